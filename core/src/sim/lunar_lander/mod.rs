//! Gymnasium's `LunarLanderContinuous-v3` on rapier2d: the same terrain, lander, engines,
//! observation, reward and termination as `gymnasium/envs/box2d/lunar_lander.py`, with Box2D's
//! behaviour reproduced where rapier differs (see `world.rs` and `sleep.rs`).
//!
//! - `terrain`: the random moon surface and the helipad.
//! - `world`: the rapier world (ground, hull, legs, joints) and its contact queries.
//! - `engines`: which engines an action fires and the impulses they apply.
//! - `sleep`: Box2D's sleep rule, which decides that the lander is at rest.
//! - `heuristic`: Gymnasium's scripted controller.

mod engines;
mod heuristic;
mod sleep;
mod terrain;
mod world;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{BoxSpace, Env, EnvSpec, Geometry, Outcome, Pose2, RenderState, Step};
pub use heuristic::heuristic;
use terrain::{HELIPAD_Y, Terrain};
use world::LanderWorld;

/// Control rate: one physics step of `1 / FPS` per env step.
pub const FPS: f32 = 50.0;
/// Pixels per world unit.
pub const SCALE: f32 = 30.0;
/// World size in units (Gymnasium's 600 x 400 px viewport).
pub const W: f32 = 600.0 / SCALE;
pub const H: f32 = 400.0 / SCALE;

const MAIN_ENGINE_POWER: f32 = 13.0;
const SIDE_ENGINE_POWER: f32 = 0.6;
/// Bound of each component of the random push at reset.
const INITIAL_RANDOM: f32 = 1000.0;
/// Hull outline in pixels, hull frame.
const LANDER_POLY: [(f32, f32); 6] = [
    (-14.0, 17.0),
    (-17.0, 0.0),
    (-17.0, -10.0),
    (17.0, -10.0),
    (17.0, 0.0),
    (14.0, 17.0),
];
const LEG_AWAY: f32 = 20.0;
const LEG_DOWN: f32 = 18.0;
/// Leg half extents in pixels.
const LEG_W: f32 = 2.0;
const LEG_H: f32 = 8.0;
const LEG_SPRING_TORQUE: f32 = 40.0;
const SIDE_ENGINE_HEIGHT: f32 = 14.0;
const SIDE_ENGINE_AWAY: f32 = 12.0;
const MAIN_ENGINE_Y_LOCATION: f32 = 4.0;
/// Flag pole height, as Gymnasium draws them.
const FLAG_HEIGHT: f32 = 50.0 / SCALE;
/// Gymnasium's `TimeLimit` for LunarLander.
pub const MAX_EPISODE_STEPS: u32 = 1000;

pub struct LunarLander {
    spec: EnvSpec,
    rng: ChaCha8Rng,
    terrain: Terrain,
    world: LanderWorld,
    /// The hull's angle, unwrapped like Box2D's (rapier reports it in `(-pi, pi]`).
    hull_angle: f32,
    obs: [f32; 8],
    /// Gymnasium's `prev_shaping`: `None` until the reset's step sets it.
    prev_shaping: Option<f64>,
    /// Agent steps since the reset (Gymnasium's `TimeLimit` does not count the step inside
    /// `reset`).
    steps: u32,
    done: bool,
    sleep: sleep::SleepTimer,
    leg_contact: [bool; 2],
    /// The last step's firing, for rendering.
    main_engine: f32,
    side_engine: f32,
}

