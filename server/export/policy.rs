//! The learner's policy for other tools: the actor network's tensors (`actor.layers.<i>.weight`
//! and `.bias`, PyTorch's `[out, in]` layout, f32) taken from a session's learner checkpoint,
//! with the learner's config and sizes in `__metadata__`. The actor is an MLP with ReLU between
//! layers whose last layer gives the tanh-squashed Gaussian's mean and log-std (`2 * act_dim`
//! outputs: means first); the deterministic action is `tanh(mean)`, in [-1, 1]. Pure.

use std::collections::HashMap;

use safetensors::tensor::TensorView;
use safetensors::{SafeTensorError, SafeTensors};

/// Why a learner checkpoint gives no policy file.
#[derive(Debug, thiserror::Error)]
pub enum PolicyError {
    #[error("the learner checkpoint: {0}")]
    Checkpoint(SafeTensorError),
    #[error("the learner checkpoint's metadata: {0}")]
    Metadata(SafeTensorError),
    #[error("the learner checkpoint holds no actor")]
    NoActor,
    /// Writing the policy's tensors.
    #[error("{0}")]
    Write(SafeTensorError),
}

/// The actor's part of a learner checkpoint (`Sac::to_safetensors` bytes).
pub fn policy_safetensors(learner: &[u8]) -> Result<Vec<u8>, PolicyError> {
    let st = SafeTensors::deserialize(learner).map_err(PolicyError::Checkpoint)?;
    let (_, header) = SafeTensors::read_metadata(learner).map_err(PolicyError::Metadata)?;
    let source = header.metadata().clone().unwrap_or_default();
    let mut actor: Vec<(String, TensorView<'_>)> = st
        .tensors()
        .into_iter()
        .filter(|(name, _)| name.starts_with("actor."))
        .collect();
    if actor.is_empty() {
        return Err(PolicyError::NoActor);
    }
    actor.sort_by(|a, b| a.0.cmp(&b.0));
    let mut metadata = HashMap::from([
        ("format".to_string(), "dualrep-policy/1".to_string()),
        (
            "activation".to_string(),
            "relu between layers; the last layer's outputs are the mean then the log-std of a tanh-squashed Gaussian; act deterministically with tanh(mean)".to_string(),
        ),
    ]);
    for key in ["config", "dims", "updates"] {
        if let Some(v) = source.get(key) {
            metadata.insert(key.to_string(), v.clone());
        }
    }
    safetensors::serialize(actor, Some(metadata)).map_err(PolicyError::Write)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rl::{Sac, SacConfig};
    use crate::sim::Task;

    #[test]
    fn the_policy_file_holds_the_actor_and_acts_like_it() {
        let mut config = SacConfig::for_task(Task::Reaching);
        config.hidden = vec![8, 8];
        let mut learner = Sac::new(4, 3, config, 1);
        let bytes = policy_safetensors(&learner.to_safetensors()).unwrap();
        let st = SafeTensors::deserialize(&bytes).unwrap();
        let names: Vec<String> = st.names().into_iter().map(String::from).collect();
        assert!(names.iter().all(|n| n.starts_with("actor.")), "{names:?}");
        assert_eq!(names.len(), 6, "three layers, weight and bias each");
        // Evaluate the actor from the file alone and compare with the learner's own action.
        let layer = |i: usize| {
            let f = |name: String| {
                let t = st.tensor(&name).unwrap();
                let v: Vec<f32> = t
                    .data()
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
                    .collect();
                (t.shape().to_vec(), v)
            };
            (
                f(format!("actor.layers.{i}.weight")),
                f(format!("actor.layers.{i}.bias")),
            )
        };
        let obs = [0.1f32, -0.2, 0.3, 0.05];
        let mut x: Vec<f32> = obs.to_vec();
        for i in 0..3 {
            let ((shape, w), (_, b)) = layer(i);
            let (out, inp) = (shape[0], shape[1]);
            x = (0..out)
                .map(|o| b[o] + (0..inp).map(|k| w[o * inp + k] * x[k]).sum::<f32>())
                .map(|v| if i < 2 { v.max(0.0) } else { v })
                .collect();
        }
        let mut action = [0.0f32; 3];
        learner.act(&obs, true, &mut action);
        for (a, m) in action.iter().zip(&x[..3]) {
            assert!((a - m.tanh()).abs() < 1e-5, "{a} vs tanh({m})");
        }
        assert!(policy_safetensors(b"nonsense").is_err());
    }
}
