//! Quiet reports: the count of steps granted "quietly" and not yet reported, shared by the
//! scheduler and the nodes of one machine, so that a node wakes the scheduler only when its
//! report could matter.
//!
//! Without it every finished step notifies the scheduler, which wakes, reads the reports in
//! and sleeps again: 3.3–3.5 wake-ups of the scheduler per 10 ms tick in the convoy (9.3
//! reports), each a context switch and 10–20 µs of CPU on a two-core machine. With it the scheduler grants a step
//! *quiet* (`Grant::quiet`) to a node that holds this count (its `Hello::quiet` names the
//! count's token); the node takes one off the count before it reports and notifies only when
//! at most one quiet step is left: when the slowest node alone still runs (the scheduler
//! grants what may overlap it) and when the last one ends. Reports are read, as before, from
//! the `done` service whenever the scheduler wakes; what they say, and so every recording, is
//! the same.
//!
//! The count is the head of a file in /dev/shm named with the group's prefix (so `caravan
//! clean` removes it), mode 0600: a token (u32, never 0) that tells a node of another
//! machine's group, or of an earlier run, from one of this run, and the count (i64). The rest
//! of the file is a report slot for each node of this machine (`slots.rs`). A count that
//! drifts (a node died in a quiet step) is set back to 0 whenever no step is outstanding;
//! until then it only costs wake-ups (too low: more notifications) or a wait of the
//! scheduler's poll (too high by two or more).

use crate::Error;
use std::path::PathBuf;
use std::sync::atomic::{AtomicI64, AtomicU32, Ordering};

/// Quiet steps left after which a report notifies: the slowest node alone (1) or none (0).
const NOTIFY_AT_OR_BELOW: i64 = 1;

// The page's layout: the token and the count in the first 64 bytes, then the report slots
// (`slots.rs`).
/// Nodes of one machine that get a slot; more report through `Done` samples.
pub const SLOTS: usize = 512;
/// The directory: a node hash for each slot (0: free), after the page's 64-byte head.
pub(super) const DIRECTORY: usize = 64;
/// The first slot, 64-aligned.
pub(super) const FIRST: usize = DIRECTORY + SLOTS * 8;
/// A slot: 64 bytes kept for a grant, then the report: `ready` (the reported step's time
/// + 1, 0 for none), `wake_ns`, `undeclared` (u32), the count of topics (u32), the topics.
pub(super) const SLOT: usize =
    (64 + 24 + caravan_schemas::lockstep::MAX_TOPICS * 8).next_multiple_of(64);
/// Where a slot's report starts.
pub(super) const REPORT: usize = 64;
/// Bytes of the page.
pub(super) const SIZE: usize = FIRST + SLOTS * SLOT;

/// The page the scheduler shares with the nodes of its machine: the count of quiet steps
/// outstanding, and a report slot for each node (`slots.rs`).
pub struct Pending {
    /// Written through raw pointers only (atomics and the slots' copies), never through a
    /// reference to its bytes.
    pub(super) map: memmap2::MmapRaw,
    /// The scheduler's side removes the file when dropped.
    owned: Option<PathBuf>,
}

fn path(config: &iceoryx2::config::Config) -> PathBuf {
    PathBuf::from(format!(
        "/dev/shm/{}lockstep_pending",
        config.global.prefix.as_str()
    ))
}

impl Pending {
    /// Creates the count for the group of `config` (the scheduler's side), replacing one an
    /// earlier run left, with a new token.
    pub fn create(config: &iceoryx2::config::Config) -> Result<Self, Error> {
        use std::os::unix::fs::OpenOptionsExt;
        let path = path(config);
        let _ = std::fs::remove_file(&path);
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .mode(0o600)
            .open(&path)
            .and_then(|f| f.set_len(SIZE as u64).map(|_| f))
            .map_err(|e| Error::Lockstep(format!("cannot create {}: {e}", path.display())))?;
        let map = memmap2::MmapRaw::map_raw(&file)
            .map_err(|e| Error::Lockstep(format!("cannot map {}: {e}", path.display())))?;
        let pending = Self {
            map,
            owned: Some(path),
        };
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let token = (nanos ^ std::process::id().rotate_left(16)) | 1;
        pending.token_cell().store(token, Ordering::SeqCst);
        Ok(pending)
    }

    /// [`Self::create`], or `None` said on stderr: without the count every report wakes the
    /// scheduler, which is slower, not wrong.
    pub fn create_or_warn(config: &iceoryx2::config::Config) -> Option<Self> {
        (Self::create(config))
            .inspect_err(|e| eprintln!("caravan: every lockstep report wakes the scheduler: {e}"))
            .ok()
    }

