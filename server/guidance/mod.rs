//! Human guidance, free of IO: when to ask (DREF's UCB query rule, the EF-p% baselines) and,
//! later, what to ask (DRPL) and the synthetic trainers that answer.
//!
//! - `query_rule`: DREF's UCB rule over abstract states (Eq. 1-2 and the authors' form).
//! - `feedback_schedule`: which steps ask, per method (DREF, EF-p%, SAC).

pub mod feedback_schedule;
pub mod query_rule;
