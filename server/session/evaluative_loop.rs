//! An evaluative session's loop (DREF, EF-p%, SAC): one env step and one learning step per
//! tick, paced for people, frames to browsers, queries through the asker, revisions (undos)
//! applied, checkpoints. On our simulator a resume replays the stored answers from step 0; on
//! a remote env it continues from the latest run checkpoint and catches up on the answers
//! stored after it (module `remote`).

use std::time::{Duration, Instant};

use super::asker::{Asker, EvaluativeAsker, Judge, load_expert, load_task_expert};
use super::error::SessionError;
use super::events::{
    AnswerValue, Checkpoint, Ending, Frame, Halt, Observer, SessionEvent, SessionSink,
};
use super::query::FrameHistory;
use super::remote::{CheckpointRule, QueryNumbering, RemoteSession, ResumeNotes};
use super::runner::{SessionContext, check_replay, halt_ending, revised};
use super::spec::{SessionSettings, SessionSpec, TrainerKind};
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig};
use crate::guidance::evaluative_trainer::{Evaluation, NoTrainer};
use crate::guidance::expert_oracle::{ExpertOracle, OracleRule};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::rl::Sac;
use crate::sim::TaskRef;

/// How often a running session reports its progress.
const PROGRESS_EVERY: Duration = Duration::from_millis(250);

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
        resume: None,
    }
}

/// The expert a synthetic DREF or EF session consults: ours for our tasks; for a remote env's
/// own task, `<models dir>/<env id>.safetensors`.
fn expert(ctx: &SessionContext, task: &TaskRef) -> Result<Sac, SessionError> {
    Ok(match task {
        TaskRef::Builtin(t) => load_task_expert(ctx.models_dir.as_deref(), *t)?,
        TaskRef::Declared(d) => match ctx.models_dir.as_deref() {
            Some(dir) => load_expert(&dir.join(format!("{}.safetensors", d.env)), &d.env)?,
            None => {
                return Err(SessionError::NoModelsDir {
                    env: d.env.to_string(),
                });
            }
        },
    })
}

/// The remote part of a session: its run checkpoints and query numbering.
struct Resumable {
    rule: CheckpointRule,
    numbering: QueryNumbering,
}

pub(super) fn run(
    spec: &SessionSpec,
    settings: SessionSettings,
    config: EvaluativeRunConfig,
    remote: Option<RemoteSession>,
    mut ctx: SessionContext,
    observer: Option<Box<dyn Observer>>,
) -> Result<Ending, SessionError> {
    let human = spec.trainer == TrainerKind::Human;
    let graph = config.scene_graph;
    let judge = if human {
        Judge::Human {
            history: FrameHistory::new(settings.clip_frames),
            graph,
        }
    } else {
        Judge::Synthetic {
            oracle: match config.method {
                EvaluativeMethod::Sac => Box::new(NoTrainer),
                _ => {
                    let act_dim = match &remote {
                        Some(r) => r.description.action_dim(),
                        None => config.make_env().spec().action_space.dim(),
                    };
                    Box::new(
                        ExpertOracle::new(
                            expert(&ctx, &config.task)?,
                            act_dim,
                            OracleRule::Authors,
                        )
                        .with_config(config.oracle)
                        .with_faults(
                            config.teacher,
                            config.seed,
                            f64::from(config.sac.gamma),
                        ),
                    )
                }
            },
            graph,
        }
    };
    let verify = ctx.verify.take();
    let mut trainer = EvaluativeAsker {
        asker: Asker::start(ctx, observer, graph),
        judge,
    };
    let (run, resumable, episode) = match remote {
        None => (EvaluativeRun::new(config, spec.budget), None, 0),
        Some(r) => {
            let RemoteSession {
                mut env,
                resume_from,
                stored_queries,
                stored_moments,
                ..
            } = r;
            env.set_frames(human);
            let (run, saved, episode) = match resume_from {
                Some(bytes) => {
                    let (run, notes) =
                        EvaluativeRun::resume_with_env(&bytes, &config, Some(env), &mut trainer)
                            .map_err(SessionError::Resume)?;
                    let notes: ResumeNotes =
                        serde_json::from_value(notes).map_err(SessionError::ResumeNotes)?;
                    (run, Some(notes.numbering), notes.episode)
                }
                None => (EvaluativeRun::with_env(config, env, spec.budget)?, None, 0),
            };
            // The numbering as of the checkpoint: the catch-up adds what it gives up on.
            let numbering = saved.unwrap_or_default();
            trainer
                .asker
                .continue_at(numbering.next, stored_queries, run.steps(), stored_moments);
            let rule = CheckpointRule::new(settings.checkpoint_every, run.steps(), human);
            (run, Some(Resumable { rule, numbering }), episode)
        }
    };
    drive(spec, settings, run, trainer, verify, resumable, episode)
}

