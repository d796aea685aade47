//! Maps on disk in the ROS map_server format: `NAME.pgm` and `NAME.yaml`.
//!
//! Written as map_saver's `scale` mode writes them: a binary PGM (P5, 8 bit) whose top row is
//! the map's highest y, each known cell's occupancy v (0–100) as the pixel (100 − v)·2.55
//! rounded (so 255 is free, 0 fully occupied) and 205 for unknown cells (no known value rounds
//! to 205), and a YAML file naming the image, with `mode: scale, negate: 0,
//! occupied_thresh: 0.65, free_thresh: 0.196`. The grades survive a round trip: Caravan's
//! maps grade occupied cells by how surely they reflect, which the run report uses to locate
//! surfaces (see `survey`).
//!
//! Reading a `scale` map restores the values; a map without `mode` (or `mode: trinary`, as
//! other tools write) is read as map_server's trinary mode: p = (255 − pixel)/255 is occupied
//! (100) above `occupied_thresh`, free (0) below `free_thresh`, unknown (−1) between. The YAML
//! is written by hand and only the keys written here are read back (flow sequence for
//! `origin`, numbers and a bare file name).

use caravan_schemas::{MAP_MAX_SIDE, OccupancyGrid, Pose2D};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Free cells in the image.
pub const PIXEL_FREE: u8 = 254;
/// Occupied cells in the image.
pub const PIXEL_OCCUPIED: u8 = 0;
/// Unknown cells in the image.
pub const PIXEL_UNKNOWN: u8 = 205;
pub const OCCUPIED_THRESH: f64 = 0.65;
pub const FREE_THRESH: f64 = 0.196;

/// Writes `grid` to `base.pgm` and `base.yaml` (`base` without extension, as map_saver's
/// `-f`); returns the YAML path.
pub fn save_map(grid: &OccupancyGrid, base: &Path) -> Result<PathBuf, String> {
    let (w, h) = (grid.width as usize, grid.height as usize);
    if w == 0 || h == 0 || w > MAP_MAX_SIDE || h > MAP_MAX_SIDE {
        return Err(format!("cannot save a {w} × {h} map"));
    }
    let pgm = base.with_extension("pgm");
    let yaml = base.with_extension("yaml");
    let image_name = pgm
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| format!("{}: not a usable file name", pgm.display()))?;

    let header = format!(
        "P5\n# CREATOR: caravan-perception {:.3} m/pix\n{w} {h}\n255\n",
        grid.resolution
    );
    let mut bytes = Vec::with_capacity(header.len() + w * h);
    bytes.extend_from_slice(header.as_bytes());
    for row in (0..h).rev() {
        bytes.extend(
            grid.data[row * w..(row + 1) * w]
                .iter()
                .map(|&v| pixel_of(v)),
        );
    }
    std::fs::write(&pgm, bytes).map_err(|e| format!("{}: {e}", pgm.display()))?;

    let mut text = String::new();
    // `{}` prints the shortest decimal that reads back as the same f64.
    let _ = writeln!(text, "image: {image_name}");
    let _ = writeln!(text, "resolution: {}", grid.resolution);
    let _ = writeln!(
        text,
        "origin: [{}, {}, {}]",
        grid.origin.x, grid.origin.y, grid.origin.theta
    );
    let _ = writeln!(text, "mode: scale");
    let _ = writeln!(text, "negate: 0");
    let _ = writeln!(text, "occupied_thresh: {OCCUPIED_THRESH}");
    let _ = writeln!(text, "free_thresh: {FREE_THRESH}");
    std::fs::write(&yaml, text).map_err(|e| format!("{}: {e}", yaml.display()))?;
    Ok(yaml)
}

