//! DREF's query rule (algorithms.md section 2, docs/dref.md): its constants, the product's
//! silence wake and ceiling with its opening, and the recent rank's window.

use serde::{Deserialize, Serialize};

use super::SettingsError;
use crate::guidance::evaluative_run::{DEFAULT_CEILING, FeedbackCeiling, QueryRuleConfig};
use crate::guidance::query_rule::UcbForm;
use crate::guidance::visit_share::OpeningPlacement;

/// DREF's query rule.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct QueryRuleSection {
    /// The query rule's exploration constant c.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c: Option<f64>,
    /// The query rule asks iff at most k ranked states score higher.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k: Option<usize>,
    /// The UCB form: `authors` or `paper`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ucb: Option<UcbForm>,
    /// Rank the current state among those visited in the last N steps; 0: among every state
    /// with feedback, the authors' [default 0; 1000 was `dref`'s recent rank until 2026-11-27].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rank_window: Option<usize>,
    /// Ask on at most this share of steps, in (0, 1]; 0: no ceiling, the authors' [default 0.1
    /// for `dref`, 0 for `dref-authors`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_feedback_rate: Option<f64>,
    /// With a ceiling: at most about this many queries in a row [default 20].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feedback_burst: Option<u32>,
    /// With a ceiling: for the run's first N steps ask as without it, and repay the queries
    /// borrowed from the steps after (the run's total stays under the ceiling); 0: off [default
    /// 2000 for `dref`, 0 otherwise].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feedback_opening: Option<u64>,
    /// With a ceiling: start the run with an empty bucket, so that once any opening is repaid
    /// the run has asked at most `max_feedback_rate` of its steps (a full bucket: up to
    /// `feedback_burst` more) [default false].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feedback_start_empty: Option<bool>,
    /// With an opening: the share of each step's earnings, in (0, 1], that repays the queries
    /// it borrowed; the rest may be asked while it repays (for the best-ranked state only), so
    /// the rule is never silent for the whole repayment; 1: all, silent until repaid [default 1].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub opening_repay_share: Option<f64>,
    /// With an opening: ask at most this share of its steps, in (0, 1], ranked as a woken rule
    /// ranks (among the states of the last `wake_after` steps), so that the opening spends that
    /// share; what passes the ceiling's earnings is repaid after as any opening's; 0: every step
    /// the authors' ranking asks [default 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub opening_rate: Option<f64>,
    /// With a paced opening: where it asks, `ranked` (as a woken rule ranks) or `by_visits`
    /// (each abstract state asked `opening_rate` of its own visits, so the answers follow where
    /// the learner is) [default `ranked`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub opening_placement: Option<OpeningPlacement>,
    /// With a paced opening: let its rate fall in a straight line from `opening_rate` at its
    /// first step to nothing at its last, so the answers thin out instead of stopping at once
    /// (it asks about half as many: double `feedback_opening` to spend the same) [default false].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub opening_taper: Option<bool>,
    /// With an opening repaid from part of the earnings (`opening_repay_share` below 1): where
    /// the rest is asked while it repays, `ranked` (the best-ranked state only) or `by_visits`
    /// (each abstract state asked that rest's share of its visits since the repayment began, so
    /// the rule keeps asking where the learner is) [default `ranked`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub repayment_placement: Option<OpeningPlacement>,
    /// With a ceiling: let the rate run from this floor (recent answers all "good") up to
    /// `max_feedback_rate` (all "bad"); 0: a fixed rate [default 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_feedback_rate: Option<f64>,
    /// After this many steps without a query, rank the current state among the states visited
    /// during that silence instead of among every state with feedback, until the rule asks
    /// again; 0: never, the authors' [default 1000 for `dref`, 0 for `dref-authors`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wake_after: Option<u64>,
}

