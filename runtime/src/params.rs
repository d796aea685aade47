//! Typed node params from the launch file's `params` table.

use crate::Error;
use serde::de::DeserializeOwned;

/// Deserialises `value` into `P`. Unknown keys and mistyped values are errors naming the key
/// (as a dotted path) and, for a wrong type, the expected type.
pub fn parse_params<P: DeserializeOwned>(
    node: &str,
    value: &serde_json::Value,
) -> Result<P, Error> {
    let mut unknown = Vec::new();
    let mut note_unknown = |path: serde_ignored::Path<'_>| unknown.push(path.to_string());
    let tracked = serde_ignored::Deserializer::new(value, &mut note_unknown);
    let parsed: Result<P, _> = serde_path_to_error::deserialize(tracked);
    let params = parsed.map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        let message = if path == "." || path.is_empty() {
            inner
        } else {
            format!("key '{path}': {inner}")
        };
        Error::Params {
            node: node.to_string(),
            message,
        }
    })?;
    if !unknown.is_empty() {
        let keys = unknown
            .iter()
            .map(|k| format!("'{k}'"))
            .collect::<Vec<_>>()
            .join(", ");
        return Err(Error::Params {
            node: node.to_string(),
            message: format!("unknown key {keys}; this node does not take it"),
        });
    }
    Ok(params)
}

/// The command-line flag with which every Caravan process prints a description of its params
/// instead of running: `caravan-physics --describe-params`. [`crate::node_main`] and the report
/// plugins' `main` handle it; docs/processes.md's params tables are generated from it
/// (`caravan docs params`).
pub const DESCRIBE_PARAMS_FLAG: &str = "--describe-params";

/// Whether the process was started as `PROGRAM --describe-params`.
pub fn describe_params_requested() -> bool {
    std::env::args().nth(1).as_deref() == Some(DESCRIBE_PARAMS_FLAG)
}

/// The params `P` as a JSON Schema (draft 2020-12, subschemas inlined): each key with its
/// type, its default (when `P` has one and the value serialises) and its doc comment as
/// `description`, where the code's convention puts the unit and range ("m/s, > 0").
pub fn describe_params<P: schemars::JsonSchema>() -> serde_json::Value {
    let generator = schemars::generate::SchemaSettings::draft2020_12()
        .with(|s| s.inline_subschemas = true)
        .into_generator();
    generator.into_root_schema_for::<P>().to_value()
}

/// Prints [`describe_params`] of `P` to stdout as pretty JSON.
pub fn print_params_description<P: schemars::JsonSchema>() {
    let text = serde_json::to_string_pretty(&describe_params::<P>())
        .expect("a JSON value always serialises");
    println!("{text}");
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;
    use serde_json::json;

    #[derive(Debug, Deserialize, PartialEq)]
    struct Gains {
        k1: f64,
        #[serde(default)]
        limits: Limits,
    }

    #[derive(Debug, Default, Deserialize, PartialEq)]
    struct Limits {
        v_max: f64,
    }

    #[test]
    fn reads_nested_params() {
        let p: Gains = parse_params("n", &json!({"k1": 1.5, "limits": {"v_max": 0.2}})).unwrap();
        assert_eq!(
            p,
            Gains {
                k1: 1.5,
                limits: Limits { v_max: 0.2 }
            }
        );
    }

    #[test]
    fn unknown_key_is_named() {
        let e = parse_params::<Gains>(
            "n",
            &json!({"k1": 1.0, "limits": {"v_max": 0.1, "vmax": 1}}),
        );
        let text = e.unwrap_err().to_string();
        assert!(text.contains("'limits.vmax'"), "{text}");
    }

    #[test]
    fn wrong_type_names_key_and_expected_type() {
        let text = parse_params::<Gains>("n", &json!({"k1": "fast"}))
            .unwrap_err()
            .to_string();
        assert!(
            text.contains("key 'k1'") && text.contains("expected f64"),
            "{text}"
        );
    }
}
