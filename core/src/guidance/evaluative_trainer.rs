//! Who answers DREF's evaluative queries: a trait, so that the synthetic oracle here and the
//! server's human trainer (a person in a browser) plug into the same training loop.

use serde::{Deserialize, Serialize};

use crate::rl::rng_state::RngStateError;
use crate::scene_graph::AbstractState;

/// A trainer's judgement of what the robot just did: H in {+1, 0, -1}, or the mean of several
/// trainers' judgements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Evaluation {
    Good,
    /// The trainer chose not to judge (or did not answer in time); stored as H = 0.
    NoFeedback,
    Bad,
    /// Several trainers' answers averaged (a session that combines k answers by their mean),
    /// when the mean is not a whole number.
    Mean(MeanLabel),
}

/// The mean of several +1 / 0 / -1 answers, strictly between -1 and 1 and not 0; compared by
/// its bits, so it can be a map key and replays compare exactly.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(try_from = "f32", into = "f32")]
pub struct MeanLabel(f32);

impl MeanLabel {
    /// `(good - bad) / count` as H, or `None` when it is a whole number (then it is a plain
    /// answer) or `count` is 0.
    pub fn of(good: u32, bad: u32, count: u32) -> Option<Self> {
        if count == 0 {
            return None;
        }
        // Through f64, so that a stored label read back as JSON gives the same f32.
        let h = ((f64::from(good) - f64::from(bad)) / f64::from(count)) as f32;
        (h.fract() != 0.0).then_some(Self(h))
    }

    pub fn value(self) -> f32 {
        self.0
    }
}

impl PartialEq for MeanLabel {
    fn eq(&self, other: &Self) -> bool {
        self.0.to_bits() == other.0.to_bits()
    }
}

impl Eq for MeanLabel {}

impl std::hash::Hash for MeanLabel {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.0.to_bits().hash(state);
    }
}

/// A number that is no [`MeanLabel`] (a whole number, or outside (-1, 1)).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("a mean label lies strictly between -1 and 1 and is not 0, got {0}")]
pub struct MeanLabelError(pub f32);

impl TryFrom<f32> for MeanLabel {
    type Error = MeanLabelError;
    fn try_from(h: f32) -> Result<Self, MeanLabelError> {
        if h.is_finite() && h > -1.0 && h < 1.0 && h.fract() != 0.0 {
            Ok(Self(h))
        } else {
            Err(MeanLabelError(h))
        }
    }
}

impl From<MeanLabel> for f32 {
    fn from(m: MeanLabel) -> f32 {
        m.0
    }
}

impl Evaluation {
    /// H as the human critic regresses it.
    pub fn value(self) -> f32 {
        match self {
            Evaluation::Good => 1.0,
            Evaluation::NoFeedback => 0.0,
            Evaluation::Bad => -1.0,
            Evaluation::Mean(m) => m.value(),
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
    /// The env's reward for the step (before any `reward_scale`).
    pub reward: f32,
    /// Whether the run stores the step as an end of the MDP (no bootstrap past it): the env
    /// terminated, or hit its time limit where the run's `time_limit` counts that as an end.
    pub terminated: bool,
    /// The scene graph on `(s_{t+1}, a_t)`.
    pub abstract_state: AbstractState,
    /// The human critic's prediction `H_hat(s_t, a_t)` before this step's update.
    pub predicted: f32,
}

/// Why a trainer's state from a run's checkpoint does not restore.
#[derive(Debug, thiserror::Error)]
pub enum RestoreError {
    /// The synthetic oracle's state is not the RNG state it writes.
    #[error("the oracle's RNG state: {0}")]
    OracleState(serde_json::Error),
    /// A stored RNG state that gives no generator.
    #[error(transparent)]
    Rng(#[from] RngStateError),
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
    fn restore_state(&mut self, _state: &serde_json::Value) -> Result<(), RestoreError> {
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

    #[test]
    fn means_are_fractions_that_read_back_exactly() {
        assert_eq!(
            MeanLabel::of(2, 0, 2),
            None,
            "a whole number is a plain answer"
        );
        assert_eq!(MeanLabel::of(0, 0, 0), None);
        let third = MeanLabel::of(1, 0, 3).unwrap();
        assert_eq!(third.value(), (1.0f64 / 3.0) as f32);
        let text = serde_json::to_string(&third).unwrap();
        assert_eq!(serde_json::from_str::<MeanLabel>(&text).unwrap(), third);
        assert!(serde_json::from_str::<MeanLabel>("1.0").is_err());
        assert!(serde_json::from_str::<MeanLabel>("0.0").is_err());
        assert_eq!(
            Evaluation::Mean(MeanLabel::of(1, 2, 4).unwrap()).value(),
            -0.25
        );
    }
}