impl QueryRuleSection {
    /// The rule's settings at `rule`'s values (0 where it has no ceiling).
    pub(super) fn offered(rule: &QueryRuleConfig) -> Self {
        Self {
            c: Some(rule.c),
            k: Some(rule.k),
            ucb: Some(rule.form),
            rank_window: Some(rule.rank_window),
            max_feedback_rate: Some(rule.ceiling.map_or(0.0, |x| x.rate)),
            feedback_burst: Some(rule.ceiling.map_or(DEFAULT_CEILING.burst, |x| x.burst)),
            feedback_opening: Some(rule.ceiling.map_or(0, |x| x.opening)),
            feedback_start_empty: Some(rule.ceiling.is_some_and(|x| x.start_empty)),
            opening_repay_share: Some(rule.ceiling.map_or(1.0, |x| x.repay_share)),
            opening_rate: Some(rule.ceiling.and_then(|x| x.opening_rate).unwrap_or(0.0)),
            opening_placement: Some(
                rule.ceiling
                    .map_or_else(Default::default, |x| x.opening_placement),
            ),
            opening_taper: Some(rule.ceiling.is_some_and(|x| x.opening_taper)),
            repayment_placement: Some(
                rule.ceiling
                    .map_or_else(Default::default, |x| x.repayment_placement),
            ),
            min_feedback_rate: Some(rule.ceiling.and_then(|x| x.floor).unwrap_or(0.0)),
            wake_after: Some(rule.wake_after),
        }
    }

    /// Every setting given, checked, into `rule`.
    pub(super) fn apply(&self, rule: &mut QueryRuleConfig) -> Result<(), SettingsError> {
        if let Some(c) = self.c {
            if !c.is_finite() || c < 0.0 {
                return Err(SettingsError::bad(
                    "c",
                    format!("expected a number >= 0, got {c}"),
                ));
            }
            rule.c = c;
        }
        if let Some(k) = self.k {
            rule.k = k;
        }
        if let Some(form) = self.ucb {
            rule.form = form;
        }
        self.apply_pacing(rule)?;
        if let Some(steps) = self.wake_after {
            rule.wake_after = steps;
        }
        Ok(())
    }

