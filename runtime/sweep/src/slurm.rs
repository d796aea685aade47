//! `caravan sweep FILE --slurm [sbatch options…]`: the sweep as a Slurm job array, one array
//! task per shard. Caravan writes an sbatch script into `<out>/slurm/`, submits it, and says
//! how to follow the job and merge its shards; Slurm does the scheduling.
//!
//! The array's ids are the shard numbers (1..=N), and each task runs
//! `caravan sweep … --shard $SLURM_ARRAY_TASK_ID/N`, so a resubmission that lists only some ids
//! keeps every run in its shard. Only shards with unfinished runs are submitted, and within a
//! shard the local sweep's resume skips finished runs: submitting again reruns only what did
//! not finish.

use super::plan::Plan;
use super::shard::{MAX_SHARDS, Shard, array_spec};
use super::{SweepArgs, runner};
use anyhow::{Context, Result};
use caravan_group::launch::EXIT_BAD_INPUT;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Caravan's own options: after `--slurm` they would be taken as sbatch's.
const OWN_OPTIONS: &[&str] = &[
    "--grid",
    "--set",
    "--seeds",
    "--jobs",
    "--out",
    "--duration",
    "--metric",
    "--quiet",
    "--shard",
    "--shards",
];

/// Writes the job script and submits it (unless `--dry-run`); returns the exit code.
pub fn submit(plan: &Plan, args: &SweepArgs, options: &[String]) -> Result<u8> {
    // sbatch has no --dry-run (its own is --test-only): after --slurm it is Caravan's.
    let dry_run = args.dry_run || options.iter().any(|o| o == "--dry-run");
    let options: Vec<&String> = options.iter().filter(|o| *o != "--dry-run").collect();
    let lines = match sbatch_lines(&options, plan.shard) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("caravan: {e}");
            return Ok(EXIT_BAD_INPUT);
        }
    };
    let total = plan.cells.len() * plan.seeds.len();
    let n = args.shards.unwrap_or(total.min(MAX_SHARDS));
    if n == 0 || n > MAX_SHARDS {
        eprintln!("caravan: --shards {n}: a sweep is split into 1 to {MAX_SHARDS} shards");
        return Ok(EXIT_BAD_INPUT);
    }
    let unfinished: Vec<usize> = plan
        .runs()
        .filter(|&(_, c, seed)| runner::finished_run(&plan.seed_dir(c, seed)).is_none())
        .map(|(i, _, _)| i)
        .collect();
    let out = std::path::absolute(&plan.out)
        .with_context(|| format!("cannot resolve {}", plan.out.display()))?;
    let merge = format!("caravan sweep merge {}", quote(&out.display().to_string()));
    if unfinished.is_empty() {
        eprintln!(
            "caravan: every one of the sweep's {total} runs has finished; nothing to submit. \
             Summarise them with `{merge}`"
        );
        return Ok(0);
    }
    let mut ids: Vec<usize> = unfinished.iter().map(|&i| Shard::of(i, n).k).collect();
    ids.sort_unstable();
    ids.dedup();
    let job = Job {
        name: &plan.name,
        array: array_spec(&ids),
        shards: n,
        out: &out,
        dir: std::env::current_dir().context("cannot read the current directory")?,
        exe: std::env::current_exe().context("cannot find the caravan executable")?,
        sbatch: lines,
        sweep: sweep_args(args, plan, &out),
    };
    let slurm_dir = out.join("slurm");
    std::fs::create_dir_all(&slurm_dir)
        .with_context(|| format!("cannot create {}", slurm_dir.display()))?;
    let script = slurm_dir.join("sweep.sbatch");
    std::fs::write(&script, job.script())
        .with_context(|| format!("cannot write {}", script.display()))?;
    let runs = format!(
        "{} unfinished of {total} runs, in {} of {n} shards",
        unfinished.len(),
        ids.len()
    );
    if dry_run {
        eprintln!(
            "caravan: wrote {} ({runs}); submit it with `sbatch {}`",
            script.display(),
            script.display()
        );
        return Ok(0);
    }
    let output = match Command::new("sbatch")
        .arg("--parsable")
        .arg(&script)
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            eprintln!(
                "caravan: cannot run sbatch ({e}): is Slurm's client installed (Debian: \
                 slurm-client)? The script is {}",
                script.display()
            );
            return Ok(1);
        }
    };
    if !output.status.success() {
        eprintln!(
            "caravan: sbatch refused {}: {}",
            script.display(),
            String::from_utf8_lossy(&output.stderr).trim()
        );
        return Ok(1);
    }
    // `--parsable` prints `jobid` or `jobid;cluster`.
    let stdout = String::from_utf8_lossy(&output.stdout);
    let id = stdout.trim().split(';').next().unwrap_or_default();
    println!("{id}");
    eprintln!(
        "caravan: submitted Slurm job {id}, array {} ({runs}); logs in {}\n\
         caravan: follow it with `squeue -j {id}` (or `sacct -j {id}`); when it has ended, \
         summarise with `{merge}`. Submitting this sweep again reruns only unfinished runs.",
        job.array,
        slurm_dir.display()
    );
    Ok(0)
}

