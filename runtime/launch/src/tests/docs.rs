//! docs/launch.md shows every key a launch file may have.

use crate::sections::*;

#[test]
fn the_launch_file_docs_show_every_key() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/launch.md");
    let doc = std::fs::read_to_string(root).unwrap();
    // Keys appear in the example's TOML as `key = …`, possibly inside an inline table or a
    // comment.
    let shown = |key: &str| {
        let written = format!("{key} =");
        doc.match_indices(&written).any(|(at, _)| {
            let before = doc[..at].chars().next_back();
            !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
        })
    };
    for (list, keys) in [
        ("group", GROUP_KEYS),
        ("hosts", HOST_KEYS),
        ("tls", TLS_KEYS),
        ("links", LINK_KEYS),
        ("process", PROCESS_KEYS),
        ("report", REPORT_KEYS),
    ] {
        for key in keys {
            assert!(
                shown(key),
                "docs/launch.md does not show [{list}] key '{key}'"
            );
        }
    }
}
