//! Every setting a run or a session takes by name: [`Settings`], one flat list of keys to its
//! users and, inside, one section per family (the session's, the teacher's, SAC's, ...). A
//! launch request's `params`, the CLI's `--set key=value` and `--config` TOML files all read
//! into it (an unknown key or a value of the wrong type is refused with the key's name and the
//! list of known keys); [`Settings::session`], [`Settings::evaluative`] and
//! [`Settings::preference`] check ranges and which task and method each setting applies to,
//! once; `GET /api/tasks` and the dashboard's advanced form read [`Settings::defaults`]. No IO.
//!
//! A setting left out keeps the published default (algorithms.md, tasks.md), so a stored
//! session's settings are exactly what its researcher gave.
//!
//! A new setting is one field, with its doc comment, in its section's struct, its offered
//! default in that section's `offered`, and its effect in that section's `apply`: the list of
//! keys (errors, OpenAPI, `GET /api/tasks`), `--set`, TOML and the family checks follow from the
//! struct (`keys`).
//!
//! Here: the list and how it reads. The sections, each with its defaults and what it does to a
//! run: `session`, `people` (who answers and the synthetic teacher), `sac`, `query_rule`,
//! `evaluative` (reward scale, a person's pace), `oracle` (the synthetic evaluative oracle),
//! `as_run`, `task_version` (scene graph and env), `preference`; `run_configs`: a run's
//! configuration from them all.

use std::sync::LazyLock;

use serde::{Deserialize, Deserializer, Serialize};

use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::sim::Task;

mod as_run;
mod combine;
mod error;
mod evaluative;
mod keys;
mod oracle;
mod people;
mod preference;
mod query_rule;
mod run_configs;
mod sac;
mod session;
mod task_version;

pub use as_run::{AsRunSection, Profile, SceneGraphChoice, time_limit_as_run};
pub use combine::Combine;
pub use error::SettingsError;
pub use evaluative::EvaluativeSection;
pub use oracle::OracleSection;
pub use people::{NeverWord, RationalWord, TeacherBeta, TeacherSection, TeacherSkip};
pub use preference::PreferenceSection;
pub use query_rule::QueryRuleSection;
pub use sac::{AutoWord, HumanCriticSection, SacSection, TargetEntropy};
pub use session::{
    DEFAULT_ANSWER_TIMEOUT_S, DEFAULT_CHECKPOINT_EVERY, DEFAULT_CLIP_FRAMES, DEFAULT_ENV_TIMEOUT_S,
    DEFAULT_PACE_HZ, SessionSection, SessionSettings,
};
pub use task_version::{EnvSection, SceneGraphSection};

/// Which runs a setting shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// SAC, EF-p% and DREF (`dualrep train`, evaluative sessions).
    Evaluative,
    /// DRPL and its baselines (`dualrep prefs`, preference sessions).
    Preference,
}

/// Every setting by name, in sections; `None` keeps the default for the run's task and method.
/// The sections are flattened: a user names `rank_window`, never a section. Their order is the
/// order of the keys in a stored session's `params`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Settings {
    /// The server's human and synthetic sessions.
    #[serde(flatten)]
    pub session: SessionSection,
    /// The synthetic teacher's faults.
    #[serde(flatten)]
    pub teacher: TeacherSection,
    /// SAC's learner.
    #[serde(flatten)]
    pub sac: SacSection,
    /// DREF's human critic.
    #[serde(flatten)]
    pub human_critic: HumanCriticSection,
    /// DREF's query rule.
    #[serde(flatten)]
    pub query_rule: QueryRuleSection,
    /// The reward's scale and a person's pace.
    #[serde(flatten)]
    pub evaluative: EvaluativeSection,
    /// The synthetic evaluative oracle.
    #[serde(flatten)]
    pub oracle: OracleSection,
    /// The authors' published runs.
    #[serde(flatten)]
    pub as_run: AsRunSection,
    /// The scene graph's options.
    #[serde(flatten)]
    pub scene_graph: SceneGraphSection,
    /// The task's version.
    #[serde(flatten)]
    pub env: EnvSection,
    /// DRPL and its baselines.
    #[serde(flatten)]
    pub preference: PreferenceSection,
}

/// Calls `$visit!(section field, section type)` for each section, in order: the one list of
/// sections that reading, the key list and the OpenAPI schema share.
macro_rules! for_each_section {
    ($visit:ident) => {
        $visit!(session, SessionSection);
        $visit!(teacher, TeacherSection);
        $visit!(sac, SacSection);
        $visit!(human_critic, HumanCriticSection);
        $visit!(query_rule, QueryRuleSection);
        $visit!(evaluative, EvaluativeSection);
        $visit!(oracle, OracleSection);
        $visit!(as_run, AsRunSection);
        $visit!(scene_graph, SceneGraphSection);
        $visit!(env, EnvSection);
        $visit!(preference, PreferenceSection);
    };
}

/// Every key, section by section, in order (generated from the sections' structs).
static KEYS: LazyLock<Vec<&'static str>> = LazyLock::new(|| {
    let mut all = Vec::new();
    macro_rules! push_keys {
        ($field:ident, $section:ty) => {
            all.extend_from_slice(keys::of::<$section>());
        };
    }
    for_each_section!(push_keys);
    all
});

