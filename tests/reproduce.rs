//! `dualrep reproduce` end to end, with `tests/fixtures/fake_dualrep.sh` (a TEST FIXTURE that
//! plays `train` and `prefs` in milliseconds) as the child program: the grid, resuming, running
//! J at a time, a failing child, EF at DREF's measured rate, and the files at the end.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::support::cli::refused;

const FAKE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/fake_dualrep.sh"
);

/// Runs `dualrep reproduce ARGS --program FAKE --out OUT` with the fake's log at `log`.
fn reproduce(out: &Path, log: &Path, fail: Option<&str>, args: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_dualrep"));
    cmd.arg("reproduce")
        .args(args)
        .arg("--program")
        .arg(FAKE)
        .arg("--out")
        .arg(out)
        .env("FAKE_LOG", log);
    match fail {
        Some(run) => cmd.env("FAKE_FAIL", run),
        None => cmd.env_remove("FAKE_FAIL"),
    };
    cmd.output().expect("dualrep runs")
}

fn log_lines(log: &Path) -> Vec<String> {
    fs::read_to_string(log)
        .unwrap_or_default()
        .lines()
        .map(str::to_owned)
        .collect()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

struct Grid {
    _tmp: tempfile::TempDir,
    out: PathBuf,
    log: PathBuf,
}

fn grid() -> Grid {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("grid");
    let log = tmp.path().join("fake.log");
    Grid {
        _tmp: tmp,
        out,
        log,
    }
}

const FIG3_SMALL: &[&str] = &[
    "fig3",
    "--tasks",
    "reaching",
    "--seeds",
    "2",
    "--steps",
    "1000",
    "--jobs",
    "2",
    "--methods",
    "dref,sac,ef-dref",
    "--set",
    "batch_size=8",
];

#[test]
fn reproduce_runs_the_grid_then_ef_at_drefs_measured_rate_then_reports() {
    let g = grid();
    let out = reproduce(&g.out, &g.log, None, FIG3_SMALL);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        stdout.contains("6 runs: 6 ran, 0 already finished, 0 failed"),
        "{stdout}"
    );
    // Not a terminal: plain progress lines.
    assert!(stdout.contains("[6/6] done  reaching/"), "{stdout}");

    // DREF asked on 5 % and 7 % of steps: EF at DREF's rate runs as ef-6, after both DREF runs.
    let log = log_lines(&g.log);
    let last_dref_end = log
        .iter()
        .rposition(|l| l.starts_with("end reaching/dref/"))
        .unwrap();
    let first_matched = log
        .iter()
        .position(|l| l.starts_with("start reaching/ef-6/"))
        .unwrap();
    assert!(last_dref_end < first_matched, "{log:#?}");
    assert!(
        log.iter()
            .filter(|l| l.starts_with("start"))
            .all(|l| l.ends_with(" batch_size=8"))
    );
    for method in ["dref", "sac", "ef-6"] {
        for seed in 0..2 {
            let dir = g.out.join(format!("reaching/{method}/seed{seed}"));
            assert!(dir.join("summary.json").is_file(), "{}", dir.display());
            assert!(dir.join("stdout.log").is_file() && dir.join("stderr.log").is_file());
        }
    }

    let table = fs::read_to_string(g.out.join("table.md")).unwrap();
    assert!(table.contains("| EF-6% (DREF's rate) |"), "{table}");
    assert!(
        table.contains(
            "| DREF | 41 ± 1 | 6.0 ± 1.0 % | 2 | 0 | 0.0 ± 0.0 % | >= 0 | – | 1.00 | 11.4k (1.6 %) |"
        ),
        "{table}"
    );
    assert!(
        table.contains("DREF above EF-6% (its rate): one-sided exact Mann-Whitney U ="),
        "{table}"
    );
    let svg = fs::read_to_string(g.out.join("fig3.svg")).unwrap();
    assert!(
        svg.contains("DREF (6.0 %)"),
        "legend with DREF's feedback percentage"
    );
    assert!(fs::metadata(g.out.join("fig3.png")).unwrap().len() > 0);
}

