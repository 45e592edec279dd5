//! The answered mix's gates on the run's own outcomes (`docs/dref-history.md`): how much of
//! H's weight the actor keeps on sampled rows nobody answered, set before every update.
//!
//! - `mix_answered_after = N`: full weight (the authors' mix) until the run's N-th successful
//!   episode, the configured `unanswered` share after it, for good.
//! - `mix_failure_window = N`: the share of the last N episodes that failed (episodes not yet
//!   run count as failed), at least `unanswered`. The first gate shut H's extrapolation off at
//!   the N-th success and Placing's learner then lost the task; this one follows the learner
//!   both ways: failing, it follows the critic's extrapolation of the answers; succeeding, Q.
//! - `mix_authors_until = N`: full weight until the run's step N, then as the other gates or
//!   the configured `unanswered` say. It follows the run's clock, not its outcomes: while an
//!   opening answers a share of every state's visits, H is constrained wherever the learner goes.
//!   With `mix_authors_fade = F` the weight then falls in a straight line to the configured
//!   `unanswered` over F steps (never below what another gate says).

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::rl::HumanCriticConfig;

/// The outcomes of the run's last `failure_window` episodes, oldest first (none while off).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MixGate {
    recent: VecDeque<bool>,
}

impl MixGate {
    /// Keeps a finished episode's outcome while `failure_window` is on.
    pub fn record(&mut self, success: bool, critic: Option<&HumanCriticConfig>) {
        let window = critic.map_or(0, |c| c.failure_window as usize);
        if window == 0 {
            return;
        }
        if self.recent.len() == window {
            self.recent.pop_front();
        }
        self.recent.push_back(success);
    }

    /// The weight on unanswered rows for the update after the run's `step`-th step, where a
    /// gate sets it (`None`: the config's `unanswered`), after `successes` successful episodes.
    pub fn unanswered_weight(
        &self,
        step: u64,
        successes: u64,
        critic: Option<&HumanCriticConfig>,
    ) -> Option<f32> {
        let critic = critic?;
        if step < critic.authors_until || reads_h_everywhere(successes, Some(critic)) {
            return Some(1.0);
        }
        let fading = fading_weight(step, critic);
        let window = critic.failure_window as usize;
        if window == 0 {
            return fading;
        }
        let succeeded = self.recent.iter().filter(|&&s| s).count().min(window);
        let failed = (window - succeeded) as f32 / window as f32;
        Some(failed.max(critic.unanswered).max(fading.unwrap_or(0.0)))
    }
}

/// `mix_authors_fade`'s weight at `step` (past `authors_until`): from 1 down to `unanswered` in
/// a straight line over `authors_fade` steps; `None` once it has run its course or while off.
fn fading_weight(step: u64, critic: &HumanCriticConfig) -> Option<f32> {
    let into = step - critic.authors_until;
    if into >= critic.authors_fade {
        return None;
    }
    let left = 1.0 - into as f32 / critic.authors_fade as f32;
    Some(left.max(critic.unanswered))
}

