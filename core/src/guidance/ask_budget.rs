//! A ceiling on how often DREF asks: a token bucket that earns `rate` of a query every step and
//! holds at most `burst` (`docs/dref.md`). The authors' rule asks on every step while k + 1 or
//! fewer states have had feedback (Reaching asked on all of 100k steps on two seeds of five);
//! with the bucket it asks at most `rate` of the steps in the long run and never more than about
//! `burst / (1 - rate)` in a row. How full the bucket is also narrows whom it asks: with a full
//! bucket the k + 1 best-ranked states may ask, with the last token only the best one, so a
//! scarce budget goes to the states the UCB ranks highest.
//!
//! Optionally (`feedback_opening = W`, off by default) the ceiling holds over the run rather
//! than over every stretch of it: for the first W steps the rule asks as it would without a
//! ceiling, borrowing against the steps after, and the queries it borrowed beyond what the
//! bucket held are paid back from its later earnings before it asks again. The authors' rule
//! floods while k + 1 or fewer states have answers, and on Placing those first answers are what
//! lead the learner (the masked authors' rule asked 867-995 of its first 1,000 steps and learnt
//! 4 seeds of 5; under the plain ceiling, about 120); the debt keeps the run's total at most
//! `rate` of its steps plus `burst` once it is repaid.
//!
//! Two refinements of the opening's accounting, both off by default: a bucket that starts empty
//! (`starting_empty`) borrows the burst too, so once repaid a run has asked at most `rate` of its
//! steps, not `rate` of them plus `burst`; and a repayment from a share of the earnings
//! (`repaying`) leaves the rest askable while the debt is paid, so the rule is not silent for
//! the whole repayment (on Placing 12k-18k steps, in which a failing learner went unasked: the
//! frozen episodes of docs/results/fig3/).
//!
//! An opening may also be paced (`opening_rate`, off by default): for its W steps the rule asks
//! at most that share of them, from a bucket of its own (empty at the start, `burst` at most),
//! and is ranked as a woken rule is, among the states of the last steps ([`QueryRule`]), so the
//! opening spends its share whatever the authors' ranking would have asked. What it asks beyond
//! the ceiling's earnings is a debt like any opening's, repaid the same way, so the run's total
//! is unchanged. It is there to spend the run's budget early: on Lunar Lander the learners that
//! take off early are those with thousands of answers in their first 15k steps
//! (`benches/grids/early_answers.py`), while the authors' ranking asks about a thousand there.
//!
//! [`QueryRule`]: super::query_rule::QueryRule
//!
//! Optionally (`min_feedback_rate`, off by default) the rate follows the answers themselves:
//! from the floor when the trainer's recent answers were all "good" to the ceiling when they were
//! all "bad", so a person is asked more while the robot keeps doing wrong and less once it does
//! right. The answers are one of DREF's own inputs, so the rule stays DREF.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

/// Answers behind an answer-driven rate.
pub const RATE_ANSWERS: usize = 50;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AskBudget {
    /// The ceiling on the rate.
    rate: f64,
    burst: f64,
    tokens: f64,
    /// The floor of an answer-driven rate (`None`: the rate is the ceiling, fixed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    floor: Option<f64>,
    /// Whether each of the last [`RATE_ANSWERS`] answers was "bad" (H < 0), oldest first.
    #[serde(default, skip_serializing_if = "VecDeque::is_empty")]
    recent_bad: VecDeque<bool>,
    /// Steps of the opening not yet begun: during the opening the rule may ask whatever the
    /// bucket holds (`tokens` goes below 0, a debt repaid by later earnings).
    #[serde(default, skip_serializing_if = "is_zero")]
    opening_left: u64,
    /// Whether the step now running is one of the opening's.
    #[serde(default, skip_serializing_if = "is_false")]
    in_opening: bool,
    /// The share of each step's earnings that repays a debt (`tokens` below 0) after the
    /// opening; 1: all of it, and nothing is asked until the debt is repaid.
    #[serde(default = "whole", skip_serializing_if = "is_whole")]
    repay_share: f64,
    /// What the rest of the earnings hold while a debt is repaid: queries the rule may ask
    /// then (only for its best-ranked state, as with a last token).
    #[serde(default, skip_serializing_if = "is_nothing")]
    spare: f64,
    /// A paced opening's own bucket, a plain one at the opening's rate (`None`: the opening
    /// asks on every step the ranking asks, as the authors' rule does).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    opening_bucket: Option<Box<AskBudget>>,
}

