//! DRPL's segmentation (algorithms.md section 3, step 2): cut a trajectory wherever its abstract
//! state g changes, so that each segment stands for one abstract state; summarise a stretch of
//! steps by its mean features; standardise features over all segments.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::scene_graph::AbstractState;

/// Runs of g shorter than this many steps are merged into a neighbour \[choice\].
pub const DEFAULT_MIN_RUN: usize = 3;

/// One stretch `start..end` of a trajectory's steps, labelled with one abstract state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    pub trajectory: usize,
    pub start: usize,
    /// Exclusive.
    pub end: usize,
    pub abstract_state: AbstractState,
}

impl Segment {
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }

    pub fn range(&self) -> Range<usize> {
        self.start..self.end
    }
}

/// The maximal runs of equal consecutive states: `(range, state)` in order.
pub fn runs(states: &[AbstractState]) -> Vec<(Range<usize>, AbstractState)> {
    let mut out: Vec<(Range<usize>, AbstractState)> = Vec::new();
    for (t, &g) in states.iter().enumerate() {
        match out.last_mut() {
            Some((range, last)) if *last == g => range.end = t + 1,
            _ => out.push((t..t + 1, g)),
        }
    }
    out
}

/// Cut trajectory `trajectory` (its per-step abstract states) into segments \[choice\]:
///
/// - a run of at least `min_run` steps starts a new segment with its own state;
/// - a shorter run is a flicker of the scene graph at a predicate's threshold (or an engine
///   blinking), not a stretch a person could judge, so it joins the segment before it, which
///   keeps that segment's state;
/// - short runs at the very start have no segment before them, so they join the next one;
/// - a trajectory without any run of `min_run` steps yields no segment (nothing in it stands
///   for one abstract state). With `min_run <= 1` every run is a segment.
pub fn segment(trajectory: usize, states: &[AbstractState], min_run: usize) -> Vec<Segment> {
    let mut out: Vec<Segment> = Vec::new();
    // Start of the short runs that precede the first real segment.
    let mut pending_start: Option<usize> = None;
    for (range, g) in runs(states) {
        if range.len() >= min_run {
            out.push(Segment {
                trajectory,
                start: pending_start.take().unwrap_or(range.start),
                end: range.end,
                abstract_state: g,
            });
        } else if let Some(last) = out.last_mut() {
            last.end = range.end;
        } else {
            pending_start.get_or_insert(range.start);
        }
    }
    out
}

/// Mean of the rows `phis[range]` (the segment features Phi of algorithms.md). An empty range
/// has no mean: that is a caller's bug.
pub fn mean_features(phis: &[Vec<f64>], range: Range<usize>) -> Vec<f64> {
    assert!(!range.is_empty(), "the mean of no steps");
    let n = range.len() as f64;
    let mut mean = vec![0.0; phis[range.start].len()];
    for row in &phis[range] {
        mean.iter_mut().zip(row).for_each(|(m, x)| *m += x);
    }
    mean.iter_mut().for_each(|m| *m /= n);
    mean
}

/// Per-feature standardisation `(x - mean) / std`, fitted once per run over all of DRPL's
/// segments and then applied to the features of every query of every method: all methods'
/// answers then live in one reward space, so theta_true and the alignment mean the same thing
/// whichever method picked the pairs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Standardizer {
    pub mean: Vec<f64>,
    pub std: Vec<f64>,
}

impl Standardizer {
    /// Leaves features as they are.
    pub fn identity(dim: usize) -> Self {
        Self {
            mean: vec![0.0; dim],
            std: vec![1.0; dim],
        }
    }

