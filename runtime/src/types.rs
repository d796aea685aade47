//! Message types that a group's tools learn at run time.
//!
//! The recorder, `caravan topic echo` and `pub`, replay and the Python module meet topics of
//! types they were not compiled with: a scenario's or a user's own. A process that opens a
//! topic of such a type registers the type's [`Descriptor`] with its group, as a file beside the
//! group's shared memory (mode 0600, removed with it); a tool reads it back by the type's
//! stable name, which iceoryx2 keeps with each topic. The catalog's types
//! ([`caravan_schemas::catalog`]) every process knows and are never registered.
//!
//! Two processes that give one type name two different layouts are refused at the second's
//! port, naming the type: what iceoryx2 checks of a type (size and alignment) would let fields
//! that differ in name or order through.

use crate::Error;
use caravan_schemas::Message;
use caravan_schemas::descriptor::{Descriptor, layout_json};
use iceoryx2::config::Config;
use std::collections::BTreeSet;
use std::io::Write;
use std::os::unix::fs::OpenOptionsExt;
use std::path::PathBuf;
use std::sync::Mutex;

/// Largest descriptor file read, bytes: a descriptor describes a handful of structs.
const MAX_FILE_BYTES: u64 = 1 << 20;

/// Where the descriptor of the type named `type_name` is registered in `config`'s group: in
/// iceoryx2's directory, named with the group's prefix so that cleaning the group removes it.
fn path(config: &Config, type_name: &str) -> PathBuf {
    let root = config.global.root_path().to_string();
    let prefix = config.global.prefix.to_string();
    let hash = caravan_schemas::lockstep::name_hash(type_name);
    PathBuf::from(root).join(format!("{prefix}type_{hash:016x}.json"))
}

/// Registers the descriptor of `T` with the group of `config`, once per process; nothing for a
/// catalog type.
pub(crate) fn register_type<T: Message>(config: &Config) -> Result<(), Error> {
    static DONE: Mutex<BTreeSet<(String, &'static str)>> = Mutex::new(BTreeSet::new());
    let type_name = caravan_schemas::type_name::<T>();
    if caravan_schemas::catalog::descriptor(type_name).is_some() {
        return Ok(());
    }
    let key = (config.global.prefix.to_string(), type_name);
    if DONE
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .contains(&key)
    {
        return Ok(());
    }
    register(config, &caravan_schemas::descriptor_of::<T>())?;
    DONE.lock().unwrap_or_else(|e| e.into_inner()).insert(key);
    Ok(())
}

/// Registers `descriptor` with the group of `config`. A descriptor registered before under the
/// same type name must be the same.
pub fn register(config: &Config, descriptor: &Descriptor) -> Result<(), Error> {
    let type_name = descriptor.type_name();
    let target = path(config, type_name);
    let text = serde_json::to_string(&descriptor.to_json()).expect("JSON serialises");
    // Written whole under a name of its own, then linked into place: a reader never sees half
    // a file, and of two processes registering at once, one links and the other compares.
    let temp = target.with_extension(format!("{}.tmp", std::process::id()));
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .mode(0o600)
        .open(&temp)
        .and_then(|mut f| f.write_all(text.as_bytes()));
    let linked = written.and_then(|_| std::fs::hard_link(&temp, &target));
    let _ = std::fs::remove_file(&temp);
    match linked {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            let known = lookup(config, type_name)?;
            if known == *descriptor {
                Ok(())
            } else {
                Err(Error::Config(format!(
                    "message type '{type_name}' is declared with two layouts in this group: \
                     {} and {}; the processes that use it were built from different declarations",
                    known.to_json(),
                    descriptor.to_json()
                )))
            }
        }
        Err(e) => Err(Error::Config(format!(
            "cannot register message type '{type_name}' at {}: {e}",
            target.display()
        ))),
    }
}

/// Makes a type that a recording describes known to the group of `config`, for replaying it:
/// a catalog type must be laid out as recorded (a recording of an older Caravan may not be);
/// any other type is registered as if a process of the group had opened a port of it.
pub fn adopt(config: &Config, recorded: &Descriptor) -> Result<(), Error> {
    let type_name = recorded.type_name();
    match caravan_schemas::catalog::descriptor(type_name) {
        Some(known) if known.layouts() == recorded.layouts() => Ok(()),
        Some(known) => Err(Error::Config(format!(
            "message type '{type_name}' was recorded with the layout {}, but this Caravan \
             lays it out as {}; replay the recording with the Caravan that made it",
            serde_json::Value::Array(recorded.layouts().iter().map(layout_json).collect()),
            serde_json::Value::Array(known.layouts().iter().map(layout_json).collect()),
        ))),
        None => register(config, recorded),
    }
}

/// The descriptor of the type named `type_name` in the group of `config`: a catalog type's, or
/// the one a process of the group registered.
pub fn lookup(config: &Config, type_name: &str) -> Result<Descriptor, Error> {
    if let Some(d) = caravan_schemas::catalog::descriptor(type_name) {
        return Ok(d.clone());
    }
    let file = path(config, type_name);
    let unknown = |why: String| {
        Error::Config(format!(
            "unknown message type '{type_name}': no process of the group registered it ({why})"
        ))
    };
    let size = std::fs::metadata(&file)
        .map_err(|e| unknown(e.to_string()))?
        .len();
    if size > MAX_FILE_BYTES {
        return Err(unknown(format!("its descriptor takes {size} bytes")));
    }
    let text = std::fs::read_to_string(&file).map_err(|e| unknown(e.to_string()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| unknown(format!("{}: {e}", file.display())))?;
    let d =
        Descriptor::from_json(&json).map_err(|e| unknown(format!("{}: {e}", file.display())))?;
    if d.type_name() != type_name {
        return Err(unknown(format!(
            "{} describes '{}'",
            file.display(),
            d.type_name()
        )));
    }
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A group's configuration with its own directory, made the way its first node makes it.
    fn config(tag: &str) -> Config {
        let group = format!("types-{tag}-{}", std::process::id());
        let config = crate::group::config(&group).unwrap();
        std::fs::create_dir_all(config.global.root_path().to_string()).unwrap();
        config
    }

    #[test]
    fn a_recorded_type_is_adopted_and_a_catalog_type_laid_out_otherwise_is_refused() {
        let config = config("adopt");
        // A type no process declares: registered, then found.
        let mut json = caravan_schemas::catalog::descriptor("caravan::Pose2D")
            .unwrap()
            .to_json();
        json["layouts"][0]["type_name"] = json!("test::Recorded");
        let recorded = Descriptor::from_json(&json).unwrap();
        adopt(&config, &recorded).unwrap();
        assert_eq!(lookup(&config, "test::Recorded").unwrap(), recorded);
        let _ = std::fs::remove_file(path(&config, "test::Recorded"));
        // The catalog's own layout is adopted as it is; another is refused, naming both.
        let pose = caravan_schemas::catalog::descriptor("caravan::Pose2D").unwrap();
        adopt(&config, pose).unwrap();
        let mut json = pose.to_json();
        json["layouts"][0]["fields"][2]["name"] = json!("heading");
        json["default"] = json!({"x": 0.0, "y": 0.0, "heading": 0.0});
        let e = adopt(&config, &Descriptor::from_json(&json).unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("'caravan::Pose2D' was recorded with the layout")
                && e.contains("heading")
                && e.contains("theta"),
            "{e}"
        );
    }
}
