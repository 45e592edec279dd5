//! The session loop: builds the run from its spec and drives it on the calling thread (the
//! server gives each session its own), pacing human sessions to a watchable rate, streaming
//! frames, asking people through the control channel, replaying stored answers after a resume,
//! and checkpointing.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::guidance::drpl::pool::QueryPool;
use crate::guidance::drpl::posterior_file::posterior_safetensors;
use crate::guidance::drpl::run::PreferenceRun;
use crate::guidance::drpl::simulated_teacher::SimulatedTeacher;
use crate::guidance::drpl::trainer::Preference;
use crate::guidance::drpl::trajectories::Trajectory;
use crate::guidance::evaluative_run::EvaluativeRun;
use crate::guidance::evaluative_trainer::{Evaluation, NoTrainer};
use crate::guidance::expert_oracle::{ExpertOracle, OracleRule};
use crate::guidance::feedback_schedule::EvaluativeMethod;

use super::asker::{Asker, Comparer, EvaluativeAsker, Judge, PreferenceAsker, load_task_expert};
use super::events::{
    AnswerValue, Checkpoint, Controls, Ending, Frame, Halt, Observer, Revision, SessionEvent,
    SessionSink, StoredRevision,
};
use super::query::FrameHistory;
use super::spec::{RunConfig, SessionSettings, SessionSpec, TrainerKind};

/// How often a running session reports its progress.
const PROGRESS_EVERY: Duration = Duration::from_millis(250);

/// Everything a session thread gets besides its spec.
pub struct SessionContext {
    pub sink: Arc<dyn SessionSink>,
    pub controls: Controls,
    /// Answers already stored for this session, by query order: replayed, never asked again.
    pub stored_answers: Vec<AnswerValue>,
    /// Revisions of stored answers (undos), ordered by the progress they were applied at.
    pub stored_revisions: Vec<StoredRevision>,
    /// The latest checkpoint `(progress, digest)`: a resumed session checks its replay against it.
    pub verify: Option<(u64, String)>,
    /// Where the synthetic trainer's experts live (`<dir>/<task>.safetensors`).
    pub models_dir: Option<PathBuf>,
    /// Sees every step, query and answer (the recording), if any.
    pub observer: Option<Box<dyn Observer>>,
}

/// Run the session to its end and report how it ended (also sent as `SessionEvent::Ended`).
pub fn run_session(spec: &SessionSpec, ctx: SessionContext) -> Ending {
    let sink = ctx.sink.clone();
    let ending = match run(spec, ctx) {
        Ok(ending) => ending,
        Err(reason) => Ending::Failed(reason),
    };
    sink.send(SessionEvent::Ended(ending.clone()));
    ending
}

/// Builds the run and drives it. The observer (the recording) goes with the trainer and is
/// dropped, and so flushed, before the session reports its end.
fn run(spec: &SessionSpec, mut ctx: SessionContext) -> Result<Ending, String> {
    let observer = ctx.observer.take();
    let settings = spec.settings()?;
    match spec.run_config()? {
        RunConfig::Evaluative(config) => {
            let run = EvaluativeRun::new(config, spec.budget);
            run_evaluative(spec, settings, run, ctx, observer)
        }
        RunConfig::Preference(config) => {
            // As `PreferenceRun::new`, but keeping the trajectories to render clips from.
            let trajs = PreferenceRun::record_trajectories(&config);
            let pool = QueryPool::from_trajectories(config.task, &trajs, config.min_run);
            let run = PreferenceRun::with_pool(config, pool);
            run_preference(spec, run, trajs, ctx, observer)
        }
    }
}

/// FNV-1a over bytes, as hex: a digest that is stable across builds and platforms.
pub fn digest(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{hash:016x}")
}

/// Ends the loop early when the replay does not reproduce the checkpoint it resumes from.
fn check_replay(
    verify: &Option<(u64, String)>,
    progress: u64,
    digest_now: impl FnOnce() -> String,
) -> Result<(), String> {
    match verify {
        Some((at, expected)) if *at == progress => {
            let got = digest_now();
            if &got == expected {
                Ok(())
            } else {
                Err(format!(
                    "the resumed session's replay diverged from its checkpoint at {progress} (digest {got}, stored {expected})"
                ))
            }
        }
        _ => Ok(()),
    }
}

fn revised(r: Revision, progress: u64) -> SessionEvent {
    SessionEvent::Revised {
        seq: r.seq,
        revision: r.revision,
        progress,
    }
}

fn halt_ending(h: Halt) -> Ending {
    match h {
        Halt::Stop => Ending::Stopped,
        Halt::Shutdown => Ending::Interrupted,
    }
}

