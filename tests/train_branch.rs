//! `dualrep train --branch-from`: a run begun as another run's checkpoint is the run its own
//! settings would have made from step 0, row for row, and a setting that had already acted is
//! refused by name.

use std::path::Path;
use std::process::Output;

use crate::support::cli::{self, ok, running_once};

fn dualrep(args: &[&str], dir: &Path) -> Output {
    cli::dualrep_in(args, Some(dir))
}

/// `train` of a small EF-100 on Lunar Lander (every step answered by the shipped expert) into
/// `out`, 1,500 steps, checkpointing every 300, with `extra` arguments.
fn small_lunar_ef100<'a>(out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["train", "--task", "lunar-lander", "--method", "ef-100"];
    args.extend(["--steps", "1500", "--checkpoint-every", "300", "--out", out]);
    args.extend(["--set", "hidden=16,16", "--set", "batch_size=32"]);
    args.extend(extra);
    args
}

fn read(d: &Path, file: &str) -> String {
    std::fs::read_to_string(d.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

#[test]
fn a_branch_is_the_run_its_settings_make_from_step_0_row_for_row() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The run to branch from: answered to its end, each checkpoint kept.
    let full = ok(&dualrep(
        &small_lunar_ef100("full", &["--keep-checkpoints"]),
        d,
    ));
    assert_eq!(full["feedback_count"], 1500);
    // Its last checkpoint at or before step 800, where the branch stops the answers.
    let mut kept: Vec<(u64, String)> = std::fs::read_dir(d.join("full/checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .map(|f| (f["step-".len()..f.len() - ".run".len()].parse().unwrap(), f))
        .filter(|(step, _)| *step <= 800)
        .collect();
    kept.sort();
    let (step, file) = kept.pop().expect("a checkpoint at or before step 800");
    let from = format!("full/checkpoints/{file}");
    let cut = ["--set", "feedback_until=800"];

    // The same settings from nothing, and as a branch of the full run.
    let scratch = ok(&dualrep(&small_lunar_ef100("scratch", &cut), d));
    assert_eq!(scratch["feedback_count"], 800, "the cut acted");
    // The full run's files as a running run's may be read: a row begun, not yet finished.
    for file in ["metrics.csv", "learner.csv", "answers.csv"] {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(d.join("full").join(file))
            .unwrap();
        f.write_all(b"15").unwrap();
    }
    let branch_args = small_lunar_ef100("branch", &[cut[0], cut[1], "--branch-from", &from]);
    let out = dualrep(&branch_args, d);
    let branch = ok(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("branched from {from} at step {step}")),
        "{stderr}"
    );
    for key in [
        "cumulative_return",
        "episodes",
        "feedback_count",
        "final_mean_return",
        "longest_flood",
        "config",
    ] {
        assert_eq!(branch[key], scratch[key], "{key}");
    }
    for file in ["metrics.csv", "learner.csv", "answers.csv"] {
        assert_eq!(
            read(d, &format!("branch/{file}")),
            read(d, &format!("scratch/{file}")),
            "{file}"
        );
    }
    let summary: serde_json::Value = serde_json::from_str(&read(d, "branch/summary.json")).unwrap();
    assert_eq!(summary["branched_from"]["step"], step);
    assert_eq!(summary["branched_from"]["checkpoint"], from.as_str());
    assert!(summary.get("branched_from").is_some());
    let plain: serde_json::Value = serde_json::from_str(&read(d, "scratch/summary.json")).unwrap();
    assert!(
        plain.get("branched_from").is_none(),
        "only a branch says so"
    );

    // A branch stopped after its own first checkpoint goes on from that one, and still says
    // where it began.
    let again_args = small_lunar_ef100("again", &[cut[0], cut[1], "--branch-from", &from]);
    let mut child = running_once(&again_args, d, "again/checkpoint.run");
    child.kill().unwrap();
    child.wait().unwrap();
    let out = dualrep(&again_args, d);
    let again = ok(&out);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("resumed from checkpoint.run"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(again["cumulative_return"], scratch["cumulative_return"]);
    assert_eq!(read(d, "again/metrics.csv"), read(d, "scratch/metrics.csv"));
    let summary: serde_json::Value = serde_json::from_str(&read(d, "again/summary.json")).unwrap();
    assert_eq!(summary["branched_from"]["step"], step);

    // Given the run's folder, the branch begins at its latest kept checkpoint at or before the
    // cut, and is the same run.
    let out = dualrep(
        &small_lunar_ef100("by-folder", &[cut[0], cut[1], "--branch-from", "full"]),
        d,
    );
    let by_folder = ok(&out);
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains(&format!("branched from {from} at step {step}")),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(by_folder["cumulative_return"], scratch["cumulative_return"]);
    assert_eq!(
        read(d, "by-folder/metrics.csv"),
        read(d, "scratch/metrics.csv")
    );
    // A cut before every kept checkpoint finds none, and says where it looked.
    let out = dualrep(
        &small_lunar_ef100(
            "none",
            &["--set", "feedback_until=100", "--branch-from", "full"],
        ),
        d,
    );
    let stderr = cli::refused(&out);
    assert!(stderr.contains("no kept checkpoint"), "{stderr}");

    // What a branch may not change, refused by name before a step is run.
    let refused = |out_dir: &str, extra: &[&str], says: &[&str]| {
        let mut extra = extra.to_vec();
        extra.extend(["--branch-from", &from]);
        let stderr = cli::refused(&dualrep(&small_lunar_ef100(out_dir, &extra), d));
        for s in says {
            assert!(stderr.contains(s), "{out_dir}: {s:?} in {stderr}");
        }
        assert!(
            !d.join(out_dir).join("metrics.csv").exists(),
            "{out_dir}: no rows"
        );
    };
    let before = format!("feedback_until={}", step - 1);
    refused(
        "too-late",
        &["--set", &before],
        &["feedback_until", &format!("step {step}")],
    );
    refused(
        "other-scale",
        &["--set", "reward_scale=2"],
        &["only feedback_until may differ", "reward_scale"],
    );
    refused("other-seed", &["--seed", "1"], &["seed"]);
    // A longer run keeps more replay rows than the run did, so it would not be that run.
    let mut longer = small_lunar_ef100("longer", &[cut[0], cut[1], "--branch-from", &from]);
    let at = longer.iter().position(|a| *a == "1500").unwrap();
    longer[at] = "1600";
    let out = dualrep(&longer, d);
    let stderr = cli::refused(&out);
    assert!(
        stderr.contains("holds 1500 rows") && stderr.contains("1600"),
        "{stderr}"
    );
    // Into the folder of the run it is a checkpoint of: that run's rows are left as they were.
    let metrics = read(d, "full/metrics.csv");
    let out = dualrep(
        &small_lunar_ef100("full", &[cut[0], cut[1], "--branch-from", &from]),
        d,
    );
    let stderr = cli::refused(&out);
    assert!(stderr.contains("branch into another folder"), "{stderr}");
    assert_eq!(read(d, "full/metrics.csv"), metrics);
}
