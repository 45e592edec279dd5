//! One training session as a plain loop on its own thread. It talks to the async side only
//! through channels (`events`), so it runs unchanged under the server, in tests and headless.
//!
//! - `spec`: what a session is (task, method, trainer kind, seed, budget, parameters).
//! - `plan`: a spec read and checked once, at launch or resume: what the hub, the thread and
//!   the trainer's `hello` share.
//! - `events`: what the loop reports and the controls it obeys; answer values.
//! - `combine`: how several trainers' answers to one query become the one the learner takes.
//! - `query`: what a person is shown (clips, predicates).
//! - `asker`: who answers: stored answers, people through the control channel, or a synthetic
//!   trainer; the observer sees every query and answer. `preference_asker`: who compares a
//!   preference session's pairs, through it.
//! - `runner`: runs the plan; `evaluative_loop` and `preference_loop` drive it:
//!   pacing, frames, asking, replaying stored answers, checkpoints.
//! - `pacing`: what both loops keep besides the algorithm: the pace people watch a session
//!   at, and how often it reports its progress.
//! - `remote`: a session on an env in another process, which resumes from its latest
//!   checkpoint instead of replaying from step 0; `catch_up`: such a resumed session meeting
//!   the moments stored after that checkpoint again, or giving them up (their answered steps
//!   are then taken into the run).

mod asker;
mod catch_up;
pub mod combine;
mod error;
mod evaluative_loop;
pub mod events;
mod pacing;
pub mod plan;
mod preference_asker;
mod preference_loop;
pub mod query;
pub mod remote;
pub mod runner;
pub mod spec;

pub use asker::{load_expert, load_task_expert};
pub use error::{ExpertError, SessionError};
pub use events::{
    AnswerValue, Answerer, Checkpoint, Control, Controls, Ending, Frame, Observer, QueryKind,
    Revision, SessionEvent, SessionSink, StoredRevision,
};
pub use plan::{PlanError, SessionPlan};
pub use query::{Clip, QueryContent, QueryData, QueryRecord, SegmentData};
pub use remote::{QueryNumbering, Reconnect, RemoteSession, StoredMoment};
pub use runner::{SessionContext, digest, run_session};
pub use spec::{SessionMethod, SessionSettings, SessionSpec, TrainerKind, UnknownMethod};
