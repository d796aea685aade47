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

/// Exit code of a node whose params, environment or input files are bad: nothing ran.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code of a node that failed while running.
pub const EXIT_FAILURE: u8 = 1;

/// The `main` of every node process whose params are `P`: reads the node's identity and
/// params from the launcher's environment and checks them with `validate` before the node
/// joins the group (so bad input never half-starts it), then runs `body`. Errors are printed
/// as `program: message`; the exit code is [`EXIT_BAD_INPUT`] for bad params or input
/// (`validate` failing, or `body` returning [`Error::Params`]/[`Error::Env`]/[`Error::Input`])
/// and [`EXIT_FAILURE`] for a failure at run time.
pub fn node_main<P: DeserializeOwned>(
    program: &str,
    validate: impl FnOnce(&P) -> Result<(), String>,
    body: impl FnOnce(crate::Node, P) -> Result<(), Error>,
) -> std::process::ExitCode {
    let bad_input = |e: Error| match e {
        Error::Params { .. } | Error::Env { .. } | Error::Input(_) => (EXIT_BAD_INPUT, e),
        other => (EXIT_FAILURE, other),
    };
    let result = (|| -> Result<(), (u8, Error)> {
        let identity = crate::NodeIdentity::from_env().map_err(bad_input)?;
        let p: P = parse_params(&identity.name, &identity.params).map_err(bad_input)?;
        validate(&p).map_err(|message| {
            let node = identity.name.clone();
            (EXIT_BAD_INPUT, Error::Params { node, message })
        })?;
        let node = crate::Node::new(identity).map_err(bad_input)?;
        body(node, p).map_err(bad_input)
    })();
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err((code, e)) => {
            eprintln!("{program}: {e}");
            std::process::ExitCode::from(code)
        }
    }
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
