//! What Reaching and Placing share: the table-top rapier world (a fixed table, a kinematic
//! gripper), the safety-gate helpers, and the episode bookkeeping (clipping, rewards, the
//! 1000-step horizon).
//!
//! Both tasks rebuild their world at every reset rather than editing the last one: rapier is
//! deterministic for the same sequence of operations, and a fresh world makes an episode depend
//! on its seed and actions only, not on what earlier episodes left in the solver's caches.

use rapier3d::prelude::{
    Ball, ColliderBuilder, PhysicsWorld, Pose, QueryFilter, RigidBodyBuilder, RigidBodyHandle,
    Vector,
};

use super::{Cuboid, Outcome, Pose3, Step};

/// Height of the table's top surface (robosuite's table height, rounded).
pub(crate) const TABLE_TOP_Z: f32 = 0.75;
/// The table is a slab this thick; only its top matters.
pub(crate) const TABLE_THICKNESS: f32 = 0.05;
pub(crate) const CONTROL_HZ: f32 = 20.0;
/// One control step, in seconds.
pub(crate) const CONTROL_DT: f32 = 1.0 / CONTROL_HZ;
/// The horizon, counting the steps the reset spends.
pub(crate) const MAX_EPISODE_STEPS: u32 = 1000;
pub(crate) const SUCCESS_REWARD: f32 = 100.0;

/// Restitution of every tabletop surface and of the ball: a lively but not superball bounce
/// (rapier averages the two sides, so the effective coefficient is this value).
pub(crate) const RESTITUTION: f32 = 0.5;
/// Friction of every tabletop surface and of the ball (wood/rubber, roughly).
pub(crate) const FRICTION: f32 = 0.5;

/// What a collider is, stored in its `user_data` so contact queries can tell parts apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Part {
    Table = 1,
    /// The hoop's walls: a ball touching one was dropped outside the ring.
    HoopWall = 2,
    /// The plates around the opening: a ball may bounce off these into the ring.
    HoopTop = 3,
    Ball = 4,
}

impl Part {
    fn from_user_data(data: u128) -> Option<Part> {
        [Part::Table, Part::HoopWall, Part::HoopTop, Part::Ball]
            .into_iter()
            .find(|p| *p as u128 == data)
    }
}

/// The table slab whose top surface is the rectangle `center ± half` at `TABLE_TOP_Z`.
pub(crate) const fn table(center: [f32; 2], half: [f32; 2]) -> Cuboid {
    Cuboid {
        center: [center[0], center[1], TABLE_TOP_Z - TABLE_THICKNESS / 2.0],
        half_extents: [half[0], half[1], TABLE_THICKNESS / 2.0],
    }
}

/// An open axis-aligned box `lo < p < hi` (per dimension): the gates' workspaces and the
/// no-entry box. Open, so a point on a boundary is outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Region<const N: usize> {
    pub lo: [f32; N],
    pub hi: [f32; N],
}

impl<const N: usize> Region<N> {
    pub(crate) fn contains(&self, p: &[f32; N]) -> bool {
        (0..N).all(|i| self.lo[i] < p[i] && p[i] < self.hi[i])
    }
}

/// The action as `N` numbers in `[-1, 1]`. NaN becomes 0: a broken policy should stand still,
/// not poison the physics.
pub(crate) fn clip_action<const N: usize>(action: &[f32]) -> [f32; N] {
    assert_eq!(action.len(), N, "expected an action of {N} entries");
    std::array::from_fn(|i| {
        let a = action[i];
        if a.is_nan() { 0.0 } else { a.clamp(-1.0, 1.0) }
    })
}

/// The safety gate both tasks use: the gripper moves by `step * a` unless the point
/// `pos + lookahead * a` is not `allowed`, in which case the whole move is zeroed (the robot
/// stays put). Returns the new position.
pub(crate) fn gated_move<const N: usize>(
    pos: [f32; N],
    a: [f32; N],
    step: f32,
    lookahead: f32,
    allowed: impl Fn(&[f32; N]) -> bool,
) -> [f32; N] {
    let probe: [f32; N] = std::array::from_fn(|i| pos[i] + lookahead * a[i]);
    if allowed(&probe) {
        std::array::from_fn(|i| pos[i] + step * a[i])
    } else {
        pos
    }
}

