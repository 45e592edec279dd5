//! The simulated participants' teachers: for each teacher setting (`teacher_beta`,
//! `teacher_gamma`, `teacher_error`, `teacher_skip`, `teacher_equal`) a fixed value or a range
//! `[low, high]`, and each participant's draw from them.
//!
//! A draw is uniform in `[low, high)` (a range whose ends are equal is that value), from a
//! ChaCha stream of the pilot's seed and the participant's number: participant 3 draws the
//! same teacher whatever the pool's size, and every participant draws one number for each of
//! the five settings in a fixed order, ranged or not, so giving one more range does not change
//! the draws of the others.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use serde_json::{Map, Value};

use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::settings::{Settings, TeacherSection};
use crate::sim::Task;

/// The teacher settings a pilot may range over, in the order each participant draws them.
pub const TEACHER_KEYS: [&str; 5] = [
    "teacher_beta",
    "teacher_gamma",
    "teacher_error",
    "teacher_skip",
    "teacher_equal",
];

/// Separates the teachers' random stream from the `random` ordering's, which seeds the same
/// way from the study's seed.
const DRAW_SALT: u64 = 0x7eac_4e25_d2a3_0000;

/// One setting's values across participants.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum TeacherRange {
    /// Every participant gets this value (a number, or `rational` / `never`).
    Fixed(Value),
    /// Uniform in `[low, high)`.
    Uniform([f64; 2]),
}

/// The ranges a pilot's teachers are drawn from: a setting not given keeps the condition's own
/// value (by default, a perfect teacher). Written as it is read: an object of settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TeacherRanges(Vec<(&'static str, TeacherRange)>);

impl Serialize for TeacherRanges {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (key, range) in &self.0 {
            map.serialize_entry(key, range)?;
        }
        map.end()
    }
}

