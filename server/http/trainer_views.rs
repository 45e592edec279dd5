//! A session broken down per trainer, and how much its trainers agree, as the API, the review
//! page and the exports show them. Pure: built from the store's rows.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::guidance::agreement::{Metric, fleiss_kappa, krippendorff_alpha};
use crate::guidance::drpl::trainer::Preference;
use crate::session::{AnswerValue, QueryKind};
use crate::store::{PersonAnswer, Survey, TrainerOrigin, TrainerRow};

/// One trainer's share of a session.
#[derive(Clone, Debug, PartialEq, Serialize, utoipa::ToSchema)]
pub struct TrainerStats {
    /// `null`: the anonymous trainer (answers on the shared link without a name, or stored
    /// before names existed).
    pub id: Option<i64>,
    pub name: Option<String>,
    pub origin: Option<TrainerOrigin>,
    /// Their own link (named trainers).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trainer_url: Option<String>,
    pub answers: usize,
    /// Their "no feedback" answers and skips (the paper's NFC; timeouts are nobody's).
    pub no_feedback: usize,
    /// Seconds from the first query they answered being asked to their last answer (T).
    pub trainer_seconds: Option<f64>,
    pub latency_ms_median: Option<f64>,
    pub latency_ms_mean: Option<f64>,
    pub survey: Option<Survey>,
}

/// Every trainer of a session: the named ones in the order they came, then the anonymous one
/// if it answered.
pub fn trainer_stats(
    session_id: &str,
    trainers: &[TrainerRow],
    answers: &[PersonAnswer],
    surveys: &[(i64, Survey)],
    anonymous_survey: Option<Survey>,
) -> Vec<TrainerStats> {
    let of = |id: Option<i64>| answers.iter().filter(move |a| a.trainer_id == id);
    let stats = |id: Option<i64>| {
        let mine: Vec<&PersonAnswer> = of(id).collect();
        let mut latencies: Vec<f64> = mine.iter().map(|a| a.latency_ms as f64).collect();
        latencies.sort_by(f64::total_cmp);
        let median = match latencies.len() {
            0 => None,
            n if n % 2 == 1 => Some(latencies[n / 2]),
            n => Some((latencies[n / 2 - 1] + latencies[n / 2]) / 2.0),
        };
        let mean =
            (!latencies.is_empty()).then(|| latencies.iter().sum::<f64>() / latencies.len() as f64);
        let first = mine.iter().map(|a| a.asked_s).fold(f64::INFINITY, f64::min);
        let last = mine
            .iter()
            .map(|a| a.answered_s)
            .fold(f64::NEG_INFINITY, f64::max);
        (
            mine.len(),
            mine.iter().filter(|a| a.value.is_no_feedback()).count(),
            (!mine.is_empty()).then_some(last - first),
            median,
            mean,
        )
    };
    let mut out: Vec<TrainerStats> = trainers
        .iter()
        .map(|t| {
            let (answers, no_feedback, trainer_seconds, median, mean) = stats(Some(t.id));
            TrainerStats {
                id: Some(t.id),
                name: Some(t.name.clone()),
                origin: Some(t.origin),
                trainer_url: Some(personal_url(session_id, &t.token)),
                answers,
                no_feedback,
                trainer_seconds,
                latency_ms_median: median,
                latency_ms_mean: mean,
                survey: surveys.iter().find(|(id, _)| *id == t.id).map(|(_, s)| *s),
            }
        })
        .collect();
    let (answers, no_feedback, trainer_seconds, median, mean) = stats(None);
    if answers > 0 || anonymous_survey.is_some() {
        out.push(TrainerStats {
            id: None,
            name: None,
            origin: None,
            trainer_url: None,
            answers,
            no_feedback,
            trainer_seconds,
            latency_ms_median: median,
            latency_ms_mean: mean,
            survey: anonymous_survey,
        });
    }
    out
}

/// A named trainer's own link.
pub fn personal_url(session_id: &str, token: &str) -> String {
    format!("/train/{session_id}?token={token}")
}

