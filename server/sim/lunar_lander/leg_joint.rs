//! The legs' revolute joints: Box2D's motor plus limits, as one velocity motor whose target and
//! torque bound are chosen before every step.
//!
//! Why not rapier's joint limits: in rapier2d 0.36 a joint that carries both an angular limit
//! and an angular motor loses its motor as soon as the leg is pressed against the ground (the
//! legs then fold under the hull's weight whatever the torque), and a limit on a second joint
//! between the same bodies is ignored. A motor alone behaves, so the limits are folded into it.
//!
//! Box2D's joint (`b2RevoluteJoint`): the motor drives the joint speed to `speed` with at most
//! `max_torque`; the limits stop the joint angle at `[lower, upper]` with unbounded torque.
//! Gymnasium's motors always drive the leg towards its "rest" limit (0.4 rad for the `i = -1`
//! leg, -0.4 for the other) and the ground pushes it towards its "fold" limit (0.9 / -0.9).
//! In the frame where the motor turns the leg at -0.3 rad/s and the rest limit is the lower one:
//! - between the limits: Box2D's motor exactly (-0.3 rad/s, at most 40 N m);
//! - at or past the rest limit: hold the angle (speed 0, or back towards the limit) with the
//!   motor's 40 N m. Box2D holds it there with the motor pushing in and the limit pushing out,
//!   and lets the leg fold only under more than 40 N m: the same. (The limit's unbounded push
//!   out of the rest side becomes 40 N m, which nothing in this task comes close to needing.)
//! - past the fold limit: hold with an unbounded torque and come back to the limit, like the
//!   limit. The leg may overshoot for one step before this engages.

/// The joint's target speed (rad/s) and torque bound (N m) for the next step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorCommand {
    pub speed: f32,
    pub max_torque: f32,
}

/// One leg's joint: `sign` flips the `i = +1` leg into the frame described above.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegJoint {
    /// +1 for the `i = -1` leg (limits [0.4, 0.9], speed -0.3), -1 for the other.
    pub sign: f32,
}

/// Box2D's motor speed magnitude in Gymnasium (`0.3 * i`).
const MOTOR_SPEED: f32 = 0.3;
const REST_LIMIT: f32 = 0.4;
const FOLD_LIMIT: f32 = 0.9;
/// Fraction of a limit violation removed per step, as Box2D's position solver's Baumgarte
/// factor (`b2_baumgarte` = 0.2).
const BAUMGARTE: f32 = 0.2;
/// "Unbounded": far more than any torque the lander can produce.
const LIMIT_TORQUE: f32 = 1.0e6;

impl LegJoint {
    /// The command for joint angle `angle` (Box2D's `GetJointAngle`), with `max_torque` the
    /// motor's torque bound and `dt` the step.
    pub fn command(&self, angle: f32, max_torque: f32, dt: f32) -> MotorCommand {
        let phi = self.sign * angle;
        let (speed, max_torque) = if phi > FOLD_LIMIT {
            ((FOLD_LIMIT - phi) * BAUMGARTE / dt, LIMIT_TORQUE)
        } else if phi <= REST_LIMIT {
            ((REST_LIMIT - phi) * BAUMGARTE / dt, max_torque)
        } else {
            (-MOTOR_SPEED, max_torque)
        };
        MotorCommand {
            speed: self.sign * speed,
            max_torque,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f32 = 0.02;

    #[test]
    fn between_the_limits_it_is_gymnasiums_motor() {
        let right = LegJoint { sign: 1.0 };
        assert_eq!(
            right.command(0.6, 40.0, DT),
            MotorCommand {
                speed: -0.3,
                max_torque: 40.0
            }
        );
        let left = LegJoint { sign: -1.0 };
        assert_eq!(
            left.command(-0.6, 40.0, DT),
            MotorCommand {
                speed: 0.3,
                max_torque: 40.0
            }
        );
    }

    #[test]
    fn at_the_rest_limit_it_holds_with_the_motor_torque() {
        let right = LegJoint { sign: 1.0 };
        let c = right.command(0.4, 40.0, DT);
        assert_eq!((c.speed, c.max_torque), (0.0, 40.0));
        // Past it: back towards the limit.
        assert!(right.command(0.3, 40.0, DT).speed > 0.0);
        assert!(LegJoint { sign: -1.0 }.command(-0.3, 40.0, DT).speed < 0.0);
    }

    #[test]
    fn past_the_fold_limit_it_is_a_hard_stop() {
        let right = LegJoint { sign: 1.0 };
        let c = right.command(0.95, 40.0, DT);
        assert!(c.speed < 0.0 && c.max_torque >= LIMIT_TORQUE);
        let c = LegJoint { sign: -1.0 }.command(-0.95, 40.0, DT);
        assert!(c.speed > 0.0 && c.max_torque >= LIMIT_TORQUE);
    }
}
