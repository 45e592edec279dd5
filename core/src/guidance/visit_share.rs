//! Where a paced opening places its questions: by rank (the default), or each abstract state
//! asked its share of its own visits (`opening_placement = "by_visits"`, `docs/dref.md`).
//!
//! Ranked as a woken rule ranks, a paced opening asks in the states the UCB score puts on top,
//! and the score's count term lifts the states with the fewest answers: the opening evens its
//! answers out over the abstract states. The learner samples its replay by how often it is in
//! a state, so on Lunar Lander, where the opening carries the take-off, the states it is in
//! most had the fewest answers for their visits; a probe that asked at random steps at about the
//! same rate took off sooner on both seeds it ran (docs/dref-lunar-lander.md, "The probe's seed
//! 1"). By visits, each state is asked `rate` of its own visits: the answers follow the learner as
//! a random draw would, but a state is never short of its share, and the choice still reads only
//! the scene graph and the answers, DREF's inputs. The spare a repayment leaves after the
//! opening may be placed the same way (`repayment_placement = "by_visits"`), with visits counted
//! from the repayment's start.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::scene_graph::AbstractState;

/// How a paced opening chooses the steps it asks on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum OpeningPlacement {
    /// Ranked as a woken rule ranks, among the states of its last `wake_after` steps.
    #[default]
    Ranked,
    /// Each abstract state asked the opening's rate of its own visits.
    ByVisits,
}

/// Per abstract state, the opening's visits and the queries asked there.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct VisitShare {
    /// `(visits, asked)`; a `BTreeMap` so that checkpoints serialise in a stable order.
    states: BTreeMap<AbstractState, (u64, u64)>,
    /// Under a tapered opening, whose rate changes from step to step: the queries each state is
    /// owed, the sum of the rate at each of its visits (empty otherwise, and in checkpoints
    /// written before it).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    owed: BTreeMap<AbstractState, f64>,
}

impl VisitShare {
    /// A step of the opening reached `g`.
    pub fn visit(&mut self, g: AbstractState) {
        self.states.entry(g).or_default().0 += 1;
    }

    /// A query was asked in `g` during the opening.
    pub fn asked(&mut self, g: AbstractState) {
        self.states.entry(g).or_default().1 += 1;
    }

    /// Whether `g` has been asked less than `rate` of its visits so far (this step's included):
    /// a state visited on every step is asked about every `1 / rate` steps, the first visit of a
    /// state at once.
    pub fn behind(&self, g: AbstractState, rate: f64) -> bool {
        let (visits, asked) = self.states.get(&g).copied().unwrap_or_default();
        (asked as f64) < rate * visits as f64
    }

    /// A step of a tapered opening reached `g`, where the opening asks `rate` of its steps now.
    pub fn visit_owing(&mut self, g: AbstractState, rate: f64) {
        self.visit(g);
        *self.owed.entry(g).or_default() += rate;
    }

    /// Whether `g` has been asked less than it is owed ([`VisitShare::visit_owing`]; this step's
    /// visit included): under a falling rate a state visited often early on is asked its share
    /// of each later visit at the later rate, not held back until its visits catch up with the
    /// early rate.
    pub fn behind_owed(&self, g: AbstractState) -> bool {
        let asked = self.states.get(&g).map_or(0, |&(_, asked)| asked);
        (asked as f64) < self.owed.get(&g).copied().unwrap_or(0.0)
    }

    /// `(visits, asked)` in `g` so far.
    pub fn of(&self, g: AbstractState) -> (u64, u64) {
        self.states.get(&g).copied().unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_visited_on_every_step_is_asked_its_rate_of_them() {
        let g = AbstractState(0b101);
        let mut share = VisitShare::default();
        let mut asked = Vec::new();
        for step in 0..20u64 {
            share.visit(g);
            if share.behind(g, 0.25) {
                share.asked(g);
                asked.push(step);
            }
        }
        assert_eq!(
            asked,
            vec![0, 4, 8, 12, 16],
            "the first visit, then every fourth"
        );
        assert_eq!(share.of(g), (20, 5));
        assert_eq!(share.of(AbstractState(1)), (0, 0), "an unvisited state");
    }

    #[test]
    fn under_a_falling_rate_a_state_is_owed_the_rate_of_each_visit() {
        let g = AbstractState(0b11);
        let mut share = VisitShare::default();
        let mut asked = Vec::new();
        // Half of the first 20 visits, then an eighth of the next 20 (binary fractions: the
        // sums are exact).
        for step in 0..40u64 {
            share.visit_owing(g, if step < 20 { 0.5 } else { 0.125 });
            if share.behind_owed(g) {
                share.asked(g);
                asked.push(step);
            }
        }
        assert_eq!(asked.len(), 13, "{asked:?}");
        assert_eq!(&asked[..3], &[0, 2, 4], "every other visit at first");
        assert_eq!(
            &asked[10..],
            &[20, 28, 36],
            "every eighth once the rate falls"
        );
        // Today's rate times all the visits (5) would leave the state unasked to the end.
        assert!(!share.behind(g, 0.125));
        assert!(
            !share.behind_owed(AbstractState(1)),
            "an unvisited state owes nothing"
        );
    }
}
