//! Launch files: the model, reading with includes, templates, arguments and `--set`
//! overrides, and validation.

pub mod args;
mod check;
pub mod command;
mod convert;
mod include;
pub mod load;
pub mod model;
pub mod overrides;
mod sections;
pub mod source;
pub mod suggest;
mod template;

#[cfg(test)]
mod tests;