/// The options after `--slurm` as `#SBATCH` lines: each option with the values that follow it
/// (`--time 1:00:00` or `--time=1:00:00`).
fn sbatch_lines(options: &[&String], shard: Shard) -> Result<Vec<String>, String> {
    if shard != Shard::ALL {
        return Err("--slurm with --shard: the job array's tasks choose their shards".into());
    }
    let mut lines: Vec<String> = Vec::new();
    for o in options {
        if o.contains(['\n', '\r']) {
            return Err(format!("--slurm: option {o:?} holds a line break"));
        }
        let name = o.split('=').next().unwrap_or(o);
        if OWN_OPTIONS.contains(&name) {
            return Err(format!(
                "--slurm {o}: after --slurm every option is sbatch's; put Caravan's {name} \
                 before --slurm"
            ));
        }
        match lines.last_mut() {
            _ if o.starts_with('-') => lines.push(o.to_string()),
            Some(last) => {
                last.push(' ');
                last.push_str(&quote(o));
            }
            None => {
                return Err(format!(
                    "--slurm {o}: expected an sbatch option such as --time=1:00:00"
                ));
            }
        }
    }
    Ok(lines)
}

/// The `caravan sweep` arguments each array task repeats, less `--shard` and `--jobs`.
fn sweep_args(args: &SweepArgs, plan: &Plan, out: &Path) -> Vec<String> {
    let target = args.target.as_deref().unwrap_or(&plan.launch);
    let mut a = vec![target.display().to_string()];
    for g in &args.grid {
        a.extend(["--grid".into(), g.clone()]);
    }
    for s in &args.set {
        a.extend(["--set".into(), s.clone()]);
    }
    if let Some(s) = &args.seeds {
        a.extend(["--seeds".into(), s.clone()]);
    }
    if let Some(d) = &args.duration {
        a.extend(["--duration".into(), d.clone()]);
    }
    a.extend(["--out".into(), out.display().to_string(), "--quiet".into()]);
    if let Some(j) = args.jobs {
        a.extend(["--jobs".into(), j.to_string()]);
    } else if !plan.jobs_given {
        // As many groups at once as the task was given CPUs.
        a.extend(["--jobs".into(), "${SLURM_CPUS_PER_TASK:-1}".into()]);
    }
    a
}

/// One job array.
struct Job<'a> {
    name: &'a str,
    /// `--array`: the ids of the shards to run.
    array: String,
    shards: usize,
    out: &'a Path,
    /// Where the tasks run (`--chdir`): relative paths in the sweep are relative to it.
    dir: PathBuf,
    exe: PathBuf,
    sbatch: Vec<String>,
    sweep: Vec<String>,
}