#[test]
fn reproduce_resumes_by_skipping_finished_runs() {
    let g = grid();
    assert!(reproduce(&g.out, &g.log, None, FIG3_SMALL).status.success());
    let before = log_lines(&g.log).len();
    // Half a grid lost: one run's summary is gone, as if it had been killed mid-way.
    fs::remove_file(g.out.join("reaching/sac/seed1/summary.json")).unwrap();

    let again = reproduce(&g.out, &g.log, None, FIG3_SMALL);
    assert!(again.status.success(), "{}", stderr(&again));
    let stdout = String::from_utf8(again.stdout).unwrap();
    assert!(
        stdout.contains("6 runs: 1 ran, 5 already finished, 0 failed"),
        "{stdout}"
    );
    let new: Vec<String> = log_lines(&g.log).split_off(before);
    assert_eq!(
        new,
        [
            // Reaching's SAC row runs at the authors' reward scale.
            "start reaching/sac/seed1 reward_scale=0.1 batch_size=8",
            "end reaching/sac/seed1"
        ]
    );
}

#[test]
fn reproduce_reports_a_failing_run_finishes_the_others_and_exits_non_zero() {
    let g = grid();
    let failing = "reaching/sac/seed0";
    let out = reproduce(&g.out, &g.log, Some(failing), FIG3_SMALL);
    let err = refused(&out);
    assert!(err.contains("1 of 6 runs failed"), "{err}");
    assert!(
        err.contains("reaching/sac/seed0: exit code 1: error: fake failure"),
        "{err}"
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.contains("FAIL  reaching/sac/seed0"), "{stdout}");

    let dir = g.out.join(failing);
    assert!(!dir.join("summary.json").exists());
    let saved = fs::read_to_string(dir.join("stderr.log")).unwrap();
    assert_eq!(saved, format!("error: fake failure of {failing}\n"));
    assert_eq!(
        log_lines(&g.log)
            .iter()
            .filter(|l| l.starts_with("end"))
            .count(),
        5
    );
    // The report covers what finished.
    let table = fs::read_to_string(g.out.join("table.md")).unwrap();
    assert!(
        table.contains("| SAC | 42 ± 0 | 0.0 ± 0.0 % | 1 |"),
        "{table}"
    );

    // Once the cause is gone, the same command runs just the failed run.
    let retry = reproduce(&g.out, &g.log, None, FIG3_SMALL);
    assert!(retry.status.success(), "{}", stderr(&retry));
    assert!(
        String::from_utf8(retry.stdout)
            .unwrap()
            .contains("6 runs: 1 ran, 5 already finished")
    );
}

#[test]
fn reproduce_without_dref_runs_ef_at_the_papers_rate() {
    let g = grid();
    let args = [
        "fig3",
        "--tasks",
        "reaching",
        "--seeds",
        "1",
        "--steps",
        "500",
        "--methods",
        "sac,ef-dref",
    ];
    let out = reproduce(&g.out, &g.log, None, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        String::from_utf8(out.stdout)
            .unwrap()
            .contains("the paper's 1.6 %")
    );
    assert!(g.out.join("reaching/ef-1.6/seed0/summary.json").is_file());
}

