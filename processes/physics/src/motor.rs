//! The DC gear motor that drives one wheel: terminal voltage in, torque at the wheel out.
//!
//! The armature inductance is left out: its electrical time constant (well under 1 ms for a
//! small motor) is far below the 2 ms physics step, so the current follows the voltage at
//! once. Per step, with the wheel's speed relative to the chassis ω (rad/s):
//!
//! ```text
//! V  = clamp(V_cmd, −V_supply, +V_supply)
//! i  = (V − k_e·N·ω) / R                      back-EMF from the rotor speed N·ω
//! τ  = N·k_t·i − b·ω − c·tanh(ω/ω_c)          at the wheel, after the gearbox
//! ```
//!
//! `b` and `c` are the gearbox's viscous and Coulomb friction expressed at the wheel. The
//! Coulomb term is smoothed over ±ω_c so that an explicit integrator does not chatter
//! around zero speed. The rotor's inertia turns N times faster than the wheel, so it adds
//! J_rotor·N² to the wheel's inertia about its axle ([`MotorParams::reflected_inertia`]);
//! the scene puts it into the wheel body.

use serde::Deserialize;

/// Motor and gearbox constants (the `dc_motor` actuator's `motor` keys). Defaults: the convoy
/// robot's motor, a property of that motor, fitted as [`crate::step_response`] documents.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MotorParams {
    /// Supply voltage, V; the firmware's command is clamped to ±this.
    pub supply_v: f64,
    /// Armature resistance, Ω.
    pub resistance_ohm: f64,
    /// Torque constant, N·m/A (at the rotor).
    pub k_t: f64,
    /// Back-EMF constant, V·s/rad (at the rotor).
    pub k_e: f64,
    /// Gear ratio N (rotor turns per wheel turn).
    pub gear_ratio: f64,
    /// Rotor inertia, kg·m².
    pub rotor_inertia: f64,
    /// Viscous friction at the wheel, N·m·s/rad.
    pub viscous: f64,
    /// Coulomb friction at the wheel, N·m.
    pub coulomb: f64,
    /// Speed over which the Coulomb friction ramps up, rad/s.
    pub coulomb_smoothing: f64,
}

impl Default for MotorParams {
    fn default() -> Self {
        Self {
            supply_v: 6.0,
            resistance_ohm: 20.0,
            k_t: 0.01,
            k_e: 0.01,
            gear_ratio: 30.0,
            rotor_inertia: 2.0e-7,
            viscous: 1.0e-5,
            coulomb: 2.0e-3,
            coulomb_smoothing: 0.05,
        }
    }
}

impl MotorParams {
    /// The rotor's inertia as seen at the wheel, J_rotor·N², kg·m².
    pub fn reflected_inertia(&self) -> f64 {
        self.rotor_inertia * self.gear_ratio * self.gear_ratio
    }

    /// Checks that the constants describe a motor; names the offending key.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("supply_v", self.supply_v),
            ("resistance_ohm", self.resistance_ohm),
            ("k_t", self.k_t),
            ("k_e", self.k_e),
            ("gear_ratio", self.gear_ratio),
            ("coulomb_smoothing", self.coulomb_smoothing),
        ];
        let non_negative = [
            ("rotor_inertia", self.rotor_inertia),
            ("viscous", self.viscous),
            ("coulomb", self.coulomb),
        ];
        // No hobby or industrial motor comes near 1e6 in any of these units; past it the
        // integration's numbers lose meaning and robots freeze or fly.
        for (key, v) in positive {
            if !(v > 0.0 && v <= 1e6) {
                return Err(format!(
                    "motor.{key} must be positive and at most 1e6, got {v}"
                ));
            }
        }
        for (key, v) in non_negative {
            if !(0.0..=1e6).contains(&v) {
                return Err(format!("motor.{key} must be 0 to 1e6, got {v}"));
            }
        }
        Ok(())
    }
}

/// What the motor does at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MotorOutput {
    /// Voltage actually applied after clamping to the supply, V.
    pub voltage: f64,
    /// Armature current, A.
    pub current: f64,
    /// Torque on the wheel about its axle (the chassis gets the opposite), N·m.
    pub torque: f64,
}

/// Torque at the wheel for commanded voltage `v_cmd` and wheel speed `omega` (relative to the
/// chassis, rad/s).
pub fn torque(p: &MotorParams, v_cmd: f64, omega: f64) -> MotorOutput {
    let voltage = v_cmd.clamp(-p.supply_v, p.supply_v);
    let current = (voltage - p.k_e * p.gear_ratio * omega) / p.resistance_ohm;
    let friction = p.viscous * omega + p.coulomb * (omega / p.coulomb_smoothing).tanh();
    MotorOutput {
        voltage,
        current,
        torque: p.gear_ratio * p.k_t * current - friction,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stalled_motor_gives_full_torque_and_clamps_voltage() {
        let p = MotorParams::default();
        let out = torque(&p, 100.0, 0.0);
        assert_eq!(out.voltage, p.supply_v);
        let stall = p.gear_ratio * p.k_t * p.supply_v / p.resistance_ohm;
        assert!((out.torque - stall).abs() < 1e-12);
    }

    #[test]
    fn back_emf_cancels_torque_at_no_load_speed() {
        let p = MotorParams {
            viscous: 0.0,
            coulomb: 0.0,
            ..MotorParams::default()
        };
        let no_load = p.supply_v / (p.k_e * p.gear_ratio);
        assert!(torque(&p, p.supply_v, no_load).torque.abs() < 1e-12);
        assert!(torque(&p, p.supply_v, 1.1 * no_load).torque < 0.0);
    }

    #[test]
    fn friction_opposes_motion() {
        let p = MotorParams::default();
        assert!(torque(&p, 0.0, 1.0).torque < 0.0);
        assert!(torque(&p, 0.0, -1.0).torque > 0.0);
        assert_eq!(torque(&p, 0.0, 0.0).torque, 0.0);
    }

    #[test]
    fn bad_constants_name_the_key() {
        let p = MotorParams {
            resistance_ohm: 0.0,
            ..MotorParams::default()
        };
        assert!(p.validate().unwrap_err().contains("motor.resistance_ohm"));
    }
}
