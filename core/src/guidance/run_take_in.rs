//! Answered steps a run takes in without asking them itself. A session on an env in another
//! process resumes from its latest run checkpoint (such an env cannot replay from step 0), and
//! the run lost the steps it took after that checkpoint; on an env that does not bring their
//! moments back (a robot) the answers people gave there would teach the learner nothing. So
//! the session keeps each step it asks about as the run stores it ([`AskedStep`]), and a
//! resumed run takes the ones answered after its checkpoint back in, with their answers: into
//! the replay buffer (SAC's and the human critic's data), the query rule's statistics and the
//! feedback counts, as the run that asked them had them. Nobody is asked them again.

use super::EvaluativeRun;
use crate::guidance::evaluative_trainer::{Evaluation, EvaluativeQuery};
use crate::rl::replay::Transition;
use crate::scene_graph::AbstractState;

/// A step a run asked about, as the run stores it beside the answer.
#[derive(Clone, Debug, PartialEq)]
pub struct AskedStep {
    pub obs: Vec<f32>,
    /// Normalised to [-1, 1].
    pub action: Vec<f32>,
    /// The env's reward (the replay holds it times the run's `reward_scale`).
    pub reward: f32,
    pub next_obs: Vec<f32>,
    /// Stored as an end of the MDP (no bootstrap past it).
    pub terminated: bool,
    /// The scene graph on `(s_{t+1}, a_t)`: where the query rule counts the answer.
    pub abstract_state: AbstractState,
    /// The human critic's prediction when it was asked (DREF's rule learns `|H - H_hat|`).
    pub predicted: f32,
}

impl AskedStep {
    pub fn of(q: &EvaluativeQuery<'_>) -> Self {
        Self {
            obs: q.obs.to_vec(),
            action: q.action.to_vec(),
            reward: q.reward,
            next_obs: q.next_obs.to_vec(),
            terminated: q.terminated,
            abstract_state: q.abstract_state,
            predicted: q.predicted,
        }
    }
}

/// Why a run took in none of the answered steps it was given: one is not of the run's sizes.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("an answered step's {what} has {found} values, the run's {expected}")]
pub struct TakeInError {
    pub what: &'static str,
    pub found: usize,
    pub expected: usize,
}

