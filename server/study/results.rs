//! A study's results from what its participants did: per condition, the cumulative reward curve
//! (mean ± s.e. over participants, Figure 4's lines), the final cumulative reward, feedback %,
//! total training time T and no-feedback count NFC (Figure 4's table), the survey's medians and
//! distributions (Figure 4's bars), and the within-subject tests of each measure (Friedman, then
//! pairwise Wilcoxon signed-rank with Holm's correction, effect sizes, a caution at small n).
//!
//! Pure: the HTTP route and `dualrep report study` read the store into [`ParticipantRun`]s and
//! call [`summarise`]; both show the same numbers.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::report::stats::{MeanSe, interpolate, linspace, mean_se};
use crate::report::within_subject::{WithinSubject, within_subject};

use super::spec::StudySpec;

/// Reads one measure off a participant's run (`None`: not measured, e.g. a survey not answered).
type Measure = Box<dyn Fn(&ParticipantRun) -> Option<f64>>;

/// Points on each condition's mean curve.
pub const CURVE_POINTS: usize = 50;

/// What one participant did in one condition (one row of the tidy table).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParticipantRun {
    pub participant_id: String,
    /// 0-based, in the order participants came.
    pub participant: usize,
    pub condition: String,
    /// 0-based position of the condition in this participant's order.
    pub position: usize,
    pub session_id: String,
    /// The session's status now (`finished`, `stopped`, ...).
    pub status: String,
    /// Did not finish its budget (stopped, failed or interrupted); still counted, and marked.
    pub ended_early: bool,
    /// Environment steps (evaluative) or queries (preference) done.
    pub progress: i64,
    /// The sum of every finished episode's return.
    pub cumulative_reward: f64,
    /// Queries asked per environment step, in percent (0 for preference methods).
    pub feedback_pct: f64,
    /// Wall-clock seconds from the session's start to its end (the paper's T).
    pub seconds: Option<f64>,
    /// "No feedback" answers, skips and timeouts (the paper's NFC).
    pub no_feedback: i64,
    /// (step, cumulative reward) after each finished episode.
    #[serde(skip)]
    pub curve: Vec<(f64, f64)>,
    /// Survey answers by question id (absent: not answered yet).
    pub survey: BTreeMap<String, i64>,
}

/// A condition's mean curve over participants.
#[derive(Clone, Debug, PartialEq, Serialize, utoipa::ToSchema)]
pub struct Curve {
    pub steps: Vec<f64>,
    pub mean: Vec<f64>,
    pub se: Vec<f64>,
}

/// One survey question's answers in a condition.
#[derive(Clone, Debug, PartialEq, Serialize, utoipa::ToSchema)]
pub struct QuestionSummary {
    pub n: usize,
    pub median: Option<f64>,
    /// `counts[i]`: answers of `i + 1` on the question's scale.
    pub counts: Vec<usize>,
}

/// One condition's results.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionResults {
    pub name: String,
    /// Participants with a session in this condition.
    pub n: usize,
    pub ended_early: usize,
    pub cumulative_reward: MeanSe,
    pub feedback_pct: MeanSe,
    pub seconds: MeanSe,
    pub no_feedback: MeanSe,
    pub curve: Curve,
    pub survey: BTreeMap<String, QuestionSummary>,
}

/// The within-subject tests of one measure, conditions in the study's order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeasureTests {
    pub measure: String,
    pub tests: WithinSubject,
}

/// A study's results.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StudyResults {
    pub participants: usize,
    /// Participants who trained and surveyed every condition.
    pub complete: usize,
    pub conditions: Vec<ConditionResults>,
    /// The measures' tests: `cumulative_reward`, `feedback_pct`, `seconds`, `no_feedback`,
    /// then one per survey question (`survey.<id>`).
    pub tests: Vec<MeasureTests>,
    pub main_contrast: [String; 2],
}