impl LunarLander {
    /// A lander already reset with seed 0 (call `reset` to choose the seed).
    pub fn new() -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let terrain = Terrain::generate(&mut rng);
        let world = LanderWorld::new(&terrain, [0.0, 0.0]);
        let mut env = Self {
            spec: spec(),
            rng,
            terrain,
            world,
            hull_angle: 0.0,
            obs: [0.0; 8],
            prev_shaping: None,
            steps: 0,
            done: false,
            sleep: sleep::SleepTimer::default(),
            leg_contact: [false; 2],
            main_engine: 0.0,
            side_engine: 0.0,
        };
        env.reset(0);
        env
    }

    /// One Gymnasium `step` body: engines, physics, observation, reward and termination.
    /// Returns the reward and, when the step terminates the episode, how.
    fn advance(&mut self, action: [f32; 2]) -> (f32, Option<Outcome>) {
        // Two dispersion draws every step, engines on or not, as Gymnasium makes them.
        let dispersion = [
            self.rng.random_range(-1.0..1.0f64) as f32 / SCALE,
            self.rng.random_range(-1.0..1.0f64) as f32 / SCALE,
        ];
        let firing = engines::fire(action, self.hull_angle, dispersion);
        let hull = self.world.hull();
        for imp in [firing.main, firing.side].into_iter().flatten() {
            let point = [
                hull.position[0] + imp.offset[0],
                hull.position[1] + imp.offset[1],
            ];
            self.world.apply_hull_impulse(imp.impulse, point);
        }
        self.main_engine = firing.m_power;
        self.side_engine = firing.direction * firing.s_power;

        self.world.step();

        let hull = self.world.hull();
        self.hull_angle += wrap_angle(hull.angle - self.hull_angle);
        self.leg_contact = [
            self.world.leg_touches_ground(0),
            self.world.leg_touches_ground(1),
        ];
        let asleep = self.sleep.update(self.world.all_quiet(), firing.any());

        // Gymnasium computes the state in f64 from Box2D's f32 values and returns it as f32.
        let (pos, vel) = (hull.position.map(f64::from), hull.linvel.map(f64::from));
        let (w, h, fps) = (f64::from(W), f64::from(H), f64::from(FPS));
        let state = [
            (pos[0] - w / 2.0) / (w / 2.0),
            (pos[1] - (f64::from(HELIPAD_Y) + f64::from(LEG_DOWN / SCALE))) / (h / 2.0),
            vel[0] * (w / 2.0) / fps,
            vel[1] * (h / 2.0) / fps,
            f64::from(self.hull_angle),
            20.0 * f64::from(hull.angvel) / fps,
            f64::from(u8::from(self.leg_contact[0])),
            f64::from(u8::from(self.leg_contact[1])),
        ];
        self.obs = state.map(|s| s as f32);

        let shaping = shaping(&state);
        let mut reward = self.prev_shaping.map_or(0.0, |prev| shaping - prev);
        self.prev_shaping = Some(shaping);
        reward -= f64::from(firing.m_power) * 0.30;
        reward -= f64::from(firing.s_power) * 0.03;

        let mut outcome = None;
        if self.world.hull_touches_ground() || state[0].abs() >= 1.0 {
            reward = -100.0;
            outcome = Some(Outcome::Failure);
        }
        // Checked last, as in Gymnasium: coming to rest wins over a crash in the same step.
        if asleep {
            reward = 100.0;
            outcome = Some(Outcome::Success);
        }
        (reward as f32, outcome)
    }
}

/// Gymnasium's potential: distance to the pad, speed and tilt cost, leg contacts pay.
fn shaping(s: &[f64; 8]) -> f64 {
    -100.0 * (s[0] * s[0] + s[1] * s[1]).sqrt()
        - 100.0 * (s[2] * s[2] + s[3] * s[3]).sqrt()
        - 100.0 * s[4].abs()
        + 10.0 * s[6]
        + 10.0 * s[7]
}

/// `a` wrapped into `[-pi, pi)`; rapier's angles are wrapped, Box2D's are not.
fn wrap_angle(a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    (a + PI).rem_euclid(TAU) - PI
}