/// The learner's state checksum (not a hash of its safetensors bytes, whose metadata order
/// varies from call to call).
fn learner_digest(run: &EvaluativeRun) -> String {
    format!("{:016x}", run.learner().state_checksum())
}

fn evaluative_checkpoint(run: &EvaluativeRun) -> Checkpoint {
    Checkpoint {
        progress: run.steps(),
        answers: run.feedback_count(),
        digest: learner_digest(run),
        weights: Some(run.learner().to_safetensors()),
    }
}

fn run_evaluative(
    spec: &SessionSpec,
    settings: SessionSettings,
    mut run: EvaluativeRun,
    mut ctx: SessionContext,
    observer: Option<Box<dyn Observer>>,
) -> Result<Ending, String> {
    let human = spec.trainer == TrainerKind::Human;
    let judge = if human {
        let mut history = FrameHistory::new(settings.clip_frames);
        history.start_episode(run.env().geometry(), run.env().render());
        Judge::Human {
            history,
            graph: run.config().scene_graph,
        }
    } else {
        Judge::Synthetic {
            oracle: match run.config().method {
                EvaluativeMethod::Sac => Box::new(NoTrainer),
                _ => {
                    let expert = load_task_expert(ctx.models_dir.as_deref(), spec.task)?;
                    let act_dim = run.env().spec().action_space.dim();
                    let config = run.config();
                    Box::new(
                        ExpertOracle::new(expert, act_dim, OracleRule::Authors).with_faults(
                            config.teacher,
                            config.seed,
                            f64::from(config.sac.gamma),
                        ),
                    )
                }
            },
            graph: run.config().scene_graph,
        }
    };
    let sink = ctx.sink.clone();
    let verify = ctx.verify.take();
    let mut trainer = EvaluativeAsker {
        asker: Asker::start(ctx, observer),
        judge,
    };

    if let Some(o) = trainer.asker.observer.as_deref_mut() {
        o.episode_start(0, 0, &run.env().geometry());
    }
    let period = Duration::from_secs_f64(1.0 / settings.pace_hz);
    let mut next_tick = Instant::now();
    let mut last_progress = Instant::now();
    // The first frame a browser can see carries the geometry, as every episode's first does
    // (after a resume, that is the first frame after the replay).
    let (mut episode, mut episode_return, mut need_geometry) = (0u64, 0.0f64, true);
    // The geometry of the episode being played (the env's is the next one's at an episode end).
    let mut episode_geometry = run.env().geometry();
    while run.steps() < spec.budget {
        if let Some(h) = trainer.asker.controls.poll() {
            return Ok(end_evaluative(h, &run, sink.as_ref(), false));
        }
        for r in trainer.asker.due_revisions(run.steps()) {
            let label = r.value.and_then(AnswerValue::as_evaluation);
            run.relabel(r.seq as usize, label.unwrap_or(Evaluation::NoFeedback));
            sink.send(revised(r, run.steps()));
        }
        let report = run.step(&mut trainer);
        if trainer.asker.aborted {
            let h = trainer.asker.controls.halted().unwrap_or(Halt::Shutdown);
            return Ok(end_evaluative(h, &run, sink.as_ref(), true));
        }
        episode_return += f64::from(report.reward);
        if let Some(o) = trainer.asker.observer.as_deref_mut() {
            let step = run.steps() - 1;
            let state = report
                .final_state
                .clone()
                .unwrap_or_else(|| run.env().render());
            // At an episode's end `run` has already counted its return.
            let cumulative = run.cumulative_return()
                + if report.episode.is_some() {
                    0.0
                } else {
                    episode_return
                };
            o.step(
                step,
                episode,
                &state,
                report.reward,
                cumulative,
                report.abstract_state,
            );
            if report.episode.is_some() {
                o.episode_start(episode + 1, run.steps(), &run.env().geometry());
            }
        }
        // Catching up on stored answers after a resume: no frames, no pacing.
        let live = human && !trainer.asker.replaying();
        if let Judge::Human { history, .. } = &mut trainer.judge {
            // At an episode's end the env has already reset: show the state it ended in.
            let state = report
                .final_state
                .clone()
                .unwrap_or_else(|| run.env().render());
            if report.episode.is_some() {
                history.start_episode(run.env().geometry(), run.env().render());
            } else {
                history.push(state.clone());
            }
            if live {
                sink.send(SessionEvent::Frame(Box::new(Frame {
                    step: run.steps(),
                    episode,
                    state,
                    geometry: std::mem::take(&mut need_geometry).then(|| episode_geometry.clone()),
                    reward: report.reward,
                    episode_return,
                })));
            }
        }
        if report.episode.is_some() {
            need_geometry = true;
            episode_geometry = run.env().geometry();
        }
        if let Some(e) = report.episode {
            sink.send(SessionEvent::Episode(e));
            episode += 1;
            episode_return = 0.0;
        }
        check_replay(&verify, run.steps(), || learner_digest(&run))?;
        if settings.checkpoint_every > 0 && run.steps().is_multiple_of(settings.checkpoint_every) {
            sink.send(SessionEvent::Checkpoint(evaluative_checkpoint(&run)));
        }
        if last_progress.elapsed() >= PROGRESS_EVERY {
            last_progress = Instant::now();
            sink.send(SessionEvent::Progress {
                progress: run.steps(),
            });
        }
        if live {
            next_tick += period;
            let now = Instant::now();
            if next_tick > now {
                if let Some(h) = trainer.asker.controls.sleep(next_tick - now) {
                    return Ok(end_evaluative(h, &run, sink.as_ref(), false));
                }
            } else {
                // Running behind (a slow update or a long wait for an answer): go on at the
                // pace from here rather than catching up in a burst.
                next_tick = now;
            }
        }
    }
    sink.send(SessionEvent::Progress {
        progress: run.steps(),
    });
    sink.send(SessionEvent::Checkpoint(evaluative_checkpoint(&run)));
    Ok(Ending::Finished)
}

