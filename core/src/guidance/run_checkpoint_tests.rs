//! Tests of `run_checkpoint`: a resumed run goes on bit for bit, kernels and threads change
//! nothing, other runs and broken bytes are refused, and a checkpoint's learner acts as the run's.

use super::*;
use crate::guidance::evaluative_run::EpisodeRecord;
use crate::guidance::expert_oracle::ExpertOracle;
use crate::sim::Task;

fn tiny(task: Task, method: &str) -> EvaluativeRunConfig {
    let mut config = EvaluativeRunConfig::new(task, method.parse().unwrap(), 5);
    config.sac.hidden = vec![8, 8];
    config.sac.batch_size = 16;
    config
}

/// An oracle whose expert samples its actions, so its random stream matters.
fn oracle(task: Task) -> ExpertOracle {
    let env = task.make_env();
    let spec = env.spec();
    let (obs_dim, act_dim) = (spec.observation_space.dim(), spec.action_space.dim());
    let mut config = crate::rl::SacConfig::for_task(task);
    config.hidden = vec![8, 8];
    ExpertOracle::new(Sac::new(obs_dim, act_dim, config, 11), act_dim)
}

fn drive(run: &mut EvaluativeRun, trainer: &mut ExpertOracle, to: u64) -> Vec<EpisodeRecord> {
    let mut episodes = Vec::new();
    while run.steps() < to {
        episodes.extend(run.step(trainer).episode);
    }
    episodes
}

/// A run of `config` driven past `to` steps to its next episode start, its trainer, and the
/// checkpoint it saved there.
fn saved_past(
    task: Task,
    config: &EvaluativeRunConfig,
    to: u64,
    budget: u64,
) -> (EvaluativeRun, ExpertOracle, Vec<u8>) {
    let mut trainer = oracle(task);
    let mut run = EvaluativeRun::new(config.clone(), budget);
    drive(&mut run, &mut trainer, to);
    while !run.at_episode_start() {
        run.step(&mut trainer);
    }
    let bytes = run.checkpoint(&trainer, serde_json::Value::Null);
    (run, trainer, bytes)
}

/// A faulty teacher (its own random stream) and a person's pace (its window of queries).
fn faulty(task: Task, config: &EvaluativeRunConfig) -> ExpertOracle {
    oracle(task).with_faults(config.teacher, config.seed, 0.99)
}

#[test]
fn a_resumed_run_continues_bit_for_bit_on_every_kernel_path() {
    for path in KernelPath::ALL.into_iter().filter(|p| p.is_available()) {
        kernels::with_path(path, || resumed_run_continues_bit_for_bit(path));
    }
}

fn resumed_run_continues_bit_for_bit(path: KernelPath) {
    let mut paced = tiny(Task::Placing, "dref");
    paced.teacher = crate::guidance::teacher::TeacherFaults {
        beta: Some(50.0),
        error: 0.2,
        ..Default::default()
    };
    paced.human_pace = Some(crate::guidance::human_pace::HumanPace {
        max_per_minute: 3,
        steps_per_minute: 40,
    });
    // The answered mix gated by the last episodes' outcomes, which the checkpoint keeps.
    let mut gated = tiny(Task::Placing, "dref");
    let critic = gated.sac.human_critic.as_mut().unwrap();
    (critic.mix, critic.failure_window) = (crate::rl::ActorMix::Answered, 3);
    // Tasks whose random episodes are short, so a few hundred steps cross several.
    for (task, method, config) in [
        (Task::Placing, "dref", tiny(Task::Placing, "dref")),
        (Task::Placing, "ef-50", tiny(Task::Placing, "ef-50")),
        (Task::LunarLander, "sac", tiny(Task::LunarLander, "sac")),
        (Task::Placing, "dref paced, faulty teacher", paced),
        (Task::Placing, "dref, answered mix gated by failures", gated),
    ] {
        let oracle = |task| faulty(task, &config);
        let steps = 600;
        let mut straight = EvaluativeRun::new(config.clone(), steps);
        let mut straight_oracle = oracle(task);
        let all = drive(&mut straight, &mut straight_oracle, steps);

        // Stop at the first episode start after step 200, checkpoint, and throw it all away.
        let mut first = EvaluativeRun::new(config.clone(), steps);
        let mut first_oracle = oracle(task);
        drive(&mut first, &mut first_oracle, 200);
        while !first.at_episode_start() {
            first.step(&mut first_oracle);
        }
        let stopped_at = first.steps();
        let successes_at_stop = first.successes();
        let gate_at_stop = first.mix_gate.clone();
        let bytes = first.checkpoint(&first_oracle, serde_json::json!({"note": stopped_at}));
        drop(first);
        assert_eq!(EvaluativeRun::checkpoint_kernels(&bytes).unwrap(), path);

        let mut fresh_oracle = oracle(task);
        let (mut resumed, notes) =
            EvaluativeRun::resume(&bytes, &config, &mut fresh_oracle).unwrap();
        assert_eq!(notes["note"], stopped_at);
        assert_eq!(resumed.steps(), stopped_at);
        assert_eq!(resumed.successes(), successes_at_stop);
        // The gate's window comes back as it was (for the gated run, with episodes in it).
        assert_eq!(resumed.mix_gate, gate_at_stop, "{task} {method}");
        if method.contains("gated") {
            assert_ne!(gate_at_stop, MixGate::default(), "episodes in the window");
        }
        let tail = drive(&mut resumed, &mut fresh_oracle, steps);
        let expected: Vec<_> = all
            .iter()
            .filter(|e| e.step > stopped_at)
            .cloned()
            .collect();
        assert!(
            !expected.is_empty(),
            "{task} {method}: episodes after the stop"
        );
        assert_eq!(tail, expected, "{path} {task} {method}");
        assert_eq!(
            resumed.learner().state_checksum(),
            straight.learner().state_checksum(),
            "{path} {task} {method}"
        );
        assert_eq!(resumed.feedback_count(), straight.feedback_count());
        assert_eq!(resumed.queries_held_back(), straight.queries_held_back());
        assert_eq!(resumed.cumulative_return(), straight.cumulative_return());
    }
}