impl Job<'_> {
    fn script(&self) -> String {
        let mut s = String::from("#!/bin/sh\n");
        s += &format!(
            "# caravan sweep '{}' as a Slurm job array: array task K runs shard K of {}.\n\
             # Written by `caravan sweep … --slurm`; run that again to submit only unfinished runs.\n",
            self.name, self.shards
        );
        let name: String = (self.name.chars())
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        s += &format!("#SBATCH --job-name=caravan-{name}\n");
        s += &format!("#SBATCH --array={}\n", self.array);
        s += &format!(
            "#SBATCH --output={}\n",
            self.out.join("slurm").join("%A_%a.out").display()
        );
        s += &format!("#SBATCH --chdir={}\n", self.dir.display());
        for line in &self.sbatch {
            s += &format!("#SBATCH {line}\n");
        }
        let mut command = vec![quote(&self.exe.display().to_string()), "sweep".into()];
        for a in &self.sweep {
            command.push(if a.starts_with("${") {
                format!("\"{a}\"")
            } else {
                quote(a)
            });
        }
        command.push("--shard".into());
        command.push(format!("\"$SLURM_ARRAY_TASK_ID/{}\"", self.shards));
        s += &format!("exec {}\n", command.join(" "));
        s
    }
}

/// Quotes a word for a POSIX shell (only when it needs it).
fn quote(word: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn sbatch_options_become_lines_with_their_values() {
        let o = strings(&["--time", "1:00:00", "--cpus-per-task=2", "-p", "batch q"]);
        let refs: Vec<&String> = o.iter().collect();
        assert_eq!(
            sbatch_lines(&refs, Shard::ALL).unwrap(),
            ["--time 1:00:00", "--cpus-per-task=2", "-p 'batch q'"]
        );
        let own = strings(&["--seeds=1..=3"]);
        let err = sbatch_lines(&own.iter().collect::<Vec<_>>(), Shard::ALL).unwrap_err();
        assert!(err.contains("before --slurm"), "{err}");
        let loose = strings(&["batch"]);
        let err = sbatch_lines(&loose.iter().collect::<Vec<_>>(), Shard::ALL).unwrap_err();
        assert!(err.contains("expected an sbatch option"), "{err}");
        let broken = strings(&["--comment=a\n#SBATCH --x"]);
        assert!(sbatch_lines(&broken.iter().collect::<Vec<_>>(), Shard::ALL).is_err());
        assert!(sbatch_lines(&[], Shard { k: 1, n: 2 }).is_err());
    }

    #[test]
    fn the_script_runs_each_task_s_shard_of_the_same_sweep() {
        let job = Job {
            name: "gain sweep",
            array: "1-3,5".into(),
            shards: 6,
            out: Path::new("/shared/sweeps/gain"),
            dir: "/shared/checkout".into(),
            exe: "/opt/caravan/bin/caravan".into(),
            sbatch: strings(&["--time=10:00"]),
            sweep: strings(&[
                "launch/pingpong.toml",
                "--grid",
                "process.pong.params.gain=1,3",
                "--set",
                "group.clock=\"lockstep\"",
                "--out",
                "/shared/sweeps/gain",
                "--quiet",
                "--jobs",
                "${SLURM_CPUS_PER_TASK:-1}",
            ]),
        };
        let script = job.script();
        assert!(script.starts_with("#!/bin/sh\n"), "{script}");
        for line in [
            "#SBATCH --job-name=caravan-gain_sweep\n",
            "#SBATCH --array=1-3,5\n",
            "#SBATCH --output=/shared/sweeps/gain/slurm/%A_%a.out\n",
            "#SBATCH --chdir=/shared/checkout\n",
            "#SBATCH --time=10:00\n",
            "exec /opt/caravan/bin/caravan sweep launch/pingpong.toml --grid \
             process.pong.params.gain=1,3 --set 'group.clock=\"lockstep\"' --out \
             /shared/sweeps/gain --quiet --jobs \"${SLURM_CPUS_PER_TASK:-1}\" --shard \
             \"$SLURM_ARRAY_TASK_ID/6\"\n",
        ] {
            assert!(script.contains(line), "{line}\nnot in\n{script}");
        }
        assert_eq!(quote("it's"), r"'it'\''s'");
    }
}
