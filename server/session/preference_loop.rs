//! A preference session's loop (DRPL and its baselines): record the trajectories (on our
//! simulator, or on the remote env, keeping them for a resume), then pick a pair, ask, update
//! the belief, query after query; a resume replays the stored answers over the same pool.

use super::asker::Asker;
use super::error::SessionError;
use super::events::{AnswerValue, Checkpoint, Ending, Observer, SessionEvent};
use super::pacing::ProgressReports;
use super::preference_asker::{ClipEnv, Comparer, PreferenceAsker};
use super::remote::RemoteSession;
use super::runner::{SessionContext, check_replay, digest, halt_ending, revised};
use super::spec::{SessionSpec, TrainerKind};
use crate::guidance::drpl::pool::QueryPool;
use crate::guidance::drpl::posterior_file::posterior_safetensors;
use crate::guidance::drpl::run::{PreferenceRun, PreferenceRunConfig};
use crate::guidance::drpl::simulated_teacher::SimulatedTeacher;
use crate::guidance::drpl::trainer::Preference;
use crate::guidance::drpl::trajectories::Trajectory;
use crate::guidance::drpl::trajectory_bytes;
use crate::sim::TaskRef;

fn preference_checkpoint(run: &PreferenceRun) -> Checkpoint {
    let mean: Vec<u8> = run
        .belief()
        .mean()
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let names = crate::guidance::drpl::features::names_of(&run.config().task);
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    Checkpoint {
        progress: run.queries() as u64,
        answers: run.queries() as u64,
        digest: digest(&mean),
        // The posterior, for `GET .../posterior.safetensors` and `dualrep export`.
        weights: Some(posterior_safetensors(run.belief(), &names, run.queries())),
        resume: None,
    }
}

pub(super) fn run(
    spec: &SessionSpec,
    config: PreferenceRunConfig,
    remote: Option<RemoteSession>,
    mut ctx: SessionContext,
    observer: Option<Box<dyn Observer>>,
) -> Result<Ending, SessionError> {
    let human = spec.trainer == TrainerKind::Human;
    if let Some(r) = &remote
        && human
        && !r.description.deterministic
    {
        return Err(SessionError::NotDeterministic {
            env: r.description.spec.id.to_string(),
        });
    }
    let verify = ctx.verify.take();
    let sink = ctx.sink.clone();
    let graph = config.scene_graph;
    let asker = Asker::start(ctx, observer, graph);
    // As `PreferenceRun::new`, but keeping the trajectories to render clips from.
    let (trajectories, clips, recorded) = match remote {
        None => {
            let task = config.task.builtin().expect("our simulator runs our tasks");
            let clips = ClipEnv::Builtin {
                task,
                options: config.env,
            };
            (PreferenceRun::record_trajectories(&config), clips, None)
        }
        Some(r) => {
            let RemoteSession {
                mut env,
                resume_from,
                reconnect,
                ..
            } = r;
            let (trajectories, recorded) = match resume_from {
                Some(bytes) => (kept_trajectories(&bytes, &config)?, None),
                None => {
                    env.set_frames(false);
                    let trajs =
                        PreferenceRun::record_trajectories_on(&config, env.as_mut(), &mut |_| {})
                            .map_err(SessionError::RecordTrajectories)?;
                    let bytes = keep_trajectories(&trajs, &config);
                    (trajs, Some(bytes))
                }
            };
            let clips = ClipEnv::Remote {
                reconnect,
                env: Some(env),
            };
            (trajectories, clips, recorded)
        }
    };
    let pool = QueryPool::from_trajectories(&config.task, &trajectories, config.min_run);
    if matches!(config.task, TaskRef::Declared(_)) && pool.segments().is_empty() {
        return Err(SessionError::NoSegments);
    }
    let run = PreferenceRun::with_pool(config, pool);
    if let Some(bytes) = recorded {
        // Kept before the first query: a resume replays the answers over these trajectories.
        let mut c = preference_checkpoint(&run);
        c.resume = Some(bytes);
        sink.send(SessionEvent::Checkpoint(c));
    }
    let comparer = if human {
        Comparer::Human {
            clips,
            graph,
            trajectories,
        }
    } else {
        Comparer::Synthetic {
            oracle: Box::new(SimulatedTeacher::new(
                run.theta_true().to_vec(),
                run.config().teacher,
                run.teacher_seed(),
                run.pool(),
            )),
            graph,
        }
    };
    drive(
        spec.budget,
        run,
        PreferenceAsker { asker, comparer },
        verify,
    )
}

