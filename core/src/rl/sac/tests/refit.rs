//! `refit_human_critic`: fresh heads on the replay's answers alone (the first ones by time, if
//! asked), the rest of the learner left as it was.

use super::tiny_config;
use crate::rl::replay::{ReplayBuffer, Transition};
use crate::rl::sac::{HumanCriticConfig, Refit, RefitError, Sac};

/// 400 transitions: the same 200 (state, action) pairs twice, observation `[j / 200, 1]` and an
/// action in [-1, 1] for `j = k mod 200`; the first 200 answered "+1 where the action is
/// positive", the second 200 the opposite way; every fourth one unanswered.
fn replay(capacity: usize) -> ReplayBuffer {
    let mut replay = ReplayBuffer::new(capacity, 2, 1);
    for k in 0..400 {
        let obs = [(k % 200) as f32 / 200.0, 1.0];
        let action = [(((k % 200) * 37 % 101) as f32 / 50.0) - 1.0];
        let sign = if action[0] > 0.0 { 1.0 } else { -1.0 };
        let human = match (k % 4, k < 200) {
            (3, _) => 0.0,
            (_, true) => sign,
            (_, false) => -sign,
        };
        replay.push(Transition {
            obs: &obs,
            action: &action,
            reward: 0.0,
            human,
            next_obs: &obs,
            terminated: false,
        });
    }
    replay
}

fn learner() -> Sac {
    let human = HumanCriticConfig {
        mask: true,
        ..HumanCriticConfig::default()
    };
    Sac::new(2, 1, tiny_config(&[16, 16], 32, Some(human)), 5)
}

/// The share of the states in which H_hat puts +0.6 above -0.6.
fn prefers_positive(sac: &mut Sac) -> f64 {
    let mut above = 0;
    for k in 0..200 {
        let obs = [k as f32 / 200.0, 1.0];
        above += usize::from(sac.human_estimate(&obs, &[0.6]) > sac.human_estimate(&obs, &[-0.6]));
    }
    above as f64 / 200.0
}

#[test]
fn the_first_answers_alone_teach_their_order_and_nothing_else_moves() {
    let replay = replay(1000);
    assert_eq!(replay.answered_len(), 300);
    let mut sac = learner();
    let q_before = sac.q_value(&[0.3, 1.0], &[0.2]);
    let refit = Refit {
        updates: 400,
        answers: Some(150),
        seed: 3,
    };
    let report = sac.refit_human_critic(&replay, refit).unwrap();
    assert_eq!((report.updates, report.answers), (400, 150));
    assert!(report.final_loss < 0.5, "loss {}", report.final_loss);
    let first = prefers_positive(&mut sac);
    assert!(first > 0.9, "the first 150 answers' order: {first}");
    assert_eq!(sac.q_value(&[0.3, 1.0], &[0.2]), q_before);

    // The same refit gives the same critic; the last 150 answers (the reversed order, at the
    // same states) are not among the first 150.
    let mut again = learner();
    again.refit_human_critic(&replay, refit).unwrap();
    assert_eq!(
        again.human_estimate(&[0.1, 1.0], &[0.4]),
        sac.human_estimate(&[0.1, 1.0], &[0.4])
    );
    let mut all = learner();
    let report = all
        .refit_human_critic(
            &replay,
            Refit {
                answers: None,
                ..refit
            },
        )
        .unwrap();
    assert_eq!(report.answers, 300);
    // Each pair answered both ways: the best fit is 0 there, a loss near 1.
    assert!(report.final_loss > 0.8, "loss {}", report.final_loss);
}

#[test]
fn refused_by_what_is_missing() {
    let replay = replay(1000);
    let refit = Refit {
        updates: 10,
        answers: None,
        seed: 0,
    };
    let mut plain = Sac::new(2, 1, tiny_config(&[4], 8, None), 1);
    assert_eq!(
        plain.refit_human_critic(&replay, refit),
        Err(RefitError::NoHumanCritic)
    );
    let mut sac = learner();
    let ask = |answers, updates| Refit {
        answers,
        updates,
        ..refit
    };
    assert_eq!(
        sac.refit_human_critic(&replay, ask(Some(301), 10)),
        Err(RefitError::TooFewAnswers {
            asked: 301,
            held: 300
        })
    );
    assert_eq!(
        sac.refit_human_critic(&replay, ask(Some(0), 10)),
        Err(RefitError::ZeroAnswers)
    );
    assert_eq!(
        sac.refit_human_critic(&replay, ask(None, 0)),
        Err(RefitError::NoUpdates)
    );
    // A full buffer may have wrapped: the first answers by slot need not be the first by time.
    let full = self::replay(400);
    assert_eq!(
        sac.refit_human_critic(&full, ask(Some(10), 10)),
        Err(RefitError::MayHaveWrapped(400))
    );
    assert!(sac.refit_human_critic(&full, ask(None, 10)).is_ok());
    let silent = ReplayBuffer::new(10, 2, 1);
    assert_eq!(
        sac.refit_human_critic(&silent, ask(None, 10)),
        Err(RefitError::NoAnswers)
    );
}
