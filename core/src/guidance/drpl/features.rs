//! The reward features phi(s_{t+1}, a_t) of each task (algorithms.md section 3, \[choice\]): the
//! synthetic oracle's true reward and the belief's reward model are both `theta . phi`.
//!
//! Every feature is oriented so that "more is better" under the task's own reward, which makes
//! the env's shaping one valid theta (Lunar Lander's features mirror Gymnasium's shaping and fuel
//! costs term by term).

use super::trajectories::TrajectoryStep;
use crate::scene_graph::lunar_lander::SIDE_ENGINE_THRESHOLD;
use crate::sim::placing::over_opening;
use crate::sim::reaching::{TABLE_HALF_X, TABLE_HALF_Y, in_goal};
use crate::sim::{Task, TaskRef};

pub const LUNAR_LANDER: [&str; 6] = [
    "neg_distance_to_pad",
    "neg_speed",
    "neg_abs_angle",
    "leg_contact",
    "neg_main_throttle",
    "neg_side_throttle",
];

pub const REACHING: [&str; 4] = ["neg_abs_x", "neg_abs_y", "in_target", "neg_action_norm"];

pub const PLACING: [&str; 5] = [
    "neg_distance_to_hoop",
    "neg_height_error",
    "above_hoop",
    "released_above_hoop",
    "neg_move_norm",
];

/// Placing's preferred carrying height: 10 cm above the hoop's top, clear of the no-entry box.
pub const PLACING_HEIGHT: f64 = 1.10;

/// The names of a task's features, in order (for output files and the trainer's display).
pub fn names(task: Task) -> &'static [&'static str] {
    match task {
        Task::LunarLander => &LUNAR_LANDER,
        Task::Reaching => &REACHING,
        Task::Placing => &PLACING,
    }
}

/// The number of features of a task, the belief's dimension.
pub fn dim(task: Task) -> usize {
    names(task).len()
}

/// The number of features of any task: ours, or the names a declared task lists.
pub fn dim_of(task: &TaskRef) -> usize {
    match task {
        TaskRef::Builtin(t) => dim(*t),
        TaskRef::Declared(d) => d.features.len(),
    }
}

/// The names of any task's features.
pub fn names_of(task: &TaskRef) -> Vec<String> {
    match task {
        TaskRef::Builtin(t) => names(*t).iter().map(|n| n.to_string()).collect(),
        TaskRef::Declared(d) => d.features.clone(),
    }
}

/// phi of a recorded step: ours computed here; a declared task's as its env reported them, or
/// (when it declares none) the observation after the step.
pub fn of_step(task: &TaskRef, step: &TrajectoryStep) -> Vec<f64> {
    match task {
        TaskRef::Builtin(t) => phi(*t, &step.next_obs, &step.action),
        TaskRef::Declared(d) if d.env_features => step.env_features.clone(),
        TaskRef::Declared(_) => step.next_obs.iter().map(|&v| f64::from(v)).collect(),
    }
}

/// phi(s_{t+1}, a_t): `next_obs` is the observation after `action` (in `[-1, 1]^n`).
pub fn phi(task: Task, next_obs: &[f32], action: &[f32]) -> Vec<f64> {
    match task {
        Task::LunarLander => lunar_lander(next_obs, action).to_vec(),
        Task::Reaching => reaching(next_obs, action).to_vec(),
        Task::Placing => placing(next_obs, action).to_vec(),
    }
}

/// Gymnasium's 8 observations (x, y, vx, vy, angle, angular velocity, two leg contacts) and the
/// (main, lateral) action. The throttles follow Gymnasium's firing rules: the main engine fires
/// for a0 > 0 at (clip(a0, 0, 1) + 1) / 2, a side engine for |a1| > 0.5 at clip(|a1|, 0.5, 1).
pub fn lunar_lander(next_obs: &[f32], action: &[f32]) -> [f64; 6] {
    let o: Vec<f64> = next_obs.iter().map(|&v| f64::from(v)).collect();
    let (a0, a1) = (f64::from(action[0]), f64::from(action[1]));
    let main = if a0 > 0.0 {
        (a0.clamp(0.0, 1.0) + 1.0) * 0.5
    } else {
        0.0
    };
    let side = if a1.abs() > f64::from(SIDE_ENGINE_THRESHOLD) {
        a1.abs().clamp(0.5, 1.0)
    } else {
        0.0
    };
    [
        -o[0].hypot(o[1]),
        -o[2].hypot(o[3]),
        -o[4].abs(),
        (o[6] + o[7]) / 2.0,
        -main,
        -side,
    ]
}

/// Gripper (x, y) and the (dx, dy) action; positions are scaled by the table's half sizes.
pub fn reaching(next_obs: &[f32], action: &[f32]) -> [f64; 4] {
    let (x, y) = (f64::from(next_obs[0]), f64::from(next_obs[1]));
    [
        -x.abs() / f64::from(TABLE_HALF_X),
        -y.abs() / f64::from(TABLE_HALF_Y),
        indicator(in_goal([next_obs[0], next_obs[1]])),
        -norm(&action[..2]),
    ]
}

