//! The rapier2d world of one episode: the ground, the hull and its two legs, built as Gymnasium
//! builds them on Box2D, with rapier set up to behave like Box2D where it matters.
//!
//! - Legs: each leg hangs from the hull on a revolute joint with Box2D's limits and motor
//!   (speed 0.3 i, at most 40 N m). Rapier's *impulse* joints cannot carry the standing
//!   lander: the hull is 68 times heavier than a leg and its weight reaches the ground through a
//!   0.9-unit lever, and under that load the motor row gives way (the legs fold until the hull
//!   lies on the ground, whatever the torque bound or iteration count; measured on rapier2d
//!   0.36.1). So hull and legs form one *multibody*: reduced coordinates make the hinges exact,
//!   and the motors and limits are then rows on the joint coordinates, which hold the load as
//!   Box2D's 180 velocity iterations do (the legs give under a hard landing and the motors push
//!   them back to the rest limit). Warm starting is off: with it, the standing multibody jitters
//!   in a limit cycle far above Box2D's sleep tolerances, so the lander would never rest.
//! - Impulses: Box2D's `ApplyLinearImpulse` on the hull becomes a generalised impulse on the
//!   multibody, `dq' = M^-1 J^T p` (J the hull's body Jacobian, M the augmented mass), which
//!   moves the whole articulated lander exactly as a hull impulse followed by Box2D's joint
//!   solver does. The one-step initial force is the impulse `F dt`.
//! - Friction: Box2D mixes `sqrt(f1 * f2)`; rapier's `GeometricMean` rule is that same formula,
//!   so every collider keeps Gymnasium's own coefficient (hull 0.1, legs Box2D's default 0.2,
//!   ground 0.1). Restitution is 0 everywhere (Box2D mixes with max).
//! - Sleeping: rapier's sleeping is off for the lander; `sleep.rs` applies Box2D's rule.
//! - Touching: Box2D reports a contact once the shapes' skins (`b2_polygonRadius` = 0.01 on the
//!   polygon and on the edge) overlap, i.e. when the cores are closer than 0.02; we test
//!   rapier's contact points against that same distance.

use rapier2d::na;
use rapier2d::prelude::*;

use super::terrain::Terrain;
use super::{
    H, LANDER_POLY, LEG_AWAY, LEG_DOWN, LEG_H, LEG_SPRING_TORQUE, LEG_W, SCALE, W,
    sleep::SleepTimer,
};

/// Substeps per 1/50 s step, and solver passes per substep. With warm starting off (see
/// `LanderWorld::new`), one pass per substep lets the motors give way under the standing lander;
/// eight hold it as Box2D's 180 velocity iterations do, at the cost of a quarter of the speed.
const SOLVER_ITERATIONS: usize = 4;
const PGS_ITERATIONS: usize = 8;
/// The velocity motor's damping factor: large enough that its constraint-force mixing
/// (`1 / (substep_dt * damping)`) vanishes, i.e. a hard velocity constraint like Box2D's
/// (finite, so that no `0 * inf` can appear in rapier's coefficient formulas).
const MOTOR_DAMPING: f32 = 1.0e9;
/// Box2D's `b2_polygonRadius` on each of the two touching shapes.
const TOUCHING_DISTANCE: f32 = 2.0 * 0.01;
/// Gymnasium's joint limits for the `i = -1` leg; the other leg's are their mirror.
const LEG_LIMITS: [f32; 2] = [0.4, 0.9];
/// Gymnasium's motor speed magnitude (`0.3 * i`).
const LEG_MOTOR_SPEED: f32 = 0.3;

/// Collision groups (Gymnasium's category/mask bits): the ground is category 1; the hull
/// (0x10) and the legs (0x20) collide with the ground only, never with each other.
const GROUND_GROUP: Group = Group::GROUP_1;
const HULL_GROUP: Group = Group::GROUP_5;
const LEG_GROUP: Group = Group::GROUP_6;

/// Box2D's default fixture friction, which Gymnasium's legs keep.
const LEG_FRICTION: f32 = 0.2;
const HULL_FRICTION: f32 = 0.1;
const GROUND_FRICTION: f32 = 0.1;

/// A rigid body's state as the env reads it: origin position, angle in `(-pi, pi]`, velocity
/// of the centre of mass and angular velocity (Box2D's `position`, `angle`, `linearVelocity`,
/// `angularVelocity`, up to the angle's wrapping).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    pub position: [f32; 2],
    pub angle: f32,
    pub linvel: [f32; 2],
    pub angvel: f32,
}

pub struct LanderWorld {
    world: PhysicsWorld,
    hull: RigidBodyHandle,
    /// `[legs[0], legs[1]]`: Gymnasium's `i = -1` leg (right of the hull), then `i = +1`.
    legs: [RigidBodyHandle; 2],
    ground_collider: ColliderHandle,
    hull_collider: ColliderHandle,
    leg_colliders: [ColliderHandle; 2],
    /// Whether the initial push must be removed after the next step (rapier keeps user
    /// forces until reset; Box2D clears them at the end of every step).
    clear_forces: bool,
}

