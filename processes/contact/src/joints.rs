//! The arm's joints on the wire: angles and torques out of a `JointState`, matched by name to
//! the arm's joint order.

use caravan_schemas::JointState;

/// (angles rad, efforts N·m) of `names`, in that order; `None` if one is missing.
pub fn read(state: &JointState, names: &[String]) -> Option<(Vec<f64>, Vec<f64>)> {
    read_all(state, names).map(|r| (r.angles, r.efforts))
}

/// The arm's joints in one joint-state message, in the arm's order.
#[derive(Debug, Clone, PartialEq)]
pub struct Reading {
    /// rad.
    pub angles: Vec<f64>,
    /// rad/s.
    pub speeds: Vec<f64>,
    /// N·m.
    pub efforts: Vec<f64>,
}

/// Angles, speeds and efforts of `names`, in that order; `None` if one is missing.
pub fn read_all(state: &JointState, names: &[String]) -> Option<Reading> {
    let joints = state.joints.as_slice();
    let mut r = Reading {
        angles: Vec::with_capacity(names.len()),
        speeds: Vec::with_capacity(names.len()),
        efforts: Vec::with_capacity(names.len()),
    };
    for n in names {
        let j = joints.iter().find(|j| j.name.as_str() == n)?;
        r.angles.push(j.position);
        r.speeds.push(j.velocity);
        r.efforts.push(j.effort);
    }
    Some(r)
}
