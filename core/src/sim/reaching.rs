//! Reaching: move the gripper over the table into the goal area at the table's centre.
//!
//! - obs = gripper (x, y); action in `[-1, 1]^2`, a full action moves 1.2 cm per 50 ms step
//!   \[authors\] (5 mm in the first version, `variant = "uniform"`).
//! - Safety gate: a move that would leave the table (`|x| < 0.38`, `|y| < 0.35`) is zeroed.
//! - Reset \[authors\]: the robot's home pose (-0.23, 0), then 100 small random moves (uniform
//!   `±0.05` actions, through the gate) that count toward the 1000-step horizon. The uniform
//!   variant starts anywhere on the table outside the goal area instead, and redraws a start
//!   whose random moves end inside the goal, so an episode never starts solved.
//! - +100 and termination on entering the goal area, 0 otherwise.
//!
//! The gripper is a kinematic body in the shared table-top world; nothing dynamic moves here,
//! so the physics pipeline is never stepped: the gripper's position is set directly.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::tabletop::{
    self, CONTROL_HZ, MAX_EPISODE_STEPS, Region, TABLE_TOP_Z, TableWorld, clip_action, gated_move,
};
use super::{
    BoxSpace, Env, EnvOptions, EnvSpec, Geometry, Outcome, RenderState, Start, Step, Variant,
};

/// Half widths of the goal area (the scene graph's band edges are the same numbers).
pub const GOAL_HALF_X: f32 = 0.05;
pub const GOAL_HALF_Y: f32 = 0.125;
/// Half sizes of the table top, which is also the safety gate's rectangle.
pub const TABLE_HALF_X: f32 = 0.38;
pub const TABLE_HALF_Y: f32 = 0.35;
/// Gripper travel per step at full action \[authors: their expert moves 1.16 cm per step\].
pub const STEP_SIZE: f32 = 0.012;
/// The first version's travel per step (`variant = "uniform"`).
pub const UNIFORM_STEP_SIZE: f32 = 0.005;
/// The robot's home pose over the table \[authors\], where every episode starts.
pub const HOME: [f32; 2] = [-0.23, 0.0];
/// Steps the reset spends on random moves (they count toward the horizon).
pub const RESET_STEPS: u32 = 100;
/// Size of the reset's random actions.
const RESET_ACTION: f32 = 0.05;
/// The gripper's locked height: just above the table top.
pub const GRIPPER_Z: f32 = TABLE_TOP_Z + 0.03;

const WORKSPACE: Region<2> = Region {
    lo: [-TABLE_HALF_X, -TABLE_HALF_Y],
    hi: [TABLE_HALF_X, TABLE_HALF_Y],
};

/// Inside the goal area, edges included, to agree with the scene graph's "centred" bands
/// (whose conjunction is success).
pub fn in_goal(p: [f32; 2]) -> bool {
    p[0].abs() <= GOAL_HALF_X && p[1].abs() <= GOAL_HALF_Y
}

/// Travel per step at full action in `variant`.
pub fn step_size(variant: Variant) -> f32 {
    match variant {
        Variant::Authors => STEP_SIZE,
        Variant::Uniform => UNIFORM_STEP_SIZE,
    }
}

/// The gripper after action `a` (already clipped) from `p`, through the safety gate.
fn gated(p: [f32; 2], a: [f32; 2], step: f32) -> [f32; 2] {
    gated_move(p, a, step, step, |q| WORKSPACE.contains(q))
}

pub struct Reaching {
    spec: EnvSpec,
    variant: Variant,
    start: Start,
    world: TableWorld,
    elapsed: u32,
    done: bool,
}

impl Reaching {
    /// The authors' Reaching (the default).
    pub fn new() -> Self {
        Self::with_variant(Variant::Authors)
    }

    pub fn with_variant(variant: Variant) -> Self {
        Self::with_options(&EnvOptions {
            variant,
            ..EnvOptions::default()
        })
    }

    /// The task's version (`variant`) and where its episodes start (`start`).
    pub fn with_options(options: &EnvOptions) -> Self {
        let variant = options.variant;
        let spec = EnvSpec {
            id: "reaching",
            observation_space: BoxSpace {
                low: vec![-TABLE_HALF_X, -TABLE_HALF_Y],
                high: vec![TABLE_HALF_X, TABLE_HALF_Y],
            },
            action_space: BoxSpace::uniform(2, -1.0, 1.0),
            observation_names: vec!["gripper_x", "gripper_y"],
            action_names: vec!["dx", "dy"],
            max_episode_steps: MAX_EPISODE_STEPS,
            control_hz: CONTROL_HZ,
        };
        // Until the first reset: the gripper at a table corner, the episode not started.
        let world = Self::build_world([-0.3, -0.3]);
        Self {
            spec,
            variant,
            start: options.start_pose(),
            world,
            elapsed: 0,
            done: true,
        }
    }

    fn table() -> super::Cuboid {
        tabletop::table([0.0, 0.0], [TABLE_HALF_X, TABLE_HALF_Y])
    }

    fn build_world(p: [f32; 2]) -> TableWorld {
        let mut world = TableWorld::new(
            &Self::table(),
            [p[0], p[1], GRIPPER_Z],
            tabletop::CONTROL_DT,
        );
        world.refresh();
        world
    }