/// Reads the map described by `yaml` (as written by [`save_map`]) into `out`.
pub fn load_map(yaml: &Path, out: &mut OccupancyGrid) -> Result<(), String> {
    let err = |what: &str| format!("{}: {what}", yaml.display());
    let text = caravan::input::read_to_string(yaml).map_err(|e| err(&e.to_string()))?;
    let mut image = None;
    let mut resolution = None;
    let mut origin = None;
    let mut negate = 0.0;
    let mut scale = false;
    let (mut occupied, mut free) = (OCCUPIED_THRESH, FREE_THRESH);
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let (key, value) = line
            .split_once(':')
            .ok_or_else(|| err(&format!("expected `key: value`, got `{line}`")))?;
        let value = value.trim();
        let number = |v: &str| {
            v.trim()
                .parse::<f64>()
                .map_err(|_| err(&format!("{key}: not a number: `{v}`")))
        };
        match key.trim() {
            "image" => image = Some(value.to_string()),
            "resolution" => resolution = Some(number(value)?),
            "origin" => {
                let inner = value
                    .strip_prefix('[')
                    .and_then(|v| v.strip_suffix(']'))
                    .ok_or_else(|| err("origin: expected [x, y, yaw]"))?;
                let v = inner
                    .split(',')
                    .map(number)
                    .collect::<Result<Vec<_>, _>>()?;
                let [x, y, theta] = v[..] else {
                    return Err(err("origin: expected [x, y, yaw]"));
                };
                origin = Some(Pose2D { x, y, theta });
            }
            "negate" => negate = number(value)?,
            "mode" => match value {
                "scale" => scale = true,
                "trinary" => scale = false,
                other => {
                    return Err(err(&format!(
                        "mode: `{other}` is not read; use scale or trinary"
                    )));
                }
            },
            "occupied_thresh" => occupied = number(value)?,
            "free_thresh" => free = number(value)?,
            other => return Err(err(&format!("unexpected key `{other}`"))),
        }
    }
    let image = image.ok_or_else(|| err("missing `image`"))?;
    let range = crate::slam::RESOLUTION_RANGE_M;
    let resolution = resolution
        .filter(|r| range.contains(r))
        .ok_or_else(|| err(&format!("missing `resolution`, or not in {range:?} m")))?;
    let origin = origin.ok_or_else(|| err("missing `origin`"))?;
    for v in [origin.x, origin.y, origin.theta] {
        use caravan_world::limits::{MAX_WORLD_EXTENT_M, coordinate};
        coordinate("origin", v, MAX_WORLD_EXTENT_M).map_err(|e| err(&e))?;
    }

    let pgm = yaml.parent().unwrap_or(Path::new("")).join(&image);
    let bytes = caravan::input::read(&pgm).map_err(|e| format!("{}: {e}", pgm.display()))?;
    let (w, h, pixels) = parse_pgm(&bytes).map_err(|e| format!("{}: {e}", pgm.display()))?;
    if w > MAP_MAX_SIDE || h > MAP_MAX_SIDE {
        return Err(format!(
            "{}: {w} × {h} is larger than {MAP_MAX_SIDE} × {MAP_MAX_SIDE}",
            pgm.display()
        ));
    }
    out.resolution = resolution;
    out.origin = origin;
    out.width = w as u32;
    out.height = h as u32;
    for (row, pixels) in pixels.chunks_exact(w).enumerate() {
        let dst = &mut out.data[(h - 1 - row) * w..(h - row) * w];
        for (d, &px) in dst.iter_mut().zip(pixels) {
            if scale {
                *d = value_of(px);
                continue;
            }
            let mut p = (255.0 - px as f64) / 255.0;
            if negate != 0.0 {
                p = 1.0 - p;
            }
            *d = if p > occupied {
                (100.0 * p).round() as i8
            } else if p < free {
                0
            } else {
                -1
            };
        }
    }
    Ok(())
}

/// The `scale` pixel of occupancy `v` (−1 unknown).
fn pixel_of(v: i8) -> u8 {
    if v < 0 {
        PIXEL_UNKNOWN
    } else {
        ((100 - v.min(100) as i32) as f64 * 2.55).round() as u8
    }
}

/// The occupancy of a `scale` pixel.
fn value_of(px: u8) -> i8 {
    if px == PIXEL_UNKNOWN {
        -1
    } else {
        (100.0 - px as f64 / 2.55).round().clamp(0.0, 100.0) as i8
    }
}

