//! The one way a node process starts: [`node_main`].

use crate::{Error, Node, NodeIdentity, parse_params};
use serde::de::DeserializeOwned;
use std::process::ExitCode;

/// Exit code of a node whose params, environment or input files are bad: nothing ran.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code of a node that failed while running.
pub const EXIT_FAILURE: u8 = 1;

/// The `main` of every node process:
///
/// 1. reads the node's identity and params `P` from the launcher's environment;
/// 2. `setup` checks them and loads what they name (world files, robot descriptions…) into
///    whatever the node needs, *before* the node joins the group, so bad input never
///    half-starts it; its error is one paragraph naming the key;
/// 3. the node joins the group and `run` steps it until the group stops.
///
/// Before it starts anything, `caravan launch` runs every Caravan program once with
/// `CARAVAN_CHECK=1` ([`crate::check_only`]): the node then stops after step 2, exiting 0 when
/// its params and inputs are good and 2 with the message when not, so a bad process param,
/// world or robot description stops the launch before any process of the group runs.
///
/// Started as `PROGRAM --describe-params` ([`crate::DESCRIBE_PARAMS_FLAG`]), it prints the
/// params `P` as a JSON Schema ([`crate::describe_params`]: keys, types, defaults, doc comments)
/// and exits 0 without reading its environment.
///
/// Started as a container's process ([`crate::env_vars::CONTAINER`], launch key `container`),
/// it does steps 1 and 2 for every member before any joins, then runs each member's `run` on
/// a stack of its own in this one thread ([`crate::container`]); `setup` and `run` are
/// therefore `Fn`, called once per member.
///
/// Errors are printed as `program: message` (`program (node): message` in a container). The exit code is [`EXIT_BAD_INPUT`] (2) for bad
/// params or input (`setup` failing, or `run` returning [`Error::Params`], [`Error::Env`] or
/// [`Error::Input`]) and [`EXIT_FAILURE`] (1) for a failure at run time.
///
/// ```no_run
/// # use serde::Deserialize;
/// #[derive(Deserialize, caravan::schemars::JsonSchema)]
/// #[schemars(crate = "caravan::schemars")]
/// #[serde(deny_unknown_fields)]
/// struct Params { gain: f64 }
///
/// fn main() -> std::process::ExitCode {
///     caravan::node_main(
///         "my-node",
///         |p: Params, _identity| {
///             if p.gain > 0.0 { Ok(p) } else { Err("key 'gain': must be positive".into()) }
///         },
///         |mut node, p| {
///             node.run(caravan::Trigger::every_hz(10.0), |_step| Ok(()))?;
///             Ok(())
///         },
///     )
/// }
/// ```
pub fn node_main<P: DeserializeOwned + schemars::JsonSchema, S>(
    program: &str,
    setup: impl Fn(P, &NodeIdentity) -> Result<S, String>,
    run: impl Fn(Node, S) -> Result<(), Error>,
) -> ExitCode {
    if crate::describe_params_requested() {
        crate::print_params_description::<P>();
        return ExitCode::SUCCESS;
    }
    let classify = |e: Error| match e {
        Error::Params { .. } | Error::Env { .. } | Error::Input(_) => (EXIT_BAD_INPUT, e),
        other => (EXIT_FAILURE, other),
    };
    // iceoryx2 installs its SIGTERM/SIGINT handlers on first use; install them now, so that a
    // group stopped while this node is still setting up ends it cleanly instead of killing it.
    if iceoryx2_bb_posix::signal::SignalHandler::termination_requested() {
        return ExitCode::SUCCESS;
    }
    // The node's name (a container's member's) goes before an error's message.
    let mut who = String::new();
    let result = (|| -> Result<(), (u8, Error)> {
        let identities = match crate::container::members_from_env().map_err(classify)? {
            Some(members) => members,
            None => vec![NodeIdentity::from_env().map_err(classify)?],
        };
        let container =
            identities.len() > 1 || std::env::var_os(crate::env_vars::CONTAINER).is_some();
        // Every member's input is checked before any joins the group.
        let mut ready = Vec::new();
        for identity in identities {
            if container {
                who = format!(" ({})", identity.name);
            }
            let p: P = parse_params(&identity.name, &identity.params).map_err(classify)?;
            let state = setup(p, &identity).map_err(|message| {
                let node = identity.name.clone();
                (EXIT_BAD_INPUT, Error::Params { node, message })
            })?;
            ready.push((identity, state));
        }
        if crate::check_only() {
            return Ok(());
        }
        if !container {
            let (identity, state) = ready.pop().expect("one identity");
            let node = Node::new(identity).map_err(classify)?;
            return run(node, state).map_err(classify);
        }
        let run = &run;
        let members = ready
            .into_iter()
            .map(|(identity, state)| {
                let name = identity.name.clone();
                let body: crate::container::Body<'_> =
                    Box::new(move || run(Node::new(identity)?, state));
                (name, body)
            })
            .collect();
        crate::container::run(members).map_err(|(name, e)| {
            who = format!(" ({name})");
            classify(e)
        })
    })();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A stop that comes while the node makes its ports (or tears them down) can fail a
        // transport call; the group is ending anyway, so that is a clean stop. Bad input is
        // still reported as such.
        Err((code, e))
            if code != EXIT_BAD_INPUT
                && iceoryx2_bb_posix::signal::SignalHandler::termination_requested() =>
        {
            eprintln!("{program}{who}: stopped ({e})");
            ExitCode::SUCCESS
        }
        Err((code, e)) => {
            eprintln!("{program}{who}: {e}");
            ExitCode::from(code)
        }
    }
}
