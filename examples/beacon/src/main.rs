//! `caravan-beacon`: broadcasts a [`Beacon`] each step on `beacon`, with the label and
//! position last received on `beacon/set`.

use beacon::{Beacon, HISTORY, SET, TOPIC};
use caravan::{Error, Node, Topic, Trigger};

/// The beacon takes no params.
#[derive(serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {}

fn main() -> std::process::ExitCode {
    caravan::node_main("caravan-beacon", |_: Params, _| Ok(()), run)
}

fn run(mut node: Node, (): ()) -> Result<(), Error> {
    let set = node.subscriber(&Topic::<Beacon>::new(SET))?;
    let out = node.publisher(&Topic::<Beacon>::new(TOPIC))?;
    let mut beacon = caravan_schemas::placement_new::<Beacon>();
    beacon.label = caravan_schemas::FixedString::new("unset");
    node.run(Trigger::every_hz(10.0), |_| {
        while let Some(m) = set.receive()? {
            beacon.label = m.label;
            beacon.position = m.position;
        }
        beacon.id += 1;
        beacon.strength_dbm = -40.0 - beacon.id as f32 * 0.5;
        let mut last: Vec<f64> = beacon.history.as_slice().to_vec();
        last.push(beacon.strength_dbm as f64);
        let keep = last.len().saturating_sub(HISTORY);
        beacon.history.set_from_slice(&last[keep..]);
        out.publish(&beacon)
    })?;
    Ok(())
}
