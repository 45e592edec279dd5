//! What every evaluative run takes besides its learner's and its rule's settings: the scale of
//! the reward the learner stores, a person's pace, and the step its questions stop at.

use serde::{Deserialize, Serialize};

use super::SettingsError;
use super::sac::set_positive;
use super::session::SessionSection;
use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::human_pace::HumanPace;

/// The reward's scale, a person's pace and the step the questions stop at.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct EvaluativeSection {
    /// The learner stores `reward_scale * r`; reported returns keep the env's scale.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reward_scale: Option<f32>,
    /// A person's pace: at most this many queries in any minute at `pace_hz` (0: no limit,
    /// the paper's behaviour) [default 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_queries_per_minute: Option<u32>,
    /// No query from this step on (0: the method asks to the run's end, as the paper's do): a
    /// probe of when answers matter (`docs/dref.md`) [default 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feedback_until: Option<u64>,
}

impl EvaluativeSection {
    pub(super) fn offered(config: &EvaluativeRunConfig) -> Self {
        Self {
            reward_scale: Some(config.reward_scale),
            max_queries_per_minute: Some(0),
            feedback_until: Some(config.feedback_until.unwrap_or(0)),
        }
    }

    /// Every setting given, checked, into `config`; a pace counts steps at the session's
    /// `pace_hz`.
    pub(super) fn apply(
        &self,
        config: &mut EvaluativeRunConfig,
        session: &SessionSection,
    ) -> Result<(), SettingsError> {
        set_positive(&mut config.reward_scale, self.reward_scale, "reward_scale")?;
        if let Some(n) = self.max_queries_per_minute.filter(|n| *n > 0) {
            let pace_hz = session.resolve()?.pace_hz;
            config.human_pace = Some(HumanPace::new(n, pace_hz));
        }
        if let Some(n) = self.feedback_until {
            config.feedback_until = (n > 0).then_some(n);
        }
        Ok(())
    }
}