#[test]
fn reproduce_fig5_runs_prefs_with_the_query_budget() {
    let g = grid();
    let args = [
        "fig5",
        "--tasks",
        "placing,reaching",
        "--seeds",
        "2",
        "--queries",
        "3",
        "--methods",
        "drpl,full",
        "--jobs",
        "3",
    ];
    let out = reproduce(&g.out, &g.log, None, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let rows = fs::read_to_string(g.out.join("placing/drpl/seed1/alignment.csv")).unwrap();
    assert_eq!(rows.lines().count(), 4, "header and three queries");
    let table = fs::read_to_string(g.out.join("table.md")).unwrap();
    assert!(table.contains("## Placing-Sim: 3 queries"), "{table}");
    assert!(
        table.contains("| DRPL | 0.300 ± 0.000 | 0.300 ± 0.000 | 7.0 ± 0.0 | 2 |"),
        "{table}"
    );
    assert!(
        fs::read_to_string(g.out.join("fig5.svg"))
            .unwrap()
            .contains("Full trajectory")
    );
}

#[test]
fn reproduce_rejects_bad_arguments_before_running_anything() {
    let g = grid();
    for (args, message) in [
        (
            &["fig3", "--methods", "dref,drpl"][..],
            "unknown method \"drpl\" for fig3",
        ),
        (&["fig5", "--steps", "10"][..], "--steps is for fig3"),
        (&["fig3", "--queries", "10"][..], "--queries is for fig5"),
        (&["fig3", "--set", "no_equals"][..], "expected KEY=VALUE"),
        (&["fig3", "--tasks", "walking"][..], "unknown task"),
        (&["fig3", "--jobs", "0"][..], "--jobs"),
        (
            &["fig5", "--partition", "short"][..],
            "--partition is for --executor slurm",
        ),
        (
            &["fig5", "--no-wait"][..],
            "--no-wait is for --executor slurm",
        ),
        (
            &["fig5", "--executor", "slurm", "--time", "1 hour"][..],
            "--time \"1 hour\": expected one word",
        ),
        (
            &["fig5", "--executor", "slurm", "--sbatch-arg", "qos=low"][..],
            "expected an sbatch option",
        ),
        (
            &["fig5", "--executor", "slurm", "--poll", "0"][..],
            "--poll 0",
        ),
        (&["fig5", "--executor", "pbs"][..], "invalid value 'pbs'"),
        (
            &["fig5", "--report-only", "--executor", "slurm", "--no-wait"][..],
            "--report-only runs nothing",
        ),
    ] {
        let err = refused(&reproduce(&g.out, &g.log, None, args));
        assert!(err.contains(message), "{args:?}: {err}");
    }
    assert!(!g.out.exists(), "nothing ran, nothing written");
    assert!(!g.log.exists());
}

#[test]
fn each_run_gets_the_cores_divided_by_the_jobs_and_the_parents_kernels() {
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    for (jobs, extra, threads) in [
        ("2", None, (cores / 2).clamp(1, 2)),
        ("1", None, cores.clamp(1, 2)),
        ("2", Some("--threads=3"), 3),
    ] {
        let g = grid();
        let mut args = vec![
            "fig3",
            "--tasks",
            "reaching",
            "--seeds",
            "1",
            "--methods",
            "sac",
            "--jobs",
            jobs,
            "--kernels",
            "portable",
        ];
        args.extend(extra);
        let out = reproduce(&g.out, &g.log, None, &args);
        assert!(out.status.success(), "{}", stderr(&out));
        let env = fs::read_to_string(g.out.join("reaching/sac/seed0/env.txt")).unwrap();
        assert_eq!(
            env.trim(),
            format!("threads={threads} kernels=portable"),
            "--jobs {jobs} {extra:?}"
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains(&format!(
                "each on {threads} thread(s) with the portable kernels"
            )),
            "{stdout}"
        );
    }
}

/// `reproduce robustness` with the real binary, at a toy size: both sweeps run, each run's
/// teacher is as its directory says, and the table and figure come out.
#[test]
fn robustness_sweeps_the_teachers_faults_and_reports() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("robust");
    let run = Command::new(env!("CARGO_BIN_EXE_dualrep"))
        .args([
            "reproduce",
            "robustness",
            "--tasks",
            "reaching",
            "--seeds",
            "1",
            "--steps",
            "120",
            "--queries",
            "3",
            "--errors",
            "0,30",
            "--betas",
            "1,rational",
            "--jobs",
            "2",
            "--set",
            "variant=uniform",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let config = |dir: &str, file: &str| -> serde_json::Value {
        let text = fs::read_to_string(out.join("reaching").join(dir).join("seed0").join(file));
        serde_json::from_str(&text.unwrap()).unwrap()
    };
    assert_eq!(config("dref-err30", "config.json")["teacher"]["error"], 0.3);
    assert!(
        config("ef-100-err0", "config.json")
            .get("teacher")
            .is_none(),
        "no faults at 0 %"
    );
    assert_eq!(
        config("drpl-beta1", "summary.json")["config"]["teacher"]["beta"],
        1.0
    );
    assert!(
        config("drpl-rational", "summary.json")["config"]
            .get("teacher")
            .is_none()
    );
    let table = fs::read_to_string(out.join("table.md")).unwrap();
    for row in [
        "| 0 % | DREF | 1 |",
        "| 30 % | EF-100% | 1 |",
        "| 1 | DRPL | 1 |",
        "| rational | DRPL | 1 |",
    ] {
        assert!(table.contains(row), "{row} in\n{table}");
    }
    assert!(out.join("robustness.svg").is_file() && out.join("robustness.png").is_file());
    // --errors belongs to this grid alone.
    let out = Command::new(env!("CARGO_BIN_EXE_dualrep"))
        .args(["reproduce", "fig5", "--errors", "10", "--out"])
        .arg(tmp.path().join("x"))
        .output()
        .unwrap();
    assert!(refused(&out).contains("robustness"));
}