impl EvaluativeRun {
    /// Take in answered steps as the run's queries `at`, `at + 1`, ...; the run's queries from
    /// `at` on (the one the step just taken asked, if any) come after them, so that the run's
    /// queries stay in the order they were asked. Each goes into the replay buffer with its
    /// answer as H (the learner trains on it from its next update) and into the query rule's
    /// statistics, and counts as a query asked. Panics if the run has fewer than `at` queries.
    pub fn take_in(
        &mut self,
        at: usize,
        answered: &[(AskedStep, Evaluation)],
    ) -> Result<(), TakeInError> {
        assert!(
            at <= self.queried.len(),
            "query {at} of a run with {} queries",
            self.queried.len()
        );
        let (obs_dim, act_dim) = (self.replay.obs_dim(), self.replay.act_dim());
        for (s, _) in answered {
            for (what, found, expected) in [
                ("observation", s.obs.len(), obs_dim),
                ("action", s.action.len(), act_dim),
                ("next observation", s.next_obs.len(), obs_dim),
            ] {
                if found != expected {
                    return Err(TakeInError {
                        what,
                        found,
                        expected,
                    });
                }
            }
        }
        // Counted at the step of the query they come before (or the next step): a person's
        // pace reads the queries' steps in order, and those answers were given just now.
        let step = self.queried.get(at).map_or(self.steps, |&(s, _)| s);
        let mut taken = Vec::with_capacity(answered.len());
        for (s, answer) in answered {
            let slot = self.replay.push(Transition {
                obs: &s.obs,
                action: &s.action,
                reward: s.reward * self.config.reward_scale,
                human: answer.value(),
                next_obs: &s.next_obs,
                terminated: s.terminated,
            });
            self.schedule
                .record(s.abstract_state, answer.value(), s.predicted);
            self.feedback_count += 1;
            self.no_feedback_count += u64::from(*answer == Evaluation::NoFeedback);
            taken.push((step, slot));
        }
        self.taken_in += answered.len() as u64;
        self.queried.splice(at..at, taken);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::evaluative_run::EvaluativeRunConfig;
    use crate::guidance::evaluative_trainer::EvaluativeTrainer;
    use crate::guidance::feedback_schedule::FeedbackSchedule;
    use crate::sim::Task;

    fn tiny(method: &str) -> EvaluativeRunConfig {
        let mut config = EvaluativeRunConfig::new(Task::Placing, method.parse().unwrap(), 5);
        config.sac.hidden = vec![8, 8];
        config.sac.batch_size = 16;
        config
    }

    /// Answers good on even steps, bad on odd ones, "no feedback" every fifth; keeps each step
    /// it is asked about, as a session does.
    #[derive(Default)]
    struct Keeper {
        asked: Vec<(AskedStep, Evaluation)>,
    }

    impl EvaluativeTrainer for Keeper {
        fn evaluate(&mut self, q: &EvaluativeQuery<'_>) -> Evaluation {
            let e = match q.step {
                s if s % 5 == 0 => Evaluation::NoFeedback,
                s if s % 2 == 0 => Evaluation::Good,
                _ => Evaluation::Bad,
            };
            self.asked.push((AskedStep::of(q), e));
            e
        }
    }

    /// A run stepped to its first episode start after `steps`, its checkpoint there, and the
    /// same run `more` steps on, with the steps it asked about after the checkpoint.
    fn checkpoint_and_on(
        config: &EvaluativeRunConfig,
        steps: u64,
        more: u64,
    ) -> (Vec<u8>, EvaluativeRun, Vec<(AskedStep, Evaluation)>) {
        let mut run = EvaluativeRun::new(config.clone(), 1_000);
        let mut trainer = Keeper::default();
        while run.steps() < steps || !run.at_episode_start() {
            run.step(&mut trainer);
        }
        let bytes = run.checkpoint(&trainer, serde_json::Value::Null);
        trainer.asked.clear();
        for _ in 0..more {
            run.step(&mut trainer);
        }
        (bytes, run, trainer.asked)
    }

    #[test]
    fn a_resumed_run_takes_in_the_answered_steps_as_the_run_that_asked_them_stored_them() {
        // EF-100 asks at every step: the run that went on stored exactly the steps it asked.
        let config = tiny("ef-100");
        let (bytes, went_on, asked) = checkpoint_and_on(&config, 30, 7);
        assert_eq!(asked.len(), 7);
        let (mut resumed, _) = EvaluativeRun::resume(&bytes, &config, &mut Keeper::default())
            .expect("the checkpoint resumes");
        let before = resumed.feedback_count() as usize;
        resumed.take_in(before, &asked).unwrap();

        assert_eq!(
            resumed.replay.to_bytes(),
            went_on.replay.to_bytes(),
            "the same rows, H included, in the same slots"
        );
        assert_eq!(resumed.feedback_count(), went_on.feedback_count());
        assert_eq!(resumed.no_feedback_count(), went_on.no_feedback_count());
        for (i, (_, answer)) in asked.iter().enumerate() {
            assert_eq!(resumed.human_label(before + i), Some(answer.value()));
        }
        // An undo of a taken-in answer relabels its row.
        assert!(resumed.relabel(before + 1, Evaluation::NoFeedback));
        assert_eq!(resumed.human_label(before + 1), Some(0.0));
        // And the next checkpoint keeps them.
        while !resumed.at_episode_start() {
            resumed.step(&mut Keeper::default());
        }
        let again = resumed.checkpoint(&Keeper::default(), serde_json::Value::Null);
        let replay = EvaluativeRun::checkpoint_replay(&again).unwrap();
        assert_eq!(replay.len() as u64, resumed.steps() + 7);
    }

    #[test]
    fn taken_in_answers_count_in_dref_rules_statistics() {
        let config = tiny("dref");
        let (bytes, went_on, asked) = checkpoint_and_on(&config, 20, 15);
        assert!(!asked.is_empty(), "DREF asks early in a run");
        let (mut resumed, _) =
            EvaluativeRun::resume(&bytes, &config, &mut Keeper::default()).unwrap();
        let at = resumed.feedback_count() as usize;
        resumed.take_in(at, &asked).unwrap();
        let stats = |run: &EvaluativeRun| match &run.schedule {
            FeedbackSchedule::Dref(rule) => {
                let rule = serde_json::to_value(rule).unwrap();
                (rule["total"].clone(), rule["stats"].clone())
            }
            _ => panic!("a DREF run"),
        };
        assert_eq!(stats(&resumed), stats(&went_on));
        assert_eq!(resumed.feedback_count(), went_on.feedback_count());
    }

    #[test]
    fn answers_taken_in_before_the_query_just_asked_keep_the_order_asked() {
        let config = tiny("ef-100");
        let (bytes, _, asked) = checkpoint_and_on(&config, 30, 3);
        let mut keeper = Keeper::default();
        let (mut resumed, _) = EvaluativeRun::resume(&bytes, &config, &mut keeper).unwrap();
        let before = resumed.feedback_count() as usize;
        // The resumed run asks a query of its own first (a resumed session on a robot gives
        // up its catch-up at such a query), then takes in.
        resumed.step(&mut keeper);
        let own = keeper.asked[0].1.value();
        resumed.take_in(before, &asked).unwrap();
        for (i, (_, answer)) in asked.iter().enumerate() {
            assert_eq!(resumed.human_label(before + i), Some(answer.value()));
        }
        assert_eq!(resumed.human_label(before + 3), Some(own));
        let steps: Vec<u64> = resumed.queried.iter().map(|&(s, _)| s).collect();
        assert!(steps.is_sorted(), "{steps:?}");
    }

    #[test]
    fn a_step_of_other_sizes_is_refused_and_nothing_is_taken_in() {
        let config = tiny("ef-100");
        let (bytes, _, mut asked) = checkpoint_and_on(&config, 30, 2);
        asked[1].0.action.push(0.0);
        let (mut resumed, _) =
            EvaluativeRun::resume(&bytes, &config, &mut Keeper::default()).unwrap();
        let (count, rows) = (resumed.feedback_count(), resumed.replay.len());
        let at = count as usize;
        let err = resumed.take_in(at, &asked).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!(
                "an answered step's action has {} values, the run's {}",
                resumed.replay.act_dim() + 1,
                resumed.replay.act_dim()
            )
        );
        assert_eq!(
            (resumed.feedback_count(), resumed.replay.len()),
            (count, rows)
        );
    }
}
