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
//! the learner is somewhere else than where its best-ranked states are. During a paced opening
//! ([`AskBudget::opening_at`]) the rule ranks as if woken from the start, among the states of
//! its last `wake_after` steps, or asks each state its share of its own visits ([`VisitShare`]);
//! the spare a repayment leaves after it may be placed by visits too.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::ask_budget::AskBudget;
use super::recent_visits::RecentVisits;
use super::visit_share::VisitShare;
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
    /// A ceiling on the rate of queries (`None`: the authors', no ceiling); boxed, as the wake.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    budget: Option<Box<AskBudget>>,
    /// Rank among the states of a long silence once it has lasted (`None`: never, the authors').
    /// Boxed: most rules have none, and the schedule that holds a rule stays small.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    wake: Option<Box<SilenceWake>>,
    /// A paced opening's visits and questions per state, when it asks each state its share of
    /// its visits instead of by rank (`None`: by rank).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    opening_share: Option<Box<VisitShare>>,
    /// The same for the spare a repayment leaves after the opening (`None`: only the
    /// best-ranked state may ask it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    repayment_share: Option<Box<VisitShare>>,
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
            opening_share: None,
            repayment_share: None,
        }
    }

    /// After `steps` without a query, rank among the states visited during the silence until
    /// the next query (the authors' ranking otherwise).
    pub fn waking_after(mut self, steps: u64) -> Self {
        self.wake = Some(Box::new(SilenceWake::new(steps)));
        self
    }

    /// In a paced opening, ask each state the opening's rate of its own visits rather than by
    /// rank ([`VisitShare`]); after the opening the rule ranks as before.
    pub fn opening_by_visits(mut self) -> Self {
        self.opening_share = Some(Box::default());
        self
    }

    /// While an opening's debt is repaid, ask each state the spare's share of its visits
    /// since the repayment began rather than only the best-ranked one ([`VisitShare`]).
    pub fn repayment_by_visits(mut self) -> Self {
        self.repayment_share = Some(Box::default());
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

    /// Ask only while `budget` holds a query: at most its rate of the steps, at most about its
    /// burst in a row ([`AskBudget`]: its floor, opening and repayment).
    pub fn with_ceiling(mut self, budget: AskBudget) -> Self {
        self.budget = Some(Box::new(budget));
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
        // A paced opening, or a repayment's spare, placed by visits asks each state its share
        // of its own visits.
        if let Some((rate, share)) = self.placement() {
            return match self.budget.as_ref().is_some_and(|b| b.in_tapered_opening()) {
                true => share.behind_owed(g),
                false => share.behind(g, rate),
            };
        }
        // Else a paced opening must still spend its share: ranked as the authors rank, Lunar
        // Lander's rule asks about a thousand of its first 15k steps whatever the bucket holds.
        let paced = self.budget.as_ref().is_some_and(|b| b.in_paced_opening());
        let own = self.score(g);
        let higher_than = |other: &AbstractState| self.score(*other) > own;
        match (&self.recent, &self.wake) {
            (Some(recent), _) => count_at_most(recent.states().filter(higher_than), k),
            (None, Some(wake)) if wake.awake() || paced => {
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
        let tapered_rate = self
            .budget
            .as_deref()
            .filter(|b| b.in_tapered_opening())
            .and_then(|b| b.opening_rate_now());
        if let Some(share) = self.placement_mut() {
            match tapered_rate {
                Some(rate) => share.visit_owing(g, rate),
                None => share.visit(g),
            }
        }
        self.should_query(g)
    }

    /// The visits that place this step's question, with the share of them to ask: the
    /// opening's during a paced opening placed by visits, the repayment's while a debt whose
    /// spare is placed by visits is repaid (`None`: the step is ranked).
    fn placement(&self) -> Option<(f64, &VisitShare)> {
        let budget = self.budget.as_deref()?;
        if let Some(rate) = budget.opening_rate_now() {
            return self.opening_share.as_deref().map(|share| (rate, share));
        }
        let rate = budget.spare_rate_now()?;
        self.repayment_share.as_deref().map(|share| (rate, share))
    }

    /// [`QueryRule::placement`]'s visits, to count a visit or a question in.
    fn placement_mut(&mut self) -> Option<&mut VisitShare> {
        let budget = self.budget.as_deref()?;
        if budget.in_paced_opening() {
            self.opening_share.as_deref_mut()
        } else if budget.spare_rate_now().is_some() {
            self.repayment_share.as_deref_mut()
        } else {
            None
        }
    }

    /// Record the trainer's answer `h` in `g`, where the human critic predicted `h_hat` before
    /// this step's update. Every answer counts, "no feedback" (0) included, and spends a query
    /// of the ceiling's budget.
    pub fn record(&mut self, g: AbstractState, h: f32, h_hat: f32) {
        if let Some(share) = self.placement_mut() {
            share.asked(g);
        }
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
#[path = "query_rule_tests.rs"]
mod tests;