impl LanderWorld {
    /// Gymnasium's `reset` world: ground from `terrain`, lander at the top centre, with
    /// `initial_force` applied to the hull's centre for the first step.
    pub fn new(terrain: &Terrain, initial_force: [f32; 2]) -> Self {
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, -10.0);
        let params = &mut world.integration_parameters;
        params.dt = 1.0 / super::FPS;
        params.num_solver_iterations = SOLVER_ITERATIONS;
        params.num_internal_pgs_iterations = PGS_ITERATIONS;
        // Warm starting makes the standing lander jitter in a five-step limit cycle (about
        // 0.5 rad/s on the hull) that never lets it rest; without it, the iterations above
        // converge the motor, limit and contact rows from zero every substep.
        params.warmstart_coefficient = 0.0;
        // Contact recycling may leave contact distances stale by up to 0.05 units, which
        // would blur the touching test; the scene is tiny, so always recompute.
        params.contact_recycling = false;

        let ground_collider = insert_ground(&mut world, terrain);

        let (x0, y0) = (W / 2.0, H);
        let hull_points: Vec<Vector> = LANDER_POLY
            .iter()
            .map(|&(x, y)| Vector::new(x / SCALE, y / SCALE))
            .collect();
        let hull = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(x0, y0))
                .can_sleep(false),
        );
        let hull_collider = world.colliders.insert_with_parent(
            ColliderBuilder::convex_polyline(hull_points)
                .expect("the lander polygon is convex")
                .density(5.0)
                .friction(HULL_FRICTION)
                .friction_combine_rule(CoefficientCombineRule::GeometricMean)
                .restitution(0.0)
                .collision_groups(InteractionGroups::new(
                    HULL_GROUP,
                    GROUND_GROUP,
                    InteractionTestMode::And,
                )),
            hull,
            &mut world.bodies,
        );

        let mut legs = [hull; 2];
        let mut leg_colliders = [hull_collider; 2];
        for (k, i) in [-1.0f32, 1.0].into_iter().enumerate() {
            let leg_angle = i * 0.05;
            let leg = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(x0 - i * LEG_AWAY / SCALE, y0))
                    .rotation(leg_angle)
                    .can_sleep(false),
            );
            leg_colliders[k] = world.colliders.insert_with_parent(
                ColliderBuilder::cuboid(LEG_W / SCALE, LEG_H / SCALE)
                    .density(1.0)
                    .friction(LEG_FRICTION)
                    .friction_combine_rule(CoefficientCombineRule::GeometricMean)
                    .restitution(0.0)
                    .collision_groups(InteractionGroups::new(
                        LEG_GROUP,
                        GROUND_GROUP,
                        InteractionTestMode::And,
                    )),
                leg,
                &mut world.bodies,
            );
            // pybox2d's `revoluteJointDef` sets the reference angle to the bodies' relative
            // angle at creation (hull 0, leg i * 0.05). rapier measures the joint angle between
            // the two local frames, so rotating the hull's frame by it is the reference angle.
            // Anchors: the hull's origin, and a point 20 px aside and 18 px up on the leg. In
            // Box2D they start apart and the solver pulls them together; a multibody starts
            // with them joined (the leg placed by the joint at angle 0), which is where Box2D
            // ends up after its first step.
            // [0.4, 0.9] for the i = -1 leg, [-0.9, -0.4] for the other.
            let limits = if i < 0.0 {
                LEG_LIMITS
            } else {
                [-LEG_LIMITS[1], -LEG_LIMITS[0]]
            };
            let joint = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
                .local_frame1(Pose::new(Vector::ZERO, leg_angle))
                .local_frame2(Pose::new(
                    Vector::new(i * LEG_AWAY / SCALE, LEG_DOWN / SCALE),
                    0.0,
                ))
                .limits(JointAxis::AngX, limits)
                .motor_model(JointAxis::AngX, MotorModel::ForceBased)
                .motor_velocity(JointAxis::AngX, LEG_MOTOR_SPEED * i, MOTOR_DAMPING)
                .motor_max_force(JointAxis::AngX, LEG_SPRING_TORQUE)
                .contacts_enabled(false)
                .build();
            world
                .multibody_joints
                .insert(hull, leg, joint, true)
                .expect("a hull and two legs form a tree");
            legs[k] = leg;
        }

        let mut lander = Self {
            world,
            hull,
            legs,
            ground_collider,
            hull_collider,
            leg_colliders,
            clear_forces: false,
        };
        // Box2D applies the force to the hull's centre for the first step and then clears it.
        // A user force on a multibody link enters the articulated dynamics (a torque would not
        // be handled faithfully by rapier 0.36's multibody, but this force has none).
        lander.world.bodies[hull].add_force(Vector::new(initial_force[0], initial_force[1]), true);
        lander.clear_forces = true;
        lander
    }

    fn with_multibody(&mut self, f: impl FnOnce(&mut Multibody, &mut RigidBodySet)) {
        let link = *self
            .world
            .multibody_joints
            .rigid_body_link(self.hull)
            .expect("the hull is the multibody's root");
        let mb = self
            .world
            .multibody_joints
            .get_multibody_mut(link.multibody)
            .expect("the lander's multibody lives as long as the world");
        f(mb, &mut self.world.bodies);
    }

    /// Box2D's `ApplyLinearImpulse(impulse, point, wake=True)` on the hull, as the generalised
    /// impulse `J^T [p; r x p]` on the multibody. Uses the augmented mass of the last step's
    /// configuration (rapier computes it while stepping), so call it after the first step:
    /// Gymnasium's reset takes that step with the engines off.
    pub fn apply_hull_impulse(&mut self, impulse: [f32; 2], point: [f32; 2]) {
        let com = self.world.bodies[self.hull].center_of_mass();
        let r = [point[0] - com.x, point[1] - com.y];
        let torque = r[0] * impulse[1] - r[1] * impulse[0];
        let hull = self.hull;
        let links = &self.world.multibody_joints;
        let root = links
            .rigid_body_link(hull)
            .expect("the hull is the root")
            .id;
        self.with_multibody(|mb, bodies| {
            let generalised = mb
                .body_jacobian(root)
                .tr_mul(&na::Vector3::new(impulse[0], impulse[1], torque));
            let dq = mb
                .inv_augmented_mass()
                .solve(&generalised)
                .expect("the augmented mass matrix is invertible");
            let mut velocity = mb.generalized_velocity_mut();
            velocity += dq;
            mb.update_rigid_bodies(bodies, false);
        });
    }

    /// One `1/FPS` step of the world.
    pub fn step(&mut self) {
        self.world.step();
        if self.clear_forces {
            self.world.bodies[self.hull].reset_forces(true);
            self.clear_forces = false;
        }
    }

    pub fn hull(&self) -> BodyState {
        self.body(self.hull)
    }

    pub fn leg(&self, k: usize) -> BodyState {
        self.body(self.legs[k])
    }

    fn body(&self, handle: RigidBodyHandle) -> BodyState {
        let b = &self.world.bodies[handle];
        let (p, v) = (b.translation(), b.linvel());
        BodyState {
            position: [p.x, p.y],
            angle: b.rotation().angle(),
            linvel: [v.x, v.y],
            angvel: b.angvel(),
        }
    }

    /// Whether the hull touches the ground (Gymnasium's `game_over`).
    pub fn hull_touches_ground(&self) -> bool {
        self.touches_ground(self.hull_collider)
    }

    /// Whether leg `k` touches the ground (Gymnasium's `legs[k].ground_contact`).
    pub fn leg_touches_ground(&self, k: usize) -> bool {
        self.touches_ground(self.leg_colliders[k])
    }

    fn touches_ground(&self, collider: ColliderHandle) -> bool {
        self.world
            .narrow_phase
            .contact_pair(self.ground_collider, collider)
            .is_some_and(|pair| {
                pair.manifolds()
                    .iter()
                    .flat_map(|m| m.points.iter())
                    .any(|p| p.dist < TOUCHING_DISTANCE)
            })
    }

    /// Whether the hull and both legs are under Box2D's sleep tolerances.
    pub fn all_quiet(&self) -> bool {
        std::iter::once(self.hull).chain(self.legs).all(|h| {
            let b = &self.world.bodies[h];
            let v = b.linvel();
            SleepTimer::is_quiet([v.x, v.y], b.angvel())
        })
    }
}

/// The moon: Gymnasium's static body with a flat edge along `y = 0` plus one edge per terrain
/// chunk, as a single polyline collider.
fn insert_ground(world: &mut PhysicsWorld, terrain: &Terrain) -> ColliderHandle {
    let mut vertices: Vec<Vector> = terrain
        .points
        .iter()
        .map(|p| Vector::new(p[0], p[1]))
        .collect();
    let n = vertices.len() as u32;
    let mut indices: Vec<[u32; 2]> = (0..n - 1).map(|i| [i, i + 1]).collect();
    vertices.push(Vector::new(0.0, 0.0));
    vertices.push(Vector::new(W, 0.0));
    indices.push([n, n + 1]);
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    world.colliders.insert_with_parent(
        ColliderBuilder::polyline(vertices, Some(indices))
            .friction(GROUND_FRICTION)
            .friction_combine_rule(CoefficientCombineRule::GeometricMean)
            .restitution(0.0)
            .collision_groups(InteractionGroups::new(
                GROUND_GROUP,
                Group::ALL,
                InteractionTestMode::And,
            )),
        ground,
        &mut world.bodies,
    )
}
