//! Placing through the public `Env` interface: the ball's fate under both grippers and both
//! hoops, the authors' gradual gripper and start, and the safety gate around the hoop.

use crate::support::episodes::run_until_done;
use dualrep_core::sim::placing::{self, Placing};
use dualrep_core::sim::rollout::{SimplePolicy, run_episodes, run_episodes_with};
use dualrep_core::sim::{
    Env, EnvOptions, GripObservation, HoopShape, Outcome, PlacingSuccess, RenderState, Step, Task,
    Variant,
};

// ---------------------------------------------------------------- Placing: the ball

/// The first version of Placing: one "open" command drops the ball, which then falls (rapier).
fn uniform_placing() -> Placing {
    Placing::with_options(EnvOptions {
        variant: Variant::Uniform,
        ..EnvOptions::default()
    })
}

fn placing_obs(env: &Placing) -> [f32; 4] {
    env.observation().try_into().unwrap()
}

/// Fly the closed gripper to `target` (rise, cross at travel height, then move vertically)
/// with proportional laws soft enough that the safety gate never blocks them. Panics if the
/// episode ends on the way.
fn fly_to(env: &mut Placing, target: [f32; 3]) {
    let travel = target[2].max(1.1);
    for _ in 0..400 {
        let [x, y, z, _] = placing_obs(env);
        let near_xy = (x - target[0]).abs() < 1e-3 && (y - target[1]).abs() < 1e-3;
        if near_xy && (z - target[2]).abs() < 1e-3 {
            return;
        }
        let p = |to: f32, at: f32, scale: f32| ((to - at) / scale).clamp(-1.0, 1.0);
        let a = if !near_xy && z < travel - 0.01 {
            [0.0, 0.0, p(travel, z, 0.1), 1.0]
        } else if !near_xy {
            [p(target[0], x, 0.05), p(target[1], y, 0.05), 0.0, 1.0]
        } else {
            [0.0, 0.0, p(target[2], z, 0.1), 1.0]
        };
        let step = env.step(&a);
        assert!(
            !step.done(),
            "episode ended on the way to {target:?}: {step:?}"
        );
    }
    panic!("did not reach {target:?}: at {:?}", env.observation());
}

/// Open the gripper and stand still until the episode ends; the last step and how many "open"
/// steps it took.
fn open_until_done(env: &mut Placing) -> (Step, u32) {
    run_until_done(env, &[0.0, 0.0, 0.0, -1.0])
}

fn ball(env: &Placing) -> ([f32; 3], bool) {
    match env.render() {
        RenderState::Placing {
            ball, ball_held, ..
        } => (ball, ball_held),
        other => panic!("wrong render state {other:?}"),
    }
}

#[test]
fn ball_released_over_the_ring_falls_through() {
    let mut env = uniform_placing();
    env.reset(7);
    fly_to(&mut env, [0.0, 0.0, 1.05]);
    assert!(ball(&env).1, "the ball starts held");
    let (step, n) = open_until_done(&mut env);
    assert_eq!(step.outcome, Some(Outcome::Success));
    assert!(step.terminated && step.reward == 100.0);
    assert!(n <= 3, "a 5 cm drop takes about 0.1 s, took {n} steps");
    let (b, held) = ball(&env);
    assert!(!held && b[2] < placing::HOOP_TOP_Z && b[0].abs() < 0.1 && b[1].abs() < 0.1);
}

#[test]
fn ball_released_over_the_ring_off_centre_still_falls_through() {
    // 5 cm off centre in both axes: still clear of the plates (opening half 0.1, ball 0.025).
    let mut env = uniform_placing();
    env.reset(8);
    fly_to(&mut env, [0.05, -0.05, 1.2]);
    let (step, _) = open_until_done(&mut env);
    assert_eq!(step.outcome, Some(Outcome::Success));
}

