//! A session's labelled data as Parquet (Apache Arrow's columnar file, read by pandas, polars,
//! pyarrow, DuckDB, Spark): one row per answered query, the rows of `GET .../answers`.
//!
//! - Evaluative sessions, **transitions**: `query_id`, `step`, `abstract_state`,
//!   `observation`, `action` (normalised to [-1, 1]), `reward` (the env's), `next_observation`,
//!   `label` (H, the answer the learner took: +1 / 0 / -1, or several trainers' mean), `who`,
//!   `trainer`, `latency_ms`, and each named trainer's own answer (`trainer_names`,
//!   `trainer_labels`) where several answered.
//! - Preference sessions, **pairs**: `query_id`, per side (`left_`, `right_`) `trajectory`,
//!   `start`, `end`, `abstract_state`, `features` (standardised, as the belief saw them),
//!   `raw_features`; `choice` (`left`, `right`, `equal`, `skip`, or several trainers' tally as
//!   JSON), `who`, `trainer`, `latency_ms`, `trainer_names`, `trainer_choices`.
//!
//! Queries stored before what the learner saw was kept have nulls there. Pure: returns bytes.

use std::sync::Arc;

use arrow_array::builder::{
    Float32Builder, Float64Builder, Int64Builder, ListBuilder, StringBuilder,
};
use arrow_array::{ArrayRef, RecordBatch};
use parquet::arrow::ArrowWriter;

use crate::session::{AnswerValue, QueryData, SegmentData};
use crate::store::{DatasetRow, PersonAnswer, TrainerRow};

