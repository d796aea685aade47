/// Everything that can go wrong in a Caravan node. Messages are meant for the person who wrote
/// the launch file or the node, so they name the key, topic or variable involved.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("params of node '{node}': {message}")]
    Params { node: String, message: String },
    #[error("environment variable {var}: {message}")]
    Env { var: &'static str, message: String },
    #[error("{0}")]
    Config(String),
    /// A bad input file or value the node found after reading its params (a world file, a
    /// robot description…); the message names the key and file.
    #[error("{0}")]
    Input(String),
    #[error("topic '{topic}': {message}")]
    Topic { topic: String, message: String },
    #[error("lockstep: {0}")]
    Lockstep(String),
    #[error("{0}")]
    Transport(String),
    #[error("step failed: {0}")]
    Step(String),
}

impl Error {
    pub(crate) fn topic(topic: &str, what: impl core::fmt::Display) -> Self {
        Error::Topic {
            topic: topic.to_string(),
            message: what.to_string(),
        }
    }

    pub fn transport(context: &str, what: impl core::fmt::Debug) -> Self {
        Error::Transport(format!("{context}: {what:?}"))
    }
}
