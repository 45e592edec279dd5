//! SAC's settings (algorithms.md section 1) and DREF's human critic, the learner's two
//! sections: what they offer and what they set in a run's [`SacConfig`].

use serde::{Deserialize, Deserializer, Serialize};

use super::SettingsError;
use crate::rl::{ActorMix, CriticLoss, HumanCriticConfig, SacConfig};

/// SAC's target entropy: SB3's `-dim(A)` ("auto") or a number.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(untagged)]
pub enum TargetEntropy {
    Auto(AutoWord),
    Value(f32),
}

/// The word `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum AutoWord {
    Auto,
}

/// SAC's learner.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct SacSection {
    /// Hidden layer sizes of the actor and every critic, e.g. `[256, 256]` or `"256,256"`.
    #[serde(
        deserialize_with = "layer_sizes",
        skip_serializing_if = "Option::is_none"
    )]
    pub hidden: Option<Vec<usize>>,
    /// Adam's learning rate (actor, critics, temperature).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub learning_rate: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batch_size: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub buffer_size: Option<usize>,
    /// Polyak coefficient, in [0, 1].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau: Option<f32>,
    /// Discount, in [0, 1].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub learning_starts: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradient_steps: Option<usize>,
    /// Initial entropy temperature.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub init_ent_coef: Option<f32>,
    /// `"auto"` (-dim(A)) or a number.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_entropy: Option<TargetEntropy>,
    /// The env critics' loss: `mse` (SAC's and the authors') or `huber` (delta 1, our learner
    /// variant: bounds each sample's pull on the critic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critic_loss: Option<CriticLoss>,
    /// Layer-normed env critics (`Linear -> LayerNorm -> ReLU`, our learner variant: a critic
    /// that cannot extrapolate to ever larger values without growing its last layer).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critic_layer_norm: Option<bool>,
}

/// DREF's human critic.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct HumanCriticSection {
    /// DREF's human critic on or off (on for DREF and EF, off for SAC).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub human_critic: Option<bool>,
    /// Weight of the human critic against Q in the actor loss (the authors: 9).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f32>,
    /// How the actor mixes Q and H: `authors` (head-wise), `paper` (Eq. 5) or `answered` (the
    /// authors' mix where the step was answered, H as 0 elsewhere) [default `answered` for
    /// `dref` on Reaching and Lunar Lander, `authors` otherwise].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix: Option<ActorMix>,
    /// Regress the human critic only on transitions that had feedback.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub human_critic_mask: Option<bool>,
    /// With `human_critic_mask`: how hard the transitions without feedback pull the human
    /// critic towards 0, a weight on their own mean squared error beside the answered ones' (0:
    /// the plain mask).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub human_critic_anchor: Option<f32>,
    /// With `human_critic_mask`: the human critic regresses a batch of its own drawn from the
    /// answered transitions, not the answered rows of SAC's batch (a few at a few percent of
    /// feedback).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub human_critic_answer_replay: Option<bool>,
    /// With `mix = "answered"`: the share of H's weight the actor keeps on transitions nobody
    /// answered (0: none, 1: the authors' mix).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix_unanswered: Option<f32>,
    /// With `mix = "answered"`: the actor reads H at full weight everywhere until the run's
    /// N-th successful episode, and as `mix_unanswered` says after it (0: from the start).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix_answered_after: Option<u32>,
    /// With `mix = "answered"`: an unanswered transition where the human critic's two heads
    /// agree within this much is read as an answered one (0: off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix_agree_within: Option<f32>,
    /// With `mix = "answered"`: the actor reads H on unanswered transitions at the share of
    /// the run's last N episodes that failed, at least `mix_unanswered` (0: off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix_failure_window: Option<u32>,
    /// With `mix = "answered"`: the actor reads H at full weight on every transition until
    /// the run's step N (the authors' mix), and as the answered mix after it (0: off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix_authors_until: Option<u64>,
    /// With `mix = "answered"`: after `mix_authors_until`, H's weight on unanswered
    /// transitions falls in a straight line from 1 to `mix_unanswered` over N steps (0: at once).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix_authors_fade: Option<u64>,
    /// With `mix = "answered"`: the share of H's weight the actor does not read on a
    /// transition goes to Q (each transition's weights sum to 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mix_unread_to_q: Option<bool>,
}

