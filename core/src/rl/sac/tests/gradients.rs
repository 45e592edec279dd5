//! Every loss's hand-written gradient against central differences of the loss itself, on tiny
//! networks with a fixed batch and fixed noise.
//!
//! The error of each network is `max_k |analytic_k - numeric_k| / max_k |numeric_k|`; a wrong
//! factor, sign or missing path (through the critics' input gradient, the tanh-Gaussian or the
//! log-prob) puts it near 1.

use super::{fill_fixed_batch_and_noise, tiny_config};
use crate::rl::sac::update::{mix_weights, temperature_loss};
use crate::rl::sac::{ActorMix, CriticLoss, HumanCriticConfig, Sac};

const STEP: f32 = 1e-3;
const TOLERANCE: f64 = 2e-3;
const ENT_COEF: f32 = 0.7;

fn tiny(human: Option<HumanCriticConfig>) -> Sac {
    tiny_with(human, false)
}

/// [`tiny`], its env critics layer-normed if `critic_layer_norm`.
fn tiny_with(human: Option<HumanCriticConfig>, critic_layer_norm: bool) -> Sac {
    let mut config = tiny_config(&[6, 5], 7, human);
    config.critic_layer_norm = critic_layer_norm;
    let mut sac = Sac::new(3, 2, config, 3);
    fill_fixed_batch_and_noise(&mut sac);
    sac
}

/// Which network's parameters a check perturbs.
type Params = fn(&mut Sac) -> &mut [f32];

const Q1: Params = |s| s.q1.params_mut();
const Q2: Params = |s| s.q2.params_mut();
const H1: Params = |s| s.human_critic.as_mut().unwrap().h1.params_mut();
const H2: Params = |s| s.human_critic.as_mut().unwrap().h2.params_mut();
const ACTOR: Params = |s| s.actor.params_mut();

/// Central differences of `loss` in every parameter of `params`, against `analytic`.
fn check(
    name: &str,
    sac: &mut Sac,
    params: Params,
    analytic: &[f32],
    loss: &mut dyn FnMut(&mut Sac) -> f32,
) -> f64 {
    let n = params(sac).len();
    assert_eq!(analytic.len(), n);
    let mut numeric = vec![0.0f64; n];
    for (k, d) in numeric.iter_mut().enumerate() {
        let original = params(sac)[k];
        params(sac)[k] = original + STEP;
        let plus = loss(sac);
        params(sac)[k] = original - STEP;
        let minus = loss(sac);
        params(sac)[k] = original;
        *d = (f64::from(plus) - f64::from(minus)) / (2.0 * f64::from(STEP));
    }
    let scale = numeric.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    assert!(
        scale > 1e-3,
        "{name}: the loss barely depends on these parameters ({scale:e})"
    );
    let err = analytic
        .iter()
        .zip(&numeric)
        .map(|(&a, &d)| (f64::from(a) - d).abs() / scale)
        .fold(0.0, f64::max);
    eprintln!("{name}: max error {err:.1e} of the largest gradient {scale:.3}");
    assert!(
        err < TOLERANCE,
        "{name}: analytic gradient off by {err:e} (relative)"
    );
    err
}

#[test]
fn critic_loss_gradient() {
    critic_case(tiny(None));
}

/// The critics' gain and bias gradients included.
#[test]
fn critic_loss_gradient_with_layer_norms() {
    critic_case(tiny_with(None, true));
}

fn critic_case(mut sac: Sac) {
    sac.compute_target_q_values(ENT_COEF);
    sac.critic_loss();
    let (g1, g2) = (sac.q1.grads().to_vec(), sac.q2.grads().to_vec());
    check("critic loss, q1", &mut sac, Q1, &g1, &mut |s| {
        s.critic_loss()
    });
    check("critic loss, q2", &mut sac, Q2, &g2, &mut |s| {
        s.critic_loss()
    });
}

#[test]
fn huber_critic_loss_gradient() {
    let mut sac = tiny(None);
    sac.config.critic_loss = CriticLoss::Huber;
    // Rewards three times the fixture's, so targets fall on both sides of the loss's seam.
    for r in &mut sac.buffers.batch.rewards {
        *r *= 3.0;
    }
    sac.compute_target_q_values(ENT_COEF);
    let huber = sac.critic_loss();
    let (g1, g2) = (sac.q1.grads().to_vec(), sac.q2.grads().to_vec());
    let off = |s: &Sac| {
        let q = s.buffers.q1_ws.output().as_slice();
        let y = &s.buffers.target_q_values;
        q.iter()
            .zip(y)
            .map(|(q, y)| (q - y).abs())
            .collect::<Vec<_>>()
    };
    let diffs = off(&sac);
    assert!(
        diffs.iter().any(|&d| d < 0.9) && diffs.iter().any(|&d| d > 1.1),
        "both branches of the Huber loss: {diffs:?}"
    );
    check("huber critic loss, q1", &mut sac, Q1, &g1, &mut |s| {
        s.critic_loss()
    });
    check("huber critic loss, q2", &mut sac, Q2, &g2, &mut |s| {
        s.critic_loss()
    });
    // Below the mse of the same batch: each sample off by more than 1 counts |d| - 0.5, not d^2.
    sac.config.critic_loss = CriticLoss::Mse;
    assert!(huber < 0.5 * sac.critic_loss());
}

