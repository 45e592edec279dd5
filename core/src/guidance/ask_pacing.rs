//! How a query rule paces itself as a person feels it (docs/dref.md): stretches of consecutive
//! queries ("floods") and silences while the learner keeps failing ("frozen"). Measured by every
//! evaluative run, written to `metrics.csv` and `summary.json`, shown per session and per grid.

use serde::{Deserialize, Serialize};

/// What a person sees of a rule's pacing: the longest stretches of consecutive asked steps
/// ("floods") and when it last asked (a long silence while the learner fails is a "freeze").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AskPacing {
    /// The step of the last query, if any.
    pub last_query: Option<u64>,
    /// Consecutive asked steps up to now.
    pub flood: u64,
    /// The longest stretch of consecutive asked steps.
    pub longest_flood: u64,
    /// The longest stretch among the steps from [`AskPacing::SETTLED_AFTER`] on (a new
    /// learner's first steps are all new states, so some flooding there is expected).
    pub longest_flood_settled: u64,
}

impl AskPacing {
    /// Steps after which a flood counts against the rule (the "after its first 2k").
    pub const SETTLED_AFTER: u64 = 2_000;

    /// Step `step` (0-based) asked or not.
    pub fn step(&mut self, step: u64, asked: bool) {
        if !asked {
            self.flood = 0;
            return;
        }
        self.last_query = Some(step);
        self.flood += 1;
        self.longest_flood = self.longest_flood.max(self.flood);
        if step >= Self::SETTLED_AFTER {
            let settled = self.flood.min(step + 1 - Self::SETTLED_AFTER);
            self.longest_flood_settled = self.longest_flood_settled.max(settled);
        }
    }

    /// Steps since the last query after `steps` steps.
    pub fn steps_since_query(&self, steps: u64) -> u64 {
        self.last_query.map_or(steps, |s| steps - 1 - s)
    }
}

/// Steps without a query after which a rule whose learner keeps failing counts as frozen.
pub const FROZEN_AFTER_STEPS: u64 = 10_000;
/// Episodes that must all have failed for a silent rule to count as frozen.
pub const FROZEN_FAILED_EPISODES: usize = 10;

/// Whether the rule counts as frozen at an episode's end: silent for [`FROZEN_AFTER_STEPS`]
/// while the last [`FROZEN_FAILED_EPISODES`] episodes (`recent_successes`, that episode last)
/// all failed.
pub fn is_frozen(
    steps_since_query: u64,
    recent_successes: impl ExactSizeIterator<Item = bool>,
) -> bool {
    steps_since_query >= FROZEN_AFTER_STEPS
        && recent_successes.len() >= FROZEN_FAILED_EPISODES
        && recent_successes
            .take(FROZEN_FAILED_EPISODES)
            .all(|success| !success)
}

/// The share of episodes after which the rule was frozen ([`is_frozen`]), over the episodes in
/// order, each as (steps since the last query at its end, whether it succeeded).
pub fn frozen_share(episodes: &[(u64, bool)]) -> f64 {
    if episodes.is_empty() {
        return 0.0;
    }
    let frozen = (FROZEN_FAILED_EPISODES - 1..episodes.len())
        .filter(|&i| {
            let last = &episodes[i + 1 - FROZEN_FAILED_EPISODES..=i];
            is_frozen(episodes[i].0, last.iter().map(|&(_, success)| success))
        })
        .count();
    frozen as f64 / episodes.len() as f64
}
