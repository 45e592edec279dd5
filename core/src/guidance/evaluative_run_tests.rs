//! Tests of `evaluative_run`: what is asked, episodes, seeds, relabelling.

use super::*;
use crate::scene_graph::SceneGraph;

/// Answers +1 when the action's first component is positive; counts the questions.
struct Scripted {
    asked: u64,
    last_step: Option<u64>,
}

impl EvaluativeTrainer for Scripted {
    fn evaluate(&mut self, q: &EvaluativeQuery<'_>) -> Evaluation {
        self.asked += 1;
        assert!(
            self.last_step.is_none_or(|s| q.step > s),
            "steps are asked in order"
        );
        self.last_step = Some(q.step);
        if q.action[0] > 0.0 {
            Evaluation::Good
        } else {
            Evaluation::Bad
        }
    }
}

fn tiny(task: Task, method: &str) -> EvaluativeRunConfig {
    let mut config = EvaluativeRunConfig::new(task, method.parse().unwrap(), 3);
    config.sac.hidden = vec![8, 8];
    config.sac.batch_size = 16;
    config
}

fn scripted() -> Scripted {
    Scripted {
        asked: 0,
        last_step: None,
    }
}

fn run(config: EvaluativeRunConfig, steps: u64) -> (EvaluativeRun, Scripted, Vec<EpisodeRecord>) {
    let mut run = EvaluativeRun::new(config, steps);
    let mut trainer = scripted();
    let mut episodes = Vec::new();
    while run.steps() < steps {
        if let Some(e) = run.step(&mut trainer).episode {
            episodes.push(e);
        }
    }
    (run, trainer, episodes)
}

#[test]
fn sac_never_asks_and_ef_100_asks_every_step() {
    let (sac, trainer, _) = run(tiny(Task::Reaching, "sac"), 50);
    assert_eq!((sac.feedback_count(), trainer.asked), (0, 0));
    assert!(sac.config().sac.human_critic.is_none());
    let (ef, trainer, _) = run(tiny(Task::Reaching, "ef-100"), 50);
    assert_eq!((ef.feedback_count(), trainer.asked), (50, 50));
    assert_eq!(ef.learner().updates(), 50);
}

#[test]
fn a_persons_pace_holds_queries_back_and_leaves_the_rest_alone() {
    let mut paced = tiny(Task::Reaching, "ef-100");
    paced.human_pace = Some(crate::guidance::human_pace::HumanPace {
        max_per_minute: 3,
        steps_per_minute: 20,
    });
    let (run, trainer, _) = run(paced, 100);
    // Three in each window of 20 steps: 15 of the 100 the method wanted.
    assert_eq!((run.feedback_count(), trainer.asked), (15, 15));
    assert_eq!(run.queries_held_back(), 85);
    let (free, _, _) = self::run(tiny(Task::Reaching, "ef-100"), 100);
    assert_eq!(free.queries_held_back(), 0);
}

#[test]
fn nothing_is_asked_from_feedback_until_on_and_the_learner_goes_on() {
    let mut front = tiny(Task::Reaching, "ef-100");
    front.feedback_until = Some(30);
    let (run, trainer, _) = run(front, 100);
    assert_eq!((run.feedback_count(), trainer.asked), (30, 30));
    assert_eq!(trainer.last_step, Some(29), "steps 0-29 asked, none after");
    assert_eq!(run.learner().updates(), 100);
    assert_eq!(
        run.queries_held_back(),
        0,
        "a cut-off is not a person's pace"
    );
    // EF's coin is drawn on every step either way: EF-50 asks the same steps before the cut.
    let (whole, _, _) = self::run(tiny(Task::Reaching, "ef-50"), 100);
    let mut cut = tiny(Task::Reaching, "ef-50");
    cut.feedback_until = Some(60);
    let (cut, _, _) = self::run(cut, 100);
    let before = |r: &EvaluativeRun| r.queried.iter().filter(|(s, _)| *s < 60).count();
    assert_eq!(before(&cut), before(&whole));
    assert_eq!(cut.queried.len(), before(&whole));
    assert!(
        whole.queried.len() > before(&whole),
        "EF-50 asks after step 60 uncut"
    );
}

#[test]
fn dref_asks_at_the_first_step_and_counts_every_answer() {
    // While fewer than k + 1 abstract states have feedback, every state ranks in the top
    // k + 1 and DREF asks; which steps it skips later is the query rule's (tested there).
    let (dref, trainer, _) = run(tiny(Task::Reaching, "dref"), 100);
    assert_eq!(
        trainer.last_step.map(|_| trainer.asked),
        Some(dref.feedback_count())
    );
    assert!(dref.feedback_count() >= 1);
    assert!(dref.config().sac.human_critic.is_some());
}

#[test]
fn episodes_are_counted_cumulatively_and_the_env_resets() {
    // Lunar Lander episodes end within a few hundred steps under an untrained policy.
    let (run, _, episodes) = run(tiny(Task::LunarLander, "sac"), 400);
    assert!(!episodes.is_empty());
    let mut cumulative = 0.0;
    for (i, e) in episodes.iter().enumerate() {
        cumulative += e.episode_return;
        assert_eq!(e.episode, i as u64);
        assert!((e.cumulative_return - cumulative).abs() < 1e-9);
        assert!(e.step <= run.steps());
    }
    assert_eq!(run.episodes(), episodes.len() as u64);
}

