//! A group's own iceoryx2 namespace.
//!
//! Every group gets an iceoryx2 config whose file prefix is derived from the group name, so two
//! groups using the same topic names never share a shared-memory segment. The launcher writes the
//! config into the run directory and hands its path to each process; tests can build it directly.

use crate::Error;
use iceoryx2::config::Config;
use iceoryx2::prelude::*;
use std::path::Path as StdPath;

/// Ports and nodes per service. iceoryx2's defaults (2 publishers, 8 subscribers, 20 nodes) are
/// too small for a convoy of 64 followers that all publish status and lockstep reports.
pub const MAX_PUBLISHERS: usize = 80;
pub const MAX_SUBSCRIBERS: usize = 80;
pub const MAX_NODES_PER_SERVICE: usize = 160;

/// File-name prefix of every shared-memory and lock file of `group`; `caravan clean` and the
/// launcher look for it under /dev/shm and iceoryx2's temp directory.
pub fn prefix(group: &str) -> String {
    // iceoryx2 file names allow [A-Za-z0-9._-]; keep the prefix short and unambiguous.
    let clean: String = group
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '-'
            }
        })
        .take(40)
        .collect();
    format!("cvn_{clean}_")
}

/// Checks that a group name is usable: non-empty, at most 40 of [A-Za-z0-9-].
pub fn validate_name(group: &str) -> Result<(), String> {
    if group.is_empty() || group.len() > 40 {
        return Err(format!("group name '{group}' must have 1 to 40 characters"));
    }
    if let Some(c) = group
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '-'))
    {
        return Err(format!(
            "group name '{group}' contains '{c}'; use letters, digits and '-'"
        ));
    }
    Ok(())
}

/// The iceoryx2 config of `group`.
pub fn config(group: &str) -> Result<Config, Error> {
    let mut config = Config::default();
    config.global.prefix = FileName::new(prefix(group).as_bytes())
        .map_err(|e| Error::Config(format!("group name '{group}' unusable as a prefix: {e:?}")))?;
    let ps = &mut config.defaults.publish_subscribe;
    ps.max_publishers = MAX_PUBLISHERS;
    ps.max_subscribers = MAX_SUBSCRIBERS;
    ps.max_nodes = MAX_NODES_PER_SERVICE;
    // Must cover the deepest subscriber queue (lossless topics), or iceoryx2 warns.
    ps.subscriber_expired_connection_buffer = 256;
    let ev = &mut config.defaults.event;
    ev.max_notifiers = MAX_PUBLISHERS * 2;
    ev.max_listeners = MAX_SUBSCRIBERS;
    ev.max_nodes = MAX_NODES_PER_SERVICE;
    Ok(config)
}

/// Writes `group`'s config as TOML to `path`.
pub fn write_config(group: &str, path: &StdPath) -> Result<(), Error> {
    let text = toml::to_string(&config(group)?)
        .map_err(|e| Error::Config(format!("cannot serialise iceoryx2 config: {e}")))?;
    std::fs::write(path, text)
        .map_err(|e| Error::Config(format!("cannot write {}: {e}", path.display())))
}

/// Makes the group's config file iceoryx2's global config of this process. iceoryx2 falls back
/// to its global config in places (its clean-up of dead nodes), which it would otherwise read
/// from `config/iceoryx2.toml` in the working directory, the user's or the system's config:
/// a stray file there could point that clean-up at another namespace. Call it before the
/// process first uses iceoryx2; later calls keep the first config.
pub fn use_as_global(path: &StdPath) -> Result<(), Error> {
    let file = iceoryx2::prelude::FilePath::new(path.as_os_str().as_encoded_bytes())
        .map_err(|e| Error::Config(format!("iceoryx2 config path {}: {e:?}", path.display())))?;
    Config::setup_global_config_from_file(&file).map_err(|e| {
        Error::Config(format!(
            "cannot load iceoryx2 config {}: {e:?}",
            path.display()
        ))
    })?;
    Ok(())
}

/// Reads a config written by [`write_config`].
pub fn load_config(path: &StdPath) -> Result<Config, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        Error::Config(format!(
            "cannot read iceoryx2 config {}: {e}",
            path.display()
        ))
    })?;
    toml::from_str(&text)
        .map_err(|e| Error::Config(format!("bad iceoryx2 config {}: {e}", path.display())))
}

