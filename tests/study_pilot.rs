//! `dualrep study pilot` end to end on a tiny budget (a second or two in debug): the study's
//! own JSON file referenced from a TOML pilot file, the three files written, the numbers in
//! range, the same pool whatever the number of jobs, and clear errors on bad input.

use std::fs;
use std::path::Path;
use std::process::Output;

use crate::support::cli;

fn dualrep(args: &[&str], dir: &Path) -> Output {
    cli::dualrep_in(args, Some(dir))
}

/// The study as a researcher POSTs it: Reaching, EF-100 against SAC, 300 steps, tiny networks.
const STUDY: &str = r#"{
  "title": "Tiny pilot",
  "conditions": [
    {"name": "ef-100", "task": "reaching", "method": "ef-100",
     "params": {"hidden": [16, 16], "batch_size": 32}},
    {"name": "sac", "task": "reaching", "method": "sac",
     "params": {"hidden": [16, 16], "batch_size": 32}}
  ],
  "budget": {"steps": 300}
}"#;

const PILOT: &str = r#"
study = "study.json"
participants = 4
studies = 50

[teachers]
teacher_beta = [0.5, 5.0]
teacher_error = [0.0, 0.2]
"#;

fn write_pilot(d: &Path, pilot: &str) {
    fs::write(d.join("study.json"), STUDY).unwrap();
    fs::write(d.join("pilot.toml"), pilot).unwrap();
}

fn run_pilot(d: &Path, out: &str, extra: &[&str]) -> Output {
    let mut args = vec!["study", "pilot", "--spec", "pilot.toml", "--out", out];
    args.extend(extra);
    dualrep(&args, d)
}

#[test]
fn a_pilot_trains_its_pool_and_reports_power_for_each_n() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_pilot(d, PILOT);
    let out = run_pilot(d, "out", &["--ns", "4,6,8", "--jobs", "2"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "stderr: {stderr}");
    assert!(
        stderr.contains("4 simulated participants x 2 conditions = 8 runs"),
        "{stderr}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("## Power"), "{stdout}");
    assert!(stdout.contains("**ef-100** vs **sac**"), "{stdout}");

    let md = fs::read_to_string(d.join("out/pilot.md")).unwrap();
    assert_eq!(md, stdout);
    let report: serde_json::Value =
        serde_json::from_slice(&fs::read(d.join("out/pilot.json")).unwrap()).unwrap();
    assert_eq!(report["participants"], 4);
    assert_eq!(report["studies"], 50);
    assert_eq!(report["measure"], "cumulative_reward");
    assert_eq!(report["contrast"], serde_json::json!(["ef-100", "sac"]));
    assert_eq!(
        report["teachers"],
        serde_json::json!({"teacher_beta": [0.5, 5.0], "teacher_error": [0.0, 0.2]})
    );
    let power = report["power"].as_array().unwrap();
    let ns: Vec<u64> = power.iter().map(|r| r["n"].as_u64().unwrap()).collect();
    assert_eq!(ns, [4, 6, 8]);
    let in_unit = |v: &serde_json::Value| v.as_f64().is_some_and(|x| (0.0..=1.0).contains(&x));
    for row in power {
        assert!(in_unit(&row["bootstrap"]["power"]), "{row}");
        assert!(in_unit(&row["bootstrap"]["mc_se"]), "{row}");
        assert_eq!(row["bootstrap"]["studies"], 50);
    }
    // Distinct participants only up to the pool's size.
    assert!(in_unit(&power[0]["subsample"]["power"]), "{}", power[0]);
    assert!(power[1]["subsample"].is_null());
    // Two conditions: no Friedman.
    assert!(power[0]["friedman_bootstrap"].is_null());
    for c in report["pool"].as_array().unwrap() {
        assert!(c["score"]["mean"].as_f64().unwrap().is_finite(), "{c}");
        assert_eq!(c["score"]["n"], 4);
    }
    assert_eq!(report["pool"][0]["feedback_percent"]["mean"], 100.0);
    assert_eq!(report["pool"][1]["feedback_percent"]["mean"], 0.0);
    assert!(report["wall_seconds"].as_f64().unwrap() > 0.0);

    let csv = fs::read_to_string(d.join("out/participants.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 8);
    for row in &rows {
        let beta: f64 = row[4].parse().unwrap();
        let error: f64 = row[6].parse().unwrap();
        assert!(
            (0.5..=5.0).contains(&beta) && (0.0..=0.2).contains(&error),
            "{row:?}"
        );
        assert!(row[9].parse::<f64>().unwrap().is_finite(), "{row:?}");
    }

    // The same pool, run by one job at a time.
    let again = run_pilot(d, "again", &["--ns", "4,6,8", "--jobs", "1"]);
    assert!(again.status.success());
    assert_eq!(
        fs::read_to_string(d.join("again/participants.csv")).unwrap(),
        csv
    );
}

fn assert_refused(d: &Path, pilot: &str, extra: &[&str], expected: &str) {
    write_pilot(d, pilot);
    let stderr = cli::refused(&run_pilot(d, "out", extra));
    assert!(
        stderr.contains(expected),
        "{pilot} {extra:?}: stderr was {stderr}"
    );
    assert!(!d.join("out").exists(), "nothing written for {pilot}");
}

#[test]
fn bad_pilots_are_refused_naming_what_was_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert_refused(
        d,
        "study = \"study.json\"\n[teachers]\nteacher_temper = [0, 1]\n",
        &[],
        "teachers.teacher_temper: not a teacher setting; expected one of teacher_beta",
    );
    assert_refused(
        d,
        "study = \"study.json\"\n[teachers]\nteacher_error = [0.3, 0.1]\n",
        &[],
        "teachers.teacher_error: [0.3, 0.1]: the low end is above the high end",
    );
    assert_refused(
        d,
        "study = \"study.json\"\n[teachers]\nteacher_error = [0.0, 1.5]\n",
        &[],
        "teachers.teacher_error: expected a probability in [0, 1), got 1.5",
    );
    assert_refused(
        d,
        "study = \"study.json\"\nstudy_size = 4\n",
        &[],
        "unknown field `study_size`",
    );
    assert_refused(d, "study = \"other.json\"\n", &[], "other.json");
    assert_refused(
        d,
        "study = \"study.json\"\n",
        &["--ns", "1,4"],
        "ns: a study has 2 to 1000",
    );
    assert_refused(
        d,
        "study = \"study.json\"\n",
        &["--participants", "1"],
        "--participants",
    );
    assert_refused(d, "study = [1, 2\n", &[], "pilot.toml");

    fs::write(d.join("pilot.yaml"), "study: {}").unwrap();
    let out = dualrep(
        &["study", "pilot", "--spec", "pilot.yaml", "--out", "out"],
        d,
    );
    assert!(cli::refused(&out).contains("expected a .toml or .json file"));

    fs::write(
        d.join("study.json"),
        STUDY.replace("\"sac\", \"task\"", "\"ef-100\", \"task\""),
    )
    .unwrap();
    fs::write(d.join("pilot.json"), r#"{"study": "study.json"}"#).unwrap();
    let out = dualrep(
        &["study", "pilot", "--spec", "pilot.json", "--out", "out"],
        d,
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("study.conditions: condition \"ef-100\" appears more than once"),
        "{stderr}"
    );
}
