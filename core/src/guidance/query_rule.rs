//! DREF's query rule: a UCB1 score per abstract state g over the human critic's feedback
//! prediction error, and a rank test that decides whether to ask at this step.
//!
//! Two forms (algorithms.md section 2, step 4):
//! - `authors` (default; it produced the published curves):
//!   `UCB(g) = mean_err(g) + c * sqrt(2 * N / (N(g) + 1))` with mean_err the running mean of
//!   `|H - H_hat|` in g.
//! - `paper` (Eq. 1 and 2): `UCB(g) = FPE(g) + c * sqrt(2 ln N / N(g))` with FPE the running mean
//!   of `(H - H_hat)^2` in g; an abstract state without feedback scores +inf.
//!
//! The authors rank the current state among the abstract states that have received feedback
//! and ask iff at most k of them score strictly higher. The product's DREF (`docs/dref.md`)
//! keeps the score and changes whom it competes with and how often it may win: it ranks among
//! the states visited in the last W steps ([`RecentVisits`]) and asks within a ceiling
//! ([`AskBudget`]); both are off in the authors' rule. A third change keeps the authors' ranking
//! and only wakes it: after W steps without a query, the current state is ranked among the
//! states visited during that silence ([`SilenceWake`]), so the rule cannot stay silent while
//! the learner is somewhere else than where its best-ranked states are.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::ask_budget::AskBudget;
use super::recent_visits::RecentVisits;
use crate::scene_graph::AbstractState;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum UcbForm {
    /// `mean |H - H_hat| + c sqrt(2 N / (N(g) + 1))`, as in the authors' code.
    #[default]
    Authors,
    /// `mean (H - H_hat)^2 + c sqrt(2 ln N / N(g))`, the paper's Eq. 1-2.
    Paper,
}

/// Feedback statistics of one abstract state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StateStats {
    /// N(g): feedback received in this abstract state.
    pub count: u64,
    /// Running mean of the prediction error (absolute or squared, by form).
    pub mean_error: f64,
}

/// The UCB query rule with its running statistics (serialisable, so a checkpoint keeps it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QueryRule {
    pub c: f64,
    pub k: usize,
    pub form: UcbForm,
    /// N: all feedback so far.
    total: u64,
    /// Per abstract state; a `BTreeMap` so that checkpoints serialise in a stable order.
    stats: BTreeMap<AbstractState, StateStats>,
    /// Rank among the states visited recently instead of among those with feedback (`None`:
    /// the authors'; checkpoints written before it existed read as `None`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    recent: Option<RecentVisits>,
    /// A ceiling on the rate of queries (`None`: the authors', no ceiling).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    budget: Option<AskBudget>,
    /// Rank among the states of a long silence once it has lasted (`None`: never, the authors').
    /// Boxed: most rules have none, and the schedule that holds a rule stays small.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    wake: Option<Box<SilenceWake>>,
}

/// The steps since the rule last asked, and the states visited in the last `after` of them:
/// once `after` steps have passed without a query, the rule ranks among those states instead
/// of among every state with feedback, until it asks again. The authors' ranking freezes
/// because the states that outrank the learner's current ones are states it no longer visits;
/// ranked among the silence's own states, one of the best k + 1 of them asks at its next visit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SilenceWake {
    after: u64,
    silent: u64,
    during: RecentVisits,
}

impl SilenceWake {
    fn new(after: u64) -> Self {
        let after = after.max(1);
        Self {
            after,
            silent: 0,
            during: RecentVisits::new(usize::try_from(after).unwrap_or(usize::MAX)),
        }
    }

    fn awake(&self) -> bool {
        self.silent >= self.after
    }
}

impl QueryRule {
    /// The authors' rule: ranked among the states with feedback, no ceiling.
    pub fn new(c: f64, k: usize, form: UcbForm) -> Self {
        Self {
            c,
            k,
            form,
            total: 0,
            stats: BTreeMap::new(),
            recent: None,
            budget: None,
            wake: None,
        }
    }

