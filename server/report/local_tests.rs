//! The local pool with `/bin/sh` as the child: each run is a tiny script that gets its run
//! directory as `$1` and plays a finished, slow or failing `dualrep train`.

use std::path::Path;

use super::*;
use crate::sim::Task;

pub(crate) const SH: &str = "/bin/sh";

/// A run whose child is `sh -c script sh <dir>`.
pub(crate) fn sh_run(root: &Path, seed: u64, script: &str) -> RunSpec {
    let dir = root.join(format!("seed{seed}"));
    RunSpec {
        task: Task::Reaching,
        method: "sac".into(),
        seed,
        args: vec![
            "-c".into(),
            script.into(),
            "sh".into(),
            dir.to_string_lossy().into_owned(),
        ],
        dir,
    }
}

pub(crate) const FINISH: &str = r#"echo '{}' > "$1/summary.json""#;

pub(crate) fn statuses(outcomes: &[Outcome]) -> Vec<(u64, RunStatus)> {
    let mut s: Vec<_> = outcomes
        .iter()
        .map(|o| (o.spec.seed, o.status.clone()))
        .collect();
    s.sort_by_key(|(seed, _)| *seed);
    s
}

/// Every run through a pool of `jobs` children of `program`, in the order they ended.
fn run_pool(program: &Path, runs: Vec<RunSpec>, jobs: usize) -> Vec<Outcome> {
    let mut pool = LocalPool::new(program, jobs);
    pool.submit(runs, &mut |_| {}).unwrap();
    let mut outcomes = Vec::new();
    while pool.in_flight() > 0 {
        outcomes.extend(pool.wait(&mut |_| {}).unwrap());
    }
    outcomes
}

#[test]
fn report_local_pool_runs_exactly_jobs_children_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("log");
    // Each child logs its start, then waits (at most ~10 s) until two children have started:
    // with jobs = 2 the first two can only get past this together, which proves they overlap.
    let script = format!(
        r#"echo start >> "{log}"
        i=0
        while [ "$(grep -c start "{log}")" -lt 2 ] && [ $i -lt 1000 ]; do sleep 0.01; i=$((i+1)); done
        sleep 0.05
        echo end >> "{log}"
        {FINISH}"#,
        log = log.display()
    );
    let runs: Vec<_> = (0..6).map(|s| sh_run(tmp.path(), s, &script)).collect();
    let outcomes = run_pool(Path::new(SH), runs, 2);
    assert!(outcomes.iter().all(|o| o.status == RunStatus::Succeeded));

    let (mut now, mut most) = (0i32, 0i32);
    for line in fs::read_to_string(&log).unwrap().lines() {
        now += if line == "start" { 1 } else { -1 };
        most = most.max(now);
    }
    assert_eq!(most, 2, "two children at once, never more");
}

#[test]
fn report_local_pool_reports_a_failing_child_and_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    let runs = vec![
        sh_run(tmp.path(), 0, FINISH),
        sh_run(
            tmp.path(),
            1,
            "echo working; echo 'error: boom' >&2; exit 3",
        ),
        sh_run(tmp.path(), 2, FINISH),
        sh_run(tmp.path(), 3, "echo 'forgot the summary'"),
    ];
    let outcomes = run_pool(Path::new(SH), runs.clone(), 1);
    assert_eq!(
        statuses(&outcomes),
        [
            (0, RunStatus::Succeeded),
            (1, RunStatus::Failed("exit code 3: error: boom".into())),
            (2, RunStatus::Succeeded),
            (
                3,
                RunStatus::Failed(format!(
                    "exited 0 but wrote no {}",
                    runs[3].dir.join("summary.json").display()
                ))
            ),
        ]
    );
    // Its output is kept in its run directory for a post-mortem.
    let dir = &runs[1].dir;
    assert_eq!(
        fs::read_to_string(dir.join("stderr.log")).unwrap(),
        "error: boom\n"
    );
    assert_eq!(
        fs::read_to_string(dir.join("stdout.log")).unwrap(),
        "working\n"
    );
}

#[test]
fn report_local_pool_reports_a_program_that_cannot_start() {
    let tmp = tempfile::tempdir().unwrap();
    let run = sh_run(tmp.path(), 0, FINISH);
    let missing = tmp.path().join("no-such-program");
    let outcomes = run_pool(&missing, vec![run.clone()], 1);
    let RunStatus::Failed(why) = &outcomes[0].status else {
        panic!("{outcomes:?}");
    };
    assert!(why.starts_with("could not run"), "{why}");
    assert!(
        fs::read_to_string(run.dir.join("stderr.log"))
            .unwrap()
            .contains(why)
    );
}
