//! Report sections: what a plugin adds to `report.json` (under the section's name) and to
//! `report.md` (a Markdown fragment), kept as files in the run directory's `sections/` until
//! the launcher merges them.

use anyhow::{Context, Result, bail};
use serde_json::Value;
use std::path::Path;

/// Where plugins leave their sections, inside the run directory.
pub const SECTIONS_DIR: &str = "sections";

/// Names the generic report uses; a plugin's section may not take them.
pub const RESERVED: [&str; 6] = ["version", "group", "run", "nodes", "topics", "links"];

/// One section of a run's report.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// The key in `report.json`: lower case letters, digits and '_'.
    pub name: String,
    /// The section's value in `report.json`.
    pub json: Value,
    /// Its part of `report.md`, starting with a `## ` heading.
    pub markdown: String,
}

impl Section {
    /// Writes `sections/<name>.json` and `sections/<name>.md` into `run_dir`.
    pub fn write(&self, run_dir: &Path) -> Result<()> {
        check_name(&self.name)?;
        let dir = run_dir.join(SECTIONS_DIR);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        std::fs::write(
            dir.join(format!("{}.json", self.name)),
            serde_json::to_string_pretty(&self.json)? + "\n",
        )?;
        std::fs::write(dir.join(format!("{}.md", self.name)), &self.markdown)?;
        Ok(())
    }

    /// Reads section `name` back from `run_dir`, with its JSON text as written.
    pub fn read(run_dir: &Path, name: &str) -> Result<(Self, String)> {
        let dir = run_dir.join(SECTIONS_DIR);
        let json_path = dir.join(format!("{name}.json"));
        let text = std::fs::read_to_string(&json_path)
            .with_context(|| format!("cannot read {}", json_path.display()))?;
        let section = Self {
            name: name.to_string(),
            json: serde_json::from_str(&text)
                .with_context(|| format!("{} is not JSON", json_path.display()))?,
            markdown: std::fs::read_to_string(dir.join(format!("{name}.md"))).unwrap_or_default(),
        };
        Ok((section, text))
    }
}

/// The names of the sections written in `run_dir`, sorted.
pub fn written(run_dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(run_dir.join(SECTIONS_DIR))
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            name.strip_suffix(".json").map(str::to_string)
        })
        .collect();
    names.sort();
    names
}

fn check_name(name: &str) -> Result<()> {
    let valid = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
    if !valid {
        bail!("section name '{name}' must be lower case letters, digits and '_'");
    }
    if RESERVED.contains(&name) {
        bail!("section name '{name}' is the generic report's own");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sections_round_trip_and_list_sorted() {
        let dir = std::env::temp_dir().join(format!("caravan-section-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for name in ["zeta", "alpha"] {
            Section {
                name: name.into(),
                json: serde_json::json!({"x": 1}),
                markdown: format!("## {name}\n"),
            }
            .write(&dir)
            .unwrap();
        }
        assert_eq!(written(&dir), ["alpha", "zeta"]);
        let (s, text) = Section::read(&dir, "zeta").unwrap();
        assert!(text.contains("\"x\": 1"));
        assert_eq!(s.json["x"], 1);
        assert_eq!(s.markdown, "## zeta\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_and_reserved_names_are_refused() {
        assert!(check_name("nodes").is_err());
        assert!(check_name("Convoy").is_err());
        assert!(check_name("").is_err());
        assert!(check_name("slam_2").is_ok());
    }
}
