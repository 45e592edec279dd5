//! The Rerun recording end to end: a short evaluative run of each task is recorded into an
//! `.rrd` file by `record::Recorder`, and the Python `rerun-sdk` of the same version reads it
//! back (`tests/support/read_rrd.py`). Checks the entity paths, both timelines, one row per step
//! for every per-step entity, the predicates against the scene graph, and every query and
//! answer.

use crate::support::rerun_py;

use std::collections::BTreeSet;
use std::path::Path;

use dualrep::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig};
use dualrep::guidance::evaluative_trainer::{Evaluation, EvaluativeQuery, EvaluativeTrainer};
use dualrep::record::{Recorder, RecordingOptions};
use dualrep::scene_graph::SceneGraph;
use dualrep::sim::Task;
use serde_json::Value;

/// A session moves its recorder to the training thread.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<Recorder>();
};

/// Answers +1, 0, -1 in turn: deterministic, and every value appears.
struct Cycling(u64);

impl EvaluativeTrainer for Cycling {
    fn evaluate(&mut self, _query: &EvaluativeQuery<'_>) -> Evaluation {
        self.0 += 1;
        [Evaluation::Good, Evaluation::NoFeedback, Evaluation::Bad][(self.0 % 3) as usize]
    }
}

/// What the run logged, to compare with what the file holds.
struct Logged {
    steps: u64,
    episodes_started: u64,
    answers: Vec<f64>,
    rewards: Vec<f64>,
}

/// Drive an EF-25 run of `steps` steps on `task`, recording everything into `rrd`, the way a
/// session does: the geometry at each episode start, the render state after each step, and
/// each query with its answer.
fn record_run(task: Task, steps: u64, rrd: &Path) -> Logged {
    let mut config = EvaluativeRunConfig::new(task, "ef-25".parse().unwrap(), 0);
    config.sac.hidden = vec![16, 16];
    config.sac.batch_size = 32;
    let options = RecordingOptions {
        path: Some(rrd.to_owned()),
        connect: None,
    };
    let recorder = Recorder::start("dualrep-test", task.id(), config.scene_graph, &options)
        .unwrap()
        .expect("a file was asked for");
    let mut run = EvaluativeRun::new(config, steps);
    let mut trainer = Cycling(0);
    recorder.episode_start(0, 0, &run.env().geometry());
    let mut logged = Logged {
        steps: 0,
        episodes_started: 1,
        answers: Vec::new(),
        rewards: Vec::new(),
    };
    let mut query_id = 0;
    while run.steps() < steps {
        let (step, episode) = (run.steps(), run.episodes());
        let report = run.step(&mut trainer);
        recorder.step(
            step,
            episode,
            &run.env().render(),
            report.reward,
            run.cumulative_return(),
            report.abstract_state,
        );
        logged.rewards.push(f64::from(report.reward));
        if let Some(answer) = report.evaluation {
            recorder.query(
                step,
                query_id,
                "evaluative",
                format!("g = {}", report.abstract_state),
            );
            let value = f64::from(answer.value());
            recorder.answer(step, query_id, value, format!("{answer:?}"));
            logged.answers.push(value);
            query_id += 1;
        }
        if report.episode.is_some() {
            recorder.episode_start(run.episodes(), run.steps(), &run.env().geometry());
            logged.episodes_started += 1;
        }
    }
    logged.steps = run.steps();
    recorder.finish().unwrap();
    logged
}

fn entity<'a>(file: &'a Value, path: &str) -> &'a Value {
    let e = &file["entities"][path];
    assert!(
        e.is_object(),
        "no entity {path} in {:?}",
        file["entities"].as_object().unwrap().keys()
    );
    e
}

fn rows(file: &Value, path: &str) -> u64 {
    entity(file, path)["rows"].as_u64().unwrap()
}

fn static_rows(file: &Value, path: &str) -> u64 {
    entity(file, path)["static_rows"].as_u64().unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Equal up to JSON's decimal round trip (serde_json parses floats to within an ulp).
fn assert_close(got: &[f64], want: &[f64], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= 1e-12 * w.abs().max(1.0),
            "{what}[{i}]: {g} != {w}"
        );
    }
}

/// One row per step, on both timelines, at steps `0..steps`.
fn assert_per_step(file: &Value, path: &str, steps: u64) {
    assert_eq!(rows(file, path), steps, "{path}: rows");
    let e = entity(file, path);
    assert_eq!(
        e["timelines"],
        serde_json::json!(["episode", "step"]),
        "{path}"
    );
    let step = &e["times"]["step"];
    assert_eq!(
        (
            step["min"].as_u64(),
            step["max"].as_u64(),
            step["distinct"].as_u64()
        ),
        (Some(0), Some(steps - 1), Some(steps)),
        "{path}: step times"
    );
}

