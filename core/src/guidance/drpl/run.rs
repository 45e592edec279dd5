//! One preference-learning run (algorithms.md section 3): record random trajectories, segment
//! them, then per query pick a pair, ask the trainer, and update the belief over theta. The CLI
//! drives it to a query budget; a server session can drive it one query at a time.
//!
//! Every random choice comes from the run's seed, each purpose on its own ChaCha stream, so that
//! the trajectories and theta_true of a seed are the same for every method: Figure 5's methods
//! are compared on the same data and the same true reward.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::acquisition::Acquisition;
use super::belief::{Belief, BeliefConfig, Response, random_unit_vector};
use super::pool::QueryPool;
use super::segments::DEFAULT_MIN_RUN;
use super::selection::{QueryMethod, QueryPair, Selector};
use super::trainer::{Preference, PreferenceQuery, PreferenceTrainer};
use super::trajectories::{self, DEFAULT_TRAJECTORIES};
use crate::guidance::teacher::TeacherFaults;
use crate::scene_graph::SceneGraph;
use crate::sim::{DeclaredTask, Env, EnvFault, EnvOptions, Start, Task, TaskRef};

/// ChaCha streams of a run's seed (stream 1 is `trajectories::rng`).
const THETA_STREAM: u64 = 2;
const SELECTION_STREAM: u64 = 3;
const BELIEF_STREAM: u64 = 4;
/// The simulated teacher's faults draw from this stream (`teacher_seed`).
const TEACHER_STREAM: u64 = 5;

/// Everything that defines a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PreferenceRunConfig {
    pub task: TaskRef,
    pub method: QueryMethod,
    pub seed: u64,
    /// Random-policy trajectories recorded.
    pub trajectories: usize,
    /// Step limit per trajectory.
    pub max_steps: usize,
    /// Runs of g shorter than this merge into a neighbouring segment.
    pub min_run: usize,
    pub acquisition: Acquisition,
    pub belief: BeliefConfig,
    pub scene_graph: SceneGraph,
    /// Which version of the task the trajectories come from (tasks.md).
    #[serde(default)]
    pub env: EnvOptions,
    /// The synthetic teacher's faults (none: the paper's deterministic oracle).
    #[serde(default, skip_serializing_if = "TeacherFaults::is_perfect")]
    pub teacher: TeacherFaults,
}

impl PreferenceRunConfig {
    /// algorithms.md's defaults for `task` and `method`: uniform acquisition (the paper's),
    /// mutual information for DRPL-MI ([`QueryMethod::default_acquisition`]).
    pub fn new(task: Task, method: QueryMethod, seed: u64) -> Self {
        Self {
            task: task.into(),
            method,
            seed,
            trajectories: DEFAULT_TRAJECTORIES,
            max_steps: trajectories::max_steps(task),
            min_run: DEFAULT_MIN_RUN,
            acquisition: method.default_acquisition(),
            belief: BeliefConfig::default(),
            scene_graph: SceneGraph::for_task(task),
            env: EnvOptions {
                // The paper's random trajectories start "at random positions": from the home
                // pose they rarely reach the hoop, and Placing's features over the opening
                // stay near constant (docs/results/fig5).
                start: (task != Task::LunarLander).then_some(Start::Uniform),
                ..EnvOptions::default()
            },
            teacher: TeacherFaults::default(),
        }
    }

    /// The defaults for a task an env in another process declared, with its `graph`:
    /// trajectories of at most `max_steps` steps (the env's own episode limit, or Lunar
    /// Lander's 1000).
    pub fn declared(
        task: DeclaredTask,
        graph: SceneGraph,
        method: QueryMethod,
        seed: u64,
        max_steps: usize,
    ) -> Self {
        Self {
            task: TaskRef::Declared(task),
            max_steps,
            scene_graph: graph,
            ..Self::new(Task::LunarLander, method, seed)
        }
    }
}

/// What one query did.
#[derive(Clone, Debug, PartialEq)]
pub struct QueryReport {
    /// Queries asked so far, this one included (the row of `alignment.csv`).
    pub query: usize,
    pub pair: QueryPair,
    pub preference: Preference,
    /// The belief's alignment with theta_true after this answer.
    pub alignment: f64,
    pub alignment_of_mean: f64,
    /// Wall time of the belief update in milliseconds; `None` for a skipped query.
    pub update_ms: Option<f64>,
}

