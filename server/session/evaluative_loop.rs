//! An evaluative session's loop (DREF, EF-p%, SAC): one env step and one learning step per
//! tick, paced for people, frames to browsers, queries through the asker, revisions (undos)
//! applied, checkpoints. On our simulator a resume replays the stored answers from step 0; on
//! a remote env it continues from the latest run checkpoint, catches up on the answers stored
//! after it and takes in the answered steps it does not meet again (module `remote`).

use std::time::Duration;

use super::asker::{Asker, EvaluativeAsker, Judge, load_expert, load_task_expert};
use super::error::SessionError;
use super::events::{
    AnswerValue, Checkpoint, Ending, Frame, Halt, Observer, SessionEvent, SessionSink,
};
use super::pacing::{Pacer, ProgressReports};
use super::query::FrameHistory;
use super::remote::{CheckpointRule, QueryNumbering, RemoteSession, ResumeNotes, take_in_given_up};
use super::runner::{SessionContext, check_replay, halt_ending, revised};
use super::spec::{SessionSettings, SessionSpec, TrainerKind};
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig, StepReport};
use crate::guidance::evaluative_trainer::{Evaluation, NoTrainer};
use crate::guidance::expert_oracle::ExpertOracle;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::rl::Sac;
use crate::sim::{EnvFault, Geometry, RenderState, TaskRef};

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
                        ExpertOracle::new(expert(&ctx, &config.task)?, act_dim)
                            .with_config(config.oracle)
                            .with_faults(config.teacher, config.seed, f64::from(config.sac.gamma)),
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
    let (run, checkpoints, episode) = match remote {
        None => {
            let checkpoints = Checkpoints::Replayable {
                verify,
                every: settings.checkpoint_every,
            };
            (EvaluativeRun::new(config, spec.budget), checkpoints, 0)
        }
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
            // Stored with each query: what a later resume takes back in.
            trainer.asker.keep_steps = true;
            let rule = CheckpointRule::new(settings.checkpoint_every, run.steps(), human);
            (
                run,
                Checkpoints::RemoteResumable { rule, numbering },
                episode,
            )
        }
    };
    let views = StepViews::start(&run, &mut trainer, episode);
    drive(
        spec.budget,
        run,
        trainer,
        views,
        checkpoints,
        Pacer::new(settings.pace_hz),
    )
}

/// The session's loop around [`EvaluativeRun::try_step`]: one env step, a query if the run
/// asks, one learning step, per tick.
fn drive(
    budget: u64,
    mut run: EvaluativeRun,
    mut trainer: EvaluativeAsker,
    mut views: StepViews,
    mut checkpoints: Checkpoints,
    mut pacer: Pacer,
) -> Result<Ending, SessionError> {
    let sink = trainer.asker.sink.clone();
    let mut progress = ProgressReports::every(PROGRESS_EVERY);
    while run.steps() < budget {
        if let Some(h) = trainer.asker.controls.poll() {
            return Ok(end_early(h, &run, sink.as_ref(), false));
        }
        apply_revisions(&mut run, &mut trainer.asker, &checkpoints);
        // The algorithm's step: act, ask if the rule says so, store, learn.
        let report = run
            .try_step(&mut trainer)
            .map_err(|fault| env_failed(&run, sink.as_ref(), fault))?;
        if let Some(h) = trainer.asker.abort_halt() {
            return Ok(end_early(h, &run, sink.as_ref(), true));
        }
        let live = trainer.live();
        views.show(&run, &mut trainer, report, live);
        checkpoints.after_step(&mut run, &mut trainer, views.episode)?;
        progress.tick(sink.as_ref(), run.steps());
        if live && let Some(h) = pacer.wait(&mut trainer.asker.controls) {
            return Ok(end_early(h, &run, sink.as_ref(), false));
        }
    }
    ProgressReports::now(sink.as_ref(), run.steps());
    sink.send(SessionEvent::Checkpoint(evaluative_checkpoint(&run)));
    Ok(Ending::Finished)
}