    fn gripper_xy(&self) -> [f32; 2] {
        let [x, y, _] = self.world.gripper();
        [x, y]
    }

    fn set_gripper_xy(&mut self, p: [f32; 2]) {
        self.world.set_gripper([p[0], p[1], GRIPPER_Z]);
    }
}

impl Default for Reaching {
    fn default() -> Self {
        Self::new()
    }
}

impl Env for Reaching {
    fn spec(&self) -> &EnvSpec {
        &self.spec
    }

    fn reset(&mut self, seed: u64) -> Vec<f32> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let step = step_size(self.variant);
        let p = loop {
            let mut p = match self.start {
                Start::Home => HOME,
                Start::Uniform => loop {
                    let p = [
                        rng.random_range(-TABLE_HALF_X..TABLE_HALF_X),
                        rng.random_range(-TABLE_HALF_Y..TABLE_HALF_Y),
                    ];
                    if !in_goal(p) {
                        break p;
                    }
                },
            };
            for _ in 0..RESET_STEPS {
                let a = [
                    rng.random_range(-RESET_ACTION..=RESET_ACTION),
                    rng.random_range(-RESET_ACTION..=RESET_ACTION),
                ];
                p = gated(p, a, step);
            }
            // A start the random moves pushed into the goal would be a free success: redraw.
            if !in_goal(p) {
                break p;
            }
        };
        self.world = Self::build_world(p);
        self.elapsed = RESET_STEPS;
        self.done = false;
        self.observation()
    }

    fn step(&mut self, action: &[f32]) -> Step {
        assert!(
            !self.done,
            "step called after the episode ended; call reset"
        );
        let a = clip_action::<2>(action);
        let p = gated(self.gripper_xy(), a, step_size(self.variant));
        self.set_gripper_xy(p);
        self.elapsed += 1;
        let event = in_goal(p).then_some(Outcome::Success);
        let step = tabletop::make_step(self.observation(), self.elapsed, event);
        self.done = step.done();
        step
    }

    fn observation(&self) -> Vec<f32> {
        self.gripper_xy().to_vec()
    }

    fn elapsed_steps(&self) -> u32 {
        self.elapsed
    }

    fn render(&self) -> RenderState {
        RenderState::Reaching {
            gripper: tabletop::upright(self.world.gripper()),
        }
    }

    fn geometry(&self) -> Geometry {
        Geometry::Reaching {
            table: Self::table(),
            goal: [-GOAL_HALF_X, -GOAL_HALF_Y, GOAL_HALF_X, GOAL_HALF_Y],
            workspace: [-TABLE_HALF_X, -TABLE_HALF_Y, TABLE_HALF_X, TABLE_HALF_Y],
        }
    }
}

/// Go to the goal's centre: a proportional controller that saturates more than one step away
/// (a 1.2 cm step; with the uniform variant's 5 mm steps it saturates all the way in, which
/// the goal's 10 cm width makes harmless).
pub fn heuristic(obs: &[f32]) -> [f32; 2] {
    [
        (-obs[0] / STEP_SIZE).clamp(-1.0, 1.0),
        (-obs[1] / STEP_SIZE).clamp(-1.0, 1.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reset_starts_outside_the_goal_after_100_moves() {
        for variant in [Variant::Authors, Variant::Uniform] {
            let mut env = Reaching::with_variant(variant);
            for seed in 0..200 {
                let obs = env.reset(seed);
                assert!(!in_goal([obs[0], obs[1]]));
                assert!(WORKSPACE.contains(&[obs[0], obs[1]]));
                assert_eq!(env.elapsed_steps(), RESET_STEPS);
            }
        }
    }

    #[test]
    fn authors_reset_stays_near_home() {
        // 100 moves of at most 5 % of 1.2 cm: at most 6 cm from home per axis.
        let mut env = Reaching::new();
        for seed in 0..50 {
            let obs = env.reset(seed);
            assert!((obs[0] - HOME[0]).abs() <= 0.06 && (obs[1] - HOME[1]).abs() <= 0.06);
        }
        let mut far = Reaching::with_variant(Variant::Uniform);
        let spread = (0..50).any(|seed| (far.reset(seed)[0] - HOME[0]).abs() > 0.2);
        assert!(spread, "the uniform variant starts anywhere on the table");
    }

    #[test]
    fn a_full_action_moves_one_step_size() {
        for variant in [Variant::Authors, Variant::Uniform] {
            let mut env = Reaching::with_variant(variant);
            let obs = env.reset(1);
            let next = env.step(&[0.0, 1.0]).obs;
            assert!((next[1] - obs[1] - step_size(variant)).abs() < 1e-6);
        }
    }

    #[test]
    fn heuristic_saturates_far_away_and_is_proportional_near() {
        assert_eq!(heuristic(&[0.3, -0.2]), [-1.0, 1.0]);
        let a = heuristic(&[0.006, -0.0024]);
        assert!((a[0] + 0.5).abs() < 1e-6 && (a[1] - 0.2).abs() < 1e-6);
    }

    #[test]
    fn nan_action_stands_still() {
        let mut env = Reaching::new();
        let obs = env.reset(3);
        let step = env.step(&[f32::NAN, f32::NAN]);
        assert_eq!(step.obs, obs);
    }
}