#[test]
fn ball_released_over_the_table_away_from_the_hoop_fails() {
    let mut env = uniform_placing();
    env.reset(9);
    fly_to(&mut env, [-0.45, 0.2, 1.2]);
    let (step, _) = open_until_done(&mut env);
    assert_eq!(step.outcome, Some(Outcome::Failure));
    assert!(step.terminated && step.reward == 0.0);
}

#[test]
fn ball_released_over_the_closed_top_rests_there_and_fails_after_two_seconds() {
    let mut env = uniform_placing();
    env.reset(10);
    fly_to(&mut env, [0.17, 0.0, 1.06]);
    let (step, n) = open_until_done(&mut env);
    assert_eq!(step.outcome, Some(Outcome::Failure));
    assert_eq!(n, 40, "2 s at 20 Hz");
    let (b, _) = ball(&env);
    // It came to rest on the plate: centre one radius above the hoop's top.
    assert!(
        (b[2] - placing::HOOP_TOP_Z - placing::BALL_RADIUS).abs() < 0.005,
        "{b:?}"
    );
}

#[test]
fn closing_again_does_not_regrasp() {
    let mut env = uniform_placing();
    env.reset(11);
    fly_to(&mut env, [-0.45, 0.2, 1.5]);
    env.step(&[0.0, 0.0, 0.0, -1.0]);
    let step = env.step(&[0.0, 0.0, 1.0, 1.0]);
    assert_eq!(step.obs[3], 1.0, "the gripper reports the last command");
    assert!(!ball(&env).1, "but the ball stays free");
}

#[test]
fn gripper_touching_the_hoop_from_the_side_fails() {
    let mut env = Placing::new();
    env.reset(12);
    fly_to(&mut env, [-0.35, 0.0, 0.9]);
    let mut last = None;
    for _ in 0..20 {
        let step = env.step(&[1.0, 0.0, 0.0, 1.0]);
        if step.done() {
            last = Some(step);
            break;
        }
    }
    let step = last.expect("the gripper should have hit the hoop's wall");
    assert_eq!(step.outcome, Some(Outcome::Failure));
    // It touched the wall (outer face x = -0.25) before the gate's no-entry box stopped it.
    let x = step.obs[0];
    assert!(x > -0.25 - placing::BALL_RADIUS && x < -0.17, "x = {x}");
    assert!(ball(&env).1, "the ball was still held");
}

#[test]
fn gripper_touching_the_top_from_beyond_the_no_entry_box_fails() {
    // Over the hoop's -x end (x < -0.17) nothing stops a descent onto the top plates.
    let mut env = Placing::new();
    env.reset(13);
    fly_to(&mut env, [-0.21, 0.0, 1.1]);
    let mut outcome = None;
    for _ in 0..20 {
        let step = env.step(&[0.0, 0.0, -0.5, 1.0]);
        if step.done() {
            assert!(step.obs[2] < placing::HOOP_TOP_Z + placing::BALL_RADIUS);
            outcome = step.outcome;
            break;
        }
    }
    assert_eq!(outcome, Some(Outcome::Failure));
}

/// The authors' ring: where the box's wall and top end an episode, the gate keeps the gripper
/// clear of every part of it, and a release over the opening still succeeds.
#[test]
fn the_ring_hoop_leaves_nothing_to_touch_behind_the_gate() {
    let ring = EnvOptions {
        hoop: HoopShape::Ring,
        ..EnvOptions::default()
    };
    let mut env = Placing::with_options(ring);
    env.reset(12);
    fly_to(&mut env, [-0.35, 0.0, 0.9]);
    for _ in 0..20 {
        let step = env.step(&[1.0, 0.0, 0.0, 1.0]);
        assert!(
            !step.done(),
            "the box's wall would have ended it here: {:?}",
            step.obs
        );
    }
    let x = placing_obs(&env)[0];
    assert!(
        (-0.25..=-0.17).contains(&x),
        "the gate stops it short of the no-entry box: x = {x}"
    );
    env.reset(13);
    fly_to(&mut env, [-0.21, 0.0, 1.1]);
    for _ in 0..40 {
        assert!(
            !env.step(&[0.0, 0.0, -0.5, 1.0]).done(),
            "nothing under the ring's -x side"
        );
    }
    assert!(placing_obs(&env)[2] < placing::HOOP_TOP_Z - 0.1);
    fly_to(&mut env, [0.0, 0.0, 1.05]);
    let (step, _) = open_until_done(&mut env);
    assert_eq!(step.outcome, Some(Outcome::Success));
}