fn check_task(task: Task, steps: u64) {
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("x.rrd");
    let logged = record_run(task, steps, &rrd);
    let file = rerun_py::read_rrd(&rrd);

    assert_eq!(file["rerun_version"], rerun_py::RERUN_VERSION);
    assert_eq!(
        file["recordings"],
        serde_json::json!([{"application_id": "dualrep-test", "recording_id": task.id()}])
    );
    assert_eq!(file["timelines"], serde_json::json!(["episode", "step"]));

    // The scene.
    let (per_step, geometry): (&[&str], &[&str]) = match task {
        Task::Reaching => (
            &["world/gripper"],
            &["world/table", "world/goal", "world/workspace"],
        ),
        Task::Placing => (
            &["world/gripper", "world/ball", "gripper/closed"],
            &[
                "world/table",
                "world/hoop",
                "world/hoop/opening",
                "world/workspace",
                "world/no_entry",
            ],
        ),
        Task::LunarLander => (
            &[
                "world/lander/hull",
                "world/lander/legs",
                "world/lander/flames",
                "engines/main",
                "engines/side",
            ],
            &["world/terrain", "world/flags"],
        ),
    };
    for path in per_step.iter().chain(&["reward", "cumulative_return"]) {
        assert_per_step(&file, path, logged.steps);
    }
    for path in geometry {
        if task == Task::LunarLander {
            // New terrain every episode, on the timelines.
            assert_eq!(rows(&file, path), logged.episodes_started, "{path}");
            assert_eq!(static_rows(&file, path), 0, "{path}");
        } else {
            // Fixed: logged once, static.
            assert_eq!(
                (static_rows(&file, path), rows(&file, path)),
                (1, 0),
                "{path}"
            );
        }
    }
    assert_close(
        &floats(&entity(&file, "reward")["scalars"]),
        &logged.rewards,
        "rewards in step order",
    );

    // The predicates: exactly the scene graph's names, each 0/1 at every step.
    let graph = SceneGraph::for_task(task);
    let recorded: BTreeSet<&str> = file["entities"]
        .as_object()
        .unwrap()
        .keys()
        .filter_map(|k| k.strip_prefix("predicates/"))
        .collect();
    let expected: BTreeSet<&str> = graph.predicates().iter().map(|p| p.name).collect();
    assert_eq!(recorded, expected);
    for p in graph.predicates() {
        let path = format!("predicates/{}", p.name);
        assert_per_step(&file, &path, logged.steps);
        assert!(
            floats(&entity(&file, &path)["scalars"])
                .iter()
                .all(|&v| v == 0.0 || v == 1.0),
            "{path} is 0/1"
        );
    }

    // Queries and answers.
    assert!(!logged.answers.is_empty(), "EF-25 asked nothing");
    let asked = logged.answers.len() as u64;
    assert_eq!(rows(&file, "queries"), asked);
    assert_eq!(rows(&file, "answers"), asked);
    assert_eq!(rows(&file, "answers/value"), asked);
    assert_close(
        &floats(&entity(&file, "answers/value")["scalars"]),
        &logged.answers,
        "answers in step order",
    );
    let texts = entity(&file, "queries")["texts"].as_array().unwrap();
    assert!(
        texts[0]
            .as_str()
            .unwrap()
            .starts_with("#0 evaluative: g = "),
        "{texts:?}"
    );
    // To look at the recordings: DUALREP_KEEP_RECORDINGS=DIR keeps a copy of each file there.
    if let Some(keep) = std::env::var_os("DUALREP_KEEP_RECORDINGS") {
        let keep = Path::new(&keep);
        std::fs::create_dir_all(keep).unwrap();
        std::fs::copy(&rrd, keep.join(format!("{task}.rrd"))).unwrap();
    }
    let size = std::fs::metadata(&rrd).unwrap().len();
    eprintln!(
        "{task}: {} steps, {} episodes, {asked} queries: {size} bytes",
        logged.steps, logged.episodes_started
    );
}

#[test]
fn reaching_is_recorded_and_read_back_by_python() {
    check_task(Task::Reaching, 300);
}

#[test]
fn placing_is_recorded_and_read_back_by_python() {
    check_task(Task::Placing, 300);
}

#[test]
fn lunar_lander_is_recorded_and_read_back_by_python() {
    // Long enough for an untrained lander to crash and start a second episode.
    check_task(Task::LunarLander, 400);
}

#[test]
fn off_when_neither_file_nor_viewer() {
    let recorder = Recorder::start(
        "dualrep-test",
        "off",
        SceneGraph::Reaching,
        &RecordingOptions::default(),
    )
    .unwrap();
    assert!(recorder.is_none());
}