fn drive(
    spec: &SessionSpec,
    settings: SessionSettings,
    mut run: EvaluativeRun,
    mut trainer: EvaluativeAsker,
    verify: Option<(u64, String)>,
    mut resumable: Option<Resumable>,
    first_episode: u64,
) -> Result<Ending, SessionError> {
    let human = spec.trainer == TrainerKind::Human;
    let sink = trainer.asker.sink.clone();
    if let Judge::Human { history, .. } = &mut trainer.judge {
        history.start_episode(run.env().geometry(), run.env().render());
    }
    if let Some(o) = trainer.asker.observer.as_deref_mut() {
        o.episode_start(first_episode, run.steps(), &run.env().geometry());
    }
    let period = Duration::from_secs_f64(1.0 / settings.pace_hz);
    let mut next_tick = Instant::now();
    let mut last_progress = Instant::now();
    // The first frame a browser can see carries the geometry, as every episode's first does
    // (after a resume, that is the first frame after the replay).
    let (mut episode, mut episode_return, mut need_geometry) = (first_episode, 0.0f64, true);
    // The geometry of the episode being played (the env's is the next one's at an episode end).
    let mut episode_geometry = run.env().geometry();
    while run.steps() < spec.budget {
        if let Some(h) = trainer.asker.controls.poll() {
            return Ok(end_evaluative(h, &run, sink.as_ref(), false));
        }
        for r in trainer.asker.due_revisions(run.steps()) {
            let label = r.value.and_then(AnswerValue::as_evaluation);
            // A remote session's run may have lost the query with an episode.
            let query = match &resumable {
                Some(x) => x.numbering.run_query(r.seq),
                None => Some(r.seq as usize),
            };
            if let Some(q) = query {
                run.relabel(q, label.unwrap_or(Evaluation::NoFeedback));
            }
            sink.send(revised(r, run.steps()));
        }
        let report = run.try_step(&mut trainer).map_err(|fault| {
            // The progress the session ends with is the step its reason names, not the last
            // one reported on the timer.
            sink.send(SessionEvent::Progress {
                progress: run.steps(),
            });
            SessionError::EnvAtStep {
                step: run.steps(),
                fault,
            }
        })?;
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
        match &mut resumable {
            None => {
                check_replay(&verify, run.steps(), || learner_digest(&run))?;
                if run.steps().is_multiple_of(settings.checkpoint_every) {
                    sink.send(SessionEvent::Checkpoint(evaluative_checkpoint(&run)));
                }
            }
            Some(x) => {
                trainer.asker.settle_catch_up(run.steps());
                x.numbering.lost.extend(trainer.asker.take_lost());
                if trainer.asker.take_answered() {
                    x.rule.answered();
                }
                if run.at_episode_start() && x.rule.due(run.steps()) {
                    x.numbering.next = trainer.asker.seq;
                    let notes = ResumeNotes {
                        numbering: x.numbering.clone(),
                        episode,
                    };
                    let notes = serde_json::to_value(notes).expect("notes serialise");
                    let mut c = evaluative_checkpoint(&run);
                    c.resume = Some(run.checkpoint(&trainer, notes));
                    sink.send(SessionEvent::Checkpoint(c));
                }
            }
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