pub struct PreferenceRun {
    config: PreferenceRunConfig,
    pool: QueryPool,
    selector: Selector,
    belief: Belief,
    theta_true: Vec<f64>,
    queries: usize,
    /// Every pair asked, in order, so an answer can be revised later (a trainer's undo).
    asked: Vec<QueryPair>,
    /// The query each of the belief's answers came from, in the belief's order.
    in_belief: Vec<usize>,
}

/// What the belief learns from a preference: one observation per left, right or "about
/// equal" (several for a tally of several trainers' answers); a skip teaches nothing.
fn responses(preference: Preference) -> Vec<Response> {
    let one = |p: Preference| match p {
        Preference::Left => Some(Response::First),
        Preference::Right => Some(Response::Second),
        Preference::Equal => Some(Response::Equal),
        Preference::Skip | Preference::Tally(_) => None,
    };
    match preference {
        Preference::Tally(t) => t.answers().filter_map(one).collect(),
        p => one(p).into_iter().collect(),
    }
}

impl PreferenceRun {
    /// Record the trajectories (seconds for Lunar Lander) and set up the run.
    pub fn new(config: PreferenceRunConfig) -> Self {
        let trajs = Self::record_trajectories(&config);
        let pool = QueryPool::from_trajectories(&config.task, &trajs, config.min_run);
        Self::with_pool(config, pool)
    }

    /// The random-policy trajectories a run with `config` draws its queries from (seconds for
    /// Lunar Lander), reproducible from the seed. Panics for a declared task: record those with
    /// [`PreferenceRun::record_trajectories_on`].
    pub fn record_trajectories(config: &PreferenceRunConfig) -> Vec<trajectories::Trajectory> {
        let task = config.task.builtin().unwrap_or_else(|| {
            panic!(
                "task {} lives in another process: record on its env",
                config.task
            )
        });
        trajectories::collect(
            task,
            &config.env,
            &config.scene_graph,
            config.trajectories,
            config.max_steps,
            &mut trajectories::rng(config.seed),
        )
    }

    /// [`PreferenceRun::record_trajectories`] on a given env (one in another process, whose
    /// episodes need not repeat from their seeds), telling `progress` the trajectories done.
    pub fn record_trajectories_on(
        config: &PreferenceRunConfig,
        env: &mut dyn Env,
        progress: &mut dyn FnMut(usize),
    ) -> Result<Vec<trajectories::Trajectory>, EnvFault> {
        trajectories::collect_from(
            env,
            &config.scene_graph,
            config.trajectories,
            config.max_steps,
            &mut trajectories::rng(config.seed),
            progress,
        )
    }

    /// A run over a given pool (tests, or trajectories recorded elsewhere).
    pub fn with_pool(config: PreferenceRunConfig, pool: QueryPool) -> Self {
        let theta_true = random_unit_vector(pool.dim(), &mut stream(config.seed, THETA_STREAM));
        let belief_seed = stream(config.seed, BELIEF_STREAM).random();
        let mut belief = Belief::new(pool.dim(), config.belief, belief_seed);
        // With no answer the posterior is the prior: sampling it gives row 0 of the curve.
        belief.update();
        let selector = Selector::new(
            config.method,
            config.acquisition,
            &pool,
            stream(config.seed, SELECTION_STREAM),
        );
        Self {
            config,
            pool,
            selector,
            belief,
            theta_true,
            queries: 0,
            asked: Vec::new(),
            in_belief: Vec::new(),
        }
    }

    /// Ask one query and learn from the answer; `None` when the method has no new pair left.
    pub fn step(&mut self, trainer: &mut dyn PreferenceTrainer) -> Option<QueryReport> {
        let pair = self.selector.next(
            &self.pool,
            self.config.scene_graph.dim(),
            self.queries,
            &self.belief,
        )?;
        let preference = trainer.compare(&PreferenceQuery {
            query: self.queries,
            left: &pair.left,
            right: &pair.right,
            predicate: pair.predicate,
        });
        let learnt = responses(preference);
        let update_ms = (!learnt.is_empty()).then(|| {
            for r in learnt {
                self.belief
                    .add_answer(&pair.left.features, &pair.right.features, r);
                self.in_belief.push(self.queries);
            }
            let start = Instant::now();
            self.belief.update();
            start.elapsed().as_secs_f64() * 1e3
        });
        self.queries += 1;
        self.asked.push(pair.clone());
        Some(QueryReport {
            query: self.queries,
            pair,
            preference,
            alignment: self.alignment(),
            alignment_of_mean: self.alignment_of_mean(),
            update_ms,
        })
    }