fn human_critic_case(mask: bool) {
    human_critic_case_anchored(mask, 0.0);
}

fn human_critic_case_anchored(mask: bool, anchor: f32) {
    let human = HumanCriticConfig {
        mask,
        anchor,
        ..HumanCriticConfig::default()
    };
    let mut sac = tiny(Some(human));
    let full = sac.human_critic_loss().unwrap();
    let hc = sac.human_critic.as_ref().unwrap();
    let (g1, g2) = (hc.h1.grads().to_vec(), hc.h2.grads().to_vec());
    let name = match (mask, anchor > 0.0) {
        (true, true) => "human critic loss, masked and anchored",
        (true, false) => "human critic loss, masked",
        (false, _) => "human critic loss",
    };
    check(&format!("{name}, h1"), &mut sac, H1, &g1, &mut |s| {
        s.human_critic_loss().unwrap()
    });
    check(&format!("{name}, h2"), &mut sac, H2, &g2, &mut |s| {
        s.human_critic_loss().unwrap()
    });
    // The masked loss ignores the rows without feedback (H = 0): moving them changes nothing,
    // unless they are anchored to 0.
    let b = &mut sac.buffers.batch;
    let unlabelled: Vec<usize> = (0..b.size).filter(|&i| b.human[i] == 0.0).collect();
    assert!(!unlabelled.is_empty());
    for &i in &unlabelled {
        b.actions[2 * i] = -b.actions[2 * i];
    }
    let moved = sac.human_critic_loss().unwrap();
    let ignored = mask && anchor == 0.0;
    assert_eq!(
        ignored,
        moved == full,
        "mask {mask}, anchor {anchor}: {full} vs {moved}"
    );
}

#[test]
fn anchored_human_critic_loss_gradient() {
    human_critic_case_anchored(true, 0.3);
}

#[test]
fn the_anchor_adds_its_share_of_the_silent_rows_mean_square() {
    let loss = |anchor: f32| {
        let human = HumanCriticConfig {
            mask: true,
            anchor,
            ..HumanCriticConfig::default()
        };
        tiny(Some(human)).human_critic_loss().unwrap()
    };
    let (plain, half, one) = (loss(0.0), loss(0.5), loss(1.0));
    // Linear in the anchor: the silent rows' mean square is (one - plain), half of it at 0.5.
    assert!(one > plain, "{one} vs {plain}");
    assert!(
        ((half - plain) - 0.5 * (one - plain)).abs() < 1e-5,
        "{plain} {half} {one}"
    );
}

#[test]
fn an_anchored_critic_still_learns_from_a_batch_without_feedback() {
    let human = HumanCriticConfig {
        mask: true,
        anchor: 0.1,
        ..HumanCriticConfig::default()
    };
    let mut sac = tiny(Some(human));
    sac.buffers.batch.human.fill(0.0);
    assert!(sac.human_critic_loss().is_some_and(|l| l > 0.0));
}

#[test]
fn human_critic_loss_gradient() {
    human_critic_case(false);
}

#[test]
fn masked_human_critic_loss_gradient() {
    human_critic_case(true);
}

#[test]
fn masked_human_critic_skips_a_batch_without_feedback() {
    let human = HumanCriticConfig {
        mask: true,
        ..HumanCriticConfig::default()
    };
    let mut sac = tiny(Some(human));
    sac.buffers.batch.human.fill(0.0);
    assert_eq!(sac.human_critic_loss(), None);
}

/// The actor loss as a function of the actor's parameters: resample `a_pi` (same noise), then
/// the loss through the frozen critics.
fn actor_case(name: &str, human: Option<HumanCriticConfig>) {
    actor_case_on(name, tiny(human));
}

fn actor_case_on(name: &str, mut sac: Sac) {
    let critics_before = (sac.q1.clone(), sac.q2.clone());
    sac.sample_policy_at_obs();
    sac.actor_loss(ENT_COEF);
    let analytic = sac.actor.grads().to_vec();
    check(name, &mut sac, ACTOR, &analytic, &mut |s| {
        s.sample_policy_at_obs();
        s.actor_loss(ENT_COEF)
    });
    assert_eq!(
        (sac.q1.clone(), sac.q2.clone()),
        critics_before,
        "critics frozen, gradients too"
    );
}