fn spec() -> EnvSpec {
    use std::f32::consts::TAU;
    EnvSpec {
        id: "lunar-lander",
        observation_space: BoxSpace {
            low: vec![-2.5, -2.5, -10.0, -10.0, -TAU, -10.0, 0.0, 0.0],
            high: vec![2.5, 2.5, 10.0, 10.0, TAU, 10.0, 1.0, 1.0],
        },
        action_space: BoxSpace::uniform(2, -1.0, 1.0),
        observation_names: vec![
            "x",
            "y",
            "vx",
            "vy",
            "angle",
            "angular_velocity",
            "right_leg_contact",
            "left_leg_contact",
        ],
        action_names: vec!["main_engine", "side_engines"],
        max_episode_steps: MAX_EPISODE_STEPS,
        control_hz: FPS,
    }
}

fn pose(b: &world::BodyState) -> Pose2 {
    Pose2 {
        x: b.position[0],
        y: b.position[1],
        angle: b.angle,
    }
}

impl Default for LunarLander {
    fn default() -> Self {
        Self::new()
    }
}

impl Env for LunarLander {
    fn spec(&self) -> &EnvSpec {
        &self.spec
    }

    /// Gymnasium's `reset`: a new terrain, a new world, a random push on the hull, then one
    /// step with a zero action whose observation is returned (it also sets the shaping).
    fn reset(&mut self, seed: u64) -> Vec<f32> {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
        self.terrain = Terrain::generate(&mut self.rng);
        let force = [
            self.rng
                .random_range(-f64::from(INITIAL_RANDOM)..f64::from(INITIAL_RANDOM))
                as f32,
            self.rng
                .random_range(-f64::from(INITIAL_RANDOM)..f64::from(INITIAL_RANDOM))
                as f32,
        ];
        self.world = LanderWorld::new(&self.terrain, force);
        self.hull_angle = 0.0;
        self.sleep = sleep::SleepTimer::default();
        self.steps = 0;
        self.done = false;
        // Gymnasium's first step has no previous shaping: its reward is only the (zero) fuel
        // cost, and it initialises `prev_shaping`.
        self.prev_shaping = None;
        self.advance([0.0, 0.0]);
        self.obs.to_vec()
    }

    fn step(&mut self, action: &[f32]) -> Step {
        assert!(
            !self.done,
            "LunarLander::step called after the episode ended"
        );
        assert_eq!(action.len(), 2, "LunarLander takes 2 actions");
        let action = [action[0].clamp(-1.0, 1.0), action[1].clamp(-1.0, 1.0)];
        let (reward, outcome) = self.advance(action);
        self.steps += 1;
        let terminated = outcome.is_some();
        let truncated = !terminated && self.steps >= MAX_EPISODE_STEPS;
        let outcome = outcome.or(truncated.then_some(Outcome::TimeLimit));
        self.done = terminated || truncated;
        Step {
            obs: self.obs.to_vec(),
            reward,
            terminated,
            truncated,
            outcome,
        }
    }

    fn observation(&self) -> Vec<f32> {
        self.obs.to_vec()
    }

    fn elapsed_steps(&self) -> u32 {
        self.steps
    }

    fn render(&self) -> RenderState {
        let hull = self.world.hull();
        RenderState::LunarLander {
            hull: Pose2 {
                angle: self.hull_angle,
                ..pose(&hull)
            },
            legs: [pose(&self.world.leg(0)), pose(&self.world.leg(1))],
            leg_contact: self.leg_contact,
            main_engine: self.main_engine,
            side_engine: self.side_engine,
        }
    }

    fn geometry(&self) -> Geometry {
        Geometry::LunarLander {
            world: [W, H],
            terrain: self.terrain.points.to_vec(),
            flags: [
                [self.terrain.helipad_x1, HELIPAD_Y],
                [self.terrain.helipad_x2, HELIPAD_Y],
            ],
            flag_height: FLAG_HEIGHT,
            hull: LANDER_POLY
                .iter()
                .map(|&(x, y)| [x / SCALE, y / SCALE])
                .collect(),
            leg_half_extents: [LEG_W / SCALE, LEG_H / SCALE],
        }
    }
}
