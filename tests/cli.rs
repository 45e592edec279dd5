//! The `dualrep` binary as a user runs it: JSON on success, a clear message and a non-zero exit
//! on bad arguments.

use std::process::Output;

use crate::support::cli::{dualrep_in, refused};

fn dualrep(args: &[&str]) -> Output {
    dualrep_in(args, None)
}

#[test]
fn sim_prints_one_json_summary_with_every_field() {
    let out = dualrep(&[
        "sim",
        "--task",
        "reaching",
        "--policy",
        "heuristic",
        "--episodes",
        "3",
        "--seed",
        "5",
    ]);
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        stdout.lines().count(),
        1,
        "one JSON object on one line: {stdout}"
    );
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["task"], "reaching");
    assert_eq!(v["policy"], "heuristic");
    assert_eq!(v["episodes"], 3);
    for field in [
        "mean_return",
        "std_return",
        "mean_length",
        "success_rate",
        "steps_per_second",
    ] {
        assert!(v[field].is_number(), "{field} missing in {v}");
    }
    assert!(v["steps_per_second"].as_f64().unwrap() > 0.0);
}

#[test]
fn sim_is_reproducible_from_its_seed() {
    let args = [
        "sim",
        "--task",
        "placing",
        "--policy",
        "random",
        "--episodes",
        "2",
        "--seed",
        "11",
    ];
    let strip = |out: Output| {
        let mut v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v.as_object_mut().unwrap().remove("steps_per_second");
        v
    };
    assert_eq!(strip(dualrep(&args)), strip(dualrep(&args)));
}

#[test]
fn sim_writes_every_step_with_its_abstract_state_and_each_episode_ends_once() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("steps.csv");
    let run = |noise: &str| {
        let out = dualrep(&[
            "sim",
            "--task",
            "lunar-lander",
            "--episodes",
            "4",
            "--seed",
            "3",
            "--noise",
            noise,
            "--steps",
            path.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (summary, std::fs::read_to_string(&path).unwrap())
    };
    let (summary, csv) = run("0.5");
    assert_eq!(summary["noise"]["std"], 0.5);
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[..3], ["seed", "t", "obs_0"]);
    assert_eq!(
        header[header.len() - 3..],
        ["reward", "abstract_state", "outcome"]
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let steps = summary["mean_length"].as_f64().unwrap() * 4.0;
    assert_eq!(rows.len() as f64, steps, "one row per step");
    let (x, y, angle, main) = (2, 3, 6, 10);
    let mut ends = 0;
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), header.len());
        let value = |c: usize| row[c].parse::<f32>().unwrap();
        let bits = row[header.len() - 2];
        assert_eq!(bits.len(), 10, "Lunar Lander's ten predicates");
        // The graph's bits against the observation and action beside them.
        assert_eq!(&bits[..1] == "1", value(x) < -0.28, "row {i}: {row:?}");
        assert_eq!(&bits[5..6] == "1", value(y) > 0.0, "row {i}: {row:?}");
        assert_eq!(
            &bits[6..7] == "1",
            value(angle).abs() < 0.5,
            "row {i}: {row:?}"
        );
        assert_eq!(&bits[7..8] == "1", value(main) > 0.0, "row {i}: {row:?}");
        let outcome = row[header.len() - 1];
        let last = rows.get(i + 1).is_none_or(|next| next[1] == "0");
        assert_eq!(
            !outcome.is_empty(),
            last,
            "an outcome on each episode's last step only"
        );
        ends += usize::from(last);
    }
    assert_eq!(ends, 4);
    // No noise, the heuristic's own episodes: it lands (tasks.md), where the noisy one differs.
    let (quiet, quiet_csv) = run("0");
    assert_eq!(quiet["noise"]["std"], 0.0);
    assert_ne!(quiet_csv, csv);
    // Streamed into a partial file that becomes the CSV at the end; a path that cannot be
    // written is refused when the file is created, before any episode runs.
    assert!(!dir.path().join("steps.partial").exists());
    let nowhere = dir.path().join("missing/steps.csv");
    assert_rejected(
        &[
            "sim",
            "--task",
            "lunar-lander",
            "--steps",
            nowhere.to_str().unwrap(),
        ],
        "missing/steps.csv: creating",
    );
    assert_rejected(
        &["sim", "--task", "lunar-lander", "--noise=-0.1"],
        "noise std -0.1: give a finite number at least 0",
    );
    assert_rejected(
        &["sim", "--task", "lunar-lander", "--noise-correlation", "1"],
        "noise correlation 1: give a number in [0, 1)",
    );
}

