//! `caravan docs params`: the params tables of the docs, generated from the processes.
//!
//! Every Caravan process prints its params as a JSON Schema when started as
//! `PROGRAM --describe-params` (`caravan::node_main`, the report plugins' `main`). A page
//! (`docs/**/*.md`, `launch/**/README.md`) asks for a process's table with a pair of markers:
//!
//! ```text
//! <!-- params:caravan-physics -->
//! (generated: leave it to `caravan docs params`)
//! <!-- /params -->
//! ```
//!
//! A marker may name several programs that take the same params
//! (`<!-- params:caravan-imu-driver caravan-imu-report -->`); they must describe the same keys.
//! Between them this command writes one row per key: nested tables flattened to dotted keys
//! (`slam.resolution`), entries of a list of tables as `robots[].urdf`, the variants of a
//! tagged table as `actuators[].kp (type = "position")`. The columns are the key, its type, its
//! default (*required* when it has none) and its doc comment, which carries the unit and range
//! by the code's convention ("m/s, > 0"). Everything outside the markers is hand-written and
//! left as it is. `--check` writes nothing and fails naming each process and key whose row
//! the page lacks or has wrong (the tests run it).

use crate::params_table::{differences, render, rows_of};
use anyhow::{Context, Result, bail};
use caravan_group::bad_input::bad;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The marker that opens a generated table: `<!-- params:PROGRAM -->`.
pub const OPEN: &str = "<!-- params:";
/// The marker that closes it.
pub const CLOSE: &str = "<!-- /params -->";

#[derive(clap::Subcommand)]
pub enum DocsCommand {
    /// Write the params tables between `<!-- params:PROGRAM -->` and `<!-- /params -->` in
    /// docs/**/*.md and launch/**/README.md from `PROGRAM --describe-params`
    Params(ParamsArgs),
}

#[derive(clap::Args)]
pub struct ParamsArgs {
    /// Write nothing; fail naming every process and key whose row differs from the code
    #[arg(long)]
    check: bool,
    /// The workspace root (its docs/ and launch/)
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// Where the process binaries are; default: beside this `caravan`
    #[arg(long)]
    bin_dir: Option<PathBuf>,
}

pub fn run(cmd: &DocsCommand) -> Result<u8> {
    let DocsCommand::Params(args) = cmd;
    let bin_dir = match &args.bin_dir {
        Some(dir) => dir.clone(),
        None => std::env::current_exe()?
            .parent()
            .context("the caravan executable has no directory")?
            .to_path_buf(),
    };
    // A root without docs/ would be walked to nothing and "match": it is the wrong directory.
    if !args.root.join("docs").is_dir() {
        return Err(bad(format!(
            "--root {}: no docs/ directory in it; give the workspace root",
            args.root.display()
        )));
    }
    let mut problems = Vec::new();
    let mut tables = 0;
    for page in pages(&args.root)? {
        let text = std::fs::read_to_string(&page)
            .with_context(|| format!("cannot read {}", page.display()))?;
        if !text.contains(OPEN) {
            continue;
        }
        let shown = page.strip_prefix(&args.root).unwrap_or(&page).display();
        let mut out = String::with_capacity(text.len());
        let mut rest = text.as_str();
        while let Some(start) = rest.find(OPEN) {
            let after = &rest[start + OPEN.len()..];
            let Some(name_end) = after.find("-->") else {
                return Err(bad(format!("{shown}: a '{OPEN}' marker without '-->'")));
            };
            // One table may stand for several programs that take the same params
            // (`<!-- params:caravan-imu-driver caravan-imu-report -->`).
            let programs: Vec<&str> = after[..name_end].split_whitespace().collect();
            let Some(&program) = programs.first() else {
                return Err(bad(format!(
                    "{shown}: a '{OPEN} -->' marker without a program"
                )));
            };
            let body_start = start + OPEN.len() + name_end + 3;
            let Some(body_len) = rest[body_start..].find(CLOSE) else {
                return Err(bad(format!(
                    "{shown}: '{OPEN}{program} -->' without a closing '{CLOSE}'"
                )));
            };
            let body = &rest[body_start..body_start + body_len];
            let rows = rows_of(&describe(&bin_dir, program)?);
            for other in &programs[1..] {
                if rows_of(&describe(&bin_dir, other)?) != rows {
                    problems.push(format!(
                        "{shown}: {other}'s params differ from {program}'s; give it a table \
                         of its own"
                    ));
                }
            }
            let table = format!("\n{}", render(&rows));
            if body != table {
                problems.extend(
                    differences(&rows, body)
                        .into_iter()
                        .map(|d| format!("{shown}: {program}: {d}")),
                );
            }
            out.push_str(&rest[..body_start]);
            out.push_str(&table);
            out.push_str(CLOSE);
            rest = &rest[body_start + body_len + CLOSE.len()..];
            tables += 1;
        }
        out.push_str(rest);
        if !args.check && out != text {
            std::fs::write(&page, &out)
                .with_context(|| format!("cannot write {}", page.display()))?;
            println!("wrote {shown}");
        }
    }
    if args.check && !problems.is_empty() {
        for p in &problems {
            eprintln!("caravan: {p}");
        }
        eprintln!(
            "caravan: {} difference(s) between the params tables and the code; \
             `caravan docs params` rewrites the tables",
            problems.len()
        );
        return Ok(1);
    }
    if args.check {
        println!("{tables} params tables match the code");
    }
    Ok(0)
}

/// The pages that may hold params tables: docs/**/*.md and launch/**/README.md.
fn pages(root: &Path) -> Result<Vec<PathBuf>> {
    fn walk(dir: &Path, keep: &dyn Fn(&Path) -> bool, out: &mut Vec<PathBuf>) -> Result<()> {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return Ok(());
        };
        for entry in entries {
            let path = entry?.path();
            if path.is_dir() {
                walk(&path, keep, out)?;
            } else if keep(&path) {
                out.push(path);
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    let md = |p: &Path| p.extension().is_some_and(|e| e == "md");
    walk(&root.join("docs"), &md, &mut out)?;
    walk(
        &root.join("launch"),
        &|p: &Path| p.file_name().is_some_and(|n| n == "README.md"),
        &mut out,
    )?;
    out.sort();
    Ok(out)
}

/// `PROGRAM --describe-params`, parsed.
fn describe(bin_dir: &Path, program: &str) -> Result<Value> {
    let exe = bin_dir.join(program);
    let out = Command::new(&exe)
        .arg(caravan::DESCRIBE_PARAMS_FLAG)
        .output()
        .with_context(|| format!("cannot run {}", exe.display()))?;
    if !out.status.success() {
        bail!(
            "{program} {}: {}; {}",
            caravan::DESCRIBE_PARAMS_FLAG,
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    serde_json::from_slice(&out.stdout)
        .with_context(|| format!("{program} {}: not JSON", caravan::DESCRIBE_PARAMS_FLAG))
}
