//! Joint actuators: from a target and the joint's state to the torque (or force, for a
//! prismatic joint) applied this physics step, bounded by the URDF's `<limit effort>`.
//!
//! - **DC motor** (the convoy's): the firmware's incremental speed PID updates at its own
//!   rate from the wheel's angle change; the motor turns its voltage and the joint speed into
//!   torque ([`crate::motor`]). It integrates the joint speed into its own angle, what an
//!   encoder-based firmware sees.
//! - **Velocity**: τ = kp·(ω* − ω) + ki·∫(ω* − ω)dt.
//! - **Position**: τ = kp·(q* − q) + ki·∫(q* − q)dt + kd·(ω* − ω) + τ_ff, as ros2_control's
//!   effort-interface PID.
//! - **Motor**: rapier's velocity motor, solved with the contacts: no explicit torque; the
//!   effort is the motor's impulse over the step.
//! - **Servo**: a spring of the given stiffness to q* and a damper to ω* (default 0), solved
//!   with the step, the spring at most the URDF's effort: rapier's motor on impulse joints,
//!   its implicit joint spring on multibody joints.
//! - **Kinematic**: no torque; the joint is moved at ω* (or to q* at up to its velocity
//!   limit), whatever the load.
//! - **Effort**: τ = τ*.
//!
//! Every loop runs every physics step on the state measured after the previous step, so the
//! torque is explicit: keep kd·dt/I below about 1 (I the inertia the joint moves) or the loop
//! rings. The integral stops growing while the output saturates (no wind-up). Targets beyond
//! the joint's limits are clamped to them.

use crate::firmware::{FirmwareParams, SpeedPid};
use crate::motor::{self, MotorOutput, MotorParams};
use crate::spec::{ActuatorSpec, JointStart};
use caravan_world::description::Limits;

/// A joint's state as the actuator sees it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointReading {
    /// rad or m.
    pub position: f64,
    /// rad/s or m/s.
    pub velocity: f64,
}

/// What the joint is asked to do; NaN fields are "not commanded".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    pub position: f64,
    pub velocity: f64,
    pub effort: f64,
}

impl Default for Target {
    fn default() -> Self {
        Self {
            position: f64::NAN,
            velocity: f64::NAN,
            effort: f64::NAN,
        }
    }
}

impl Target {
    /// Keeps this target's fields where `update` has NaN.
    pub fn merge(&mut self, update: Target) {
        let keep = |old: &mut f64, new: f64| {
            if !new.is_nan() {
                *old = if new.is_finite() { new } else { f64::NAN };
            }
        };
        keep(&mut self.position, update.position);
        keep(&mut self.velocity, update.velocity);
        keep(&mut self.effort, update.effort);
    }
}

/// The convoy's motor and firmware on one joint.
#[derive(Debug, Clone)]
pub struct DcMotor {
    pub motor: MotorParams,
    pub pid_params: FirmwareParams,
    pid: SpeedPid,
    /// Angle integrated from the joint speed, rad.
    pub angle: f64,
    angle_at_tick: f64,
    /// Speed the firmware measured at its last tick, rad/s.
    pub measured: f64,
    /// Joint speed after the last step, rad/s.
    pub speed: f64,
    pub output: MotorOutput,
    next_tick_ns: u64,
    last_tick_ns: Option<u64>,
}

impl DcMotor {
    fn new(motor: MotorParams, pid_params: FirmwareParams) -> Self {
        Self {
            pid: SpeedPid::new(&pid_params, motor.supply_v),
            motor,
            pid_params,
            angle: 0.0,
            angle_at_tick: 0.0,
            measured: 0.0,
            speed: 0.0,
            output: MotorOutput::default(),
            next_tick_ns: 0,
            last_tick_ns: None,
        }
    }
}

/// How the engine moves a joint at exactly its commanded speed, whatever the load.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinematic {
    /// rapier's kinematic multibody joint ([`crate::spec::ActuatorSpec::Kinematic`]).
    Joint,
    /// A wheel welded to its parent, its frame and contacts turned
    /// ([`crate::spec::ActuatorSpec::Rim`]).
    Rim,
}

#[derive(Debug, Clone)]
pub enum Control {
    DcMotor(Box<DcMotor>),
    Velocity {
        kp: f64,
        ki: f64,
        integral: f64,
    },
    Position {
        kp: f64,
        ki: f64,
        kd: f64,
        integral: f64,
    },
    Motor {
        damping: f64,
    },
    Servo {
        stiffness: f64,
        damping: f64,
    },
    Kinematic(Kinematic),
    Effort,
}

/// What rapier's joint motor is set to, each step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorSetting {
    /// Position target, rad or m; used when `stiffness` > 0.
    pub position: f64,
    /// Speed target, rad/s or m/s.
    pub velocity: f64,
    /// Spring to the position target, N·m/rad (N/m); 0 for a pure velocity motor.
    pub stiffness: f64,
    /// Damping of the speed error, ≥ 0, N·m·s/rad (N·s/m): rapier's force-based motor damping,
    /// or a multibody joint's damping under its spring.
    pub damping: f64,
    /// Largest effort, N·m or N.
    pub max_effort: f64,
}