/// Gripper (x, y, z, g) with g < 0 open, and the (dx, dy, dz, gripper) action. "Above the
/// hoop" is over its 0.2 m x 0.2 m opening (the ring), the only place a release succeeds.
pub fn placing(next_obs: &[f32], action: &[f32]) -> [f64; 5] {
    let (x, y, z) = (
        f64::from(next_obs[0]),
        f64::from(next_obs[1]),
        f64::from(next_obs[2]),
    );
    let above = over_opening(next_obs[0], next_obs[1]);
    let open = next_obs[3] < 0.0;
    [
        -x.hypot(y),
        -(z - PLACING_HEIGHT).abs(),
        indicator(above),
        indicator(above && open),
        -norm(&action[..3]),
    ]
}

fn indicator(b: bool) -> f64 {
    if b { 1.0 } else { 0.0 }
}

fn norm(v: &[f32]) -> f64 {
    v.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-6
    }

    #[test]
    fn names_match_the_feature_vectors() {
        for task in Task::ALL {
            let env = task.make_env();
            let obs = vec![0.0; env.spec().observation_space.dim()];
            let act = vec![0.0; env.spec().action_space.dim()];
            assert_eq!(phi(task, &obs, &act).len(), dim(task), "{task}");
        }
    }

    #[test]
    fn lunar_lander_signs_and_contact() {
        let f = lunar_lander(&[0.3, 0.4, -0.6, 0.8, -0.2, 0.0, 1.0, 0.0], &[0.0, 0.0]);
        assert!(close(f[0], -0.5) && close(f[1], -1.0) && close(f[2], -0.2));
        assert!(close(f[3], 0.5));
        assert_eq!((f[4], f[5]), (0.0, 0.0));
        let both = lunar_lander(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0], &[0.0, 0.0]);
        assert_eq!(both[..4], [0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn lunar_lander_throttles_follow_gymnasium_firing_rules() {
        let obs = [0.0; 8];
        let main = |a0: f32| lunar_lander(&obs, &[a0, 0.0])[4];
        assert_eq!(main(0.0), 0.0);
        assert_eq!(main(-1.0), 0.0);
        assert!(close(main(1e-4), -0.50005));
        assert!(close(main(1.0), -1.0));
        let side = |a1: f32| lunar_lander(&obs, &[0.0, a1])[5];
        assert_eq!(side(0.5), 0.0);
        assert_eq!(side(-0.5), 0.0);
        assert!(close(side(0.5001), -0.5001));
        assert!(close(side(-0.75), -0.75));
        assert!(close(side(-1.0), -1.0));
        // Out-of-range actions count at full throttle, as the env clips them.
        assert!(close(side(1.5), -1.0));
        assert!(close(main(2.0), -1.0));
    }

    #[test]
    fn reaching_scales_positions_and_tests_the_goal_edges() {
        let f = reaching(&[-0.19, 0.35], &[0.6, -0.8]);
        assert!(close(f[0], -0.5) && close(f[1], -1.0));
        assert_eq!(f[2], 0.0);
        assert!(close(f[3], -1.0));
        assert_eq!(reaching(&[0.05, -0.125], &[0.0, 0.0])[2], 1.0);
        assert_eq!(reaching(&[0.0501, 0.0], &[0.0, 0.0])[2], 0.0);
        assert_eq!(reaching(&[0.0, 0.1251], &[0.0, 0.0])[2], 0.0);
    }

    #[test]
    fn placing_height_and_distance() {
        let f = placing(&[0.3, -0.4, 1.3, 1.0], &[0.0, 0.0, 0.0, -1.0]);
        assert!(close(f[0], -0.5));
        assert!(close(f[1], -0.2));
        assert_eq!(f[4], 0.0);
        assert!(close(placing(&[0.0, 0.0, 1.0, 1.0], &[0.0; 4])[1], -0.1));
        // The gripper command does not count as a move.
        assert!(close(placing(&[0.0; 4], &[0.0, 0.6, 0.8, 1.0])[4], -1.0));
    }

    #[test]
    fn placing_indicators_on_both_sides_of_the_opening() {
        let above = |x: f32, y: f32, g: f32| {
            let f = placing(&[x, y, 1.1, g], &[0.0; 4]);
            (f[2], f[3])
        };
        assert_eq!(above(0.0999, -0.0999, 1.0), (1.0, 0.0));
        assert_eq!(above(0.0999, -0.0999, -1.0), (1.0, 1.0));
        assert_eq!(above(0.1, 0.0, -1.0), (0.0, 0.0));
        assert_eq!(above(0.0, -0.1, -1.0), (0.0, 0.0));
        assert_eq!(above(-0.2, 0.0, 1.0), (0.0, 0.0));
    }
}
