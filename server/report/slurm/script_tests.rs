//! The batch script run by bash as a Slurm node would run it (the array variables set by hand),
//! and the `sbatch` command line.

use std::fs;
use std::process::Command;

use super::*;
use crate::sim::Task;

fn settings() -> ArraySettings {
    ArraySettings {
        job_name: "dualrep-fig5".into(),
        program: "/bin/sh".into(),
        partition: None,
        time: None,
        cpus_per_task: 1,
        max_running: None,
        extra: vec![],
        env: vec![("DUALREP_KERNELS".into(), "avx2".into())],
    }
}

/// A run whose "program" is `sh -c script sh WORD`: it prints WORD and its own arguments'
/// count (and the kernels the task exported), so the test sees exactly which words reached it.
fn run(root: &Path, seed: u64, word: &str) -> RunSpec {
    RunSpec {
        task: Task::Placing,
        method: "drpl".into(),
        seed,
        dir: root.join(format!("placing/drpl/seed{seed}")),
        args: vec![
            "-c".into(),
            r#"printf '%s|%s|%s\n' "$#" "$1" "${DUALREP_KERNELS:-}"; echo "to stderr" >&2; exit 3"#
                .into(),
            "sh".into(),
            word.into(),
        ],
    }
}

#[test]
fn report_slurm_quoting_keeps_every_word_whole() {
    for word in [
        "plain",
        "two words",
        "it's",
        "a'b'c",
        "line\nbreak",
        "$HOME `id`",
        "",
    ] {
        let out = Command::new("bash")
            .arg("-c")
            .arg(format!("printf '%s' {}", shell_quote(word)))
            .output()
            .unwrap();
        assert_eq!(String::from_utf8(out.stdout).unwrap(), word);
    }
}

#[test]
fn report_slurm_array_task_runs_its_run_into_the_run_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("grid");
    let logs = root.join(".slurm/logs");
    let runs = [run(&root, 0, "first"), run(&root, 1, "it's the 'second'")];
    let script = tmp.path().join("array.sh");
    fs::write(
        &script,
        batch_script(&settings(), &runs, &root, &logs, &logs),
    )
    .unwrap();

    let status = Command::new("bash")
        .arg(&script)
        .env("SLURM_ARRAY_TASK_ID", "1")
        .env("SLURM_ARRAY_JOB_ID", "77")
        .status()
        .unwrap();
    assert_eq!(status.code(), Some(3), "the run's own exit status");
    let dir = &runs[1].dir;
    assert_eq!(
        fs::read_to_string(dir.join(STDOUT_LOG)).unwrap(),
        "1|it's the 'second'|avx2\n"
    );
    assert_eq!(
        fs::read_to_string(dir.join(STDERR_LOG)).unwrap(),
        "to stderr\n"
    );
    assert_eq!(
        fs::read_link(dir.join(SLURM_LOG_LINK)).unwrap(),
        Path::new("../../../.slurm/logs/77_1.log")
    );
    assert!(!runs[0].dir.exists(), "task 1 touches only its own run");

    // An index past the array is an error, not some other run.
    let out = Command::new("bash")
        .arg(&script)
        .env("SLURM_ARRAY_TASK_ID", "2")
        .env("SLURM_ARRAY_JOB_ID", "77")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("array task 2 has no run"));
}

#[test]
fn report_slurm_link_is_absolute_for_a_run_outside_the_grid() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("grid");
    let elsewhere = run(tmp.path(), 4, "x");
    let text = batch_script(
        &settings(),
        &[elsewhere],
        &root,
        &root.join(".slurm/logs"),
        Path::new("/abs/grid/.slurm/logs"),
    );
    assert!(text.contains("logs='/abs/grid/.slurm/logs'"), "{text}");
}

#[test]
fn report_slurm_sbatch_arguments() {
    let mut s = settings();
    assert_eq!(
        sbatch_args(
            &s,
            4,
            Path::new("/g/.slurm/array-1.sh"),
            Path::new("/g/.slurm/logs"),
            Path::new("/home/me")
        ),
        [
            "--parsable",
            "--job-name=dualrep-fig5",
            "--array=0-3",
            "--output=/g/.slurm/logs/%A_%a.log",
            "--open-mode=append",
            "--chdir=/home/me",
            "--cpus-per-task=1",
            "/g/.slurm/array-1.sh",
        ]
    );
    s.partition = Some("short".into());
    s.time = Some("1:00:00".into());
    s.cpus_per_task = 2;
    s.max_running = Some(8);
    s.extra = vec!["--qos=low".into(), "--requeue".into()];
    let args = sbatch_args(&s, 90, Path::new("a.sh"), Path::new("/l"), Path::new("/w"));
    assert_eq!(
        args[2..],
        [
            "--array=0-89%8",
            "--output=/l/%A_%a.log",
            "--open-mode=append",
            "--chdir=/w",
            "--cpus-per-task=2",
            "--partition=short",
            "--time=1:00:00",
            "--qos=low",
            "--requeue",
            "a.sh",
        ]
    );
}
