//! The Random Step Environment (RSE): a grid of 10 × 10 cm blocks whose heights come from a
//! ladder of steps, shaped by obstacle primitives combined by max.
//!
//! The terrain covers the whole world: an approach strip at ground height, the field where
//! the primitives act, and a run-out strip, along +x (the driving direction). Each
//! primitive proposes a height for the blocks it acts on; a block takes the highest proposal
//! (heights never add), or [`GROUND_M`] where none acts. Only the area primitives (random,
//! Gaussian) make holes: walls, peaks and hills fall to ground, not below. Each primitive draws from its own generator seeded
//! from (seed, its index), so adding a primitive leaves the others' blocks as they were.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

/// Side of a block, m.
pub const CELL_M: f64 = 0.1;
/// The heights a block can have, m (the reference's blocks).
pub const STEPS_M: [f64; 6] = [0.0, 0.05, 0.1, 0.2, 0.3, 0.4];
/// The level the robot drives on, m; 0 and 0.05 are holes.
pub const GROUND_M: f64 = 0.1;

/// The whole terrain description (a spec file's contents).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    pub terrain: Layout,
    /// Obstacle primitives, combined by max; at least one.
    #[serde(default, rename = "primitive")]
    pub primitives: Vec<Primitive>,
}

/// Where the field lies and how big it is.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layout {
    /// Seed of the random primitives; `--seed` overrides it.
    #[serde(default)]
    pub seed: u64,
    /// Field extent along x and y, m; positive multiples of [`CELL_M`], at most 20 m.
    pub field: [f64; 2],
    /// Ground before the field, m; a multiple of [`CELL_M`] in [0, 20]. Default 2.
    #[serde(default = "two")]
    pub approach: f64,
    /// Ground after the field, m; a multiple of [`CELL_M`] in [0, 20]. Default 2.
    #[serde(default = "two")]
    pub run_out: f64,
    /// Friction coefficient of every block, in [0, 100] (written to the world file). Default 1.
    #[serde(default = "one")]
    pub friction: f64,
    /// Flank length of a primitive with softness 100, m, in (0, 20]. Default 1.
    #[serde(default = "one")]
    pub flank: f64,
}

fn two() -> f64 {
    2.0
}
fn one() -> f64 {
    1.0
}

/// One obstacle primitive. Positions are in field coordinates: m from the field's corner
/// (first block along x, first along y). The ranges of the keys, and why, are in
/// [`crate::rse_check`].
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Primitive {
    /// Every block an independent uniform choice among the steps in [`min`, `max`] (m,
    /// both ladder steps).
    Random { min: f64, max: f64 },
    /// Every block drawn from a normal distribution (`mean`, `std`, m, both in [0, 0.4]),
    /// kept within [0, 0.4] and rounded to the nearest step.
    Gaussian { mean: f64, std: f64 },
    /// A wall across the field (along y) whose core spans x ∈ [`at` − `width`/2,
    /// `at` + `width`/2] (m; `at` on the field, `width` in [0.1, 20]), `height` m high (a
    /// step above ground), with flanks set by `softness` (0–100).
    HorizontalBarrier {
        at: f64,
        width: f64,
        height: f64,
        #[serde(default)]
        softness: f64,
    },
    /// The same wall turned by `angle_deg` (default 45°, in (−90, 90)) about the point
    /// (`at`, field centre): its core is the band within `width`/2 of that line.
    DiagonalBarrier {
        at: f64,
        width: f64,
        height: f64,
        #[serde(default = "forty_five")]
        angle_deg: f64,
        #[serde(default)]
        softness: f64,
    },
    /// A cone of `height` m (a step above ground) at `center` (m, on the field), falling
    /// linearly to ground at `radius` m (in [0.1, 20]).
    Peak {
        center: [f64; 2],
        height: f64,
        radius: f64,
    },
    /// `count` (1–100) Gaussian hills of `height` m (a step above ground) and spread `sigma`
    /// m (at least a block, below a quarter of the field's shorter side), each centred at a
    /// uniformly random point at least 2 σ inside the field's edges: a hill proposes
    /// ground + (`height` − ground)·exp(−r²/2σ²) rounded to the nearest step, where that is
    /// above ground. So a hill is a round staircase: its top step within 0.76 σ of the
    /// centre when it is two steps high (the reference's "random Gaussian" obstacle).
    Hills { count: u32, height: f64, sigma: f64 },
}

fn forty_five() -> f64 {
    45.0
}

/// Block heights over the whole world, x fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Blocks along x.
    pub nx: usize,
    /// Blocks along y.
    pub ny: usize,
    /// Blocks of the approach before the field, along x.
    pub field_start: usize,
    /// Blocks of the field along x.
    pub field_nx: usize,
    /// Heights, m, each one of [`STEPS_M`]; index `iy * nx + ix`.
    pub heights: Vec<f64>,
}

impl Grid {
    /// The height of block (`ix`, `iy`), m.
    pub fn at(&self, ix: usize, iy: usize) -> f64 {
        self.heights[iy * self.nx + ix]
    }

    /// World extent, m.
    pub fn size_m(&self) -> [f64; 2] {
        [self.nx as f64 * CELL_M, self.ny as f64 * CELL_M]
    }
}

/// The highest step ≤ `h` (a flank never overshoots its wall).
pub fn step_below(h: f64) -> f64 {
    STEPS_M
        .iter()
        .rev()
        .copied()
        .find(|&s| s <= h + 1e-9)
        .unwrap_or(0.0)
}

/// The step nearest to `h`.
pub fn nearest_step(h: f64) -> f64 {
    STEPS_M
        .iter()
        .copied()
        .min_by(|a, b| (a - h).abs().total_cmp(&(b - h).abs()))
        .unwrap_or(0.0)
}

