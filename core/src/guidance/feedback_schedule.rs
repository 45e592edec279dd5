//! Which steps ask the evaluative trainer, per method: plain SAC never asks, EF-p% asks with
//! probability p at every step, DREF asks when its UCB rule ranks the abstract state high
//! (`dref`: the product's rule, `docs/dref.md`; `dref-authors`: exactly the authors' code).

use std::fmt;
use std::str::FromStr;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::query_rule::QueryRule;
use crate::scene_graph::AbstractState;

/// An evaluative-feedback method as the CLI and the API spell it: `sac`, `dref`,
/// `dref-authors`, `ef-<p>`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum EvaluativeMethod {
    /// SAC alone: no feedback.
    Sac,
    /// EF-p%: feedback at every step with probability `percent / 100`.
    Ef { percent: f64 },
    /// DREF as the product runs it for people (`docs/dref.md`): the authors' UCB score, ranked
    /// among recently visited states, under a ceiling on the rate, with the human critic
    /// regressed on answered steps only.
    Dref,
    /// DREF exactly as the authors' code has it (algorithms.md section 2): ranked among every
    /// state with feedback, no ceiling, the human critic regressed on every step.
    DrefAuthors,
}

impl EvaluativeMethod {
    /// Whether the method asks by DREF's UCB rule (either form).
    pub fn is_dref(self) -> bool {
        matches!(self, EvaluativeMethod::Dref | EvaluativeMethod::DrefAuthors)
    }
}

impl fmt::Display for EvaluativeMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EvaluativeMethod::Sac => f.write_str("sac"),
            EvaluativeMethod::Dref => f.write_str("dref"),
            EvaluativeMethod::DrefAuthors => f.write_str("dref-authors"),
            EvaluativeMethod::Ef { percent } => write!(f, "ef-{percent}"),
        }
    }
}

/// Why a name is no evaluative method.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EvaluativeMethodError {
    #[error("unknown method {0:?}: expected sac, dref, dref-authors or ef-<percent> (e.g. ef-25)")]
    Unknown(String),
    /// `ef-<p>` with `p` outside (0, 100].
    #[error("EF percentage must be in (0, 100], got {0}")]
    EfPercent(f64),
}

impl FromStr for EvaluativeMethod {
    type Err = EvaluativeMethodError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || EvaluativeMethodError::Unknown(s.to_string());
        match s {
            "sac" => Ok(EvaluativeMethod::Sac),
            "dref" => Ok(EvaluativeMethod::Dref),
            "dref-authors" => Ok(EvaluativeMethod::DrefAuthors),
            _ => {
                let percent: f64 = s
                    .strip_prefix("ef-")
                    .ok_or_else(bad)?
                    .parse()
                    .map_err(|_| bad())?;
                if !(percent > 0.0 && percent <= 100.0) {
                    return Err(EvaluativeMethodError::EfPercent(percent));
                }
                Ok(EvaluativeMethod::Ef { percent })
            }
        }
    }
}

impl TryFrom<String> for EvaluativeMethod {
    type Error = EvaluativeMethodError;
    fn try_from(s: String) -> Result<Self, EvaluativeMethodError> {
        s.parse()
    }
}

impl From<EvaluativeMethod> for String {
    fn from(m: EvaluativeMethod) -> String {
        m.to_string()
    }
}

/// The per-step decision of a running method.
#[derive(Clone, Debug)]
pub enum FeedbackSchedule {
    Never,
    /// EF-p%: its own generator, so that the coin flips do not disturb the policy's randomness.
    Random {
        probability: f64,
        rng: Box<ChaCha8Rng>,
    },
    Dref(QueryRule),
}

impl FeedbackSchedule {
    /// The schedule of `method`; DREF (either) uses `rule`, EF draws from a generator seeded by
    /// `seed`.
    pub fn new(method: EvaluativeMethod, rule: QueryRule, seed: u64) -> Self {
        match method {
            EvaluativeMethod::Sac => FeedbackSchedule::Never,
            EvaluativeMethod::Ef { percent } => FeedbackSchedule::Random {
                probability: percent / 100.0,
                rng: Box::new(ChaCha8Rng::seed_from_u64(seed ^ 0xef00_0000_0000_00ef)),
            },
            EvaluativeMethod::Dref | EvaluativeMethod::DrefAuthors => FeedbackSchedule::Dref(rule),
        }
    }

    /// Whether to ask at this step, whose next state has abstract state `g` (called once a
    /// step: DREF's rule remembers the visit).
    pub fn should_ask(&mut self, g: AbstractState) -> bool {
        match self {
            FeedbackSchedule::Never => false,
            FeedbackSchedule::Random { probability, rng } => rng.random_bool(*probability),
            FeedbackSchedule::Dref(rule) => rule.visit(g),
        }
    }

    /// Tell the schedule the answer `h` given in `g` (the human critic predicted `h_hat`).
    /// DREF: how many abstract states have had feedback (the states its rule ranks); 0 for the
    /// other methods, which keep no per-state statistics.
    pub fn states_with_feedback(&self) -> usize {
        match self {
            FeedbackSchedule::Dref(rule) => rule.seen().count(),
            _ => 0,
        }
    }

    pub fn record(&mut self, g: AbstractState, h: f32, h_hat: f32) {
        if let FeedbackSchedule::Dref(rule) = self {
            rule.record(g, h, h_hat);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::query_rule::UcbForm;

    #[test]
    fn methods_parse_and_print_as_the_cli_spells_them() {
        for s in [
            "sac",
            "dref",
            "dref-authors",
            "ef-100",
            "ef-50",
            "ef-25",
            "ef-6.2",
            "ef-1.6",
        ] {
            let m: EvaluativeMethod = s.parse().unwrap();
            assert_eq!(m.to_string(), s);
        }
        assert_eq!(
            "ef-8.4".parse::<EvaluativeMethod>().unwrap(),
            EvaluativeMethod::Ef { percent: 8.4 }
        );
        for bad in ["ef", "ef-", "ef-0", "ef-101", "ef-x", "drpl", "SAC"] {
            assert!(bad.parse::<EvaluativeMethod>().is_err(), "{bad} accepted");
        }
        let json = serde_json::to_string(&EvaluativeMethod::Ef { percent: 25.0 }).unwrap();
        assert_eq!(json, "\"ef-25\"");
    }

    #[test]
    fn ef_asks_at_its_rate_and_sac_never() {
        let rule = QueryRule::new(0.1, 2, UcbForm::Authors);
        let mut ef = FeedbackSchedule::new(EvaluativeMethod::Ef { percent: 25.0 }, rule.clone(), 3);
        let asked = (0..20_000)
            .filter(|_| ef.should_ask(AbstractState(0)))
            .count();
        assert!(
            (4_600..5_400).contains(&asked),
            "asked {asked} of 20000 at 25 %"
        );
        let mut sac = FeedbackSchedule::new(EvaluativeMethod::Sac, rule, 3);
        assert!((0..1000).all(|_| !sac.should_ask(AbstractState(0))));
    }
}