    /// Replace the answer to query `query` (0-based) with `preference` (`Skip` for an undone
    /// answer) and resample the posterior from the answers that now stand. Returns false, and
    /// consumes no randomness, when nothing changed (an unknown query, or skip for skip).
    pub fn revise(&mut self, query: usize, preference: Preference) -> bool {
        let Some(pair) = self.asked.get(query) else {
            return false;
        };
        let mut changed = false;
        // Every observation the query gave (a tally gives several), last first.
        while let Some(i) = self.in_belief.iter().rposition(|&q| q == query) {
            self.belief.remove_answer(i);
            self.in_belief.remove(i);
            changed = true;
        }
        for r in responses(preference) {
            self.belief
                .add_answer(&pair.left.features, &pair.right.features, r);
            self.in_belief.push(query);
            changed = true;
        }
        if changed {
            self.belief.update();
        }
        changed
    }

    pub fn config(&self) -> &PreferenceRunConfig {
        &self.config
    }

    pub fn pool(&self) -> &QueryPool {
        &self.pool
    }

    pub fn belief(&self) -> &Belief {
        &self.belief
    }

    pub fn theta_true(&self) -> &[f64] {
        &self.theta_true
    }

    /// Queries asked so far.
    pub fn queries(&self) -> usize {
        self.queries
    }

    /// The seed of the simulated teacher's own random stream (its faults), from the run's.
    pub fn teacher_seed(&self) -> u64 {
        stream(self.config.seed, TEACHER_STREAM).random()
    }

    pub fn alignment(&self) -> f64 {
        self.belief.alignment(&self.theta_true)
    }

    pub fn alignment_of_mean(&self) -> f64 {
        self.belief.alignment_of_mean(&self.theta_true)
    }
}

