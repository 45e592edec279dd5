//! Human guidance, free of IO: when to ask (DREF's UCB query rule, the EF-p% baselines), what to
//! ask (DRPL), and the synthetic trainers that answer.
//!
//! - `query_rule`: DREF's UCB rule over abstract states (Eq. 1-2 and the authors' form).
//! - `recent_visits`, `ask_budget`: the product DREF's rank among recent visits and its ceiling on
//!   the rate of queries (`docs/dref.md`); the authors' rule uses neither.
//! - `visit_share`: where a paced opening (or a repayment's spare) asks: by rank, or each state
//!   its share of its visits.
//! - `ask_pacing`: a rule's floods and freezes, as runs, sessions and grids report them.
//! - `feedback_schedule`: which steps ask, per method (DREF, EF-p%, SAC).
//! - `evaluative_trainer`: the `EvaluativeTrainer` trait (synthetic oracle or a person) and H.
//! - `expert_oracle`: the synthetic trainer, a SAC expert's critic judging the learner's action.
//! - `teacher`: simulated teachers' faults after B-Pref (Boltzmann rationality, myopia, errors,
//!   skip and "about equal" thresholds), shared by both synthetic oracles.
//! - `mix_gate`: the answered mix's gates on the run's own outcomes (how much of H the actor
//!   reads where nobody answered).
//! - `human_pace`: at most N queries a minute, for people (the query rule still picks which).
//! - `agreement`: how much trainers agree (Krippendorff's alpha, Fleiss' kappa).
//! - `evaluative_config`: what defines a run (task, method, constants; its `config.json`).
//! - `evaluative_run`: one SAC / EF-p% / DREF run, step by step, and policy evaluation; its
//!   `run_checkpoint` saves a whole run between episodes so a long one resumes bit for bit, and
//!   its `run_take_in` gives a resumed run the steps answered after its checkpoint (a session
//!   on a remote env, whose robot does not bring those moments back).
//! - `drpl`: what to ask: DRPL's scene-graph segments and pairs, its baselines, the belief over
//!   the reward weights (APReL's sampling-based belief), acquisition, the synthetic preference
//!   oracle and the preference run.

pub mod agreement;
pub mod ask_budget;
pub mod ask_pacing;
pub mod drpl;
pub mod evaluative_config;
pub mod evaluative_run;
pub mod evaluative_trainer;
pub mod expert_oracle;
pub mod feedback_schedule;
pub mod human_pace;
pub mod mix_gate;
pub mod query_rule;
pub mod recent_visits;
pub mod teacher;
pub mod visit_share;
