//! `dualrep reproduce --executor slurm` against a real single-node Slurm cluster that each test
//! starts and stops itself (`support::slurm_cluster`): the job array, waiting, `--no-wait`,
//! runs still queued picked up instead of submitted again, a task cancelled or failed submitted
//! again by the next run, logs beside the runs, and the same `table.md` as the local executor.
//!
//! Needs Debian's `slurmctld`, `slurmd` and `slurm-client` (`bash tests/run.sh` installs whichever is
//! missing). `DUALREP_SKIP_SLURM=1` skips these tests, loudly; without it, missing packages are a
//! failure.

use std::fs;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use crate::support::cli::refused;
use crate::support::slurm_cluster::Cluster;

const FAKE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/fake_dualrep.sh"
);

/// A Figure 5 grid of four real `dualrep prefs` runs of a second or so each.
const FIG5_TINY: &[&str] = &[
    "fig5",
    "--tasks",
    "reaching",
    "--seeds",
    "2",
    "--queries",
    "3",
    "--methods",
    "drpl,full",
    "--set",
    "trajectories=6",
    "--set",
    "samples=20",
];

/// `dualrep reproduce ARGS --out OUT` talking to `cluster`.
fn reproduce(cluster: &Cluster, out: &Path, args: &[&str]) -> Command {
    let mut cmd = cluster.command(env!("CARGO_BIN_EXE_dualrep"));
    cmd.arg("reproduce")
        .args(args)
        .arg("--out")
        .arg(out)
        .env_remove("FAKE_FAIL")
        .env_remove("FAKE_HANG");
    cmd
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn succeeded(out: &Output, cluster: &Cluster) -> String {
    assert!(
        out.status.success(),
        "stdout:\n{}\nstderr:\n{}\n{}",
        text(&out.stdout),
        text(&out.stderr),
        cluster.logs()
    );
    text(&out.stdout)
}

/// The job id in "submitted N run(s) as Slurm job array ID (...)", the `nth` such line.
fn array_id(stdout: &str, nth: usize) -> String {
    stdout
        .lines()
        .filter_map(|l| l.split("as Slurm job array ").nth(1))
        .nth(nth)
        .and_then(|rest| rest.split_whitespace().next())
        .unwrap_or_else(|| panic!("no submission line {nth} in:\n{stdout}"))
        .to_string()
}

#[test]
fn slurm_fig5_grid_matches_the_local_table_and_resubmits_a_cancelled_task() {
    let Some(cluster) = Cluster::start() else {
        return;
    };
    let started = Instant::now();
    let tmp = tempfile::tempdir().unwrap();
    let (local, slurm) = (tmp.path().join("local"), tmp.path().join("slurm"));

    let out = Command::new(env!("CARGO_BIN_EXE_dualrep"))
        .arg("reproduce")
        .args(FIG5_TINY)
        .arg("--out")
        .arg(&local)
        .output()
        .unwrap();
    succeeded(&out, &cluster);

    // Submitted on hold, without waiting: all four are in the queue and the command is done.
    let no_wait = [
        FIG5_TINY,
        &["--executor", "slurm", "--no-wait", "--sbatch-arg=--hold"],
    ]
    .concat();
    let out = reproduce(&cluster, &slurm, &no_wait).output().unwrap();
    let stdout = succeeded(&out, &cluster);
    assert!(
        stdout.contains("4 runs: 4 in the Slurm queue, 0 already finished"),
        "{stdout}"
    );
    let first = array_id(&stdout, 0);
    assert!(
        stdout.contains(&format!("queue reaching/drpl/seed1 (Slurm task {first}_1)")),
        "{stdout}"
    );
    let queued = cluster.output("squeue", &["--noheader", "--array", "--format=%i %T"]);
    assert_eq!(
        text(&queued.stdout).lines().count(),
        4,
        "{}",
        text(&queued.stdout)
    );

    // One task is cancelled before it runs.
    assert!(
        cluster
            .output("scancel", &[&format!("{first}_1")])
            .status
            .success()
    );

    // The same command, waiting: the three runs still held are waited for, and only the
    // cancelled one is submitted again. They are let go once it has looked at the queue, so
    // that none can finish before (and be skipped as finished instead).
    let wait = [FIG5_TINY, &["--executor", "slurm", "--poll", "0.2"]].concat();
    let mut child = reproduce(&cluster, &slurm, &wait)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let mut head = String::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        head += &line;
        head.push('\n');
        if line.starts_with("submitted ") {
            break;
        }
    }
    assert!(
        cluster
            .output("scontrol", &["release", &first])
            .status
            .success()
    );
    let rest: Vec<String> = lines.map(Result::unwrap).collect();
    let mut out = child.wait_with_output().unwrap();
    out.stdout = format!("{head}{}", rest.join("\n")).into_bytes();
    let stdout = succeeded(&out, &cluster);
    assert!(
        stdout.contains("3 run(s) already in the Slurm queue from an earlier submission"),
        "{stdout}"
    );
    let second = array_id(&stdout, 0);
    assert_ne!(first, second);
    assert!(
        stdout.contains("submitted 1 run(s) as Slurm job array"),
        "{stdout}"
    );
    assert!(
        stdout.contains("4 runs: 4 ran, 0 already finished, 0 failed"),
        "{stdout}"
    );
    assert_eq!(stdout.matches("as Slurm job array").count(), 1, "{stdout}");

    let table = |root: &Path| fs::read(root.join("table.md")).unwrap();
    let (ours, theirs) = (table(&slurm), table(&local));
    assert!(
        ours == theirs,
        "the cluster's table.md is the local executor's, byte for byte:\n{}\n---\n{}",
        text(&ours),
        text(&theirs)
    );
    assert!(text(&ours).contains("| DRPL |"), "{}", text(&ours));
    // Each run's output is beside it, as the local executor leaves it, with a link to Slurm's
    // log of the task that ran it.
    let resubmitted = slurm.join("reaching/drpl/seed1");
    for file in ["summary.json", "stdout.log", "stderr.log"] {
        assert!(resubmitted.join(file).is_file(), "{file}");
    }
    assert_eq!(
        fs::read_link(resubmitted.join("slurm.log")).unwrap(),
        Path::new(&format!("../../../.slurm/logs/{second}_0.log"))
    );
    assert!(resubmitted.join("slurm.log").is_file(), "the link resolves");
    eprintln!(
        "slurm: fig5 grid test took {:.1} s after the cluster was up",
        started.elapsed().as_secs_f64()
    );
}