/// Width, height and pixels of a binary 8-bit PGM.
fn parse_pgm(bytes: &[u8]) -> Result<(usize, usize, &[u8]), String> {
    let mut pos = 0;
    // Header tokens: magic, width, height, maxval; `#` comments run to the end of the line.
    let mut token = || -> Result<&[u8], String> {
        loop {
            while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
                pos += 1;
            }
            if pos < bytes.len() && bytes[pos] == b'#' {
                while pos < bytes.len() && bytes[pos] != b'\n' {
                    pos += 1;
                }
                continue;
            }
            break;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        (pos > start)
            .then(|| &bytes[start..pos])
            .ok_or_else(|| "truncated header".to_string())
    };
    if token()? != b"P5" {
        return Err("not a binary PGM (P5)".into());
    }
    let mut int = || -> Result<usize, String> {
        let t = token()?;
        std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| format!("bad header number `{}`", String::from_utf8_lossy(t)))
    };
    let (w, h, max) = (int()?, int()?, int()?);
    if max != 255 {
        return Err(format!("only 8-bit PGMs (maxval 255) are read, got {max}"));
    }
    if w == 0 || h == 0 {
        return Err("empty image".into());
    }
    // Exactly one whitespace byte separates the header from the pixels.
    let data = bytes.get(pos + 1..).unwrap_or(&[]);
    if w.checked_mul(h).is_none_or(|n| data.len() < n) {
        return Err(format!("{} pixel bytes for a {w} × {h} image", data.len()));
    }
    Ok((w, h, &data[..w * h]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("caravan-perception-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn round_trip() {
        let mut grid = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
        grid.resolution = 0.025;
        grid.origin = Pose2D {
            x: -6.4,
            y: -3.2125,
            theta: 0.0,
        };
        grid.width = 37;
        grid.height = 23;
        let value = |x: usize, y: usize| match (x * 3 + y * 5) % 7 {
            0 | 1 => -1,
            2 | 3 => 0,
            4 => 100,
            5 => 10,
            _ => 80,
        };
        for y in 0..23 {
            for x in 0..37 {
                grid.data[y * 37 + x] = value(x, y);
            }
        }
        let dir = temp_dir("round-trip");
        let yaml = save_map(&grid, &dir.join("map")).unwrap();
        assert_eq!(yaml, dir.join("map.yaml"));
        let text = std::fs::read_to_string(&yaml).unwrap();
        assert!(text.contains("image: map.pgm\n") && text.contains("origin: [-6.4, -3.2125, 0]"));
        let pgm = std::fs::read(dir.join("map.pgm")).unwrap();
        // The image's first pixel is the top-left cell: x = 0, y = height − 1.
        let pixel = |v: i8| match v {
            -1 => PIXEL_UNKNOWN,
            v => ((100 - v as i32) as f64 * 2.55).round() as u8,
        };
        assert_eq!(pgm[pgm.len() - 37 * 23], pixel(value(0, 22)));
        assert_eq!(pgm[pgm.len() - 1], pixel(value(36, 0)));

        let mut back = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
        load_map(&yaml, &mut back).unwrap();
        assert_eq!((back.width, back.height, back.resolution), (37, 23, 0.025));
        assert_eq!(back.origin, grid.origin);
        for y in 0..23u32 {
            for x in 0..37u32 {
                // Every value comes back as it was.
                let want = value(x as usize, y as usize);
                assert_eq!(back.get(x, y), Some(want), "cell {x} {y}");
            }
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn errors_name_the_file() {
        let dir = temp_dir("errors");
        let mut out = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
        let missing = dir.join("missing.yaml");
        assert!(
            load_map(&missing, &mut out)
                .unwrap_err()
                .contains("missing.yaml")
        );
        let yaml = dir.join("bad.yaml");
        std::fs::write(
            &yaml,
            "image: nothere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n",
        )
        .unwrap();
        assert!(
            load_map(&yaml, &mut out)
                .unwrap_err()
                .contains("nothere.pgm")
        );
        std::fs::write(&yaml, "image: x.pgm\nresolution: fine\n").unwrap();
        let e = load_map(&yaml, &mut out).unwrap_err();
        assert!(e.contains("bad.yaml") && e.contains("resolution"), "{e}");
        std::fs::write(dir.join("x.pgm"), b"P2\n1 1\n255\n0").unwrap();
        std::fs::write(&yaml, "image: x.pgm\nresolution: 1\norigin: [0, 0, 0]\n").unwrap();
        let e = load_map(&yaml, &mut out).unwrap_err();
        assert!(e.contains("x.pgm") && e.contains("P5"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn absurd_resolutions_and_image_sizes_are_errors_not_panics() {
        let dir = temp_dir("absurd");
        let mut out = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
        let yaml = dir.join("map.yaml");
        std::fs::write(
            &yaml,
            "image: map.pgm\nresolution: 1e-300\norigin: [0, 0, 0]\n",
        )
        .unwrap();
        let e = load_map(&yaml, &mut out).unwrap_err();
        assert!(e.contains("resolution"), "{e}");
        std::fs::write(
            &yaml,
            "image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n",
        )
        .unwrap();
        std::fs::write(dir.join("map.pgm"), b"P5 4294967296 4294967296 255\n\x00").unwrap();
        let e = load_map(&yaml, &mut out).unwrap_err();
        assert!(e.contains("map.pgm"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }
}
