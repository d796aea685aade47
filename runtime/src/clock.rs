/// How a group's time advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ClockMode {
    /// Steps follow the wall clock; waiting is event-driven.
    #[default]
    Realtime,
    /// Simulated time is granted step by step by the group's scheduler.
    Lockstep,
}

impl std::str::FromStr for ClockMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "realtime" => Ok(ClockMode::Realtime),
            "lockstep" => Ok(ClockMode::Lockstep),
            other => Err(format!(
                "unknown clock '{other}', expected 'realtime' or 'lockstep'"
            )),
        }
    }
}

impl std::fmt::Display for ClockMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ClockMode::Realtime => "realtime",
            ClockMode::Lockstep => "lockstep",
        })
    }
}