    /// The product rule's window and ceiling (docs/dref.md), on any DREF: 0 switches either off.
    fn apply_pacing(&self, rule: &mut QueryRuleConfig) -> Result<(), SettingsError> {
        if let Some(w) = self.rank_window {
            rule.rank_window = w;
        }
        match self.max_feedback_rate {
            None => {}
            Some(0.0) => rule.ceiling = None,
            Some(r) if r.is_finite() && r > 0.0 && r <= 1.0 => {
                rule.ceiling = Some(FeedbackCeiling {
                    rate: r,
                    ..rule.ceiling.unwrap_or(DEFAULT_CEILING)
                });
            }
            Some(r) => {
                return Err(SettingsError::bad(
                    "max_feedback_rate",
                    format!("expected a share of steps in (0, 1], or 0 for no ceiling, got {r}"),
                ));
            }
        }
        match (self.min_feedback_rate, &mut rule.ceiling) {
            (None, _) => {}
            (Some(0.0), Some(c)) => c.floor = None,
            (Some(0.0), None) => {}
            (Some(f), Some(c)) if f.is_finite() && f > 0.0 && f <= c.rate => c.floor = Some(f),
            (Some(f), Some(c)) => {
                return Err(SettingsError::bad(
                    "min_feedback_rate",
                    format!(
                        "expected a share of steps in (0, max_feedback_rate = {}], or 0 for a fixed rate, got {f}",
                        c.rate
                    ),
                ));
            }
            (Some(_), None) => {
                return Err(SettingsError::bad(
                    "min_feedback_rate",
                    "the rule has no ceiling; set max_feedback_rate too",
                ));
            }
        }
        if let Some(b) = self.feedback_burst {
            if b == 0 {
                return Err(SettingsError::bad("feedback_burst", "expected at least 1"));
            }
            if let Some(c) = the_ceiling(rule, "feedback_burst", false)? {
                c.burst = b;
            }
        }
        if let Some(steps) = self.feedback_opening
            && let Some(c) = the_ceiling(rule, "feedback_opening", steps == 0)?
        {
            // Closing a task's opening closes all of it: nothing of an opening that never runs
            // is left in the run's config to be read as if it did.
            match steps {
                0 => *c = c.without_opening(),
                _ => c.opening = steps,
            }
        }
        if let Some(empty) = self.feedback_start_empty
            && let Some(c) = the_ceiling(rule, "feedback_start_empty", !empty)?
        {
            c.start_empty = empty;
        }
        if let Some(share) = self.opening_repay_share {
            if !(share.is_finite() && share > 0.0 && share <= 1.0) {
                return Err(SettingsError::bad(
                    "opening_repay_share",
                    format!("expected a share of the earnings in (0, 1], got {share}"),
                ));
            }
            if let Some(c) = the_ceiling(rule, "opening_repay_share", share == 1.0)? {
                if share < 1.0 && c.opening == 0 {
                    return Err(SettingsError::bad(
                        "opening_repay_share",
                        "the rule has no opening to repay; set feedback_opening too",
                    ));
                }
                c.repay_share = share;
            }
        }
        if let Some(rate) = self.opening_rate {
            if !(rate.is_finite() && (0.0..=1.0).contains(&rate)) {
                return Err(SettingsError::bad(
                    "opening_rate",
                    format!(
                        "expected a share of the opening's steps in (0, 1], or 0 for all, got {rate}"
                    ),
                ));
            }
            if let Some(c) = the_ceiling(rule, "opening_rate", rate == 0.0)? {
                if rate > 0.0 && c.opening == 0 {
                    return Err(SettingsError::bad(
                        "opening_rate",
                        "the rule has no opening to pace; set feedback_opening too",
                    ));
                }
                // Unpacing a task's opening unpaces all of it: no placement or taper of a pace
                // that never runs is left in the run's config (Lunar Lander's is placed by visits).
                if rate > 0.0 {
                    c.opening_rate = Some(rate);
                } else {
                    *c = c.without_pace();
                }
            }
        }
        if let Some(placement) = self.opening_placement {
            let ranked = placement == OpeningPlacement::Ranked;
            if let Some(c) = the_ceiling(rule, "opening_placement", ranked)? {
                if !ranked && c.opening_rate.is_none() {
                    return Err(SettingsError::bad(
                        "opening_placement",
                        "only a paced opening places its questions; set opening_rate too",
                    ));
                }
                c.opening_placement = placement;
            }
        }
        if let Some(taper) = self.opening_taper
            && let Some(c) = the_ceiling(rule, "opening_taper", !taper)?
        {
            if taper && c.opening_rate.is_none() {
                return Err(SettingsError::bad(
                    "opening_taper",
                    "only a paced opening tapers; set opening_rate too",
                ));
            }
            c.opening_taper = taper;
        }
        if let Some(placement) = self.repayment_placement {
            let ranked = placement == OpeningPlacement::Ranked;
            if let Some(c) = the_ceiling(rule, "repayment_placement", ranked)? {
                if !ranked && (c.opening == 0 || c.repay_share >= 1.0) {
                    return Err(SettingsError::bad(
                        "repayment_placement",
                        "only an opening repaid from part of the earnings leaves a spare to \
                         place; set feedback_opening and an opening_repay_share below 1",
                    ));
                }
                c.repayment_placement = placement;
            }
        }
        Ok(())
    }
}

/// The rule's ceiling, for a setting of it named `key`: `None` when the rule has none and the
/// value is the setting's "off" (nothing to set), refused by name when it has none otherwise.
fn the_ceiling<'a>(
    rule: &'a mut QueryRuleConfig,
    key: &'static str,
    off: bool,
) -> Result<Option<&'a mut FeedbackCeiling>, SettingsError> {
    match &mut rule.ceiling {
        Some(c) => Ok(Some(c)),
        None if off => Ok(None),
        None => Err(SettingsError::bad(
            key,
            "the rule has no ceiling; set max_feedback_rate too",
        )),
    }
}

#[cfg(test)]
#[path = "query_rule_tests.rs"]
mod tests;