impl Settings {
    /// Every setting's key, in order: what an unknown key's error lists.
    pub fn keys() -> &'static [&'static str] {
        &KEYS
    }

    /// Settings from `key=value` pairs (the CLI's `--set`, in order; a later key wins). A value
    /// is read as JSON where it is JSON (`0.3`, `true`, `[64, 64]`) and as text otherwise
    /// (`paper`, `256,256`).
    pub fn from_pairs<'a>(
        pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> Result<Self, SettingsError> {
        let mut map = serde_json::Map::new();
        for (key, text) in pairs {
            let value = serde_json::from_str::<serde_json::Value>(text)
                .ok()
                .filter(|v| !v.is_object() && !v.is_string())
                .unwrap_or_else(|| serde_json::Value::String(text.to_string()));
            map.insert(key.to_string(), value);
        }
        Self::from_json(serde_json::Value::Object(map))
    }

    /// Settings from a JSON object (a launch request's `params`, a TOML file read as JSON).
    /// Errors name the key: `beta: invalid type: string ...`.
    pub fn from_json(value: serde_json::Value) -> Result<Self, SettingsError> {
        let serde_json::Value::Object(map) = value else {
            return Err(SettingsError::NotAnObject {
                found: keys::unexpected(&value),
            });
        };
        keys::refuse_unknown(&map, Self::keys())?;
        let object = serde_json::Value::Object(map);
        let mut settings = Settings::default();
        macro_rules! read_section {
            ($field:ident, $section:ty) => {
                settings.$field = keys::read::<$section>(&object)?;
            };
        }
        for_each_section!(read_section);
        Ok(settings)
    }

    /// `other`'s settings over ours.
    pub fn merged(self, other: Settings) -> Result<Self, SettingsError> {
        let serialize = |e: serde_json::Error| SettingsError::Serialize(e.to_string());
        let mut base = serde_json::to_value(self).map_err(serialize)?;
        let over = serde_json::to_value(other).map_err(serialize)?;
        if let (Some(base), Some(over)) = (base.as_object_mut(), over.as_object()) {
            for (k, v) in over {
                base.insert(k.clone(), v.clone());
            }
        }
        Self::from_json(base)
    }

    /// The session settings with defaults, checked.
    pub fn session(&self) -> Result<SessionSettings, SettingsError> {
        self.session.resolve()
    }

    /// The names of the session's own settings that are set (a headless run has no session).
    pub fn session_keys_set(&self) -> Vec<&'static str> {
        keys::set(&self.session)
    }

    /// Every setting that applies to `task` and `family`, at its default: what `GET /api/tasks`
    /// offers and the dashboard's advanced form shows. Session settings are included.
    pub fn defaults(task: Task, family: Family) -> Settings {
        let shared = Settings {
            session: SessionSection::offered(),
            teacher: TeacherSection::offered(),
            scene_graph: SceneGraphSection::offered(task),
            ..Settings::default()
        };
        match family {
            Family::Evaluative => {
                let c = EvaluativeRunConfig::new(task, EvaluativeMethod::Dref, 0);
                Settings {
                    sac: SacSection::offered(&c.sac),
                    human_critic: HumanCriticSection::offered(&c.sac),
                    query_rule: QueryRuleSection::offered(&c.query_rule),
                    evaluative: EvaluativeSection::offered(&c),
                    oracle: OracleSection::offered(&c.oracle),
                    as_run: AsRunSection::offered(&c),
                    env: EnvSection::offered(task, &c.env),
                    ..shared
                }
            }
            Family::Preference => {
                let c = PreferenceRunConfig::new(task, QueryMethod::Drpl, 0);
                Settings {
                    preference: PreferenceSection::offered(&c),
                    env: EnvSection::offered(task, &c.env),
                    ..shared
                }
            }
        }
    }
}

/// Read through [`Settings::from_json`], so that a stored spec's or a request's settings are
/// refused and named exactly as `--set`'s are.
impl<'de> Deserialize<'de> for Settings {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let value = serde_json::Value::deserialize(d)?;
        Settings::from_json(value).map_err(serde::de::Error::custom)
    }
}

/// One flat object of every key, as users write it (the sections' properties merged).
impl utoipa::PartialSchema for Settings {
    fn schema() -> utoipa::openapi::RefOr<utoipa::openapi::schema::Schema> {
        use utoipa::openapi::schema::{AdditionalProperties, ObjectBuilder, Schema};
        use utoipa::openapi::{RefOr, Type};
        let mut object = ObjectBuilder::new()
            .schema_type(Type::Object)
            .description(Some(
                "Every setting by name. A setting left out keeps the default for the run's task and method.",
            ))
            .additional_properties(Some(AdditionalProperties::FreeForm(false)))
            .build();
        macro_rules! merge_section {
            ($field:ident, $section:ty) => {
                if let RefOr::T(Schema::Object(section)) =
                    <$section as utoipa::PartialSchema>::schema()
                {
                    object.properties.extend(section.properties);
                }
            };
        }
        for_each_section!(merge_section);
        RefOr::T(Schema::Object(object))
    }
}

impl utoipa::ToSchema for Settings {
    fn schemas(
        schemas: &mut Vec<(
            String,
            utoipa::openapi::RefOr<utoipa::openapi::schema::Schema>,
        )>,
    ) {
        macro_rules! section_schemas {
            ($field:ident, $section:ty) => {
                <$section as utoipa::ToSchema>::schemas(schemas);
            };
        }
        for_each_section!(section_schemas);
    }
}

#[cfg(test)]
mod as_run_tests;
#[cfg(test)]
mod pinned;
#[cfg(test)]
mod product_dref_tests;
#[cfg(test)]
mod tests;