/// The results of `runs` (every participant × condition with a session) for `spec`.
pub fn summarise(spec: &StudySpec, participants: usize, runs: &[ParticipantRun]) -> StudyResults {
    let names: Vec<&str> = spec.conditions.iter().map(|c| c.name.as_str()).collect();
    let budget_steps = runs.iter().map(|r| r.progress).max().unwrap_or(0) as f64;
    let grid = linspace(0.0, budget_steps.max(1.0), CURVE_POINTS);
    let conditions = names
        .iter()
        .map(|&name| {
            let mine: Vec<&ParticipantRun> = runs.iter().filter(|r| r.condition == name).collect();
            condition_results(spec, name, &mine, &grid)
        })
        .collect();
    let mut measures: Vec<(String, Measure)> = vec![
        (
            "cumulative_reward".into(),
            Box::new(|r| Some(r.cumulative_reward)),
        ),
        ("feedback_pct".into(), Box::new(|r| Some(r.feedback_pct))),
        ("seconds".into(), Box::new(|r| r.seconds)),
        (
            "no_feedback".into(),
            Box::new(|r| Some(r.no_feedback as f64)),
        ),
    ];
    for q in &spec.survey {
        let id = q.id.clone();
        measures.push((
            format!("survey.{}", q.id),
            Box::new(move |r| r.survey.get(&id).map(|&v| v as f64)),
        ));
    }
    let tests = measures
        .iter()
        .map(|(measure, read)| MeasureTests {
            measure: measure.clone(),
            tests: within_subject(&matrix(&names, participants, runs, read), names.len()),
        })
        .collect();
    let complete = (0..participants)
        .filter(|&p| {
            names.iter().all(|&c| {
                runs.iter()
                    .any(|r| r.participant == p && r.condition == c && !r.survey.is_empty())
            })
        })
        .count();
    let [a, b] = spec.contrast();
    StudyResults {
        participants,
        complete,
        conditions,
        tests,
        main_contrast: [a.to_string(), b.to_string()],
    }
}

/// Rows: participants; columns: conditions; a cell is the measure of that participant's run in
/// that condition, `None` where there is none (the tests drop such rows and count them).
fn matrix(
    names: &[&str],
    participants: usize,
    runs: &[ParticipantRun],
    read: &dyn Fn(&ParticipantRun) -> Option<f64>,
) -> Vec<Vec<Option<f64>>> {
    (0..participants)
        .map(|p| {
            names
                .iter()
                .map(|&c| {
                    runs.iter()
                        .find(|r| r.participant == p && r.condition == c)
                        .and_then(read)
                })
                .collect()
        })
        .collect()
}

fn condition_results(
    spec: &StudySpec,
    name: &str,
    runs: &[&ParticipantRun],
    grid: &[f64],
) -> ConditionResults {
    let values = |f: &dyn Fn(&ParticipantRun) -> Option<f64>| -> Vec<f64> {
        runs.iter().filter_map(|r| f(r)).collect()
    };
    let at_each_step: Vec<Vec<f64>> = grid
        .iter()
        .map(|&x| {
            runs.iter()
                .map(|r| {
                    // Before the first finished episode nothing has been earned yet.
                    let mut points = vec![(0.0, 0.0)];
                    points.extend(r.curve.iter().copied());
                    // Held flat after the session's last step, not extended past it.
                    interpolate(&points, x.min(r.progress as f64))
                })
                .collect()
        })
        .collect();
    let stats: Vec<MeanSe> = at_each_step.iter().map(|v| mean_se(v)).collect();
    let survey = spec
        .survey
        .iter()
        .map(|q| {
            let answers: Vec<i64> = runs
                .iter()
                .filter_map(|r| r.survey.get(&q.id).copied())
                .collect();
            let mut counts = vec![0; q.points as usize];
            for &a in &answers {
                if (1..=q.points as i64).contains(&a) {
                    counts[a as usize - 1] += 1;
                }
            }
            let summary = QuestionSummary {
                n: answers.len(),
                median: median(&answers),
                counts,
            };
            (q.id.clone(), summary)
        })
        .collect();
    ConditionResults {
        name: name.to_string(),
        n: runs.len(),
        ended_early: runs.iter().filter(|r| r.ended_early).count(),
        cumulative_reward: mean_se(&values(&|r| Some(r.cumulative_reward))),
        feedback_pct: mean_se(&values(&|r| Some(r.feedback_pct))),
        seconds: mean_se(&values(&|r| r.seconds)),
        no_feedback: mean_se(&values(&|r| Some(r.no_feedback as f64))),
        curve: Curve {
            steps: grid.to_vec(),
            mean: stats.iter().map(|s| s.mean).collect(),
            se: stats.iter().map(|s| s.se).collect(),
        },
        survey,
    }
}