/// The authors' scene run from their fork (docs/results/calibration/): 200 random episodes
/// last 71.6 steps, none touches the hoop and none succeeds. The ring with their release point
/// (eight net "open" steps) gives the same: a release after n net opens with nothing to touch
/// lasts n(n + 1) = 72 steps on average.
#[test]
fn random_play_on_the_ring_with_the_authors_release_matches_their_scene() {
    let authors_scene = EnvOptions {
        hoop: HoopShape::Ring,
        release_at: 0.92,
        ..EnvOptions::default()
    };
    let (s, _) = run_episodes_with(Task::Placing, &authors_scene, SimplePolicy::Random, 200, 0);
    assert!(
        (60.0..=85.0).contains(&s.mean_length) && s.success_rate <= 0.02,
        "{s:?}"
    );
    let (ours, _) = run_episodes(Task::Placing, SimplePolicy::Random, 200, 0);
    assert!(
        ours.mean_length > s.mean_length + 15.0,
        "{ours:?} against {s:?}"
    );
}

// ---------------------------------------------------------------- Placing: the authors' gripper

#[test]
fn authors_gripper_lets_go_after_twelve_open_steps_over_the_ring_and_succeeds_at_once() {
    let mut env = Placing::new();
    env.reset(7);
    fly_to(&mut env, [0.0, 0.0, 1.05]);
    for i in 1..12 {
        let step = env.step(&[0.0, 0.0, 0.0, -1.0]);
        assert!(!step.done(), "released after {i} open steps");
        assert_eq!(
            step.obs[3], -1.0,
            "the observation shows the last command's sign"
        );
        assert!(ball(&env).1);
    }
    let step = env.step(&[0.0, 0.0, 0.0, -1.0]);
    assert_eq!(step.outcome, Some(Outcome::Success));
    assert!(step.terminated && step.reward == 100.0);
    let (b, held) = ball(&env);
    assert!(
        !held && (b[2] - 1.05).abs() < 1e-3,
        "judged where it was let go: {b:?}"
    );
}

#[test]
fn authors_gripper_release_away_from_the_ring_fails_at_once() {
    for target in [[-0.45, 0.2, 1.2], [0.17, 0.0, 1.06]] {
        let mut env = Placing::new();
        env.reset(9);
        fly_to(&mut env, target);
        let (step, n) = open_until_done(&mut env);
        assert_eq!(n, 12);
        assert_eq!(step.outcome, Some(Outcome::Failure), "{target:?}");
        assert!(step.terminated && step.reward == 0.0);
    }
}

#[test]
fn authors_gripper_integrates_commands_and_zero_holds_it() {
    let mut env = Placing::new();
    env.reset(3);
    fly_to(&mut env, [-0.45, 0.2, 1.3]);
    let level = |env: &Placing| match env.render() {
        RenderState::Placing { grip_level, .. } => grip_level,
        other => panic!("{other:?}"),
    };
    // Open, close, open, ... never gets past one step open; a zero command keeps the level.
    for _ in 0..50 {
        env.step(&[0.0, 0.0, 0.0, -0.3]);
        assert!(!env.step(&[0.0, 0.0, 0.0, 0.7]).done());
    }
    assert_eq!(level(&env), 1.0);
    for _ in 0..5 {
        env.step(&[0.0, 0.0, 0.0, -1.0]);
    }
    let five_open = level(&env);
    assert!((five_open - 0.95).abs() < 1e-5, "{five_open}");
    let step = env.step(&[0.0, 0.0, 0.0, 0.0]);
    assert_eq!(level(&env), five_open);
    assert_eq!(step.obs[3], 1.0, "a zero command reads as not open");
    let (_, n) = open_until_done(&mut env);
    assert_eq!(n, 7, "twelve net open steps release the ball");
}

