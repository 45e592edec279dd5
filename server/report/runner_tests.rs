//! The runner with `/bin/sh` as the child: each run is a tiny script that gets its run
//! directory as `$1` and plays a finished, slow or failing `dualrep train`.

use std::path::Path;

use super::*;
use crate::sim::Task;

const SH: &str = "/bin/sh";

/// A run whose child is `sh -c script sh <dir>`.
fn sh_run(root: &Path, seed: u64, script: &str) -> RunSpec {
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

const FINISH: &str = r#"echo '{}' > "$1/summary.json""#;

fn statuses(outcomes: &[Outcome]) -> Vec<(u64, RunStatus)> {
    let mut s: Vec<_> = outcomes
        .iter()
        .map(|o| (o.spec.seed, o.status.clone()))
        .collect();
    s.sort_by_key(|(seed, _)| *seed);
    s
}

#[test]
fn report_runner_skips_finished_runs_so_a_grid_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let runs = vec![
        sh_run(tmp.path(), 0, &format!("echo ran > \"$1/ran\"; {FINISH}")),
        sh_run(tmp.path(), 1, &format!("echo ran > \"$1/ran\"; {FINISH}")),
    ];
    // Seed 0 finished in an earlier, interrupted invocation.
    fs::create_dir_all(&runs[0].dir).unwrap();
    fs::write(runs[0].dir.join("summary.json"), "{\"earlier\": true}").unwrap();

    let outcomes = run_grid(Path::new(SH), runs.clone(), 2, |_| vec![], |_| {});
    assert_eq!(
        statuses(&outcomes),
        [(0, RunStatus::Skipped), (1, RunStatus::Succeeded)]
    );
    assert!(
        !runs[0].dir.join("ran").exists(),
        "a finished run is not run again"
    );
    assert_eq!(
        fs::read_to_string(runs[0].dir.join("summary.json")).unwrap(),
        "{\"earlier\": true}"
    );
    // A second invocation finds everything done and starts nothing.
    let mut started = 0;
    let again = run_grid(
        Path::new(SH),
        runs,
        2,
        |_| vec![],
        |e| {
            started += matches!(e, Event::Started(_)) as usize;
        },
    );
    assert_eq!(started, 0);
    assert!(again.iter().all(|o| o.status == RunStatus::Skipped));
}

#[test]
fn report_runner_runs_exactly_jobs_children_at_once() {
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
    let outcomes = run_grid(Path::new(SH), runs, 2, |_| vec![], |_| {});
    assert!(outcomes.iter().all(|o| o.status == RunStatus::Succeeded));

    let (mut now, mut most) = (0i32, 0i32);
    for line in fs::read_to_string(&log).unwrap().lines() {
        now += if line == "start" { 1 } else { -1 };
        most = most.max(now);
    }
    assert_eq!(most, 2, "two children at once, never more");
}

#[test]
fn report_runner_reports_a_failing_child_and_goes_on() {
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
    let outcomes = run_grid(Path::new(SH), runs.clone(), 1, |_| vec![], |_| {});
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
fn report_runner_reports_a_program_that_cannot_start() {
    let tmp = tempfile::tempdir().unwrap();
    let run = sh_run(tmp.path(), 0, FINISH);
    let missing = tmp.path().join("no-such-program");
    let outcomes = run_grid(&missing, vec![run.clone()], 1, |_| vec![], |_| {});
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

#[test]
fn report_runner_queues_follow_up_runs_after_their_trigger() {
    let tmp = tempfile::tempdir().unwrap();
    let first = sh_run(tmp.path(), 0, FINISH);
    let later = sh_run(tmp.path(), 9, FINISH);
    let mut events = Vec::new();
    let outcomes = run_grid(
        Path::new(SH),
        vec![first],
        4,
        |o| {
            if o.spec.seed == 0 {
                vec![later.clone()]
            } else {
                vec![]
            }
        },
        |e| {
            events.push(match e {
                Event::Added(n) => format!("added {n}"),
                Event::Started(s) => format!("started {}", s.seed),
                Event::Finished(o) => format!("finished {}", o.spec.seed),
            })
        },
    );
    assert_eq!(outcomes.len(), 2);
    assert_eq!(
        events,
        [
            "started 0",
            "finished 0",
            "added 1",
            "started 9",
            "finished 9"
        ]
    );
}
