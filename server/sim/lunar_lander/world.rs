//! The rapier2d world of one episode: the ground, the hull and its two legs, built as Gymnasium
//! builds them on Box2D, with rapier tuned to behave like Box2D where it matters.
//!
//! Box2D settings we reproduce, and how:
//! - Friction: Box2D mixes `sqrt(f1 * f2)`; rapier's `GeometricMean` rule is that same formula,
//!   so every collider keeps Gymnasium's own coefficient (hull 0.1, legs Box2D's default 0.2,
//!   ground 0.1). Restitution is 0 everywhere (Box2D mixes with max).
//! - Joint stiffness: Gymnasium steps Box2D with 180 velocity and 60 position iterations, which
//!   makes the hull-leg hinges effectively rigid. rapier's joints are rigid by default (1 MHz
//!   spring); we keep that, warm-start them and run `SOLVER_ITERATIONS` substeps.
//! - Leg motors: Box2D's revolute motor is a hard velocity constraint whose accumulated impulse is
//!   clamped to `maxMotorTorque * dt`. A rapier velocity motor with a huge damping factor
//!   (zero constraint-force mixing) and `max_force` = the torque is that constraint; rapier
//!   clamps it per substep to `max_force * substep_dt`, the same total per step. The joint
//!   limits are folded into that motor (see `leg_joint.rs` for why and how).
//!
//! KNOWN GAP: with the lander standing on its legs, rapier's solver does not transmit the
//! hull's weight through the light legs (0.07 vs 4.8 mass units) to the ground: the motor's
//! impulse stays far below its bound and the legs fold until the hull touches the ground. More
//! substeps or PGS iterations, joint warm-starting, stiffer contacts and larger motor torques
//! did not change that; Box2D holds the same load with the motor saturated at 40 N m against
//! the limit. So landings end as crashes and the lander never comes to rest.
//! - Sleeping: rapier's sleeping is off for the lander; `sleep.rs` applies Box2D's rule.
//! - Touching: Box2D reports a contact once the shapes' skins (`b2_polygonRadius` = 0.01 on the
//!   polygon and on the edge) overlap, i.e. when the cores are closer than 0.02; we test
//!   rapier's contact points against that same distance.

use rapier2d::prelude::*;

use super::leg_joint::LegJoint;
use super::terrain::Terrain;
use super::{
    H, LANDER_POLY, LEG_AWAY, LEG_DOWN, LEG_H, LEG_SPRING_TORQUE, LEG_W, SCALE, W,
    sleep::SleepTimer,
};

/// Substeps per 1/50 s step: the joint anchors stay within 1e-4 units in flight, and more
/// substeps did not help the standing lander (see the module docs).
const SOLVER_ITERATIONS: usize = 8;
/// The velocity motor's damping factor: large enough that its constraint-force mixing
/// (`1 / (substep_dt * damping)`) vanishes, i.e. a hard velocity constraint like Box2D's
/// (finite, so that no `0 * inf` can appear in rapier's coefficient formulas).
const MOTOR_DAMPING: f32 = 1.0e9;
/// Box2D's `b2_polygonRadius` on each of the two touching shapes.
const TOUCHING_DISTANCE: f32 = 2.0 * 0.01;

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
    /// The hull-leg revolute joints, and how each folds Box2D's limits into its motor.
    joints: [ImpulseJointHandle; 2],
    leg_joints: [LegJoint; 2],
    /// Each joint's reference angle (the legs' relative angle at creation).
    references: [f32; 2],
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
        params.warmstart_joints = true;
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
                .can_sleep(false)
                // Box2D sweeps dynamic bodies against static ones (TOI) by default.
                .ccd_enabled(true),
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
        world.bodies[hull].add_force(Vector::new(initial_force[0], initial_force[1]), true);

        let mut legs = [hull; 2];
        let mut leg_colliders = [hull_collider; 2];
        let mut joints = [ImpulseJointHandle::invalid(); 2];
        let mut leg_joints = [LegJoint { sign: 1.0 }; 2];
        let mut references = [0.0; 2];
        for (k, i) in [-1.0f32, 1.0].into_iter().enumerate() {
            let leg_angle = i * 0.05;
            let leg = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(x0 - i * LEG_AWAY / SCALE, y0))
                    .rotation(leg_angle)
                    .can_sleep(false)
                    .ccd_enabled(true),
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
            // The anchors (hull origin, and a point 20 px aside and 18 px up on the leg) do not
            // coincide at creation; the joint pulls them together on the first step, as
            // Box2D's position solver does.
            let joint = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
                .local_frame1(Pose::new(Vector::ZERO, leg_angle))
                .local_frame2(Pose::new(
                    Vector::new(i * LEG_AWAY / SCALE, LEG_DOWN / SCALE),
                    0.0,
                ))
                .motor_model(JointAxis::AngX, MotorModel::ForceBased)
                .motor_velocity(JointAxis::AngX, 0.3 * i, MOTOR_DAMPING)
                .motor_max_force(JointAxis::AngX, LEG_SPRING_TORQUE)
                .contacts_enabled(false)
                .build();
            joints[k] = world.impulse_joints.insert(hull, leg, joint, true);
            leg_joints[k] = LegJoint { sign: -i };
            references[k] = leg_angle;
            legs[k] = leg;
        }

        Self {
            world,
            hull,
            legs,
            ground_collider,
            hull_collider,
            leg_colliders,
            clear_forces: true,
            joints,
            leg_joints,
            references,
        }
    }

    /// Box2D's `ApplyLinearImpulse(impulse, point, wake=True)` on the hull.
    pub fn apply_hull_impulse(&mut self, impulse: [f32; 2], point: [f32; 2]) {
        self.world.bodies[self.hull].apply_impulse_at_point(
            Vector::new(impulse[0], impulse[1]),
            Vector::new(point[0], point[1]),
            true,
        );
    }

    /// One `1/FPS` step of the world.
    pub fn step(&mut self) {
        self.command_leg_motors();
        self.world.step();
        if self.clear_forces {
            self.world.bodies[self.hull].reset_forces(true);
            self.clear_forces = false;
        }
    }

    /// Box2D's `GetJointAngle`: the leg's angle relative to the hull, minus the reference.
    pub fn joint_angle(&self, k: usize) -> f32 {
        let hull = self.world.bodies[self.hull].rotation().angle();
        let leg = self.world.bodies[self.legs[k]].rotation().angle();
        super::wrap_angle(leg - hull - self.references[k])
    }

    fn command_leg_motors(&mut self) {
        let dt = self.world.integration_parameters.dt;
        for k in 0..2 {
            let cmd = self.leg_joints[k].command(self.joint_angle(k), LEG_SPRING_TORQUE, dt);
            let joint = self
                .world
                .impulse_joints
                .get_mut(self.joints[k], false)
                .expect("the leg joints live as long as the world");
            joint
                .data
                .set_motor_velocity(JointAxis::AngX, cmd.speed, MOTOR_DAMPING)
                .set_motor_max_force(JointAxis::AngX, cmd.max_torque);
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
