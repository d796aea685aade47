//! The spin-up check: how long a motor of maximum torque M takes to bring a bar of inertia I
//! about its axis to rate ω. Analytically t = I·ω/M. The reference's table (and its
//! simulator's times) is [`REFERENCE_ROWS`].
//!
//! The time is measured from the gyro readings two ways:
//! - **Fit** (the paper's method): a line fitted by least squares to the readings between 10 %
//!   and 90 % of ω, intersected with ω (the end) and with 0 (the start). Since the motor's
//!   torque is constant on the ramp, t = ω / slope. Each reading is the mean rate over its
//!   step, so it is placed at the step's middle.
//! - **Threshold**: from the fitted start to the middle of the first step whose reading
//!   reaches ω·(1 − [`THRESHOLD`]). It includes the speed loop's approach to ω once the
//!   torque leaves its bound.

use serde::Serialize;

/// How close to ω a reading must come to end the spin-up by the threshold method.
pub const THRESHOLD: f64 = 1e-3;

/// One row of the reference's spin-up table: M (N·m), ω (°/s), m (kg), the analytic time,
/// the paper's simulator's time and its error (s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ReferenceRow {
    pub torque_nm: f64,
    pub rate_deg_s: f64,
    pub mass_kg: f64,
    pub analytic_s: f64,
    pub paper_s: f64,
    pub paper_err_s: f64,
}

const fn row(m: f64, w: f64, kg: f64, t: f64, paper: f64, err: f64) -> ReferenceRow {
    ReferenceRow {
        torque_nm: m,
        rate_deg_s: w,
        mass_kg: kg,
        analytic_s: t,
        paper_s: paper,
        paper_err_s: err,
    }
}

/// `shared/reference/imu.md`, spin-up table, in its order (rows 1 to 6).
pub const REFERENCE_ROWS: [ReferenceRow; 6] = [
    row(5.0, 45.0, 10.0, 0.416, 0.399, 0.018),
    row(5.0, 45.0, 5.0, 0.208, 0.200, 0.008),
    row(5.0, 30.0, 5.0, 0.139, 0.150, 0.012),
    row(15.0, 90.0, 5.0, 0.139, 0.150, 0.012),
    row(15.0, 45.0, 10.0, 0.139, 0.150, 0.012),
    row(15.0, 30.0, 20.0, 0.185, 0.200, 0.015),
];

/// The reference row with these values, if any.
pub fn reference_row(torque_nm: f64, rate_deg_s: f64, mass_kg: f64) -> Option<ReferenceRow> {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * b.abs().max(1.0);
    REFERENCE_ROWS.iter().copied().find(|r| {
        close(r.torque_nm, torque_nm)
            && close(r.rate_deg_s, rate_deg_s)
            && close(r.mass_kg, mass_kg)
    })
}

/// Spin-up times measured from gyro readings `(stamp s, rate rad/s)`, `step_s` apart.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Measured {
    /// When the ramp began, by the fitted line, s.
    pub start_s: f64,
    /// Spin-up time by the fitted line, s.
    pub fit_s: f64,
    /// Spin-up time by the threshold crossing, s; `None` if ω was never reached.
    pub threshold_s: Option<f64>,
    /// Readings on the fitted ramp.
    pub ramp_readings: usize,
}