/// Takes in the undos and new answers due now: the run relabels the queries they revise.
fn apply_revisions(run: &mut EvaluativeRun, asker: &mut Asker, checkpoints: &Checkpoints) {
    for r in asker.due_revisions(run.steps()) {
        let label = r.value.and_then(AnswerValue::as_evaluation);
        if let Some(q) = checkpoints.run_query(r.seq) {
            run.relabel(q, label.unwrap_or(Evaluation::NoFeedback));
        }
        asker.sink.send(revised(r, run.steps()));
    }
}

/// The env failed in a step: the session ends with the step it failed at as its progress (the
/// step its reason names, not the last one reported on the timer).
fn env_failed(run: &EvaluativeRun, sink: &dyn SessionSink, fault: EnvFault) -> SessionError {
    ProgressReports::now(sink, run.steps());
    SessionError::EnvAtStep {
        step: run.steps(),
        fault,
    }
}

impl EvaluativeAsker {
    /// Whether people watch this step: a human session, not catching up on stored answers
    /// after a resume (which shows no frames and is not paced).
    fn live(&self) -> bool {
        matches!(self.judge, Judge::Human { .. }) && !self.asker.replaying()
    }
}

/// What people and the recording see of the steps: the observer's steps and episodes, the
/// human judge's frame history (the clips its queries show), frames to browsers, and the
/// episode counters they are numbered and summed with. Kept apart from the loop so that the
/// step reads plainly there; none of it feeds back into the run.
struct StepViews {
    /// The episode being played (episodes finished, counting those before a resume).
    episode: u64,
    episode_return: f64,
    /// The first frame a browser can see carries the geometry, as every episode's first does
    /// (after a resume, that is the first frame after the replay).
    need_geometry: bool,
    /// The geometry of the episode being played (the env's is the next one's at an episode end).
    episode_geometry: Geometry,
}

impl StepViews {
    /// Starts showing the run as it is now, in episode `episode`: the judge's history and the
    /// recording start an episode.
    fn start(run: &EvaluativeRun, trainer: &mut EvaluativeAsker, episode: u64) -> Self {
        if let Judge::Human { history, .. } = &mut trainer.judge {
            history.start_episode(run.env().geometry(), run.env().render());
        }
        if let Some(o) = trainer.asker.observer.as_deref_mut() {
            o.episode_start(episode, run.steps(), &run.env().geometry());
        }
        Self {
            episode,
            episode_return: 0.0,
            need_geometry: true,
            episode_geometry: run.env().geometry(),
        }
    }

    /// Shows the step just taken: to the recording, to the judge's history, as a frame to
    /// browsers when `live`, and its episode's end if it ended one.
    fn show(
        &mut self,
        run: &EvaluativeRun,
        trainer: &mut EvaluativeAsker,
        report: StepReport,
        live: bool,
    ) {
        self.episode_return += f64::from(report.reward);
        // At an episode's end the env has already reset: show the state it ended in.
        let state = || {
            report
                .final_state
                .clone()
                .unwrap_or_else(|| run.env().render())
        };
        if let Some(o) = trainer.asker.observer.as_deref_mut() {
            self.record(o, run, &report, state());
        }
        if let Judge::Human { history, .. } = &mut trainer.judge {
            let state = state();
            if report.episode.is_some() {
                history.start_episode(run.env().geometry(), run.env().render());
            } else {
                history.push(state.clone());
            }
            if live {
                trainer.asker.sink.send(self.frame(run, &report, state));
            }
        }
        if let Some(e) = report.episode {
            self.need_geometry = true;
            self.episode_geometry = run.env().geometry();
            trainer.asker.sink.send(SessionEvent::Episode(e));
            self.episode += 1;
            self.episode_return = 0.0;
        }
    }

