//! The `Env` contract every task keeps, checked the same way for all three: sizes as data,
//! clipping, determinism, episode ends, and a render state the browser can parse.

use dualrep_core::scene_graph::SceneGraph;
use dualrep_core::sim::{Env, Outcome, Task};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_actions(dim: usize, n: usize, seed: u64) -> Vec<Vec<f32>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| (0..dim).map(|_| rng.random_range(-1.0..=1.0)).collect())
        .collect()
}

/// Observations and rewards of one episode prefix, as raw bits so that comparison is exact.
fn trace(env: &mut dyn Env, seed: u64, actions: &[Vec<f32>]) -> Vec<u32> {
    let mut bits: Vec<u32> = env.reset(seed).iter().map(|x| x.to_bits()).collect();
    for action in actions {
        let step = env.step(action);
        bits.extend(step.obs.iter().map(|x| x.to_bits()));
        bits.push(step.reward.to_bits());
        if step.done() {
            break;
        }
    }
    bits
}

#[test]
fn same_seed_and_actions_give_bit_identical_observations_and_rewards() {
    for task in Task::ALL {
        let actions = random_actions(task.make_env().spec().action_space.dim(), 400, 3);
        let a = trace(task.make_env().as_mut(), 42, &actions);
        // A second env, and the first env again after other episodes, must agree bit for bit.
        let mut env = task.make_env();
        trace(env.as_mut(), 1, &actions);
        let b = trace(env.as_mut(), 42, &actions);
        assert_eq!(a, b, "{task}: not deterministic");
        let c = trace(task.make_env().as_mut(), 43, &actions);
        assert_ne!(a, c, "{task}: seed has no effect");
    }
}

#[test]
fn spaces_are_data_and_observations_respect_them() {
    for task in Task::ALL {
        let mut env = task.make_env();
        let spec = env.spec().clone();
        assert_eq!(spec.id, task.id());
        assert_eq!(spec.observation_names.len(), spec.observation_space.dim());
        assert_eq!(spec.action_names.len(), spec.action_space.dim());
        assert!(spec.action_space.low.iter().all(|&l| l == -1.0));
        assert!(spec.action_space.high.iter().all(|&h| h == 1.0));
        let obs = env.reset(0);
        assert_eq!(obs.len(), spec.observation_space.dim(), "{task}");
        assert_eq!(env.observation(), obs);
        for action in random_actions(spec.action_space.dim(), 200, 9) {
            let step = env.step(&action);
            for ((x, lo), hi) in step
                .obs
                .iter()
                .zip(&spec.observation_space.low)
                .zip(&spec.observation_space.high)
            {
                assert!(
                    x.is_finite() && lo <= x && x <= hi,
                    "{task}: obs {x} outside [{lo}, {hi}]"
                );
            }
            assert!(step.reward.is_finite());
            if step.done() {
                break;
            }
        }
    }
}

#[test]
fn actions_outside_the_box_are_clipped() {
    for task in Task::ALL {
        let dim = task.make_env().spec().action_space.dim();
        let wild: Vec<Vec<f32>> = random_actions(dim, 60, 5)
            .into_iter()
            .map(|a| a.iter().map(|x| x * 7.0).collect())
            .collect();
        let clipped: Vec<Vec<f32>> = wild
            .iter()
            .map(|a| a.iter().map(|x| x.clamp(-1.0, 1.0)).collect())
            .collect();
        let a = trace(task.make_env().as_mut(), 8, &wild);
        let b = trace(task.make_env().as_mut(), 8, &clipped);
        assert_eq!(
            a, b,
            "{task}: out-of-range actions must act like clipped ones"
        );
    }
}

#[test]
fn every_episode_ends_within_the_horizon_with_an_outcome() {
    for task in Task::ALL {
        let mut env = task.make_env();
        let max = env.spec().max_episode_steps;
        for seed in 0..3 {
            env.reset(seed);
            let action = vec![0.0; env.spec().action_space.dim()];
            let step = loop {
                let step = env.step(&action);
                assert!(env.elapsed_steps() <= max, "{task}: past the horizon");
                if step.done() {
                    break step;
                }
            };
            match step.outcome {
                Some(Outcome::TimeLimit) => {
                    assert!(step.truncated && !step.terminated && env.elapsed_steps() == max)
                }
                Some(Outcome::Success | Outcome::Failure) => {
                    assert!(step.terminated && !step.truncated)
                }
                None => panic!("{task}: last step without an outcome"),
            }
        }
    }
}

#[test]
fn render_state_geometry_and_scene_graph_are_available_every_step() {
    for task in Task::ALL {
        let mut env = task.make_env();
        let graph = SceneGraph::for_task(task);
        env.reset(2);
        let geometry = serde_json::to_value(env.geometry()).unwrap();
        assert_eq!(geometry["task"], task.id());
        for action in random_actions(env.spec().action_space.dim(), 30, 1) {
            let step = env.step(&action);
            let render = serde_json::to_value(env.render()).unwrap();
            assert_eq!(render["task"], task.id());
            let g = graph.evaluate(&step.obs, &action);
            assert!(g.0 < 1 << graph.dim());
            if step.done() {
                break;
            }
        }
    }
}
