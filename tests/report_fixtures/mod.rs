//! TEST FIXTURE: fake grid directories in the formats `dualrep train` and `dualrep prefs`
//! document (system.md), with made-up, deterministic numbers shaped like the paper's curves.
//! Nothing here comes from a real run.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

/// A deterministic stand-in for noise in [-1, 1] (no RNG, so the fixture never changes).
fn wiggle(a: u64, b: u64) -> f64 {
    let h = (a.wrapping_mul(6364136223846793005) ^ b.wrapping_mul(1442695040888963407))
        .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// (method, learning gain, feedback fraction) of the fake Figure 3 methods on a task.
fn fig3_methods(task: &str) -> Vec<(&'static str, f64, f64)> {
    let dref = match task {
        "lunar-lander" => 0.062,
        "reaching" => 0.016,
        _ => 0.084,
    };
    vec![
        ("dref", 1.0, dref),
        ("ef-100", 0.95, 1.0),
        ("ef-50", 0.7, 0.5),
        ("ef-25", 0.5, 0.25),
        ("sac", 0.35, 0.0),
        (
            match task {
                "lunar-lander" => "ef-6.2",
                "reaching" => "ef-1.6",
                _ => "ef-8.4",
            },
            0.2,
            dref,
        ),
    ]
}

/// Writes one fake `train` run: episodes of ~200 steps whose return grows with training.
pub fn write_train_run(
    dir: &Path,
    task: &str,
    method: &str,
    seed: u64,
    steps: u64,
    gain: f64,
    feedback: f64,
) {
    fs::create_dir_all(dir).unwrap();
    let mut csv =
        String::from("step,episode,return,cumulative_return,feedback_count,feedback_fraction\n");
    let (mut step, mut episode, mut cumulative) = (0u64, 0u64, 0.0f64);
    let seed_feedback = (feedback * (1.0 + 0.05 * wiggle(seed, 7))).min(1.0);
    // Seeds learn at different speeds, so the standard-error band has something to show.
    let gain = gain * (1.0 + 0.12 * wiggle(seed, 3));
    loop {
        let len = 180 + (seed * 13 + episode * 7) % 60;
        if step + len > steps {
            break;
        }
        step += len;
        let progress = step as f64 / steps as f64;
        let ret = -20.0 + 120.0 * gain * progress + 15.0 * wiggle(seed, episode);
        cumulative += ret;
        let count = (seed_feedback * step as f64).round() as u64;
        let _ = writeln!(
            csv,
            "{step},{episode},{ret:.3},{cumulative:.3},{count},{seed_feedback:.6}"
        );
        episode += 1;
    }
    fs::write(dir.join("metrics.csv"), csv).unwrap();
    let summary = serde_json::json!({
        "task": task, "method": method, "seed": seed, "steps": steps,
        "cumulative_return": cumulative,
        "feedback_count": (seed_feedback * steps as f64).round() as u64,
        "feedback_fraction": seed_feedback,
        "final_mean_return": 0.0, "wall_seconds": 1.0, "updates_per_second": 100.0,
        "some_future_field": [1, 2, 3],
    });
    fs::write(dir.join("summary.json"), summary.to_string()).unwrap();
}

/// A fake Figure 3 grid under `root`: three tasks, six methods, `seeds` seeds.
pub fn write_fig3_grid(root: &Path, seeds: u64) {
    for (task, steps) in [
        ("lunar-lander", 150_000),
        ("reaching", 100_000),
        ("placing", 100_000),
    ] {
        for (method, gain, feedback) in fig3_methods(task) {
            for seed in 0..seeds {
                let dir = root.join(task).join(method).join(format!("seed{seed}"));
                write_train_run(&dir, task, method, seed, steps, gain, feedback);
            }
        }
    }
}

/// A fake Figure 5 grid: alignment rising towards a method-specific level over 40 queries.
pub fn write_fig5_grid(root: &Path, seeds: u64) {
    let methods = [
        ("drpl", 0.85, 6.0),
        ("drpl-ss", 0.65, 9.0),
        ("fragment", 0.45, 12.0),
        ("full", 0.3, 15.0),
    ];
    for task in ["lunar-lander", "reaching", "placing"] {
        for (method, level, tau) in methods {
            for seed in 0..seeds {
                let dir = root.join(task).join(method).join(format!("seed{seed}"));
                fs::create_dir_all(&dir).unwrap();
                let mut csv = String::from("query,alignment,alignment_of_mean\n");
                let mut last = 0.0;
                for q in 1..=40u64 {
                    let a = level * (1.0 - (-(q as f64) / tau).exp())
                        + 0.08 * wiggle(seed * 100 + q, level.to_bits());
                    let _ = writeln!(csv, "{q},{a:.4},{:.4}", (a + 0.05).min(1.0));
                    last = a;
                }
                fs::write(dir.join("alignment.csv"), csv).unwrap();
                let summary = serde_json::json!({
                    "task": task, "method": method, "seed": seed, "queries": 40,
                    "final_alignment": last, "mean_segment_length": 11.5 + seed as f64,
                    "belief_update_ms_median": 3.0,
                });
                fs::write(dir.join("summary.json"), summary.to_string()).unwrap();
            }
        }
    }
}