/// The run seed's generator on `stream`.
fn stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::drpl::pool::TrajectoryFeatures;
    use crate::guidance::drpl::trainer::SyntheticOracle;
    use crate::scene_graph::AbstractState;

    /// Two trajectories over states 0, 1, 2, 3 with features that vary along them.
    fn pool() -> QueryPool {
        let traj = |g: &[u32], shift: f64| TrajectoryFeatures {
            states: g.iter().map(|&b| AbstractState(b)).collect(),
            phis: (0..g.len())
                .map(|t| vec![t as f64 + shift, (t as f64 * 0.7).sin()])
                .collect(),
        };
        let g = [0, 0, 0, 1, 1, 1, 3, 3, 3, 2, 2, 2];
        QueryPool::new(
            2,
            vec![traj(&g, 0.0), traj(&g, 5.0), traj(&g[3..], -2.0)],
            3,
        )
    }

    #[test]
    fn each_answer_is_a_query_and_theta_true_is_a_unit_vector_of_the_seed() {
        let config = PreferenceRunConfig::new(Task::Reaching, QueryMethod::Drpl, 9);
        let mut run = PreferenceRun::with_pool(config.clone(), pool());
        let mut oracle = SyntheticOracle::new(run.theta_true().to_vec());
        for q in 1..=5 {
            let r = run.step(&mut oracle).expect("pairs left");
            assert_eq!(r.query, q);
            assert!(r.update_ms.is_some());
            assert!((-1.0..=1.0).contains(&r.alignment));
            // Only bits 0 and 1 ever differ, so predicates 2..5 fall through to the next i.
            let i = r.pair.predicate.expect("drpl names its predicate");
            assert!(i < 2, "predicate {i}");
            let (gl, gr) = (r.pair.left.abstract_state, r.pair.right.abstract_state);
            assert_ne!(gl.unwrap().bit(i), gr.unwrap().bit(i));
        }
        assert_eq!(run.queries(), 5);
        let norm: f64 = run.theta_true().iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-12);
        let same = PreferenceRun::with_pool(config, pool());
        assert_eq!(same.theta_true(), run.theta_true());
        let other = PreferenceRun::with_pool(
            PreferenceRunConfig::new(Task::Reaching, QueryMethod::Full, 10),
            pool(),
        );
        assert_ne!(other.theta_true(), run.theta_true());
    }

    /// DRPL-MI is DRPL with the mutual-information pick and nothing else: the same config but
    /// for its name, and, query by query, the same pairs, answers and posterior.
    #[test]
    fn drpl_mi_is_drpl_with_the_mutual_information_pick() {
        let mi = PreferenceRunConfig::new(Task::Reaching, QueryMethod::DrplMi, 9);
        assert_eq!(mi.acquisition, Acquisition::MutualInformation);
        let mut drpl = PreferenceRunConfig::new(Task::Reaching, QueryMethod::Drpl, 9);
        assert_eq!(drpl.acquisition, Acquisition::Uniform);
        drpl.acquisition = Acquisition::MutualInformation;
        assert_eq!(
            PreferenceRunConfig {
                method: QueryMethod::Drpl,
                ..mi.clone()
            },
            drpl
        );
        let mut a = PreferenceRun::with_pool(mi, pool());
        let mut b = PreferenceRun::with_pool(drpl, pool());
        let mut oracle = SyntheticOracle::new(a.theta_true().to_vec());
        for _ in 0..5 {
            let (ra, rb) = (a.step(&mut oracle).unwrap(), b.step(&mut oracle).unwrap());
            assert_eq!((&ra.pair, ra.preference), (&rb.pair, rb.preference));
            assert_eq!(ra.alignment, rb.alignment);
        }
        assert_eq!(a.belief().mean(), b.belief().mean());
    }

    /// Skips count as queries but teach the belief nothing.
    #[test]
    fn skips_are_recorded_without_an_update() {
        struct Skipper;
        impl PreferenceTrainer for Skipper {
            fn compare(&mut self, _q: &PreferenceQuery<'_>) -> Preference {
                Preference::Skip
            }
        }
        let config = PreferenceRunConfig::new(Task::Reaching, QueryMethod::DrplSs, 1);
        let mut run = PreferenceRun::with_pool(config, pool());
        let r = run.step(&mut Skipper).unwrap();
        assert_eq!((r.preference, r.update_ms), (Preference::Skip, None));
        assert_eq!(run.belief().answers(), 0);
        assert_eq!(run.queries(), 1);
    }

    #[test]
    fn a_revised_answer_replaces_the_old_one_in_the_posterior() {
        let config = PreferenceRunConfig::new(Task::Reaching, QueryMethod::Drpl, 9);
        let mut run = PreferenceRun::with_pool(config, pool());
        let mut oracle = SyntheticOracle::new(run.theta_true().to_vec());
        for _ in 0..4 {
            run.step(&mut oracle).expect("pairs left");
        }
        assert_eq!(run.belief().answers(), 4);
        let mean = run.belief().mean();
        // Undone: the posterior is resampled without it.
        assert!(run.revise(1, Preference::Skip));
        assert_eq!(run.belief().answers(), 3);
        assert_ne!(run.belief().mean(), mean);
        // Skip for skip changes nothing and draws nothing.
        let undone = run.belief().mean();
        assert!(!run.revise(1, Preference::Skip));
        assert_eq!(run.belief().mean(), undone);
        // Answered again, the answer joins the others.
        assert!(run.revise(1, Preference::Equal));
        assert_eq!(run.belief().answers(), 4);
        assert!(!run.revise(7, Preference::Left), "query 7 was never asked");
        assert_eq!(run.queries(), 4);
        // The same revisions at the same points reproduce the posterior exactly (a resume).
        let config = PreferenceRunConfig::new(Task::Reaching, QueryMethod::Drpl, 9);
        let mut again = PreferenceRun::with_pool(config, pool());
        for _ in 0..4 {
            again.step(&mut oracle).expect("pairs left");
        }
        again.revise(1, Preference::Skip);
        again.revise(1, Preference::Equal);
        assert_eq!(again.belief().mean(), run.belief().mean());
    }
}
