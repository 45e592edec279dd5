//! The `Env` trait: Gymnasium's reset/step contract, with the sizes and bounds as data and a
//! render state for the browser and the recorder.

use serde::{Deserialize, Serialize};

use super::frame::ImageFrame;

/// A box-shaped space (Gymnasium's `Box`): per-dimension lower and upper bounds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoxSpace {
    pub low: Vec<f32>,
    pub high: Vec<f32>,
}

impl BoxSpace {
    /// A space whose every dimension lies in `[low, high]`.
    pub fn uniform(dim: usize, low: f32, high: f32) -> Self {
        Self {
            low: vec![low; dim],
            high: vec![high; dim],
        }
    }

    pub fn dim(&self) -> usize {
        self.low.len()
    }

    /// Clip `x` in place into the space.
    pub fn clip(&self, x: &mut [f32]) {
        for ((v, lo), hi) in x.iter_mut().zip(&self.low).zip(&self.high) {
            *v = v.clamp(*lo, *hi);
        }
    }
}

/// What does not change while an episode runs: sizes, bounds and timing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EnvSpec {
    /// Stable identifier, as the CLI and the API spell it (`lunar-lander`).
    pub id: &'static str,
    pub observation_space: BoxSpace,
    /// Actions the learner emits are always in `[-1, 1]`; the env scales them.
    pub action_space: BoxSpace,
    /// Human-readable name of every observation dimension, in order.
    pub observation_names: Vec<&'static str>,
    /// Human-readable name of every action dimension, in order.
    pub action_names: Vec<&'static str>,
    /// Episode length limit, in steps, counting the steps a reset spends (Placing, Reaching).
    pub max_episode_steps: u32,
    /// Control rate: agent steps per simulated second.
    pub control_hz: f32,
}

/// How an episode ended, beyond Gymnasium's two flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The task was achieved (goal reached, ball through the ring, lander at rest on the pad).
    Success,
    /// The episode terminated without success (crash, ball dropped, gripper hit the hoop).
    Failure,
    /// The time limit was reached.
    TimeLimit,
}

impl Outcome {
    /// The name files and the API use (as serde writes it).
    pub fn id(self) -> &'static str {
        match self {
            Outcome::Success => "success",
            Outcome::Failure => "failure",
            Outcome::TimeLimit => "time_limit",
        }
    }
}

/// The result of one `Env::step`, with Gymnasium's meaning of the flags: `terminated` is a true
/// end of the MDP (bootstrap stops), `truncated` is the time limit (bootstrap continues).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Step {
    pub obs: Vec<f32>,
    pub reward: f32,
    pub terminated: bool,
    pub truncated: bool,
    /// Set on the last step of an episode.
    pub outcome: Option<Outcome>,
}

impl Step {
    pub fn done(&self) -> bool {
        self.terminated || self.truncated
    }
}

/// A rigid body's pose in the plane (Lunar Lander), in world units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    pub x: f32,
    pub y: f32,
    pub angle: f32,
}

/// A rigid body's pose in space (Placing and Reaching), position plus unit quaternion (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose3 {
    pub position: [f32; 3],
    pub rotation: [f32; 4],
}

/// An axis-aligned box in space: centre and half extents.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cuboid {
    pub center: [f32; 3],
    pub half_extents: [f32; 3],
}

/// What stays fixed during an episode and is drawn once: table, goal, hoop, terrain, flags.
/// Lunar Lander's terrain is new at every reset, so ask again after `reset`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "task", rename_all = "kebab-case")]
pub enum Geometry {
    Reaching {
        /// Table top (z of the top surface is `table.center[2] + table.half_extents[2]`).
        table: Cuboid,
        /// Goal area on the table, as a rectangle `[x_min, y_min, x_max, y_max]`.
        goal: [f32; 4],
        /// The safety gate's rectangle `[x_min, y_min, x_max, y_max]`.
        workspace: [f32; 4],
    },
    Placing {
        table: Cuboid,
        /// The hoop's solid parts (walls and the top around the opening), as boxes.
        hoop_parts: Vec<Cuboid>,
        /// The opening in the hoop's top, `[x_min, y_min, x_max, y_max]` at `hoop_top_z`.
        opening: [f32; 4],
        hoop_top_z: f32,
        ball_radius: f32,
        /// The grip level at or below which the ball drops (`RenderState::Placing::grip_level`).
        #[serde(default = "fully_open")]
        release_level: f32,
        /// The safety gate's workspace `[x_min, y_min, z_min, x_max, y_max, z_max]`.
        workspace: [f32; 6],
        /// The no-entry box under and beside the hoop, same layout as `workspace`.
        no_entry: [f32; 6],
    },
    /// An environment in another process (`remote_env`): nothing to draw but its own frames.
    Remote {
        /// The id it declared (`LunarLanderContinuous-v3`, `my-robot`).
        env: String,
        /// Width and height of its frames (the episode's first), when it sends frames.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        frame_size: Option<[u32; 2]>,
    },
    LunarLander {
        /// World size in units (20 x 13.333).
        world: [f32; 2],
        /// Terrain polyline, left to right, in world units.
        terrain: Vec<[f32; 2]>,
        /// Flag poles: x of each pole, the pad's y, and pole height.
        flags: [[f32; 2]; 2],
        flag_height: f32,
        /// Hull polygon in body coordinates (world units).
        hull: Vec<[f32; 2]>,
        /// Leg half sizes (width, height) in world units.
        leg_half_extents: [f32; 2],
    },
}

