//! `sim --checkpoint PATH --judge`: beside each step of the run's policy, the run's human critic
//! H_hat(s, a) and the answer its synthetic teacher would give there (the task's expert as the
//! run's oracle, without faults, at the checkpoint's step). Where the rule did not ask, a run
//! that reads H_hat everywhere (`mix = authors`) learns from the critic instead of the teacher:
//! how well the one stands in for the other on the policy's own steps is what this measures.

use serde::Serialize;

use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::evaluative_trainer::{Evaluation, EvaluativeQuery, EvaluativeTrainer};
use crate::guidance::expert_oracle::ExpertOracle;
use crate::rl::Sac;
use crate::scene_graph::SceneGraph;
use crate::sim::Outcome;
use crate::sim::rollout::StepSeen;

/// The critic and the teacher, judging the same steps.
pub(super) struct Judge {
    critic: Sac,
    teacher: ExpertOracle,
    graph: SceneGraph,
    /// The step the run was at: the teacher's alpha follows it.
    step: u64,
    action_scale: f32,
    shown_action: Vec<f32>,
    judged: Vec<(f32, Evaluation)>,
}

/// The judge's account in `sim`'s summary.
#[derive(Debug, Serialize)]
pub(super) struct JudgeSummary {
    pub steps: usize,
    /// The teacher's answers: +1, -1, and no judgement.
    pub good: usize,
    pub bad: usize,
    pub none: usize,
    /// H_hat's mean on the steps the teacher answers +1, and -1.
    pub h_hat_mean_good: f64,
    pub h_hat_mean_bad: f64,
    /// The share of +1 and -1 steps on which H_hat has the answer's sign.
    pub sign_agreement: f64,
    /// P(H_hat on a +1 step > H_hat on a -1 step), ties half: 0.5 is a critic that cannot tell
    /// them apart, 1 one that always can.
    pub auc_good_over_bad: f64,
}

impl Judge {
    /// The judge of the steps of a run with `config` at `step` (the teacher: the task's
    /// `expert` as that run's oracle), by the human critic of `critic`, that run's learner or
    /// another's. `Err`: `critic` has no human critic.
    pub(super) fn new(
        config: &EvaluativeRunConfig,
        critic: Sac,
        expert: Sac,
        step: u64,
        act_dim: usize,
    ) -> anyhow::Result<Self> {
        if !critic.has_human_critic() {
            anyhow::bail!(
                "--judge: the critic's learner has no human critic; only a run that learns from \
                 answers has an H_hat to judge (this run's method: {})",
                config.method
            );
        }
        Ok(Self {
            critic,
            teacher: ExpertOracle::new(expert, act_dim).with_config(config.oracle),
            graph: config.scene_graph,
            step,
            action_scale: config.oracle.action_scale,
            shown_action: vec![0.0; act_dim],
            judged: Vec::new(),
        })
    }

    /// H_hat and the teacher's answer on one step (the action shown to the critic scaled as
    /// the run showed it).
    pub(super) fn judge(&mut self, seen: &StepSeen<'_>) -> (f32, Evaluation) {
        for (shown, a) in self.shown_action.iter_mut().zip(seen.action) {
            *shown = a * self.action_scale;
        }
        let predicted = self.critic.human_estimate(seen.obs, &self.shown_action);
        let answer = self.teacher.evaluate(&EvaluativeQuery {
            step: self.step,
            obs: seen.obs,
            action: seen.action,
            next_obs: seen.next_obs,
            reward: seen.reward,
            terminated: seen.outcome.is_some_and(|o| o != Outcome::TimeLimit),
            abstract_state: self.graph.evaluate(seen.next_obs, seen.action),
            predicted,
        });
        self.judged.push((predicted, answer));
        (predicted, answer)
    }

    pub(super) fn summary(&self) -> JudgeSummary {
        let of = |wanted: Evaluation| -> Vec<f32> {
            self.judged
                .iter()
                .filter(|(_, a)| *a == wanted)
                .map(|(h, _)| *h)
                .collect()
        };
        let (good, bad) = (of(Evaluation::Good), of(Evaluation::Bad));
        let mean = |v: &[f32]| v.iter().map(|&h| f64::from(h)).sum::<f64>() / v.len().max(1) as f64;
        let agree =
            good.iter().filter(|&&h| h > 0.0).count() + bad.iter().filter(|&&h| h < 0.0).count();
        JudgeSummary {
            steps: self.judged.len(),
            good: good.len(),
            bad: bad.len(),
            none: self.judged.len() - good.len() - bad.len(),
            h_hat_mean_good: mean(&good),
            h_hat_mean_bad: mean(&bad),
            sign_agreement: agree as f64 / (good.len() + bad.len()).max(1) as f64,
            auc_good_over_bad: auc(&good, &bad),
        }
    }
}

/// P(x > y) + P(x = y) / 2 for x from `xs`, y from `ys` (0.5 when either is empty), by ranks.
fn auc(xs: &[f32], ys: &[f32]) -> f64 {
    if xs.is_empty() || ys.is_empty() {
        return 0.5;
    }
    let mut all: Vec<(f32, bool)> = xs
        .iter()
        .map(|&x| (x, true))
        .chain(ys.iter().map(|&y| (y, false)))
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Midranks over ties, summed for the xs.
    let (mut rank_sum, mut i) = (0.0f64, 0);
    while i < all.len() {
        let j = (i..all.len())
            .find(|&j| all[j].0 != all[i].0)
            .unwrap_or(all.len());
        let midrank = (i + j + 1) as f64 / 2.0;
        rank_sum += midrank * all[i..j].iter().filter(|(_, x)| *x).count() as f64;
        i = j;
    }
    let (n, m) = (xs.len() as f64, ys.len() as f64);
    (rank_sum - n * (n + 1.0) / 2.0) / (n * m)
}

#[cfg(test)]
mod tests {
    use super::auc;

    #[test]
    fn auc_counts_pairs_and_half_ties() {
        assert_eq!(auc(&[2.0, 3.0], &[0.0, 1.0]), 1.0);
        assert_eq!(auc(&[0.0, 1.0], &[2.0, 3.0]), 0.0);
        assert_eq!(auc(&[1.0], &[1.0]), 0.5);
        // 3 > 1, 3 > 2; 2 > 1, 2 = 2: (1 + 1 + 1 + 0.5) / 4.
        assert_eq!(auc(&[3.0, 2.0], &[1.0, 2.0]), 0.875);
        assert_eq!(auc(&[], &[1.0]), 0.5);
    }
}
