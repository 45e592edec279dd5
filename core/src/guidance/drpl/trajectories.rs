//! The recorded trajectories DRPL and its baselines draw queries from (algorithms.md section 3,
//! step 1 \[choice\]): a random policy from the env's own randomised resets, as the paper records
//! "agents starting at random positions and taking random actions".

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::scene_graph::{AbstractState, SceneGraph};
use crate::sim::{Env, EnvFault, EnvOptions, Task};

/// Trajectories per run when not overridden.
pub const DEFAULT_TRAJECTORIES: usize = 100;

/// Step limit of one trajectory: Lunar Lander's Gymnasium horizon, shorter for the table-top
/// tasks where a random gripper barely moves anyway (their resets already spend 50-100 steps).
pub fn max_steps(task: Task) -> usize {
    match task {
        Task::LunarLander => 1000,
        Task::Reaching | Task::Placing => 200,
    }
}

/// One step `(s_t, a_t) -> s_{t+1}` and the scene graph `g_t` on `(s_{t+1}, a_t)`.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryStep {
    pub obs: Vec<f32>,
    pub action: Vec<f32>,
    pub next_obs: Vec<f32>,
    pub abstract_state: AbstractState,
    /// The features phi the env computed for this step (an env in another process that
    /// declares features); empty when they are computed from the task.
    pub env_features: Vec<f64>,
}

/// One recorded episode (cut at the step limit or where the env ended it).
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// The env's reset seed, so a viewer can replay it.
    pub reset_seed: u64,
    pub steps: Vec<TrajectoryStep>,
}

impl Trajectory {
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }
}

/// `count` random-policy trajectories of `task`, at most `max_steps` steps each, reproducible
/// from `rng` alone: it draws each reset seed and then that trajectory's actions.
pub fn collect(
    task: Task,
    options: &EnvOptions,
    graph: &SceneGraph,
    count: usize,
    max_steps: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Trajectory> {
    let mut env = task.make_env_with(options);
    collect_from(env.as_mut(), graph, count, max_steps, rng, &mut |_| {})
        .expect("the built-in tasks never fail")
}

/// [`collect`] on a given env (one in another process), telling `progress` how many
/// trajectories are done after each: recording a remote env's trajectories takes as long as
/// its steps do.
pub fn collect_from(
    env: &mut dyn Env,
    graph: &SceneGraph,
    count: usize,
    max_steps: usize,
    rng: &mut ChaCha8Rng,
    progress: &mut dyn FnMut(usize),
) -> Result<Vec<Trajectory>, EnvFault> {
    let act_dim = env.spec().action_space.dim();
    let mut trajectories = Vec::with_capacity(count);
    for done_so_far in 0..count {
        let reset_seed: u64 = rng.random();
        let mut obs = env.try_reset(reset_seed)?;
        let mut steps = Vec::new();
        while steps.len() < max_steps {
            let action: Vec<f32> = (0..act_dim).map(|_| rng.random_range(-1.0..=1.0)).collect();
            let step = env.try_step(&action)?;
            let abstract_state = graph.after_step(env, &step.obs, &action);
            let env_features = env.reported_features().map(<[f64]>::to_vec);
            let done = step.done();
            steps.push(TrajectoryStep {
                obs: std::mem::replace(&mut obs, step.obs.clone()),
                action,
                next_obs: step.obs,
                abstract_state,
                env_features: env_features.unwrap_or_default(),
            });
            if done {
                break;
            }
        }
        trajectories.push(Trajectory { reset_seed, steps });
        progress(done_so_far + 1);
    }
    Ok(trajectories)
}

/// A generator for `collect` from a run's seed, on its own ChaCha stream so that the
/// trajectories do not depend on what else the run draws.
pub fn rng(seed: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1);
    rng
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_chain_and_carry_the_scene_graph() {
        let task = Task::Reaching;
        let graph = SceneGraph::for_task(task);
        let trajs = collect(task, &EnvOptions::default(), &graph, 3, 20, &mut rng(7));
        assert_eq!(trajs.len(), 3);
        for t in &trajs {
            assert!(!t.is_empty() && t.len() <= 20);
            for w in t.steps.windows(2) {
                assert_eq!(w[0].next_obs, w[1].obs);
            }
            for s in &t.steps {
                assert!(s.action.iter().all(|a| (-1.0..=1.0).contains(a)));
                assert_eq!(s.abstract_state, graph.evaluate(&s.next_obs, &s.action));
            }
        }
        assert_ne!(trajs[0].reset_seed, trajs[1].reset_seed);
    }

    #[test]
    fn reproducible_from_the_seed() {
        let task = Task::Placing;
        let graph = SceneGraph::for_task(task);
        let a = collect(task, &EnvOptions::default(), &graph, 2, 30, &mut rng(3));
        let b = collect(task, &EnvOptions::default(), &graph, 2, 30, &mut rng(3));
        let c = collect(task, &EnvOptions::default(), &graph, 2, 30, &mut rng(4));
        assert_eq!(a, b);
        assert_ne!(a, c);
    }
}
