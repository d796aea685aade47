//! A small SVG writer for trajectory plots over the world (like the paper's Fig. 9): the
//! world's obstacles, each robot's path, start poses and goals, in metres with y up.

use caravan_world::{Shape, World};
use std::fmt::Write;

const COLOURS: [&str; 8] = [
    "#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

pub struct Plot {
    scale: f64,
    height_m: f64,
    body: String,
    width_px: f64,
    height_px: f64,
}

impl Plot {
    /// A plot of the floor `size` (m), `px_per_m` pixels per metre, with a margin.
    pub fn new(size: [f64; 2], px_per_m: f64) -> Self {
        Self {
            scale: px_per_m,
            height_m: size[1],
            body: String::new(),
            width_px: size[0] * px_per_m + 40.0,
            height_px: size[1] * px_per_m + 60.0,
        }
    }

    fn xy(&self, p: [f64; 2]) -> (f64, f64) {
        (
            20.0 + p[0] * self.scale,
            20.0 + (self.height_m - p[1]) * self.scale,
        )
    }

    pub fn world(&mut self, world: &World) {
        self.obstacles(world, "#888", "#444");
    }

    /// The obstacles' outlines only, over an image of a map.
    pub fn world_outline(&mut self, world: &World) {
        self.obstacles(world, "none", "#d62728");
    }

    /// A raster image (e.g. `data:image/png;base64,…`) covering `[min, max]` in metres.
    pub fn image(&mut self, href: &str, min: [f64; 2], max: [f64; 2]) {
        let (x0, y0) = self.xy([min[0], max[1]]);
        let (x1, y1) = self.xy([max[0], min[1]]);
        let _ = writeln!(
            self.body,
            r#"<image x="{x0:.2}" y="{y0:.2}" width="{:.2}" height="{:.2}" preserveAspectRatio="none" style="image-rendering:pixelated" href="{href}"/>"#,
            x1 - x0,
            y1 - y0
        );
    }

    fn obstacles(&mut self, world: &World, fill: &str, stroke: &str) {
        for o in &world.obstacles {
            match o.shape {
                Shape::Box { .. } => {
                    let pts: Vec<String> = o
                        .corners()
                        .iter()
                        .map(|c| self.xy(*c))
                        .map(|(x, y)| format!("{x:.1},{y:.1}"))
                        .collect();
                    let _ = writeln!(
                        self.body,
                        r#"<polygon points="{}" fill="{fill}" stroke="{stroke}"/>"#,
                        pts.join(" ")
                    );
                }
                Shape::Cylinder { radius } => {
                    let (x, y) = self.xy(o.center);
                    let _ = writeln!(
                        self.body,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="{:.1}" fill="{fill}" stroke="{stroke}"/>"#,
                        radius * self.scale
                    );
                }
            }
        }
    }

    pub fn path(&mut self, index: usize, label: &str, points: &[[f64; 2]]) {
        let colour = COLOURS[index % COLOURS.len()];
        let pts: Vec<String> = points
            .iter()
            .map(|p| self.xy(*p))
            .map(|(x, y)| format!("{x:.1},{y:.1}"))
            .collect();
        let _ = writeln!(
            self.body,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
            pts.join(" ")
        );
        if let Some(first) = points.first() {
            let (x, y) = self.xy(*first);
            let _ = writeln!(
                self.body,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="3" fill="{colour}"/>"#
            );
        }
        let legend_y = self.height_px - 25.0;
        let legend_x = 20.0 + index as f64 * 90.0;
        let _ = writeln!(
            self.body,
            r#"<rect x="{legend_x}" y="{}" width="14" height="4" fill="{colour}"/><text x="{}" y="{legend_y}" font-size="12" font-family="sans-serif">{label}</text>"#,
            legend_y - 4.0,
            legend_x + 18.0
        );
    }

    pub fn goal(&mut self, label: &str, p: [f64; 2]) {
        let (x, y) = self.xy(p);
        let _ = writeln!(
            self.body,
            r##"<circle cx="{x:.1}" cy="{y:.1}" r="5" fill="none" stroke="#000"/><text x="{:.1}" y="{:.1}" font-size="13" font-family="sans-serif">{label}</text>"##,
            x + 7.0,
            y - 7.0
        );
    }

    pub fn finish(self) -> String {
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" viewBox=\"0 0 {w:.0} {h:.0}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n{}</svg>\n",
            self.body,
            w = self.width_px,
            h = self.height_px
        )
    }
}
