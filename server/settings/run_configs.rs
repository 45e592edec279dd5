//! Reading the settings into a run's configuration: the published defaults for the task and
//! method, then every section given, each checked once against its ranges and against the task
//! and method family it belongs to. A family's check is "the other family's sections are
//! empty": no list of names.

use super::{EnvSection, Family, Settings, SettingsError, keys};
use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::sim::{EnvOptions, Task};

impl Settings {
    /// The task's version alone (`dualrep sim`): refuses every setting but the env's.
    pub fn env_options(&self, task: Task) -> Result<EnvOptions, SettingsError> {
        let env_only = Settings {
            env: self.env.clone(),
            ..Settings::default()
        };
        if &env_only != self {
            return Err(SettingsError::OnlyEnv {
                allowed: keys::of::<EnvSection>(),
            });
        }
        let mut options = EnvOptions::default();
        self.env.apply(&mut options, &task.into())?;
        Ok(options)
    }

    /// An evaluative run's configuration: the published defaults for `task` and `method`, then
    /// every setting given. Refuses settings of preference runs, of other tasks, and values out
    /// of range. Session settings are not the algorithm's and are left to [`Settings::session`].
    pub fn evaluative(
        &self,
        task: Task,
        method: EvaluativeMethod,
        seed: u64,
    ) -> Result<EvaluativeRunConfig, SettingsError> {
        self.apply_evaluative(EvaluativeRunConfig::new(task, method, seed))
    }

    /// [`Settings::evaluative`] over given defaults (a declared task's, see
    /// [`EvaluativeRunConfig::declared`]).
    pub fn apply_evaluative(
        &self,
        mut config: EvaluativeRunConfig,
    ) -> Result<EvaluativeRunConfig, SettingsError> {
        if let Some(key) = keys::first_set(&self.preference) {
            return Err(SettingsError::WrongFamily {
                key,
                family: Family::Preference,
                method: config.method.to_string(),
            });
        }
        // The profile first: every setting given overrides its values.
        self.as_run.apply_profile(&mut config)?;
        self.sac.apply(&mut config.sac)?;
        self.human_critic.apply(&mut config.sac)?;
        self.query_rule.apply(&mut config.query_rule)?;
        self.evaluative.apply(&mut config, &self.session)?;
        config.teacher = self.teacher.faults()?;
        self.oracle.apply(&mut config.oracle)?;
        self.as_run.apply_switches(&mut config);
        self.scene_graph.apply(&mut config.scene_graph)?;
        self.env.apply(&mut config.env, &config.task)?;
        Ok(config)
    }

    /// A preference run's configuration: defaults, then every setting given; refuses settings
    /// of evaluative runs and of other tasks.
    pub fn preference(
        &self,
        task: Task,
        method: QueryMethod,
        seed: u64,
    ) -> Result<PreferenceRunConfig, SettingsError> {
        self.apply_preference(PreferenceRunConfig::new(task, method, seed))
    }

    /// [`Settings::preference`] over given defaults (a declared task's, see
    /// [`PreferenceRunConfig::declared`]).
    pub fn apply_preference(
        &self,
        mut config: PreferenceRunConfig,
    ) -> Result<PreferenceRunConfig, SettingsError> {
        let evaluative_only = [
            keys::first_set(&self.sac),
            keys::first_set(&self.human_critic),
            keys::first_set(&self.query_rule),
            keys::first_set(&self.evaluative),
            keys::first_set(&self.oracle),
            keys::first_set(&self.as_run),
        ];
        if let Some(key) = evaluative_only.into_iter().flatten().next() {
            return Err(SettingsError::WrongFamily {
                key,
                family: Family::Evaluative,
                method: config.method.id().to_string(),
            });
        }
        self.preference.apply(&mut config)?;
        config.teacher = self.teacher.faults()?;
        self.scene_graph.apply(&mut config.scene_graph)?;
        self.env.apply(&mut config.env, &config.task)?;
        Ok(config)
    }
}