/// One joint's actuator.
#[derive(Debug, Clone)]
pub struct Actuator {
    pub control: Control,
    pub limits: Limits,
    pub target: Target,
    /// Torque or force applied over the last step, N·m or N.
    pub effort: f64,
}

impl Actuator {
    pub fn new(spec: &ActuatorSpec, limits: Limits) -> Option<Self> {
        let control = match spec {
            ActuatorSpec::DcMotor { motor, pid, .. } => {
                Control::DcMotor(Box::new(DcMotor::new(*motor, *pid)))
            }
            ActuatorSpec::Velocity { kp, ki, .. } => Control::Velocity {
                kp: *kp,
                ki: *ki,
                integral: 0.0,
            },
            ActuatorSpec::Position { kp, ki, kd, .. } => Control::Position {
                kp: *kp,
                ki: *ki,
                kd: *kd,
                integral: 0.0,
            },
            ActuatorSpec::Motor { damping, .. } => Control::Motor { damping: *damping },
            ActuatorSpec::Servo {
                stiffness, damping, ..
            } => Control::Servo {
                stiffness: *stiffness,
                damping: *damping,
            },
            ActuatorSpec::Kinematic { .. } => Control::Kinematic(Kinematic::Joint),
            ActuatorSpec::Rim { .. } => Control::Kinematic(Kinematic::Rim),
            ActuatorSpec::Effort { .. } => Control::Effort,
            ActuatorSpec::None { .. } => return None,
        };
        Some(Self {
            control,
            limits,
            target: Target::default(),
            effort: 0.0,
        })
    }

    /// Starts the targets at the joint's initial state, where given: a loop holding a
    /// position (`position`, `servo`) holds the initial position, one following a velocity
    /// keeps the initial velocity.
    pub fn start_at(&mut self, start: JointStart) {
        let (target, given) = match self.control {
            Control::Position { .. } | Control::Servo { .. } => {
                (&mut self.target.position, start.position)
            }
            Control::Effort => return,
            _ => (&mut self.target.velocity, start.velocity),
        };
        if let Some(v) = given {
            *target = v;
        }
    }

    /// The inertia this actuator adds about its joint axis (a motor's rotor through its gear).
    pub fn reflected_inertia(&self) -> f64 {
        match &self.control {
            Control::DcMotor(m) => m.motor.reflected_inertia(),
            _ => 0.0,
        }
    }

    /// How the engine moves this joint at exactly its commanded speed, if it does.
    pub fn kinematic(&self) -> Option<Kinematic> {
        match self.control {
            Control::Kinematic(k) => Some(k),
            _ => None,
        }
    }

    /// The DC motor's firmware, when its tick is due at `now_ns`.
    pub fn firmware_tick(&mut self, now_ns: u64) {
        let Control::DcMotor(m) = &mut self.control else {
            return;
        };
        if now_ns < m.next_tick_ns {
            return;
        }
        let elapsed = m.last_tick_ns.map(|t| (now_ns - t) as f64 * 1e-9);
        m.measured = match elapsed {
            Some(e) if e > 0.0 => (m.angle - m.angle_at_tick) / e,
            _ => 0.0,
        };
        m.angle_at_tick = m.angle;
        let setpoint = if self.target.velocity.is_nan() {
            0.0
        } else {
            self.target.velocity
        };
        m.pid.update(setpoint, m.measured);
        m.last_tick_ns = Some(now_ns);
        m.next_tick_ns += m.pid_params.period_ns();
    }

    /// The torque for this step, given the joint's state after the last step; `dt` in s.
    pub fn torque(&mut self, state: JointReading, dt: f64) -> f64 {
        let l = self.limits;
        let t = self.target;
        let or = |v: f64, default: f64| if v.is_nan() { default } else { v };
        let effort_ff = or(t.effort, 0.0);
        let bound = |tau: f64| tau.clamp(-l.effort, l.effort);
        let tau = match &mut self.control {
            Control::DcMotor(m) => {
                m.output = motor::torque(&m.motor, m.pid.output(), m.speed);
                bound(m.output.torque)
            }
            // The engine sets the motor ([`Self::motor`]) and reads its effort back, or moves
            // a kinematic joint ([`Self::kinematic_velocity`]).
            Control::Motor { .. } | Control::Servo { .. } | Control::Kinematic(_) => {
                return 0.0;
            }
            Control::Effort => bound(effort_ff),
            Control::Velocity { kp, ki, integral } => {
                let target = or(t.velocity, 0.0).clamp(-l.velocity, l.velocity);
                let e = target - state.velocity;
                let raw = *kp * e + *ki * (*integral + e * dt) + effort_ff;
                let tau = bound(raw);
                if tau == raw {
                    *integral += e * dt;
                }
                tau
            }
            Control::Position {
                kp,
                ki,
                kd,
                integral,
            } => {
                let target = or(t.position, state.position).clamp(l.lower, l.upper);
                let speed = or(t.velocity, 0.0).clamp(-l.velocity, l.velocity);
                let e = target - state.position;
                let raw = *kp * e
                    + *ki * (*integral + e * dt)
                    + *kd * (speed - state.velocity)
                    + effort_ff;
                let tau = bound(raw);
                if tau == raw {
                    *integral += e * dt;
                }
                tau
            }
        };
        self.effort = tau;
        tau
    }

