//! SAC's settings by name: every key `--set`, TOML and a launch's `params` may give overrides the
//! run's `SacConfig`, and an unknown key or a bad value is refused with its name.

use dualrep::guidance::feedback_schedule::EvaluativeMethod;
use dualrep::rl::sac::{ActorMix, HumanCriticConfig, SacConfig};
use dualrep::settings::{Settings, SettingsError};
use dualrep::sim::Task;

/// A run's SAC settings by name, as `--set` and a launch's `params` give them.
fn sac_with(pairs: &[(&str, &str)]) -> Result<SacConfig, SettingsError> {
    Settings::from_pairs(pairs.iter().copied())?
        .evaluative(Task::LunarLander, EvaluativeMethod::DrefAuthors, 0)
        .map(|c| c.sac)
}

#[test]
fn settings_override_every_sac_key() {
    let c = sac_with(&[
        ("hidden", "256,256"),
        ("learning_rate", "3e-4"),
        ("batch_size", "256"),
        ("buffer_size", "1000"),
        ("tau", "0.005"),
        ("gamma", "0.98"),
        ("learning_starts", "100"),
        ("gradient_steps", "2"),
        ("init_ent_coef", "0.1"),
        ("target_entropy", "-3"),
        ("lambda", "4"),
        ("mix", "paper"),
        ("human_critic_mask", "true"),
        ("human_critic_anchor", "0.25"),
    ])
    .unwrap();
    assert_eq!(c.hidden, [256, 256]);
    assert_eq!(
        (c.learning_rate, c.batch_size, c.buffer_size),
        (3e-4, 256, 1000)
    );
    assert_eq!(
        (c.tau, c.gamma, c.learning_starts, c.gradient_steps),
        (0.005, 0.98, 100, 2)
    );
    assert_eq!((c.init_ent_coef, c.target_entropy), (0.1, Some(-3.0)));
    assert_eq!(
        c.human_critic,
        Some(HumanCriticConfig {
            lambda: 4.0,
            mix: ActorMix::Paper,
            mask: true,
            anchor: 0.25,
            unanswered: 0.0,
            answered_after: 0,
            agree_within: 0.0,
            failure_window: 0,
            authors_until: 0,
            authors_fade: 0,
            unread_to_q: false,
            answer_replay: false,
        })
    );
    let answered = sac_with(&[
        ("mix", "answered"),
        ("mix_unanswered", "0.3"),
        ("mix_answered_after", "10"),
        ("mix_agree_within", "0.2"),
        ("mix_failure_window", "10"),
        ("mix_authors_until", "30000"),
        ("mix_authors_fade", "30000"),
        ("mix_unread_to_q", "true"),
    ])
    .unwrap();
    let critic = answered.human_critic.unwrap();
    assert_eq!(
        (
            critic.mix,
            critic.unanswered,
            critic.answered_after,
            critic.agree_within,
            critic.failure_window,
            critic.authors_until,
            critic.authors_fade,
            critic.unread_to_q
        ),
        (ActorMix::Answered, 0.3, 10, 0.2, 10, 30_000, 30_000, true)
    );
    let replayed = sac_with(&[
        ("human_critic_mask", "true"),
        ("human_critic_answer_replay", "true"),
    ])
    .unwrap();
    assert!(replayed.human_critic.unwrap().answer_replay);
    let anchored = sac_with(&[
        ("human_critic_mask", "true"),
        ("human_critic_anchor", "0.5"),
        ("human_critic_answer_replay", "true"),
    ])
    .unwrap_err();
    assert_eq!(anchored.key(), Some("human_critic_answer_replay"));
    assert!(anchored.to_string().contains("human_critic_anchor = 0"));
    let c = sac_with(&[("target_entropy", "-3"), ("target_entropy", "auto")]).unwrap();
    assert_eq!(c.target_entropy, None);
    assert_eq!(
        sac_with(&[("human_critic", "false")]).unwrap().human_critic,
        None
    );
    assert_eq!(
        sac_with(&[("human_critic", "true")]).unwrap().human_critic,
        Some(HumanCriticConfig::default())
    );
}

#[test]
fn settings_reject_unknown_keys_and_bad_values_clearly() {
    for (k, v, says) in [
        ("hiden", "64", "unknown field `hiden`"),
        ("hidden", "64,0", "positive layer sizes"),
        ("hidden", "", "layer sizes"),
        ("learning_rate", "fast", "invalid type"),
        ("learning_rate", "-1", "positive number"),
        ("batch_size", "0", "at least 1"),
        ("batch_size", "1.5", "invalid type"),
        ("tau", "2", "[0, 1]"),
        ("gamma", "NaN", "invalid type"),
        ("mix", "both", "unknown variant `both`"),
        ("human_critic", "yes", "invalid type"),
        ("human_critic_mask", "1", "invalid type"),
        ("lambda", "-1", ">= 0"),
        ("human_critic_anchor", "-1", ">= 0"),
        ("human_critic_anchor", "0.5", "human_critic_mask = true"),
        ("mix_unanswered", "1.5", "between 0 and 1"),
        ("mix_unanswered", "0.3", "mix = \"answered\""),
        ("mix_answered_after", "10", "mix = \"answered\""),
        ("mix_answered_after", "-1", "invalid"),
        ("mix_agree_within", "-0.1", ">= 0"),
        ("mix_agree_within", "0.2", "mix = \"answered\""),
        ("mix_failure_window", "10", "mix = \"answered\""),
        ("mix_failure_window", "-1", "invalid"),
        ("mix_authors_until", "30000", "mix = \"answered\""),
        ("mix_authors_until", "-1", "invalid"),
        ("mix_authors_fade", "30000", "mix = \"answered\""),
        ("mix_unread_to_q", "true", "mix = \"answered\""),
        ("mix_unread_to_q", "1", "invalid type"),
        (
            "human_critic_answer_replay",
            "true",
            "human_critic_mask = true",
        ),
        ("human_critic_answer_replay", "on", "invalid type"),
    ] {
        let err = sac_with(&[(k, v)]).expect_err(&format!("{k}={v} accepted"));
        assert_eq!(err.key(), Some(k), "{k}={v}: {err:?} should name its key");
        assert!(
            err.to_string().contains(says),
            "{k}={v}: {err:?} should say {says:?}"
        );
    }
}

// --- checkpoints ---------------------------------------------------------------------------
