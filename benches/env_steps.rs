//! Env steps per second for each task under a random policy (resets included, as in training).
//!
//! `cargo bench --bench env_steps`; compare Lunar Lander with Gymnasium's Box2D version via
//! `python3 benches/reference/gym_lunar_lander.py --policy random` on the same machine.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dualrep::sim::Task;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Steps per measured iteration: long enough to cross several episode boundaries.
const STEPS: u64 = 2_000;

fn env_steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("env_steps_random_policy");
    group.throughput(Throughput::Elements(STEPS));
    for task in Task::ALL {
        let mut env = task.make_env();
        let dim = env.spec().action_space.dim();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut action = vec![0.0f32; dim];
        let mut episode = 0u64;
        env.reset(episode);
        group.bench_function(task.id(), |b| {
            b.iter(|| {
                for _ in 0..STEPS {
                    action
                        .iter_mut()
                        .for_each(|a| *a = rng.random_range(-1.0..=1.0));
                    if env.step(&action).done() {
                        episode += 1;
                        env.reset(episode);
                    }
                }
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // No HTML plots: criterion's plotters output needs system fonts, which a server may lack
    // (and this crate's plotters is built with embedded fonts only).
    config = Criterion::default().without_plots();
    targets = env_steps
}
criterion_main!(benches);
