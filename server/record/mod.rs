//! Rerun recording of a training session: the scene per step, rewards, the scene-graph
//! predicates, and every query with its answer, on the `step` and `episode` timelines, into an
//! `.rrd` file, a live viewer, or both.
//!
//! The training thread only pushes small events onto a bounded channel ([`Recorder`]); a logging
//! thread owns the `rerun::RecordingStream` and does the encoding and the IO, so the training
//! loop never waits on a disk or a socket unless the logging thread falls a whole channel behind.
//!
//! - `sink`: which `RecordingStream` the options ask for (file, gRPC, or both teed).
//! - `writer`: the logging thread: timelines, scalars, predicates, queries and answers.
//! - `scene`: the task's geometry and render state as Rerun archetypes.
//!
//! ## Timelines
//!
//! `step` (sequence): the 0-based index of the environment step (the transition's index, as
//! `EvaluativeQuery::step`). `episode` (sequence): the 0-based episode index. Everything that is
//! not static is logged on both; queries and answers get the episode in which their step lies.
//!
//! ## Entity paths
//!
//! | path | archetype | when |
//! |---|---|---|
//! | `world` | `ViewCoordinates` (right-handed, z up) | static, Reaching and Placing |
//! | `world/table` | `Boxes3D` (solid) | static per geometry |
//! | `world/goal` | `Boxes3D` (flat, solid) | static, Reaching |
//! | `world/workspace` | `Boxes3D` (wireframe): the safety gate | static, Reaching and Placing |
//! | `world/hoop` | `Boxes3D` (solid): the hoop's walls and top | static, Placing |
//! | `world/hoop/opening` | `LineStrips3D`: the ring | static, Placing |
//! | `world/no_entry` | `Boxes3D` (wireframe) | static, Placing |
//! | `world/gripper` | `Boxes3D` posed (colour: open orange, closed grey) | per step |
//! | `world/ball` | `Points3D` with the ball's radius (colour: held or free) | per step, Placing |
//! | `world/frame` | `EncodedImage` (PNG or JPEG, as the env sent it) | per step it sent one: sessions on a remote env that people watch |
//! | `world/terrain` | `LineStrips2D` | each episode, Lunar Lander |
//! | `world/flags` | `LineStrips2D`: poles and pennants | each episode, Lunar Lander |
//! | `world/lander/hull` | `LineStrips2D`: closed polygon in world coordinates | per step |
//! | `world/lander/legs` | `LineStrips2D`: two rectangles (`[right, left]`, green on contact) | per step |
//! | `world/lander/flames` | `Arrows2D`: exhaust, length = throttle (none when off) | per step |
//! | `engines/main`, `engines/side` | `Scalars`: throttles (side: negative = left) | per step, Lunar Lander |
//! | `gripper/closed` | `Scalars`: 1 closed, 0 open | per step, Placing |
//! | `reward` | `Scalars`: r_t | per step |
//! | `cumulative_return` | `Scalars`: sum of finished episodes' returns | per step |
//! | `predicates/<name>` | `Scalars` 0/1, one per scene-graph predicate (`Predicate::name`); a static `SeriesLines` names it by its label | per step |
//! | `queries` | `TextLog` `#<id> <kind>: <text>` | per query |
//! | `answers` | `TextLog` `#<id> = <value>: <text>` | per answer |
//! | `answers/value` | `Scalars`: the answer's value | per answer |
//!
//! Lunar Lander is a 2D scene in world units with y flipped (`y_view = world_height - y`): a
//! Rerun 2D view draws y downwards, so the flip shows the lander upright, as Gymnasium draws it.

mod scene;
mod sink;
mod writer;

use std::path::PathBuf;
use std::sync::mpsc::{SyncSender, sync_channel};
use std::thread::JoinHandle;

use anyhow::Context;

use crate::scene_graph::{AbstractState, SceneGraph};
use crate::sim::{Geometry, RenderState};

/// Events the logging thread may be behind by before a sender blocks. A step event is about a
/// hundred bytes, so the queue holds at most a few hundred KiB; at thousands of steps per second
/// it absorbs a second of bursts, and when the disk or the viewer is slower than training, the
/// training thread blocks (back-pressure) rather than the memory growing without bound.
const CHANNEL_CAPACITY: usize = 4096;

