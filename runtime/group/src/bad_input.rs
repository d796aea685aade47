//! Bad input to a command: an error its user fixes by changing what they typed (a malformed
//! message, a type that does not match, a group or topic that does not exist, a recording
//! that cannot be read). A command exits 2 for it and 1 for every other error, a run-time
//! failure; docs/launch.md has the table of every command's codes.

use std::fmt;

/// Exit code for bad input: nothing was started.
pub const EXIT_BAD_INPUT: u8 = 2;

/// The error's message, marked as bad input.
#[derive(Debug)]
pub struct BadInput(pub String);

impl fmt::Display for BadInput {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// An error that is bad input.
pub fn bad(message: impl Into<String>) -> anyhow::Error {
    BadInput(message.into()).into()
}

/// Marks any error as bad input, keeping its whole message.
pub fn as_bad(e: anyhow::Error) -> anyhow::Error {
    bad(format!("{e:#}"))
}

/// The exit code for a command's error: 2 when any cause is bad input, else 1.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    if e.chain().any(|cause| cause.is::<BadInput>()) {
        EXIT_BAD_INPUT
    } else {
        1
    }
}

/// Why `dir` cannot be a directory to write into: it, or the nearest part of its path that
/// exists, is not a directory (`--runs-dir FILE`, `--out FILE/sub`). What does not exist yet
/// is made later.
pub fn not_a_directory(dir: &std::path::Path) -> Option<String> {
    let existing = dir.ancestors().find(|a| a.exists())?;
    (!existing.is_dir()).then(|| {
        if existing == dir {
            format!("{}: exists and is not a directory", dir.display())
        } else {
            format!(
                "{}: {} is not a directory",
                dir.display(),
                existing.display()
            )
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    #[test]
    fn bad_input_is_found_under_context_and_other_errors_are_run_time() {
        let e = Err::<(), _>(bad("no group 'x' is running"))
            .context("topic pub")
            .unwrap_err();
        assert_eq!(exit_code(&e), 2);
        assert_eq!(format!("{e:#}"), "topic pub: no group 'x' is running");
        assert_eq!(exit_code(&anyhow::anyhow!("disk full")), 1);
        assert_eq!(exit_code(&as_bad(anyhow::anyhow!("truncated"))), 2);
    }

    #[test]
    fn a_directory_under_a_file_is_named_with_the_file() {
        let dir = std::env::temp_dir().join(format!("caravan-nad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("afile");
        std::fs::write(&file, "x").unwrap();
        assert_eq!(not_a_directory(&dir), None);
        assert_eq!(not_a_directory(&dir.join("new/deeper")), None);
        let said = not_a_directory(&file).unwrap();
        assert!(
            said.ends_with("afile: exists and is not a directory"),
            "{said}"
        );
        let said = not_a_directory(&file.join("sub")).unwrap();
        assert!(said.contains("afile is not a directory"), "{said}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
