//! What a person is shown when asked: the clip leading to an evaluative query with the action
//! taken and the predicates that hold, or a preference pair's two clips (re-simulated from their
//! trajectory's reset seed and actions, since DRPL's pool keeps features, not render states).

use std::collections::VecDeque;

use serde::Serialize;

use crate::guidance::drpl::pool;
use crate::guidance::drpl::trajectories::Trajectory;
use crate::guidance::evaluative_run::AskedStep;
use crate::scene_graph::{AbstractState, Predicate, SceneGraph};
use crate::sim::{Env, EnvFault, EnvOptions, Geometry, RenderState, Task};

/// A short stretch of an episode for a browser to loop.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Clip {
    pub geometry: Geometry,
    pub frames: Vec<RenderState>,
}

/// The body of a query message (the websocket adds `type`, `id`, `seq`, `step`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum QueryContent {
    /// "Was that good?": the clip ends in `s_t`, where the robot took `action`; `holding` are the
    /// labels of the predicates true after it (the scene graph of `(s_{t+1}, a_t)`).
    Evaluative {
        clip: Clip,
        action: Vec<f32>,
        holding: Vec<&'static str>,
        /// The human critic's current estimate of this judgement (for researchers; browsers
        /// need not show it).
        predicted: f32,
    },
    /// "Which is better?" over two clips shown side by side.
    Preference {
        left: Clip,
        right: Clip,
        left_holding: Vec<&'static str>,
        right_holding: Vec<&'static str>,
        /// DRPL's predicate that the two segments differ in (none for the baselines).
        #[serde(skip_serializing_if = "Option::is_none")]
        predicate: Option<Predicate>,
    },
}

/// What the learner saw at a query, kept with it for datasets (`queries.data`): an evaluative
/// query's transition, or a preference query's two segments.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum QueryData {
    Evaluative {
        observation: Vec<f32>,
        /// Normalised to [-1, 1].
        action: Vec<f32>,
        /// The env's reward for the step.
        reward: f32,
        next_observation: Vec<f32>,
    },
    Preference {
        left: SegmentData,
        right: SegmentData,
    },
}

/// What a query keeps besides what people are shown: what the learner saw (datasets), and for
/// a session on an env in another process the step as the run stored it (`query_transitions`),
/// which a run resumed from an earlier checkpoint takes back in once it is answered.
#[derive(Clone, Debug, PartialEq)]
pub struct QueryRecord {
    pub data: QueryData,
    pub asked: Option<AskedStep>,
}

/// One side of a preference query.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct SegmentData {
    pub trajectory: usize,
    pub start: usize,
    /// Exclusive.
    pub end: usize,
    /// Its abstract state (none for windows and whole trajectories).
    pub abstract_state: Option<u32>,
    /// Standardised mean features, as the belief sees them.
    pub features: Vec<f64>,
    /// Mean features before standardisation.
    pub raw_features: Vec<f64>,
}

impl SegmentData {
    pub fn of(clip: &pool::Clip) -> Self {
        Self {
            trajectory: clip.trajectory,
            start: clip.start,
            end: clip.end,
            abstract_state: clip.abstract_state.map(|s| s.0),
            features: clip.features.clone(),
            raw_features: clip.raw_features.clone(),
        }
    }
}

/// The latest frames of the current episode, for the clip of an evaluative query.
pub struct FrameHistory {
    capacity: usize,
    geometry: Option<Geometry>,
    frames: VecDeque<RenderState>,
}

impl FrameHistory {
    pub fn new(capacity: usize) -> Self {
        Self {
            capacity: capacity.max(1),
            geometry: None,
            frames: VecDeque::new(),
        }
    }

    /// A new episode: forget the old frames.
    pub fn start_episode(&mut self, geometry: Geometry, first: RenderState) {
        self.geometry = Some(geometry);
        self.frames.clear();
        self.frames.push_back(first);
    }

    pub fn push(&mut self, frame: RenderState) {
        if self.frames.len() == self.capacity {
            self.frames.pop_front();
        }
        self.frames.push_back(frame);
    }

    pub fn clip(&self) -> Option<Clip> {
        Some(Clip {
            geometry: self.geometry.clone()?,
            frames: self.frames.iter().cloned().collect(),
        })
    }
}

/// Replays `clip`'s steps of `trajectory` in a fresh env: the state before its first step and
/// after each of its steps.
pub fn render_clip(
    task: Task,
    options: &EnvOptions,
    trajectory: &Trajectory,
    clip: &pool::Clip,
) -> Clip {
    let mut env = task.make_env_with(options);
    render_clip_on(env.as_mut(), trajectory, clip).expect("the built-in tasks never fail")
}

/// [`render_clip`] on a given env (one in another process that repeats an episode from its
/// seed), asking it for frames only on the clip's steps.
pub fn render_clip_on(
    env: &mut dyn Env,
    trajectory: &Trajectory,
    clip: &pool::Clip,
) -> Result<Clip, EnvFault> {
    env.set_frames(clip.start == 0);
    env.try_reset(trajectory.reset_seed)?;
    let geometry = env.geometry();
    let mut frames = Vec::with_capacity(clip.len() + 1);
    if clip.start == 0 {
        frames.push(env.render());
    }
    for (i, step) in trajectory.steps[..clip.end].iter().enumerate() {
        env.set_frames(i + 1 >= clip.start);
        env.try_step(&step.action)?;
        if i + 1 >= clip.start {
            frames.push(env.render());
        }
    }
    Ok(Clip { geometry, frames })
}

/// The predicate labels that hold in the clip's abstract state (empty for windows that span
/// several).
pub fn holding(graph: &SceneGraph, state: Option<AbstractState>) -> Vec<&'static str> {
    state.map(|s| graph.holding(s)).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::drpl::trajectories;

    #[test]
    fn history_keeps_the_latest_frames_of_the_episode() {
        let mut env = Task::Reaching.make_env();
        env.reset(3);
        let mut h = FrameHistory::new(3);
        assert!(h.clip().is_none());
        h.start_episode(env.geometry(), env.render());
        for _ in 0..5 {
            env.step(&vec![0.5; env.spec().action_space.dim()]);
            h.push(env.render());
        }
        let clip = h.clip().unwrap();
        assert_eq!(clip.frames.len(), 3);
        assert_eq!(clip.frames[2], env.render());
    }

    #[test]
    fn a_rendered_clip_replays_the_recorded_steps() {
        let graph = SceneGraph::for_task(Task::LunarLander);
        let trajs = trajectories::collect(
            Task::LunarLander,
            &EnvOptions::default(),
            &graph,
            1,
            60,
            &mut trajectories::rng(5),
        );
        let t = &trajs[0];
        let c = pool::Clip {
            trajectory: 0,
            start: 10,
            end: 20,
            abstract_state: None,
            features: vec![],
            raw_features: vec![],
        };
        let clip = render_clip(Task::LunarLander, &EnvOptions::default(), t, &c);
        // The state before step 10, then after each of steps 10..20.
        assert_eq!(clip.frames.len(), 11);
        // The last frame is the state after step 19, whose observation the trajectory recorded.
        let mut env = Task::LunarLander.make_env();
        env.reset(t.reset_seed);
        for s in &t.steps[..20] {
            env.step(&s.action);
        }
        assert_eq!(env.observation(), t.steps[19].next_obs);
        assert_eq!(clip.frames[10], env.render());
    }
}