pub(super) fn is_zero(n: &u64) -> bool {
    *n == 0
}

pub(super) fn whole() -> f64 {
    1.0
}

pub(super) fn is_whole(x: &f64) -> bool {
    *x == 1.0
}

fn is_nothing(x: &f64) -> bool {
    *x == 0.0
}

pub(super) fn is_false(b: &bool) -> bool {
    !*b
}

impl AskBudget {
    /// A full bucket: `rate` in (0, 1], `burst` at least 1.
    pub fn new(rate: f64, burst: u32) -> Self {
        let burst = f64::from(burst.max(1));
        Self {
            rate,
            burst,
            tokens: burst,
            floor: None,
            recent_bad: VecDeque::new(),
            opening_left: 0,
            in_opening: false,
            repay_share: 1.0,
            spare: 0.0,
            opening_bucket: None,
        }
    }

    /// The same bucket, empty at the start: a run's total stays within `rate` of its steps
    /// once any opening is repaid (a full one allows `burst` more).
    pub fn starting_empty(mut self) -> Self {
        self.tokens = 0.0;
        self
    }

    /// The same bucket, repaying a debt from `share` (in (0, 1]) of each step's earnings; the
    /// rest may be asked while it repays.
    pub fn repaying(mut self, share: f64) -> Self {
        self.repay_share = share;
        self
    }

    /// The same bucket, open for its first `steps` steps: the rule asks as it would without a
    /// ceiling and repays what it borrowed afterwards.
    pub fn opening_for(mut self, steps: u64) -> Self {
        self.opening_left = steps;
        self
    }

    /// The same bucket, its opening paced: at most `rate` (in (0, 1]) of the opening's steps
    /// asked, from a bucket of the opening's own that starts empty.
    pub fn opening_at(mut self, rate: f64) -> Self {
        let burst = self.burst as u32;
        self.opening_bucket = Some(Box::new(AskBudget::new(rate, burst).starting_empty()));
        self
    }

    /// Whether the step now running is one of a paced opening's: the rule then ranks as a
    /// woken rule does, so that it spends the opening's share.
    pub fn in_paced_opening(&self) -> bool {
        self.in_opening && self.opening_bucket.is_some()
    }

    /// The share of its steps a paced opening may ask, while the step now running is one of
    /// its steps (`None` otherwise).
    pub fn opening_rate_now(&self) -> Option<f64> {
        match (self.in_opening, &self.opening_bucket) {
            (true, Some(bucket)) => Some(bucket.rate),
            _ => None,
        }
    }

    /// The same bucket with a rate between `floor` and its ceiling, by the share of "bad"
    /// answers among the last [`RATE_ANSWERS`] (the ceiling before any answer).
    pub fn following_answers(mut self, floor: f64) -> Self {
        self.floor = Some(floor.min(self.rate));
        self
    }

    /// The share of steps the bucket earns a query for now.
    pub fn current_rate(&self) -> f64 {
        match self.floor {
            None => self.rate,
            Some(_) if self.recent_bad.is_empty() => self.rate,
            Some(floor) => {
                let bad = self.recent_bad.iter().filter(|b| **b).count() as f64;
                floor + (self.rate - floor) * bad / self.recent_bad.len() as f64
            }
        }
    }

