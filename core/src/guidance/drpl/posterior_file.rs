//! DRPL's posterior as a safetensors file for other tools: `samples` (`[n, d]`, each a unit
//! theta) and `mean_theta` (`[d]`, their mean normalised to unit length, APReL's `mean`), f64
//! little-endian; `__metadata__` names the features in order and says how many answers shaped
//! it. Pure: returns the bytes.

use std::collections::HashMap;

use safetensors::tensor::TensorView;
use safetensors::{Dtype, SafeTensorError, SafeTensors};

use super::belief::Belief;

/// The posterior of `belief`, whose features are `names`, after `queries` queries.
pub fn posterior_safetensors(belief: &Belief, names: &[&str], queries: usize) -> Vec<u8> {
    let dim = belief.dim();
    let samples: Vec<f64> = belief.samples().flatten().copied().collect();
    let n = samples.len() / dim.max(1);
    let mut mean = belief.mean();
    let norm = mean.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm > 0.0 {
        mean.iter_mut().for_each(|x| *x /= norm);
    }
    let bytes = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    let (samples, mean) = (bytes(&samples), bytes(&mean));
    let tensors = [
        (
            "samples",
            TensorView::new(Dtype::F64, vec![n, dim], &samples).expect("samples' shape"),
        ),
        (
            "mean_theta",
            TensorView::new(Dtype::F64, vec![dim], &mean).expect("mean's shape"),
        ),
    ];
    let metadata = HashMap::from([
        ("format".to_string(), "dualrep-drpl-posterior/1".to_string()),
        (
            "features".to_string(),
            serde_json::to_string(names).expect("names serialise"),
        ),
        ("answers".to_string(), belief.answers().to_string()),
        ("queries".to_string(), queries.to_string()),
    ]);
    safetensors::serialize(tensors, Some(metadata)).expect("a posterior serialises")
}

/// Why bytes are not a posterior file.
#[derive(Debug, thiserror::Error)]
pub enum PosteriorFileError {
    /// Not safetensors (safetensors' words).
    #[error("{0}")]
    Format(SafeTensorError),
    /// The tensor `name` is not there.
    #[error("{name}: {error}")]
    Tensor {
        name: String,
        error: SafeTensorError,
    },
    /// The tensor `name` is not f64.
    #[error("{name} is {dtype:?}, not F64")]
    Dtype { name: String, dtype: Dtype },
}

/// The `(samples, mean_theta)` of a posterior file, rows of `samples` first (tests, tools).
pub fn read_posterior(bytes: &[u8]) -> Result<(Vec<Vec<f64>>, Vec<f64>), PosteriorFileError> {
    let st = SafeTensors::deserialize(bytes).map_err(PosteriorFileError::Format)?;
    let floats = |name: &str| -> Result<(Vec<usize>, Vec<f64>), PosteriorFileError> {
        let t = st
            .tensor(name)
            .map_err(|error| PosteriorFileError::Tensor {
                name: name.to_string(),
                error,
            })?;
        if t.dtype() != Dtype::F64 {
            return Err(PosteriorFileError::Dtype {
                name: name.to_string(),
                dtype: t.dtype(),
            });
        }
        let v = t
            .data()
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        Ok((t.shape().to_vec(), v))
    };
    let (shape, samples) = floats("samples")?;
    let (_, mean) = floats("mean_theta")?;
    let dim = shape.get(1).copied().unwrap_or(0).max(1);
    Ok((samples.chunks(dim).map(<[f64]>::to_vec).collect(), mean))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::drpl::belief::{BeliefConfig, Response};

    #[test]
    fn a_posterior_reads_back_with_its_samples_and_unit_mean() {
        let mut b = Belief::new(
            3,
            BeliefConfig {
                samples: 20,
                ..Default::default()
            },
            7,
        );
        b.add_answer(&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], Response::First);
        b.update();
        let bytes = posterior_safetensors(&b, &["a", "b", "c"], 1);
        let (samples, mean) = read_posterior(&bytes).unwrap();
        assert_eq!(samples.len(), 20);
        assert_eq!(samples[0], b.samples().next().unwrap().to_vec());
        let norm: f64 = mean.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-12);
        let (_, meta) = SafeTensors::read_metadata(&bytes).unwrap();
        let meta = meta.metadata().clone().unwrap();
        assert_eq!(meta["features"], r#"["a","b","c"]"#);
        assert_eq!(meta["answers"], "1");
    }
}
