//! `GET /api/sessions/{id}/export?format=csv`: a session's answers as CSV, one row per answer
//! with the trainer who gave it. Pure: the caller reads the rows.

use crate::store::AnswerRow;

/// The columns, in order.
const HEADER: [&str; 11] = [
    "query_id",
    "kind",
    "step",
    "abstract_state",
    "value",
    "who",
    "trainer",
    "asked_at",
    "answered_at",
    "latency_ms",
    "revision",
];

/// The CSV text of `answers`, a header line first.
pub fn answers_csv(answers: &[AnswerRow]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(HEADER)?;
    for a in answers {
        // An answer's value as its JSON, unquoted: `1`, `-1`, `left`, a mean's fraction.
        let value = serde_json::to_string(&a.value).unwrap_or_default();
        w.write_record([
            a.query_id.to_string(),
            a.kind.as_str().to_string(),
            a.step.to_string(),
            a.abstract_state.to_string(),
            value.trim_matches('"').to_string(),
            a.who.as_str().to_string(),
            a.trainer.clone().unwrap_or_default(),
            a.asked_at.clone(),
            a.answered_at.clone(),
            a.latency_ms.to_string(),
            a.revision.to_string(),
        ])?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_answers_is_the_header_alone() {
        assert_eq!(
            answers_csv(&[]).unwrap(),
            "query_id,kind,step,abstract_state,value,who,trainer,asked_at,answered_at,latency_ms,revision\n"
        );
    }
}
