//! Placing: carry a grasped ball over the hoop and drop it through the ring in its top.
//!
//! Two versions (tasks.md), chosen by [`EnvOptions`]:
//!
//! - **Authors'** (the default, after their robosuite `ball_basket.py`): the gripper starts at the
//!   robot's home pose (-0.315, 0, 1.00) holding the ball, then 50 reset moves of 5 % of full
//!   scale with the gripper closed; a full action moves it 1.2 cm. The gripper opens gradually:
//!   an integrated command c in [-1, 1], +1 (closed) at reset, moves by 0.01 * sign(a3) per
//!   step, and the ball drops once c <= `release_at` (twelve net "open" steps by default).
//!   Success \[authors\]: the ball is released while its centre is over the opening and above
//!   the ring; +100 and the episode ends at once. A release anywhere else ends it with 0.
//! - **Uniform** (the first version): a uniform start above z = 1.05 and 50 full-size random
//!   moves, 2 cm per step, the ball released by the first "open" command; success when the
//!   released ball falls through the ring (`success = "through"`).
//!
//! Shared by both:
//! - obs = gripper (x, y, z, g): g = -1 if the last gripper command was "open" (a3 < 0), else +1
//!   \[authors: robosuite observes only that sign\]; `observe_grip = "level"` puts c there.
//! - action in `[-1, 1]^4`: (dx, dy, dz) and the gripper command a3.
//! - Safety gate \[authors\]: the xyz move is zeroed if `gripper + 0.07 * a_xyz` leaves the
//!   workspace or enters the no-entry box under and beside the hoop (see `hoop`).
//! - A reset whose random moves touch the hoop is redrawn (same seed stream): an episode never
//!   starts in a failure.
//! - `success = "through"`: opening releases the ball as a dynamic rapier body with the
//!   gripper's velocity of that step; closing again does not re-grasp. The released ball is
//!   simulated with 10 substeps of 5 ms per step, so the 2.5 cm ball moves at most ~2 cm per
//!   substep even after the tallest drop and cannot tunnel through the 1 cm plates (their
//!   contact band is 6 cm deep). Success when its centre passes below the hoop's top (z = 1.0)
//!   over the opening; failure when it passes below elsewhere, touches the table or a hoop
//!   wall, or has not gone through 2 s after release (e.g. it rests on the top plates).
//! - Failure (0) when the gripper's contact volume (a ball-sized sphere around the gripper
//!   point) touches the hoop. Contacts are shape-intersection queries against the rapier world.

mod heuristic;
mod hoop;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::prelude::RigidBodyHandle;

use super::tabletop::{
    self, CONTROL_DT, CONTROL_HZ, MAX_EPISODE_STEPS, Part, TableWorld, clip_action, gated_move,
};
use super::{
    BoxSpace, Env, EnvOptions, EnvSpec, Geometry, GripObservation, HoopShape, Outcome,
    PlacingSuccess, RenderState, Start, Step, Variant,
};
pub use heuristic::heuristic;
pub use hoop::{
    BALL_RADIUS, HOME, HOOP_HALF_X, HOOP_HALF_Y, HOOP_TOP_Z, LOOKAHEAD, OPENING_HALF, START_MIN_Z,
    STEP_SIZE, UNIFORM_STEP_SIZE, over_opening,
};
use hoop::{NO_ENTRY, WORKSPACE, gate_allows};

/// Steps the reset spends on random moves (they count toward the horizon).
pub const RESET_STEPS: u32 = 50;
/// Size of the authors' reset moves, as a fraction of a full action.
const RESET_ACTION: f32 = 0.05;
/// How far one gripper command moves the integrated command c \[authors\].
pub const GRIP_RATE: f32 = 0.01;
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

/// Travel per step at full action in `variant`.
pub fn step_size(variant: Variant) -> f32 {
    match variant {
        Variant::Authors => STEP_SIZE,
        Variant::Uniform => UNIFORM_STEP_SIZE,
    }
}

/// Where the ball is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ball {
    Held,
    /// Released and simulated (`success = "through"`).
    Free(RigidBodyHandle),
    /// Released and judged on the spot (`success = "over"`): where it was let go.
    Dropped([f32; 3]),
}

pub struct Placing {
    spec: EnvSpec,
    options: EnvOptions,
    world: TableWorld,
    ball: Ball,
    /// The last gripper command was not "open" (what the sign observation shows).
    gripper_closed: bool,
    /// The integrated gripper command c: +1 closed, -1 fully open.
    grip_level: f32,
    /// Physics substeps since the release.
    free_substeps: u32,
    elapsed: u32,
    done: bool,
}

impl Placing {
    /// The authors' Placing (the default).
    pub fn new() -> Self {
        Self::with_options(EnvOptions::default())
    }

