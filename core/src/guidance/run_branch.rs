//! A run branched from another run's checkpoint: the same run up to the checkpoint, a setting
//! changed from there on. "What if the answers had stopped at 60k?" then costs the steps after
//! the branch, not a run from nothing, and the two runs share every step before it bit for bit.
//!
//! A branch is only what a run begun with the new config would have been: a setting may differ
//! only where it has not acted yet by the checkpoint's step. Today that is `feedback_until`
//! (its window must agree with the source run's on every step taken); any other difference is
//! refused by name, since the learner, replay and rule at the checkpoint were made under the
//! source run's value.

use super::{EvaluativeRun, EvaluativeRunConfig, EvaluativeTrainer, RunCheckpointError};
use crate::sim::Env;

/// Why a checkpoint cannot be branched under a config.
#[derive(Debug, thiserror::Error)]
pub enum BranchError {
    #[error(transparent)]
    Checkpoint(#[from] RunCheckpointError),
    /// Settings other than `feedback_until` differ; dotted names, e.g. `sac.learning_rate`.
    #[error(
        "branch: only feedback_until may differ from the run the checkpoint is of; these differ too: {}",
        .0.join(", ")
    )]
    OtherSettings(Vec<String>),
    /// The two `feedback_until`s disagree about a step the checkpoint has already taken.
    #[error(
        "branch: the checkpoint is at step {step}, and feedback_until {} would have asked otherwise than the run's {} before it (branch from a checkpoint at or before the earlier of the two)",
        show_until(*.now),
        show_until(*.was)
    )]
    FeedbackUntilActed {
        step: u64,
        was: Option<u64>,
        now: Option<u64>,
    },
    /// A run of the branch's length would keep another number of replay rows than the run
    /// did (the replay holds every step, up to `buffer_size`).
    #[error(
        "branch: the run's replay holds {kept} rows; a run of {steps} steps would hold {would}, so the branch would not be that run (give the run's own number of steps)"
    )]
    OtherLength {
        steps: u64,
        kept: usize,
        would: usize,
    },
}

fn show_until(until: Option<u64>) -> String {
    until.map_or_else(|| "(none: to the end)".into(), |n| n.to_string())
}

impl EvaluativeRun {
    /// The run `bytes` is a checkpoint of, going on under `config` from its step to `steps`
    /// (on `env` when given, as [`EvaluativeRun::resume_with_env`]), with `trainer` put back to
    /// its state then, and the caller's notes. `config` may differ from the run's own only as
    /// [`branch_check`] allows, and `steps` must give the replay the run's size.
    pub fn branch(
        bytes: &[u8],
        config: &EvaluativeRunConfig,
        steps: u64,
        env: Option<Box<dyn Env>>,
        trainer: &mut dyn EvaluativeTrainer,
    ) -> Result<(Self, serde_json::Value), BranchError> {
        let (was, _, step) = Self::checkpoint_learner(bytes)?;
        branch_check(&was, config, step)?;
        let (mut run, notes) = Self::resume_with_env(bytes, &was, env, trainer)?;
        let (kept, would) = (run.replay.capacity(), super::replay_capacity(config, steps));
        if kept != would {
            return Err(BranchError::OtherLength { steps, kept, would });
        }
        run.config = config.clone();
        Ok((run, notes))
    }
}

/// Whether a run under `was`, at `step`, is also the run `now` would have made to that step.
pub fn branch_check(
    was: &EvaluativeRunConfig,
    now: &EvaluativeRunConfig,
    step: u64,
) -> Result<(), BranchError> {
    let mut same = now.clone();
    same.feedback_until = was.feedback_until;
    if same != *was {
        let was = serde_json::to_value(was).expect("a config serialises");
        let now = serde_json::to_value(&same).expect("a config serialises");
        let mut names = Vec::new();
        differing_paths(&was, &now, String::new(), &mut names);
        return Err(BranchError::OtherSettings(names));
    }
    // Steps 0..step were asked where `index < feedback_until`: the windows agree on them when
    // both cut at the same place within them (or beyond).
    let window = |until: Option<u64>| until.map_or(step, |n| n.min(step));
    if window(was.feedback_until) != window(now.feedback_until) {
        return Err(BranchError::FeedbackUntilActed {
            step,
            was: was.feedback_until,
            now: now.feedback_until,
        });
    }
    Ok(())
}

