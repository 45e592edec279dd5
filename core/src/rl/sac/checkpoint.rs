//! A learner as safetensors bytes: every network (PyTorch names: `actor.layers.0.weight`,
//! `q1_target.layers.2.bias`, ...), `log_ent_coef`, every Adam moment
//! (`optimizer.critic.1.exp_avg_sq`), and in `__metadata__`, as JSON strings, the config, the
//! sizes, the update and optimiser step counts and the RNG state. Resuming from it continues
//! bit for bit as if training had never stopped. The caller writes the bytes wherever it likes.
//!
//! A checksum (FNV-1a, 64 bits) over every tensor and metadata entry turns corrupt bytes into a
//! [`CheckpointError`] rather than a silently different learner.

use std::collections::{BTreeMap, HashMap};

use safetensors::tensor::TensorView;
use safetensors::{Dtype, SafeTensorError, SafeTensors};
use serde::{Deserialize, Serialize};

use super::{Adam, Mlp, Sac, SacConfig};
use crate::rl::rng_state::RngState;

const FORMAT: &str = "dualrep-sac/1";

/// Why bytes could not be read back as a [`Sac`].
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("not a readable safetensors file: {0}")]
    Format(#[from] SafeTensorError),
    #[error("checkpoint metadata has no {0:?} entry")]
    MissingMetadata(&'static str),
    #[error("checkpoint metadata {key:?} is unreadable: {message}")]
    BadMetadata { key: &'static str, message: String },
    #[error("checkpoint format {found:?}, this build reads {FORMAT:?}")]
    UnknownFormat { found: String },
    #[error("checkpoint is corrupt: checksum {found:016x}, recorded {recorded:016x}")]
    Checksum { recorded: u64, found: u64 },
    #[error("checkpoint lacks tensor {0:?}")]
    MissingTensor(String),
    #[error("checkpoint tensor {name:?}: {message}")]
    BadTensor { name: String, message: String },
    #[error("checkpoint has {found} tensors, a learner of this config has {expected}")]
    TensorCount { expected: usize, found: usize },
    #[error("checkpoint config is invalid: {0}")]
    InvalidConfig(String),
}

#[derive(Serialize, Deserialize)]
struct Dims {
    obs_dim: usize,
    act_dim: usize,
}

/// A learner's tensors `(name, shape, f32 bytes)` and metadata, before serialisation.
type Parts = (Vec<(String, Vec<usize>, Vec<u8>)>, BTreeMap<String, String>);

impl Sac {
    /// Everything needed to resume, as safetensors bytes. The bytes of one state can differ
    /// from call to call (safetensors writes its metadata from a `HashMap`); compare learners
    /// with [`Sac::state_checksum`].
    pub fn to_safetensors(&self) -> Vec<u8> {
        let (tensors, mut metadata) = self.parts();
        let sum = checksum_of(&tensors, &metadata);
        metadata.insert("checksum".into(), format!("{sum:016x}"));

        let views = tensors.iter().map(|(name, shape, bytes)| {
            let view = TensorView::new(Dtype::F32, shape.clone(), bytes)
                .expect("shape and byte length agree by construction");
            (name.as_str(), view)
        });
        safetensors::serialize(views, Some(metadata.into_iter().collect()))
            .expect("serialising in-memory f32 tensors cannot fail")
    }

    /// FNV-1a over every tensor and metadata entry in a fixed order: equal exactly when two
    /// learners would resume identically (the checkpoint's recorded checksum).
    pub fn state_checksum(&self) -> u64 {
        let (tensors, metadata) = self.parts();
        checksum_of(&tensors, &metadata)
    }

    fn parts(&self) -> Parts {
        let mut tensors: Vec<(String, Vec<usize>, Vec<u8>)> = Vec::new();
        for (net_name, net) in self.networks() {
            for t in net.named_parameters() {
                tensors.push((format!("{net_name}.{}", t.name), t.shape, to_bytes(t.data)));
            }
        }
        tensors.push((
            "log_ent_coef".into(),
            vec![1],
            to_bytes(&[self.log_ent_coef]),
        ));
        let mut steps = BTreeMap::new();
        for (opt_name, adam) in self.optimizers() {
            steps.insert(opt_name, adam.steps());
            for (group, (m, v)) in adam.moments().enumerate() {
                let name = format!("optimizer.{opt_name}.{group}");
                tensors.push((format!("{name}.exp_avg"), vec![m.len()], to_bytes(m)));
                tensors.push((format!("{name}.exp_avg_sq"), vec![v.len()], to_bytes(v)));
            }
        }

        let rng = RngState::of(&self.rng);
        let metadata = BTreeMap::from([
            ("format".to_string(), FORMAT.to_string()),
            ("config".to_string(), json(&self.config)),
            (
                "dims".to_string(),
                json(&Dims {
                    obs_dim: self.obs_dim,
                    act_dim: self.act_dim,
                }),
            ),
            ("updates".to_string(), self.updates.to_string()),
            ("optimizer_steps".to_string(), json(&steps)),
            ("rng".to_string(), json(&rng)),
        ]);
        (tensors, metadata)
    }

    /// Read back what [`Sac::to_safetensors`] wrote. Never panics on bad bytes.
    pub fn from_safetensors(bytes: &[u8]) -> Result<Self, CheckpointError> {
        let st = SafeTensors::deserialize(bytes)?;
        let (_, header) = SafeTensors::read_metadata(bytes)?;
        let metadata: BTreeMap<String, String> = header
            .metadata()
            .clone()
            .unwrap_or_default()
            .into_iter()
            .collect();
        let format: String = metadata
            .get("format")
            .cloned()
            .ok_or(CheckpointError::MissingMetadata("format"))?;
        if format != FORMAT {
            return Err(CheckpointError::UnknownFormat { found: format });
        }

        // Checksum first: everything after may then trust what it reads.
        let recorded = u64::from_str_radix(meta(&metadata, "checksum")?, 16).map_err(|e| {
            CheckpointError::BadMetadata {
                key: "checksum",
                message: e.to_string(),
            }
        })?;
        let stored = st.tensors();
        let unchecked: BTreeMap<String, String> = metadata
            .iter()
            .filter(|(k, _)| *k != "checksum")
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        let mut entries: Vec<(&str, &[usize], &[u8])> = stored
            .iter()
            .map(|(name, view)| (name.as_str(), view.shape(), view.data()))
            .collect();
        let found = checksum(&mut entries, &unchecked);
        if found != recorded {
            return Err(CheckpointError::Checksum { recorded, found });
        }

        let config: SacConfig = parse(&metadata, "config")?;
        let dims: Dims = parse(&metadata, "dims")?;
        let updates: u64 = parse(&metadata, "updates")?;
        let steps: HashMap<String, u64> = parse(&metadata, "optimizer_steps")?;
        let rng: RngState = parse(&metadata, "rng")?;
        validate(&config, &dims)?;

        let (obs_dim, act_dim, hidden) = (dims.obs_dim, dims.act_dim, config.hidden.clone());
        let critic = || Mlp::zeros(obs_dim + act_dim, &hidden, 1);
        let layer_norm = config.critic_layer_norm;
        let env_critic = || match layer_norm {
            true => critic().with_layer_norm(),
            false => critic(),
        };
        let actor = Mlp::zeros(obs_dim, &hidden, 2 * act_dim);
        let human = config.human_critic.is_some().then(|| (critic(), critic()));
        let rng = rng.restore().map_err(|e| CheckpointError::BadMetadata {
            key: "rng",
            message: e.to_string(),
        })?;
        let mut sac = Sac::from_parts(
            obs_dim,
            act_dim,
            config,
            actor,
            [env_critic(), env_critic()],
            human,
            rng,
        );
        sac.updates = updates;

        let tensors: HashMap<&str, TensorView<'_>> = stored
            .iter()
            .map(|(n, v)| (n.as_str(), v.clone()))
            .collect();
        let mut expected = 1;
        for (net_name, net) in sac.networks_mut() {
            let layout: Vec<(String, Vec<usize>)> = net
                .named_parameters()
                .map(|t| (format!("{net_name}.{}", t.name), t.shape))
                .collect();
            let mut offset = 0;
            for (name, shape) in layout {
                let len = shape.iter().product::<usize>();
                read(
                    &tensors,
                    &name,
                    &shape,
                    &mut net.params_mut()[offset..offset + len],
                )?;
                offset += len;
                expected += 1;
            }
        }
        read(
            &tensors,
            "log_ent_coef",
            &[1],
            std::slice::from_mut(&mut sac.log_ent_coef),
        )?;
        for (opt_name, adam) in sac.optimizers_mut() {
            let t = *steps.get(opt_name).ok_or(CheckpointError::BadMetadata {
                key: "optimizer_steps",
                message: format!("no step count for {opt_name:?}"),
            })?;
            for (group, (m, v)) in adam.moments_mut(t).enumerate() {
                let name = format!("optimizer.{opt_name}.{group}");
                read(&tensors, &format!("{name}.exp_avg"), &[m.len()], m)?;
                read(&tensors, &format!("{name}.exp_avg_sq"), &[v.len()], v)?;
                expected += 2;
            }
        }
        if tensors.len() != expected {
            return Err(CheckpointError::TensorCount {
                expected,
                found: tensors.len(),
            });
        }
        Ok(sac)
    }

    fn networks(&self) -> Vec<(&'static str, &Mlp)> {
        let mut nets = vec![
            ("actor", &self.actor),
            ("q1", &self.q1),
            ("q2", &self.q2),
            ("q1_target", &self.q1_target),
            ("q2_target", &self.q2_target),
        ];
        if let Some(hc) = &self.human_critic {
            nets.extend([("h1", &hc.h1), ("h2", &hc.h2)]);
        }
        nets
    }

    fn networks_mut(&mut self) -> Vec<(&'static str, &mut Mlp)> {
        let mut nets = vec![
            ("actor", &mut self.actor),
            ("q1", &mut self.q1),
            ("q2", &mut self.q2),
            ("q1_target", &mut self.q1_target),
            ("q2_target", &mut self.q2_target),
        ];
        if let Some(hc) = &mut self.human_critic {
            nets.extend([("h1", &mut hc.h1), ("h2", &mut hc.h2)]);
        }
        nets
    }

    fn optimizers(&self) -> Vec<(&'static str, &Adam)> {
        let mut opts = vec![
            ("actor", &self.actor_optimizer),
            ("critic", &self.critic_optimizer),
            ("ent_coef", &self.ent_coef_optimizer),
        ];
        if let Some(hc) = &self.human_critic {
            opts.push(("human_critic", &hc.optimizer));
        }
        opts
    }

    fn optimizers_mut(&mut self) -> Vec<(&'static str, &mut Adam)> {
        let mut opts = vec![
            ("actor", &mut self.actor_optimizer),
            ("critic", &mut self.critic_optimizer),
            ("ent_coef", &mut self.ent_coef_optimizer),
        ];
        if let Some(hc) = &mut self.human_critic {
            opts.push(("human_critic", &mut hc.optimizer));
        }
        opts
    }
}

fn json<T: Serialize>(value: &T) -> String {
    serde_json::to_string(value).expect("metadata serialises")
}

fn to_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Copy one stored f32 tensor of the expected shape into `out`.
fn read(
    tensors: &HashMap<&str, TensorView<'_>>,
    name: &str,
    shape: &[usize],
    out: &mut [f32],
) -> Result<(), CheckpointError> {
    let view = tensors
        .get(name)
        .ok_or_else(|| CheckpointError::MissingTensor(name.to_string()))?;
    let bad = |message: String| CheckpointError::BadTensor {
        name: name.to_string(),
        message,
    };
    if view.dtype() != Dtype::F32 {
        return Err(bad(format!("dtype {:?}, expected F32", view.dtype())));
    }
    if view.shape() != shape {
        return Err(bad(format!("shape {:?}, expected {shape:?}", view.shape())));
    }
    for (v, b) in out.iter_mut().zip(view.data().chunks_exact(4)) {
        *v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    }
    Ok(())
}

fn meta<'a>(
    metadata: &'a BTreeMap<String, String>,
    key: &'static str,
) -> Result<&'a str, CheckpointError> {
    metadata
        .get(key)
        .map(String::as_str)
        .ok_or(CheckpointError::MissingMetadata(key))
}

