//! What is wrong with a launch file: each problem with where it was found, all of them at once.

use std::fmt;
use std::path::PathBuf;

/// Why a launch file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    #[error("cannot read launch file {}: {reason}", path.display())]
    Read { path: PathBuf, reason: String },
    /// Every problem found, one per line: overrides first, then by file and line.
    #[error("{}", lines(.0))]
    Invalid(Vec<Problem>),
}

impl LaunchError {
    /// Bad input, as opposed to a failure while running.
    #[allow(dead_code)] // the launcher has its own EXIT_BAD_INPUT (also 2) for now
    pub fn exit_code(&self) -> i32 {
        2
    }
}

fn lines(problems: &[Problem]) -> String {
    let lines: Vec<String> = problems.iter().map(Problem::to_string).collect();
    lines.join("\n")
}

/// One problem: where (`file:line`, `file:line:col` or `--set KEY=VALUE`) and what.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub location: String,
    /// For ordering; `None` for overrides and whole-file problems.
    pub line: Option<usize>,
    /// For ordering: which file (0 = the top file, then in the order they were read).
    pub rank: usize,
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, self.message)
    }
}