    pub fn with_options(options: EnvOptions) -> Self {
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
            options,
            world: Self::build_world([-0.4, 0.0, 1.3], options.hoop),
            ball: Ball::Held,
            gripper_closed: true,
            grip_level: 1.0,
            free_substeps: 0,
            elapsed: 0,
            done: true,
        }
    }

    fn build_world(gripper: [f32; 3], hoop_shape: HoopShape) -> TableWorld {
        let mut world = TableWorld::new(&hoop::table(), gripper, SUBSTEP_DT);
        hoop::add_to(&mut world, hoop_shape);
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
            Ball::Free(b) => self.world.body_position(b),
            Ball::Dropped(p) => p,
            Ball::Held => self.world.gripper(),
        }
    }

    /// The grip level at or below which the ball drops: `release_at` for the authors' gradual
    /// gripper, -1 for the first version's (one "open" command sets c to -1).
    pub fn release_level(&self) -> f32 {
        match self.options.variant {
            Variant::Authors => self.options.release_at,
            Variant::Uniform => -1.0,
        }
    }

    /// The new grip level after command `a3`.
    fn integrate_grip(&self, a3: f32) -> f32 {
        match self.options.variant {
            Variant::Authors => {
                // sign(0) = 0: a zero command leaves the gripper where it is.
                let sign = if a3 > 0.0 {
                    1.0
                } else if a3 < 0.0 {
                    -1.0
                } else {
                    0.0
                };
                (self.grip_level + GRIP_RATE * sign).clamp(-1.0, 1.0)
            }
            Variant::Uniform => {
                if a3 < 0.0 {
                    -1.0
                } else {
                    1.0
                }
            }
        }
    }

    /// A start for the reset: the home pose, or a uniform draw above the table (`None` for a
    /// draw the workspace or the no-entry box rejects).
    fn draw_start(&self, rng: &mut ChaCha8Rng) -> Option<[f32; 3]> {
        match self.options.start_pose() {
            Start::Home => Some(HOME),
            Start::Uniform => {
                let p = [
                    rng.random_range(WORKSPACE.lo[0]..WORKSPACE.hi[0]),
                    rng.random_range(WORKSPACE.lo[1]..WORKSPACE.hi[1]),
                    rng.random_range(START_MIN_Z..WORKSPACE.hi[2]),
                ];
                // The ranges are half open; the gate's workspace is open on both sides.
                (WORKSPACE.contains(&p) && !NO_ENTRY.contains(&p)).then_some(p)
            }
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
        let mut world = Self::build_world([0.0, 0.0, 1.3], self.options.hoop);
        let (step, reset_action) = match self.options.variant {
            Variant::Authors => (STEP_SIZE, RESET_ACTION),
            Variant::Uniform => (UNIFORM_STEP_SIZE, 1.0),
        };
        let start = 'draw: loop {
            let Some(mut p) = self.draw_start(&mut rng) else {
                continue;
            };
            for _ in 0..RESET_STEPS {
                let a: [f32; 3] =
                    std::array::from_fn(|_| rng.random_range(-reset_action..=reset_action));
                p = gated_move(p, a, step, LOOKAHEAD, gate_allows);
                if world.touching(p, BALL_RADIUS, &HOOP) {
                    continue 'draw;
                }
            }
            break p;
        };
        world.set_gripper(start);
        self.world = world;
        self.ball = Ball::Held;
        self.gripper_closed = true;
        self.grip_level = 1.0;
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
        let step = step_size(self.options.variant);
        let to = gated_move(from, [a[0], a[1], a[2]], step, LOOKAHEAD, gate_allows);
        self.gripper_closed = a[3] >= 0.0;
        self.grip_level = self.integrate_grip(a[3]);
        let mut event = None;
        // The level is a sum of f32 steps of 0.01: a hundredth of a step's tolerance makes
        // "twelve net open steps" exact whatever the rounding.
        let released = self.grip_level <= self.release_level() + GRIP_RATE * 0.01;
        if self.ball == Ball::Held && released {
            match self.options.placing_success() {
                PlacingSuccess::Over => {
                    // Judged where the gripper let go, at the end of this step's move.
                    let placed = over_opening(to[0], to[1]) && to[2] > HOOP_TOP_Z;
                    self.ball = Ball::Dropped(to);
                    event = Some(if placed {
                        Outcome::Success
                    } else {
                        Outcome::Failure
                    });
                }
                PlacingSuccess::Through => {
                    // Released at the start of the step, moving as the gripper moves during it.
                    let v = std::array::from_fn(|i| (to[i] - from[i]) / CONTROL_DT);
                    self.ball = Ball::Free(self.world.add_ball(from, v, BALL_RADIUS));
                }
            }
        }
        self.world.set_gripper(to);
        // The physics runs only while a ball is free: a held ball just follows the gripper.
        if let Ball::Free(b) = self.ball {
            event = self.simulate_ball(b);
        }
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
        let g = match self.options.observe_grip {
            GripObservation::Sign if self.gripper_closed => 1.0,
            GripObservation::Sign => -1.0,
            GripObservation::Level => self.grip_level,
        };
        vec![x, y, z, g]
    }

    fn elapsed_steps(&self) -> u32 {
        self.elapsed
    }

    fn render(&self) -> RenderState {
        RenderState::Placing {
            gripper: tabletop::upright(self.world.gripper()),
            gripper_closed: self.gripper_closed,
            grip_level: self.grip_level,
            ball: self.ball_position(),
            ball_held: self.ball == Ball::Held,
        }
    }

    fn geometry(&self) -> Geometry {
        Geometry::Placing {
            table: hoop::table(),
            hoop_parts: hoop::parts(self.options.hoop),
            opening: [-OPENING_HALF, -OPENING_HALF, OPENING_HALF, OPENING_HALF],
            hoop_top_z: HOOP_TOP_Z,
            ball_radius: BALL_RADIUS,
            release_level: self.release_level(),
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
