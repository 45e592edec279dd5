//! Recorded trajectories as bytes, so that a preference session on an environment in another
//! process keeps the trajectories it recorded there: a robot's, or any env's that does not
//! repeat an episode from its seed, cannot be recorded again on resume. No IO here.
//!
//! Layout, little-endian: `MAGIC`, then u32 trajectory count; per trajectory its u64 reset seed
//! and u32 step count; per step u32 sizes (obs, action, env features), the obs, action and
//! next obs as f32, the abstract state as u32, the env features as f64.

use super::trajectories::{Trajectory, TrajectoryStep};
use crate::scene_graph::AbstractState;

const MAGIC: &[u8] = b"dualrep-trajectories/1\n";

/// Why bytes are not recorded trajectories.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TrajectoryBytesError {
    #[error("not dualrep's recorded trajectories")]
    NotTrajectories,
    #[error("the trajectories are cut short")]
    CutShort,
    #[error("the trajectories have trailing bytes")]
    TrailingBytes,
}

/// The trajectories as bytes.
pub fn to_bytes(trajectories: &[Trajectory]) -> Vec<u8> {
    let mut out = Vec::from(MAGIC);
    out.extend_from_slice(&(trajectories.len() as u32).to_le_bytes());
    for t in trajectories {
        out.extend_from_slice(&t.reset_seed.to_le_bytes());
        out.extend_from_slice(&(t.steps.len() as u32).to_le_bytes());
        for s in &t.steps {
            for n in [s.obs.len(), s.action.len(), s.env_features.len()] {
                out.extend_from_slice(&(n as u32).to_le_bytes());
            }
            for v in s.obs.iter().chain(&s.action).chain(&s.next_obs) {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&s.abstract_state.0.to_le_bytes());
            for v in &s.env_features {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

/// Reads the bytes back in order.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], TrajectoryBytesError> {
        let (head, rest) = self
            .0
            .split_first_chunk::<N>()
            .ok_or(TrajectoryBytesError::CutShort)?;
        self.0 = rest;
        Ok(*head)
    }

    fn u32(&mut self) -> Result<u32, TrajectoryBytesError> {
        self.take().map(u32::from_le_bytes)
    }

    fn f32s(&mut self, n: usize) -> Result<Vec<f32>, TrajectoryBytesError> {
        (0..n)
            .map(|_| self.take().map(f32::from_le_bytes))
            .collect()
    }
}

/// The trajectories [`to_bytes`] wrote.
pub fn from_bytes(bytes: &[u8]) -> Result<Vec<Trajectory>, TrajectoryBytesError> {
    let mut r = Reader(
        bytes
            .strip_prefix(MAGIC)
            .ok_or(TrajectoryBytesError::NotTrajectories)?,
    );
    let count = r.u32()? as usize;
    let mut out = Vec::with_capacity(count.min(1 << 16));
    for _ in 0..count {
        let reset_seed = u64::from_le_bytes(r.take()?);
        let steps = r.u32()? as usize;
        let mut t = Trajectory {
            reset_seed,
            steps: Vec::with_capacity(steps.min(1 << 16)),
        };
        for _ in 0..steps {
            let (obs, act, feat) = (r.u32()? as usize, r.u32()? as usize, r.u32()? as usize);
            let step = TrajectoryStep {
                obs: r.f32s(obs)?,
                action: r.f32s(act)?,
                next_obs: r.f32s(obs)?,
                abstract_state: AbstractState(r.u32()?),
                env_features: (0..feat)
                    .map(|_| r.take().map(f64::from_le_bytes))
                    .collect::<Result<_, _>>()?,
            };
            t.steps.push(step);
        }
        out.push(t);
    }
    if !r.0.is_empty() {
        return Err(TrajectoryBytesError::TrailingBytes);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::drpl::trajectories::{collect, rng};
    use crate::scene_graph::SceneGraph;
    use crate::sim::{EnvOptions, Task};

    #[test]
    fn recorded_trajectories_round_trip_bit_for_bit() {
        let task = Task::LunarLander;
        let mut trajs = collect(
            task,
            &EnvOptions::default(),
            &SceneGraph::for_task(task),
            3,
            40,
            &mut rng(2),
        );
        trajs[1].steps[0].env_features = vec![0.25, -1.5];
        let bytes = to_bytes(&trajs);
        assert_eq!(from_bytes(&bytes).unwrap(), trajs);
        assert_eq!(
            from_bytes(&bytes[..bytes.len() - 1])
                .unwrap_err()
                .to_string(),
            "the trajectories are cut short"
        );
        assert_eq!(
            from_bytes(b"nope").unwrap_err().to_string(),
            "not dualrep's recorded trajectories"
        );
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(
            from_bytes(&longer).unwrap_err().to_string(),
            "the trajectories have trailing bytes"
        );
    }
}
