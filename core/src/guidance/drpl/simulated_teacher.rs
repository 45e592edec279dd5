//! The preference oracle with a teacher's faults (`guidance::teacher`, after B-Pref): it knows
//! theta_true like the paper's oracle, but may prefer by chance (Boltzmann beta), weigh a
//! segment's last steps more (myopic gamma), answer "about equal" below a margin, skip pairs
//! whose better segment is worth less than a threshold, and flip its answer at an error rate.
//! Without faults it is [`SyntheticOracle`] exactly.
//!
//! Rewards are the oracle's own, `theta . Phi` over standardised mean features; the myopic
//! teacher's Phi is the mean of the segment's per-step features weighted by `gamma^(H-1-t)`
//! (B-Pref discounts the sum of a segment's rewards the same way), then standardised as every
//! clip is.

use super::pool::{Clip, QueryPool};
use super::segments::Standardizer;
use super::trainer::{Preference, PreferenceQuery, PreferenceTrainer, SyntheticOracle};
use crate::guidance::teacher::{Decision, FaultyJudge, TeacherFaults, myopic_weights};

/// What a myopic teacher needs of the pool: every step's features and the standardisation.
struct MyopicView {
    gamma: f64,
    steps: Vec<Vec<Vec<f64>>>,
    standardizer: Standardizer,
}

impl MyopicView {
    fn new(pool: &QueryPool, gamma: f64) -> Self {
        Self {
            gamma,
            steps: (0..pool.trajectories())
                .map(|t| pool.step_features(t).to_vec())
                .collect(),
            standardizer: pool.standardizer().clone(),
        }
    }

    /// The clip's standardised features as the myopic teacher sees them.
    fn features(&self, clip: &Clip) -> Vec<f64> {
        let steps = &self.steps[clip.trajectory][clip.start..clip.end];
        let weights = myopic_weights(steps.len(), self.gamma);
        let dim = self.standardizer.mean.len();
        let mut raw = vec![0.0; dim];
        for (phi, w) in steps.iter().zip(&weights) {
            for (r, x) in raw.iter_mut().zip(phi) {
                *r += w * x;
            }
        }
        self.standardizer.apply(&raw)
    }
}

/// The synthetic preference teacher, with or without faults.
pub struct SimulatedTeacher {
    oracle: SyntheticOracle,
    judge: FaultyJudge,
    myopic: Option<MyopicView>,
}

impl SimulatedTeacher {
    /// A teacher who knows `theta_true`, with `faults` drawing from a stream of `seed`, over the
    /// run's `pool` (read only by a myopic teacher).
    pub fn new(theta_true: Vec<f64>, faults: TeacherFaults, seed: u64, pool: &QueryPool) -> Self {
        Self {
            oracle: SyntheticOracle::new(theta_true),
            judge: FaultyJudge::new(faults, seed),
            myopic: faults.myopia().map(|g| MyopicView::new(pool, g)),
        }
    }

    pub fn theta(&self) -> &[f64] {
        self.oracle.theta()
    }
}

impl PreferenceTrainer for SimulatedTeacher {
    fn compare(&mut self, q: &PreferenceQuery<'_>) -> Preference {
        if self.judge.faults().is_perfect() {
            return self.oracle.compare(q);
        }
        let (left, right) = match &self.myopic {
            Some(view) => (
                self.oracle.reward(&view.features(q.left)),
                self.oracle.reward(&view.features(q.right)),
            ),
            None => (
                self.oracle.reward(&q.left.features),
                self.oracle.reward(&q.right.features),
            ),
        };
        match self.judge.decide(left - right, left.max(right)) {
            Decision::First => Preference::Left,
            Decision::Second => Preference::Right,
            Decision::Equal => Preference::Equal,
            Decision::Skip => Preference::Skip,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::drpl::pool::TrajectoryFeatures;
    use crate::scene_graph::AbstractState;

    /// One trajectory of 4 steps with feature t, cut into one segment per step pair.
    fn pool() -> QueryPool {
        let t = TrajectoryFeatures {
            states: [0, 0, 1, 1].map(AbstractState).to_vec(),
            phis: vec![vec![0.0], vec![4.0], vec![2.0], vec![1.0]],
        };
        QueryPool::new(1, vec![t], 1)
    }

    fn ask(t: &mut SimulatedTeacher, pool: &QueryPool) -> Preference {
        let (left, right) = (pool.window_clip(0, 0..2), pool.window_clip(0, 2..4));
        t.compare(&PreferenceQuery {
            query: 0,
            left: &left,
            right: &right,
            predicate: None,
        })
    }

    #[test]
    fn without_faults_it_is_the_papers_oracle() {
        let pool = pool();
        let mut t = SimulatedTeacher::new(vec![1.0], TeacherFaults::default(), 1, &pool);
        // Means 2.0 against 1.5: left.
        assert_eq!(ask(&mut t, &pool), Preference::Left);
    }

    #[test]
    fn a_myopic_teacher_judges_by_the_last_steps() {
        let pool = pool();
        let myopic = TeacherFaults {
            gamma: Some(0.01),
            ..Default::default()
        };
        // Nearly only the last step counts: 4.0 (left) against 1.0 (right), still left; with
        // theta = -1 the perfect teacher prefers right (mean 1.5 < 2.0)...
        let mut t = SimulatedTeacher::new(vec![-1.0], TeacherFaults::default(), 1, &pool);
        assert_eq!(ask(&mut t, &pool), Preference::Right);
        // ...and so does the myopic one, now by more (-4 against -1).
        let mut m = SimulatedTeacher::new(vec![-1.0], myopic, 1, &pool);
        assert_eq!(ask(&mut m, &pool), Preference::Right);
        // A segment whose early steps are good and last step bad flips: left = steps 1..3
        // (4.0 then 2.0: mean 3.0, last 2.0) against right = steps 0..2 (0.0 then 4.0: mean
        // 2.0, last 4.0).
        let (left, right) = (pool.window_clip(0, 1..3), pool.window_clip(0, 0..2));
        let q = PreferenceQuery {
            query: 0,
            left: &left,
            right: &right,
            predicate: None,
        };
        let mut perfect = SimulatedTeacher::new(vec![1.0], TeacherFaults::default(), 1, &pool);
        assert_eq!(perfect.compare(&q), Preference::Left);
        let mut m = SimulatedTeacher::new(vec![1.0], myopic, 1, &pool);
        assert_eq!(m.compare(&q), Preference::Right);
    }

    #[test]
    fn skip_and_equal_thresholds_apply_to_the_true_rewards() {
        let pool = pool();
        let skipper = TeacherFaults {
            skip: Some(100.0),
            ..Default::default()
        };
        let mut t = SimulatedTeacher::new(vec![1.0], skipper, 1, &pool);
        assert_eq!(ask(&mut t, &pool), Preference::Skip);
        let unsure = TeacherFaults {
            equal: 10.0,
            ..Default::default()
        };
        let mut t = SimulatedTeacher::new(vec![1.0], unsure, 1, &pool);
        assert_eq!(ask(&mut t, &pool), Preference::Equal);
    }
}