fn parse<T: serde::de::DeserializeOwned>(
    metadata: &BTreeMap<String, String>,
    key: &'static str,
) -> Result<T, CheckpointError> {
    serde_json::from_str(meta(metadata, key)?).map_err(|e| CheckpointError::BadMetadata {
        key,
        message: e.to_string(),
    })
}

/// What [`Sac::new`] would assert, as errors.
fn validate(config: &SacConfig, dims: &Dims) -> Result<(), CheckpointError> {
    let bad = |m: &str| Err(CheckpointError::InvalidConfig(m.to_string()));
    if dims.obs_dim == 0 || dims.act_dim == 0 {
        return bad("empty observation or action");
    }
    if config.batch_size == 0 {
        return bad("batch_size is 0");
    }
    if config.hidden.contains(&0) {
        return bad("a hidden layer of size 0");
    }
    Ok(())
}

/// FNV-1a over `(name, shape, bytes)` of every tensor in name order, then every metadata entry.
fn checksum_of(
    tensors: &[(String, Vec<usize>, Vec<u8>)],
    metadata: &BTreeMap<String, String>,
) -> u64 {
    let mut entries: Vec<(&str, &[usize], &[u8])> = tensors
        .iter()
        .map(|(name, shape, bytes)| (name.as_str(), &shape[..], &bytes[..]))
        .collect();
    checksum(&mut entries, metadata)
}

fn checksum(tensors: &mut [(&str, &[usize], &[u8])], metadata: &BTreeMap<String, String>) -> u64 {
    tensors.sort_by(|a, b| a.0.cmp(b.0));
    let mut hash = Fnv1a::default();
    for (name, shape, bytes) in tensors.iter() {
        hash.write(name.as_bytes());
        for &d in shape.iter() {
            hash.write(&(d as u64).to_le_bytes());
        }
        hash.write(bytes);
    }
    for (key, value) in metadata {
        hash.write(key.as_bytes());
        hash.write(value.as_bytes());
    }
    hash.0
}

struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
        // Separate fields, so that ("ab", "c") and ("a", "bc") differ.
        self.0 = (self.0 ^ 0xff).wrapping_mul(0x0100_0000_01b3);
    }
}
