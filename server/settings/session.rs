//! The session's own settings: the server's human and synthetic sessions read them, a headless
//! run refuses them. The section as given, and [`SessionSettings`], its values with defaults.

use serde::{Deserialize, Serialize};

use super::people;
use super::{Combine, SettingsError};
use crate::rl::kernels::KernelPath;

/// A human session's control rate when the researcher does not set `pace_hz`: the robot's own.
pub const DEFAULT_PACE_HZ: f64 = 20.0;
/// How long a query waits for a person before it counts as "no feedback" (or a skipped pair).
pub const DEFAULT_ANSWER_TIMEOUT_S: f64 = 60.0;
/// Environment steps between periodic checkpoints of evaluative sessions.
pub const DEFAULT_CHECKPOINT_EVERY: u64 = 5_000;
/// Frames of the clip that leads up to an evaluative query (1.5 s at 20 Hz).
pub const DEFAULT_CLIP_FRAMES: usize = 30;
/// Seconds a remote env may take to answer one request (a robot's reset included).
pub const DEFAULT_ENV_TIMEOUT_S: f64 = 30.0;

/// The session's settings as given.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct SessionSection {
    /// Steps per second of a human session while people watch [default 20, at most 1000].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pace_hz: Option<f64>,
    /// Seconds a query waits for a person before it counts as "no feedback" [default 60].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub answer_timeout_s: Option<f64>,
    /// Steps (or queries) between a session's checkpoints [default 5000].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checkpoint_every: Option<u64>,
    /// Frames of the clip before an evaluative query [default 30].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clip_frames: Option<usize>,
    /// Write the session's Rerun recording [default true].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record: Option<bool>,
    /// Also stream the session to a running Rerun viewer at this URL.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rerun_connect: Option<String>,
    /// Seconds a remote env (`env: {"url": ...}`) may take to answer one request [default 30].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env_timeout_s: Option<f64>,
    /// The kernels the session's networks compute with: `portable`, `avx2` or `avx512` [default
    /// the server's, recorded at launch so that a resume replays with the same numerics].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kernels: Option<KernelPath>,
    /// Answers each query takes from different named trainers [default 1].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub answers_per_query: Option<usize>,
    /// How a query's answers combine: `first` (one answer, the first), `majority` or `mean`
    /// (evaluative), `each` (preference: every answer its own observation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub combine: Option<Combine>,
}

/// The session's own settings, with their defaults filled in.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SessionSettings {
    pub pace_hz: f64,
    pub answer_timeout_s: f64,
    pub checkpoint_every: u64,
    pub clip_frames: usize,
    /// Write the session's Rerun recording (`<data dir>/recordings/<id>.rrd`).
    pub record: bool,
    /// Also stream to a running Rerun viewer at this URL (else the server's `--rerun-connect`).
    pub rerun_connect: Option<String>,
    /// Seconds a remote env may take to answer one request.
    pub env_timeout_s: f64,
    /// The kernels the session computes with; `None` for sessions stored before they were
    /// recorded (the server's then).
    pub kernels: Option<KernelPath>,
    /// Answers each query takes (from different named trainers).
    pub answers_per_query: usize,
    /// How they combine.
    pub combine: Combine,
}

impl SessionSection {
    /// What `GET /api/tasks` offers: every session setting with a default, at it.
    pub(super) fn offered() -> Self {
        Self {
            pace_hz: Some(DEFAULT_PACE_HZ),
            answer_timeout_s: Some(DEFAULT_ANSWER_TIMEOUT_S),
            checkpoint_every: Some(DEFAULT_CHECKPOINT_EVERY),
            clip_frames: Some(DEFAULT_CLIP_FRAMES),
            record: Some(true),
            env_timeout_s: Some(DEFAULT_ENV_TIMEOUT_S),
            answers_per_query: Some(1),
            combine: Some(Combine::First),
            rerun_connect: None,
            kernels: None,
        }
    }

    /// The values with defaults, checked.
    pub(super) fn resolve(&self) -> Result<SessionSettings, SettingsError> {
        let positive =
            |key: &'static str, v: Option<f64>, default: f64| -> Result<f64, SettingsError> {
                match v {
                    None => Ok(default),
                    Some(x) if x.is_finite() && x > 0.0 => Ok(x),
                    Some(x) => Err(SettingsError::bad(
                        key,
                        format!("expected a positive number, got {x}"),
                    )),
                }
            };
        let pace_hz = positive("pace_hz", self.pace_hz, DEFAULT_PACE_HZ)?;
        if pace_hz > 1000.0 {
            return Err(SettingsError::bad(
                "pace_hz",
                format!("at most 1000, got {pace_hz}"),
            ));
        }
        let at_least_one =
            |key: &'static str, v: Option<u64>, default: u64| -> Result<u64, SettingsError> {
                match v {
                    None => Ok(default),
                    Some(0) => Err(SettingsError::bad(key, "expected at least 1")),
                    Some(n) => Ok(n),
                }
            };
        if self.rerun_connect.as_deref() == Some("") {
            return Err(SettingsError::bad(
                "rerun_connect",
                "expected a viewer URL, got an empty string",
            ));
        }
        let (answers_per_query, combine) = people::answers(self.answers_per_query, self.combine)?;
        Ok(SessionSettings {
            pace_hz,
            answer_timeout_s: positive(
                "answer_timeout_s",
                self.answer_timeout_s,
                DEFAULT_ANSWER_TIMEOUT_S,
            )?,
            checkpoint_every: at_least_one(
                "checkpoint_every",
                self.checkpoint_every,
                DEFAULT_CHECKPOINT_EVERY,
            )?,
            clip_frames: at_least_one(
                "clip_frames",
                self.clip_frames.map(|n| n as u64),
                DEFAULT_CLIP_FRAMES as u64,
            )? as usize,
            record: self.record.unwrap_or(true),
            rerun_connect: self.rerun_connect.clone(),
            env_timeout_s: positive("env_timeout_s", self.env_timeout_s, DEFAULT_ENV_TIMEOUT_S)?,
            kernels: self.kernels,
            answers_per_query,
            combine,
        })
    }
}
