//! Human-subject studies, the paper's Figures 4 and 6: within-subject, every participant trains
//! with every method in a counterbalanced order, then answers a Likert survey.
//!
//! Only the pure pieces live here (no IO): [`StudySpec`] is what a researcher launches
//! ([`spec`]: conditions, budget, survey, consent); [`StudyDesign`] says which conditions a
//! study compares and in which order each participant meets them ([`ordering`]); [`progress`]
//! derives where a participant is from what is stored; [`results`] turns what participants did
//! into Figure 4's numbers and the within-subject tests ([`crate::report::within_subject`]).
//! [`pilot`] estimates a study's power before anyone is recruited, with simulated
//! participants. The routes are `http::studies` and `http::participants`.

pub mod ordering;
pub mod pilot;
pub mod progress;
pub mod results;
pub mod spec;

use serde::{Deserialize, Serialize};

pub use self::ordering::Ordering;
pub use self::spec::{Condition, StudySpec, StudySpecError};

/// A within-subject study's design: the conditions (method names) and how to order them.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct StudyDesign {
    /// The conditions every participant meets, each once; the order given is the one
    /// [`Ordering::Fixed`] uses and the one the other orderings index into.
    pub conditions: Vec<String>,
    pub ordering: Ordering,
    /// Seeds [`Ordering::Random`]; the other orderings ignore it.
    pub seed: u64,
}

/// Why a [`StudyDesign`] cannot be run.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DesignError {
    #[error("a within-subject study needs at least two conditions, got {0}")]
    TooFewConditions(usize),
    #[error("condition {0:?} appears more than once")]
    DuplicateCondition(String),
}

impl StudyDesign {
    /// A design, checked: at least two conditions, no name twice.
    pub fn new(
        conditions: Vec<String>,
        ordering: Ordering,
        seed: u64,
    ) -> Result<Self, DesignError> {
        let design = StudyDesign {
            conditions,
            ordering,
            seed,
        };
        design.validate()?;
        Ok(design)
    }

    /// The checks of [`StudyDesign::new`], for a design that came in through serde.
    pub fn validate(&self) -> Result<(), DesignError> {
        if self.conditions.len() < 2 {
            return Err(DesignError::TooFewConditions(self.conditions.len()));
        }
        for (i, name) in self.conditions.iter().enumerate() {
            if self.conditions[..i].contains(name) {
                return Err(DesignError::DuplicateCondition(name.clone()));
            }
        }
        Ok(())
    }

    /// The conditions, in the order participant `participant` (counted from 0) meets them.
    pub fn order_for(&self, participant: usize) -> Vec<&str> {
        self.ordering
            .order(self.conditions.len(), participant, self.seed)
            .into_iter()
            .map(|i| self.conditions[i].as_str())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(names: &[&str]) -> Vec<String> {
        names.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn design_names_the_conditions_in_each_participants_order() {
        let design =
            StudyDesign::new(names(&["sac", "dref", "drpl"]), Ordering::Williams, 0).unwrap();
        // n = 3 is odd: the square (0 1 2, 1 2 0, 2 0 1) and its mirror.
        let orders: Vec<Vec<&str>> = (0..7).map(|p| design.order_for(p)).collect();
        assert_eq!(orders[0], ["sac", "dref", "drpl"]);
        assert_eq!(orders[1], ["dref", "drpl", "sac"]);
        assert_eq!(orders[3], ["drpl", "dref", "sac"]);
        assert_eq!(orders[6], orders[0]);
        let fixed = StudyDesign {
            ordering: Ordering::Fixed,
            ..design.clone()
        };
        assert_eq!(fixed.order_for(4), ["sac", "dref", "drpl"]);
    }

    #[test]
    fn design_round_trips_through_json_and_is_validated() {
        let design = StudyDesign::new(names(&["a", "b"]), Ordering::Random, 7).unwrap();
        let json = serde_json::to_value(&design).unwrap();
        assert_eq!(
            json,
            serde_json::json!({"conditions": ["a", "b"], "ordering": "random", "seed": 7})
        );
        let back: StudyDesign = serde_json::from_value(json).unwrap();
        assert_eq!(back, design);
        assert_eq!(back.order_for(3), design.order_for(3));

        assert_eq!(
            StudyDesign::new(names(&["a"]), Ordering::Fixed, 0),
            Err(DesignError::TooFewConditions(1))
        );
        assert_eq!(
            StudyDesign::new(names(&["a", "b", "a"]), Ordering::Fixed, 0),
            Err(DesignError::DuplicateCondition("a".into()))
        );
    }
}
