//! Simulated teachers that make mistakes (algorithms.md section 4), after B-Pref's `SimTeacher`
//! (Lee et al. 2021, `bpref/reward_model.py`): the same five faults for the evaluative oracle
//! (`expert_oracle`) and the preference oracle (`drpl::simulated_teacher`).
//!
//! A teacher compares two things by a *margin* `m` (preferences: the left segment's reward minus
//! the right one's; evaluative: how far the learner's action clears the expert's bar), then:
//!
//! 1. **skip** (B-Pref's `thres_skip`): when what it is shown is worth too little (both segments'
//!    rewards, or the expert's own value, below `skip`), it declines to answer;
//! 2. **about equal** (`thres_equal`): when `|m| < equal` it answers "about equal" (evaluative:
//!    0, "no feedback", the protocol's one neutral answer);
//! 3. **Boltzmann rationality** (`beta`): it picks the first with probability
//!    `sigmoid(beta * m)`; without `beta` it is perfectly rational (`m > 0`);
//! 4. **error** (`eps`): the choice is flipped with probability `error`.
//!
//! **Myopia** (`gamma`, B-Pref's discount over a segment's steps, later steps weighing more)
//! changes the margin itself and is applied by each oracle before the steps above.
//!
//! A teacher with no fault set ([`TeacherFaults::is_perfect`]) is the paper's oracle exactly and
//! draws no random number. A faulty one draws two uniforms per decision whatever its faults, so
//! two teachers of the same seed that differ only in `error` make the same Boltzmann draws and
//! the 20 % teacher's flips include the 10 % teacher's (common random numbers: a robustness
//! curve over error rates compares like with like).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The faults of a simulated teacher; the default has none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeacherFaults {
    /// Boltzmann rationality: `P(first) = sigmoid(beta * margin)`; `None`: perfectly rational.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// Myopic discount in (0, 1]: step `t` of a segment of length `H` weighs `gamma^(H-1-t)`;
    /// `None` (or 1): not myopic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gamma: Option<f64>,
    /// Probability in [0, 1) that a choice is flipped.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub error: f64,
    /// Decline to answer when what is shown is worth less than this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skip: Option<f64>,
    /// Answer "about equal" when `|margin|` is below this.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub equal: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl TeacherFaults {
    /// No fault at all: the paper's deterministic oracle.
    pub fn is_perfect(&self) -> bool {
        *self == Self::default()
    }

    /// The myopic discount, if one below 1 is set.
    pub fn myopia(&self) -> Option<f64> {
        self.gamma.filter(|g| *g < 1.0)
    }

    /// Ranges: beta >= 0, gamma in (0, 1], error in [0, 1), equal >= 0, every value finite.
    pub fn validate(&self) -> Result<(), TeacherError> {
        let finite = |key: &'static str, value: f64| {
            if value.is_finite() {
                Ok(())
            } else {
                Err(TeacherError::NotFinite { key, value })
            }
        };
        if let Some(b) = self.beta {
            finite("teacher_beta", b)?;
            if b < 0.0 {
                return Err(TeacherError::Negative {
                    key: "teacher_beta",
                    value: b,
                });
            }
        }
        if let Some(g) = self.gamma
            && !(g > 0.0 && g <= 1.0)
        {
            return Err(TeacherError::Gamma(g));
        }
        if !(0.0..1.0).contains(&self.error) {
            return Err(TeacherError::ErrorRate(self.error));
        }
        if let Some(s) = self.skip {
            finite("teacher_skip", s)?;
        }
        finite("teacher_equal", self.equal)?;
        if self.equal < 0.0 {
            return Err(TeacherError::Negative {
                key: "teacher_equal",
                value: self.equal,
            });
        }
        Ok(())
    }
}

