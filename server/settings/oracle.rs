//! The synthetic evaluative oracle (algorithms.md section 2, "Synthetic evaluative oracle"):
//! alpha's start, the factor on the actions its critic is shown, and its rule. The as-run
//! profile sets the first two per task (`as_run`); a value given here overrides the profile's.

use serde::{Deserialize, Serialize};

use super::SettingsError;
use crate::guidance::expert_oracle::{OracleConfig, OracleRule};

/// The synthetic evaluative oracle.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct OracleSection {
    /// The synthetic oracle's alpha at step 0 (it grows 1e-8 a step) [default 0.999].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub oracle_alpha0: Option<f64>,
    /// Factor on both actions the oracle's critic and H_hat are shown [default 1].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub oracle_action_scale: Option<f32>,
    /// How the oracle judges: `authors` (+1 iff `alpha Q*(s, a*) < Q*(s, a)`, stricter than
    /// the expert itself where Q* is negative) or `sign-aware` (`Q* - (1 - alpha) |Q*|`, the
    /// same margin for either sign) [default authors].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub oracle_rule: Option<OracleRule>,
}

impl OracleSection {
    pub(super) fn offered(c: &OracleConfig) -> Self {
        Self {
            oracle_alpha0: Some(c.alpha0),
            oracle_action_scale: Some(c.action_scale),
            oracle_rule: Some(c.rule),
        }
    }

    /// The settings given, checked, into `oracle`.
    pub(super) fn apply(&self, oracle: &mut OracleConfig) -> Result<(), SettingsError> {
        if let Some(a) = self.oracle_alpha0 {
            if !(a.is_finite() && a > 0.0 && a <= 1.0) {
                return Err(SettingsError::bad(
                    "oracle_alpha0",
                    format!("expected a number in (0, 1], got {a}"),
                ));
            }
            oracle.alpha0 = a;
        }
        if let Some(s) = self.oracle_action_scale {
            if !(s.is_finite() && s > 0.0) {
                return Err(SettingsError::bad(
                    "oracle_action_scale",
                    format!("expected a positive number, got {s}"),
                ));
            }
            oracle.action_scale = s;
        }
        if let Some(rule) = self.oracle_rule {
            oracle.rule = rule;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Family, Settings};
    use crate::guidance::drpl::selection::QueryMethod;
    use crate::guidance::evaluative_run::EvaluativeRunConfig;
    use crate::guidance::expert_oracle::OracleRule;
    use crate::guidance::feedback_schedule::EvaluativeMethod;
    use crate::sim::Task;

    #[test]
    fn the_oracle_rule_is_a_setting_and_a_run_records_it() {
        let sign_aware = Settings::from_pairs([("oracle_rule", "sign-aware")])
            .unwrap()
            .evaluative(Task::LunarLander, EvaluativeMethod::Dref, 0)
            .unwrap();
        assert_eq!(sign_aware.oracle.rule, OracleRule::SignAware);
        assert_eq!(sign_aware.oracle.alpha0, 0.999);
        // config.json says so, and reads back as the run it was.
        let json = serde_json::to_value(&sign_aware).unwrap();
        assert_eq!(json["oracle"]["rule"], "sign-aware");
        let back: EvaluativeRunConfig = serde_json::from_value(json).unwrap();
        assert_eq!(back.oracle.rule, OracleRule::SignAware);
        // A run of the authors' rule writes no rule, so the files of runs from before the
        // setting (an as-run config names alpha and the scale only) read as the authors' rule.
        let as_run = Settings::from_pairs([("profile", "as-run")])
            .unwrap()
            .evaluative(Task::LunarLander, EvaluativeMethod::DrefAuthors, 0)
            .unwrap();
        let json = serde_json::to_value(&as_run).unwrap();
        assert_eq!(
            json["oracle"],
            serde_json::json!({"alpha0": 0.99, "action_scale": 1.0})
        );
        let back: EvaluativeRunConfig = serde_json::from_value(json).unwrap();
        assert_eq!(back.oracle.rule, OracleRule::Authors);
        // Offered at its default where the oracle judges, refused where it does not.
        let offered =
            serde_json::to_value(Settings::defaults(Task::Reaching, Family::Evaluative)).unwrap();
        assert_eq!(offered["oracle_rule"], "authors");
        let refused = Settings::from_pairs([("oracle_rule", "sign-aware")])
            .unwrap()
            .preference(Task::Reaching, QueryMethod::Drpl, 0)
            .unwrap_err()
            .to_string();
        assert!(refused.contains("oracle_rule"), "{refused}");
        let unknown = Settings::from_pairs([("oracle_rule", "lenient")])
            .unwrap_err()
            .to_string();
        assert!(unknown.contains("oracle_rule"), "{unknown}");
    }
}
