//! Shards: a sweep's runs split N ways so that N machines (a Slurm job array, a Kubernetes
//! Indexed Job, GNU parallel over ssh) each run one part into the same output layout.
//!
//! The rule is round-robin over the sweep's runs in their canonical order (seed-major, as the
//! local sweep starts them: every cell's first seed, then every cell's second…): run `i` belongs
//! to shard `i mod N + 1`. It depends only on the sweep's definition and N, never on which
//! shards ran, and it spreads every seed over the shards so that each shard's load is about
//! the same.

/// Shard `k` of `n`, numbered from 1 like `--array=1-N` and nextest's `--partition`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Shard {
    pub k: usize,
    pub n: usize,
}

/// The most shards a sweep is split into (Slurm's default `MaxArraySize` is 1001, so array
/// ids 1..=1000 fit).
pub const MAX_SHARDS: usize = 1000;

impl Shard {
    /// The whole sweep, unsplit.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// Whether the run at `index` in the canonical order belongs to this shard.
    pub fn has(self, index: usize) -> bool {
        index % self.n == self.k - 1
    }

    /// The shard that run `index` belongs to when the sweep is split `n` ways.
    pub fn of(index: usize, n: usize) -> Shard {
        Shard {
            k: index % n + 1,
            n,
        }
    }

    /// The file name of this shard's manifest: `2-of-3.json`.
    pub fn file_name(self) -> String {
        format!("{}-of-{}.json", self.k, self.n)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

/// Parses `--shard`: `K/N`, `env` (both from a Slurm job array's environment) or `env/N` (K
/// from the environment, N given). `env` reads a variable through `var`.
///
/// From the environment, K is `SLURM_ARRAY_TASK_ID` (the array's ids are the shard numbers:
/// submit `--array=1-N`) or Kubernetes' `JOB_COMPLETION_INDEX` + 1 (it counts from 0); N is
/// `SLURM_ARRAY_TASK_COUNT`. Kubernetes does not tell a pod the number of completions, so there
/// N must be given (`env/N`); Caravan's own Slurm script gives it too, because a resubmission
/// that runs only some ids (`--array=2,5`) has a smaller task count than N.
pub fn parse(text: &str, var: impl Fn(&str) -> Option<String>) -> Result<Shard, String> {
    let (k, n) = match text.trim().split_once('/') {
        Some((k, n)) => (k.trim(), Some(n.trim())),
        None if text.trim() == "env" => ("env", None),
        None => return Err(format!("--shard {text}: expected K/N, env or env/N")),
    };
    let number = |what: &str, s: &str| {
        s.parse::<usize>()
            .map_err(|_| format!("--shard {text}: '{s}' is not a {what} (a whole number ≥ 1)"))
    };
    let n = match n {
        Some(n) => number("shard count", n)?,
        None => {
            let count = var("SLURM_ARRAY_TASK_COUNT").ok_or_else(|| {
                format!(
                    "--shard {text}: SLURM_ARRAY_TASK_COUNT is not set (not in a Slurm job array); \
                     elsewhere give the count: --shard env/N"
                )
            })?;
            number("shard count (SLURM_ARRAY_TASK_COUNT)", &count)?
        }
    };
    let k = if k == "env" {
        if let Some(id) = var("SLURM_ARRAY_TASK_ID") {
            number("shard number (SLURM_ARRAY_TASK_ID)", &id)?
        } else if let Some(index) = var("JOB_COMPLETION_INDEX") {
            let index = index.parse::<usize>().map_err(|_| {
                format!("--shard {text}: JOB_COMPLETION_INDEX='{index}' is not a whole number")
            })?;
            index + 1
        } else {
            return Err(format!(
                "--shard {text}: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set \
                 (not in a job array)"
            ));
        }
    } else {
        number("shard number", k)?
    };
    if n == 0 || n > MAX_SHARDS {
        return Err(format!(
            "--shard {text}: {n} shards; a sweep is split into 1 to {MAX_SHARDS}"
        ));
    }
    if k == 0 || k > n {
        return Err(format!(
            "--shard {text}: shard {k} of {n} does not exist; shards are numbered 1 to {n} \
             (in Slurm: --array=1-{n})"
        ));
    }
    Ok(Shard { k, n })
}

/// Array ids as Slurm's `--array` takes them, runs of consecutive ids as ranges: `1-3,5`.
pub fn array_spec(ids: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < ids.len() {
        let start = ids[i];
        while i + 1 < ids.len() && ids[i + 1] == ids[i] + 1 {
            i += 1;
        }
        parts.push(if ids[i] == start {
            start.to_string()
        } else {
            format!("{start}-{}", ids[i])
        });
        i += 1;
    }
    parts.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| {
            vars.iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn every_run_is_in_exactly_one_shard_and_the_loads_differ_by_one_at_most() {
        for n in 1..7 {
            let mut counts = vec![0; n];
            for index in 0..23 {
                let owners: Vec<usize> = (1..=n).filter(|&k| Shard { k, n }.has(index)).collect();
                assert_eq!(owners, [Shard::of(index, n).k]);
                counts[owners[0] - 1] += 1;
            }
            let (lo, hi) = (counts.iter().min(), counts.iter().max());
            assert!(hi.unwrap() - lo.unwrap() <= 1, "{counts:?}");
        }
    }

    #[test]
    fn explicit_shards() {
        let none = env(&[]);
        assert_eq!(parse("2/3", &none), Ok(Shard { k: 2, n: 3 }));
        assert_eq!(parse(" 1 / 1 ", &none), Ok(Shard::ALL));
        assert!(parse("0/3", &none).unwrap_err().contains("numbered 1 to 3"));
        assert!(parse("4/3", &none).unwrap_err().contains("does not exist"));
        assert!(parse("1/0", &none).unwrap_err().contains("1 to 1000"));
        assert!(parse("1/1001", &none).is_err());
        assert!(parse("a/3", &none).unwrap_err().contains("'a'"));
        assert!(parse("3", &none).unwrap_err().contains("K/N"));
        assert!(parse("-1/3", &none).is_err());
    }

    #[test]
    fn shards_from_a_job_array() {
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(parse("env", &slurm), Ok(Shard { k: 3, n: 4 }));
        // A resubmission of some ids: the count is not N, so N is given.
        let some = env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ]);
        assert_eq!(parse("env/6", &some), Ok(Shard { k: 5, n: 6 }));
        assert!(parse("env", &some).unwrap_err().contains("does not exist"));
        let zero_based = env(&[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ]);
        assert!(
            parse("env", &zero_based)
                .unwrap_err()
                .contains("--array=1-2")
        );
        let kubernetes = env(&[("JOB_COMPLETION_INDEX", "0")]);
        assert_eq!(parse("env/5", &kubernetes), Ok(Shard { k: 1, n: 5 }));
        assert!(
            parse("env", &kubernetes)
                .unwrap_err()
                .contains("SLURM_ARRAY_TASK_COUNT is not set")
        );
        assert!(
            parse("env/5", env(&[]))
                .unwrap_err()
                .contains("not in a job array")
        );
    }

    #[test]
    fn array_specs_join_consecutive_ids() {
        assert_eq!(array_spec(&[1, 2, 3]), "1-3");
        assert_eq!(array_spec(&[1, 2, 3, 5, 7, 8]), "1-3,5,7-8");
        assert_eq!(array_spec(&[4]), "4");
        assert_eq!(array_spec(&[]), "");
    }
}