    /// Population mean and std of `rows` (each of length `dim`). A feature that never varies
    /// gets std 1, so it standardises to 0 instead of dividing by zero; no rows give identity.
    pub fn fit<'a>(dim: usize, rows: impl IntoIterator<Item = &'a [f64]>) -> Self {
        let rows: Vec<&[f64]> = rows.into_iter().collect();
        if rows.is_empty() {
            return Self::identity(dim);
        }
        let n = rows.len() as f64;
        let mean: Vec<f64> = (0..dim)
            .map(|j| rows.iter().map(|r| r[j]).sum::<f64>() / n)
            .collect();
        let std = (0..dim)
            .map(|j| {
                let var = rows.iter().map(|r| (r[j] - mean[j]).powi(2)).sum::<f64>() / n;
                let s = var.sqrt();
                if s > 1e-12 { s } else { 1.0 }
            })
            .collect();
        Self { mean, std }
    }

    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.mean.iter().zip(&self.std))
            .map(|(x, (m, s))| (x - m) / s)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// "AAAB" -> states with bit patterns 'A' = 0, 'B' = 1, ...
    fn states(s: &str) -> Vec<AbstractState> {
        s.bytes()
            .map(|c| AbstractState(u32::from(c - b'A')))
            .collect()
    }

    fn spans(segments: &[Segment]) -> Vec<(usize, usize, char)> {
        segments
            .iter()
            .map(|s| (s.start, s.end, char::from(b'A' + s.abstract_state.0 as u8)))
            .collect()
    }

    #[test]
    fn runs_are_maximal() {
        let r = runs(&states("AAABBBBCA"));
        let got: Vec<_> = r.iter().map(|(r, g)| (r.clone(), g.0)).collect();
        assert_eq!(got, vec![(0..3, 0), (3..7, 1), (7..8, 2), (8..9, 0)]);
        assert!(runs(&[]).is_empty());
    }

    #[test]
    fn cuts_where_the_state_changes() {
        let s = segment(4, &states("AAABBBBCCC"), 3);
        assert_eq!(spans(&s), vec![(0, 3, 'A'), (3, 7, 'B'), (7, 10, 'C')]);
        assert!(s.iter().all(|x| x.trajectory == 4));
    }

    #[test]
    fn short_runs_join_the_previous_segment() {
        // "CA" at the end is shorter than 3: both join B's segment, which stays B.
        let s = segment(0, &states("AAABBBBCA"), 3);
        assert_eq!(spans(&s), vec![(0, 3, 'A'), (3, 9, 'B')]);
        // A short run between two long ones joins the one before it.
        let s = segment(0, &states("AAABBCCCC"), 3);
        assert_eq!(spans(&s), vec![(0, 5, 'A'), (5, 9, 'C')]);
    }

    #[test]
    fn short_runs_at_the_start_join_the_next_segment() {
        let s = segment(0, &states("ABCCCDD"), 3);
        assert_eq!(spans(&s), vec![(0, 7, 'C')]);
        let s = segment(0, &states("BAAAACCC"), 3);
        assert_eq!(spans(&s), vec![(0, 5, 'A'), (5, 8, 'C')]);
    }

    #[test]
    fn no_long_run_no_segment_and_min_run_one_keeps_every_run() {
        assert!(segment(0, &states("ABABAB"), 3).is_empty());
        assert!(segment(0, &[], 3).is_empty());
        let s = segment(0, &states("ABBA"), 1);
        assert_eq!(spans(&s), vec![(0, 1, 'A'), (1, 3, 'B'), (3, 4, 'A')]);
    }

    #[test]
    fn segments_tile_the_trajectory_from_the_first_long_run() {
        let g = states("ABAAACCDDDDBAAAB");
        let s = segment(0, &g, 3);
        assert_eq!(s.first().unwrap().start, 0);
        assert_eq!(s.last().unwrap().end, g.len());
        for w in s.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
        assert_eq!(spans(&s), vec![(0, 7, 'A'), (7, 12, 'D'), (12, 16, 'A')]);
    }

    #[test]
    fn mean_features_over_a_range() {
        let phis = vec![vec![1.0, 0.0], vec![3.0, 2.0], vec![5.0, 4.0]];
        assert_eq!(mean_features(&phis, 0..2), vec![2.0, 1.0]);
        assert_eq!(mean_features(&phis, 1..3), vec![4.0, 3.0]);
        assert_eq!(mean_features(&phis, 2..3), vec![5.0, 4.0]);
    }

    #[test]
    fn standardizer_centres_and_scales_and_survives_constants() {
        let rows = [vec![1.0, 7.0], vec![3.0, 7.0]];
        let st = Standardizer::fit(2, rows.iter().map(Vec::as_slice));
        assert_eq!(st.mean, vec![2.0, 7.0]);
        assert_eq!(st.std, vec![1.0, 1.0]);
        assert_eq!(st.apply(&[3.0, 7.0]), vec![1.0, 0.0]);
        let st = Standardizer::fit(1, [[0.0].as_slice(), &[4.0]]);
        assert_eq!(st.std, vec![2.0]);
        assert_eq!(st.apply(&[0.0]), vec![-1.0]);
        assert_eq!(Standardizer::fit(3, []), Standardizer::identity(3));
    }
}