/// A pose with no rotation (the gripper and the ball are drawn upright).
pub(crate) fn upright(position: [f32; 3]) -> Pose3 {
    Pose3 {
        position,
        rotation: [0.0, 0.0, 0.0, 1.0],
    }
}

/// The `Step` for one control step that took the episode to `elapsed` steps. `event` is a
/// terminal outcome (success or failure) if the step produced one; otherwise the step truncates
/// when the horizon is reached. A success pays `SUCCESS_REWARD`, everything else 0.
pub(crate) fn make_step(obs: Vec<f32>, elapsed: u32, event: Option<Outcome>) -> Step {
    let (terminated, truncated, outcome) = match event {
        Some(o) => (true, false, Some(o)),
        None if elapsed >= MAX_EPISODE_STEPS => (false, true, Some(Outcome::TimeLimit)),
        None => (false, false, None),
    };
    let reward = if event == Some(Outcome::Success) {
        SUCCESS_REWARD
    } else {
        0.0
    };
    Step {
        obs,
        reward,
        terminated,
        truncated,
        outcome,
    }
}

fn vec3(p: [f32; 3]) -> Vector {
    Vector::new(p[0], p[1], p[2])
}

fn array3(v: Vector) -> [f32; 3] {
    [v.x, v.y, v.z]
}

/// The rapier world of a table-top task: z up, a fixed body holding the table (and whatever
/// fixed parts a task adds), and the gripper as a kinematic body. The gripper has no collider:
/// its open fingers do not push the ball, and its contact volume is queried explicitly
/// (`touching`), so it never needs the physics pipeline to move.
pub(crate) struct TableWorld {
    world: PhysicsWorld,
    ground: RigidBodyHandle,
    gripper: RigidBodyHandle,
}

