//! Launch files: the model, reading with includes, templates, arguments and `--set`
//! overrides, and validation. No shared memory: loading a launch file starts nothing.

pub mod args;
mod check;
mod container;
mod convert;
mod include;
pub mod load;
pub mod model;
pub mod overrides;
pub mod problem;
mod sections;
pub mod source;
pub mod suggest;
mod template;

pub use convert::value_json;
pub use load::{load_checked, load_source};
pub use model::LaunchFile;
pub use problem::{LaunchError, Problem};

#[cfg(test)]
mod tests;
