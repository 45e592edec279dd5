//! `learner.csv`: the learner's own curves beside `metrics.csv`, one row per finished episode
//! (the means of that episode's updates), so a run whose returns collapse can be read against
//! its critic's loss, its actor's objective and its temperature at the same step. A row per
//! episode keeps it aligned with `metrics.csv` and exact across a resume: a run checkpoint is
//! taken at an episode's start, so no episode's updates are split by it. (`expert`'s periodic
//! checks stop a drive mid-episode; that episode's row then averages the updates after the
//! check only, and its `updates` column says how many.)

use std::path::Path;

use super::episode_file::{EpisodeFile, keep_episode_rows};
use crate::rl::UpdateStats;

/// The file's name inside a run's folder.
pub const LEARNER_FILE: &str = "learner.csv";

const HEADER: &str = "step,episode,updates,critic_loss,actor_loss,human_critic_loss,ent_coef";

/// Sums of the updates since the last episode ended.
#[derive(Default)]
struct EpisodeSums {
    updates: u64,
    critic_loss: f64,
    actor_loss: f64,
    human_critic_loss: f64,
    ent_coef: f64,
}

/// Appends a row per finished episode to `learner.csv`.
pub struct LearnerLog {
    file: EpisodeFile,
    sums: EpisodeSums,
}

impl LearnerLog {
    /// A new file in `out`, or the one an earlier call began when `append`.
    pub fn open(out: &Path, append: bool) -> anyhow::Result<Self> {
        Ok(Self {
            file: EpisodeFile::open(&out.join(LEARNER_FILE), HEADER, append)?,
            sums: EpisodeSums::default(),
        })
    }

    /// One update of the learner.
    pub fn update(&mut self, stats: &UpdateStats) {
        let s = &mut self.sums;
        s.updates += 1;
        s.critic_loss += f64::from(stats.critic_loss);
        s.actor_loss += f64::from(stats.actor_loss);
        s.human_critic_loss += f64::from(stats.human_critic_loss);
        s.ent_coef += f64::from(stats.ent_coef);
    }

    /// The episode that ended at `step` (the run's `episode`-th): its row, flushed; the means
    /// are empty when no update ran in it (before `learning_starts`).
    pub fn episode_end(&mut self, step: u64, episode: u64) -> anyhow::Result<()> {
        let s = std::mem::take(&mut self.sums);
        let mean = |sum: f64| match s.updates {
            0 => String::new(),
            n => format!("{}", sum / n as f64),
        };
        self.file.row(format_args!(
            "{step},{episode},{},{},{},{},{}",
            s.updates,
            mean(s.critic_loss),
            mean(s.actor_loss),
            mean(s.human_critic_loss),
            mean(s.ent_coef)
        ))
    }
}

/// Cut `learner.csv` in `out` back to the rows of episodes before `episodes` (those a run
/// checkpoint counts); nothing to do if the run has no such file.
pub fn keep_learner_rows(out: &Path, episodes: u64) -> anyhow::Result<()> {
    keep_episode_rows(&out.join(LEARNER_FILE), HEADER, episodes)
}