#[test]
fn actor_loss_gradient_plain_sac() {
    actor_case("actor loss, plain SAC", None);
}

#[test]
fn actor_loss_gradient_authors_mix() {
    let human = HumanCriticConfig {
        lambda: 9.0,
        mix: ActorMix::Authors,
        ..HumanCriticConfig::default()
    };
    actor_case("actor loss, authors' mix", Some(human));
}

/// Through the layer norms of the frozen env critics' input gradient.
#[test]
fn actor_loss_gradient_through_layer_normed_critics() {
    let human = HumanCriticConfig {
        lambda: 9.0,
        mix: ActorMix::Authors,
        ..HumanCriticConfig::default()
    };
    actor_case_on("actor loss, normed critics", tiny_with(Some(human), true));
    actor_case_on(
        "actor loss, normed critics, plain SAC",
        tiny_with(None, true),
    );
}

#[test]
fn actor_loss_gradient_paper_mix() {
    let human = HumanCriticConfig {
        lambda: 2.0,
        mix: ActorMix::Paper,
        ..HumanCriticConfig::default()
    };
    actor_case("actor loss, paper's mix", Some(human));
}

#[test]
fn actor_loss_gradient_answered_mix() {
    for unanswered in [0.0, 0.3] {
        let human = HumanCriticConfig {
            lambda: 9.0,
            mix: ActorMix::Answered,
            mask: true,
            unanswered,
            ..HumanCriticConfig::default()
        };
        actor_case(
            &format!("actor loss, answered mix, unanswered {unanswered}"),
            Some(human),
        );
    }
}

#[test]
fn actor_loss_gradient_answered_mix_where_the_heads_agree() {
    let human = HumanCriticConfig {
        lambda: 9.0,
        mix: ActorMix::Answered,
        mask: true,
        agree_within: 0.05,
        ..HumanCriticConfig::default()
    };
    actor_case("actor loss, answered mix, heads agreeing", Some(human));
}

#[test]
fn actor_loss_gradient_answered_mix_with_h_unread_weight_on_q() {
    let human = HumanCriticConfig {
        lambda: 9.0,
        mix: ActorMix::Answered,
        mask: true,
        unanswered: 0.3,
        unread_to_q: true,
        ..HumanCriticConfig::default()
    };
    actor_case("actor loss, answered mix, unread weight on Q", Some(human));
}

/// With `unread_to_q` a row whose H is not read at all is SAC's: `ent_coef log_pi - min_j Q_j`,
/// ten times the Q term the answered mix keeps there otherwise; an answered row is the
/// authors' mix either way.
#[test]
fn h_unread_weight_goes_to_q() {
    let with = |unread_to_q: bool, human: f32| {
        let config = HumanCriticConfig {
            mix: ActorMix::Answered,
            mask: true,
            unread_to_q,
            ..HumanCriticConfig::default()
        };
        let mut sac = tiny(Some(config));
        sac.buffers.batch.human.fill(human);
        sac.sample_policy_at_obs();
        let loss = sac.actor_loss(ENT_COEF);
        let b = &sac.buffers;
        let n = b.log_pi.len() as f32;
        let (mut entropy, mut min_q) = (0.0f32, 0.0f32);
        for i in 0..b.log_pi.len() {
            entropy += ENT_COEF * b.log_pi[i] / n;
            min_q += b.q1_ws.output()[i].min(b.q2_ws.output()[i]) / n;
        }
        (loss, entropy, min_q)
    };
    let (sac_like, entropy, min_q) = with(true, 0.0);
    assert!((sac_like - (entropy - min_q)).abs() < 1e-5 * (1.0 + sac_like.abs()));
    let (tenth, ..) = with(false, 0.0);
    assert!((tenth - (entropy - 0.1 * min_q)).abs() < 1e-5 * (1.0 + tenth.abs()));
    assert_eq!(
        with(true, 1.0).0,
        with(false, 1.0).0,
        "answered rows: 0.1 and 0.9"
    );
    // The weights themselves: the authors' to the bit where H is read in full.
    let authors = (1.0f32 / 10.0, 9.0f32 / 10.0);
    assert_eq!(mix_weights(9.0, 1.0, true), authors);
    assert_eq!(mix_weights(9.0, 1.0, false), authors);
    assert_eq!(mix_weights(9.0, 0.0, true), (1.0, 0.0));
    assert_eq!(mix_weights(9.0, 0.0, false), (0.1, 0.0));
}