    fn record(
        &self,
        o: &mut dyn Observer,
        run: &EvaluativeRun,
        report: &StepReport,
        state: RenderState,
    ) {
        // At an episode's end `run` has already counted its return.
        let cumulative = run.cumulative_return()
            + if report.episode.is_some() {
                0.0
            } else {
                self.episode_return
            };
        let step = run.steps() - 1;
        o.step(
            step,
            self.episode,
            &state,
            report.reward,
            cumulative,
            report.abstract_state,
        );
        if report.episode.is_some() {
            o.episode_start(self.episode + 1, run.steps(), &run.env().geometry());
        }
    }

    fn frame(
        &mut self,
        run: &EvaluativeRun,
        report: &StepReport,
        state: RenderState,
    ) -> SessionEvent {
        let geometry =
            std::mem::take(&mut self.need_geometry).then(|| self.episode_geometry.clone());
        SessionEvent::Frame(Box::new(Frame {
            step: run.steps(),
            episode: self.episode,
            state,
            geometry,
            reward: report.reward,
            episode_return: self.episode_return,
        }))
    }
}

/// When a session checkpoints, by how it resumes.
enum Checkpoints {
    /// On our simulator a resume replays the stored answers from step 0: the replay is checked
    /// against the checkpoint it resumes from (`verify`), and the learner is kept every `every`
    /// steps.
    Replayable {
        verify: Option<(u64, String)>,
        every: u64,
    },
    /// A remote env cannot replay: the whole run is kept at episode starts, as `rule` says,
    /// with the numbering of the session's queries among the run's (module `remote`).
    RemoteResumable {
        rule: CheckpointRule,
        numbering: QueryNumbering,
    },
}

impl Checkpoints {
    /// The run's query index of session query `seq` (`None`: a remote session's run lost it
    /// with an episode).
    fn run_query(&self, seq: u64) -> Option<usize> {
        match self {
            Checkpoints::Replayable { .. } => Some(seq as usize),
            Checkpoints::RemoteResumable { numbering, .. } => numbering.run_query(seq),
        }
    }

    /// After a step, in episode `episode`: checks the replay, or settles the catch-up and takes
    /// in what it gave up on; and checkpoints if one is due.
    fn after_step(
        &mut self,
        run: &mut EvaluativeRun,
        trainer: &mut EvaluativeAsker,
        episode: u64,
    ) -> Result<(), SessionError> {
        match self {
            Checkpoints::Replayable { verify, every } => {
                check_replay(verify, run.steps(), || learner_digest(run))?;
                if run.steps().is_multiple_of(*every) {
                    let c = evaluative_checkpoint(run);
                    trainer.asker.sink.send(SessionEvent::Checkpoint(c));
                }
            }
            Checkpoints::RemoteResumable { rule, numbering } => {
                trainer.asker.settle_catch_up(run.steps());
                for given_up in trainer.asker.take_given_up() {
                    take_in_given_up(run, numbering, given_up)?;
                }
                if trainer.asker.take_answered() {
                    rule.answered();
                }
                if run.at_episode_start() && rule.due(run.steps()) {
                    numbering.next = trainer.asker.seq;
                    let notes = ResumeNotes {
                        numbering: numbering.clone(),
                        episode,
                    };
                    let notes = serde_json::to_value(notes).expect("notes serialise");
                    let mut c = evaluative_checkpoint(run);
                    c.resume = Some(run.checkpoint(trainer, notes));
                    trainer.asker.sink.send(SessionEvent::Checkpoint(c));
                }
            }
        }
        Ok(())
    }
}

/// Leave early: on shutdown, checkpoint first unless the last step used an answer nobody gave
/// (a replay could not reproduce it; the previous checkpoint stands).
fn end_early(h: Halt, run: &EvaluativeRun, sink: &dyn SessionSink, aborted: bool) -> Ending {
    if h == Halt::Shutdown && !aborted {
        sink.send(SessionEvent::Checkpoint(evaluative_checkpoint(run)));
    }
    halt_ending(h)
}