    /// After `steps` without a query, rank among the states visited during the silence until
    /// the next query (the authors' ranking otherwise).
    pub fn waking_after(mut self, steps: u64) -> Self {
        self.wake = Some(Box::new(SilenceWake::new(steps)));
        self
    }

    /// Steps since the rule last asked, when it wakes from silences (else `None`).
    pub fn silent_steps(&self) -> Option<u64> {
        self.wake.as_ref().map(|w| w.silent)
    }

    /// Rank among the states visited in the last `window` steps.
    pub fn ranked_among_recent(mut self, window: usize) -> Self {
        self.recent = Some(RecentVisits::new(window));
        self
    }

    /// Ask on at most `rate` of the steps, at most about `burst` in a row; with `floor`, at a
    /// rate between it and `rate` by the share of recent "bad" answers.
    pub fn with_ceiling(mut self, rate: f64, burst: u32, floor: Option<f64>) -> Self {
        let budget = AskBudget::new(rate, burst);
        self.budget = Some(match floor {
            Some(floor) => budget.following_answers(floor),
            None => budget,
        });
        self
    }

    /// With a ceiling: ask as without it for the first `steps` steps, borrowing against the
    /// ceiling's later earnings ([`AskBudget::opening_for`]).
    pub fn opening_for(mut self, steps: u64) -> Self {
        self.budget = self.budget.map(|b| b.opening_for(steps));
        self
    }

    /// N, the feedback received so far.
    pub fn total_feedback(&self) -> u64 {
        self.total
    }

    /// The statistics of `g` (zero if it never received feedback).
    pub fn stats(&self, g: AbstractState) -> StateStats {
        self.stats.get(&g).copied().unwrap_or_default()
    }

    /// Abstract states that received feedback, with their statistics.
    pub fn seen(&self) -> impl Iterator<Item = (AbstractState, StateStats)> + '_ {
        self.stats.iter().map(|(g, s)| (*g, *s))
    }

    /// UCB(g) under the configured form.
    pub fn score(&self, g: AbstractState) -> f64 {
        let s = self.stats(g);
        let n = self.total as f64;
        match self.form {
            UcbForm::Authors => s.mean_error + self.c * (2.0 * n / (s.count as f64 + 1.0)).sqrt(),
            UcbForm::Paper if s.count == 0 => f64::INFINITY,
            // N >= N(g) >= 1 here, so ln N >= 0.
            UcbForm::Paper => s.mean_error + self.c * (2.0 * n.ln() / s.count as f64).sqrt(),
        }
    }

    /// Whether to ask for feedback in abstract state `g`: iff at most `k` of the ranked states
    /// (those with feedback, or those visited recently) score strictly higher than `g`, and,
    /// with a ceiling, the budget has a query for a state of that rank.
    pub fn should_query(&self, g: AbstractState) -> bool {
        let k = match &self.budget {
            None => self.k,
            Some(budget) if budget.can_ask() => budget.ranks_allowed(self.k),
            Some(_) => return false,
        };
        let own = self.score(g);
        let higher_than = |other: &AbstractState| self.score(*other) > own;
        match (&self.recent, &self.wake) {
            (Some(recent), _) => count_at_most(recent.states().filter(higher_than), k),
            (None, Some(wake)) if wake.awake() => {
                count_at_most(wake.during.states().filter(higher_than), k)
            }
            (None, _) => count_at_most(self.stats.keys().filter(|o| higher_than(o)), k),
        }
    }

    /// One environment step reached `g`: remember the visit, earn the step's share of a query,
    /// and say whether to ask. The authors' rule has no memory of visits, so this is
    /// [`QueryRule::should_query`] for it.
    pub fn visit(&mut self, g: AbstractState) -> bool {
        if let Some(recent) = &mut self.recent {
            recent.push(g);
        }
        if let Some(budget) = &mut self.budget {
            budget.tick();
        }
        if let Some(wake) = &mut self.wake {
            wake.during.push(g);
            wake.silent += 1;
        }
        self.should_query(g)
    }

    /// Record the trainer's answer `h` in `g`, where the human critic predicted `h_hat` before
    /// this step's update. Every answer counts, "no feedback" (0) included, and spends a query
    /// of the ceiling's budget.
    pub fn record(&mut self, g: AbstractState, h: f32, h_hat: f32) {
        if let Some(budget) = &mut self.budget {
            budget.spend(h);
        }
        if let Some(wake) = &mut self.wake {
            wake.silent = 0;
        }
        let diff = f64::from(h) - f64::from(h_hat);
        let error = match self.form {
            UcbForm::Authors => diff.abs(),
            UcbForm::Paper => diff * diff,
        };
        let s = self.stats.entry(g).or_default();
        s.count += 1;
        s.mean_error += (error - s.mean_error) / s.count as f64;
        self.total += 1;
    }
}