pub use crate::rse_check::{parse_spec, validate};

/// A wall's proposal at distance `d` (m) beyond its core: its height inside, then a
/// staircase down to ground over `flank_m`·`softness`/100 m (none at softness 0), then
/// nothing.
fn wall(height: f64, d: f64, softness: f64, flank_m: f64) -> Option<f64> {
    if d <= 0.0 {
        return Some(height);
    }
    let len = softness / 100.0 * flank_m;
    (d < len).then(|| slope(height, d / len))
}

/// The step at fraction `f` ∈ [0, 1) of the way from `height` down to ground (rounded down,
/// so a flank never overshoots its wall, and never below ground).
fn slope(height: f64, f: f64) -> f64 {
    step_below(GROUND_M + (height - GROUND_M) * (1.0 - f)).max(GROUND_M.min(height))
}

impl Primitive {
    /// The points this primitive places before it proposes heights: the hills' centres
    /// (field coordinates, m), none for the others.
    fn centres(&self, field: [f64; 2], rng: &mut ChaCha8Rng) -> Vec<[f64; 2]> {
        match *self {
            Primitive::Hills { count, sigma, .. } => {
                // A hill's lowest stair reaches 1.2–1.9 σ (one to three steps high); centres
                // 2 σ inside the field keep it whole, not cut by the field's edge into a wall (or at the middle of a
                // field too small for that).
                let along = |len: f64, rng: &mut ChaCha8Rng| {
                    let margin = 2.0 * sigma;
                    if len > 2.0 * margin {
                        rng.random_range(margin..len - margin)
                    } else {
                        len / 2.0
                    }
                };
                (0..count)
                    .map(|_| [along(field[0], rng), along(field[1], rng)])
                    .collect()
            }
            _ => Vec::new(),
        }
    }

    /// This primitive's proposal for the block whose centre is (`x`, `y`) in field
    /// coordinates, m (`field` is the field's extent; `centres` from [`Self::centres`]), or
    /// `None` where it does not act.
    fn height(
        &self,
        [x, y]: [f64; 2],
        field: [f64; 2],
        flank_m: f64,
        centres: &[[f64; 2]],
        rng: &mut ChaCha8Rng,
    ) -> Option<f64> {
        match *self {
            Primitive::Random { min, max } => {
                let choices: Vec<f64> = STEPS_M
                    .iter()
                    .copied()
                    .filter(|s| *s >= min - 1e-9 && *s <= max + 1e-9)
                    .collect();
                Some(choices[rng.random_range(0..choices.len())])
            }
            Primitive::Gaussian { mean, std } => {
                // Box–Muller: two uniforms in (0, 1] give one standard normal.
                let (u1, u2): (f64, f64) = (1.0 - rng.random::<f64>(), rng.random());
                let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                Some(nearest_step((mean + std * z).clamp(0.0, 0.4)))
            }
            Primitive::HorizontalBarrier {
                at,
                width,
                height,
                softness,
            } => wall(height, (x - at).abs() - width / 2.0, softness, flank_m),
            Primitive::DiagonalBarrier {
                at,
                width,
                height,
                angle_deg,
                softness,
            } => {
                // Distance to the line through (at, centre) whose normal is turned by angle.
                let a = angle_deg.to_radians();
                let d = ((x - at) * a.cos() + (y - field[1] / 2.0) * a.sin()).abs();
                wall(height, d - width / 2.0, softness, flank_m)
            }
            Primitive::Peak {
                center,
                height,
                radius,
            } => {
                let r = (x - center[0]).hypot(y - center[1]);
                (r < radius).then(|| slope(height, r / radius))
            }
            Primitive::Hills { height, sigma, .. } => {
                let top = centres
                    .iter()
                    .map(|c| {
                        let r2 = (x - c[0]).powi(2) + (y - c[1]).powi(2);
                        nearest_step(
                            GROUND_M + (height - GROUND_M) * (-r2 / (2.0 * sigma * sigma)).exp(),
                        )
                    })
                    .fold(GROUND_M, f64::max);
                (top > GROUND_M).then_some(top)
            }
        }
    }
}

/// The seed of primitive `index`'s own generator: independent of the other primitives.
fn primitive_seed(seed: u64, index: usize) -> u64 {
    seed ^ (index as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// Generates the terrain of a checked spec with `seed`.
pub fn generate(spec: &Spec, seed: u64) -> Grid {
    let t = &spec.terrain;
    let n = |len: f64| (len / CELL_M).round() as usize;
    let (field_nx, ny) = (n(t.field[0]), n(t.field[1]));
    let field_start = n(t.approach);
    let nx = field_start + field_nx + n(t.run_out);
    // Each block: the highest proposal, or ground where no primitive acts.
    let mut proposals: Vec<Option<f64>> = vec![None; nx * ny];
    for (i, p) in spec.primitives.iter().enumerate() {
        let mut rng = ChaCha8Rng::seed_from_u64(primitive_seed(seed, i));
        let centres = p.centres(t.field, &mut rng);
        for iy in 0..ny {
            for fx in 0..field_nx {
                let xy = [(fx as f64 + 0.5) * CELL_M, (iy as f64 + 0.5) * CELL_M];
                if let Some(h) = p.height(xy, t.field, t.flank, &centres, &mut rng) {
                    let cell = &mut proposals[iy * nx + field_start + fx];
                    *cell = Some(cell.map_or(h, |c| c.max(h)));
                }
            }
        }
    }
    let heights = proposals.iter().map(|h| h.unwrap_or(GROUND_M)).collect();
    Grid {
        nx,
        ny,
        field_start,
        field_nx,
        heights,
    }
}

#[cfg(test)]
#[path = "rse_tests.rs"]
mod tests;