/// Measures the spin-up to `target` (rad/s, > 0); `None` with fewer than 3 ramp readings.
pub fn measure(readings: &[(f64, f64)], target: f64, step_s: f64) -> Option<Measured> {
    let mid = |t: f64| t - step_s / 2.0;
    let ramp: Vec<(f64, f64)> = readings
        .iter()
        .filter(|(_, w)| *w >= 0.1 * target && *w <= 0.9 * target)
        .map(|&(t, w)| (mid(t), w))
        .collect();
    if ramp.len() < 3 {
        return None;
    }
    let n = ramp.len() as f64;
    let (mt, mw) = ramp
        .iter()
        .fold((0.0, 0.0), |(a, b), (t, w)| (a + t / n, b + w / n));
    let (mut stw, mut stt) = (0.0, 0.0);
    for (t, w) in &ramp {
        stw += (t - mt) * (w - mw);
        stt += (t - mt) * (t - mt);
    }
    let slope = stw / stt;
    let start_s = mt - mw / slope;
    let threshold_s = readings
        .iter()
        .find(|(_, w)| *w >= target * (1.0 - THRESHOLD))
        .map(|(t, _)| mid(*t) - start_s);
    Some(Measured {
        start_s,
        fit_s: target / slope,
        threshold_s,
        ramp_readings: ramp.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_rows_are_i_omega_over_m_with_i_0_265_m() {
        for r in REFERENCE_ROWS {
            let t = 0.265 * r.mass_kg * r.rate_deg_s.to_radians() / r.torque_nm;
            assert!((t - r.analytic_s).abs() < 6e-4, "{r:?}: {t}");
        }
        assert_eq!(reference_row(15.0, 30.0, 20.0), Some(REFERENCE_ROWS[5]));
        assert_eq!(reference_row(15.0, 30.0, 21.0), None);
    }

    #[test]
    fn a_constant_torque_ramp_is_measured_exactly() {
        // Ramp from 0.2003 s at 2 rad/s², then held at 1 rad/s; readings are step means.
        let (start, accel, target, dt) = (0.2003, 2.0, 1.0, 0.001);
        let rate = |t: f64| (accel * (t - start)).clamp(0.0, target);
        let readings: Vec<(f64, f64)> = (1..1500)
            .map(|k| {
                let t = k as f64 * dt;
                // The mean over [t − dt, t] by Simpson's rule (exact for piecewise linear
                // pieces away from the kinks).
                let mean = (rate(t - dt) + 4.0 * rate(t - dt / 2.0) + rate(t)) / 6.0;
                (t, mean)
            })
            .collect();
        let m = measure(&readings, target, dt).unwrap();
        assert!((m.fit_s - 0.5).abs() < 1e-9, "{m:?}");
        assert!((m.start_s - start).abs() < 1e-9, "{m:?}");
        let threshold = m.threshold_s.unwrap();
        assert!(threshold > 0.5 - dt && threshold < 0.5 + dt, "{m:?}");
    }
}

/// The bar and motor of a spin-up, from its robot description.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bar {
    /// The motor's maximum torque: the joint's `<limit effort>`, N·m.
    pub torque_nm: f64,
    /// The target rate: the joint's `<limit velocity>`, rad/s.
    pub rate_rad_s: f64,
    /// The bar's mass, kg.
    pub mass_kg: f64,
    /// The bar's inertia about the joint axis, kg·m².
    pub inertia_kg_m2: f64,
}

impl Bar {
    /// Reads joint `joint` of `d` and the link it moves; the error names what is missing.
    pub fn from_description(
        d: &caravan_world::description::RobotDescription,
        joint: &str,
    ) -> Result<Self, String> {
        let j = d.joint(joint).ok_or_else(|| {
            format!(
                "key 'joint': robot description {} has no joint '{joint}'",
                d.file
            )
        })?;
        let joint = &d.joints[j];
        let link = &d.links[joint.child];
        let inertial = link
            .inertial
            .as_ref()
            .ok_or_else(|| format!("{}: link '{}' has no <inertial>", d.file, link.name))?;
        let (effort, velocity) = (joint.limits.effort, joint.limits.velocity);
        if !(effort.is_finite() && velocity.is_finite()) {
            return Err(format!(
                "{}: joint '{}' needs <limit effort velocity>: the motor's torque and rate",
                d.file, joint.name
            ));
        }
        // About the joint axis a through the link origin: aᵀ·R·I·Rᵀ·a + m·|c ⊥ a|².
        let a = joint.axis;
        let r = inertial.origin.rotation.to_rotation_matrix();
        let about_com =
            (a.transpose() * r.matrix() * inertial.inertia * r.matrix().transpose() * a)[0];
        let c = inertial.origin.translation.vector;
        let offset_sq = c.norm_squared() - c.dot(&a).powi(2);
        Ok(Self {
            torque_nm: effort,
            rate_rad_s: velocity,
            mass_kg: inertial.mass,
            inertia_kg_m2: about_com + inertial.mass * offset_sq,
        })
    }

    /// The analytic spin-up time I·ω/M, s.
    pub fn analytic_s(&self) -> f64 {
        self.inertia_kg_m2 * self.rate_rad_s / self.torque_nm
    }
}
