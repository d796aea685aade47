//! The running gear of the four variants of the reference's tracked robot: where each wheel
//! sits, how big it is, and whether it has teeth.
//!
//! Frames are the URDF's: x forward, y left, z up, metres, from `base_link`'s origin (the
//! chassis centre). Each side has a main track (a row of wheels under the chassis) and a
//! front flipper (a row of wheels on an arm turning about the front main wheel's axis).
//!
//! | variant | main track (per side) | flipper (per side) |
//! |---|---|---|
//! | v1 small round | 22 overlapping round wheels r = 2 cm along the track outline | 9 round, r 2 → 1.2 cm, along the big flipper's bottom |
//! | v2 small gear | 22 overlapping gear wheels r = 2 cm (8 teeth) along the outline | 9 gear, r 2 → 1.2 cm, along the big flipper's bottom |
//! | v3 big round | 9 overlapping round wheels r = 6.256 cm | 9 round, r 5.5 → 3.3 cm |
//! | v4 big gear | 9 overlapping gear wheels r = 6.256 cm (12 teeth) | 9 gear, r 5.5 → 3.3 cm |
//!
//! v4's main row is the reference's: x = −0.1855 … 0.1835 m (pitch 0.046125 m), y = ±0.1 m,
//! z = −0.03 m, circumscribed radius 0.06256 m; the teeth of wheel N start at (φ/3)·(N mod 3),
//! φ the angle between teeth. Sizes the reference does not give (widths, tooth counts and
//! depths, the small wheels, the flipper) are this module's choices.

use serde::Serialize;

/// The reference's main-track row (v3, v4): first and last wheel x, m.
pub const MAIN_X_M: [f64; 2] = [-0.1855, 0.1835];
/// Wheels per main row of the big variants.
pub const MAIN_WHEELS: usize = 9;
/// Lateral offset of the main tracks, m (the reference's wheel separation 0.2 m).
pub const MAIN_Y_M: f64 = 0.1;
/// Height of the main wheels' axes under the chassis centre, m.
pub const MAIN_Z_M: f64 = -0.03;
/// Circumscribed radius of a big wheel, m (the reference's odometry radius).
pub const BIG_RADIUS_M: f64 = 0.06256;
/// Radius of a small wheel, m (v1, v2; chosen).
pub const SMALL_RADIUS_M: f64 = 0.02;
/// Small wheels around each main track's outline (v1, v2): the most the 64 joints of a
/// `JointState` message allow (2 × (22 + 9) wheels + 2 flippers). Along the open outline
/// (`track_outline`) they stand 3.0 cm apart, so the 4 cm wheels overlap and a block's edge
/// cannot lodge between two of them.
pub const SMALL_OUTLINE_WHEELS: usize = 22;
/// Width of a main-track wheel, m (chosen).
pub const MAIN_WIDTH_M: f64 = 0.04;
/// Lateral offset of the flippers, m: outside the main tracks (chosen).
pub const FLIPPER_Y_M: f64 = 0.145;
/// Width of a flipper wheel, m (chosen).
pub const FLIPPER_WIDTH_M: f64 = 0.03;
/// Length of a flipper from its pivot to its last wheel's axis, m (chosen).
pub const FLIPPER_LENGTH_M: f64 = 0.22;
/// Wheels per flipper (the reference's).
pub const FLIPPER_WHEELS: usize = 9;
/// The last flipper wheel's radius over the first's (tapering; chosen).
pub const FLIPPER_TAPER: f64 = 0.6;
/// Radius of the big variants' first flipper wheel, m (chosen). Every variant's flipper
/// wheels stand on one bottom line this far below the pivot's axis: the small wheels of v1
/// and v2 line the bottom of the big flipper's outline, as their main-track wheels ring the
/// big main wheels' outline.
pub const FLIPPER_BIG_RADIUS_M: f64 = 0.055;
/// Mass of every wheel, kg (the reference's).
pub const WHEEL_MASS_KG: f64 = 0.15;
/// Teeth per gear: (count, depth m) for big and small gears (chosen).
pub const BIG_TEETH: (usize, f64) = (12, 0.009);
pub const SMALL_TEETH: (usize, f64) = (8, 0.004);

/// The four running-gear variants of the reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Variant {
    /// Many small round wheels around the track outline.
    V1,
    /// Many small gear wheels.
    V2,
    /// One row of big overlapping round wheels.
    V3,
    /// One row of big overlapping gear wheels, teeth phase-staggered.
    V4,
}

impl Variant {
    pub const ALL: [Variant; 4] = [Variant::V1, Variant::V2, Variant::V3, Variant::V4];

    pub fn name(self) -> &'static str {
        match self {
            Variant::V1 => "v1",
            Variant::V2 => "v2",
            Variant::V3 => "v3",
            Variant::V4 => "v4",
        }
    }

    pub fn parse(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|v| v.name() == s)
            .ok_or_else(|| format!("unknown variant '{s}' (v1, v2, v3, v4)"))
    }

    fn gear(self) -> bool {
        matches!(self, Variant::V2 | Variant::V4)
    }

    fn big(self) -> bool {
        matches!(self, Variant::V3 | Variant::V4)
    }
}