    /// One environment step passes: the bucket earns the current rate's share of a query.
    pub fn tick(&mut self) {
        self.in_opening = self.opening_left > 0;
        self.opening_left = self.opening_left.saturating_sub(1);
        let earned = self.current_rate();
        if self.tokens < 0.0 && !self.in_opening && self.repay_share < 1.0 {
            let repaid = earned * self.repay_share;
            self.tokens += repaid;
            self.spare += earned - repaid;
            if self.tokens >= 0.0 {
                // Repaid: what was spare is the bucket's again.
                self.tokens = (self.tokens + self.spare).min(self.burst);
                self.spare = 0.0;
            }
        } else {
            self.tokens = (self.tokens + earned).min(self.burst);
        }
        if let (true, Some(bucket)) = (self.in_opening, &mut self.opening_bucket) {
            bucket.tick();
        }
    }

    /// Whether a whole query is in the bucket (always during an unpaced opening; in a paced
    /// one, in the opening's bucket), or spare while a debt is repaid.
    pub fn can_ask(&self) -> bool {
        match (self.in_opening, &self.opening_bucket) {
            (true, None) => true,
            (true, Some(bucket)) => bucket.can_ask(),
            (false, _) => self.tokens >= 1.0 || self.spare >= 1.0,
        }
    }

    /// How many of the `k` states ranked above the best may still ask: all of them with a full
    /// bucket or during an unpaced opening, none (only the best-ranked state) with less than
    /// two queries' worth (in a paced opening, of the opening's bucket).
    pub fn ranks_allowed(&self, k: usize) -> usize {
        match (self.in_opening, &self.opening_bucket) {
            (true, None) => return k,
            (true, Some(bucket)) => return bucket.ranks_allowed(k),
            (false, _) => {}
        }
        let fill = ((self.tokens - 1.0) / (self.burst - 1.0).max(1.0)).clamp(0.0, 1.0);
        (k as f64 * fill).floor() as usize
    }

