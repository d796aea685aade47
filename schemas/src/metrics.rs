//! Named measures of a running experiment at one time, for live plots and recordings: what a
//! scenario's monitor computes as the run goes (the convoy's gaps and cross-track errors), so
//! that Foxglove's Plot panel can draw it (`"convoy/metrics".values[:]{name=="gap_1"}.value`)
//! without the report.

use crate::describe::Describe;
use crate::{FixedString, FixedVec};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// A short name (a metric, an outcome).
pub type ShortName = FixedString<28>;

/// A named number.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::NamedValue")]
pub struct NamedValue {
    pub name: ShortName,
    pub value: f64,
}

/// Most values in one [`Metrics`] message.
pub const MAX_METRICS: usize = 32;

/// Named values at the message's stamp (units in the names, e.g. `gap_1_m`).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::Metrics")]
pub struct Metrics {
    pub values: FixedVec<NamedValue, MAX_METRICS>,
}

impl Metrics {
    /// Adds `name = value`; false when the message is full.
    pub fn push(&mut self, name: &str, value: f64) -> bool {
        self.values
            .push(NamedValue {
                name: ShortName::new(name),
                value,
            })
            .is_ok()
    }

    /// The value named `name`, if present.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.values
            .as_slice()
            .iter()
            .find(|v| v.name.as_str() == name)
            .map(|v| v.value)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn values_are_found_by_name_and_a_full_message_refuses_more() {
        let mut m = crate::boxed_placement_new::<super::Metrics>();
        assert!(m.push("gap_1_m", 0.5));
        assert_eq!(m.get("gap_1_m"), Some(0.5));
        assert_eq!(m.get("gap_2_m"), None);
        for i in 1..super::MAX_METRICS {
            assert!(m.push(&format!("v{i}"), i as f64));
        }
        assert!(!m.push("one_too_many", 0.0));
        let json = serde_json::to_value(m.as_ref()).unwrap();
        assert_eq!(json["values"][0]["name"], "gap_1_m");
    }
}