#[test]
fn a_bad_viewer_url_is_an_error_before_any_file_is_made() {
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("x.rrd");
    let options = RecordingOptions {
        path: Some(rrd.clone()),
        connect: Some("http://127.0.0.1:9876".into()),
    };
    let err = Recorder::start("dualrep-test", "bad", SceneGraph::Reaching, &options)
        .err()
        .expect("not a proxy url");
    assert!(format!("{err:#}").contains("rerun+http"), "{err:#}");
    assert!(!rrd.exists());
}

#[test]
fn file_and_unreachable_viewer_tee_and_the_file_is_complete() {
    // Nothing listens on port 1: the gRPC sink never connects; the file sink must not care.
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("nested/x.rrd");
    let options = RecordingOptions {
        path: Some(rrd.clone()),
        connect: Some("rerun+http://127.0.0.1:1/proxy".into()),
    };
    let task = Task::Reaching;
    let recorder = Recorder::start("dualrep-test", "tee", SceneGraph::for_task(task), &options)
        .unwrap()
        .unwrap();
    let mut env = task.make_env();
    env.reset(0);
    recorder.episode_start(0, 0, &env.geometry());
    for step in 0..20 {
        // Away from the goal (the home pose is 15 steps from it), so the episode lasts.
        env.step(&[-1.0, 0.0]);
        recorder.step(
            step,
            0,
            &env.render(),
            0.0,
            0.0,
            dualrep::scene_graph::AbstractState(0),
        );
    }
    // The flush reports the viewer it could not reach (after the gRPC sink's 5 s connect
    // timeout); the file gets every row all the same.
    let err = recorder.finish().expect_err("the viewer was unreachable");
    assert!(format!("{err:#}").contains("unable to connect"), "{err:#}");
    let file = rerun_py::read_rrd(&rrd);
    assert_per_step(&file, "world/gripper", 20);
}

/// A 2 x 1 PNG (a red and a green pixel), as `dualrep.env` encodes frames.
const PNG_2X1: [u8; 72] = [
    137, 80, 78, 71, 13, 10, 26, 10, 0, 0, 0, 13, 73, 72, 68, 82, 0, 0, 0, 2, 0, 0, 0, 1, 8, 2, 0,
    0, 0, 123, 64, 232, 221, 0, 0, 0, 15, 73, 68, 65, 84, 120, 94, 99, 248, 207, 192, 192, 240,
    159, 1, 0, 7, 255, 1, 255, 34, 219, 85, 25, 0, 0, 0, 0, 73, 69, 78, 68, 174, 66, 96, 130,
];

#[test]
fn a_remote_envs_own_frames_are_recorded_as_images_with_its_predicates() {
    use dualrep::scene_graph::declared::{DeclaredPredicate, declare};
    use dualrep::sim::{Geometry, ImageFrame, MediaType, RenderState};

    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("remote.rrd");
    let graph = SceneGraph::Declared(
        declare(&[DeclaredPredicate {
            name: "upright".into(),
            label: "pendulum upright".into(),
        }])
        .unwrap(),
    );
    let options = RecordingOptions {
        path: Some(rrd.clone()),
        connect: None,
    };
    let recorder = Recorder::start("dualrep-test", "remote", graph, &options)
        .unwrap()
        .unwrap();
    let geometry = Geometry::Remote {
        env: "Pendulum-v1".into(),
        frame_size: Some([2, 1]),
    };
    recorder.episode_start(0, 0, &geometry);
    let frame = ImageFrame {
        media_type: MediaType::Png,
        width: 2,
        height: 1,
        data: std::sync::Arc::from(&PNG_2X1[..]),
    };
    for step in 0..12u64 {
        // Frames come only while people watch: here on the first ten steps.
        let state = RenderState::Remote {
            frame: (step < 10).then(|| frame.clone()),
            observation: vec![step as f32, 0.0, 0.0],
        };
        let g = dualrep::scene_graph::AbstractState(u32::from(step % 2 == 0));
        recorder.step(step, 0, &state, -1.0, 0.0, g);
    }
    recorder.finish().unwrap();
    let file = rerun_py::read_rrd(&rrd);
    assert_eq!(rows(&file, "world/frame"), 10);
    let components = entity(&file, "world/frame")["components"].to_string();
    assert!(components.contains("EncodedImage:blob"), "{components}");
    assert!(
        components.contains("EncodedImage:media_type"),
        "{components}"
    );
    assert_per_step(&file, "predicates/upright", 12);
    assert_eq!(
        floats(&entity(&file, "predicates/upright")["scalars"]),
        (0..12)
            .map(|s| f64::from(u8::from(s % 2 == 0)))
            .collect::<Vec<_>>()
    );
    assert!(
        !file["entities"].as_object().unwrap().contains_key("world"),
        "no 3D axes for a remote env's frames"
    );
}
