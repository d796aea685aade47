//! A small SVG writer for trajectory plots over the world (like the paper's Fig. 9): the
//! world's obstacles, each robot's path, start poses and goals, in metres with y up.

use caravan_world::{Shape, World};
use std::fmt::Write;

/// Left margin, room for the y labels, px.
const LEFT_PX: f64 = 40.0;

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
    /// A plot of the floor `size` (m), `px_per_m` pixels per metre, with margins for the axes
    /// and the legend.
    pub fn new(size: [f64; 2], px_per_m: f64) -> Self {
        let mut plot = Self {
            scale: px_per_m,
            height_m: size[1],
            body: String::new(),
            width_px: size[0] * px_per_m + LEFT_PX + 20.0,
            height_px: size[1] * px_per_m + 80.0,
        };
        plot.axes(size);
        plot
    }

    fn xy(&self, p: [f64; 2]) -> (f64, f64) {
        (
            LEFT_PX + p[0] * self.scale,
            20.0 + (self.height_m - p[1]) * self.scale,
        )
    }

    /// The floor's frame with a tick and a label every metre (every 5 m on a floor over 20 m)
    /// along x and y, and a 1 m scale bar.
    fn axes(&mut self, size: [f64; 2]) {
        let step = if size[0].max(size[1]) > 20.0 {
            5.0
        } else {
            1.0
        };
        let (x0, y0) = self.xy([0.0, 0.0]);
        let (x1, y1) = self.xy([size[0], size[1]]);
        let _ = writeln!(
            self.body,
            r##"<rect x="{x0:.1}" y="{y1:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#bbb"/>"##,
            x1 - x0,
            y0 - y1
        );
        let ticks = |len: f64| (0..=(len / step).floor() as usize).map(move |k| k as f64 * step);
        for x in ticks(size[0]) {
            let (px, _) = self.xy([x, 0.0]);
            let _ = writeln!(
                self.body,
                r##"<line x1="{px:.1}" y1="{y0:.1}" x2="{px:.1}" y2="{:.1}" stroke="#888"/><text x="{px:.1}" y="{:.1}" font-size="10" font-family="sans-serif" text-anchor="middle">{x}</text>"##,
                y0 + 4.0,
                y0 + 15.0
            );
        }
        for y in ticks(size[1]) {
            let (_, py) = self.xy([0.0, y]);
            let _ = writeln!(
                self.body,
                r##"<line x1="{:.1}" y1="{py:.1}" x2="{x0:.1}" y2="{py:.1}" stroke="#888"/><text x="{:.1}" y="{:.1}" font-size="10" font-family="sans-serif" text-anchor="end">{y}</text>"##,
                x0 - 4.0,
                x0 - 6.0,
                py + 3.5
            );
        }
        // A 1 m bar at the bottom right, under the floor, and the units.
        let bar_y = y0 + 30.0;
        let _ = writeln!(
            self.body,
            r##"<line x1="{:.1}" y1="{bar_y:.1}" x2="{x1:.1}" y2="{bar_y:.1}" stroke="#000" stroke-width="3"/><text x="{:.1}" y="{:.1}" font-size="11" font-family="sans-serif" text-anchor="middle">1 m</text><text x="{:.1}" y="{:.1}" font-size="10" font-family="sans-serif">x, y (m)</text>"##,
            x1 - self.scale,
            x1 - self.scale / 2.0,
            bar_y - 5.0,
            x0 - 30.0,
            y1 - 6.0
        );
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
        let legend_x = LEFT_PX + index as f64 * 90.0;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floor_has_metre_ticks_and_a_scale_bar() {
        let svg = Plot::new([3.0, 2.0], 100.0).finish();
        assert!(svg.contains(">1 m</text>"), "{svg}");
        assert!(svg.contains(">x, y (m)</text>"), "{svg}");
        // x ticks 0…3 and y ticks 0…2, each labelled.
        for label in [">0<", ">1<", ">2<", ">3<"] {
            assert!(svg.contains(label), "{label}: {svg}");
        }
        assert_eq!(svg.matches("<line").count(), 4 + 3 + 1);
        // The bar is 1 m long at 100 px per metre.
        let plot = Plot::new([30.0, 10.0], 10.0);
        assert!(
            plot.body.contains(r#"x1="330.0" y1="150.0" x2="340.0""#),
            "{}",
            plot.body
        );
    }
}
