//! `dualrep sim --checkpoint` end to end: the policy a stopped `train` run had learnt, rolled
//! out step by step, and clear errors on a checkpoint that does not fit.

use std::path::Path;
use std::process::Output;

use crate::support::cli::{self, ok, running_once};

fn dualrep(args: &[&str], dir: &Path) -> Output {
    cli::dualrep_in(args, Some(dir))
}

#[test]
fn sim_rolls_out_the_policy_of_a_runs_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A SAC run on Lunar Lander, stopped once its first checkpoint is on disk.
    let mut args = vec![
        "train",
        "--task",
        "lunar-lander",
        "--method",
        "sac",
        "--steps",
        "5000",
        "--checkpoint-every",
        "200",
        "--out",
        "run",
    ];
    args.extend(["--set", "hidden=16,16", "--set", "batch_size=32"]);
    let mut child = running_once(&args, d, "run/checkpoint.run");
    child.kill().unwrap();
    child.wait().unwrap();

    let sim = |extra: &[&str]| {
        let mut args = vec![
            "sim",
            "--checkpoint",
            "run/checkpoint.run",
            "--episodes",
            "2",
        ];
        args.extend(extra);
        dualrep(&args, d)
    };
    let sampled = ok(&sim(&["--steps", "steps.csv"]));
    assert_eq!(sampled["task"], "lunar-lander", "the run's task");
    assert_eq!(sampled["policy"], "learned");
    let steps = std::fs::read_to_string(d.join("steps.csv")).unwrap();
    assert_eq!(
        steps.lines().count() as f64,
        1.0 + 2.0 * sampled["mean_length"].as_f64().unwrap()
    );
    // Its own actions, not the heuristic's: the heuristic on the same seeds steps otherwise.
    ok(&dualrep(
        &[
            "sim",
            "--task",
            "lunar-lander",
            "--episodes",
            "2",
            "--steps",
            "h.csv",
        ],
        d,
    ));
    assert_ne!(std::fs::read_to_string(d.join("h.csv")).unwrap(), steps);
    // The mean action is one policy, the same every time.
    let mean = ok(&sim(&["--deterministic"]));
    assert_eq!(
        mean["mean_return"],
        ok(&sim(&["--deterministic"]))["mean_return"]
    );

    let refused = |extra: &[&str], expected: &str| {
        let out = sim(extra);
        assert!(!out.status.success(), "{extra:?} should fail");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
    };
    refused(&["--task", "reaching"], "is of a lunar-lander run");
    refused(&["--policy", "random"], "cannot be used with");
    let out = dualrep(&["sim", "--checkpoint", "nowhere.run"], d);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--checkpoint nowhere.run"));
    std::fs::write(d.join("junk.run"), b"hello").unwrap();
    let out = dualrep(&["sim", "--checkpoint", "junk.run"], d);
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a dualrep"));
}