    /// What rapier's motor is set to: a velocity motor's speed target (clamped to the
    /// joint's limit; none commanded: hold still), a servo's position target (clamped to the
    /// limits; none commanded: the joint's zero) and feed-forward speed; `None` for other
    /// actuators.
    pub fn motor(&self) -> Option<MotorSetting> {
        let l = self.limits;
        let or = |v: f64, default: f64| if v.is_nan() { default } else { v };
        let velocity = or(self.target.velocity, 0.0).clamp(-l.velocity, l.velocity);
        match self.control {
            Control::Motor { damping } => Some(MotorSetting {
                position: 0.0,
                velocity,
                stiffness: 0.0,
                damping,
                max_effort: l.effort,
            }),
            Control::Servo { stiffness, damping } => Some(MotorSetting {
                position: or(self.target.position, 0.0).clamp(l.lower, l.upper),
                velocity,
                stiffness,
                damping,
                max_effort: l.effort,
            }),
            _ => None,
        }
    }

    /// The speed a kinematic joint moves at over the next step of `dt` s, from its state
    /// `now`: to the position target in one step if the velocity limit allows (else at the
    /// limit toward it), else the velocity target, else 0; never past the joint's position
    /// limits (nothing else holds them: see `ActuatorSpec::Kinematic`); `None` for other
    /// actuators.
    pub fn kinematic_velocity(&self, now: JointReading, dt: f64) -> Option<f64> {
        self.kinematic()?;
        let l = self.limits;
        let t = self.target;
        let speed = if !t.position.is_nan() {
            (t.position - now.position) / dt
        } else if !t.velocity.is_nan() {
            t.velocity
        } else {
            0.0
        };
        let within = (l.lower - now.position) / dt..=(l.upper - now.position) / dt;
        Some(
            speed
                .clamp(*within.start(), *within.end())
                .clamp(-l.velocity, l.velocity),
        )
    }

    /// After the step: a DC motor integrates the joint speed into its angle.
    pub fn after_step(&mut self, speed: f64, dt: f64) {
        if let Control::DcMotor(m) = &mut self.control {
            m.speed = speed;
            m.angle += speed * dt;
        }
    }

    pub fn dc_motor(&self) -> Option<&DcMotor> {
        match &self.control {
            Control::DcMotor(m) => Some(m),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(effort: f64) -> Limits {
        Limits {
            lower: -1.0,
            upper: 1.0,
            effort,
            velocity: 2.0,
        }
    }

    fn position(kp: f64, ki: f64, kd: f64) -> Actuator {
        let spec = ActuatorSpec::Position {
            joints: vec![],
            kp,
            ki,
            kd,
        };
        Actuator::new(&spec, limits(5.0)).unwrap()
    }

    #[test]
    fn position_loop_is_a_pd_with_clamped_target_and_effort() {
        let mut a = position(10.0, 0.0, 1.0);
        a.target.position = 0.5;
        let tau = a.torque(
            JointReading {
                position: 0.25,
                velocity: 0.5,
            },
            0.001,
        );
        assert!((tau - (10.0 * 0.25 - 0.5)).abs() < 1e-12);
        a.target.position = 3.0; // beyond the upper limit 1.0
        let tau = a.torque(JointReading::default(), 0.001);
        assert_eq!(tau, 5.0, "10·1.0 = 10 N·m bounded by effort 5");
    }

    #[test]
    fn the_integral_does_not_wind_up_while_saturated() {
        let mut a = position(10.0, 100.0, 0.0);
        a.target.position = 1.0;
        for _ in 0..1000 {
            a.torque(JointReading::default(), 0.01);
        }
        let Control::Position { integral, .. } = a.control else {
            unreachable!()
        };
        assert_eq!(integral, 0.0);
    }

    #[test]
    fn targets_merge_field_by_field() {
        let mut t = Target::default();
        t.merge(Target {
            position: 1.0,
            ..Target::default()
        });
        t.merge(Target {
            velocity: 2.0,
            ..Target::default()
        });
        assert_eq!((t.position, t.velocity), (1.0, 2.0));
        assert!(t.effort.is_nan());
    }

    #[test]
    fn effort_actuator_is_bounded() {
        let mut a = Actuator::new(&ActuatorSpec::Effort { joints: vec![] }, limits(3.0)).unwrap();
        a.target.effort = -7.0;
        assert_eq!(a.torque(JointReading::default(), 0.001), -3.0);
    }
}