/// Whether `mix_answered_after`'s gate is open after `successes` successful episodes: the actor
/// still reads H on unanswered rows at full weight.
pub fn reads_h_everywhere(successes: u64, critic: Option<&HumanCriticConfig>) -> bool {
    successes < u64::from(critic.map_or(0, |c| c.answered_after))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn critic(answered_after: u32, failure_window: u32, unanswered: f32) -> HumanCriticConfig {
        HumanCriticConfig {
            answered_after,
            failure_window,
            unanswered,
            ..HumanCriticConfig::default()
        }
    }

    #[test]
    fn the_failure_window_reads_h_at_the_share_of_recent_failures() {
        let c = critic(0, 4, 0.0);
        let mut gate = MixGate::default();
        // Episodes not yet run count as failed: a new run follows H everywhere.
        assert_eq!(gate.unanswered_weight(0, 0, Some(&c)), Some(1.0));
        for (success, weight) in [
            (true, 0.75),
            (true, 0.5),
            (false, 0.5),
            (true, 0.25),
            (true, 0.25), // the first success leaves the window
            (true, 0.25),
            (true, 0.0),
            (false, 0.25),
        ] {
            gate.record(success, Some(&c));
            assert_eq!(gate.unanswered_weight(0, 0, Some(&c)), Some(weight));
        }
        // At least the configured share.
        assert_eq!(
            gate.unanswered_weight(0, 0, Some(&critic(0, 4, 0.5))),
            Some(0.5)
        );
    }

    #[test]
    fn the_success_gate_opens_full_until_its_count_and_off_is_off() {
        let gate = MixGate::default();
        let c = critic(3, 0, 0.0);
        assert_eq!(gate.unanswered_weight(0, 2, Some(&c)), Some(1.0));
        assert_eq!(gate.unanswered_weight(0, 3, Some(&c)), None);
        assert_eq!(gate.unanswered_weight(0, 0, Some(&critic(0, 0, 0.2))), None);
        assert_eq!(gate.unanswered_weight(0, 0, None), None);
        let mut off = MixGate::default();
        off.record(true, Some(&critic(0, 0, 0.0)));
        assert_eq!(off, MixGate::default(), "nothing kept while off");
    }

    /// A gate that has recorded `outcomes` under `c`.
    fn after(outcomes: &[bool], c: &HumanCriticConfig) -> MixGate {
        let mut gate = MixGate::default();
        for &success in outcomes {
            gate.record(success, Some(c));
        }
        gate
    }

    #[test]
    fn the_step_gate_reads_h_everywhere_until_its_step_then_yields_to_the_rest() {
        let gate = MixGate::default();
        let until = |n: u64, unanswered: f32, failure_window: u32| HumanCriticConfig {
            authors_until: n,
            ..critic(0, failure_window, unanswered)
        };
        let c = until(30_000, 0.0, 0);
        assert_eq!(gate.unanswered_weight(0, 0, Some(&c)), Some(1.0));
        assert_eq!(gate.unanswered_weight(29_999, 5, Some(&c)), Some(1.0));
        // From its step on: the configured share, as if the gate were not there.
        assert_eq!(gate.unanswered_weight(30_000, 0, Some(&c)), None);
        // ... or what another gate says (a new run's window counts every episode as failed).
        let with_window = until(30_000, 0.0, 4);
        let window = after(&[true; 3], &with_window);
        assert_eq!(
            window.unanswered_weight(10, 3, Some(&with_window)),
            Some(1.0)
        );
        assert_eq!(
            window.unanswered_weight(30_000, 3, Some(&with_window)),
            Some(0.25)
        );
    }

    #[test]
    fn the_fade_takes_the_weight_down_in_a_straight_line_then_leaves_it() {
        let gate = MixGate::default();
        let fade = |unanswered: f32, failure_window: u32| HumanCriticConfig {
            authors_until: 1_000,
            authors_fade: 400,
            ..critic(0, failure_window, unanswered)
        };
        let c = fade(0.0, 0);
        for (step, weight) in [(999, Some(1.0)), (1_000, Some(1.0)), (1_100, Some(0.75))] {
            assert_eq!(gate.unanswered_weight(step, 0, Some(&c)), weight);
        }
        assert_eq!(gate.unanswered_weight(1_300, 0, Some(&c)), Some(0.25));
        assert_eq!(
            gate.unanswered_weight(1_400, 0, Some(&c)),
            None,
            "its course run"
        );
        // Never below the configured share, nor below another gate.
        assert_eq!(
            gate.unanswered_weight(1_300, 0, Some(&fade(0.5, 0))),
            Some(0.5)
        );
        let with_window = fade(0.0, 4);
        let window = after(&[true; 4], &with_window);
        assert_eq!(
            window.unanswered_weight(1_200, 0, Some(&with_window)),
            Some(0.5)
        );
        assert_eq!(
            window.unanswered_weight(1_400, 0, Some(&with_window)),
            Some(0.0)
        );
        // From the run's first step when the authors' mix is not kept at all.
        let from_start = HumanCriticConfig {
            authors_until: 0,
            ..c
        };
        assert_eq!(gate.unanswered_weight(200, 0, Some(&from_start)), Some(0.5));
    }
}
