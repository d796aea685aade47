//! Launch files: the model, parsing with `--set` overrides, and validation.

pub mod args;
pub mod load;
pub mod model;
pub mod overrides;
pub mod suggest;