#[test]
fn grip_level_observation_and_release_point_are_selectable() {
    let mut env = Placing::with_options(EnvOptions {
        observe_grip: GripObservation::Level,
        release_at: 0.9,
        ..EnvOptions::default()
    });
    env.reset(4);
    fly_to(&mut env, [0.0, 0.0, 1.05]);
    let obs = env.step(&[0.0, 0.0, 0.0, -1.0]).obs;
    assert!((obs[3] - 0.99).abs() < 1e-5, "{obs:?}");
    let (step, n) = open_until_done(&mut env);
    assert_eq!((n, step.outcome), (9, Some(Outcome::Success)));
}

#[test]
fn authors_gripper_with_the_fall_through_rule_simulates_the_ball() {
    let mut env = Placing::with_options(EnvOptions {
        success: Some(PlacingSuccess::Through),
        ..EnvOptions::default()
    });
    env.reset(7);
    fly_to(&mut env, [0.0, 0.0, 1.05]);
    let (step, n) = open_until_done(&mut env);
    assert_eq!(step.outcome, Some(Outcome::Success));
    assert!(
        (12..=15).contains(&n),
        "12 open steps, then a 5 cm fall: {n}"
    );
    let (b, _) = ball(&env);
    assert!(b[2] < placing::HOOP_TOP_Z, "{b:?}");
}

#[test]
fn authors_start_is_the_home_pose_with_small_noise() {
    let mut env = Placing::new();
    for seed in 0..30 {
        let obs = env.reset(seed);
        for (o, home) in obs.iter().zip(placing::HOME) {
            assert!((o - home).abs() <= 0.05 * 0.012 * 50.0 + 1e-6);
        }
        assert_eq!(obs[3], 1.0);
    }
}

// ---------------------------------------------------------------- the safety gate

#[test]
fn placing_gate_looks_ahead_further_than_the_move() {
    let mut env = Placing::new();
    env.reset(14);
    fly_to(&mut env, [-0.45, 0.2, 1.0]);
    // Full speed down: stops once z - 0.07 would leave the workspace (z > 0.80), i.e. with
    // the gripper still 5 to 7 cm above the workspace's floor.
    let mut z = 1.0;
    for _ in 0..30 {
        z = env.step(&[0.0, 0.0, -1.0, 1.0]).obs[2];
    }
    assert!(z > 0.80 + placing::LOOKAHEAD - placing::STEP_SIZE && z <= 0.80 + placing::LOOKAHEAD);
    assert_eq!(env.step(&[0.0, 0.0, -1.0, 1.0]).obs[2], z);
    // Smaller actions probe less far and creep closer.
    let lower = env.step(&[0.0, 0.0, -0.5, 1.0]).obs[2];
    assert!(lower < z);
}

#[test]
fn placing_gate_keeps_the_gripper_above_the_no_entry_box_over_the_hoop() {
    let mut env = Placing::new();
    env.reset(15);
    fly_to(&mut env, [0.0, 0.0, 1.1]);
    for _ in 0..100 {
        let step = env.step(&[0.0, 0.0, -1.0, 1.0]);
        assert!(!step.done());
        assert!(step.obs[2] >= 1.03, "{:?}", step.obs);
    }
    // Not even small actions get it below the box's top.
    for _ in 0..200 {
        let step = env.step(&[0.0, 0.0, -0.05, 1.0]);
        assert!(!step.done() && step.obs[2] > 1.03);
    }
}