    /// A query was asked and answered `h`.
    pub fn spend(&mut self, h: f32) {
        if !self.in_opening && self.tokens < 1.0 && self.spare >= 1.0 {
            self.spare -= 1.0;
        } else {
            self.tokens -= 1.0;
        }
        if let (true, Some(bucket)) = (self.in_opening, &mut self.opening_bucket) {
            bucket.spend(h);
        }
        if self.floor.is_some() {
            self.recent_bad.push_back(h < 0.0);
            if self.recent_bad.len() > RATE_ANSWERS {
                self.recent_bad.pop_front();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::ask_pacing::AskPacing;
    use super::*;

    /// Asks on every step it may for `steps` steps, ticking first as the rule does; the count.
    fn ask_whenever_allowed(budget: &mut AskBudget, steps: u64) -> u64 {
        let mut asked = 0;
        for _ in 0..steps {
            budget.tick();
            if budget.can_ask() {
                budget.spend(1.0);
                asked += 1;
            }
        }
        asked
    }

    /// As [`ask_whenever_allowed`], with the longest stretch of consecutive asked steps.
    fn ask_whenever_allowed_streaks(budget: &mut AskBudget, steps: u64) -> (u64, u64) {
        let (mut asked, mut pacing) = (0, AskPacing::default());
        for step in 0..steps {
            let ask = ask_whenever_allowed(budget, 1) == 1;
            pacing.step(step, ask);
            asked += u64::from(ask);
        }
        (asked, pacing.longest_flood)
    }

    #[test]
    fn an_opening_asks_on_every_step_then_repays_before_asking_again() {
        let mut budget = AskBudget::new(0.1, 20).opening_for(2_000);
        budget.tick();
        assert_eq!(
            budget.ranks_allowed(4),
            4,
            "the opening lets every rank ask"
        );
        budget.spend(1.0);
        assert_eq!(1 + ask_whenever_allowed(&mut budget, 1_999), 2_000);
        // 20 held and 0.1 a step earned over the 1,999 steps after the first: 1,780.1
        // borrowed, and nothing more asked until earnings repay them (17,811 steps).
        assert!((budget.tokens + 1_780.1).abs() < 1e-6, "{}", budget.tokens);
        budget.tick();
        assert!(!budget.can_ask(), "the step after the opening");
        assert_eq!(budget.ranks_allowed(4), 0);
        assert_eq!(ask_whenever_allowed(&mut budget, 17_799), 0);
        // Over the whole run the ceiling holds: at most 10 % of the steps plus the burst.
        let total = 2_000 + ask_whenever_allowed(&mut budget, 100_000 - 2_000 - 17_800);
        assert!(total <= 10_000 + 20, "{total}");
        assert!(total >= 9_990, "{total}");
    }

    #[test]
    fn an_empty_start_keeps_a_greedy_run_within_its_rate_at_every_step_after_repaying() {
        for (start_empty, limit) in [(false, 10_020), (true, 10_000)] {
            let mut budget = AskBudget::new(0.1, 20).opening_for(2_000);
            if start_empty {
                budget = budget.starting_empty();
            }
            let mut asked = ask_whenever_allowed(&mut budget, 2_000);
            assert_eq!(asked, 2_000);
            let mut worst = 0.0f64;
            for step in 2_001..=100_000u64 {
                asked += ask_whenever_allowed(&mut budget, 1);
                if step > 20_100 {
                    worst = worst.max(asked as f64 - 0.1 * step as f64);
                }
            }
            assert!(asked <= limit, "start empty {start_empty}: {asked}");
            assert!(asked >= limit - 10, "start empty {start_empty}: {asked}");
            // A full bucket runs up to its burst over 10 % of the steps so far; an empty one
            // never passes 10 % once the opening is repaid.
            let most = if start_empty { 0.0 } else { 20.0 };
            assert!(worst <= most + 1e-9, "start empty {start_empty}: {worst}");
            assert!(worst > most - 1.5, "start empty {start_empty}: {worst}");
        }
    }

    #[test]
    fn repaying_from_a_share_asks_the_rest_while_it_repays_and_keeps_the_total() {
        let mut budget = AskBudget::new(0.1, 20)
            .opening_for(2_000)
            .starting_empty()
            .repaying(0.9);
        assert_eq!(ask_whenever_allowed(&mut budget, 2_000), 2_000);
        // 1,800 borrowed (2,000 asked, 200 earned), repaid at 0.09 a step: 20,000 steps, in
        // which the other 0.01 a step is askable: one query every 100 steps, for the best state.
        let (mut asked, mut silent, mut longest_silence) = (0u64, 0u64, 0u64);
        for _ in 0..19_990 {
            budget.tick();
            assert!(budget.tokens < 0.0, "still repaying");
            if budget.can_ask() {
                assert_eq!(budget.ranks_allowed(4), 0, "only the best-ranked state");
                budget.spend(-1.0);
                asked += 1;
                silent = 0;
            } else {
                silent += 1;
                longest_silence = longest_silence.max(silent);
            }
        }
        assert!((198..=200).contains(&asked), "{asked}");
        assert!(longest_silence <= 101, "{longest_silence}");
        // Once repaid, the plain ceiling; over the run at most 10 % of the steps.
        let total = 2_000 + asked + ask_whenever_allowed(&mut budget, 100_000 - 2_000 - 19_990);
        assert!((9_990..=10_000).contains(&total), "{total}");
        assert!(budget.tokens >= 0.0 && budget.spare == 0.0);
    }

    #[test]
    fn repaying_in_full_is_the_opening_as_before_bit_for_bit() {
        let mut before = AskBudget::new(0.1, 20).opening_for(2_000);
        let mut whole = AskBudget::new(0.1, 20).opening_for(2_000).repaying(1.0);
        for step in 0..30_000u32 {
            before.tick();
            whole.tick();
            assert_eq!(before.can_ask(), whole.can_ask());
            if before.can_ask() && step % 2 == 0 {
                before.spend(1.0);
                whole.spend(1.0);
            }
            assert_eq!(before.tokens.to_bits(), whole.tokens.to_bits());
        }
        assert_eq!(before, whole);
    }

    #[test]
    fn a_paced_opening_asks_its_share_then_repays_within_the_runs_ceiling() {
        let mut budget = AskBudget::new(0.1, 20)
            .opening_for(15_000)
            .starting_empty()
            .repaying(0.9)
            .opening_at(1.0 / 3.0);
        let (asked, longest) = ask_whenever_allowed_streaks(&mut budget, 15_000);
        assert!(budget.in_paced_opening(), "its last step");
        // A third of the steps from a bucket that starts empty: no flood at all.
        assert!((4_990..=5_000).contains(&asked), "{asked}");
        assert_eq!(longest, 1, "one query, then two steps earning the next");
        // 5,000 asked against 1,500 earned: 3,500 repaid at 0.09 a step (38,889 steps), after
        // which the run is within 10 % of its steps.
        assert!((budget.tokens + 3_500.0).abs() < 5.0, "{}", budget.tokens);
        let after = ask_whenever_allowed(&mut budget, 150_000 - 15_000);
        assert!(!budget.in_paced_opening());
        assert!(
            (14_990..=15_000).contains(&(asked + after)),
            "{}",
            asked + after
        );
    }

    #[test]
    fn a_paced_opening_admits_more_ranks_as_its_bucket_fills() {
        let mut budget = AskBudget::new(0.1, 21).opening_for(1_000).opening_at(0.5);
        budget.tick();
        assert!(!budget.can_ask(), "its own bucket starts empty");
        budget.tick();
        assert!(budget.can_ask());
        assert_eq!(
            budget.ranks_allowed(60),
            0,
            "one query: the best state only"
        );
        for _ in 0..40 {
            budget.tick();
        }
        assert_eq!(budget.ranks_allowed(60), 60, "full: every rank");
        // Ticks outside the opening leave the opening's bucket alone.
        let mut done = AskBudget::new(0.1, 20).opening_for(1).opening_at(0.5);
        done.tick();
        done.tick();
        assert!(!done.in_paced_opening());
        assert_eq!(done.opening_bucket.map(|b| b.tokens), Some(0.5));
    }

    #[test]
    fn no_opening_is_the_plain_bucket_bit_for_bit() {
        let mut plain = AskBudget::new(0.1, 20);
        let mut opened = AskBudget::new(0.1, 20).opening_for(0);
        for step in 0..5_000u32 {
            plain.tick();
            opened.tick();
            assert_eq!(plain.can_ask(), opened.can_ask());
            if plain.can_ask() && step % 3 == 0 {
                plain.spend(1.0);
                opened.spend(1.0);
            }
            assert_eq!(plain.tokens.to_bits(), opened.tokens.to_bits());
        }
        assert_eq!(plain, opened);
    }

    #[test]
    fn asks_at_most_its_rate_and_its_burst_in_a_row() {
        let mut budget = AskBudget::new(0.05, 20);
        let (asked, longest) = ask_whenever_allowed_streaks(&mut budget, 100_000);
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
            budget.spend(-1.0);
        }
        assert!(budget.can_ask());
        assert_eq!(
            budget.ranks_allowed(4),
            0,
            "the last token goes to the best state"
        );
        budget.spend(-1.0);
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

    #[test]
    fn an_answer_driven_rate_runs_from_the_floor_to_the_ceiling() {
        let mut budget = AskBudget::new(0.1, 20).following_answers(0.02);
        assert_eq!(budget.current_rate(), 0.1, "the ceiling before any answer");
        for _ in 0..RATE_ANSWERS {
            budget.spend(1.0);
        }
        assert!(
            (budget.current_rate() - 0.02).abs() < 1e-12,
            "all good: the floor"
        );
        for _ in 0..RATE_ANSWERS / 2 {
            budget.spend(-1.0);
        }
        assert!(
            (budget.current_rate() - 0.06).abs() < 1e-12,
            "half bad: half way"
        );
        for _ in 0..RATE_ANSWERS {
            budget.spend(-1.0);
        }
        assert!(
            (budget.current_rate() - 0.1).abs() < 1e-12,
            "all bad: the ceiling"
        );
        // "No feedback" (0) counts as not bad; a fixed bucket ignores answers.
        let mut fixed = AskBudget::new(0.05, 20);
        fixed.spend(-1.0);
        assert_eq!(fixed.current_rate(), 0.05);
    }
}
