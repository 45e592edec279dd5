//! A session's recording: the Rerun recorder (module `record`) as the session's `Observer`.

use crate::record::{Recorder, RecordingOptions};
use crate::scene_graph::{AbstractState, SceneGraph};
use crate::session::{AnswerValue, Observer, QueryKind};
use crate::sim::{Geometry, RenderState};

/// The session's recorder as its observer (`None` when recording is off and no viewer is set).
pub fn start(
    session_id: &str,
    graph: SceneGraph,
    options: &RecordingOptions,
) -> anyhow::Result<Option<Box<dyn Observer>>> {
    if let Some(dir) = options.path.as_ref().and_then(|p| p.parent()) {
        std::fs::create_dir_all(dir)?;
    }
    let recorder = Recorder::start("dualrep", session_id, graph, options)?;
    Ok(recorder.map(|r| Box::new(Recording(r)) as Box<dyn Observer>))
}

/// Hands every step, query and answer to the recorder's logging thread; queries are numbered by
/// their order in the session (`seq`), which the API's answers carry too.
pub struct Recording(pub Recorder);

impl Observer for Recording {
    fn episode_start(&mut self, episode: u64, step: u64, geometry: &Geometry) {
        self.0.episode_start(episode, step, geometry);
    }

    fn step(
        &mut self,
        step: u64,
        episode: u64,
        state: &RenderState,
        reward: f32,
        cumulative_return: f64,
        abstract_state: AbstractState,
    ) {
        self.0.step(
            step,
            episode,
            state,
            reward,
            cumulative_return,
            abstract_state,
        );
    }

    fn query(&mut self, step: u64, seq: u64, kind: QueryKind, text: String) {
        self.0.query(step, seq as i64, kind.as_str(), text);
    }

    fn answer(&mut self, step: u64, seq: u64, value: AnswerValue) {
        let text = format!(
            "query {seq}: {}",
            serde_json::to_string(&value).unwrap_or_default()
        );
        self.0.answer(step, seq as i64, value.as_number(), text);
    }

    fn revision(&mut self, progress: u64, seq: u64, value: Option<AnswerValue>) {
        let text = match value {
            None => format!("query {seq}: undone"),
            Some(v) => format!(
                "query {seq}: answered again, {}",
                serde_json::to_string(&v).unwrap_or_default()
            ),
        };
        let number = value.map_or(0.0, AnswerValue::as_number);
        self.0.answer(progress, seq as i64, number, text);
    }
}