#[test]
fn bench_sac_reports_the_work_it_skips_beside_the_nominal_work() {
    // Reaching's sizes with the human critic: obs 15, act 4, [64, 64], batch 512 (debug build,
    // so the rates mean nothing; the arithmetic does).
    let out = dualrep(&[
        "bench",
        "sac",
        "--task",
        "reaching",
        "--hidden",
        "16,16",
        "--batch",
        "64",
        "--seconds",
        "0.3",
        "--kernels",
        "portable",
        "--threads",
        "1",
    ]);
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (obs, act) = (
        v["obs_dim"].as_f64().unwrap(),
        v["act_dim"].as_f64().unwrap(),
    );
    let per_column = 2.0 * ((obs + act) * 16.0 + 16.0 * 16.0 + 16.0) / 1e6;
    let nominal = v["mflop_per_update"].as_f64().unwrap();
    let done = v["mflop_done_per_update"].as_f64().unwrap();
    // Four frozen critics in the actor loss; each sample passes back through one head of each
    // of the two twin pairs: 2 x 64 of the 4 x 64 columns are skipped.
    let skipped_columns = (nominal - done) / per_column;
    assert!(
        (skipped_columns - 2.0 * 64.0).abs() < 1e-6,
        "{skipped_columns} columns skipped per update: {v}"
    );
    let (nominal_rate, done_rate) = (
        v["fraction_of_fma_peak"].as_f64().unwrap(),
        v["fraction_of_fma_peak_done"].as_f64().unwrap(),
    );
    assert!(done_rate < nominal_rate, "{v}");
}

fn assert_rejected(args: &[&str], expected_in_message: &str) {
    let out = dualrep(args);
    let stderr = refused(&out);
    assert!(out.stdout.is_empty(), "nothing on stdout for {args:?}");
    assert!(
        stderr.contains(expected_in_message),
        "{args:?}: stderr was {stderr}"
    );
}

#[test]
fn bad_arguments_exit_non_zero_with_a_clear_message() {
    assert_rejected(
        &["sim", "--task", "cartpole"],
        "expected one of reaching, placing, lunar-lander",
    );
    assert_rejected(
        &["sim", "--task", "reaching", "--policy", "greedy"],
        "expected random or heuristic",
    );
    assert_rejected(
        &["sim", "--task", "reaching", "--episodes", "0"],
        "--episodes",
    );
    assert_rejected(
        &["sim", "--task", "reaching", "--seed=-3"],
        "invalid value '-3' for '--seed",
    );
    assert_rejected(&["sim"], "--task");
    assert_rejected(&["fly"], "unrecognized subcommand");
}

#[test]
fn serve_names_what_is_wrong_with_its_database_and_never_its_password() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().to_str().unwrap();
    // Nothing listens on a port that was free a moment ago: refused at once.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let refused = format!("postgres://ann:secret@127.0.0.1:{port}/dualrep");
    let cases = [
        (
            "mysql://ann:secret@localhost/x",
            "names neither SQLite nor PostgreSQL".to_string(),
        ),
        (
            "postgres://ann:secret@localhost:port/x",
            "is not a valid PostgreSQL URL".into(),
        ),
        (
            &refused,
            format!("connecting to PostgreSQL at ann@127.0.0.1:{port}/dualrep"),
        ),
        (
            "sqlite:///nonexistent-dir/dualrep.db",
            "opening the SQLite database /nonexistent-dir/dualrep.db".into(),
        ),
    ];
    for (url, expected) in cases {
        let args = [
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--token",
            "t",
            "--data-dir",
            data,
            "--database",
            url,
        ];
        assert_rejected(&args, &expected);
        let stderr = String::from_utf8_lossy(&dualrep(&args).stderr).into_owned();
        assert!(!stderr.contains("secret"), "{url}: {stderr}");
    }
}
