//! Placing: carry a grasped ball over the hoop and drop it through the ring in its top.
//!
//! - obs = gripper (x, y, z, g), g = +1 closed, -1 open (the last gripper command).
//! - action in `[-1, 1]^4`: (dx, dy, dz) moves up to 2 cm per 50 ms step, the fourth entry
//!   opens the gripper when negative.
//! - Safety gate \[authors\]: the xyz move is zeroed if `gripper + 0.07 * a_xyz` leaves the
//!   workspace or enters the no-entry box under and beside the hoop (see `hoop`).
//! - Reset: a uniform start above z = 1.05, then 50 random moves with the gripper closed that
//!   count toward the 1000-step horizon. A reset whose random moves touch the hoop is redrawn
//!   (new start, same seed stream): an episode never starts in a failure.
//! - While held, the ball's centre is the gripper point. Opening releases it as a dynamic
//!   rapier body with the gripper's velocity of that step; closing again does not re-grasp.
//!   The released ball is simulated with 10 substeps of 5 ms per step, so the 2.5 cm ball moves
//!   at most ~2 cm per substep even after the tallest drop and cannot tunnel through the 1 cm
//!   plates (their contact band is 6 cm deep).
//! - Success (+100) when the free ball's centre passes below the hoop's top (z = 1.0) over the
//!   opening. Failure (0) when it passes below elsewhere, touches the table or a hoop wall, or
//!   has not gone through 2 s after release (e.g. it rests on the top plates); and when the
//!   gripper's contact volume (a ball-sized sphere around the gripper point) touches the hoop.
//!   Contacts are shape-intersection queries against the rapier world.

mod heuristic;
mod hoop;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::prelude::RigidBodyHandle;

use super::tabletop::{
    self, CONTROL_DT, CONTROL_HZ, MAX_EPISODE_STEPS, Part, TableWorld, clip_action, gated_move,
};
use super::{BoxSpace, Env, EnvSpec, Geometry, Outcome, RenderState, Step};
pub use heuristic::heuristic;
pub use hoop::{
    BALL_RADIUS, HOOP_HALF_X, HOOP_HALF_Y, HOOP_TOP_Z, LOOKAHEAD, OPENING_HALF, START_MIN_Z,
    STEP_SIZE, over_opening,
};
use hoop::{NO_ENTRY, WORKSPACE, gate_allows};

/// Steps the reset spends on random moves (they count toward the horizon).
pub const RESET_STEPS: u32 = 50;
/// Physics substeps per control step while the ball is free.
pub const SUBSTEPS: u32 = 10;
const SUBSTEP_DT: f32 = CONTROL_DT / SUBSTEPS as f32;
/// A released ball that has not gone through after this long is a failed drop.
pub const RELEASE_TIMEOUT_S: f32 = 2.0;
/// `RELEASE_TIMEOUT_S` in substeps (counted in integers so the cut is exact).
const RELEASE_TIMEOUT_SUBSTEPS: u32 = 40 * SUBSTEPS;

/// What the gripper must not touch.
const HOOP: [Part; 2] = [Part::HoopWall, Part::HoopTop];
/// What a free ball must not touch (the top plates are fine: it may bounce off the ring).
const DROPPED_ON: [Part; 2] = [Part::Table, Part::HoopWall];

pub struct Placing {
    spec: EnvSpec,
    world: TableWorld,
    /// The ball's dynamic body once released; `None` while the gripper holds it.
    ball: Option<RigidBodyHandle>,
    gripper_closed: bool,
    /// Physics substeps since the release.
    free_substeps: u32,
    elapsed: u32,
    done: bool,
}

impl Placing {
    pub fn new() -> Self {
        let spec = EnvSpec {
            id: "placing",
            observation_space: BoxSpace {
                low: vec![WORKSPACE.lo[0], WORKSPACE.lo[1], WORKSPACE.lo[2], -1.0],
                high: vec![WORKSPACE.hi[0], WORKSPACE.hi[1], WORKSPACE.hi[2], 1.0],
            },
            action_space: BoxSpace::uniform(4, -1.0, 1.0),
            observation_names: vec!["gripper_x", "gripper_y", "gripper_z", "gripper_closed"],
            action_names: vec!["dx", "dy", "dz", "gripper"],
            max_episode_steps: MAX_EPISODE_STEPS,
            control_hz: CONTROL_HZ,
        };
        // Until the first reset: the gripper holding the ball high behind the hoop, not started.
        Self {
            spec,
            world: Self::build_world([-0.4, 0.0, 1.3]),
            ball: None,
            gripper_closed: true,
            free_substeps: 0,
            elapsed: 0,
            done: true,
        }
    }

    fn build_world(gripper: [f32; 3]) -> TableWorld {
        let mut world = TableWorld::new(&hoop::table(), gripper, SUBSTEP_DT);
        hoop::add_to(&mut world);
        world.refresh();
        world
    }

