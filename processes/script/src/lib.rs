//! `caravan-script`: scripted commands for any scenario, from its launch file. A timeline of
//! messages, each of any of Caravan's message types by name with its fields as TOML, published
//! once at a simulated time (`at_s`), on every step of an interval (`from_s` … `until_s`,
//! optionally every `every_s`), or once when a field of another topic crosses a threshold
//! (`when`). Everything is checked before the group starts (see [`params`]); see
//! docs/processes.md, "caravan-script".
//!
//! - [`timeline`]: which commands a step publishes;
//! - [`message`]: a message's bytes from its JSON, over the type's default;
//! - [`field`]: a trigger's number inside a message, by its path;
//! - [`params`]: the params and their checks.

pub mod field;
pub mod message;
pub mod params;
pub mod timeline;
