//! `dualrep bench sac`: SAC update throughput (one thread unless `--threads`), as one JSON
//! object, beside two ceilings measured in the same process: the core's FMA peak (a loop of
//! fused multiply-adds on registers, at the kernels' vector width, on as many threads) and
//! matrixmultiply's `sgemm` at 256^3 on one thread.
//!
//! The learner is DREF's (human critic on) with the task's sizes, updating on a replay buffer of
//! random transitions. `gflops` = `updates_per_second * mflop_per_update / 1000`;
//! `fraction_of_fma_peak` says how close the whole update (products, elementwise work,
//! sampling, Adam) comes to the arithmetic limit of the core(s), `fraction_of_sgemm` how it
//! compares with nothing but large products through matrixmultiply.
//! `benches/reference/torch_sac_update.py` times the same update in PyTorch.
//!
//! `dualrep bench train` (`bench_train.rs`): environment steps per second of a whole run;
//! `dualrep bench kernels` (`bench_kernels.rs`): each product of a layer alone.
//!
//! `dualrep bench env` (module `bench_env`): env steps per second in-process and through the
//! env protocol.
//!
//! `dualrep bench belief`: milliseconds per DRPL belief update (one Metropolis-Hastings chain)
//! on random answers; `benches/reference/aprel_belief.py` times APReL's algorithm in numpy.

use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Serialize;

use super::compute::Compute;
use crate::guidance::drpl::belief::{Belief, BeliefConfig, Response};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::rl::kernels::{self, KernelPath};
use crate::rl::replay::{ReplayBuffer, Transition};
use crate::rl::sac::{Sac, mflop_per_update, mflop_skipped_per_update};
use crate::settings::Settings;
use crate::sim::Task;

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub what: BenchWhat,
}

#[derive(Debug, Subcommand)]
pub enum BenchWhat {
    /// Gradient steps per second of DREF's SAC update, against the sgemm peak.
    Sac(SacBenchArgs),
    /// Milliseconds per DRPL belief update (2199 Metropolis-Hastings proposals).
    Belief(BeliefBenchArgs),
    /// GFLOP/s of each of a layer's products on every kernel path, against the FMA peak.
    Kernels(super::bench_kernels::KernelBenchArgs),
    /// Environment steps per second of a whole run (env, scene graph, oracle, updates).
    Train(super::bench_train::TrainBenchArgs),
    /// Env steps per second: our simulator, and through the env protocol on a remote env.
    Env(super::bench_env::EnvBenchArgs),
}

#[derive(Debug, Args)]
pub struct BeliefBenchArgs {
    /// Reward features D (theta's dimension).
    #[arg(long, default_value_t = 6)]
    pub features: usize,
    /// Recorded answers N.
    #[arg(long, default_value_t = 40)]
    pub answers: usize,
    /// Timed updates; the median is reported.
    #[arg(long, default_value_t = 50)]
    pub repeats: usize,
}

#[derive(Serialize)]
struct BeliefBench {
    features: usize,
    answers: usize,
    proposals: usize,
    repeats: usize,
    median_ms: f64,
    mean_ms: f64,
    min_ms: f64,
}

#[derive(Debug, Args)]
pub struct SacBenchArgs {
    /// reaching, placing or lunar-lander: the observation and action sizes and the config.
    #[arg(long)]
    pub task: Task,
    /// Hidden layer sizes instead of the task's, e.g. 256,256.
    #[arg(long)]
    pub hidden: Option<String>,
    /// Batch size instead of the task's (512).
    #[arg(long)]
    pub batch: Option<usize>,
    /// How long to time the updates.
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
}

#[derive(Serialize)]
struct SacBench {
    task: Task,
    hidden: Vec<usize>,
    batch: usize,
    obs_dim: usize,
    act_dim: usize,
    /// The kernel path that computed the updates, and how many threads they used.
    kernels: KernelPath,
    threads: usize,
    updates: u64,
    /// 1 / the median time of an update: what the machine does when nothing else runs on the
    /// core (other processes on a shared machine only ever lengthen some updates).
    updates_per_second: f64,
    /// Updates over the whole time, interruptions included.
    mean_updates_per_second: f64,
    mflop_per_update: f64,
    /// At the median rate.
    gflops: f64,
    /// The FMA loop on `threads` threads at the kernels' vector width (for portable, the widest
    /// this CPU has, which matrixmultiply uses).
    fma_peak_gflops: f64,
    fraction_of_fma_peak: f64,
    /// The arithmetic the update actually did: `mflop_per_update` (what PyTorch computes) less
    /// the input-gradient passes the actor loss skips (for each sample, the twin its `min` did
    /// not pick); and that work's rate against the FMA peak.
    mflop_done_per_update: f64,
    fraction_of_fma_peak_done: f64,
    /// matrixmultiply's `sgemm` at 256^3 on one thread.
    sgemm_gflops: f64,
    fraction_of_sgemm: f64,
}

