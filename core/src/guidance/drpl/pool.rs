//! What queries are drawn from: every recorded trajectory's per-step features, DRPL's segments,
//! and the standardisation they share. Built once per run; every method reads clips from it.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use super::features;
use super::segments::{self, Segment, Standardizer};
use super::trajectories::Trajectory;
use crate::scene_graph::AbstractState;
use crate::sim::TaskRef;

/// One trajectory as the pool needs it: g_t and phi(s_{t+1}, a_t) per step.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryFeatures {
    pub states: Vec<AbstractState>,
    pub phis: Vec<Vec<f64>>,
}

/// One side of a query: steps `start..end` of a trajectory and their mean features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Clip {
    pub trajectory: usize,
    pub start: usize,
    /// Exclusive.
    pub end: usize,
    /// The segment's abstract state; `None` for windows and whole trajectories, which may span
    /// several.
    pub abstract_state: Option<AbstractState>,
    /// Standardised mean phi: what the belief and the synthetic oracle see.
    pub features: Vec<f64>,
    /// Mean phi before standardisation, for people and logs.
    pub raw_features: Vec<f64>,
}

impl Clip {
    /// Identifies the stretch of steps, so that a pair is never asked twice.
    pub fn key(&self) -> ClipKey {
        (self.trajectory, self.start, self.end)
    }

    pub fn len(&self) -> usize {
        self.end - self.start
    }

    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}

/// `(trajectory, start, end)`.
pub type ClipKey = (usize, usize, usize);

pub struct QueryPool {
    dim: usize,
    trajectories: Vec<TrajectoryFeatures>,
    segments: Vec<Segment>,
    /// Raw mean phi of each segment, in `segments` order.
    segment_features: Vec<Vec<f64>>,
    standardizer: Standardizer,
}

impl QueryPool {
    /// Segment every trajectory (runs shorter than `min_run` merged, see `segments::segment`)
    /// and fit the standardisation over all segments.
    pub fn new(dim: usize, trajectories: Vec<TrajectoryFeatures>, min_run: usize) -> Self {
        let mut segs = Vec::new();
        for (id, t) in trajectories.iter().enumerate() {
            assert_eq!(t.states.len(), t.phis.len(), "trajectory {id}");
            assert!(t.phis.iter().all(|p| p.len() == dim), "trajectory {id}");
            segs.extend(segments::segment(id, &t.states, min_run));
        }
        let segment_features: Vec<Vec<f64>> = segs
            .iter()
            .map(|s| segments::mean_features(&trajectories[s.trajectory].phis, s.range()))
            .collect();
        let standardizer = Standardizer::fit(dim, segment_features.iter().map(Vec::as_slice));
        Self {
            dim,
            trajectories,
            segments: segs,
            segment_features,
            standardizer,
        }
    }

    /// The pool of `task`'s recorded trajectories, with phi from `features`.
    pub fn from_trajectories(task: &TaskRef, trajectories: &[Trajectory], min_run: usize) -> Self {
        let feats = trajectories
            .iter()
            .map(|t| TrajectoryFeatures {
                states: t.steps.iter().map(|s| s.abstract_state).collect(),
                phis: t.steps.iter().map(|s| features::of_step(task, s)).collect(),
            })
            .collect();
        Self::new(features::dim_of(task), feats, min_run)
    }

    pub fn dim(&self) -> usize {
        self.dim
    }

    pub fn trajectories(&self) -> usize {
        self.trajectories.len()
    }

    pub fn trajectory_len(&self, trajectory: usize) -> usize {
        self.trajectories[trajectory].phis.len()
    }

    /// phi(s_{t+1}, a_t) of every step of `trajectory`, before standardisation.
    pub fn step_features(&self, trajectory: usize) -> &[Vec<f64>] {
        &self.trajectories[trajectory].phis
    }

    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    pub fn standardizer(&self) -> &Standardizer {
        &self.standardizer
    }

    /// Mean number of steps per segment (0 without segments).
    pub fn mean_segment_length(&self) -> f64 {
        if self.segments.is_empty() {
            return 0.0;
        }
        let steps: usize = self.segments.iter().map(Segment::len).sum();
        steps as f64 / self.segments.len() as f64
    }

    /// The random-fragment baseline's window: DRPL's mean segment length, rounded, at least 1.
    pub fn fragment_length(&self) -> usize {
        (self.mean_segment_length().round() as usize).max(1)
    }

    /// Segment `index` as a clip labelled with its abstract state.
    pub fn segment_clip(&self, index: usize) -> Clip {
        let s = &self.segments[index];
        let raw = self.segment_features[index].clone();
        Clip {
            trajectory: s.trajectory,
            start: s.start,
            end: s.end,
            abstract_state: Some(s.abstract_state),
            features: self.standardizer.apply(&raw),
            raw_features: raw,
        }
    }

    /// Steps `range` of `trajectory` as a clip with no single abstract state.
    pub fn window_clip(&self, trajectory: usize, range: Range<usize>) -> Clip {
        let raw = segments::mean_features(&self.trajectories[trajectory].phis, range.clone());
        Clip {
            trajectory,
            start: range.start,
            end: range.end,
            abstract_state: None,
            features: self.standardizer.apply(&raw),
            raw_features: raw,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trajectory whose state at step t is `g[t]` and whose single feature is `t`.
    fn traj(g: &[u32]) -> TrajectoryFeatures {
        TrajectoryFeatures {
            states: g.iter().map(|&b| AbstractState(b)).collect(),
            phis: (0..g.len()).map(|t| vec![t as f64]).collect(),
        }
    }

    #[test]
    fn segments_standardised_over_all_segments() {
        let pool = QueryPool::new(1, vec![traj(&[0, 0, 0, 1, 1, 1]), traj(&[2, 2, 2])], 3);
        assert_eq!(pool.segments().len(), 3);
        // Raw segment means 1, 4, 1: mean 2, population std sqrt(2).
        let st = pool.standardizer();
        assert!((st.mean[0] - 2.0).abs() < 1e-12);
        assert!((st.std[0] - 2f64.sqrt()).abs() < 1e-12);
        let c = pool.segment_clip(1);
        assert_eq!((c.trajectory, c.start, c.end), (0, 3, 6));
        assert_eq!(c.abstract_state, Some(AbstractState(1)));
        assert_eq!(c.raw_features, vec![4.0]);
        assert!((c.features[0] - 2.0 / 2f64.sqrt()).abs() < 1e-12);
        assert!((pool.mean_segment_length() - 3.0).abs() < 1e-12);
        assert_eq!(pool.fragment_length(), 3);
    }

    #[test]
    fn windows_use_the_same_standardisation() {
        let pool = QueryPool::new(1, vec![traj(&[0, 0, 0, 1, 1, 1]), traj(&[2, 2, 2])], 3);
        let w = pool.window_clip(0, 2..4);
        assert_eq!(w.raw_features, vec![2.5]);
        assert_eq!(w.abstract_state, None);
        assert_eq!(w.features, pool.standardizer().apply(&[2.5]));
        assert_eq!(w.key(), (0, 2, 4));
    }

    #[test]
    fn fragment_length_rounds_and_is_at_least_one() {
        // Segment lengths 3 and 4 -> 3.5 -> 4.
        let pool = QueryPool::new(1, vec![traj(&[0, 0, 0, 1, 1, 1, 1])], 3);
        assert_eq!(pool.fragment_length(), 4);
        let empty = QueryPool::new(1, vec![traj(&[0, 1, 0])], 3);
        assert_eq!(empty.segments().len(), 0);
        assert_eq!(empty.fragment_length(), 1);
    }
}
