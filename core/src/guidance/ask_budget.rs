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
//! A paced opening may also taper (`opening_taper`, off by default): its rate falls in a straight
//! line from `opening_rate` at its first step to nothing after its last, so the answers thin out
//! instead of stopping at once. On Lunar Lander most of what the product's DREF gives up against
//! EF-100 it gives up in the 30k steps after its flat 30k-step opening ends
//! (docs/dref-lunar-lander.md, "Where Lunar Lander's gap builds"); a taper over 60k steps spends
//! the same 13,500 answers with no step at which they stop.
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
    /// A tapered opening's `(rate at its first step, its length in steps)`: the paced opening's
    /// bucket earns a rate falling in a straight line from the first to nothing after the last
    /// (`None`: a flat rate; checkpoints written before it read so).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    taper: Option<(f64, u64)>,
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
            taper: None,
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

    /// The same bucket, its paced opening tapered: the opening's rate falls in a straight line
    /// from the rate it was paced at, on its first step, to nothing after its last, so it asks
    /// about half as many. Call after [`AskBudget::opening_for`] and [`AskBudget::opening_at`];
    /// an unpaced opening is left as it is.
    pub fn tapering(mut self) -> Self {
        if let (Some(bucket), true) = (&self.opening_bucket, self.opening_left > 0) {
            self.taper = Some((bucket.rate, self.opening_left));
        }
        self
    }

    /// Whether the step now running is one of a tapered opening's: its rate changes from step
    /// to step, so a state placed by visits is owed the rate of each visit, not today's rate
    /// times its visits.
    pub fn in_tapered_opening(&self) -> bool {
        self.taper.is_some() && self.in_paced_opening()
    }

    /// Whether the step now running is one of a paced opening's: the rule then ranks as a
    /// woken rule does, so that it spends the opening's share.
    pub fn in_paced_opening(&self) -> bool {
        self.opening_rate_now().is_some()
    }

    /// The share of its steps a paced opening may ask, while the step now running is one of
    /// its steps (`None` otherwise).
    pub fn opening_rate_now(&self) -> Option<f64> {
        let bucket = self.opening_bucket.as_ref().filter(|_| self.in_opening);
        bucket.map(|bucket| bucket.rate)
    }

    /// The share of its steps the spare may ask, while an opening's debt is repaid from part
    /// of the earnings (`None` otherwise): the earnings' share the repayment leaves.
    pub fn spare_rate_now(&self) -> Option<f64> {
        self.repaying_in_part()
            .then(|| self.current_rate() * (1.0 - self.repay_share))
    }

    /// Whether a debt is being repaid from part of the earnings now: after the opening, with a
    /// repayment share below 1 (the rest is the spare).
    fn repaying_in_part(&self) -> bool {
        self.tokens < 0.0 && !self.in_opening && self.repay_share < 1.0
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
        if let (true, Some((first, steps)), Some(bucket)) =
            (self.in_opening, self.taper, &mut self.opening_bucket)
        {
            // Step i of the opening's n (from 1) earns first * (n - i + 1) / n: `first` on its
            // first step, first / n on its last, about first * n / 2 in all.
            bucket.rate = first * (self.opening_left + 1) as f64 / steps as f64;
        }
        let earned = self.current_rate();
        if self.repaying_in_part() {
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
#[path = "ask_budget_tests.rs"]
mod tests;