    /// Opens the count of the group of `config` (a node's side), if this machine has one: a
    /// regular file of this user's, private to it, of the page's size (not a link, nor a file
    /// another user put there first).
    pub fn open(config: &iceoryx2::config::Config) -> Option<Self> {
        use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(path(config))
            .ok()?;
        let meta = file.metadata().ok()?;
        // SAFETY: geteuid has no preconditions.
        let own = meta.uid() == unsafe { libc::geteuid() };
        if !(meta.is_file() && own && meta.mode() & 0o077 == 0 && meta.len() == SIZE as u64) {
            return None;
        }
        let map = memmap2::MmapRaw::map_raw(&file).ok()?;
        Some(Self { map, owned: None })
    }

    fn token_cell(&self) -> &AtomicU32 {
        // SAFETY: the map is SIZE bytes (checked when made or opened), page-aligned, writable,
        // lives as long as `self`, and is only ever accessed through these atomics. (A process
        // of the same user that shortens the file makes the next access fault: that user can
        // stop the group anyway.)
        unsafe { AtomicU32::from_ptr(self.map.as_mut_ptr().cast()) }
    }

    fn count(&self) -> &AtomicI64 {
        // SAFETY: as in `token_cell`, for bytes 8..16, which are 8-aligned.
        unsafe { AtomicI64::from_ptr(self.map.as_mut_ptr().add(8).cast()) }
    }

    /// The token that tells this run's count from any other (never 0).
    pub fn token(&self) -> u32 {
        self.token_cell().load(Ordering::SeqCst)
    }

    /// The scheduler is about to grant `quiet` quiet steps (counted before the grants go out,
    /// so no report can take the count below); `idle`: no step is outstanding, so a count
    /// above 0 is drift (a node died in a quiet step). Returns the token to grant them under.
    pub fn granting(&self, quiet: usize, idle: bool) -> u32 {
        if idle {
            self.reset();
        }
        self.add(quiet as i64);
        self.token()
    }

    /// The scheduler grants `n` quiet steps (before it sends the grants).
    pub fn add(&self, n: i64) {
        self.count().fetch_add(n, Ordering::SeqCst);
    }

    /// No step is outstanding: whatever the count says is drift.
    pub fn reset(&self) {
        self.count().store(0, Ordering::SeqCst);
    }

    /// A node finished a quiet step (before it reports): whether it must notify.
    pub fn finish(&self) -> bool {
        self.count().fetch_sub(1, Ordering::SeqCst) - 1 <= NOTIFY_AT_OR_BELOW
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        if let Some(path) = &self.owned {
            let _ = std::fs::remove_file(path);
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// The config of a group of its own for the test `name` (the slots' tests use it too).
    pub(in crate::lockstep) fn config(name: &str) -> iceoryx2::config::Config {
        let group = format!("pending-{name}-{}", std::process::id());
        crate::group::config(&group).unwrap()
    }

    #[test]
    fn a_node_notifies_when_at_most_one_quiet_step_is_left() {
        let config = config("notify");
        let scheduler = Pending::create(&config).unwrap();
        let node = Pending::open(&config).expect("the node finds the count");
        assert_eq!(node.token(), scheduler.token());
        assert_ne!(scheduler.token(), 0);
        scheduler.add(4);
        let notified: Vec<bool> = (0..4).map(|_| node.finish()).collect();
        assert_eq!(notified, [false, false, true, true]);
    }

    #[test]
    fn a_count_another_made_is_not_opened() {
        use std::os::unix::fs::PermissionsExt;
        let config = config("foreign");
        let at = path(&config);
        // Readable by others: not the group's own.
        std::fs::write(&at, vec![0u8; SIZE]).unwrap();
        std::fs::set_permissions(&at, std::fs::Permissions::from_mode(0o644)).unwrap();
        assert!(Pending::open(&config).is_none());
        std::fs::remove_file(&at).unwrap();
        // A link to a file of the right shape.
        let target = std::env::temp_dir().join(format!("pending-target-{}", std::process::id()));
        std::fs::write(&target, vec![0u8; SIZE]).unwrap();
        std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o600)).unwrap();
        std::os::unix::fs::symlink(&target, &at).unwrap();
        assert!(Pending::open(&config).is_none());
        std::fs::remove_file(&at).unwrap();
        std::fs::remove_file(&target).unwrap();
    }

    #[test]
    fn the_count_is_private_and_gone_with_its_scheduler() {
        use std::os::unix::fs::PermissionsExt;
        let config = config("private");
        let scheduler = Pending::create(&config).unwrap();
        let mode = std::fs::metadata(path(&config))
            .unwrap()
            .permissions()
            .mode();
        assert_eq!(mode & 0o777, 0o600);
        drop(scheduler);
        assert!(Pending::open(&config).is_none());
    }

    #[test]
    fn drift_is_reset_and_a_new_run_gets_a_new_token() {
        let config = config("drift");
        let first = Pending::create(&config).unwrap();
        first.add(3);
        first.reset();
        first.add(1);
        assert!(Pending::open(&config).unwrap().finish());
        let token = first.token();
        drop(first);
        std::thread::sleep(std::time::Duration::from_millis(1));
        let second = Pending::create(&config).unwrap();
        assert_ne!(second.token(), 0);
        // From the clock (a millisecond apart here) and the process.
        assert_ne!(second.token(), token);
    }
}