    /// Simulate the free ball for one control step; the outcome it decides, if any.
    fn simulate_ball(&mut self, ball: RigidBodyHandle) -> Option<Outcome> {
        for _ in 0..SUBSTEPS {
            self.world.step();
            self.free_substeps += 1;
            let p = self.world.body_position(ball);
            if p[2] < HOOP_TOP_Z {
                return Some(if over_opening(p[0], p[1]) {
                    Outcome::Success
                } else {
                    Outcome::Failure
                });
            }
            if self.world.touching(p, BALL_RADIUS, &DROPPED_ON)
                || self.free_substeps >= RELEASE_TIMEOUT_SUBSTEPS
            {
                return Some(Outcome::Failure);
            }
        }
        None
    }

    fn ball_position(&self) -> [f32; 3] {
        match self.ball {
            Some(b) => self.world.body_position(b),
            None => self.world.gripper(),
        }
    }
}

impl Default for Placing {
    fn default() -> Self {
        Self::new()
    }
}

impl Env for Placing {
    fn spec(&self) -> &EnvSpec {
        &self.spec
    }

    fn reset(&mut self, seed: u64) -> Vec<f32> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut world = Self::build_world([0.0, 0.0, 1.3]);
        let start = 'draw: loop {
            let mut p = [
                rng.random_range(WORKSPACE.lo[0]..WORKSPACE.hi[0]),
                rng.random_range(WORKSPACE.lo[1]..WORKSPACE.hi[1]),
                rng.random_range(START_MIN_Z..WORKSPACE.hi[2]),
            ];
            // The ranges are half open; the gate's workspace is open on both sides.
            if !WORKSPACE.contains(&p) || NO_ENTRY.contains(&p) {
                continue;
            }
            for _ in 0..RESET_STEPS {
                let a: [f32; 3] = std::array::from_fn(|_| rng.random_range(-1.0..=1.0));
                p = gated_move(p, a, STEP_SIZE, LOOKAHEAD, gate_allows);
                if world.touching(p, BALL_RADIUS, &HOOP) {
                    continue 'draw;
                }
            }
            break p;
        };
        world.set_gripper(start);
        self.world = world;
        self.ball = None;
        self.gripper_closed = true;
        self.free_substeps = 0;
        self.elapsed = RESET_STEPS;
        self.done = false;
        self.observation()
    }

    fn step(&mut self, action: &[f32]) -> Step {
        assert!(
            !self.done,
            "step called after the episode ended; call reset"
        );
        let a = clip_action::<4>(action);
        let from = self.world.gripper();
        let to = gated_move(from, [a[0], a[1], a[2]], STEP_SIZE, LOOKAHEAD, gate_allows);
        self.gripper_closed = a[3] >= 0.0;
        if self.ball.is_none() && !self.gripper_closed {
            // Released at the start of the step, moving as the gripper moves during it.
            let v = std::array::from_fn(|i| (to[i] - from[i]) / CONTROL_DT);
            self.ball = Some(self.world.add_ball(from, v, BALL_RADIUS));
        }
        self.world.set_gripper(to);
        // The physics runs only while a ball is free: a held ball just follows the gripper.
        let mut event = self.ball.and_then(|b| self.simulate_ball(b));
        if self.world.touching(to, BALL_RADIUS, &HOOP) {
            event = Some(Outcome::Failure);
        }
        self.elapsed += 1;
        let step = tabletop::make_step(self.observation(), self.elapsed, event);
        self.done = step.done();
        step
    }

    fn observation(&self) -> Vec<f32> {
        let [x, y, z] = self.world.gripper();
        vec![x, y, z, if self.gripper_closed { 1.0 } else { -1.0 }]
    }

    fn elapsed_steps(&self) -> u32 {
        self.elapsed
    }

    fn render(&self) -> RenderState {
        RenderState::Placing {
            gripper: tabletop::upright(self.world.gripper()),
            gripper_closed: self.gripper_closed,
            ball: self.ball_position(),
            ball_held: self.ball.is_none(),
        }
    }

    fn geometry(&self) -> Geometry {
        Geometry::Placing {
            table: hoop::table(),
            hoop_parts: hoop::parts(),
            opening: [-OPENING_HALF, -OPENING_HALF, OPENING_HALF, OPENING_HALF],
            hoop_top_z: HOOP_TOP_Z,
            ball_radius: BALL_RADIUS,
            workspace: [
                WORKSPACE.lo[0],
                WORKSPACE.lo[1],
                WORKSPACE.lo[2],
                WORKSPACE.hi[0],
                WORKSPACE.hi[1],
                WORKSPACE.hi[2],
            ],
            no_entry: [
                NO_ENTRY.lo[0],
                NO_ENTRY.lo[1],
                NO_ENTRY.lo[2],
                NO_ENTRY.hi[0],
                NO_ENTRY.hi[1],
                NO_ENTRY.hi[2],
            ],
        }
    }
}
