//! `sim --checkpoint PATH --judge`: beside each step of the run's policy, the run's human critic
//! H_hat(s, a) and the answer its synthetic teacher would give there (the task's expert as the
//! run's oracle, without faults, at the checkpoint's step). Where the rule did not ask, a run
//! that reads H_hat everywhere (`mix = authors`) learns from the critic instead of the teacher:
//! how well the one stands in for the other on the policy's own steps is what this measures.

use anyhow::Context as _;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig};
use crate::guidance::evaluative_trainer::{Evaluation, EvaluativeQuery, EvaluativeTrainer};
use crate::guidance::expert_oracle::ExpertOracle;
use crate::rl::Sac;
use crate::rl::sac::{Refit, RefitReport};
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
    /// Actions around each step's, ranked by H_hat and by the expert's Q (`--judge-actions`).
    around: Option<AroundActions>,
    /// How the critic was fitted again, if it was (`--refit-critic`).
    refit: Option<RefitReport>,
}

/// Other actions in each state: does H_hat order them as the teacher's critic does? The actor
/// follows H_hat's ranking of actions within a state, which an AUC over steps mixes with the
/// ranking across states.
struct AroundActions {
    /// The teacher's critic (a copy of the expert the oracle consults).
    expert: Sac,
    count: usize,
    noise: Normal<f32>,
    rng: ChaCha8Rng,
    /// Per step, Spearman's rho between H_hat and the expert's Q over the step's action and
    /// `count` others (steps where either is constant are left out).
    rhos: Vec<f64>,
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
    /// With `--judge-actions K`: the mean over steps of Spearman's rho between H_hat and the
    /// expert's Q on the step's action and K others around it (Gaussian, sd 0.3, clipped): 1 is
    /// a critic that orders a state's actions as the teacher's critic does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub within_state_rank_correlation: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub within_state_steps: Option<usize>,
    /// With `--refit-critic`: the judged critic is not the run's but one fitted again on its
    /// answers alone: the gradient steps, the answers drawn from, the last steps' loss.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refit: Option<RefitReport>,
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
            around: None,
            refit: None,
        })
    }

    /// Also rank `count` actions around each step's by H_hat and by `expert`'s Q (a copy of the
    /// teacher's expert); the perturbations are drawn from `seed`.
    pub(super) fn with_actions_around(mut self, expert: Sac, count: usize, seed: u64) -> Self {
        self.around = Some(AroundActions {
            expert,
            count,
            noise: Normal::new(0.0, 0.3).expect("a positive sd"),
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x1d6e_a5c7_0000_0003),
            rhos: Vec::new(),
        });
        self
    }

    /// The critic judged is one fitted again as `refit` says (`--refit-critic`): said in the
    /// summary.
    pub(super) fn with_refit(mut self, refit: Option<RefitReport>) -> Self {
        self.refit = refit;
        self
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
        if let Some(around) = self.around.as_mut() {
            around.rank(&mut self.critic, seen.obs, seen.action, self.action_scale);
        }
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
            within_state_rank_correlation: self
                .around
                .as_ref()
                .map(|a| a.rhos.iter().sum::<f64>() / a.rhos.len().max(1) as f64),
            within_state_steps: self.around.as_ref().map(|a| a.rhos.len()),
            refit: self.refit,
        }
    }
}

/// `critic`'s human critic fitted again on the answers of `checkpoint`'s replay (the critic's
/// own run's checkpoint), as `refit` says.
pub(super) fn refit_critic(
    critic: &mut Sac,
    checkpoint: &[u8],
    refit: Refit,
) -> anyhow::Result<RefitReport> {
    let replay = EvaluativeRun::checkpoint_replay(checkpoint).context("--refit-critic")?;
    let report = critic
        .refit_human_critic(&replay, refit)
        .context("--refit-critic")?;
    eprintln!(
        "sim: the critic fitted again from fresh heads (seed {}): {} gradient steps on {} of the replay's {} answered transitions, last loss {:.4}",
        refit.seed,
        report.updates,
        report.answers,
        replay.answered_len(),
        report.final_loss
    );
    Ok(report)
}

impl AroundActions {
    /// H_hat and the expert's Q on `action` and `count` actions around it, as both critics are
    /// shown them (scaled by `scale`), and their rank correlation.
    fn rank(&mut self, critic: &mut Sac, obs: &[f32], action: &[f32], scale: f32) {
        let (mut h, mut q) = (Vec::new(), Vec::new());
        let mut shown = vec![0.0; action.len()];
        for k in 0..=self.count {
            for (s, a) in shown.iter_mut().zip(action) {
                let moved = if k == 0 {
                    *a
                } else {
                    (a + self.noise.sample(&mut self.rng)).clamp(-1.0, 1.0)
                };
                *s = moved * scale;
            }
            h.push(critic.human_estimate(obs, &shown));
            q.push(self.expert.q_value(obs, &shown));
        }
        if let Some(rho) = spearman(&h, &q) {
            self.rhos.push(rho);
        }
    }
}

/// Spearman's rho (Pearson's on midranks); `None` when either side is constant.
fn spearman(xs: &[f32], ys: &[f32]) -> Option<f64> {
    let (rx, ry) = (midranks(xs), midranks(ys));
    let n = rx.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in rx.iter().zip(&ry) {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// Each value's rank from 1, ties sharing their mean rank.
fn midranks(values: &[f32]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut i = 0;
    while i < order.len() {
        let j = (i..order.len())
            .find(|&j| values[order[j]] != values[order[i]])
            .unwrap_or(order.len());
        for &at in &order[i..j] {
            ranks[at] = (i + j + 1) as f64 / 2.0;
        }
        i = j;
    }
    ranks
}

/// P(x > y) + P(x = y) / 2 for x from `xs`, y from `ys` (0.5 when either is empty), by ranks.
fn auc(xs: &[f32], ys: &[f32]) -> f64 {
    if xs.is_empty() || ys.is_empty() {
        return 0.5;
    }
    let pooled: Vec<f32> = xs.iter().chain(ys).copied().collect();
    let rank_sum: f64 = midranks(&pooled)[..xs.len()].iter().sum();
    let (n, m) = (xs.len() as f64, ys.len() as f64);
    (rank_sum - n * (n + 1.0) / 2.0) / (n * m)
}

#[cfg(test)]
mod tests {
    use super::{auc, spearman};

    #[test]
    fn spearman_ranks_with_ties_and_says_when_it_cannot() {
        assert_eq!(spearman(&[1.0, 2.0, 3.0], &[10.0, 20.0, 30.0]), Some(1.0));
        assert_eq!(spearman(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]), Some(-1.0));
        assert_eq!(spearman(&[1.0, 1.0, 1.0], &[3.0, 2.0, 1.0]), None);
        // Midranks (1.5, 1.5, 3) against (1, 2, 3): 1.5 / sqrt(1.5 * 2).
        let rho = spearman(&[5.0, 5.0, 9.0], &[1.0, 2.0, 3.0]).unwrap();
        assert!((rho - 0.866_025_403_784_438_6).abs() < 1e-12, "{rho}");
    }

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