/// The answered mix reads H only on answered rows: with no answer in the batch the loss is the
/// authors' mix with H = 0 (whatever H says), and with every row answered it is the authors' mix.
/// With `unanswered = 1` it is the authors' mix everywhere, and in between it reads H on silent
/// rows at that share of its weight.
#[test]
fn answered_mix_reads_h_on_answered_rows_only() {
    let with = |mix: ActorMix, unanswered: f32, human: f32, scale_h: f32| {
        let config = HumanCriticConfig {
            lambda: 9.0,
            mix,
            mask: true,
            unanswered,
            ..HumanCriticConfig::default()
        };
        let mut sac = tiny(Some(config));
        sac.buffers.batch.human.fill(human);
        for p in sac.human_critic.as_mut().unwrap().h1.params_mut() {
            *p *= scale_h;
        }
        sac.sample_policy_at_obs();
        sac.actor_loss(ENT_COEF)
    };
    let silent = with(ActorMix::Answered, 0.0, 0.0, 1.0);
    assert_eq!(
        silent,
        with(ActorMix::Answered, 0.0, 0.0, 3.0),
        "H unread on silent rows"
    );
    let authors = with(ActorMix::Authors, 0.0, 0.0, 1.0);
    assert_ne!(silent, authors, "the authors' mix reads H");
    assert_eq!(
        with(ActorMix::Answered, 0.0, 1.0, 1.0),
        with(ActorMix::Authors, 0.0, 1.0, 1.0),
        "every row answered: the authors' mix"
    );
    assert_eq!(
        with(ActorMix::Answered, 1.0, 0.0, 1.0),
        authors,
        "unanswered = 1: the authors' mix on silent rows too"
    );
    let partial = with(ActorMix::Answered, 0.3, 0.0, 1.0);
    assert_ne!(
        partial,
        with(ActorMix::Answered, 0.3, 0.0, 3.0),
        "unanswered = 0.3 reads H on silent rows"
    );
    assert!(
        partial != silent && partial != authors,
        "0.3 is neither end: {silent} {partial} {authors}"
    );
}

/// `agree_within`: an unanswered row counts as answered where the heads of H agree within it;
/// wide enough it is the authors' mix, and a width inside the batch's gaps reads H on some
/// silent rows only.
#[test]
fn the_answered_mix_reads_h_where_the_heads_agree() {
    let run = |mix: ActorMix, agree_within: f32| {
        let config = HumanCriticConfig {
            lambda: 9.0,
            mix,
            mask: true,
            agree_within,
            ..HumanCriticConfig::default()
        };
        let mut sac = tiny(Some(config));
        sac.buffers.batch.human.fill(0.0);
        sac.sample_policy_at_obs();
        let loss = sac.actor_loss(ENT_COEF);
        let [h1, h2] = sac.buffers.h_ws.as_ref().unwrap();
        let mut gaps: Vec<f32> = (h1.output().iter().zip(h2.output()))
            .map(|(a, b)| (a - b).abs())
            .collect();
        gaps.sort_by(f32::total_cmp);
        (loss, gaps)
    };
    let (authors, gaps) = run(ActorMix::Authors, 0.0);
    let (silent, _) = run(ActorMix::Answered, 0.0);
    assert_ne!(silent, authors);
    assert_eq!(
        run(ActorMix::Answered, 1e9).0,
        authors,
        "heads always agree: the authors' mix"
    );
    let median = (gaps[gaps.len() / 2 - 1] + gaps[gaps.len() / 2]) / 2.0;
    let (middle, _) = run(ActorMix::Answered, median);
    assert!(
        middle != silent && middle != authors,
        "agreeing within the median gap reads H on some silent rows: {silent} {middle} {authors}"
    );
}

#[test]
fn temperature_loss_gradient() {
    let log_pi = [0.3f32, -1.7, 2.2, 0.9];
    let (target_entropy, log_ent_coef) = (-2.0f32, -0.4f32);
    let (_, analytic) = temperature_loss(log_ent_coef, &log_pi, target_entropy);
    let h = 1e-2f32;
    let plus = temperature_loss(log_ent_coef + h, &log_pi, target_entropy).0;
    let minus = temperature_loss(log_ent_coef - h, &log_pi, target_entropy).0;
    let numeric = (plus - minus) / (2.0 * h);
    assert!(
        (analytic - numeric).abs() < 1e-4 * numeric.abs().max(1.0),
        "{analytic} vs {numeric}"
    );
    // Entropy -mean(log_pi) = -0.425 is above the target -2: alpha must fall (gradient > 0).
    assert!(analytic > 0.0);
}