/// Leave early: on shutdown, checkpoint first unless the last step used an answer nobody gave
/// (a replay could not reproduce it; the previous checkpoint stands).
fn end_evaluative(h: Halt, run: &EvaluativeRun, sink: &dyn SessionSink, aborted: bool) -> Ending {
    if h == Halt::Shutdown && !aborted {
        sink.send(SessionEvent::Checkpoint(evaluative_checkpoint(run)));
    }
    halt_ending(h)
}

fn preference_checkpoint(run: &PreferenceRun) -> Checkpoint {
    let mean: Vec<u8> = run
        .belief()
        .mean()
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let names = crate::guidance::drpl::features::names(run.config().task);
    Checkpoint {
        progress: run.queries() as u64,
        answers: run.queries() as u64,
        digest: digest(&mean),
        // The posterior, for `GET .../posterior.safetensors` and `dualrep export`.
        weights: Some(posterior_safetensors(run.belief(), names, run.queries())),
    }
}

fn run_preference(
    spec: &SessionSpec,
    mut run: PreferenceRun,
    trajectories: Vec<Trajectory>,
    mut ctx: SessionContext,
    observer: Option<Box<dyn Observer>>,
) -> Result<Ending, String> {
    let comparer = match spec.trainer {
        TrainerKind::Human => Comparer::Human {
            task: spec.task,
            env: run.config().env,
            graph: run.config().scene_graph,
            trajectories,
        },
        TrainerKind::Synthetic => Comparer::Synthetic {
            oracle: Box::new(SimulatedTeacher::new(
                run.theta_true().to_vec(),
                run.config().teacher,
                run.teacher_seed(),
                run.pool(),
            )),
            graph: run.config().scene_graph,
        },
    };
    let sink = ctx.sink.clone();
    let verify = ctx.verify.take();
    let mut trainer = PreferenceAsker {
        asker: Asker::start(ctx, observer),
        comparer,
    };
    while (run.queries() as u64) < spec.budget {
        if let Some(h) = trainer.asker.controls.poll() {
            // Between queries the posterior is whole: keep it (a stopped session's too, so its
            // posterior can be exported).
            sink.send(SessionEvent::Checkpoint(preference_checkpoint(&run)));
            return Ok(halt_ending(h));
        }
        let progress = run.queries() as u64;
        for r in trainer.asker.due_revisions(progress) {
            let preference = r.value.and_then(AnswerValue::as_preference);
            run.revise(r.seq as usize, preference.unwrap_or(Preference::Skip));
            sink.send(revised(r, progress));
            sink.send(SessionEvent::Alignment {
                queries: progress,
                alignment: run.alignment(),
                alignment_of_mean: run.alignment_of_mean(),
            });
        }
        let Some(report) = run.step(&mut trainer) else {
            break; // the method has no new pair left
        };
        if trainer.asker.aborted {
            let h = trainer.asker.controls.halted().unwrap_or(Halt::Shutdown);
            return Ok(halt_ending(h));
        }
        sink.send(SessionEvent::Alignment {
            queries: report.query as u64,
            alignment: report.alignment,
            alignment_of_mean: report.alignment_of_mean,
        });
        sink.send(SessionEvent::Progress {
            progress: run.queries() as u64,
        });
        check_replay(&verify, run.queries() as u64, || {
            preference_checkpoint(&run).digest
        })?;
    }
    sink.send(SessionEvent::Checkpoint(preference_checkpoint(&run)));
    Ok(Ending::Finished)
}