impl TableWorld {
    /// A world with `table` and the gripper at `gripper`, stepping `dt` seconds per physics step.
    pub(crate) fn new(table: &Cuboid, gripper: [f32; 3], dt: f32) -> Self {
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -9.81);
        world.integration_parameters.dt = dt;
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let gripper = world
            .insert_body(RigidBodyBuilder::kinematic_position_based().translation(vec3(gripper)));
        let mut tw = Self {
            world,
            ground,
            gripper,
        };
        tw.add_fixed(table, Part::Table);
        tw
    }

    /// Add a fixed box to the ground body.
    pub(crate) fn add_fixed(&mut self, c: &Cuboid, part: Part) {
        let [hx, hy, hz] = c.half_extents;
        let collider = ColliderBuilder::cuboid(hx, hy, hz)
            .translation(vec3(c.center))
            .restitution(RESTITUTION)
            .friction(FRICTION)
            .user_data(part as u128);
        self.world.insert_collider(collider, Some(self.ground));
    }

    /// Bring collision detection up to date, so that scene queries see every collider. Call
    /// after adding fixed parts: the broad phase only learns of colliders when it runs.
    pub(crate) fn refresh(&mut self) {
        self.world.detect_collisions(&(), &());
    }

    /// Advance the physics by one `dt` (only needed while something dynamic moves).
    pub(crate) fn step(&mut self) {
        self.world.step();
    }

    pub(crate) fn gripper(&self) -> [f32; 3] {
        array3(self.world.bodies[self.gripper].translation())
    }

    /// Teleport the kinematic gripper (no physics step needed: nothing is pushed by it).
    pub(crate) fn set_gripper(&mut self, p: [f32; 3]) {
        self.world.bodies[self.gripper].set_translation(vec3(p), false);
    }

    /// Whether a sphere of `radius` at `centre` intersects a collider tagged with one of
    /// `parts` (a shape-intersection query against the broad phase's current state).
    pub(crate) fn touching(&self, centre: [f32; 3], radius: f32, parts: &[Part]) -> bool {
        let shape = Ball::new(radius);
        self.world
            .intersect_shape(
                Pose::from_translation(vec3(centre)),
                &shape,
                QueryFilter::default(),
            )
            .any(|(_, co)| Part::from_user_data(co.user_data).is_some_and(|p| parts.contains(&p)))
    }

    /// Add a dynamic ball at `centre` moving at `velocity`; returns its body.
    pub(crate) fn add_ball(
        &mut self,
        centre: [f32; 3],
        velocity: [f32; 3],
        radius: f32,
    ) -> RigidBodyHandle {
        let body = RigidBodyBuilder::dynamic()
            .translation(vec3(centre))
            .linvel(vec3(velocity));
        let collider = ColliderBuilder::ball(radius)
            // Rubber, roughly (a 2.5 cm ball of it weighs about 65 g).
            .density(1000.0)
            .restitution(RESTITUTION)
            .friction(FRICTION)
            .user_data(Part::Ball as u128);
        self.world.insert(body, collider).0
    }

    pub(crate) fn body_position(&self, body: RigidBodyHandle) -> [f32; 3] {
        array3(self.world.bodies[body].translation())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn region_is_open_on_both_sides_of_each_boundary() {
        let r = Region {
            lo: [-1.0, 0.0],
            hi: [1.0, 2.0],
        };
        assert!(r.contains(&[0.0, 1.0]));
        assert!(r.contains(&[-0.999, 1.999]));
        assert!(!r.contains(&[-1.0, 1.0]));
        assert!(!r.contains(&[0.0, 2.0]));
        assert!(!r.contains(&[1.001, 1.0]));
    }

    #[test]
    fn clip_action_clamps_and_zeroes_nan() {
        assert_eq!(clip_action::<3>(&[2.0, -7.0, f32::NAN]), [1.0, -1.0, 0.0]);
        assert_eq!(clip_action::<2>(&[0.25, -0.5]), [0.25, -0.5]);
    }

    #[test]
    fn gate_zeroes_the_whole_move_when_the_probe_leaves() {
        let inside = |p: &[f32; 2]| p[0] < 1.0;
        // The probe (lookahead 0.1) leaves although the move (0.01) would not: zeroed, y too.
        assert_eq!(
            gated_move([0.95, 0.0], [1.0, 1.0], 0.01, 0.1, inside),
            [0.95, 0.0]
        );
        assert_eq!(
            gated_move([0.85, 0.0], [1.0, 1.0], 0.01, 0.1, inside),
            [0.86, 0.01]
        );
    }

    #[test]
    fn make_step_rewards_success_and_truncates_at_the_horizon() {
        let s = make_step(vec![], 10, Some(Outcome::Success));
        assert!(s.terminated && !s.truncated && s.reward == SUCCESS_REWARD);
        let f = make_step(vec![], MAX_EPISODE_STEPS, Some(Outcome::Failure));
        assert!(f.terminated && !f.truncated && f.reward == 0.0);
        let t = make_step(vec![], MAX_EPISODE_STEPS, None);
        assert!(!t.terminated && t.truncated && t.outcome == Some(Outcome::TimeLimit));
        let n = make_step(vec![], MAX_EPISODE_STEPS - 1, None);
        assert!(!n.done() && n.outcome.is_none());
    }

    #[test]
    fn touching_sees_the_table_before_any_physics_step() {
        let mut tw = TableWorld::new(&table([0.0, 0.0], [0.5, 0.5]), [0.0, 0.0, 1.0], 0.005);
        tw.refresh();
        let r = 0.025;
        assert!(tw.touching([0.0, 0.0, TABLE_TOP_Z + r - 0.001], r, &[Part::Table]));
        assert!(!tw.touching([0.0, 0.0, TABLE_TOP_Z + r + 0.001], r, &[Part::Table]));
        assert!(!tw.touching([0.0, 0.0, TABLE_TOP_Z], r, &[Part::HoopWall]));
        tw.set_gripper([0.1, 0.2, 0.8]);
        assert_eq!(tw.gripper(), [0.1, 0.2, 0.8]);
    }
}