/// The recorded trajectories with the run's config before them (a u64 LE length, the config as
/// JSON), so that a resume on an env that now declares something else is refused.
fn keep_trajectories(trajectories: &[Trajectory], config: &PreferenceRunConfig) -> Vec<u8> {
    let head = serde_json::to_vec(config).expect("configs serialise");
    let mut bytes = (head.len() as u64).to_le_bytes().to_vec();
    bytes.extend_from_slice(&head);
    bytes.extend_from_slice(&trajectory_bytes::to_bytes(trajectories));
    bytes
}

fn kept_trajectories(
    bytes: &[u8],
    config: &PreferenceRunConfig,
) -> Result<Vec<Trajectory>, SessionError> {
    let bad = |e: &str| SessionError::KeptTrajectories(e.to_string());
    let (len, rest) = bytes
        .split_first_chunk::<8>()
        .ok_or_else(|| bad("cut short"))?;
    let len = usize::try_from(u64::from_le_bytes(*len)).map_err(|_| bad("cut short"))?;
    if rest.len() < len {
        return Err(bad("cut short"));
    }
    let (head, trajectories) = rest.split_at(len);
    let saved: PreferenceRunConfig =
        serde_json::from_slice(head).map_err(|e| bad(&e.to_string()))?;
    if saved != *config {
        return Err(SessionError::EnvChanged);
    }
    trajectory_bytes::from_bytes(trajectories).map_err(|e| bad(&e.to_string()))
}

/// The session's loop around [`PreferenceRun::step`]: pick a pair, ask, update the belief,
/// query after query.
fn drive(
    budget: u64,
    mut run: PreferenceRun,
    mut trainer: PreferenceAsker,
    verify: Option<(u64, String)>,
) -> Result<Ending, SessionError> {
    let sink = trainer.asker.sink.clone();
    let mut progress = ProgressReports::every_step();
    while (run.queries() as u64) < budget {
        if let Some(h) = trainer.asker.controls.poll() {
            // Between queries the posterior is whole: keep it (a stopped session's too, so its
            // posterior can be exported).
            sink.send(SessionEvent::Checkpoint(preference_checkpoint(&run)));
            return Ok(halt_ending(h));
        }
        apply_revisions(&mut run, &mut trainer.asker);
        // The algorithm's step: pick a pair, ask, update the belief.
        let Some(report) = run.step(&mut trainer) else {
            break; // the method has no new pair left
        };
        if let Some(reason) = trainer.asker.fault.take() {
            return Err(reason);
        }
        if let Some(h) = trainer.asker.abort_halt() {
            return Ok(halt_ending(h));
        }
        sink.send(SessionEvent::Alignment {
            queries: report.query as u64,
            alignment: report.alignment,
            alignment_of_mean: report.alignment_of_mean,
        });
        progress.tick(sink.as_ref(), run.queries() as u64);
        check_replay(&verify, run.queries() as u64, || {
            preference_checkpoint(&run).digest
        })?;
    }
    sink.send(SessionEvent::Checkpoint(preference_checkpoint(&run)));
    Ok(Ending::Finished)
}

/// Takes in the undos and new answers due now: the belief is resampled from the answers that
/// then stand, and its alignment reported after each.
fn apply_revisions(run: &mut PreferenceRun, asker: &mut Asker) {
    let progress = run.queries() as u64;
    for r in asker.due_revisions(progress) {
        let preference = r.value.and_then(AnswerValue::as_preference);
        run.revise(r.seq as usize, preference.unwrap_or(Preference::Skip));
        asker.sink.send(revised(r, progress));
        asker.sink.send(SessionEvent::Alignment {
            queries: progress,
            alignment: run.alignment(),
            alignment_of_mean: run.alignment_of_mean(),
        });
    }
}
