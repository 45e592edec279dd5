//! A study's tidy table: one row per participant × condition, for R or pandas, as CSV and as
//! Parquet with the same columns: `participant_id`, `participant` (0-based, in the order they
//! came), `condition`, `position` (0-based place in their order), `session_id`, `status`,
//! `ended_early`, `progress` (steps or queries done), `cumulative_reward`, `feedback_pct`,
//! `seconds` (T), `no_feedback` (NFC), then one column per survey question (`survey_<id>`,
//! empty or null until answered). Pure: returns text or bytes.

use std::sync::Arc;

use arrow_array::{ArrayRef, BooleanArray, Float64Array, Int64Array, StringArray};

use super::tables::{TableError, write};
use crate::study::StudySpec;
use crate::study::results::ParticipantRun;

/// The fixed columns, before the survey's.
pub const COLUMNS: [&str; 12] = [
    "participant_id",
    "participant",
    "condition",
    "position",
    "session_id",
    "status",
    "ended_early",
    "progress",
    "cumulative_reward",
    "feedback_pct",
    "seconds",
    "no_feedback",
];

fn survey_columns(spec: &StudySpec) -> Vec<String> {
    spec.survey
        .iter()
        .map(|q| format!("survey_{}", q.id))
        .collect()
}

/// A CSV field, quoted when it has to be.
fn field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// The table as CSV (header first; rows in participant, then position, order).
pub fn csv(spec: &StudySpec, runs: &[ParticipantRun]) -> String {
    let mut header: Vec<String> = COLUMNS.iter().map(|c| c.to_string()).collect();
    header.extend(survey_columns(spec));
    let mut out = header.join(",");
    out.push('\n');
    for r in runs {
        let mut cells = vec![
            field(&r.participant_id),
            r.participant.to_string(),
            field(&r.condition),
            r.position.to_string(),
            field(&r.session_id),
            field(&r.status),
            r.ended_early.to_string(),
            r.progress.to_string(),
            r.cumulative_reward.to_string(),
            r.feedback_pct.to_string(),
            r.seconds.map_or(String::new(), |s| s.to_string()),
            r.no_feedback.to_string(),
        ];
        for q in &spec.survey {
            cells.push(r.survey.get(&q.id).map_or(String::new(), |v| v.to_string()));
        }
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// The table as Parquet.
pub fn parquet(spec: &StudySpec, runs: &[ParticipantRun]) -> Result<Vec<u8>, TableError> {
    let strings = |f: &dyn Fn(&ParticipantRun) -> &str| -> ArrayRef {
        Arc::new(StringArray::from_iter_values(runs.iter().map(f)))
    };
    let ints = |f: &dyn Fn(&ParticipantRun) -> i64| -> ArrayRef {
        Arc::new(Int64Array::from_iter_values(runs.iter().map(f)))
    };
    let floats = |f: &dyn Fn(&ParticipantRun) -> f64| -> ArrayRef {
        Arc::new(Float64Array::from_iter_values(runs.iter().map(f)))
    };
    let mut columns: Vec<(String, ArrayRef, bool)> = vec![
        (COLUMNS[0].into(), strings(&|r| &r.participant_id), false),
        (COLUMNS[1].into(), ints(&|r| r.participant as i64), false),
        (COLUMNS[2].into(), strings(&|r| &r.condition), false),
        (COLUMNS[3].into(), ints(&|r| r.position as i64), false),
        (COLUMNS[4].into(), strings(&|r| &r.session_id), false),
        (COLUMNS[5].into(), strings(&|r| &r.status), false),
        (
            COLUMNS[6].into(),
            Arc::new(BooleanArray::from(
                runs.iter().map(|r| r.ended_early).collect::<Vec<_>>(),
            )),
            false,
        ),
        (COLUMNS[7].into(), ints(&|r| r.progress), false),
        (COLUMNS[8].into(), floats(&|r| r.cumulative_reward), false),
        (COLUMNS[9].into(), floats(&|r| r.feedback_pct), false),
        (
            COLUMNS[10].into(),
            Arc::new(Float64Array::from(
                runs.iter().map(|r| r.seconds).collect::<Vec<_>>(),
            )),
            true,
        ),
        (COLUMNS[11].into(), ints(&|r| r.no_feedback), false),
    ];
    for (q, name) in spec.survey.iter().zip(survey_columns(spec)) {
        let values: Vec<Option<i64>> = runs.iter().map(|r| r.survey.get(&q.id).copied()).collect();
        columns.push((name, Arc::new(Int64Array::from(values)), true));
    }
    write(
        columns
            .iter()
            .map(|(n, a, null)| (n.as_str(), a.clone(), *null))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn csv_has_a_row_per_run_and_a_column_per_question() {
        let spec: StudySpec = serde_json::from_value(json!({
            "title": "t",
            "conditions": [
                {"name": "a, quoted", "task": "reaching", "method": "dref"},
                {"name": "sac", "task": "reaching", "method": "sac"}
            ]
        }))
        .unwrap();
        let run = ParticipantRun {
            participant_id: "p1".into(),
            participant: 0,
            condition: "a, quoted".into(),
            position: 1,
            session_id: "s".into(),
            status: "finished".into(),
            ended_early: false,
            progress: 100,
            cumulative_reward: 12.5,
            feedback_pct: 4.0,
            seconds: None,
            no_feedback: 3,
            curve: vec![],
            survey: [("E".to_string(), 4)].into(),
        };
        let text = csv(&spec, std::slice::from_ref(&run));
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 2);
        assert!(lines[0].ends_with("no_feedback,survey_E,survey_I,survey_C"));
        assert_eq!(
            lines[1],
            "p1,0,\"a, quoted\",1,s,finished,false,100,12.5,4,,3,4,,"
        );
        let bytes = parquet(&spec, &[run]).unwrap();
        assert_eq!(&bytes[..4], b"PAR1");
    }
}
