//! DRPL's settings (algorithms.md section 3): the query pool and the belief over rewards.

use serde::{Deserialize, Serialize};

use super::SettingsError;
use crate::guidance::drpl::acquisition::Acquisition;
use crate::guidance::drpl::run::PreferenceRunConfig;

/// DRPL and its baselines.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct PreferenceSection {
    /// Random trajectories recorded for the query pool.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trajectories: Option<usize>,
    /// Step limit per trajectory.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<usize>,
    /// Runs of one abstract state shorter than this merge into the previous segment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_run: Option<usize>,
    /// The final pick among candidate pairs: `uniform` or `mutual_information`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub acquisition: Option<Acquisition>,
    /// Rationality of the softmax user model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// The weak-comparison model's perceivable difference ("about equal").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta: Option<f64>,
    /// Metropolis-Hastings proposal step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub proposal_std: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub burn_in: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thinning: Option<usize>,
    /// Posterior samples kept per update.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
}

impl PreferenceSection {
    pub(super) fn offered(c: &PreferenceRunConfig) -> Self {
        Self {
            trajectories: Some(c.trajectories),
            max_steps: Some(c.max_steps),
            min_run: Some(c.min_run),
            acquisition: Some(c.acquisition),
            beta: Some(c.belief.beta),
            delta: Some(c.belief.delta),
            proposal_std: Some(c.belief.proposal_std),
            burn_in: Some(c.belief.burn_in),
            thinning: Some(c.belief.thinning),
            samples: Some(c.belief.samples),
        }
    }

    /// Every setting given, checked, into `config`.
    pub(super) fn apply(&self, config: &mut PreferenceRunConfig) -> Result<(), SettingsError> {
        let at_least = |key: &'static str,
                        v: Option<usize>,
                        min: usize|
         -> Result<Option<usize>, SettingsError> {
            match v {
                Some(n) if n < min => Err(SettingsError::bad(
                    key,
                    format!("expected an integer >= {min}, got {n}"),
                )),
                other => Ok(other),
            }
        };
        if let Some(n) = at_least("trajectories", self.trajectories, 2)? {
            config.trajectories = n;
        }
        if let Some(n) = at_least("max_steps", self.max_steps, 1)? {
            config.max_steps = n;
        }
        if let Some(n) = at_least("min_run", self.min_run, 1)? {
            config.min_run = n;
        }
        if let Some(a) = self.acquisition {
            config.acquisition = a;
        }
        let belief = &mut config.belief;
        for (key, value, slot) in [
            ("beta", self.beta, &mut belief.beta),
            ("delta", self.delta, &mut belief.delta),
            ("proposal_std", self.proposal_std, &mut belief.proposal_std),
        ] {
            if let Some(x) = value {
                if !x.is_finite() {
                    return Err(SettingsError::bad(
                        key,
                        format!("expected a finite number, got {x}"),
                    ));
                }
                *slot = x;
            }
        }
        if let Some(n) = self.burn_in {
            belief.burn_in = n;
        }
        if let Some(n) = at_least("thinning", self.thinning, 1)? {
            belief.thinning = n;
        }
        if let Some(n) = at_least("samples", self.samples, 1)? {
            belief.samples = n;
        }
        Ok(())
    }
}