#[test]
fn a_run_is_reproducible_from_its_seed() {
    let returns = |seed| {
        let mut config = tiny(Task::LunarLander, "ef-50");
        config.seed = seed;
        run(config, 200)
            .2
            .iter()
            .map(|e| e.episode_return)
            .collect::<Vec<_>>()
    };
    assert_eq!(returns(1), returns(1));
    assert_ne!(returns(1), returns(2));
}

#[test]
fn an_answer_can_be_relabelled_after_the_run_moved_on() {
    let (mut ef, trainer, _) = run(tiny(Task::Reaching, "ef-100"), 40);
    assert_eq!(trainer.asked, 40);
    let before = ef.human_label(10).unwrap();
    assert_ne!(before, 0.0, "the scripted trainer always judges");
    // Undone: "no feedback" until answered again.
    assert!(ef.relabel(10, Evaluation::NoFeedback));
    assert_eq!(ef.human_label(10), Some(0.0));
    assert_eq!(ef.no_feedback_count(), 1);
    assert!(ef.relabel(10, Evaluation::Bad));
    assert_eq!(ef.human_label(10), Some(-1.0));
    assert_eq!(ef.no_feedback_count(), 0);
    // Other queries keep their labels; queries never asked cannot be relabelled.
    assert_eq!(ef.human_label(11).map(f32::abs), Some(1.0));
    assert!(!ef.relabel(40, Evaluation::Good));
    // The relabelled transition is what later updates learn from: the learner diverges
    // from a run that kept the old label.
    let (mut kept, _, _) = run(tiny(Task::Reaching, "ef-100"), 40);
    let mut nobody = crate::guidance::evaluative_trainer::NoTrainer;
    let label = if before > 0.0 {
        Evaluation::Bad
    } else {
        Evaluation::Good
    };
    ef.relabel(10, label);
    for _ in 0..5 {
        ef.step(&mut nobody);
        kept.step(&mut nobody);
    }
    assert_ne!(
        ef.learner().state_checksum(),
        kept.learner().state_checksum()
    );
}

#[test]
fn a_transition_that_left_the_replay_buffer_is_not_relabelled() {
    let mut config = tiny(Task::Reaching, "ef-100");
    config.sac.buffer_size = 8;
    let (mut ef, _, _) = run(config, 20);
    assert!(!ef.relabel(0, Evaluation::Good), "overwritten long ago");
    assert!(ef.relabel(19, Evaluation::NoFeedback));
    assert!(
        ef.relabel(12, Evaluation::NoFeedback),
        "the oldest still held"
    );
    assert!(!ef.relabel(11, Evaluation::NoFeedback));
}

/// Every step's report of a run of `steps` steps, with the run's first observation after it.
fn reports(
    config: EvaluativeRunConfig,
    steps: u64,
) -> (EvaluativeRun, Vec<(StepReport, Vec<f32>)>) {
    let mut run = EvaluativeRun::new(config, steps);
    let mut trainer = scripted();
    let mut out = Vec::new();
    while run.steps() < steps {
        let report = run.step(&mut trainer);
        out.push((report, run.obs.clone()));
    }
    (run, out)
}

#[test]
fn the_graph_at_an_episodes_end_reads_the_reset_observation_as_run() {
    let mut as_run = tiny(Task::Reaching, "sac");
    as_run.graph_at_episode_end = GraphAtEpisodeEnd::Reset;
    let (_, head) = reports(tiny(Task::Reaching, "sac"), 2_000);
    let (_, reset) = reports(as_run, 2_000);
    let mut ends = 0;
    for ((h, h_next), (r, r_next)) in head.iter().zip(&reset) {
        // The same run step for step: only the graph of an episode's last step differs.
        assert_eq!(h_next, r_next);
        assert_eq!(h.episode, r.episode);
        if r.episode.is_some() {
            ends += 1;
            assert_eq!(
                r.abstract_state,
                SceneGraph::Reaching.evaluate(r_next, &[0.0; 2])
            );
        } else {
            assert_eq!(h.abstract_state, r.abstract_state);
        }
    }
    assert!(ends >= 2, "{ends} episodes ended in 2000 steps");
    // A success's last graph is the goal cell at the head, the home pose's cell as run.
    let success = head.iter().zip(&reset).find(|((h, _), _)| {
        h.episode
            .as_ref()
            .is_some_and(|e| e.outcome == Outcome::Success)
    });
    if let Some(((h, _), (r, _))) = success {
        assert_ne!(h.abstract_state, r.abstract_state);
    }
}

