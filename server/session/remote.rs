//! A session on an environment in another process or on another machine. Such an env cannot
//! be replayed from step 0 (a robot, or any env whose episodes do not repeat), so the session
//! does not resume by replaying its stored answers as a simulated one does:
//!
//! - an evaluative session saves its whole run (learner, replay buffer, query-rule state,
//!   random streams; `guidance::run_checkpoint`) at episode starts and resumes from the latest
//!   one. The run then catches up on the queries stored after that checkpoint
//!   ([`StoredMoment`], module `catch_up`): an env that repeats its episodes (a simulator)
//!   brings back the same moments, and each one that meets the next stored query (same step,
//!   same action) takes its stored answer, under its number, without asking anyone. The first
//!   moment that differs (a robot) ends the catch-up: the queries not met again keep their
//!   stored answers and numbers, and new queries are numbered after every stored one. The run
//!   lost their steps with the episode, so it takes the answered ones back in from the steps
//!   stored with them ([`take_in_given_up`], `guidance::run_take_in`): its learner learns from
//!   every answer given. Either way nobody is asked an answered query again, by number or by
//!   moment, and [`QueryNumbering`] maps the session's query numbers to the run's.
//! - a preference session keeps the trajectories it recorded on the env, and resumes by
//!   replaying its stored answers over them (no env step is replayed).

use serde::{Deserialize, Serialize};

use super::catch_up::GivenUp;
use super::error::SessionError;
use super::events::AnswerValue;
use crate::guidance::evaluative_run::{AskedStep, EvaluativeRun};
use crate::guidance::evaluative_trainer::Evaluation;
use crate::remote_env::RemoteDescription;
use crate::sim::{Env, EnvFault};

/// Opens another connection to the session's env (clips of human preference sessions are
/// replayed on one).
pub type Reconnect = Box<dyn Fn() -> Result<Box<dyn Env>, EnvFault> + Send>;

/// The env a session runs on when it is not our simulator, connected by the caller (the hub's
/// session thread), with what the session resumes from.
pub struct RemoteSession {
    pub env: Box<dyn Env>,
    pub description: RemoteDescription,
    pub reconnect: Reconnect,
    /// The bytes of the latest `Checkpoint::resume` the session reported, if any.
    pub resume_from: Option<Vec<u8>>,
    /// Queries stored for the session so far (answered or not): new ones are numbered after.
    pub stored_queries: u64,
    /// The session's stored evaluative queries, in query order: a resumed run catches up on
    /// those after its checkpoint, and takes in the answered ones it does not meet again.
    pub stored_moments: Vec<StoredMoment>,
}

/// A stored evaluative query: the moment it asked about, its answer, if it got one, and the
/// step as the run stored it.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredMoment {
    pub seq: u64,
    pub step: u64,
    /// The action asked about, normalised to [-1, 1] (none: stored without its transition).
    pub action: Option<Vec<f32>>,
    /// The answer as first given (an undo is applied as a stored revision).
    pub value: Option<AnswerValue>,
    /// The step as the run stored it (none: stored before steps were kept).
    pub asked: Option<AskedStep>,
}

/// Which of the session's query numbers the run knows, and under which of its own: numbers
/// whose steps the run lost with an env fault or a shutdown mid-episode, and could not take
/// back in (unanswered, or stored without their step), are skipped.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct QueryNumbering {
    /// Session query numbers the run does not have, as `[start, end)` ranges in order.
    pub lost: Vec<(u64, u64)>,
    /// The next session query number.
    pub next: u64,
}

impl QueryNumbering {
    /// The run's query index of session query `seq` (`None`: the run lost it).
    pub fn run_query(&self, seq: u64) -> Option<usize> {
        let mut skipped = 0;
        for &(start, end) in &self.lost {
            if seq < start {
                break;
            }
            if seq < end {
                return None;
            }
            skipped += end - start;
        }
        Some((seq - skipped) as usize)
    }
}

/// The stored queries the catch-up gave up on: the answered ones whose steps were stored go
/// into `run` as its next queries (before the one the step just taken asked, if it asked one),
/// the rest are lost to it.
pub(super) fn take_in_given_up(
    run: &mut EvaluativeRun,
    numbering: &mut QueryNumbering,
    given_up: GivenUp,
) -> Result<(), SessionError> {
    // Every number below `start` is the run's or lost before it: the run's next query index.
    let at = numbering
        .run_query(given_up.start)
        .expect("the catch-up starts after every lost number");
    let (answered, lost) = split_given_up(given_up);
    run.take_in(at, &answered).map_err(SessionError::TakeIn)?;
    numbering.lost.extend(lost);
    Ok(())
}

/// Steps a run takes in, each with its answer.
type AnsweredSteps = Vec<(AskedStep, Evaluation)>;

