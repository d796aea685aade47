//! A shard's manifest, `<out>/shards/K-of-N.json`: which sweep the shard belongs to (its
//! definition and a fingerprint of it), which Caravan ran it, and which runs are the shard's.
//! `caravan sweep merge` rebuilds the sweep from it and refuses to join shards whose
//! fingerprints or versions differ.
//!
//! The manifest is written when the shard starts, before any run, so a shard that was killed
//! still says what it was meant to run; what it finished is in its run directories.

use super::grid::{Axis, fnv};
use super::shard::Shard;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The Caravan that ran a shard. Shards of different versions may have measured differently.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// What identifies a sweep: everything that decides its runs and their results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Definition {
    pub name: String,
    /// The launch file as the sweep named it.
    pub launch: PathBuf,
    /// FNV-1a of the launch file's bytes, in hex: a shard run from an edited launch file is
    /// another sweep. (Files the launch file includes are not hashed.)
    pub launch_hash: String,
    pub seeds: Vec<u64>,
    /// The overrides of every run.
    pub sets: Vec<String>,
    pub duration: Option<String>,
    pub axes: Vec<Axis>,
}

impl Definition {
    /// A stable hash of the definition (its JSON), in hex.
    pub fn fingerprint(&self) -> String {
        let json = serde_json::to_string(self).expect("a definition serialises");
        format!("{:016x}", fnv(json.as_bytes()))
    }
}

/// One run of the shard: a cell by id, and a seed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRef {
    pub cell: String,
    pub seed: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub caravan: String,
    pub fingerprint: String,
    /// Shard number, from 1.
    pub shard: usize,
    pub shards: usize,
    pub sweep: Definition,
    pub runs: Vec<RunRef>,
}

impl Manifest {
    pub fn new(sweep: Definition, shard: Shard, runs: Vec<RunRef>) -> Self {
        Self {
            caravan: VERSION.into(),
            fingerprint: sweep.fingerprint(),
            shard: shard.k,
            shards: shard.n,
            sweep,
            runs,
        }
    }

    pub fn shard(&self) -> Shard {
        Shard {
            k: self.shard,
            n: self.shards,
        }
    }

    /// Writes `<out>/shards/K-of-N.json`, replacing an earlier attempt's.
    pub fn write(&self, out: &Path) -> Result<()> {
        let dir = out.join("shards");
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        let path = dir.join(self.shard().file_name());
        let text = serde_json::to_string_pretty(self)? + "\n";
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))
    }
}

/// The manifests in `dir/shards`, with their paths, sorted by path; a file that is not a
/// manifest is an error naming it.
pub fn read_all(dir: &Path) -> Result<Vec<(PathBuf, Manifest)>, String> {
    let shards = dir.join("shards");
    let entries = std::fs::read_dir(&shards).map_err(|e| {
        format!(
            "{}: no shard manifests ({}: {e}); is it a sweep's output directory?",
            dir.display(),
            shards.display()
        )
    })?;
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(format!(
            "{}: no shard manifests in {}",
            dir.display(),
            shards.display()
        ));
    }
    paths
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p)
                .map_err(|e| format!("cannot read {}: {e}", p.display()))?;
            let m: Manifest = serde_json::from_str(&text)
                .map_err(|e| format!("{}: not a shard manifest: {e}", p.display()))?;
            Ok((p, m))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn definition() -> Definition {
        Definition {
            name: "gain".into(),
            launch: "launch/pingpong.toml".into(),
            launch_hash: format!("{:016x}", fnv(b"[group]")),
            seeds: vec![1, 2],
            sets: vec!["group.clock=\"lockstep\"".into()],
            duration: Some("2s".into()),
            axes: vec![Axis::plain(
                "process.pong.params.gain",
                vec!["1".into(), "3".into()],
            )],
        }
    }

    #[test]
    fn the_fingerprint_changes_with_anything_that_decides_a_run() {
        let base = definition();
        assert_eq!(base.fingerprint(), definition().fingerprint());
        let mut other = definition();
        other.seeds.push(3);
        assert_ne!(base.fingerprint(), other.fingerprint());
        let mut other = definition();
        other.launch_hash = format!("{:016x}", fnv(b"[group] "));
        assert_ne!(base.fingerprint(), other.fingerprint());
        let mut other = definition();
        other.axes[0].values[1].label = "4".into();
        assert_ne!(base.fingerprint(), other.fingerprint());
    }

    #[test]
    fn a_manifest_round_trips_and_axes_come_back_whole() {
        let dir = std::env::temp_dir().join(format!("caravan-manifest-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let runs = vec![RunRef {
            cell: "gain=3".into(),
            seed: 2,
        }];
        let m = Manifest::new(definition(), Shard { k: 2, n: 3 }, runs);
        m.write(&dir).unwrap();
        let read = read_all(&dir).unwrap();
        assert_eq!(read.len(), 1);
        assert!(read[0].0.ends_with("shards/2-of-3.json"));
        assert_eq!(read[0].1, m);
        assert_eq!(
            read[0].1.sweep.axes[0],
            Axis::plain("process.pong.params.gain", vec!["1".into(), "3".into()])
        );
        std::fs::write(dir.join("shards/x.json"), "{}").unwrap();
        assert!(read_all(&dir).unwrap_err().contains("not a shard manifest"));
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(read_all(&dir).unwrap_err().contains("no shard manifests"));
    }
}