/// Everything that moves, per step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "task", rename_all = "kebab-case")]
pub enum RenderState {
    Reaching {
        gripper: Pose3,
    },
    Placing {
        gripper: Pose3,
        gripper_closed: bool,
        /// The gripper's integrated command c: +1 closed, -1 fully open; the ball drops at the
        /// geometry's `release_level`.
        #[serde(default = "closed")]
        grip_level: f32,
        ball: [f32; 3],
        /// True while the ball is held by the gripper.
        ball_held: bool,
    },
    LunarLander {
        hull: Pose2,
        /// Legs as `[right, left]` (the order of the observation's contact flags).
        legs: [Pose2; 2],
        leg_contact: [bool; 2],
        /// Main engine throttle this step, 0 when off.
        main_engine: f32,
        /// Side engine throttle this step: negative fires the left engine, positive the right.
        side_engine: f32,
    },
    /// An environment in another process: the frame it rendered, if it was asked for one (people
    /// watch) and can render, and its observation.
    Remote {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        frame: Option<ImageFrame>,
        observation: Vec<f32>,
    },
}

/// Why an environment could not answer: one in another process that is unreachable, too slow,
/// sends what the protocol does not allow, or went away. The built-in tasks never fail.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct EnvFault(pub String);

/// A simulated task. Deterministic: the same seed and the same actions give bit-identical
/// observations and rewards.
pub trait Env: Send {
    fn spec(&self) -> &EnvSpec;

    /// Start a new episode from `seed` and return the first observation.
    fn reset(&mut self, seed: u64) -> Vec<f32>;

    /// Advance one control step. `action` has `spec().action_space.dim()` entries and is clipped
    /// to `[-1, 1]`. Calling `step` after the episode ended is a programming error (panics).
    fn step(&mut self, action: &[f32]) -> Step;

    /// The current observation (the one the last `reset` or `step` returned).
    fn observation(&self) -> Vec<f32>;

    /// Steps taken in this episode, including those the reset spent.
    fn elapsed_steps(&self) -> u32;

    fn render(&self) -> RenderState;

    fn geometry(&self) -> Geometry;

    /// `reset` for callers that may hold an env that can fail (one in another process); the
    /// built-in tasks never do.
    fn try_reset(&mut self, seed: u64) -> Result<Vec<f32>, EnvFault> {
        Ok(self.reset(seed))
    }

    /// `step` for callers that may hold an env that can fail. After an `Err` the episode is
    /// lost: reset (or reconnect) before stepping again.
    fn try_step(&mut self, action: &[f32]) -> Result<Step, EnvFault> {
        Ok(self.step(action))
    }

    /// The scene-graph predicates that hold after the last step, bit `i` for declared predicate
    /// `i`, when the env evaluates its own scene graph (an env in another process that declared
    /// predicates); `None`: the task's graph is evaluated on the observation.
    fn reported_predicates(&self) -> Option<u32> {
        None
    }

    /// DRPL's features phi of the last step, when the env computes them itself.
    fn reported_features(&self) -> Option<&[f64]> {
        None
    }

    /// Render with every later reset and step (`render` then shows it): an env that sends
    /// images from another process does so only while asked, since a frame costs it more than
    /// a step. The built-in tasks' render states cost nothing, and they ignore this.
    fn set_frames(&mut self, _on: bool) {}
}

/// Serde defaults for render files written before the gradual gripper existed.
fn fully_open() -> f32 {
    -1.0
}

fn closed() -> f32 {
    1.0
}
