//! Who compares a preference session's pairs: people, shown the two segments' clips (replayed
//! on our task or on the session's remote env), or the synthetic teacher; both through the
//! session's [`Asker`], which stores every query and answer.

use super::asker::Asker;
use super::error::SessionError;
use super::events::{AnswerValue, QueryKind};
use super::query::{self, QueryContent, QueryData, QueryRecord, SegmentData};
use super::remote::Reconnect;
use crate::guidance::drpl::pool::Clip;
use crate::guidance::drpl::simulated_teacher::SimulatedTeacher;
use crate::guidance::drpl::trainer::{Preference, PreferenceQuery, PreferenceTrainer};
use crate::guidance::drpl::trajectories::Trajectory;
use crate::scene_graph::SceneGraph;
use crate::sim::{Env, EnvOptions, Task};

/// Where a human preference session replays its clips: a new env of our task, or a
/// connection of its own to the remote env the trajectories were recorded on.
pub(super) enum ClipEnv {
    Builtin {
        task: Task,
        /// The task's version, to replay the clips in the env they were recorded in.
        options: EnvOptions,
    },
    Remote {
        reconnect: Reconnect,
        /// Opened at the first query.
        env: Option<Box<dyn Env>>,
    },
}

impl ClipEnv {
    fn render(
        &mut self,
        trajectory: &Trajectory,
        clip: &Clip,
    ) -> Result<query::Clip, SessionError> {
        match self {
            ClipEnv::Builtin { task, options } => {
                Ok(query::render_clip(*task, options, trajectory, clip))
            }
            ClipEnv::Remote { reconnect, env } => {
                if env.is_none() {
                    *env = Some(reconnect()?);
                }
                let on = env.as_deref_mut().expect("connected above");
                query::render_clip_on(on, trajectory, clip).map_err(|e| {
                    // A broken connection is not used again.
                    *env = None;
                    SessionError::ClipReplay(e)
                })
            }
        }
    }
}

/// Who compares a preference session's pairs.
pub(super) enum Comparer {
    Human {
        clips: ClipEnv,
        graph: SceneGraph,
        trajectories: Vec<Trajectory>,
    },
    Synthetic {
        /// Boxed: a myopic teacher carries a copy of the pool's features.
        oracle: Box<SimulatedTeacher>,
        graph: SceneGraph,
    },
}

pub(super) struct PreferenceAsker {
    pub(super) asker: Asker,
    pub(super) comparer: Comparer,
}

impl PreferenceTrainer for PreferenceAsker {
    fn compare(&mut self, q: &PreferenceQuery<'_>) -> Preference {
        let state = q.left.abstract_state.map_or(0, |s| s.0);
        match &mut self.comparer {
            Comparer::Human {
                clips,
                graph,
                trajectories,
            } => self
                .asker
                .ask(
                    q.query as u64,
                    state,
                    QueryKind::Preference,
                    describe_preference(graph, q),
                    || {
                        let content = QueryContent::Preference {
                            left: clips.render(&trajectories[q.left.trajectory], q.left)?,
                            right: clips.render(&trajectories[q.right.trajectory], q.right)?,
                            left_holding: query::holding(graph, q.left.abstract_state),
                            right_holding: query::holding(graph, q.right.abstract_state),
                            predicate: q.predicate.map(|i| graph.predicates()[i]),
                        };
                        Ok((content, segments(q)))
                    },
                )
                .and_then(AnswerValue::as_preference)
                .unwrap_or(Preference::Skip),
            Comparer::Synthetic { oracle, graph } => {
                let p = oracle.compare(q);
                let describe = if self.asker.observer.is_some() {
                    describe_preference(graph, q)
                } else {
                    String::new()
                };
                self.asker.report(
                    q.query as u64,
                    state,
                    QueryKind::Preference,
                    describe,
                    AnswerValue::Preference(p),
                    segments(q),
                );
                p
            }
        }
    }
}

/// A preference query's two segments, for datasets.
fn segments(q: &PreferenceQuery<'_>) -> QueryRecord {
    QueryRecord {
        data: QueryData::Preference {
            left: SegmentData::of(q.left),
            right: SegmentData::of(q.right),
        },
        asked: None,
    }
}

/// A preference query in words, for the recording.
fn describe_preference(graph: &SceneGraph, q: &PreferenceQuery<'_>) -> String {
    let differ = q
        .predicate
        .map(|i| format!(" (they differ in \"{}\")", graph.predicates()[i].label))
        .unwrap_or_default();
    format!(
        "query {}: trajectory {} steps {}..{} or trajectory {} steps {}..{}?{differ}",
        q.query,
        q.left.trajectory,
        q.left.start,
        q.left.end,
        q.right.trajectory,
        q.right.start,
        q.right.end
    )
}