/// Why a teacher's faults are out of range; the text names the setting (`teacher_beta`).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum TeacherError {
    /// An infinite or NaN value.
    #[error("{key}: expected a finite number, got {value}")]
    NotFinite { key: &'static str, value: f64 },
    /// A negative `teacher_beta` or `teacher_equal`.
    #[error("{key}: expected a number >= 0, got {value}")]
    Negative { key: &'static str, value: f64 },
    /// `teacher_gamma` outside (0, 1].
    #[error("teacher_gamma: expected a number in (0, 1], got {0}")]
    Gamma(f64),
    /// `teacher_error` outside [0, 1).
    #[error("teacher_error: expected a probability in [0, 1), got {0}")]
    ErrorRate(f64),
}

impl TeacherError {
    /// The setting the error names.
    pub fn key(&self) -> &'static str {
        match self {
            TeacherError::NotFinite { key, .. } | TeacherError::Negative { key, .. } => key,
            TeacherError::Gamma(_) => "teacher_gamma",
            TeacherError::ErrorRate(_) => "teacher_error",
        }
    }
}

/// What a teacher decided between "first" (left, good) and "second" (right, bad).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    First,
    Second,
    Equal,
    Skip,
}

/// The faults and the random stream they draw from.
#[derive(Clone, Debug)]
pub struct FaultyJudge {
    faults: TeacherFaults,
    rng: ChaCha8Rng,
}

impl FaultyJudge {
    pub fn new(faults: TeacherFaults, seed: u64) -> Self {
        Self {
            faults,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x7eac_4e25_fa17_0000),
        }
    }

    pub fn faults(&self) -> &TeacherFaults {
        &self.faults
    }

    pub fn rng(&self) -> &ChaCha8Rng {
        &self.rng
    }

    pub fn set_rng(&mut self, rng: ChaCha8Rng) {
        self.rng = rng;
    }

    /// Decide on `margin` (positive favours the first) when what is shown is worth `worth`
    /// (compared with the skip threshold). A perfect teacher answers `First` iff `margin > 0`
    /// and draws nothing.
    pub fn decide(&mut self, margin: f64, worth: f64) -> Decision {
        let f = self.faults;
        if f.is_perfect() {
            return if margin > 0.0 {
                Decision::First
            } else {
                Decision::Second
            };
        }
        // Both draws happen on every decision (see the module's note on common random numbers).
        let (u_choice, u_error): (f64, f64) = (self.rng.random(), self.rng.random());
        if f.skip.is_some_and(|s| worth < s) {
            return Decision::Skip;
        }
        if margin.abs() < f.equal {
            return Decision::Equal;
        }
        let first = match f.beta {
            None => margin > 0.0,
            Some(beta) => u_choice < sigmoid(beta * margin),
        };
        let first = first != (u_error < f.error);
        if first {
            Decision::First
        } else {
            Decision::Second
        }
    }
}

/// The logistic function, without overflow for large |x|.
pub fn sigmoid(x: f64) -> f64 {
    if x >= 0.0 {
        1.0 / (1.0 + (-x).exp())
    } else {
        let e = x.exp();
        e / (1.0 + e)
    }
}

