//! The logging thread: receives the recorder's events in order, sets the `step` and `episode`
//! timelines, logs the scene (through `scene`), the scalars, the predicates, the queries and the
//! answers, and flushes the stream when the last sender is gone.

use std::sync::mpsc::Receiver;
use std::time::Duration;

use anyhow::Context;
use rerun::{RecordingStream, Scalars, SeriesLines, TextLog, TextLogLevel};

use super::Event;
use super::scene::{self, Scene};
use crate::scene_graph::SceneGraph;
use crate::sim::Geometry;

pub(super) const STEP: &str = "step";
pub(super) const EPISODE: &str = "episode";

/// How long `finish` waits for the sinks. A file flushes in well under a second; a live viewer
/// that went away must not hang the end of a session.
const FLUSH_TIMEOUT: Duration = Duration::from_secs(30);

pub(super) struct Writer {
    rec: RecordingStream,
    graph: SceneGraph,
    scene: Scene,
    /// The last geometry logged as static, so that identical episodes do not repeat it.
    static_geometry: Option<Geometry>,
    episodes: EpisodeIndex,
}

/// `(first step, episode)` of every episode started, ascending: which episode a query's step
/// lies in. Grows by one entry per episode, not per step.
#[derive(Default)]
struct EpisodeIndex(Vec<(u64, u64)>);

impl EpisodeIndex {
    /// Remember where `episode` starts. A session resumed from a checkpoint may restart at an
    /// earlier step; the entries after it belong to the abandoned future and are dropped.
    fn start(&mut self, step: u64, episode: u64) {
        let keep = self.0.partition_point(|&(s, _)| s < step);
        self.0.truncate(keep);
        self.0.push((step, episode));
    }

    /// The episode in which `step` lies, if one had started by then.
    fn of(&self, step: u64) -> Option<u64> {
        let i = self.0.partition_point(|&(s, _)| s <= step);
        i.checked_sub(1).map(|i| self.0[i].1)
    }
}

impl Writer {
    /// Take over `rec` and log what never changes: axes, and the series' display names.
    pub(super) fn new(rec: RecordingStream, graph: SceneGraph) -> anyhow::Result<Self> {
        // The table-top tasks are 3D; Lunar Lander and a remote env's frames are 2D.
        if matches!(
            graph,
            SceneGraph::Reaching | SceneGraph::Placing | SceneGraph::PlacingAsRun
        ) {
            scene::log_view_coordinates(&rec)?;
        }
        for predicate in graph.predicates() {
            rec.log_static(
                predicate_path(predicate.name),
                &SeriesLines::new().with_names([predicate.label]),
            )?;
        }
        rec.log_static("reward", &SeriesLines::new().with_names(["reward"]))?;
        rec.log_static(
            "cumulative_return",
            &SeriesLines::new().with_names(["cumulative return"]),
        )?;
        rec.log_static("answers/value", &SeriesLines::new().with_names(["answer"]))?;
        Ok(Self {
            rec,
            graph,
            scene: Scene::default(),
            static_geometry: None,
            episodes: EpisodeIndex::default(),
        })
    }

    /// Log every event until the recorder is dropped, then flush. A failed event does not stop
    /// the loop (the channel must keep draining or the training thread would block on it); the
    /// first error is returned at the end.
    pub(super) fn run(mut self, events: Receiver<Event>) -> anyhow::Result<()> {
        let mut first_error = None;
        for event in events {
            if let Err(e) = self.handle(event) {
                first_error.get_or_insert(e);
            }
        }
        let flushed = self
            .rec
            .flush_with_timeout(FLUSH_TIMEOUT)
            .context("flushing the recording");
        // Dropping the last handle shuts the sinks down; the file sink writes its footer then.
        drop(self.rec);
        match first_error {
            Some(e) => Err(e),
            None => flushed,
        }
    }

    fn handle(&mut self, event: Event) -> anyhow::Result<()> {
        match event {
            Event::EpisodeStart {
                episode,
                step,
                geometry,
            } => {
                self.episodes.start(step, episode);
                self.set_time(step, Some(episode));
                if scene::is_static(&geometry) {
                    if self.static_geometry.as_ref() == Some(&geometry) {
                        return Ok(());
                    }
                    self.scene.log_geometry(&self.rec, &geometry)?;
                    self.static_geometry = Some(geometry);
                } else {
                    self.scene.log_geometry(&self.rec, &geometry)?;
                }
            }
            Event::Step {
                step,
                episode,
                state,
                reward,
                cumulative_return,
                abstract_state,
            } => {
                self.set_time(step, Some(episode));
                self.scene.log_state(&self.rec, &state)?;
                self.rec
                    .log("reward", &Scalars::single(f64::from(reward)))?;
                self.rec
                    .log("cumulative_return", &Scalars::single(cumulative_return))?;
                for (i, predicate) in self.graph.predicates().iter().enumerate() {
                    let holds = f64::from(u8::from(abstract_state.bit(i)));
                    self.rec
                        .log(predicate_path(predicate.name), &Scalars::single(holds))?;
                }
            }
            Event::Query {
                step,
                query_id,
                kind,
                text,
            } => {
                self.set_time(step, self.episodes.of(step));
                self.rec.log(
                    "queries",
                    &TextLog::new(format!("#{query_id} {kind}: {text}"))
                        .with_level(TextLogLevel::INFO),
                )?;
            }
            Event::Answer {
                step,
                query_id,
                value,
                text,
            } => {
                self.set_time(step, self.episodes.of(step));
                self.rec.log(
                    "answers",
                    &TextLog::new(format!("#{query_id} = {value}: {text}"))
                        .with_level(TextLogLevel::INFO),
                )?;
                self.rec.log("answers/value", &Scalars::single(value))?;
            }
        }
        Ok(())
    }

    fn set_time(&self, step: u64, episode: Option<u64>) {
        self.rec.set_time_sequence(STEP, sequence(step));
        match episode {
            Some(e) => self.rec.set_time_sequence(EPISODE, sequence(e)),
            None => self.rec.disable_timeline(EPISODE),
        }
    }
}

/// `predicates/<name>`: the name is snake_case, a valid entity path part as it is.
fn predicate_path(name: &str) -> String {
    format!("predicates/{name}")
}

/// Rerun's sequence timelines are `i64`; steps and episodes never reach 2^63.
fn sequence(n: u64) -> i64 {
    i64::try_from(n).unwrap_or(i64::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_belongs_to_the_last_episode_started_at_or_before_it() {
        let mut index = EpisodeIndex::default();
        assert_eq!(index.of(0), None);
        index.start(0, 0);
        index.start(120, 1);
        index.start(300, 2);
        assert_eq!(
            [0, 119, 120, 299, 300, 10_000].map(|s| index.of(s)),
            [Some(0), Some(0), Some(1), Some(1), Some(2), Some(2)]
        );
        // Resumed from a checkpoint at step 200: the abandoned episode 2 is forgotten.
        index.start(200, 1);
        assert_eq!(index.of(250), Some(1));
        assert_eq!(index.0.len(), 3);
    }
}