/// The answered steps among given-up queries, in order, and the numbers left (unanswered,
/// stored without a step, or not an evaluative query) as `[start, end)` ranges.
fn split_given_up(given_up: GivenUp) -> (AnsweredSteps, Vec<(u64, u64)>) {
    let GivenUp {
        start,
        end,
        moments,
    } = given_up;
    let mut answered = Vec::new();
    let mut lost: Vec<(u64, u64)> = Vec::new();
    let mut lose = |seq: u64| match lost.last_mut() {
        Some(range) if range.1 == seq => range.1 += 1,
        _ => lost.push((seq, seq + 1)),
    };
    let mut moments = moments.into_iter().peekable();
    for seq in start..end {
        let moment = moments.next_if(|m| m.seq == seq);
        match moment.and_then(|m| Some((m.asked?, m.value?))) {
            Some((step, value)) => answered.push((
                step,
                value.as_evaluation().unwrap_or(Evaluation::NoFeedback),
            )),
            None => lose(seq),
        }
    }
    (answered, lost)
}

/// What an evaluative run checkpoint of a remote session keeps besides the run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ResumeNotes {
    pub numbering: QueryNumbering,
    /// Episodes finished (the session's episode counter, for frames and the recording).
    pub episode: u64,
}

/// When a remote evaluative session saves its run: at the first episode start after every
/// `every` steps, and (people answering) after any episode in which someone answered, so that
/// an env lost mid-episode costs at most that episode's answers.
pub struct CheckpointRule {
    every: u64,
    next_at: u64,
    human: bool,
    answered_since: bool,
}

impl CheckpointRule {
    pub fn new(every: u64, steps: u64, human: bool) -> Self {
        Self {
            every,
            next_at: (steps / every + 1) * every,
            human,
            answered_since: false,
        }
    }

    /// A person answered a query.
    pub fn answered(&mut self) {
        self.answered_since = true;
    }

    /// Whether to save now, at an episode start after `steps` steps.
    pub fn due(&mut self, steps: u64) -> bool {
        let due = steps >= self.next_at || (self.human && self.answered_since);
        if due {
            self.next_at = (steps / self.every + 1) * self.every;
            self.answered_since = false;
        }
        due
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lost_queries_are_skipped_and_the_rest_map_to_the_run() {
        // The run checkpointed after query 4; queries 5..8 were answered and lost.
        let n = QueryNumbering {
            lost: vec![(5, 8)],
            next: 8,
        };
        assert_eq!(n.run_query(4), Some(4));
        assert_eq!(n.run_query(6), None);
        assert_eq!(n.run_query(8), Some(5));
        // A second loss later: 10..12.
        let n = QueryNumbering {
            lost: vec![(5, 8), (10, 12)],
            next: 12,
        };
        assert_eq!(n.run_query(9), Some(6));
        assert_eq!(n.run_query(11), None);
        assert_eq!(n.run_query(12), Some(7));
    }

    fn stored(seq: u64, value: Option<i8>, kept: bool) -> StoredMoment {
        StoredMoment {
            seq,
            step: 20 + seq,
            action: Some(vec![0.5]),
            value: value.map(AnswerValue::Evaluation),
            asked: kept.then(|| AskedStep {
                obs: vec![seq as f32],
                action: vec![0.5],
                reward: -0.5,
                next_obs: vec![0.5],
                terminated: false,
                abstract_state: crate::scene_graph::AbstractState(1),
                predicted: 0.0,
            }),
        }
    }

    #[test]
    fn given_up_queries_are_taken_in_where_answered_with_their_step_and_lost_otherwise() {
        let given_up = GivenUp {
            start: 5,
            end: 11,
            moments: vec![
                stored(5, Some(1), true),
                stored(6, Some(-1), true),
                // 7 and 10 not stored (queries of another kind), 8 stored before steps were
                // kept, 9 left open.
                stored(8, Some(1), false),
                stored(9, None, true),
            ],
        };
        let (answered, lost) = split_given_up(given_up);
        let taken: Vec<(f32, Evaluation)> = answered.iter().map(|(s, e)| (s.obs[0], *e)).collect();
        assert_eq!(taken, vec![(5.0, Evaluation::Good), (6.0, Evaluation::Bad)]);
        assert_eq!(lost, vec![(7, 11)]);
        // Taken in at 5 and 6, the run knows them; 7..11 are skipped.
        let n = QueryNumbering { lost, next: 11 };
        assert_eq!(
            (n.run_query(6), n.run_query(9), n.run_query(11)),
            (Some(6), None, Some(7))
        );
    }

    #[test]
    fn checkpoints_come_every_n_steps_and_after_answered_episodes() {
        let mut rule = CheckpointRule::new(100, 0, true);
        assert!(!rule.due(40));
        rule.answered();
        assert!(rule.due(60));
        assert!(!rule.due(90));
        assert!(rule.due(130));
        assert!(!rule.due(150));
        let mut synthetic = CheckpointRule::new(100, 250, false);
        synthetic.answered();
        assert!(!synthetic.due(280));
        assert!(synthetic.due(300));
    }
}