/// The dotted names under which `a` and `b` differ (a whole value where one is not an object).
fn differing_paths(
    a: &serde_json::Value,
    b: &serde_json::Value,
    at: String,
    out: &mut Vec<String>,
) {
    use serde_json::Value::Object;
    match (a, b) {
        (Object(a), Object(b)) => {
            let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
            keys.sort();
            keys.dedup();
            for key in keys {
                let name = if at.is_empty() {
                    key.clone()
                } else {
                    format!("{at}.{key}")
                };
                let none = serde_json::Value::Null;
                differing_paths(
                    a.get(key).unwrap_or(&none),
                    b.get(key).unwrap_or(&none),
                    name,
                    out,
                );
            }
        }
        _ if a != b => out.push(if at.is_empty() { "(config)".into() } else { at }),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::feedback_schedule::EvaluativeMethod;
    use crate::sim::Task;

    fn config(until: Option<u64>) -> EvaluativeRunConfig {
        let mut c =
            EvaluativeRunConfig::new(Task::Reaching, EvaluativeMethod::Ef { percent: 100.0 }, 3);
        c.feedback_until = until;
        c
    }

    #[test]
    fn feedback_until_may_move_only_where_it_has_not_acted() {
        // From "to the end" to a cut at or after the checkpoint: the same steps were asked.
        assert!(branch_check(&config(None), &config(Some(5_000)), 5_000).is_ok());
        assert!(branch_check(&config(None), &config(Some(9_000)), 5_000).is_ok());
        // Two cuts past the checkpoint, or the same cut before it.
        assert!(branch_check(&config(Some(7_000)), &config(None), 5_000).is_ok());
        assert!(branch_check(&config(Some(2_000)), &config(Some(2_000)), 5_000).is_ok());
        // A cut before the checkpoint where the run asked on: refused, with both values.
        let e = branch_check(&config(None), &config(Some(4_999)), 5_000).unwrap_err();
        assert!(
            matches!(
                e,
                BranchError::FeedbackUntilActed {
                    step: 5_000,
                    was: None,
                    now: Some(4_999)
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("4999"), "{e}");
        // The run stopped asking before the checkpoint; the branch would have asked on.
        assert!(branch_check(&config(Some(2_000)), &config(None), 5_000).is_err());
        assert!(branch_check(&config(Some(2_000)), &config(Some(3_000)), 5_000).is_err());
    }

    #[test]
    fn any_other_difference_is_refused_by_its_dotted_name() {
        let was = config(None);
        let mut now = config(Some(9_000));
        now.sac.learning_rate *= 2.0;
        now.reward_scale = 2.0;
        let e = branch_check(&was, &now, 5_000).unwrap_err();
        match &e {
            BranchError::OtherSettings(names) => {
                assert_eq!(names, &["reward_scale", "sac.learning_rate"], "{e}")
            }
            other => panic!("{other}"),
        }
        assert!(e.to_string().contains("sac.learning_rate"), "{e}");
        // A different seed is another run altogether.
        let other_seed = config_with_seed(4);
        assert!(matches!(
            branch_check(&was, &other_seed, 5_000),
            Err(BranchError::OtherSettings(names)) if names == ["seed"]
        ));
    }

    fn config_with_seed(seed: u64) -> EvaluativeRunConfig {
        EvaluativeRunConfig::new(
            Task::Reaching,
            EvaluativeMethod::Ef { percent: 100.0 },
            seed,
        )
    }
}
