//! Who answers DREF's evaluative queries: a trait, so that the synthetic oracle here and the
//! server's human trainer (a person in a browser) plug into the same training loop.

use serde::{Deserialize, Serialize};

use crate::scene_graph::AbstractState;

/// A trainer's judgement of what the robot just did: H in {+1, 0, -1}.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Evaluation {
    Good,
    /// The trainer chose not to judge (or did not answer in time); stored as H = 0.
    NoFeedback,
    Bad,
}

impl Evaluation {
    /// H as the human critic regresses it.
    pub fn value(self) -> f32 {
        match self {
            Evaluation::Good => 1.0,
            Evaluation::NoFeedback => 0.0,
            Evaluation::Bad => -1.0,
        }
    }

    /// Parse H from its integer form (the websocket's `"value": 1 | 0 | -1`).
    pub fn from_value(value: i64) -> Option<Self> {
        match value {
            1 => Some(Evaluation::Good),
            0 => Some(Evaluation::NoFeedback),
            -1 => Some(Evaluation::Bad),
            _ => None,
        }
    }
}

/// What the trainer is asked about: the step `(s_t, a_t) -> s_{t+1}`.
#[derive(Clone, Copy, Debug)]
pub struct EvaluativeQuery<'a> {
    /// Environment steps taken in the run before this one (0-based index of this step).
    pub step: u64,
    pub obs: &'a [f32],
    /// The action taken, normalised to `[-1, 1]`.
    pub action: &'a [f32],
    pub next_obs: &'a [f32],
    /// The scene graph on `(s_{t+1}, a_t)`.
    pub abstract_state: AbstractState,
    /// The human critic's prediction `H_hat(s_t, a_t)` before this step's update.
    pub predicted: f32,
}

/// Answers evaluative queries. `evaluate` may block (a person deciding); the training loop runs
/// on its own thread, so blocking there stalls nothing else.
pub trait EvaluativeTrainer {
    fn evaluate(&mut self, query: &EvaluativeQuery<'_>) -> Evaluation;

    /// The trainer's own state for a run's checkpoint (a synthetic oracle's random stream);
    /// `Null` for a trainer that has none.
    fn checkpoint_state(&self) -> serde_json::Value {
        serde_json::Value::Null
    }

    /// Continue from a state that [`EvaluativeTrainer::checkpoint_state`] returned.
    fn restore_state(&mut self, _state: &serde_json::Value) -> Result<(), String> {
        Ok(())
    }
}

/// The trainer of a run that never asks (plain SAC): every query would get "no feedback".
pub struct NoTrainer;

impl EvaluativeTrainer for NoTrainer {
    fn evaluate(&mut self, _query: &EvaluativeQuery<'_>) -> Evaluation {
        Evaluation::NoFeedback
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip() {
        for e in [Evaluation::Good, Evaluation::NoFeedback, Evaluation::Bad] {
            assert_eq!(Evaluation::from_value(e.value() as i64), Some(e));
        }
        assert_eq!(Evaluation::from_value(2), None);
    }
}
