//! The product's `dref` against the authors' code: which settings separate them on each task
//! (docs/dref.md, "The rule"), and the recent rank, the default before, a few settings away.

use super::*;
use crate::guidance::evaluative_run::{DEFAULT_CEILING, FeedbackCeiling};
use crate::guidance::visit_share::OpeningPlacement;
use crate::rl::ActorMix;

#[test]
fn the_products_dref_and_the_authors_differ_only_in_their_switches() {
    for (task, mix) in [
        (Task::Placing, ActorMix::Authors),
        (Task::Reaching, ActorMix::Answered),
        (Task::LunarLander, ActorMix::Answered),
    ] {
        let dref = Settings::default()
            .evaluative(task, EvaluativeMethod::Dref, 0)
            .unwrap();
        let authors = Settings::default()
            .evaluative(task, EvaluativeMethod::DrefAuthors, 0)
            .unwrap();
        let critic = dref.sac.human_critic.as_ref().unwrap();
        assert!(critic.mask, "{task:?}");
        assert_eq!(critic.mix, mix, "{task:?}");
        assert!(!authors.sac.human_critic.as_ref().unwrap().mask);
        assert_eq!(
            authors.sac.human_critic.as_ref().unwrap().mix,
            ActorMix::Authors
        );
        // The authors' ranking (no window), woken after 1,000 silent steps, under a 10 %
        // ceiling that starts empty and repays its opening from 90 % of its earnings. The
        // opening is 2,000 steps of the authors' asking, but on Lunar Lander, whose learner
        // takes off only with thousands of early answers: 30,000 steps asked at 0.45 of each
        // abstract state's visits.
        assert_eq!(
            (dref.query_rule.rank_window, dref.query_rule.wake_after),
            (0, 1000)
        );
        let (opening, opening_rate, placement) = match task {
            Task::LunarLander => (30_000, Some(0.45), OpeningPlacement::ByVisits),
            _ => (2_000, None, OpeningPlacement::Ranked),
        };
        assert_eq!(
            dref.query_rule.ceiling.map(|c| (
                c.rate,
                c.burst,
                c.opening,
                c.start_empty,
                c.repay_share,
                c.opening_rate,
                c.opening_placement,
                c.repayment_placement,
            )),
            Some((
                0.1,
                20,
                opening,
                true,
                0.9,
                opening_rate,
                placement,
                OpeningPlacement::Ranked
            )),
            "{task:?}"
        );
        assert_eq!(
            (authors.query_rule.ceiling, authors.query_rule.wake_after),
            (None, 0)
        );
        // Switched off one by one, the product's rule is the authors' (but for the method's
        // name).
        let off = Settings::from_pairs([
            ("human_critic_mask", "false"),
            ("mix", "authors"),
            ("wake_after", "0"),
            ("max_feedback_rate", "0"),
        ])
        .unwrap()
        .evaluative(task, EvaluativeMethod::Dref, 0)
        .unwrap();
        assert_eq!(
            EvaluativeRunConfig {
                method: EvaluativeMethod::DrefAuthors,
                ..off
            },
            authors
        );
    }
    // The recent rank, the product's rule before the wake with an opening, is four settings
    // away (and the mix on Reaching and Lunar Lander).
    let recent = Settings::from_pairs([
        ("rank_window", "1000"),
        ("wake_after", "0"),
        ("feedback_opening", "0"),
        ("feedback_start_empty", "false"),
    ])
    .unwrap()
    .evaluative(Task::Placing, EvaluativeMethod::Dref, 0)
    .unwrap();
    assert_eq!(
        (recent.query_rule.rank_window, recent.query_rule.wake_after),
        (1000, 0)
    );
    assert_eq!(
        recent
            .query_rule
            .ceiling
            .map(|c| (c.rate, c.opening, c.start_empty)),
        Some((0.1, 0, false))
    );
    // The opening wake as it shipped before its accounting changed (12th session) is two.
    let before = Settings::from_pairs([
        ("feedback_start_empty", "false"),
        ("opening_repay_share", "1"),
    ])
    .unwrap()
    .evaluative(Task::Placing, EvaluativeMethod::Dref, 0)
    .unwrap();
    assert_eq!(
        before.query_rule.ceiling,
        Some(FeedbackCeiling {
            opening: 2000,
            ..DEFAULT_CEILING
        })
    );
    let bad = Settings::from_pairs([("max_feedback_rate", "1.5")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::Dref, 0)
        .unwrap_err()
        .to_string();
    assert!(bad.contains("max_feedback_rate"), "{bad}");
    let no_ceiling = Settings::from_pairs([("feedback_burst", "5")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::DrefAuthors, 0)
        .unwrap_err()
        .to_string();
    assert!(no_ceiling.contains("no ceiling"), "{no_ceiling}");
    // An answer-driven rate: a floor under the ceiling, checked against it.
    let following =
        Settings::from_pairs([("max_feedback_rate", "0.1"), ("min_feedback_rate", "0.02")])
            .unwrap()
            .evaluative(Task::Placing, EvaluativeMethod::Dref, 0)
            .unwrap();
    assert_eq!(
        following
            .query_rule
            .ceiling
            .map(|c| (c.rate, c.burst, c.floor)),
        Some((0.1, 20, Some(0.02)))
    );
    let above = Settings::from_pairs([("min_feedback_rate", "0.2")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::Dref, 0)
        .unwrap_err()
        .to_string();
    assert!(above.contains("min_feedback_rate"), "{above}");
}

#[test]
fn the_silence_wake_is_a_setting_of_its_own_on_for_dref_only() {
    let wake = |method| {
        Settings::default()
            .evaluative(Task::Placing, method, 0)
            .unwrap()
            .query_rule
            .wake_after
    };
    assert_eq!(wake(EvaluativeMethod::Dref), 1000);
    assert_eq!(wake(EvaluativeMethod::DrefAuthors), 0);
    let waking = Settings::from_pairs([("wake_after", "2000")])
        .unwrap()
        .evaluative(Task::Placing, EvaluativeMethod::DrefAuthors, 0)
        .unwrap();
    assert_eq!(
        (waking.query_rule.wake_after, waking.query_rule.rank_window),
        (2000, 0)
    );
    assert_eq!(waking.query_rule.build().silent_steps(), Some(0));
    let not_a_number = Settings::from_pairs([("wake_after", "soon")])
        .unwrap_err()
        .to_string();
    assert!(not_a_number.contains("wake_after"), "{not_a_number}");
}