/// Whether `items` has at most `k` elements, looking at no more than k + 1 of them.
fn count_at_most<T>(items: impl Iterator<Item = T>, k: usize) -> bool {
    items.take(k + 1).count() <= k
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: AbstractState = AbstractState(0b01);
    const B: AbstractState = AbstractState(0b10);
    const C: AbstractState = AbstractState(0b11);

    #[test]
    fn the_first_step_always_asks() {
        for form in [UcbForm::Authors, UcbForm::Paper] {
            assert!(QueryRule::new(0.1, 0, form).should_query(A));
        }
    }

    #[test]
    fn running_mean_of_absolute_error_per_state() {
        let mut rule = QueryRule::new(0.1, 2, UcbForm::Authors);
        rule.record(A, 1.0, 0.5);
        rule.record(A, -1.0, 0.0);
        rule.record(B, 0.0, 0.25);
        assert_eq!(rule.total_feedback(), 3);
        assert_eq!(
            rule.stats(A),
            StateStats {
                count: 2,
                mean_error: 0.75
            }
        );
        assert_eq!(
            rule.stats(B),
            StateStats {
                count: 1,
                mean_error: 0.25
            }
        );
    }

    #[test]
    fn authors_score_matches_the_formula() {
        let mut rule = QueryRule::new(0.2, 4, UcbForm::Authors);
        rule.record(A, 1.0, 0.5);
        rule.record(A, 1.0, 0.7);
        rule.record(B, -1.0, 0.0);
        // N = 3; A: N(g) = 2, mean 0.4; B: N(g) = 1, mean 1.0; C unseen.
        let close = |x: f64, y: f64| (x - y).abs() < 1e-6;
        assert!(close(rule.score(A), 0.4 + 0.2 * (6.0f64 / 3.0).sqrt()));
        assert!(close(rule.score(B), 1.0 + 0.2 * (6.0f64 / 2.0).sqrt()));
        assert!(close(rule.score(C), 0.2 * 6.0f64.sqrt()));
    }

    #[test]
    fn paper_score_uses_squared_error_and_log_count() {
        let mut rule = QueryRule::new(0.2, 4, UcbForm::Paper);
        rule.record(A, 1.0, 0.5);
        rule.record(B, -1.0, 0.0);
        rule.record(B, 1.0, 0.0);
        let close = |x: f64, y: f64| (x - y).abs() < 1e-6;
        assert!(close(
            rule.score(A),
            0.25 + 0.2 * (2.0 * 3.0f64.ln() / 1.0).sqrt()
        ));
        assert!(close(
            rule.score(B),
            1.0 + 0.2 * (2.0 * 3.0f64.ln() / 2.0).sqrt()
        ));
        assert_eq!(rule.score(C), f64::INFINITY);
        assert!(rule.should_query(C));
    }

    #[test]
    fn asks_only_when_at_most_k_seen_states_score_higher() {
        // Three seen states with clearly ordered errors, tiny exploration bonus.
        let mut rule = QueryRule::new(1e-6, 0, UcbForm::Authors);
        let low = AbstractState(4);
        rule.record(A, 1.0, 0.0); // error 1.0
        rule.record(B, 1.0, 0.5); // error 0.5
        rule.record(low, 1.0, 0.9); // error 0.1
        assert!(rule.should_query(A), "top state is asked with k = 0");
        assert!(!rule.should_query(B), "one state scores higher, k = 0");
        rule.k = 1;
        assert!(rule.should_query(B));
        assert!(!rule.should_query(low), "two states score higher, k = 1");
        rule.k = 2;
        assert!(rule.should_query(low));
    }

    #[test]
    fn an_unseen_state_gets_the_largest_bonus() {
        let mut rule = QueryRule::new(0.1, 0, UcbForm::Authors);
        for _ in 0..50 {
            rule.record(A, 1.0, 1.0); // perfectly predicted: error 0
        }
        assert!(rule.score(C) > rule.score(A));
        assert!(rule.should_query(C));
    }

    #[test]
    fn a_well_predicted_state_stops_being_asked() {
        let mut rule = QueryRule::new(0.1, 0, UcbForm::Authors);
        rule.record(B, 1.0, -1.0); // B is badly predicted: error 2
        for _ in 0..20 {
            rule.record(A, 1.0, 0.95);
        }
        assert!(!rule.should_query(A));
        assert!(rule.should_query(B));
    }

    #[test]
    fn survives_a_serde_round_trip() {
        let mut rule = QueryRule::new(0.2, 60, UcbForm::Paper);
        rule.record(A, 1.0, 0.0);
        let back: QueryRule = serde_json::from_str(&serde_json::to_string(&rule).unwrap()).unwrap();
        assert_eq!(back, rule);
    }

    #[test]
    fn with_at_most_k_plus_one_states_seen_every_state_is_asked() {
        // Only other seen states can outrank g, so with k + 1 of them or fewer seen the rank
        // test always passes: DREF asks at every step until a (k + 2)-th state has feedback.
        let (a, b, c, d) = (
            AbstractState(1),
            AbstractState(2),
            AbstractState(3),
            AbstractState(4),
        );
        let mut rule = QueryRule::new(0.1, 2, UcbForm::Authors);
        for _ in 0..500 {
            rule.record(a, 1.0, 1.0);
        }
        rule.record(b, 1.0, -1.0);
        rule.record(c, 1.0, -1.0);
        // `a` has by far the lowest score of the three, and is still asked.
        assert!(rule.score(a) < rule.score(b) && rule.score(a) < rule.score(c));
        assert!(rule.should_query(a));
        // A fourth state with feedback puts three above `a`: it is no longer asked.
        rule.record(d, 1.0, -1.0);
        assert!(!rule.should_query(a));
        assert!(rule.should_query(d));
    }

    /// The freeze of the authors' rule: states ranked high by early answers are never visited
    /// again, and the one the learner now visits ranks below k of them for good.
    fn frozen_history(rule: &mut QueryRule) -> AbstractState {
        for g in 1..=5 {
            rule.record(AbstractState(g), 1.0, -1.0); // badly predicted: error 2
        }
        let now = AbstractState(9);
        for _ in 0..50 {
            rule.record(now, 1.0, 1.0); // well predicted: error 0, and many answers
        }
        now
    }

    #[test]
    fn the_authors_rule_freezes_and_the_recent_rank_does_not() {
        let mut authors = QueryRule::new(0.1, 2, UcbForm::Authors);
        let now = frozen_history(&mut authors);
        assert!(
            (0..5_000).all(|_| !authors.visit(now)),
            "the authors' rule asks again"
        );

        let mut recent = QueryRule::new(0.1, 2, UcbForm::Authors).ranked_among_recent(100);
        let now = frozen_history(&mut recent);
        // Only the states visited in the window compete: the learner's own state is the best.
        assert!(recent.visit(now));
        let asked = (0..5_000).filter(|_| recent.visit(now)).count();
        assert_eq!(
            asked, 5_000,
            "nothing else is recent, so every visit may ask"
        );
    }

    #[test]
    fn a_waking_rule_keeps_the_authors_ranking_until_a_silence_and_then_asks_once() {
        let mut rule = QueryRule::new(0.1, 2, UcbForm::Authors).waking_after(1_000);
        let now = frozen_history(&mut rule);
        let mut asked_at = Vec::new();
        for step in 1..=3_500u64 {
            if rule.visit(now) {
                rule.record(now, 1.0, 1.0);
                asked_at.push(step);
            }
        }
        // Silent as the authors' rule for 999 steps, then one query per 1,000 steps: the
        // silence's only state is its best, and the answer ends the silence.
        assert_eq!(asked_at, [1_000, 2_000, 3_000]);
        assert_eq!(rule.silent_steps(), Some(500));
    }

    #[test]
    fn a_waking_rule_asks_the_best_state_of_the_silence() {
        let (good, bad) = (AbstractState(20), AbstractState(21));
        let mut rule = QueryRule::new(0.1, 0, UcbForm::Authors).waking_after(10);
        frozen_history(&mut rule);
        rule.record(good, 1.0, 1.0);
        rule.record(good, 1.0, 1.0);
        rule.record(bad, 1.0, -1.0);
        rule.record(bad, 1.0, -1.0);
        for _ in 0..5 {
            assert!(
                !rule.visit(bad),
                "ranked among every answered state: not asked"
            );
        }
        for _ in 0..4 {
            assert!(!rule.visit(good));
        }
        // The tenth silent step: `bad` outranks `good` among the silence's states.
        assert!(
            !rule.visit(good),
            "k = 0: only the best ranked state of the silence asks"
        );
        assert!(rule.visit(bad));
    }

    #[test]
    fn the_recent_rank_still_prefers_the_worse_predicted_of_the_visited_states() {
        let (good, bad) = (AbstractState(1), AbstractState(2));
        let mut rule = QueryRule::new(0.01, 0, UcbForm::Authors).ranked_among_recent(10);
        rule.record(good, 1.0, 0.9);
        rule.record(bad, 1.0, -1.0);
        rule.visit(good);
        assert!(
            rule.visit(bad),
            "the worse predicted state is the best ranked"
        );
        assert!(
            !rule.visit(good),
            "k = 0: only the best ranked recent state asks"
        );
        // Once `bad` has left the window, `good` is the best of what the learner visits.
        for _ in 0..10 {
            rule.visit(good);
        }
        assert!(rule.visit(good));
    }

    #[test]
    fn a_ceiling_bounds_the_flood_of_the_first_states() {
        // With k + 1 or fewer states answered the authors' rule asks at every step.
        let (a, b) = (AbstractState(1), AbstractState(2));
        let mut authors = QueryRule::new(0.1, 2, UcbForm::Authors);
        let mut capped = QueryRule::new(0.1, 2, UcbForm::Authors)
            .ranked_among_recent(1_000)
            .with_ceiling(0.05, 20, None);
        let run = |rule: &mut QueryRule| {
            let (mut asked, mut streak, mut longest) = (0u32, 0u32, 0u32);
            for step in 0..20_000u32 {
                let g = if step % 7 < 4 { a } else { b };
                if rule.visit(g) {
                    rule.record(g, 1.0, 0.5);
                    asked += 1;
                    streak += 1;
                    longest = longest.max(streak);
                } else {
                    streak = 0;
                }
            }
            (asked, longest)
        };
        assert_eq!(run(&mut authors), (20_000, 20_000));
        let (asked, longest) = run(&mut capped);
        assert!(asked <= 1_020, "asked {asked} of 20000 under a 5 % ceiling");
        assert!(longest <= 21, "{longest} in a row");
    }

    #[test]
    fn a_rule_with_window_and_ceiling_survives_a_serde_round_trip() {
        let mut rule = QueryRule::new(0.2, 4, UcbForm::Authors)
            .ranked_among_recent(50)
            .with_ceiling(0.05, 20, None)
            .waking_after(7);
        for g in 0..30 {
            if rule.visit(AbstractState(g % 7)) {
                rule.record(AbstractState(g % 7), 1.0, 0.0);
            }
        }
        let back: QueryRule = serde_json::from_str(&serde_json::to_string(&rule).unwrap()).unwrap();
        assert_eq!(back, rule);
        // A checkpoint of the authors' rule written before these fields existed still reads.
        let old = r#"{"c":0.2,"k":4,"form":"authors","total":0,"stats":{}}"#;
        let old: QueryRule = serde_json::from_str(old).unwrap();
        assert_eq!(old, QueryRule::new(0.2, 4, UcbForm::Authors));
    }
}
