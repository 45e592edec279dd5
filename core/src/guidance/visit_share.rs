//! Where a paced opening places its questions: by rank (the default), or each abstract state
//! asked its share of its own visits (`opening_placement = "by_visits"`, `docs/dref.md`).
//!
//! Ranked as a woken rule ranks, a paced opening asks in the states the UCB score puts on top,
//! and the score's count term lifts the states with the fewest answers: the opening evens its
//! answers out over the abstract states. The learner samples its replay by how often it is in
//! a state, so on Lunar Lander, where the opening carries the take-off, the states it is in
//! most had the fewest answers for their visits; a probe that asked at random steps at about the
//! same rate took off sooner on both seeds it ran (docs/dref.md, "The probe's seed 1"). By
//! visits, each state is asked `rate` of its own visits: the answers follow the learner as a
//! random draw would, but a state is never short of its share, and the choice still reads only
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
}