/// Removes every shared-memory segment and iceoryx2 file of `group`. Call it only when no
/// process of the group is alive (the launcher after its children exited; `caravan clean` after
/// checking). Returns how many entries were removed.
pub fn remove_resources(group: &str) -> Result<usize, Error> {
    let prefix = prefix(group);
    let root = config(group)?.global.root_path().to_string();
    let mut removed = 0;
    for dir in [
        std::path::PathBuf::from("/dev/shm"),
        std::path::PathBuf::from(root),
    ] {
        removed += remove_prefixed(&dir, &prefix);
    }
    Ok(removed)
}

/// Makes `group`'s shared-memory files private to their owner (0600). iceoryx2 creates one of
/// them, its global management segment, readable and writable by everyone; another user could
/// then write into the group. Every process of a group runs as the launcher's user, so nothing
/// else needs access. Returns how many files were changed.
pub fn make_private(group: &str) -> usize {
    use std::os::unix::fs::PermissionsExt;
    let mut changed = 0;
    for entry in entries_named(StdPath::new("/dev/shm"), &prefix(group), "") {
        let open = entry
            .metadata()
            .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o077 != 0);
        if open
            && std::fs::set_permissions(entry.path(), std::fs::Permissions::from_mode(0o600))
                .is_ok()
        {
            changed += 1;
        }
    }
    changed
}

/// Removes the service descriptions of `config`'s group that a process left half-written,
/// and returns how many. iceoryx2 0.10 writes a service's description with mode 0600 and
/// makes it 0400 once the service is complete; a process killed in between (a SIGKILL while
/// it starts) leaves the service "hanging in creation" for good, and every later open of it
/// fails (fixed after 0.10, iceoryx2#1584). Only files older than the creation timeout are
/// taken: iceoryx2 itself gives up on a creation after that long.
pub fn remove_hung_services(config: &Config) -> usize {
    use std::os::unix::fs::PermissionsExt;
    let global = &config.global;
    let mut removed = 0;
    for entry in entries_named(
        StdPath::new(&global.service_dir().to_string()),
        &global.prefix.to_string(),
        &global.service.static_config_storage_suffix.to_string(),
    ) {
        let hung = entry.metadata().is_ok_and(|m| {
            m.is_file()
                && m.permissions().mode() & 0o777 == 0o600
                && m.modified()
                    .ok()
                    .and_then(|t| t.elapsed().ok())
                    .is_some_and(|age| age > global.creation_timeout)
        });
        if hung && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// The entries of `dir` whose names start with `prefix` and end with `suffix`.
fn entries_named(
    dir: &StdPath,
    prefix: &str,
    suffix: &str,
) -> impl Iterator<Item = std::fs::DirEntry> {
    let (prefix, suffix) = (prefix.to_string(), suffix.to_string());
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(move |e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.starts_with(&prefix) && name.ends_with(&suffix)
        })
}

/// Deletes files under `dir` (recursively) whose name starts with `prefix`, and directories
/// left empty by that.
fn remove_prefixed(dir: &StdPath, prefix: &str) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let path = entry.path();
        let is_ours = entry.file_name().to_string_lossy().starts_with(prefix);
        match entry.file_type() {
            Ok(t) if t.is_dir() => {
                let n = remove_prefixed(&path, prefix);
                removed += n;
                // Node directories hold only one node's files; drop them once emptied.
                if n > 0 && std::fs::remove_dir(&path).is_ok() {
                    removed += 1;
                }
            }
            Ok(_) if is_ours && std::fs::remove_file(&path).is_ok() => removed += 1,
            _ => {}
        }
    }
    removed
}

/// Names of groups that have resources in /dev/shm, from their file prefixes.
pub fn groups_with_resources() -> Vec<String> {
    let mut groups: Vec<String> = std::fs::read_dir("/dev/shm")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            let rest = name.strip_prefix("cvn_")?;
            Some(rest[..rest.find('_')?].to_string())
        })
        .collect();
    groups.sort();
    groups.dedup();
    groups
}