/// The median of Likert answers (the mean of the middle two for an even count).
fn median(values: &[i64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_unstable();
    let n = sorted.len();
    Some(if n % 2 == 1 {
        sorted[n / 2] as f64
    } else {
        (sorted[n / 2 - 1] + sorted[n / 2]) as f64 / 2.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn spec() -> StudySpec {
        let s: StudySpec = serde_json::from_value(json!({
            "title": "t",
            "conditions": [
                {"name": "dref", "task": "reaching", "method": "dref"},
                {"name": "sac", "task": "reaching", "method": "sac"}
            ]
        }))
        .unwrap();
        s.validate().unwrap();
        s
    }

    fn run(p: usize, condition: &str, reward: f64, e: i64) -> ParticipantRun {
        ParticipantRun {
            participant_id: format!("p{p}"),
            participant: p,
            condition: condition.into(),
            position: 0,
            session_id: format!("{p}{condition}"),
            status: "finished".into(),
            ended_early: false,
            progress: 100,
            cumulative_reward: reward,
            feedback_pct: 5.0,
            seconds: Some(60.0),
            no_feedback: 2,
            curve: vec![(50.0, reward / 2.0), (100.0, reward)],
            survey: [("E".to_string(), e), ("I".into(), 3), ("C".into(), 4)].into(),
        }
    }

    #[test]
    fn conditions_get_means_curves_survey_counts_and_paired_tests() {
        let runs: Vec<ParticipantRun> = (0..6)
            .flat_map(|p| {
                [
                    run(p, "dref", 100.0 + p as f64, 5),
                    run(p, "sac", 10.0 + 2.0 * p as f64, 2),
                ]
            })
            .collect();
        let r = summarise(&spec(), 6, &runs);
        assert_eq!(r.participants, 6);
        assert_eq!(r.complete, 6);
        let dref = &r.conditions[0];
        assert_eq!(dref.n, 6);
        assert!((dref.cumulative_reward.mean - 102.5).abs() < 1e-12);
        assert_eq!(dref.survey["E"].counts, [0, 0, 0, 0, 6]);
        assert_eq!(dref.survey["E"].median, Some(5.0));
        assert_eq!(r.conditions[1].survey["E"].counts, [0, 6, 0, 0, 0]);
        // The curve starts at 0 and ends at the final cumulative reward.
        assert_eq!(dref.curve.mean[0], 0.0);
        assert!((dref.curve.mean[CURVE_POINTS - 1] - 102.5).abs() < 1e-9);
        // Six of six participants favour dref: the exact two-sided signed-rank p is 2/64.
        let reward = &r.tests[0];
        assert_eq!(reward.measure, "cumulative_reward");
        assert!((reward.tests.pairs[0].test.p - 0.03125).abs() < 1e-12);
        let measures: Vec<&str> = r.tests.iter().map(|t| t.measure.as_str()).collect();
        assert_eq!(
            measures,
            [
                "cumulative_reward",
                "feedback_pct",
                "seconds",
                "no_feedback",
                "survey.E",
                "survey.I",
                "survey.C"
            ]
        );
    }

    #[test]
    fn a_participant_missing_a_condition_is_counted_and_left_out_of_the_tests() {
        let mut runs = vec![run(0, "dref", 1.0, 4), run(0, "sac", 0.0, 4)];
        runs.push(run(1, "dref", 2.0, 4));
        let mut early = run(2, "dref", 3.0, 4);
        early.ended_early = true;
        runs.push(early);
        runs.push(run(2, "sac", 1.0, 4));
        let r = summarise(&spec(), 3, &runs);
        assert_eq!(r.complete, 2);
        assert_eq!(r.conditions[0].n, 3);
        assert_eq!(r.conditions[0].ended_early, 1);
        assert_eq!(r.tests[0].tests.participants, 2);
        assert_eq!(r.tests[0].tests.dropped, 1);
        assert!(r.tests[0].tests.caution.is_some());
        assert_eq!(median(&[1, 2, 4, 5]), Some(3.0));
    }
}