pub fn run(args: BenchArgs, compute: &Compute) -> anyhow::Result<()> {
    match args.what {
        BenchWhat::Sac(args) => bench_sac(args, compute),
        BenchWhat::Belief(args) => bench_belief(args),
        BenchWhat::Kernels(args) => super::bench_kernels::run(args, compute.threads.unwrap_or(1)),
        BenchWhat::Train(args) => super::bench_train::run(args, compute),
        BenchWhat::Env(args) => super::bench_env::bench_env(args),
    }
}

/// Observation and action sizes. Lunar Lander's are Gymnasium's `LunarLanderContinuous` (8, 2),
/// stated here so the benchmark needs no simulator.
fn task_dims(task: Task) -> (usize, usize) {
    match task {
        Task::LunarLander => (8, 2),
        _ => {
            let env = task.make_env();
            let spec = env.spec();
            (spec.observation_space.dim(), spec.action_space.dim())
        }
    }
}

fn bench_sac(args: SacBenchArgs, compute: &Compute) -> anyhow::Result<()> {
    // One thread unless asked: the figure the peers (PyTorch on one thread) compare with.
    let threads = compute.threads.unwrap_or(1);
    kernels::with_threads(threads, || bench_sac_on(args, compute.path, threads))
}

fn bench_sac_on(args: SacBenchArgs, path: KernelPath, threads: usize) -> anyhow::Result<()> {
    if !args.seconds.is_finite() || args.seconds <= 0.0 {
        bail!("--seconds must be positive");
    }
    let settings = Settings::from_pairs(
        [
            ("hidden", args.hidden.as_deref()),
            ("human_critic", Some("true")),
        ]
        .into_iter()
        .filter_map(|(k, v)| Some((k, v?))),
    )
    .map_err(anyhow::Error::msg)
    .context("--hidden")?;
    let mut config = settings
        .evaluative(args.task, EvaluativeMethod::Dref, 0)
        .map_err(anyhow::Error::msg)
        .context("--hidden")?
        .sac;
    if let Some(batch) = args.batch {
        if batch == 0 {
            bail!("--batch must be at least 1");
        }
        config.batch_size = batch;
    }
    config.gradient_steps = 1;
    let (obs_dim, act_dim) = task_dims(args.task);
    let replay = random_replay(obs_dim, act_dim, 100_000);
    let mut sac = Sac::new(obs_dim, act_dim, config.clone(), 0);
    for _ in 0..3 {
        sac.update(&replay); // warm-up: caches, page faults
    }

    let budget = Duration::from_secs_f64(args.seconds);
    let start = Instant::now();
    let mut times = Vec::with_capacity(4096);
    while start.elapsed() < budget {
        let update = Instant::now();
        sac.update(&replay);
        times.push(update.elapsed().as_secs_f64());
    }
    let updates = times.len() as u64;
    let mean_updates_per_second = updates as f64 / start.elapsed().as_secs_f64();
    let updates_per_second = 1.0 / median(&mut times);
    let mflop = mflop_per_update(obs_dim, act_dim, &config);
    let gflops = updates_per_second * mflop / 1000.0;
    let mflop_done = mflop - mflop_skipped_per_update(obs_dim, act_dim, &config);
    let gflops_done = updates_per_second * mflop_done / 1000.0;
    let ceiling_budget = Duration::from_secs_f64(args.seconds.min(2.0));
    let fma_peak_gflops = path.fma_peak_gflops(threads, ceiling_budget);
    let sgemm_gflops = sgemm_gflops(256, ceiling_budget);
    let report = SacBench {
        task: args.task,
        hidden: config.hidden,
        batch: config.batch_size,
        obs_dim,
        act_dim,
        kernels: path,
        threads,
        updates,
        updates_per_second,
        mean_updates_per_second,
        mflop_per_update: mflop,
        gflops,
        fma_peak_gflops,
        fraction_of_fma_peak: gflops / fma_peak_gflops,
        mflop_done_per_update: mflop_done,
        fraction_of_fma_peak_done: gflops_done / fma_peak_gflops,
        sgemm_gflops,
        fraction_of_sgemm: gflops / sgemm_gflops,
    };
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// Times `Belief::update` on N pairs of standard-normal features (DRPL standardises its
/// segment features) answered by the deterministic oracle of a random theta, after one
/// warm-up update.
fn bench_belief(args: BeliefBenchArgs) -> anyhow::Result<()> {
    if args.features == 0 || args.repeats == 0 {
        bail!("--features and --repeats must be positive");
    }
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let theta: Vec<f64> = (0..args.features)
        .map(|_| rng.sample(StandardNormal))
        .collect();
    let config = BeliefConfig::default();
    let mut belief = Belief::new(args.features, config, 0);
    for _ in 0..args.answers {
        let a: Vec<f64> = (0..args.features)
            .map(|_| rng.sample(StandardNormal))
            .collect();
        let b: Vec<f64> = (0..args.features)
            .map(|_| rng.sample(StandardNormal))
            .collect();
        let gap: f64 = theta
            .iter()
            .zip(a.iter().zip(&b))
            .map(|(t, (x, y))| t * (x - y))
            .sum();
        let response = if gap > 0.0 {
            Response::First
        } else {
            Response::Second
        };
        belief.add_answer(&a, &b, response);
    }
    belief.update(); // warm-up
    let mut times: Vec<f64> = (0..args.repeats)
        .map(|_| {
            let start = Instant::now();
            belief.update();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    std::hint::black_box(belief.mean());
    let median = median(&mut times);
    let report = BeliefBench {
        features: args.features,
        answers: args.answers,
        proposals: config.proposals(),
        repeats: args.repeats,
        median_ms: median,
        mean_ms: times.iter().sum::<f64>() / times.len() as f64,
        min_ms: times[0],
    };
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// The median of `values` (sorted in place); NaN if empty.
fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    match values.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => values[n / 2],
        n => (values[n / 2 - 1] + values[n / 2]) / 2.0,
    }
}

fn random_replay(obs_dim: usize, act_dim: usize, n: usize) -> ReplayBuffer {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut replay = ReplayBuffer::new(n, obs_dim, act_dim);
    let (mut obs, mut next_obs, mut action) =
        (vec![0.0; obs_dim], vec![0.0; obs_dim], vec![0.0; act_dim]);
    for _ in 0..n {
        for v in obs.iter_mut().chain(&mut next_obs) {
            *v = rng.random_range(-1.0..1.0);
        }
        for v in &mut action {
            *v = rng.random_range(-1.0..1.0);
        }
        replay.push(Transition {
            obs: &obs,
            action: &action,
            reward: rng.random_range(-1.0..1.0),
            human: [-1.0, 0.0, 0.0, 1.0][rng.random_range(0..4)],
            next_obs: &next_obs,
            terminated: rng.random_bool(0.01),
        });
    }
    replay
}

/// GFLOP/s of matrixmultiply's `sgemm` on `n x n x n` column-major products, one thread.
fn sgemm_gflops(n: usize, budget: Duration) -> f64 {
    let a: Vec<f32> = (0..n * n).map(|k| (k as f32 * 0.37).sin()).collect();
    let b: Vec<f32> = (0..n * n).map(|k| (k as f32 * 0.11).cos()).collect();
    let mut c = vec![0.0f32; n * n];
    let product = |c: &mut [f32]| {
        // SAFETY: a, b and c each hold n * n f32 in column-major order (row stride 1, column
        // stride n), and c is borrowed mutably, so it aliases neither input.
        unsafe {
            matrixmultiply::sgemm(
                n,
                n,
                n,
                1.0,
                a.as_ptr(),
                1,
                n as isize,
                b.as_ptr(),
                1,
                n as isize,
                0.0,
                c.as_mut_ptr(),
                1,
                n as isize,
            );
        }
    };
    product(&mut c); // warm-up
    let start = Instant::now();
    let mut count = 0u64;
    while start.elapsed() < budget {
        product(&mut c);
        count += 1;
    }
    std::hint::black_box(&c);
    2.0 * (n * n * n) as f64 * count as f64 / start.elapsed().as_secs_f64() / 1e9
}