/// A teacher range that cannot be used; the text names the setting.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RangeError {
    #[error("teachers.{key}: not a teacher setting; expected one of {}", TEACHER_KEYS.join(", "))]
    UnknownSetting { key: String },
    #[error(
        "teachers.{key}: expected a number, a word the setting takes, or [low, high], got {found}"
    )]
    Shape { key: &'static str, found: String },
    #[error("teachers.{key}: [{low}, {high}]: the low end is above the high end")]
    Reversed {
        key: &'static str,
        low: f64,
        high: f64,
    },
    #[error("teachers.{key}: {reason}")]
    OutOfRange { key: &'static str, reason: String },
}

impl TeacherRanges {
    /// The ranges of a `teachers` object (`{"teacher_beta": [0.5, 5.0], "teacher_error":
    /// 0.1}`), each end checked as the setting itself is.
    pub fn from_json(object: &Map<String, Value>) -> Result<Self, RangeError> {
        let mut ranges = Vec::new();
        for (key, value) in object {
            let Some(&key) = TEACHER_KEYS.iter().find(|k| **k == key) else {
                return Err(RangeError::UnknownSetting { key: key.clone() });
            };
            let range = match value {
                Value::Array(ends) => match ends.as_slice() {
                    [low, high] => match (low.as_f64(), high.as_f64()) {
                        (Some(low), Some(high)) => {
                            check(key, &Value::from(low))?;
                            check(key, &Value::from(high))?;
                            if low > high {
                                return Err(RangeError::Reversed { key, low, high });
                            }
                            TeacherRange::Uniform([low, high])
                        }
                        _ => return Err(shape(key, value)),
                    },
                    _ => return Err(shape(key, value)),
                },
                Value::Number(_) | Value::String(_) => {
                    check(key, value)?;
                    TeacherRange::Fixed(value.clone())
                }
                _ => return Err(shape(key, value)),
            };
            ranges.push((key, range));
        }
        ranges.sort_by_key(|(key, _)| TEACHER_KEYS.iter().position(|k| k == key));
        Ok(TeacherRanges(ranges))
    }

    /// The ranges given, in [`TEACHER_KEYS`] order.
    pub fn ranges(&self) -> &[(&'static str, TeacherRange)] {
        &self.0
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Participant `participant`'s teacher: the ranged settings drawn, the fixed ones as
    /// given, as the settings object a condition's params are merged with.
    pub fn draw(&self, seed: u64, participant: usize) -> Map<String, Value> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ DRAW_SALT);
        rng.set_stream(participant as u64);
        let mut drawn = Map::new();
        for key in TEACHER_KEYS {
            // One number per setting, used or not: the draws do not depend on which are ranged.
            let u: f64 = rng.random();
            let value = match self.0.iter().find(|(k, _)| *k == key) {
                None => continue,
                Some((_, TeacherRange::Fixed(v))) => v.clone(),
                Some((_, TeacherRange::Uniform([low, high]))) => {
                    Value::from((low + (high - low) * u).clamp(*low, *high))
                }
            };
            drawn.insert(key.to_string(), value);
        }
        drawn
    }
}

fn shape(key: &'static str, value: &Value) -> RangeError {
    RangeError::Shape {
        key,
        found: value.to_string(),
    }
}

/// Reads `value` as setting `key` alone and checks it as a run would.
fn check(key: &'static str, value: &Value) -> Result<(), RangeError> {
    // The settings' own messages start with the key, which the error names already.
    let out_of_range = |reason: String| RangeError::OutOfRange {
        key,
        reason: reason
            .strip_prefix(&format!("{key}: "))
            .map_or(reason.clone(), str::to_string),
    };
    let mut object = Map::new();
    object.insert(key.to_string(), value.clone());
    let settings =
        Settings::from_json(Value::Object(object)).map_err(|e| out_of_range(e.to_string()))?;
    let alone = Settings {
        teacher: settings.teacher.clone(),
        ..Settings::default()
    };
    debug_assert_ne!(alone.teacher, TeacherSection::default());
    // The teacher's checks are the same for every task and method.
    alone
        .evaluative(Task::Reaching, EvaluativeMethod::Dref, 0)
        .map(|_| ())
        .map_err(|e| out_of_range(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn ranges(value: Value) -> Result<TeacherRanges, String> {
        TeacherRanges::from_json(value.as_object().unwrap()).map_err(|e| e.to_string())
    }

    #[test]
    fn draws_stay_in_their_ranges_and_fixed_values_stay_fixed() {
        let r = ranges(json!({
            "teacher_error": [0.0, 0.2],
            "teacher_beta": [0.5, 5.0],
            "teacher_skip": "never",
            "teacher_equal": [0.1, 0.1]
        }))
        .unwrap();
        let keys: Vec<&str> = r.ranges().iter().map(|(k, _)| *k).collect();
        assert_eq!(
            keys,
            [
                "teacher_beta",
                "teacher_error",
                "teacher_skip",
                "teacher_equal"
            ]
        );
        let (mut betas, mut errors) = (Vec::new(), Vec::new());
        for p in 0..500 {
            let d = r.draw(11, p);
            assert_eq!(d.len(), 4);
            let beta = d["teacher_beta"].as_f64().unwrap();
            let error = d["teacher_error"].as_f64().unwrap();
            assert!((0.5..=5.0).contains(&beta), "{beta}");
            assert!((0.0..=0.2).contains(&error), "{error}");
            assert_eq!(d["teacher_skip"], json!("never"));
            assert_eq!(d["teacher_equal"], json!(0.1));
            // Every draw makes settings a run accepts.
            let s = Settings::from_json(Value::Object(d)).unwrap();
            s.evaluative(Task::Reaching, EvaluativeMethod::Dref, 0)
                .unwrap();
            betas.push(beta);
            errors.push(error);
        }
        // Spread over the range, not stuck at one end.
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        assert!((mean(&betas) - 2.75).abs() < 0.25, "{}", mean(&betas));
        assert!((mean(&errors) - 0.1).abs() < 0.015, "{}", mean(&errors));
        assert!(betas.iter().any(|b| *b < 1.0) && betas.iter().any(|b| *b > 4.5));
    }

    #[test]
    fn draws_are_reproducible_and_each_participants_own() {
        let r = ranges(json!({"teacher_beta": [0.5, 5.0]})).unwrap();
        assert_eq!(r.draw(3, 7), r.draw(3, 7));
        assert_ne!(r.draw(3, 7), r.draw(3, 8));
        assert_ne!(r.draw(3, 7), r.draw(4, 7));
        // Ranging one more setting leaves the other draws as they were.
        let more =
            ranges(json!({"teacher_beta": [0.5, 5.0], "teacher_error": [0.0, 0.3]})).unwrap();
        for p in 0..20 {
            assert_eq!(
                more.draw(3, p)["teacher_beta"],
                r.draw(3, p)["teacher_beta"]
            );
        }
        assert!(TeacherRanges::default().draw(3, 0).is_empty());
    }

    #[test]
    fn bad_ranges_are_refused_by_name() {
        let err = ranges(json!({"teacher_temper": [0, 1]})).unwrap_err();
        assert!(
            err.starts_with("teachers.teacher_temper: not a teacher setting"),
            "{err}"
        );
        assert!(err.contains("teacher_beta, teacher_gamma"), "{err}");
        assert_eq!(
            ranges(json!({"teacher_beta": [5.0, 0.5]})).unwrap_err(),
            "teachers.teacher_beta: [5, 0.5]: the low end is above the high end"
        );
        assert_eq!(
            ranges(json!({"teacher_error": [0.0, 1.5]})).unwrap_err(),
            "teachers.teacher_error: expected a probability in [0, 1), got 1.5"
        );
        let err = ranges(json!({"teacher_gamma": [0.0, 1.0]})).unwrap_err();
        assert!(err.starts_with("teachers.teacher_gamma: "), "{err}");
        for bad in [
            json!([1, 2, 3]),
            json!(["a", 1]),
            json!({"low": 1}),
            json!(true),
        ] {
            let err = ranges(json!({"teacher_beta": bad})).unwrap_err();
            assert!(err.starts_with("teachers.teacher_beta: expected"), "{err}");
        }
        let err = ranges(json!({"teacher_skip": "sometimes"})).unwrap_err();
        assert!(err.starts_with("teachers.teacher_skip: "), "{err}");
        assert!(ranges(json!({"teacher_beta": "rational"})).is_ok());
    }
}