/// Where a recording goes. Both `None` means recording is off.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RecordingOptions {
    /// An `.rrd` file (its parent directory is created).
    pub path: Option<PathBuf>,
    /// A running viewer's gRPC proxy, e.g. `rerun+http://127.0.0.1:9876/proxy`.
    pub connect: Option<String>,
}

impl RecordingOptions {
    pub fn is_off(&self) -> bool {
        self.path.is_none() && self.connect.is_none()
    }
}

/// One thing to log, owned so that it can cross to the logging thread.
enum Event {
    EpisodeStart {
        episode: u64,
        step: u64,
        geometry: Geometry,
    },
    Step {
        step: u64,
        episode: u64,
        state: RenderState,
        reward: f32,
        cumulative_return: f64,
        abstract_state: AbstractState,
    },
    Query {
        step: u64,
        query_id: i64,
        kind: String,
        text: String,
    },
    Answer {
        step: u64,
        query_id: i64,
        value: f64,
        text: String,
    },
}

/// A handle on a session's recording. Its methods only queue an event for the logging thread;
/// when the queue is full they block until the thread catches up (bounded memory).
pub struct Recorder {
    events: Option<SyncSender<Event>>,
    thread: Option<JoinHandle<anyhow::Result<()>>>,
}

impl Recorder {
    /// Open the recording and start its logging thread; `None` when `options` turn it off.
    /// `recording_name` (e.g. the session id) is both the recording id, so that a resumed
    /// session's recordings merge in the viewer, and its displayed name.
    pub fn start(
        application: &str,
        recording_name: &str,
        scene_graph: SceneGraph,
        options: &RecordingOptions,
    ) -> anyhow::Result<Option<Recorder>> {
        let Some(stream) = sink::open(application, recording_name, options)? else {
            return Ok(None);
        };
        let (events, receiver) = sync_channel(CHANNEL_CAPACITY);
        let thread = std::thread::Builder::new()
            .name(format!("record {recording_name}"))
            .spawn(move || writer::Writer::new(stream, scene_graph)?.run(receiver))
            .context("spawning the recording thread")?;
        Ok(Some(Recorder {
            events: Some(events),
            thread: Some(thread),
        }))
    }

    /// An episode begins at `step` with `geometry` (what stays fixed while it runs).
    pub fn episode_start(&self, episode: u64, step: u64, geometry: &Geometry) {
        self.send(Event::EpisodeStart {
            episode,
            step,
            geometry: geometry.clone(),
        });
    }

    /// Step `step` of `episode` took the scene to `state`, earned `reward`, and its
    /// `(s_{t+1}, a_t)` evaluates to `abstract_state`.
    pub fn step(
        &self,
        step: u64,
        episode: u64,
        state: &RenderState,
        reward: f32,
        cumulative_return: f64,
        abstract_state: AbstractState,
    ) {
        self.send(Event::Step {
            step,
            episode,
            state: state.clone(),
            reward,
            cumulative_return,
            abstract_state,
        });
    }

    /// Query `query_id` of `kind` (`evaluative`, `preference`) was asked about `step`.
    pub fn query(&self, step: u64, query_id: i64, kind: &str, text: String) {
        self.send(Event::Query {
            step,
            query_id,
            kind: kind.to_owned(),
            text,
        });
    }

    /// Query `query_id` (about `step`) was answered with `value`.
    pub fn answer(&self, step: u64, query_id: i64, value: f64, text: String) {
        self.send(Event::Answer {
            step,
            query_id,
            value,
            text,
        });
    }

    /// Log everything queued, flush the sinks (the file gets its footer), and join the
    /// logging thread. Returns the first error the thread met; a live viewer that cannot be
    /// reached is one (after the gRPC sink's 5 s connect timeout), and the file is complete
    /// all the same.
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.close()
    }

    fn send(&self, event: Event) {
        // The thread drains the channel until every sender is gone, even after a logging
        // error, so a send fails only if it panicked; that surfaces in `finish`.
        if let Some(events) = &self.events {
            let _ = events.send(event);
        }
    }

    fn close(&mut self) -> anyhow::Result<()> {
        // Dropping the sender ends the thread's receive loop.
        drop(self.events.take());
        match self.thread.take() {
            Some(thread) => thread
                .join()
                .map_err(|_| anyhow::anyhow!("the recording thread panicked"))?,
            None => Ok(()),
        }
    }
}

impl Drop for Recorder {
    /// A recorder dropped without `finish` (a session that failed) still leaves a complete file.
    fn drop(&mut self) {
        let _ = self.close();
    }
}
