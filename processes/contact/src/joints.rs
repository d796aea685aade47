//! The arm's joints on the wire: angles and torques out of a `JointState`, matched by name to
//! the arm's joint order.

use caravan_schemas::JointState;

/// (angles rad, efforts N·m) of `names`, in that order; `None` if one is missing.
pub fn read(state: &JointState, names: &[String]) -> Option<(Vec<f64>, Vec<f64>)> {
    let joints = state.joints.as_slice();
    names
        .iter()
        .map(|n| {
            joints
                .iter()
                .find(|j| j.name.as_str() == n)
                .map(|j| (j.position, j.effort))
        })
        .collect::<Option<Vec<_>>>()
        .map(|v| v.into_iter().unzip())
}