/// Waits until `file` holds `line` (a task has got as far as printing it).
fn wait_for_line(cluster: &Cluster, file: &Path, line: &str) {
    let deadline = Instant::now() + Duration::from_secs(60);
    while Instant::now() < deadline {
        if fs::read_to_string(file).is_ok_and(|t| t.lines().any(|l| l == line)) {
            return;
        }
        thread::sleep(Duration::from_millis(50));
    }
    panic!(
        "{} never said {line:?}:\n{}",
        file.display(),
        cluster.logs()
    );
}

#[test]
fn slurm_failed_and_killed_tasks_keep_their_logs_and_run_again() {
    let Some(cluster) = Cluster::start() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let grid = tmp.path().join("grid");
    let args = [
        "fig5",
        "--tasks",
        "reaching",
        "--seeds",
        "2",
        "--queries",
        "3",
        "--methods",
        "drpl,full",
        "--executor",
        "slurm",
        "--program",
        FAKE,
        "--poll",
        "0.2",
    ];
    // One run fails; another hangs until it is killed with scancel while running. The
    // environment at submission is the tasks' environment (sbatch --export=ALL).
    let child = reproduce(&cluster, &grid, &args)
        .env("FAKE_FAIL", "reaching/drpl/seed0")
        .env("FAKE_HANG", "reaching/full/seed1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let ledger = grid.join(".slurm/submissions.jsonl");
    let deadline = Instant::now() + Duration::from_secs(30);
    while !ledger.is_file() && Instant::now() < deadline {
        thread::sleep(Duration::from_millis(50));
    }
    let line: serde_json::Value =
        serde_json::from_str(fs::read_to_string(&ledger).unwrap().lines().next().unwrap()).unwrap();
    let job = line["job"].as_str().unwrap().to_string();
    assert_eq!(line["runs"][3], "reaching/full/seed1");
    // Killed while it runs: once it has printed its first line.
    let hanging = format!("{job}_3");
    let killed = grid.join("reaching/full/seed1");
    wait_for_line(
        &cluster,
        &killed.join("stdout.log"),
        "training reaching/full/seed1",
    );
    assert!(cluster.output("scancel", &[&hanging]).status.success());

    let stderr = refused(&child.wait_with_output().unwrap());
    assert!(stderr.contains("2 of 4 runs failed"), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "reaching/drpl/seed0: Slurm FAILED {job}_0, exit code 1: error: fake failure of \
             reaching/drpl/seed0"
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!("reaching/full/seed1: Slurm CANCELLED {job}_3")),
        "{stderr}"
    );
    // The failed run's logs stay beside it.
    let failed = grid.join("reaching/drpl/seed0");
    assert!(!failed.join("summary.json").exists());
    assert_eq!(
        fs::read_to_string(failed.join("stderr.log")).unwrap(),
        "error: fake failure of reaching/drpl/seed0\n"
    );
    assert_eq!(
        fs::read_to_string(failed.join("stdout.log")).unwrap(),
        "training reaching/drpl/seed0\n"
    );
    assert_eq!(
        fs::read_to_string(killed.join("stdout.log")).unwrap(),
        "training reaching/full/seed1\n"
    );
    // Slurm's own word on the kill is in the task's log, linked beside the run.
    let slurm_log = fs::read_to_string(killed.join("slurm.log")).unwrap();
    assert!(slurm_log.contains("CANCELLED"), "{slurm_log}");

    // The cause gone, the same command submits just the two and waits for them.
    let out = reproduce(&cluster, &grid, &args).output().unwrap();
    let stdout = succeeded(&out, &cluster);
    assert!(
        stdout.contains("submitted 2 run(s) as Slurm job array"),
        "{stdout}"
    );
    assert!(
        stdout.contains("4 runs: 2 ran, 2 already finished, 0 failed"),
        "{stdout}"
    );
    assert!(failed.join("summary.json").is_file() && killed.join("summary.json").is_file());
}
