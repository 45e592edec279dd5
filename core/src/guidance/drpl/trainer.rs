//! Who answers preference queries: a trait, so that the synthetic oracle here and a person in a
//! browser plug into the same query loop (as `evaluative_trainer` does for DREF).

use serde::{Deserialize, Serialize};

use super::pool::Clip;

/// A trainer's answer to "which of the two is better?".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Preference {
    Left,
    Right,
    /// "About equal": recorded, and the belief uses aprel's weak-comparison likelihood.
    Equal,
    /// The trainer declined to compare: recorded, nothing learnt.
    Skip,
    /// Several trainers' answers to one query (a session that combines k answers `each`):
    /// every left, right and "about equal" enters the belief as its own observation, as APReL
    /// does with several users' answers.
    Tally(PreferenceTally),
}

/// How many trainers chose each answer of one query.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct PreferenceTally {
    pub left: u8,
    pub right: u8,
    pub equal: u8,
    pub skip: u8,
}

impl PreferenceTally {
    /// The tally of `answers` (a tally among them adds its counts).
    pub fn of(answers: &[Preference]) -> Self {
        let mut t = Self::default();
        for a in answers {
            t.add(*a);
        }
        t
    }

    fn add(&mut self, p: Preference) {
        match p {
            Preference::Left => self.left += 1,
            Preference::Right => self.right += 1,
            Preference::Equal => self.equal += 1,
            Preference::Skip => self.skip += 1,
            Preference::Tally(t) => {
                self.left += t.left;
                self.right += t.right;
                self.equal += t.equal;
                self.skip += t.skip;
            }
        }
    }

    pub fn total(&self) -> u32 {
        u32::from(self.left) + u32::from(self.right) + u32::from(self.equal) + u32::from(self.skip)
    }

    /// The single answers it counts, in a fixed order (left, right, equal, skip): the order in
    /// which they enter the belief, so a replay reproduces the posterior.
    pub fn answers(&self) -> impl Iterator<Item = Preference> + '_ {
        [
            (Preference::Left, self.left),
            (Preference::Right, self.right),
            (Preference::Equal, self.equal),
            (Preference::Skip, self.skip),
        ]
        .into_iter()
        .flat_map(|(p, n)| std::iter::repeat_n(p, usize::from(n)))
    }
}

/// What the trainer is asked about.
#[derive(Clone, Copy, Debug)]
pub struct PreferenceQuery<'a> {
    /// Queries asked in the run before this one (0-based index of this query).
    pub query: usize,
    pub left: &'a Clip,
    pub right: &'a Clip,
    /// DRPL's predicate that the two abstract states differ in, for the trainer's display.
    pub predicate: Option<usize>,
}

/// Answers preference queries. `compare` may block (a person deciding).
pub trait PreferenceTrainer {
    fn compare(&mut self, query: &PreferenceQuery<'_>) -> Preference;
}

/// The paper's synthetic human: it knows theta_true and answers deterministically by the true
/// reward of the clips' (standardised) features, `Left` iff `theta . Phi(left) > theta .
/// Phi(right)` (so a tie is `Right`, as the paper's q = 1 "otherwise").
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticOracle {
    theta: Vec<f64>,
}

impl SyntheticOracle {
    pub fn new(theta_true: Vec<f64>) -> Self {
        Self { theta: theta_true }
    }

    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// The true reward `theta . Phi` of features `phi`.
    pub fn reward(&self, phi: &[f64]) -> f64 {
        assert_eq!(phi.len(), self.theta.len(), "feature dimension");
        self.theta.iter().zip(phi).map(|(t, x)| t * x).sum()
    }
}

impl PreferenceTrainer for SyntheticOracle {
    fn compare(&mut self, query: &PreferenceQuery<'_>) -> Preference {
        if self.reward(&query.left.features) > self.reward(&query.right.features) {
            Preference::Left
        } else {
            Preference::Right
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(features: Vec<f64>) -> Clip {
        Clip {
            trajectory: 0,
            start: 0,
            end: 1,
            abstract_state: None,
            raw_features: features.clone(),
            features,
        }
    }

    fn ask(oracle: &mut SyntheticOracle, l: Vec<f64>, r: Vec<f64>) -> Preference {
        let (left, right) = (clip(l), clip(r));
        oracle.compare(&PreferenceQuery {
            query: 0,
            left: &left,
            right: &right,
            predicate: None,
        })
    }

    #[test]
    fn prefers_the_higher_true_reward() {
        let mut o = SyntheticOracle::new(vec![0.6, -0.8]);
        assert_eq!(
            ask(&mut o, vec![1.0, 0.0], vec![0.0, 0.0]),
            Preference::Left
        );
        assert_eq!(
            ask(&mut o, vec![0.0, 1.0], vec![0.0, 0.0]),
            Preference::Right
        );
        // theta . (1, 1) = -0.2 beats theta . (0, 0.5) = -0.4: a mix is judged by the sum.
        assert_eq!(
            ask(&mut o, vec![1.0, 1.0], vec![0.0, 0.5]),
            Preference::Left
        );
        assert_eq!(
            ask(&mut o, vec![0.0, 0.5], vec![1.0, 1.0]),
            Preference::Right
        );
    }

    #[test]
    fn ties_go_right_and_answers_are_deterministic() {
        let mut o = SyntheticOracle::new(vec![1.0, 0.0]);
        assert_eq!(
            ask(&mut o, vec![2.0, 5.0], vec![2.0, -5.0]),
            Preference::Right
        );
        // No margin: the smallest true difference decides.
        assert_eq!(
            ask(&mut o, vec![2.0 + 1e-12, 0.0], vec![2.0, 0.0]),
            Preference::Left
        );
        for _ in 0..3 {
            assert_eq!(
                ask(&mut o, vec![2.1, 0.0], vec![2.0, 0.0]),
                Preference::Left
            );
        }
    }

    #[test]
    fn a_tally_counts_and_lists_its_answers_in_a_fixed_order() {
        let t = PreferenceTally::of(&[Preference::Right, Preference::Left, Preference::Right]);
        assert_eq!((t.left, t.right, t.total()), (1, 2, 3));
        assert_eq!(
            t.answers().collect::<Vec<_>>(),
            vec![Preference::Left, Preference::Right, Preference::Right]
        );
        let json = serde_json::to_string(&Preference::Tally(t)).unwrap();
        assert_eq!(json, r#"{"tally":{"left":1,"right":2,"equal":0,"skip":0}}"#);
        assert_eq!(
            serde_json::from_str::<Preference>(&json).unwrap(),
            Preference::Tally(t)
        );
    }

    #[test]
    fn serde_names_are_snake_case() {
        assert_eq!(
            serde_json::to_string(&Preference::Skip).unwrap(),
            "\"skip\""
        );
        assert_eq!(
            serde_json::from_str::<Preference>("\"equal\"").unwrap(),
            Preference::Equal
        );
    }
}
