//! A trained actor as the agent runs it: a small multilayer perceptron read from JSON
//! (`{"layers": [{"weight": [[…]], "bias": […]}, …]}`, ReLU between layers, tanh on the output,
//! as TD3's and SAC's deterministic actors), evaluated with nalgebra, no training stack.

use crate::encounter::Action;
use crate::policy::Policy;
use nalgebra::{DMatrix, DVector};
use serde::Deserialize;

#[derive(Deserialize)]
struct Layer {
    weight: Vec<Vec<f64>>,
    bias: Vec<f64>,
}

#[derive(Deserialize)]
struct File {
    layers: Vec<Layer>,
}

/// The actor: observation → continuous action in [−1, 1]ⁿ.
#[derive(Debug, Clone, PartialEq)]
pub struct Mlp {
    layers: Vec<(DMatrix<f64>, DVector<f64>)>,
}

impl Mlp {
    /// Reads the weights file at `path` and checks it ([`Mlp::parse`]). Only a regular file
    /// of at most [`caravan::input::MAX_INPUT_BYTES`] is read: a device, a directory or an
    /// absurdly large file is an error at once, not a hang or an exhausted memory.
    pub fn read(path: &std::path::Path, inputs: usize) -> Result<Self, String> {
        let text = caravan::input::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
        Self::parse(&text, inputs)
    }

    /// Reads and checks a weights file: consecutive layers must fit, the first take 6 inputs.
    pub fn parse(text: &str, inputs: usize) -> Result<Self, String> {
        let file: File =
            serde_json::from_str(text).map_err(|e| format!("not a weights file: {e}"))?;
        if file.layers.is_empty() {
            return Err("no layers".into());
        }
        let mut width = inputs;
        let mut layers = Vec::new();
        for (k, l) in file.layers.iter().enumerate() {
            let rows = l.weight.len();
            if rows == 0 || l.weight.iter().any(|r| r.len() != width) || l.bias.len() != rows {
                return Err(format!(
                    "layer {k}: a {rows}×{width} weight and {rows} biases expected"
                ));
            }
            let values: Vec<f64> = l.weight.iter().flatten().copied().collect();
            if values.iter().chain(&l.bias).any(|x| !x.is_finite()) {
                return Err(format!("layer {k}: a weight or bias is not finite"));
            }
            layers.push((
                DMatrix::from_row_slice(rows, width, &values),
                DVector::from_vec(l.bias.clone()),
            ));
            width = rows;
        }
        Ok(Self { layers })
    }

    pub fn outputs(&self) -> usize {
        self.layers.last().map_or(0, |l| l.1.len())
    }

    pub fn forward(&self, input: &[f64]) -> DVector<f64> {
        let mut x = DVector::from_column_slice(input);
        let last = self.layers.len() - 1;
        for (k, (w, b)) in self.layers.iter().enumerate() {
            x = w * x + b;
            x.apply(|v| *v = if k == last { v.tanh() } else { v.max(0.0) });
        }
        x
    }
}

impl Policy for Mlp {
    fn act(&mut self, observation: &[f64; 6]) -> Action {
        let y = self.forward(observation);
        Action::Continuous([y[0], y[1]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hand_made_network_gives_its_hand_computed_answer() {
        // 6 → 2 (ReLU) → 2 (tanh).
        let text = r#"{"layers": [
            {"weight": [[1,0,0,0,0,0],[0,-1,0,0,0,0]], "bias": [0, 0.5]},
            {"weight": [[1,1],[0,-2]], "bias": [0, 0]}]}"#;
        let m = Mlp::parse(text, 6).unwrap();
        // Hidden: relu(0.3) = 0.3, relu(-0.8 + 0.5) = 0 → out tanh(0.3), tanh(0).
        let y = m.forward(&[0.3, 0.8, 0.0, 0.0, 0.0, 0.0]);
        assert!(
            (y[0] - 0.3f64.tanh()).abs() < 1e-12 && y[1].abs() < 1e-12,
            "{y}"
        );
        assert_eq!(m.outputs(), 2);
    }

    #[test]
    fn bad_files_are_named() {
        assert!(Mlp::parse("{}", 6).is_err());
        let wrong = r#"{"layers": [{"weight": [[1,2,3]], "bias": [0]}]}"#;
        assert!(Mlp::parse(wrong, 6).unwrap_err().contains("layer 0"));
    }
}
