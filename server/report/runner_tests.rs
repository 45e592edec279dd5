//! The runner's own rules (skip what finished, follow-ups after their trigger) with the local
//! pool as its executor and `/bin/sh` as the child: each run is a tiny script that gets its run
//! directory as `$1` and plays a finished or slow `dualrep train`.

use std::fs;
use std::path::Path;

use super::*;
use crate::report::local::LocalPool;
use crate::report::local::tests::{FINISH, SH, sh_run, statuses};

/// `run_grid` on a local pool of `jobs`, waiting until done.
fn run_local(
    runs: Vec<RunSpec>,
    jobs: usize,
    follow_up: impl FnMut(&Outcome) -> Vec<RunSpec>,
    on_event: impl FnMut(Event<'_>),
) -> Vec<Outcome> {
    let mut pool = LocalPool::new(Path::new(SH), jobs);
    let run = run_grid(&mut pool, runs, Waiting::UntilDone, follow_up, on_event).unwrap();
    assert_eq!(run.in_flight, 0);
    run.outcomes
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

    let outcomes = run_local(runs.clone(), 2, |_| vec![], |_| {});
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
    let again = run_local(
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
fn report_runner_queues_follow_up_runs_after_their_trigger() {
    let tmp = tempfile::tempdir().unwrap();
    let first = sh_run(tmp.path(), 0, FINISH);
    let later = sh_run(tmp.path(), 9, FINISH);
    let mut events = Vec::new();
    let outcomes = run_local(
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
                Event::Queued { spec, job } => format!("queued {} {job:?}", spec.seed),
                Event::Started(s) => format!("started {}", s.seed),
                Event::Finished(o) => format!("finished {}", o.spec.seed),
                Event::Note(text) => format!("note {text}"),
            })
        },
    );
    assert_eq!(outcomes.len(), 2);
    assert_eq!(
        events,
        [
            "queued 0 None",
            "started 0",
            "finished 0",
            "added 1",
            "queued 9 None",
            "started 9",
            "finished 9"
        ]
    );
}