/// Weights `gamma^(n-1-t)` for `t = 0..n`, normalised to sum to one: the myopic teacher's view
/// of a stretch of `n` steps (the last step weighs most).
pub fn myopic_weights(n: usize, gamma: f64) -> Vec<f64> {
    let mut w: Vec<f64> = (0..n).map(|t| gamma.powi((n - 1 - t) as i32)).collect();
    let sum: f64 = w.iter().sum();
    if sum > 0.0 {
        for x in &mut w {
            *x /= sum;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn judge(faults: TeacherFaults) -> FaultyJudge {
        FaultyJudge::new(faults, 3)
    }

    #[test]
    fn a_perfect_teacher_is_the_sign_of_the_margin_and_draws_nothing() {
        let mut j = judge(TeacherFaults::default());
        let before = j.rng().get_word_pos();
        assert_eq!(j.decide(0.1, 0.0), Decision::First);
        assert_eq!(j.decide(-0.1, 0.0), Decision::Second);
        assert_eq!(j.decide(0.0, 0.0), Decision::Second, "a tie is the second");
        assert_eq!(j.rng().get_word_pos(), before);
    }

    #[test]
    fn error_flips_at_its_rate_and_higher_rates_flip_a_superset() {
        let n = 20_000;
        let run = |error: f64| -> Vec<bool> {
            let mut j = judge(TeacherFaults {
                error,
                ..Default::default()
            });
            (0..n)
                .map(|_| j.decide(1.0, 0.0) == Decision::Second)
                .collect()
        };
        let (low, high) = (run(0.1), run(0.3));
        let rate = |v: &[bool]| v.iter().filter(|x| **x).count() as f64 / n as f64;
        assert!((rate(&low) - 0.1).abs() < 0.01, "{}", rate(&low));
        assert!((rate(&high) - 0.3).abs() < 0.015, "{}", rate(&high));
        assert!(low.iter().zip(&high).all(|(l, h)| !l || *h));
    }

    #[test]
    fn boltzmann_choices_follow_the_sigmoid() {
        let mut j = judge(TeacherFaults {
            beta: Some(2.0),
            ..Default::default()
        });
        let n = 20_000;
        let first = (0..n)
            .filter(|_| j.decide(0.5, 0.0) == Decision::First)
            .count() as f64
            / n as f64;
        assert!((first - sigmoid(1.0)).abs() < 0.01, "{first}");
        // beta = 0 is a coin.
        let mut coin = judge(TeacherFaults {
            beta: Some(0.0),
            ..Default::default()
        });
        let heads = (0..n)
            .filter(|_| coin.decide(100.0, 0.0) == Decision::First)
            .count() as f64
            / n as f64;
        assert!((heads - 0.5).abs() < 0.015, "{heads}");
    }

    #[test]
    fn skip_and_equal_come_before_the_choice() {
        let mut j = judge(TeacherFaults {
            skip: Some(0.0),
            equal: 0.2,
            error: 0.5,
            ..Default::default()
        });
        assert_eq!(j.decide(5.0, -1.0), Decision::Skip);
        assert_eq!(j.decide(0.1, 1.0), Decision::Equal);
        assert_eq!(j.decide(-0.19, 1.0), Decision::Equal);
        assert!(matches!(
            j.decide(1.0, 1.0),
            Decision::First | Decision::Second
        ));
    }

    #[test]
    fn ranges_are_checked() {
        let bad = [
            TeacherFaults {
                error: 1.0,
                ..Default::default()
            },
            TeacherFaults {
                gamma: Some(0.0),
                ..Default::default()
            },
            TeacherFaults {
                beta: Some(-1.0),
                ..Default::default()
            },
            TeacherFaults {
                equal: f64::NAN,
                ..Default::default()
            },
        ];
        let refused: Vec<String> = bad
            .iter()
            .map(|f| f.validate().unwrap_err().to_string())
            .collect();
        assert_eq!(
            refused,
            [
                "teacher_error: expected a probability in [0, 1), got 1",
                "teacher_gamma: expected a number in (0, 1], got 0",
                "teacher_beta: expected a number >= 0, got -1",
                "teacher_equal: expected a finite number, got NaN",
            ]
        );
        assert!(TeacherFaults::default().validate().is_ok());
        assert!(TeacherFaults::default().is_perfect());
    }

    #[test]
    fn myopic_weights_favour_the_last_steps() {
        let w = myopic_weights(3, 0.5);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((w[2] - 4.0 / 7.0).abs() < 1e-12 && (w[0] - 1.0 / 7.0).abs() < 1e-12);
        assert_eq!(myopic_weights(2, 1.0), vec![0.5, 0.5]);
        assert!((sigmoid(800.0) - 1.0).abs() < 1e-12 && sigmoid(-800.0) >= 0.0);
    }
}
