//! A ceiling on how often DREF asks: a token bucket that earns `rate` of a query every step and
//! holds at most `burst` (`docs/dref.md`). The authors' rule asks on every step while k + 1 or
//! fewer states have had feedback (Reaching asked on all of 100k steps on two seeds of five);
//! with the bucket it asks at most `rate` of the steps in the long run and never more than about
//! `burst / (1 - rate)` in a row. How full the bucket is also narrows whom it asks: with a full
//! bucket the k + 1 best-ranked states may ask, with the last token only the best one, so a
//! scarce budget goes to the states the UCB ranks highest.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AskBudget {
    rate: f64,
    burst: f64,
    tokens: f64,
}

impl AskBudget {
    /// A full bucket: `rate` in (0, 1], `burst` at least 1.
    pub fn new(rate: f64, burst: u32) -> Self {
        let burst = f64::from(burst.max(1));
        Self {
            rate,
            burst,
            tokens: burst,
        }
    }

    /// One environment step passes: the bucket earns `rate` of a query.
    pub fn tick(&mut self) {
        self.tokens = (self.tokens + self.rate).min(self.burst);
    }

    /// Whether a whole query is in the bucket.
    pub fn can_ask(&self) -> bool {
        self.tokens >= 1.0
    }

    /// How many of the `k` states ranked above the best may still ask: all of them with a full
    /// bucket, none (only the best-ranked state) with less than two queries' worth.
    pub fn ranks_allowed(&self, k: usize) -> usize {
        let spare = ((self.tokens - 1.0) / (self.burst - 1.0).max(1.0)).clamp(0.0, 1.0);
        (k as f64 * spare).floor() as usize
    }

    /// A query was asked.
    pub fn spend(&mut self) {
        self.tokens -= 1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn asks_at_most_its_rate_and_its_burst_in_a_row() {
        let mut budget = AskBudget::new(0.05, 20);
        let (mut asked, mut streak, mut longest) = (0u32, 0u32, 0u32);
        for _ in 0..100_000 {
            budget.tick();
            if budget.can_ask() {
                budget.spend();
                asked += 1;
                streak += 1;
                longest = longest.max(streak);
            } else {
                streak = 0;
            }
        }
        // A greedy asker gets the full bucket, then one query every 20 steps.
        assert!((5_000..=5_020).contains(&asked), "asked {asked}");
        assert!((20..=22).contains(&longest), "longest streak {longest}");
    }

    #[test]
    fn a_scarce_budget_admits_only_the_best_ranked_state() {
        let mut budget = AskBudget::new(0.1, 11);
        assert_eq!(
            budget.ranks_allowed(4),
            4,
            "a full bucket admits the top k + 1"
        );
        for _ in 0..10 {
            budget.spend();
        }
        assert!(budget.can_ask());
        assert_eq!(
            budget.ranks_allowed(4),
            0,
            "the last token goes to the best state"
        );
        budget.spend();
        assert!(!budget.can_ask());
        // A query's worth again after 1 / rate steps (one more for rounding of 0.1).
        for _ in 0..9 {
            budget.tick();
        }
        assert!(!budget.can_ask());
        budget.tick();
        budget.tick();
        assert!(budget.can_ask());
    }
}