/// Why a table could not be written.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    #[error("building the table: {0}")]
    Arrow(#[from] arrow_schema::ArrowError),
    #[error("writing Parquet: {0}")]
    Parquet(#[from] parquet::errors::ParquetError),
}

/// Each named trainer's own answers to one query, by name.
fn own_answers<'a>(
    query_id: i64,
    people: &'a [PersonAnswer],
    trainers: &'a [TrainerRow],
) -> impl Iterator<Item = (&'a str, AnswerValue)> + 'a {
    people
        .iter()
        .filter(move |p| p.query_id == query_id)
        .filter_map(move |p| {
            let t = trainers.iter().find(|t| Some(t.id) == p.trainer_id)?;
            Some((t.name.as_str(), p.value))
        })
}

/// An answer as a choice word: `"left"`, or a tally's JSON.
fn choice(v: AnswerValue) -> String {
    serde_json::to_string(&v)
        .unwrap_or_default()
        .trim_matches('"')
        .to_string()
}

/// H as the learner took it (`None` for a value that is not an evaluation).
fn label(v: AnswerValue) -> Option<f32> {
    v.as_evaluation().map(|e| e.value())
}

fn floats32(values: Option<&[f32]>, b: &mut ListBuilder<Float32Builder>) {
    match values {
        Some(v) => {
            b.values().append_slice(v);
            b.append(true);
        }
        None => b.append(false),
    }
}

fn floats64(values: Option<&[f64]>, b: &mut ListBuilder<Float64Builder>) {
    match values {
        Some(v) => {
            b.values().append_slice(v);
            b.append(true);
        }
        None => b.append(false),
    }
}

/// The columns every table shares: who answered and how fast, and each trainer's own answer.
struct Common {
    who: StringBuilder,
    trainer: StringBuilder,
    latency: Int64Builder,
    names: ListBuilder<StringBuilder>,
}

impl Common {
    fn new() -> Self {
        Self {
            who: StringBuilder::new(),
            trainer: StringBuilder::new(),
            latency: Int64Builder::new(),
            names: ListBuilder::new(StringBuilder::new()),
        }
    }

    fn push(&mut self, r: &DatasetRow, own: &[(&str, AnswerValue)]) {
        self.who.append_value(r.who.as_str());
        self.trainer.append_option(r.trainer.as_deref());
        self.latency.append_value(r.latency_ms);
        for (name, _) in own {
            self.names.values().append_value(name);
        }
        self.names.append(true);
    }
}

/// One record batch of `columns` (name, values, nullable) as a Parquet file.
pub(crate) fn write(columns: Vec<(&str, ArrayRef, bool)>) -> Result<Vec<u8>, TableError> {
    let batch = RecordBatch::try_from_iter_with_nullable(columns)?;
    let mut bytes = Vec::new();
    let mut writer = ArrowWriter::try_new(&mut bytes, batch.schema(), None)?;
    writer.write(&batch)?;
    writer.close()?;
    Ok(bytes)
}

/// An evaluative session's labelled transitions as Parquet.
pub fn transitions(
    rows: &[DatasetRow],
    people: &[PersonAnswer],
    trainers: &[TrainerRow],
) -> Result<Vec<u8>, TableError> {
    let mut query_id = Int64Builder::new();
    let mut step = Int64Builder::new();
    let mut state = Int64Builder::new();
    let mut obs = ListBuilder::new(Float32Builder::new());
    let mut action = ListBuilder::new(Float32Builder::new());
    let mut reward = Float32Builder::new();
    let mut next_obs = ListBuilder::new(Float32Builder::new());
    let mut h = Float32Builder::new();
    let mut labels = ListBuilder::new(Float32Builder::new());
    let mut common = Common::new();
    for r in rows {
        query_id.append_value(r.query_id);
        step.append_value(r.step);
        state.append_value(r.abstract_state);
        let t = match &r.data {
            Some(QueryData::Evaluative {
                observation,
                action,
                reward,
                next_observation,
            }) => Some((observation, action, *reward, next_observation)),
            _ => None,
        };
        floats32(t.map(|t| t.0.as_slice()), &mut obs);
        floats32(t.map(|t| t.1.as_slice()), &mut action);
        reward.append_option(t.map(|t| t.2));
        floats32(t.map(|t| t.3.as_slice()), &mut next_obs);
        h.append_option(label(r.value));
        let own: Vec<(&str, AnswerValue)> = own_answers(r.query_id, people, trainers).collect();
        for (_, v) in &own {
            labels.values().append_option(label(*v));
        }
        labels.append(true);
        common.push(r, &own);
    }
    let a = |x: ArrayRef| x;
    write(vec![
        ("query_id", a(Arc::new(query_id.finish())), false),
        ("step", a(Arc::new(step.finish())), false),
        ("abstract_state", a(Arc::new(state.finish())), false),
        ("observation", a(Arc::new(obs.finish())), true),
        ("action", a(Arc::new(action.finish())), true),
        ("reward", a(Arc::new(reward.finish())), true),
        ("next_observation", a(Arc::new(next_obs.finish())), true),
        ("label", a(Arc::new(h.finish())), true),
        ("who", a(Arc::new(common.who.finish())), false),
        ("trainer", a(Arc::new(common.trainer.finish())), true),
        ("latency_ms", a(Arc::new(common.latency.finish())), false),
        ("trainer_names", a(Arc::new(common.names.finish())), false),
        ("trainer_labels", a(Arc::new(labels.finish())), false),
    ])
}

/// One side's columns of the pairs table.
struct Side {
    trajectory: Int64Builder,
    start: Int64Builder,
    end: Int64Builder,
    state: Int64Builder,
    features: ListBuilder<Float64Builder>,
    raw: ListBuilder<Float64Builder>,
}

impl Side {
    fn new() -> Self {
        Self {
            trajectory: Int64Builder::new(),
            start: Int64Builder::new(),
            end: Int64Builder::new(),
            state: Int64Builder::new(),
            features: ListBuilder::new(Float64Builder::new()),
            raw: ListBuilder::new(Float64Builder::new()),
        }
    }

    fn push(&mut self, s: Option<&SegmentData>) {
        self.trajectory
            .append_option(s.map(|s| s.trajectory as i64));
        self.start.append_option(s.map(|s| s.start as i64));
        self.end.append_option(s.map(|s| s.end as i64));
        self.state
            .append_option(s.and_then(|s| s.abstract_state).map(i64::from));
        floats64(s.map(|s| s.features.as_slice()), &mut self.features);
        floats64(s.map(|s| s.raw_features.as_slice()), &mut self.raw);
    }

    fn columns(mut self, prefix: &str) -> Vec<(String, ArrayRef)> {
        vec![
            (
                format!("{prefix}_trajectory"),
                Arc::new(self.trajectory.finish()) as ArrayRef,
            ),
            (format!("{prefix}_start"), Arc::new(self.start.finish())),
            (format!("{prefix}_end"), Arc::new(self.end.finish())),
            (
                format!("{prefix}_abstract_state"),
                Arc::new(self.state.finish()),
            ),
            (
                format!("{prefix}_features"),
                Arc::new(self.features.finish()),
            ),
            (
                format!("{prefix}_raw_features"),
                Arc::new(self.raw.finish()),
            ),
        ]
    }
}

/// A preference session's pairs and choices as Parquet.
pub fn pairs(
    rows: &[DatasetRow],
    people: &[PersonAnswer],
    trainers: &[TrainerRow],
) -> Result<Vec<u8>, TableError> {
    let mut query_id = Int64Builder::new();
    let (mut left, mut right) = (Side::new(), Side::new());
    let mut chosen = StringBuilder::new();
    let mut choices = ListBuilder::new(StringBuilder::new());
    let mut common = Common::new();
    for r in rows {
        query_id.append_value(r.query_id);
        let (l, rr) = match &r.data {
            Some(QueryData::Preference { left, right }) => (Some(left), Some(right)),
            _ => (None, None),
        };
        left.push(l);
        right.push(rr);
        chosen.append_value(choice(r.value));
        let own: Vec<(&str, AnswerValue)> = own_answers(r.query_id, people, trainers).collect();
        for (_, v) in &own {
            choices.values().append_value(choice(*v));
        }
        choices.append(true);
        common.push(r, &own);
    }
    let mut columns: Vec<(String, ArrayRef, bool)> =
        vec![("query_id".into(), Arc::new(query_id.finish()), false)];
    for (name, array) in left
        .columns("left")
        .into_iter()
        .chain(right.columns("right"))
    {
        columns.push((name, array, true));
    }
    columns.extend([
        (
            "choice".to_string(),
            Arc::new(chosen.finish()) as ArrayRef,
            false,
        ),
        ("who".into(), Arc::new(common.who.finish()), false),
        ("trainer".into(), Arc::new(common.trainer.finish()), true),
        (
            "latency_ms".into(),
            Arc::new(common.latency.finish()),
            false,
        ),
        (
            "trainer_names".into(),
            Arc::new(common.names.finish()),
            false,
        ),
        ("trainer_choices".into(), Arc::new(choices.finish()), false),
    ]);
    write(
        columns
            .iter()
            .map(|(n, a, nullable)| (n.as_str(), a.clone(), *nullable))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::Answerer;
    use parquet::file::reader::{FileReader, SerializedFileReader};

    fn row(q: i64, data: Option<QueryData>, value: AnswerValue) -> DatasetRow {
        DatasetRow {
            query_id: q,
            step: q * 10,
            abstract_state: 3,
            data,
            value,
            who: Answerer::Synthetic,
            trainer: None,
            latency_ms: 0,
        }
    }

    fn rows_of(bytes: Vec<u8>) -> (i64, Vec<String>) {
        use std::io::{Seek, Write};
        let mut file = tempfile::tempfile().unwrap();
        file.write_all(&bytes).unwrap();
        file.rewind().unwrap();
        let reader = SerializedFileReader::new(file).unwrap();
        let meta = reader.metadata();
        let names = meta
            .file_metadata()
            .schema_descr()
            .root_schema()
            .get_fields()
            .iter()
            .map(|f| f.name().to_string())
            .collect();
        (meta.file_metadata().num_rows(), names)
    }

    #[test]
    fn transitions_have_a_row_per_answer_and_nulls_where_nothing_was_kept() {
        let t = QueryData::Evaluative {
            observation: vec![0.1, 0.2],
            action: vec![0.5],
            reward: 1.0,
            next_observation: vec![0.3, 0.4],
        };
        let rows = [
            row(0, Some(t), AnswerValue::Evaluation(1)),
            row(1, None, AnswerValue::Evaluation(-1)),
        ];
        let (n, names) = rows_of(transitions(&rows, &[], &[]).unwrap());
        assert_eq!(n, 2);
        for c in [
            "observation",
            "action",
            "reward",
            "next_observation",
            "label",
            "who",
        ] {
            assert!(names.iter().any(|x| x == c), "{c} in {names:?}");
        }
    }

    #[test]
    fn pairs_have_both_sides_and_the_choice() {
        let side = |t| SegmentData {
            trajectory: t,
            start: 0,
            end: 4,
            abstract_state: Some(2),
            features: vec![0.5, -0.5],
            raw_features: vec![1.0, 2.0],
        };
        let rows = [row(
            0,
            Some(QueryData::Preference {
                left: side(0),
                right: side(1),
            }),
            AnswerValue::Preference(crate::guidance::drpl::trainer::Preference::Left),
        )];
        let (n, names) = rows_of(pairs(&rows, &[], &[]).unwrap());
        assert_eq!(n, 1);
        for c in [
            "left_features",
            "right_abstract_state",
            "choice",
            "trainer_choices",
        ] {
            assert!(names.iter().any(|x| x == c), "{c} in {names:?}");
        }
    }
}
