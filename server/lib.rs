//! # dualrep
//!
//! Teach robots from a browser: a robot trains its SAC policy in simulation and asks people for
//! guidance, choosing *when* to ask (DREF) and *what* to ask (DRPL) from a symbolic scene graph,
//! after Zhang et al., "A Dual Representation Framework for Robot Learning with Human Guidance"
//! (CoRL 2022).
//!
//! ## Layout
//!
//! The algorithms live in the crate `dualrep-core` (`core/`), which does no IO and cannot: no
//! tokio, axum, sqlx or rerun in its dependency tree. They are re-exported here under their
//! own names, so `dualrep::rl` is `dualrep_core::rl`:
//!
//! - [`sim`]: the `Env` trait and the three tasks on rapier; heuristic controllers; rollouts.
//! - [`scene_graph`]: each task's predicates into an `AbstractState` bit vector.
//! - [`rl`]: MLPs with a hand-written backward pass, Adam, SAC with DREF's twin human critic,
//!   on the portable or the AVX-512 / AVX2 kernels (`kernels/`).
//! - [`guidance`]: when to ask (DREF), who answers, the evaluative training loop, what to ask
//!   (DRPL), and how much trainers agree.
//!
//! The service's own modules that do no IO either:
//!
//! - [`settings`]: every setting by name (`Settings`: flat keys to users, one section per
//!   family inside, the key list read from the sections), read by launch requests, `--set`/TOML,
//!   `GET /api/tasks` and the dashboard.
//! - [`session`]: one training session as a plain loop on its own thread, talking to the
//!   server only through channels; its `SessionPlan` (spec, session settings, run config, scene
//!   graph, query kind) is validated once, at launch or resume, and shared by the hub, the
//!   thread and the trainer's `hello`; pacing, queries to people, replay of stored answers on
//!   resume (on a remote env, which cannot replay, its latest whole-run checkpoint instead, then
//!   the stored answers to the moments it meets again and the stored answered steps it does
//!   not), checkpoints. No async runtime, no database.
//! - [`study`]: human-subject studies (the paper's Figures 4 and 6): what a researcher
//!   launches (conditions, budget, survey, consent), the counterbalanced order (Williams,
//!   random, fixed) in which each participant meets the conditions, where a participant is
//!   (derived from what is stored), the results and their within-subject tests
//!   ([`report::within_subject`]), and the pilot with simulated participants (power before
//!   recruiting).
//!
//! The edge (files, processes, network, database):
//!
//! - [`store`]: SQLite (embedded, the default) or PostgreSQL through sqlx, one SQL text for
//!   both (schemas in `migrations/` and `migrations/postgres/`): sessions, queries, answers,
//!   episodes, checkpoints, trainers, studies.
//! - [`hub`]: the sessions a server runs: a cap on how many at once, one thread each, and one
//!   owner task each that alone holds the session's live state (events, answers, undo,
//!   deadlines and status in one `select!`; commit, then acknowledge); stop, resume and
//!   graceful shutdown; on PostgreSQL, several servers: leases on the sessions each runs, and
//!   relays to those another runs, over LISTEN/NOTIFY (`docs/serving-several.md`).
//! - [`http`]: REST routes (sessions, trainers, datasets, studies and their participants),
//!   security headers, the web UI's files; [`ws`]: the trainer
//!   websocket and its typed protocol; [`api`]: what both share (the app state, who may call,
//!   every refusal and its JSON shape); [`json_input`]: clients' JSON read with errors
//!   that name the field that was wrong.
//! - [`shipped`]: the web UI and the shipped experts, carried inside the binary.
//! - [`remote_env`]: environments in another process or on another machine
//!   (`docs/env-protocol.md`): a blocking TCP client that is an `Env` like the built-in tasks,
//!   with a deadline on every read and a reason for every fault.
//! - [`export`]: a session's datasets for other tools: transitions or preference pairs as
//!   Parquet, the policy as safetensors; a study's tidy table as CSV and Parquet.
//! - [`record`]: the Rerun recording of a session (scene per step, rewards, predicates,
//!   queries and answers on `step` and `episode` timelines) to an `.rrd` file and/or a live
//!   viewer, from a logging thread behind a bounded channel.
//! - [`report`]: the paper's Figures 3 and 5: the run grid, run as child processes here or as
//!   Slurm job array tasks (one executor trait, two implementations), aggregation over seeds,
//!   `table.md`, SVG and PNG figures (aggregation and tables are pure functions); a study's
//!   figure; rank tests.
//! - [`cli`]: the `dualrep` command line: `serve`, `sim`, `train`, `prefs`, `expert`,
//!   `reproduce`, `export`, `bench`, `loadtest`, `study` (create, list, pilot), `report study`.

pub use dualrep_core::{guidance, rl, scene_graph, sim};

pub mod api;
pub mod cli;
pub mod export;
pub mod http;
pub mod hub;
pub mod json_input;
pub mod protocol;
pub mod record;
pub mod remote_env;
pub mod report;
pub mod server;
pub mod session;
pub mod settings;
pub mod shipped;
pub mod store;
pub mod study;
pub mod ws;
