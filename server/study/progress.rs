//! Where a participant is in their study, derived from what is stored (consent, the session
//! launched per position and its status, the surveys answered), never kept as a separate
//! state: a participant who closes the tab and opens their link again is exactly where they
//! were, and a session that ended early is a fact the survey step shows, not a reason to
//! launch it again.

use serde::Serialize;

use crate::store::Status;

/// What a participant is to do now.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, utoipa::ToSchema)]
#[serde(tag = "step", rename_all = "snake_case")]
pub enum Step {
    /// Read the consent text and agree.
    Consent,
    /// Start the condition at `position` (no session yet).
    Ready { position: usize },
    /// Train in the session of the condition at `position` (queued, running or waiting).
    Training { position: usize, session_id: String },
    /// Answer the survey after the condition at `position`; `ended_early` when its session did
    /// not finish its budget (stopped, failed, interrupted): it is marked so in the results,
    /// and not run again.
    Survey {
        position: usize,
        session_id: String,
        ended_early: bool,
    },
    /// Every condition trained and surveyed.
    Done,
}

/// A participant's session at one position, with its status now.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PositionSession {
    pub position: usize,
    pub session_id: String,
    pub status: Status,
}

/// The step for a participant with `conditions` positions: the first position whose survey is
/// not answered decides it.
pub fn next_step(
    consented: bool,
    conditions: usize,
    sessions: &[PositionSession],
    surveyed: &[usize],
) -> Step {
    if !consented {
        return Step::Consent;
    }
    let Some(position) = (0..conditions).find(|p| !surveyed.contains(p)) else {
        return Step::Done;
    };
    match sessions.iter().find(|s| s.position == position) {
        None => Step::Ready { position },
        Some(s) if s.status.is_active() => Step::Training {
            position,
            session_id: s.session_id.clone(),
        },
        Some(s) => Step::Survey {
            position,
            session_id: s.session_id.clone(),
            ended_early: s.status != Status::Finished,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(position: usize, status: Status) -> PositionSession {
        PositionSession {
            position,
            session_id: format!("s{position}"),
            status,
        }
    }

    #[test]
    fn a_participant_goes_consent_ready_training_survey_and_on_to_done() {
        assert_eq!(next_step(false, 3, &[], &[]), Step::Consent);
        assert_eq!(next_step(true, 3, &[], &[]), Step::Ready { position: 0 });
        let running = [at(0, Status::Queued)];
        assert_eq!(
            next_step(true, 3, &running, &[]),
            Step::Training {
                position: 0,
                session_id: "s0".into()
            }
        );
        let finished = [at(0, Status::Finished)];
        assert_eq!(
            next_step(true, 3, &finished, &[]),
            Step::Survey {
                position: 0,
                session_id: "s0".into(),
                ended_early: false
            }
        );
        assert_eq!(
            next_step(true, 3, &finished, &[0]),
            Step::Ready { position: 1 }
        );
        let all = [
            at(0, Status::Finished),
            at(1, Status::Finished),
            at(2, Status::Finished),
        ];
        assert_eq!(next_step(true, 3, &all, &[0, 1, 2]), Step::Done);
    }

    #[test]
    fn a_session_that_ended_early_goes_to_the_survey_marked_not_to_a_new_session() {
        for status in [Status::Stopped, Status::Failed, Status::Interrupted] {
            assert_eq!(
                next_step(true, 2, &[at(0, status)], &[]),
                Step::Survey {
                    position: 0,
                    session_id: "s0".into(),
                    ended_early: true
                },
                "{status:?}"
            );
        }
    }
}