/// Left (+y) or right (−y).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    Left,
    Right,
}

impl Side {
    pub const BOTH: [Side; 2] = [Side::Left, Side::Right];

    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    /// +1 for left, −1 for right.
    pub fn sign(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }
}

/// Teeth of a gear wheel: boxes standing on the rim.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Teeth {
    pub count: usize,
    /// Radial height of a tooth, m; the rim's radius is the wheel's radius minus this.
    pub depth_m: f64,
    /// Angle of the first tooth about the axis, rad.
    pub phase_rad: f64,
}

/// Which link carries a wheel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Carrier {
    /// The chassis (`base_link`).
    Chassis,
    /// The flipper of a side, whose frame is on its pivot.
    Flipper,
}

/// One wheel: a continuous joint about y on its carrier.
#[derive(Debug, Clone, PartialEq)]
pub struct Wheel {
    pub side: Side,
    pub carrier: Carrier,
    /// Index along its row, from the back (main) or the pivot (flipper).
    pub index: usize,
    /// Axis position in the carrier's frame, m (x, z; y is the side's offset).
    pub x_m: f64,
    pub z_m: f64,
    /// Circumscribed radius, m, > 0.
    pub radius_m: f64,
    pub width_m: f64,
    pub teeth: Option<Teeth>,
}

impl Wheel {
    /// The joint's and link's name stem, e.g. `left_main_3`.
    pub fn name(&self) -> String {
        let row = match self.carrier {
            Carrier::Chassis => "main",
            Carrier::Flipper => "flipper",
        };
        format!("{}_{row}_{}", self.side.name(), self.index)
    }
}

/// The flipper pivot in the chassis frame, m (x, z): the front main wheel's axis.
pub fn flipper_pivot() -> (f64, f64) {
    (MAIN_X_M[1], MAIN_Z_M)
}

/// Teeth of the `index`-th gear of a row, phase-staggered as the reference: (φ/3)·(N mod 3).
fn teeth(variant: Variant, index: usize, big: bool) -> Option<Teeth> {
    if !variant.gear() {
        return None;
    }
    let (count, depth_m) = if big { BIG_TEETH } else { SMALL_TEETH };
    let phi = std::f64::consts::TAU / count as f64;
    Some(Teeth {
        count,
        depth_m,
        phase_rad: phi / 3.0 * (index % 3) as f64,
    })
}

/// Points spaced evenly along the part of a stadium (two semicircles of radius `r` about x0
/// and x1 on the line z = `z`) that meets the terrain: from the top of the back arc, down and
/// along the bottom run, up to the top of the front arc; both ends included, `n` ≥ 2. The top
/// run carries no wheels: it never touches the ground while the robot is upright, and wheels
/// there would only thin out the bottom row (the joints are bounded).
fn track_outline(x0: f64, x1: f64, z: f64, r: f64, n: usize) -> Vec<(f64, f64)> {
    let half = std::f64::consts::PI * r;
    let straight = x1 - x0;
    let length = 2.0 * half + straight;
    (0..n)
        .map(|k| {
            let s = length * k as f64 / (n - 1) as f64;
            if s < half {
                // Back arc: from the top (+90°) round the back (180°) to the bottom (270°).
                let a = std::f64::consts::FRAC_PI_2 + s / r;
                return (x0 + r * a.cos(), z + r * a.sin());
            }
            if s < half + straight {
                return (x0 + s - half, z - r);
            }
            let a = -std::f64::consts::FRAC_PI_2 + (s - half - straight) / r;
            (x1 + r * a.cos(), z + r * a.sin())
        })
        .collect()
}