#[test]
fn time_limit_ends_are_stored_as_terminal_only_as_run() {
    for (time_limit, stored) in [
        (TimeLimitEnd::Truncation, false),
        (TimeLimitEnd::Terminal, true),
    ] {
        let mut config = tiny(Task::Reaching, "sac");
        config.time_limit = time_limit;
        let (run, steps) = reports(config, 1_500);
        let mut limits = 0;
        for (step, (report, _)) in steps.iter().enumerate() {
            let terminal = run.replay.terminated(step);
            match report.episode.as_ref().map(|e| e.outcome) {
                Some(Outcome::TimeLimit) => {
                    limits += 1;
                    assert_eq!(terminal, stored, "{time_limit:?} at step {step}");
                }
                Some(Outcome::Success | Outcome::Failure) => assert!(terminal),
                None => assert!(!terminal),
            }
        }
        assert!(
            limits >= 1,
            "no episode reached the time limit in 1500 steps"
        );
    }
}

#[test]
fn the_as_run_action_scale_shows_the_oracle_and_h_hat_a_tenth_of_the_action() {
    // The expert's critic is the oracle's only judge: scaling both actions changes what it
    // compares. Checked on the estimate the run shows the query rule.
    let mut config = tiny(Task::Reaching, "dref-authors");
    config.oracle.action_scale = 0.1;
    let mut run = EvaluativeRun::new(config, 10);
    run.action.copy_from_slice(&[0.8, -0.6]);
    let shown = run.human_estimate();
    let expected = run.learner.human_estimate(&run.obs.clone(), &[0.08, -0.06]);
    assert_eq!(shown, expected);
    let full = run.learner.human_estimate(&run.obs.clone(), &[0.8, -0.6]);
    assert_ne!(shown, full);
}

/// What the learner does at a fixed state: its action, Q and H there, as bits.
fn probe(run: &EvaluativeRun) -> [u32; 4] {
    let mut sac = run.learner().clone();
    let (obs, mut action) = ([0.1f32, -0.2], [0.0f32; 2]);
    sac.act(&obs, true, &mut action);
    let (q, h) = (
        sac.q_value(&obs, &action),
        sac.human_estimate(&obs, &action),
    );
    [action[0], action[1], q, h].map(f32::to_bits)
}

/// `answered_after`: the answered mix reads H at full weight everywhere, which is the authors'
/// mix bit for bit, until the run's N-th successful episode has ended; then it reads H only on
/// answered rows, and the learner parts from the authors'.
#[test]
fn the_answered_mix_reads_h_everywhere_until_the_first_success() {
    use crate::rl::ActorMix;
    let with = |mix: ActorMix, answered_after: u32| {
        let mut config = tiny(Task::Reaching, "dref");
        let critic = config.sac.human_critic.as_mut().unwrap();
        (critic.mix, critic.answered_after) = (mix, answered_after);
        config
    };
    let (_, _, episodes) = run(with(ActorMix::Authors, 0), 4000);
    let first = episodes
        .iter()
        .find(|e| e.outcome == Outcome::Success)
        .expect("a success within 4,000 steps")
        .step;
    let (authors, ..) = run(with(ActorMix::Authors, 0), first);
    let (gated, ..) = run(with(ActorMix::Answered, 1), first);
    assert_eq!(gated.successes(), 1);
    assert!(
        !gated.reads_h_everywhere(),
        "the gate shuts at the first success"
    );
    assert_eq!(
        probe(&gated),
        probe(&authors),
        "the authors' mix until the first success ({first} steps)"
    );
    let (authors, ..) = run(with(ActorMix::Authors, 0), first + 50);
    let (gated, ..) = run(with(ActorMix::Answered, 1), first + 50);
    assert_ne!(probe(&gated), probe(&authors), "the answered mix after it");
    let (never, ..) = run(with(ActorMix::Answered, 1000), first + 50);
    assert!(never.reads_h_everywhere());
    assert_eq!(
        probe(&never),
        probe(&authors),
        "a gate that never shuts is the authors' mix"
    );
}

/// `authors_until`: the answered mix is the authors' mix bit for bit for the run's first N
/// steps, whatever the episodes' outcomes, and parts from it after. (Reaching's 2,000-step
/// opening asks nearly every step, so the mixes differ only past it.)
#[test]
fn the_answered_mix_reads_h_everywhere_until_its_step() {
    use crate::rl::ActorMix;
    const UNTIL: u64 = 2_400;
    let with = |mix: ActorMix, authors_until: u64| {
        let mut config = tiny(Task::Reaching, "dref");
        let critic = config.sac.human_critic.as_mut().unwrap();
        (critic.mix, critic.authors_until) = (mix, authors_until);
        config
    };
    let (authors, ..) = run(with(ActorMix::Authors, 0), UNTIL);
    let (gated, ..) = run(with(ActorMix::Answered, UNTIL), UNTIL);
    assert_eq!(
        probe(&gated),
        probe(&authors),
        "the authors' mix until its step"
    );
    let (answered, ..) = run(with(ActorMix::Answered, 0), UNTIL);
    assert_ne!(
        probe(&answered),
        probe(&authors),
        "the gate is what made them equal"
    );
    let (authors, ..) = run(with(ActorMix::Authors, 0), UNTIL + 50);
    let (gated, ..) = run(with(ActorMix::Answered, UNTIL), UNTIL + 50);
    assert_ne!(probe(&gated), probe(&authors), "the answered mix after it");
}
