//! How a query's answers combine when a session takes several (k answers from different named
//! trainers), by the rule its settings name ([`Combine`]): `first` (one answer, the first
//! committed: the default), `majority` or `mean` of +1 / 0 / -1 (evaluative), `each`
//! (preference: every answer enters the belief as its own observation, as APReL does with
//! several users). Pure.
//!
//! The rule's name is a setting and lives in `settings`; what it does with answers needs the
//! session's answer types, so it is implemented here, where those are.

use super::events::{AnswerValue, QueryKind};
use crate::guidance::drpl::trainer::{Preference, PreferenceTally};
use crate::guidance::evaluative_trainer::MeanLabel;
use crate::settings::Combine;

impl Combine {
    /// Whether the rule combines answers of `kind`.
    pub fn fits(self, kind: QueryKind) -> bool {
        match self {
            Combine::First => true,
            Combine::Majority | Combine::Mean => kind == QueryKind::Evaluative,
            Combine::Each => kind == QueryKind::Preference,
        }
    }

    /// The answer the learner takes from `answers` (each a trainer's own, in the order
    /// committed); no answer at all is the timeout's ("no feedback" or a skip).
    pub fn combine(self, kind: QueryKind, answers: &[AnswerValue]) -> AnswerValue {
        if answers.is_empty() {
            return AnswerValue::timeout(kind);
        }
        match self {
            Combine::First => answers[0],
            Combine::Majority => majority(answers),
            Combine::Mean => mean(answers),
            Combine::Each => {
                let prefs: Vec<Preference> =
                    answers.iter().filter_map(|a| a.as_preference()).collect();
                match prefs.as_slice() {
                    [one] => AnswerValue::Preference(*one),
                    _ => AnswerValue::Preference(Preference::Tally(PreferenceTally::of(&prefs))),
                }
            }
        }
    }
}

/// Counts of +1, 0 and -1 among evaluative answers.
fn counts(answers: &[AnswerValue]) -> (u32, u32, u32) {
    answers.iter().fold((0, 0, 0), |(g, n, b), a| match a {
        AnswerValue::Evaluation(1) => (g + 1, n, b),
        AnswerValue::Evaluation(-1) => (g, n, b + 1),
        _ => (g, n + 1, b),
    })
}

fn majority(answers: &[AnswerValue]) -> AnswerValue {
    let (good, none, bad) = counts(answers);
    let value = if good > none && good > bad {
        1
    } else if bad > none && bad > good {
        -1
    } else {
        0
    };
    AnswerValue::Evaluation(value)
}

fn mean(answers: &[AnswerValue]) -> AnswerValue {
    let (good, none, bad) = counts(answers);
    match MeanLabel::of(good, bad, good + none + bad) {
        Some(m) => AnswerValue::Mean(m),
        None => AnswerValue::Evaluation(if good > bad {
            1
        } else if bad > good {
            -1
        } else {
            0
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(values: &[i8]) -> Vec<AnswerValue> {
        values.iter().map(|v| AnswerValue::Evaluation(*v)).collect()
    }

    #[test]
    fn majority_takes_the_most_given_value_and_a_tie_is_no_feedback() {
        let k = QueryKind::Evaluative;
        assert_eq!(
            Combine::Majority.combine(k, &ev(&[1, 1, -1])),
            AnswerValue::Evaluation(1)
        );
        assert_eq!(
            Combine::Majority.combine(k, &ev(&[-1, 0, -1])),
            AnswerValue::Evaluation(-1)
        );
        assert_eq!(
            Combine::Majority.combine(k, &ev(&[1, -1])),
            AnswerValue::Evaluation(0)
        );
        assert_eq!(
            Combine::Majority.combine(k, &ev(&[1, 0])),
            AnswerValue::Evaluation(0)
        );
        assert_eq!(
            Combine::Majority.combine(k, &[]),
            AnswerValue::Evaluation(0)
        );
    }

    #[test]
    fn mean_is_a_fraction_unless_whole() {
        let k = QueryKind::Evaluative;
        let m = Combine::Mean.combine(k, &ev(&[1, 0]));
        assert_eq!(m.as_evaluation().unwrap().value(), 0.5);
        assert_eq!(
            Combine::Mean.combine(k, &ev(&[1, 1])),
            AnswerValue::Evaluation(1)
        );
        assert_eq!(
            Combine::Mean.combine(k, &ev(&[1, -1])),
            AnswerValue::Evaluation(0)
        );
        let third = Combine::Mean.combine(k, &ev(&[-1, 0, 0]));
        assert_eq!(
            third.as_evaluation().unwrap().value(),
            (-1.0f64 / 3.0) as f32
        );
    }

    #[test]
    fn each_keeps_every_preference() {
        let p = |x| AnswerValue::Preference(x);
        let k = QueryKind::Preference;
        let t = Combine::Each.combine(
            k,
            &[
                p(Preference::Left),
                p(Preference::Left),
                p(Preference::Equal),
            ],
        );
        let Some(Preference::Tally(t)) = t.as_preference() else {
            panic!("{t:?}")
        };
        assert_eq!((t.left, t.equal, t.total()), (2, 1, 3));
        assert_eq!(
            Combine::Each.combine(k, &[p(Preference::Right)]),
            p(Preference::Right)
        );
        assert_eq!(Combine::Each.combine(k, &[]), p(Preference::Skip));
    }

    #[test]
    fn rules_fit_their_family() {
        assert!(Combine::Majority.fits(QueryKind::Evaluative));
        assert!(!Combine::Majority.fits(QueryKind::Preference));
        assert!(Combine::Each.fits(QueryKind::Preference));
        assert!(!Combine::Mean.fits(QueryKind::Preference));
        assert!(Combine::First.fits(QueryKind::Preference));
    }
}