#[test]
fn a_run_is_the_same_bits_on_avx512_and_avx2_and_on_any_number_of_threads() {
    let fast: Vec<KernelPath> = [KernelPath::Avx512, KernelPath::Avx2]
        .into_iter()
        .filter(|p| p.is_available())
        .collect();
    let config = tiny(Task::Placing, "dref");
    let mut checksums = Vec::new();
    for &path in &fast {
        for threads in [1, 2] {
            let checksum = kernels::with_path(path, || {
                kernels::with_threads(threads, || {
                    let mut run = EvaluativeRun::new(config.clone(), 300);
                    let mut trainer = oracle(Task::Placing);
                    drive(&mut run, &mut trainer, 300);
                    run.learner().state_checksum()
                })
            });
            checksums.push((path, threads, checksum));
        }
    }
    for (path, threads, checksum) in &checksums {
        assert_eq!(*checksum, checksums[0].2, "{path} on {threads} threads");
    }
}

#[test]
fn a_checkpoint_of_another_run_or_broken_bytes_is_refused() {
    let config = tiny(Task::Placing, "dref");
    let (_, mut trainer, bytes) = saved_past(Task::Placing, &config, 30, 100);
    let mut other = config.clone();
    other.seed += 1;
    let refused = |b: &[u8], c: &EvaluativeRunConfig, t: &mut ExpertOracle| {
        EvaluativeRun::resume(b, c, t)
            .err()
            .expect("refused")
            .to_string()
    };
    assert!(refused(&bytes, &other, &mut trainer).contains("another configuration"));
    // A remote env that comes back declaring another scene graph.
    let mut redeclared = config.clone();
    redeclared.scene_graph = crate::scene_graph::SceneGraph::Reaching;
    assert!(refused(&bytes, &redeclared, &mut trainer).contains("scene graph"));
    assert!(refused(&bytes[..bytes.len() - 4], &config, &mut trainer).contains("replay"));
    assert!(refused(&bytes[..40], &config, &mut trainer).contains("truncated"));
    assert!(refused(b"hello", &config, &mut trainer).contains("not a dualrep"));
    assert!(EvaluativeRun::resume(&bytes, &config, &mut trainer).is_ok());
}

#[test]
fn a_checkpoints_learner_acts_as_the_run_that_saved_it() {
    let config = tiny(Task::LunarLander, "ef-100");
    let (run, _, bytes) = saved_past(Task::LunarLander, &config, 300, 400);
    let (read, mut learner, steps) = EvaluativeRun::checkpoint_learner(&bytes).unwrap();
    assert_eq!((read, steps), (config, run.steps()));
    assert!(learner.updates() > 0, "a learner that has trained");
    let mut saved = run.into_learner();
    let (mut ours, mut theirs) = ([0.0f32; 2], [0.0f32; 2]);
    for i in 0..20 {
        let obs: Vec<f32> = (0..8).map(|j| ((i * 8 + j) as f32 * 0.37).sin()).collect();
        learner.act(&obs, i % 2 == 0, &mut ours);
        saved.act(&obs, i % 2 == 0, &mut theirs);
        assert_eq!(
            ours, theirs,
            "observation {i}: the same action, sampled or not"
        );
    }
    assert!(EvaluativeRun::checkpoint_learner(&bytes[..40]).is_err());
    assert!(EvaluativeRun::checkpoint_learner(b"hello").is_err());
}
