//! `answers.csv`: what the trainer answered in each finished episode, by sign, beside
//! `metrics.csv` (whose `feedback_count` counts queries only). A synthetic teacher's bar decides
//! how often a learner's action passes; the share of +1 answers, read against the returns, says
//! whether a run that does not take off is told "no" to nearly everything it tries, or is told
//! "yes" and does not follow.

use std::path::Path;

use super::episode_file::{EpisodeFile, keep_episode_rows};
use crate::guidance::evaluative_trainer::Evaluation;

/// The file's name inside a run's folder.
pub const ANSWERS_FILE: &str = "answers.csv";

/// `good`, `bad`: answers above and below 0 (+1 and -1, or a mean of several people's);
/// `none`: "no feedback" (0). `asked` is their sum.
const HEADER: &str = "step,episode,asked,good,bad,none";

/// Counts of one episode's answers.
#[derive(Default)]
struct EpisodeAnswers {
    good: u64,
    bad: u64,
    none: u64,
}

/// Appends a row per finished episode to `answers.csv`.
pub struct AnswerLog {
    file: EpisodeFile,
    counts: EpisodeAnswers,
}

impl AnswerLog {
    /// A new file in `out`, or the one an earlier call began when `append`.
    pub fn open(out: &Path, append: bool) -> anyhow::Result<Self> {
        Ok(Self {
            file: EpisodeFile::open(&out.join(ANSWERS_FILE), HEADER, append)?,
            counts: EpisodeAnswers::default(),
        })
    }

    /// A step asked and was answered `answer`.
    pub fn answered(&mut self, answer: Evaluation) {
        let c = &mut self.counts;
        match answer.value() {
            v if v > 0.0 => c.good += 1,
            v if v < 0.0 => c.bad += 1,
            _ => c.none += 1,
        }
    }

    /// The episode that ended at `step` (the run's `episode`-th): its row, flushed.
    pub fn episode_end(&mut self, step: u64, episode: u64) -> anyhow::Result<()> {
        let c = std::mem::take(&mut self.counts);
        let asked = c.good + c.bad + c.none;
        self.file.row(format_args!(
            "{step},{episode},{asked},{},{},{}",
            c.good, c.bad, c.none
        ))
    }
}

/// Cut `answers.csv` in `out` back to the rows of episodes before `episodes` (those a run
/// checkpoint counts); nothing to do if the run has no such file.
pub fn keep_answer_rows(out: &Path, episodes: u64) -> anyhow::Result<()> {
    keep_episode_rows(&out.join(ANSWERS_FILE), HEADER, episodes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::evaluative_trainer::MeanLabel;

    #[test]
    fn answers_are_counted_by_sign_per_episode_and_cut_back_on_a_resume() {
        let dir = tempfile::tempdir().unwrap();
        let mut log = AnswerLog::open(dir.path(), false).unwrap();
        let two_of_three_good = MeanLabel::of(2, 1, 3).unwrap();
        let one_of_three_bad = MeanLabel::of(0, 1, 3).unwrap();
        for answer in [
            Evaluation::Good,
            Evaluation::Bad,
            Evaluation::Bad,
            Evaluation::NoFeedback,
            Evaluation::Mean(two_of_three_good),
            Evaluation::Mean(one_of_three_bad),
        ] {
            log.answered(answer);
        }
        log.episode_end(40, 0).unwrap();
        log.episode_end(90, 1).unwrap();
        log.answered(Evaluation::Good);
        log.episode_end(120, 2).unwrap();
        let read = || std::fs::read_to_string(dir.path().join(ANSWERS_FILE)).unwrap();
        assert_eq!(
            read(),
            "step,episode,asked,good,bad,none\n40,0,6,2,3,1\n90,1,0,0,0,0\n120,2,1,1,0,0\n"
        );
        // A checkpoint that counts two episodes: the third's row goes, and the run appends.
        keep_answer_rows(dir.path(), 2).unwrap();
        let mut log = AnswerLog::open(dir.path(), true).unwrap();
        log.answered(Evaluation::Bad);
        log.episode_end(125, 2).unwrap();
        assert_eq!(
            read(),
            "step,episode,asked,good,bad,none\n40,0,6,2,3,1\n90,1,0,0,0,0\n125,2,1,0,1,0\n"
        );
    }
}