/// `hidden` as a list of layer sizes, the CLI's comma-separated text, or one number.
fn layer_sizes<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<usize>>, D::Error> {
    use serde_json::Value;
    let value = Value::deserialize(d)?;
    let size = |v: &Value| v.as_u64().map(|n| n as usize);
    let sizes = match &value {
        Value::Array(items) => items.iter().map(size).collect::<Option<Vec<_>>>(),
        Value::String(text) => text
            .split(',')
            .map(|s| s.trim().parse::<usize>().ok())
            .collect(),
        Value::Number(_) => size(&value).map(|n| vec![n]),
        _ => None,
    };
    sizes.map(Some).ok_or_else(|| {
        serde::de::Error::custom(format!(
            "hidden: expected layer sizes such as [256, 256] or \"256,256\", got {value}"
        ))
    })
}

impl SacSection {
    /// The learner's settings at `sac`'s values (the task's defaults).
    pub(super) fn offered(sac: &SacConfig) -> Self {
        Self {
            hidden: Some(sac.hidden.clone()),
            learning_rate: Some(sac.learning_rate),
            batch_size: Some(sac.batch_size),
            buffer_size: Some(sac.buffer_size),
            tau: Some(sac.tau),
            gamma: Some(sac.gamma),
            learning_starts: Some(sac.learning_starts),
            gradient_steps: Some(sac.gradient_steps),
            init_ent_coef: Some(sac.init_ent_coef),
            target_entropy: Some(
                sac.target_entropy
                    .map_or(TargetEntropy::Auto(AutoWord::Auto), TargetEntropy::Value),
            ),
            critic_loss: Some(sac.critic_loss),
            critic_layer_norm: Some(sac.critic_layer_norm),
        }
    }