/// Agreement between two trainers.
#[derive(Clone, Debug, PartialEq, Serialize, utoipa::ToSchema)]
pub struct PairAgreement {
    pub a: i64,
    pub b: i64,
    pub a_name: String,
    pub b_name: String,
    pub value: Option<f64>,
    /// Queries both answered.
    pub units: usize,
}

/// How much a session's named trainers agree.
#[derive(Clone, Debug, PartialEq, Serialize, utoipa::ToSchema)]
pub struct AgreementView {
    /// `krippendorff_alpha_ordinal` (evaluative answers) or `fleiss_kappa` (preferences).
    pub measure: &'static str,
    /// `null` when undefined: no query with two answers, or no variation at all.
    pub value: Option<f64>,
    /// Queries with at least two trainers' answers.
    pub units: usize,
    pub trainers: usize,
    pub pairs: Vec<PairAgreement>,
}

/// An answer as a rating: evaluative answers on their ordinal scale, preferences as their
/// choice (skips and combined values are not ratings).
enum Rating {
    Ordinal(f64),
    Choice(&'static str),
}

fn rating(v: AnswerValue) -> Option<Rating> {
    match v {
        AnswerValue::Evaluation(x) => Some(Rating::Ordinal(f64::from(x))),
        AnswerValue::Preference(Preference::Left) => Some(Rating::Choice("left")),
        AnswerValue::Preference(Preference::Right) => Some(Rating::Choice("right")),
        AnswerValue::Preference(Preference::Equal) => Some(Rating::Choice("equal")),
        _ => None,
    }
}

/// The agreement of the named trainers' answers, per session and per pair of trainers.
pub fn agreement(
    kind: QueryKind,
    trainers: &[TrainerRow],
    answers: &[PersonAnswer],
) -> AgreementView {
    // Query -> (trainer -> rating).
    let mut by_query: BTreeMap<i64, BTreeMap<i64, Rating>> = BTreeMap::new();
    for a in answers {
        if let (Some(t), Some(r)) = (a.trainer_id, rating(a.value)) {
            by_query.entry(a.query_id).or_default().insert(t, r);
        }
    }
    let measure = |units: Vec<Vec<&Rating>>| -> Option<f64> {
        match kind {
            QueryKind::Evaluative => {
                let units: Vec<Vec<f64>> = units
                    .iter()
                    .map(|u| {
                        u.iter()
                            .filter_map(|r| match r {
                                Rating::Ordinal(x) => Some(*x),
                                Rating::Choice(_) => None,
                            })
                            .collect()
                    })
                    .collect();
                krippendorff_alpha(&units, Metric::Ordinal)
            }
            QueryKind::Preference => {
                let units: Vec<Vec<&str>> = units
                    .iter()
                    .map(|u| {
                        u.iter()
                            .filter_map(|r| match r {
                                Rating::Choice(c) => Some(*c),
                                Rating::Ordinal(_) => None,
                            })
                            .collect()
                    })
                    .collect();
                fleiss_kappa(&units)
            }
        }
    };
    let all: Vec<Vec<&Rating>> = by_query.values().map(|m| m.values().collect()).collect();
    let units = all.iter().filter(|u| u.len() >= 2).count();
    let mut pairs = Vec::new();
    for (i, a) in trainers.iter().enumerate() {
        for b in &trainers[i + 1..] {
            let both: Vec<Vec<&Rating>> = by_query
                .values()
                .filter_map(|m| Some(vec![m.get(&a.id)?, m.get(&b.id)?]))
                .collect();
            if both.is_empty() {
                continue;
            }
            pairs.push(PairAgreement {
                a: a.id,
                b: b.id,
                a_name: a.name.clone(),
                b_name: b.name.clone(),
                units: both.len(),
                value: measure(both),
            });
        }
    }
    AgreementView {
        measure: match kind {
            QueryKind::Evaluative => "krippendorff_alpha_ordinal",
            QueryKind::Preference => "fleiss_kappa",
        },
        value: measure(all),
        units,
        trainers: trainers.len(),
        pairs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trainer(id: i64, name: &str) -> TrainerRow {
        TrainerRow {
            id,
            session_id: "s".into(),
            name: name.into(),
            token: format!("tok{id}"),
            origin: TrainerOrigin::Invited,
            created_at: String::new(),
        }
    }

    fn answer(query: i64, trainer: Option<i64>, v: i8, latency: i64, at: f64) -> PersonAnswer {
        PersonAnswer {
            query_id: query,
            trainer_id: trainer,
            value: AnswerValue::Evaluation(v),
            latency_ms: latency,
            asked_s: at,
            answered_s: at + latency as f64 / 1000.0,
        }
    }

    #[test]
    fn each_trainer_gets_their_answers_time_nfc_and_latency() {
        let trainers = [trainer(1, "ada"), trainer(2, "bo")];
        let answers = [
            answer(0, Some(1), 1, 1000, 10.0),
            answer(0, Some(2), 0, 3000, 10.0),
            answer(1, Some(1), -1, 2000, 20.0),
            answer(2, None, 0, 500, 30.0),
        ];
        let survey = Survey {
            overall_experience: 4,
            perceived_intelligence: 3,
            cognitive_ease: 5,
        };
        let stats = trainer_stats("s", &trainers, &answers, &[(2, survey)], None);
        assert_eq!(stats.len(), 3, "two named, one anonymous");
        let ada = &stats[0];
        assert_eq!((ada.answers, ada.no_feedback), (2, 0));
        assert_eq!(ada.trainer_seconds, Some(12.0));
        assert_eq!(
            (ada.latency_ms_median, ada.latency_ms_mean),
            (Some(1500.0), Some(1500.0))
        );
        assert_eq!(ada.trainer_url.as_deref(), Some("/train/s?token=tok1"));
        let bo = &stats[1];
        assert_eq!(
            (bo.answers, bo.no_feedback, bo.survey),
            (1, 1, Some(survey))
        );
        assert_eq!((stats[2].name.clone(), stats[2].answers), (None, 1));
    }

    #[test]
    fn agreement_per_session_and_per_pair() {
        let trainers = [trainer(1, "ada"), trainer(2, "bo"), trainer(3, "cy")];
        let answers = [
            answer(0, Some(1), 1, 0, 0.0),
            answer(0, Some(2), 1, 0, 0.0),
            answer(1, Some(1), -1, 0, 0.0),
            answer(1, Some(2), -1, 0, 0.0),
            answer(2, Some(1), 1, 0, 0.0),
            answer(2, Some(2), 0, 0, 0.0),
            answer(3, Some(3), 1, 0, 0.0),
        ];
        let view = agreement(QueryKind::Evaluative, &trainers, &answers);
        assert_eq!(view.measure, "krippendorff_alpha_ordinal");
        assert_eq!(view.units, 3);
        let units = [vec![1.0, 1.0], vec![-1.0, -1.0], vec![1.0, 0.0]];
        assert_eq!(view.value, krippendorff_alpha(&units, Metric::Ordinal));
        // The `krippendorff` package (PyPI) on the same two coders: 7/9.
        assert!(
            (view.value.unwrap() - 7.0 / 9.0).abs() < 1e-12,
            "{:?}",
            view.value
        );
        // Only ada and bo answered the same queries.
        assert_eq!(view.pairs.len(), 1);
        assert_eq!(
            (view.pairs[0].a_name.as_str(), view.pairs[0].units),
            ("ada", 3)
        );
        assert_eq!(view.pairs[0].value, view.value);
    }

    #[test]
    fn preference_agreement_is_fleiss_kappa_over_choices() {
        let trainers = [trainer(1, "ada"), trainer(2, "bo")];
        let p = |q, t, v| PersonAnswer {
            query_id: q,
            trainer_id: Some(t),
            value: AnswerValue::Preference(v),
            latency_ms: 0,
            asked_s: 0.0,
            answered_s: 0.0,
        };
        let answers = [
            p(0, 1, Preference::Left),
            p(0, 2, Preference::Left),
            p(1, 1, Preference::Right),
            p(1, 2, Preference::Left),
            p(2, 1, Preference::Skip),
            p(2, 2, Preference::Right),
        ];
        let view = agreement(QueryKind::Preference, &trainers, &answers);
        assert_eq!((view.measure, view.units), ("fleiss_kappa", 2));
        assert_eq!(
            view.value,
            fleiss_kappa(&[vec!["left", "left"], vec!["right", "left"]])
        );
    }
}