/// Every wheel of a variant, left side first, main rows before flippers.
pub fn wheels(variant: Variant) -> Vec<Wheel> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        let main: Vec<(f64, f64)> = if variant.big() {
            let pitch = (MAIN_X_M[1] - MAIN_X_M[0]) / (MAIN_WHEELS - 1) as f64;
            (0..MAIN_WHEELS)
                .map(|i| (MAIN_X_M[0] + pitch * i as f64, MAIN_Z_M))
                .collect()
        } else {
            // Small wheels around the outline the big wheels would have.
            let inset = BIG_RADIUS_M - SMALL_RADIUS_M;
            track_outline(
                MAIN_X_M[0],
                MAIN_X_M[1],
                MAIN_Z_M,
                inset,
                SMALL_OUTLINE_WHEELS,
            )
        };
        let radius_m = if variant.big() {
            BIG_RADIUS_M
        } else {
            SMALL_RADIUS_M
        };
        for (index, (x_m, z_m)) in main.into_iter().enumerate() {
            out.push(Wheel {
                side,
                carrier: Carrier::Chassis,
                index,
                x_m,
                z_m,
                radius_m,
                width_m: MAIN_WIDTH_M,
                teeth: teeth(variant, index, variant.big()),
            });
        }
        let r0 = if variant.big() {
            FLIPPER_BIG_RADIUS_M
        } else {
            SMALL_RADIUS_M
        };
        for index in 0..FLIPPER_WHEELS {
            let f = index as f64 / (FLIPPER_WHEELS - 1) as f64;
            let radius_m = r0 * (1.0 - (1.0 - FLIPPER_TAPER) * f);
            out.push(Wheel {
                side,
                carrier: Carrier::Flipper,
                index,
                x_m: FLIPPER_LENGTH_M * f,
                // The flipper's wheels share one bottom line; the top tapers. (The small
                // wheels once sat 3.5 cm higher, on their own radius: v2's flipper then met a
                // stair's edge above its wheels and stalled there.)
                z_m: radius_m - FLIPPER_BIG_RADIUS_M,
                radius_m,
                width_m: FLIPPER_WIDTH_M,
                teeth: teeth(variant, index, variant.big()),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v4_has_the_reference_main_rows_and_36_wheels() {
        let w = wheels(Variant::V4);
        assert_eq!(w.len(), 36);
        let main: Vec<&Wheel> = w
            .iter()
            .filter(|w| w.side == Side::Left && w.carrier == Carrier::Chassis)
            .collect();
        assert_eq!(main.len(), 9);
        assert!((main[0].x_m + 0.1855).abs() < 1e-12);
        assert!((main[8].x_m - 0.1835).abs() < 1e-12);
        assert!((main[1].x_m - main[0].x_m - 0.046125).abs() < 1e-12);
        assert!(main.iter().all(|w| w.z_m == -0.03 && w.radius_m == 0.06256));
        // Overlapping: the pitch is less than a diameter.
        assert!(0.046125 < 2.0 * main[0].radius_m);
    }

    #[test]
    fn gear_teeth_start_at_a_third_of_the_tooth_angle_per_wheel_mod_3() {
        let w = wheels(Variant::V4);
        let phi = std::f64::consts::TAU / 12.0;
        for (k, wheel) in w.iter().take(9).enumerate() {
            let t = wheel.teeth.expect("a gear");
            assert!((t.phase_rad - phi / 3.0 * (k % 3) as f64).abs() < 1e-12);
        }
        assert!(wheels(Variant::V3).iter().all(|w| w.teeth.is_none()));
        assert!(wheels(Variant::V1).iter().all(|w| w.teeth.is_none()));
    }

    #[test]
    fn small_wheels_ring_the_big_outline_and_the_bottom_touches_the_same_line() {
        for v in [Variant::V1, Variant::V2] {
            let w = wheels(v);
            assert_eq!(w.len(), 2 * (SMALL_OUTLINE_WHEELS + FLIPPER_WHEELS));
            let lowest = w
                .iter()
                .filter(|w| w.carrier == Carrier::Chassis)
                .map(|w| w.z_m - w.radius_m)
                .fold(f64::INFINITY, f64::min);
            assert!(
                (lowest - (MAIN_Z_M - BIG_RADIUS_M)).abs() < 1e-9,
                "{lowest}"
            );
            // Neighbours overlap (an edge cannot lodge between them), evenly spaced, and
            // the row runs from the top of the back arc to the top of the front arc.
            let main: Vec<&Wheel> = w
                .iter()
                .filter(|w| w.side == Side::Left && w.carrier == Carrier::Chassis)
                .collect();
            let gaps: Vec<f64> = main
                .windows(2)
                .map(|p| (p[1].x_m - p[0].x_m).hypot(p[1].z_m - p[0].z_m))
                .collect();
            assert!(gaps.iter().all(|g| *g < 2.0 * SMALL_RADIUS_M), "{gaps:?}");
            assert!(gaps.iter().all(|g| (g - gaps[0]).abs() < 2e-3), "{gaps:?}");
            let top = MAIN_Z_M + BIG_RADIUS_M - SMALL_RADIUS_M;
            let (first, last) = (main[0], main[main.len() - 1]);
            assert!((first.x_m - MAIN_X_M[0]).abs() < 1e-9 && (first.z_m - top).abs() < 1e-9);
            assert!((last.x_m - MAIN_X_M[1]).abs() < 1e-9 && (last.z_m - top).abs() < 1e-9);
        }
    }

    #[test]
    fn flipper_wheels_taper_along_one_bottom_line_in_every_variant() {
        for v in Variant::ALL {
            let w = wheels(v);
            let flipper: Vec<&Wheel> = w
                .iter()
                .filter(|w| w.side == Side::Right && w.carrier == Carrier::Flipper)
                .collect();
            assert_eq!(flipper.len(), 9);
            for pair in flipper.windows(2) {
                assert!(pair[1].radius_m < pair[0].radius_m, "{v:?}");
            }
            // Bottoms on the big flipper's line (flipper frame z = −0.055 m), small wheels
            // and big alike, so every variant meets an edge with the same outline.
            for wheel in flipper {
                let bottom = wheel.z_m - wheel.radius_m;
                assert!(
                    (bottom + FLIPPER_BIG_RADIUS_M).abs() < 1e-12,
                    "{v:?}: {bottom}"
                );
            }
        }
    }
}