    /// Every setting given, checked, into `sac`.
    pub(super) fn apply(&self, sac: &mut SacConfig) -> Result<(), SettingsError> {
        if let Some(h) = &self.hidden {
            if h.is_empty() || h.contains(&0) {
                return Err(SettingsError::bad(
                    "hidden",
                    format!("expected positive layer sizes, got {h:?}"),
                ));
            }
            sac.hidden = h.clone();
        }
        set_positive(&mut sac.learning_rate, self.learning_rate, "learning_rate")?;
        set_count(&mut sac.batch_size, self.batch_size, "batch_size")?;
        set_count(&mut sac.buffer_size, self.buffer_size, "buffer_size")?;
        set_unit(&mut sac.tau, self.tau, "tau")?;
        set_unit(&mut sac.gamma, self.gamma, "gamma")?;
        if let Some(n) = self.learning_starts {
            sac.learning_starts = n;
        }
        if let Some(n) = self.gradient_steps {
            sac.gradient_steps = n;
        }
        set_positive(&mut sac.init_ent_coef, self.init_ent_coef, "init_ent_coef")?;
        if let Some(loss) = self.critic_loss {
            sac.critic_loss = loss;
        }
        if let Some(on) = self.critic_layer_norm {
            sac.critic_layer_norm = on;
        }
        match self.target_entropy {
            None => {}
            Some(TargetEntropy::Auto(_)) => sac.target_entropy = None,
            Some(TargetEntropy::Value(v)) if v.is_finite() => sac.target_entropy = Some(v),
            Some(TargetEntropy::Value(v)) => {
                return Err(SettingsError::bad(
                    "target_entropy",
                    format!("expected a finite number, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

impl HumanCriticSection {
    /// The critic's settings, on, at `sac`'s critic's values (its defaults if it has none).
    pub(super) fn offered(sac: &SacConfig) -> Self {
        let critic = sac.human_critic.clone().unwrap_or_default();
        Self {
            human_critic: Some(true),
            lambda: Some(critic.lambda),
            mix: Some(critic.mix),
            human_critic_mask: Some(critic.mask),
            human_critic_anchor: Some(critic.anchor),
            human_critic_answer_replay: Some(critic.answer_replay),
            mix_unanswered: Some(critic.unanswered),
            mix_answered_after: Some(critic.answered_after),
            mix_agree_within: Some(critic.agree_within),
            mix_failure_window: Some(critic.failure_window),
            mix_authors_until: Some(critic.authors_until),
            mix_authors_fade: Some(critic.authors_fade),
            mix_unread_to_q: Some(critic.unread_to_q),
        }
    }

    /// Switches the critic on or off; any of its own settings switches it on (with defaults
    /// for the rest).
    pub(super) fn apply(&self, sac: &mut SacConfig) -> Result<(), SettingsError> {
        if let Some(on) = self.human_critic {
            sac.human_critic = on.then(|| sac.human_critic.clone().unwrap_or_default());
        }
        if let Some(l) = self.lambda {
            if !(l.is_finite() && l >= 0.0) {
                return Err(SettingsError::bad(
                    "lambda",
                    format!("expected a number >= 0, got {l}"),
                ));
            }
            critic(sac).lambda = l;
        }
        if let Some(m) = self.mix {
            critic(sac).mix = m;
        }
        if let Some(m) = self.human_critic_mask {
            critic(sac).mask = m;
        }
        if let Some(a) = self.human_critic_anchor {
            if !(a.is_finite() && a >= 0.0) {
                return Err(SettingsError::bad(
                    "human_critic_anchor",
                    "must be finite and >= 0",
                ));
            }
            if a > 0.0 && !critic(sac).mask {
                return Err(SettingsError::bad(
                    "human_critic_anchor",
                    "anchors the masked human critic: set human_critic_mask = true too",
                ));
            }
            critic(sac).anchor = a;
        }
        if let Some(on) = self.human_critic_answer_replay {
            if on && !critic(sac).mask {
                return Err(SettingsError::bad(
                    "human_critic_answer_replay",
                    "replays the masked human critic's answers: set human_critic_mask = true too",
                ));
            }
            if on && critic(sac).anchor > 0.0 {
                return Err(SettingsError::bad(
                    "human_critic_answer_replay",
                    "its batch holds answered transitions only, so nothing is left to anchor: \
                     set human_critic_anchor = 0",
                ));
            }
            critic(sac).answer_replay = on;
        }
        if let Some(w) = self.mix_unanswered {
            if !(0.0..=1.0).contains(&w) {
                return Err(SettingsError::bad(
                    "mix_unanswered",
                    format!("expected a share between 0 and 1, got {w}"),
                ));
            }
            answered_mix_only(
                sac,
                "mix_unanswered",
                w > 0.0,
                "weighs H on unanswered transitions of the answered mix",
            )?;
            critic(sac).unanswered = w;
        }
        if let Some(n) = self.mix_answered_after {
            answered_mix_only(sac, "mix_answered_after", n > 0, "gates the answered mix")?;
            critic(sac).answered_after = n;
        }
        if let Some(d) = self.mix_agree_within {
            if !(d.is_finite() && d >= 0.0) {
                return Err(SettingsError::bad(
                    "mix_agree_within",
                    format!("expected a number >= 0, got {d}"),
                ));
            }
            answered_mix_only(sac, "mix_agree_within", d > 0.0, "widens the answered mix")?;
            critic(sac).agree_within = d;
        }
        if let Some(n) = self.mix_failure_window {
            answered_mix_only(sac, "mix_failure_window", n > 0, "gates the answered mix")?;
            critic(sac).failure_window = n;
        }
        if let Some(n) = self.mix_authors_until {
            answered_mix_only(sac, "mix_authors_until", n > 0, "gates the answered mix")?;
            critic(sac).authors_until = n;
        }
        if let Some(n) = self.mix_authors_fade {
            answered_mix_only(sac, "mix_authors_fade", n > 0, "fades the answered mix in")?;
            critic(sac).authors_fade = n;
        }
        if let Some(on) = self.mix_unread_to_q {
            answered_mix_only(sac, "mix_unread_to_q", on, "gives Q H's unread weight")?;
            critic(sac).unread_to_q = on;
        }
        Ok(())
    }
}

/// A setting that refines the answered mix, given a value that does something (`set`) while
/// the mix is another: refused, naming the key and what it would have done.
fn answered_mix_only(
    sac: &mut SacConfig,
    key: &'static str,
    set: bool,
    what: &str,
) -> Result<(), SettingsError> {
    if set && critic(sac).mix != ActorMix::Answered {
        return Err(SettingsError::bad(
            key,
            format!("{what}: set mix = \"answered\" too"),
        ));
    }
    Ok(())
}

/// The human critic's config, switched on (with defaults) if it was off.
fn critic(sac: &mut SacConfig) -> &mut HumanCriticConfig {
    sac.human_critic.get_or_insert_default()
}

pub(super) fn set_positive(
    slot: &mut f32,
    value: Option<f32>,
    key: &'static str,
) -> Result<(), SettingsError> {
    match value {
        None => Ok(()),
        Some(v) if v.is_finite() && v > 0.0 => {
            *slot = v;
            Ok(())
        }
        Some(v) => Err(SettingsError::bad(
            key,
            format!("expected a positive number, got {v}"),
        )),
    }
}

fn set_unit(slot: &mut f32, value: Option<f32>, key: &'static str) -> Result<(), SettingsError> {
    match value {
        None => Ok(()),
        Some(v) if (0.0..=1.0).contains(&v) => {
            *slot = v;
            Ok(())
        }
        Some(v) => Err(SettingsError::bad(
            key,
            format!("expected a number in [0, 1], got {v}"),
        )),
    }
}

fn set_count(
    slot: &mut usize,
    value: Option<usize>,
    key: &'static str,
) -> Result<(), SettingsError> {
    match value {
        None => Ok(()),
        Some(0) => Err(SettingsError::bad(key, "expected at least 1")),
        Some(n) => {
            *slot = n;
            Ok(())
        }
    }
}
