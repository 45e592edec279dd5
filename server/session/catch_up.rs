//! A remote session resumed from a run checkpoint catches up on the evaluative queries stored
//! after it (module `remote`): while the run meets their moments again (an env that repeats its
//! episodes), each takes its stored answer under its own number; the first moment that differs
//! (a robot) ends the catch-up, and the stored queries not met again are given up on, to be
//! taken into the run from their stored steps where they were answered.

use std::collections::VecDeque;

use super::remote::StoredMoment;

/// The catch-up of a remote session's asker (none for other sessions).
#[derive(Default)]
pub(super) struct CatchUp {
    /// The stored queries not met again yet, from the asker's next number on.
    moments: VecDeque<StoredMoment>,
    /// Session query numbers stored before the resume: the catch-up lasts while the asker's
    /// next number is below.
    end: u64,
    /// What the catch-up gave up on, since [`CatchUp::take_given_up`].
    given_up: Vec<GivenUp>,
}

/// Stored queries the resumed run did not meet again: session numbers `[start, end)`, and those
/// of them that were stored as evaluative queries, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct GivenUp {
    pub start: u64,
    pub end: u64,
    pub moments: Vec<StoredMoment>,
}

impl CatchUp {
    /// Catch up from session query number `next` on, up to `end` (query numbers stored), on
    /// `stored` (every stored evaluative query of the session).
    pub(super) fn new(next: u64, end: u64, stored: Vec<StoredMoment>) -> Self {
        Self {
            moments: stored.into_iter().filter(|m| m.seq >= next).collect(),
            end: end.max(next),
            given_up: Vec::new(),
        }
    }

    /// Whether query number `seq` is one stored before the resume.
    pub(super) fn active(&self, seq: u64) -> bool {
        seq < self.end
    }

    /// The run asks, as query `*seq`, about the moment `(step, action)`: the stored query it
    /// is, if it is the next one (its answer, if any, is taken; an unanswered one is asked again
    /// under its number). Any other moment ends the catch-up.
    pub(super) fn meet(
        &mut self,
        seq: &mut u64,
        step: u64,
        action: &[f32],
    ) -> Option<StoredMoment> {
        if !self.active(*seq) {
            return None;
        }
        let met = self.moments.front().is_some_and(|m| {
            m.seq == *seq && m.step == step && m.action.as_deref() == Some(action)
        });
        if !met {
            self.give_up(seq);
            return None;
        }
        self.moments.pop_front()
    }

    /// End the catch-up once the run is past the next stored query's step (`steps` steps done)
    /// without having met it.
    pub(super) fn settle(&mut self, seq: &mut u64, steps: u64) {
        if self.active(*seq) && self.moments.front().is_none_or(|m| m.step < steps) {
            self.give_up(seq);
        }
    }

    /// The run did not meet the stored queries from `*seq` on again: they are given up on, and
    /// new queries are numbered after every stored one.
    fn give_up(&mut self, seq: &mut u64) {
        if self.active(*seq) {
            self.given_up.push(GivenUp {
                start: *seq,
                end: self.end,
                moments: std::mem::take(&mut self.moments).into(),
            });
            *seq = self.end;
        }
        self.moments.clear();
    }

    /// What the catch-up gave up on since the last call.
    pub(super) fn take_given_up(&mut self) -> Vec<GivenUp> {
        std::mem::take(&mut self.given_up)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::AnswerValue;

    fn moment(seq: u64, step: u64, a: f32) -> StoredMoment {
        StoredMoment {
            seq,
            step,
            action: Some(vec![a]),
            value: Some(AnswerValue::Evaluation(1)),
            asked: None,
        }
    }

    #[test]
    fn met_moments_are_taken_and_the_first_other_one_gives_up_the_rest() {
        let stored = vec![moment(3, 20, 0.1), moment(4, 21, 0.2), moment(5, 22, 0.3)];
        let mut c = CatchUp::new(4, 7, stored);
        let mut seq = 4;
        assert_eq!(c.meet(&mut seq, 21, &[0.2]), Some(moment(4, 21, 0.2)));
        seq += 1;
        assert_eq!(c.meet(&mut seq, 22, &[0.9]), None);
        assert_eq!(seq, 7, "new queries come after every stored one");
        assert!(!c.active(seq));
        assert_eq!(
            c.take_given_up(),
            vec![GivenUp {
                start: 5,
                end: 7,
                moments: vec![moment(5, 22, 0.3)]
            }]
        );
        assert!(c.take_given_up().is_empty());
    }

    #[test]
    fn a_run_past_the_next_stored_step_gives_up() {
        let mut c = CatchUp::new(0, 2, vec![moment(0, 5, 0.1), moment(1, 6, 0.2)]);
        let mut seq = 0;
        c.settle(&mut seq, 5);
        assert!(c.active(seq));
        c.settle(&mut seq, 6);
        assert_eq!(seq, 2);
        assert_eq!(c.take_given_up()[0].moments.len(), 2);
    }
}
