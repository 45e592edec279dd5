//! Two full updates agree with PyTorch 2.15 doing the same in SB3's order
//! (`benches/reference/torch_sac_reference.py`; its docstring gives every formula).

use super::{fill, fill_fixed_batch_and_noise, tiny_config};
use crate::rl::Mlp;
use crate::rl::sac::{ActorMix, CriticLoss, HumanCriticConfig, Sac, UpdateStats};

// torch 2.15.0+cu132, benches/reference/torch_sac_reference.py
const SAC_LOSSES_0: [f32; 5] = [0.8060646, 0.0, -0.33957392, 0.5, -1.8509042];
const SAC_LOSSES_1: [f32; 5] = [0.73928744, 0.0, -0.4279972, 0.49502492, -1.9648921];
const SAC_FINGERPRINTS: [f32; 8] = [
    0.3737209,
    0.8586387,
    0.69946486,
    0.86071074,
    0.6859073,
    0.0,
    0.0,
    -0.71315646,
];
const SAC_ACTOR_PROBE: [f32; 4] = [0.06991044, -0.12189866, 0.4827133, -0.12455022];
const AUTHORS_LOSSES_0: [f32; 5] = [0.8060646, 0.5712106, -0.5763812, 0.5, -1.8509042];
const AUTHORS_LOSSES_1: [f32; 5] = [0.7433474, 0.51901144, -0.62594813, 0.49502492, -1.9647026];
const AUTHORS_FINGERPRINTS: [f32; 8] = [
    0.3436217,
    0.8586492,
    0.6994179,
    0.8607112,
    0.685905,
    0.026594028,
    -0.54516786,
    -0.7131564,
];
const AUTHORS_ACTOR_PROBE: [f32; 4] = [0.06991109, -0.12183206, 0.4827133, -0.1245478];
const PAPER_LOSSES_0: [f32; 5] = [0.8060646, 0.73620814, -0.8860642, 0.5, -1.8509042];
const PAPER_LOSSES_1: [f32; 5] = [0.7450588, 0.66886795, -0.96009046, 0.49502492, -1.9644417];
const PAPER_FINGERPRINTS: [f32; 8] = [
    0.35965985, 0.8586536, 0.69939584, 0.86071146, 0.68590385, 0.07957399, -0.5555318, -0.7131564,
];
const PAPER_ACTOR_PROBE: [f32; 4] = [0.06991759, -0.121809766, 0.4827133, -0.12454332];
const HUBER_LOSSES_0: [f32; 5] = [1.7055526, 0.0, -0.3462461, 0.5, -1.8509042];
const HUBER_LOSSES_1: [f32; 5] = [1.6793151, 0.0, -0.44156304, 0.49502492, -1.9648921];
const HUBER_FINGERPRINTS: [f32; 8] = [
    0.37392884,
    0.82584167,
    0.69921327,
    0.85791767,
    0.68606573,
    0.0,
    0.0,
    -0.71315646,
];
const HUBER_ACTOR_PROBE: [f32; 4] = [0.069905914, -0.12194824, 0.4827133, -0.124544784];
/// The Huber learner's rewards are this times the fixture's (the script's `HUBER_REWARD_FACTOR`).
const HUBER_REWARD_FACTOR: f32 = 3.0;
const ACTOR_PROBE: [usize; 4] = [0, 17, 40, 75];

/// The reference learner: obs 3, act 2, hidden [6, 5], batch 5, weights by formula.
fn reference_sac(human: Option<HumanCriticConfig>) -> Sac {
    let mut sac = Sac::new(3, 2, tiny_config(&[6, 5], 5, human), 0);
    let set =
        |net: &mut Mlp, n: f64| fill(net.params_mut(), |k| 0.5 * (1.3 * k + 0.1 + 0.7 * n).sin());
    set(&mut sac.actor, 0.0);
    set(&mut sac.q1, 1.0);
    set(&mut sac.q2, 2.0);
    sac.q1_target.copy_params_from(&sac.q1);
    sac.q2_target.copy_params_from(&sac.q2);
    if let Some(hc) = &mut sac.human_critic {
        set(&mut hc.h1, 3.0);
        set(&mut hc.h2, 4.0);
    }
    fill_fixed_batch_and_noise(&mut sac);
    sac
}

/// `sum_k p[k] cos(0.37 k)` and the scale `sum_k |p[k]|` its rounding is relative to.
fn fingerprint(net: Option<&Mlp>) -> (f64, f64) {
    let Some(net) = net else { return (0.0, 0.0) };
    net.params()
        .iter()
        .enumerate()
        .fold((0.0, 0.0), |(f, s), (k, &p)| {
            (
                f + f64::from(p) * (0.37 * k as f64).cos(),
                s + f64::from(p).abs(),
            )
        })
}

fn close(name: &str, got: f64, want: f64, scale: f64, tolerance: f64) -> f64 {
    let err = (got - want).abs() / scale.max(want.abs()).max(1e-3);
    assert!(
        err < tolerance,
        "{name}: got {got}, PyTorch {want} (relative error {err:.2e})"
    );
    err
}

fn check(mut sac: Sac, losses: [[f32; 5]; 2], prints: [f32; 8], probe: [f32; 4]) -> f64 {
    let mut worst = 0.0f64;
    for (step, want) in losses.iter().enumerate() {
        let s: UpdateStats = sac.gradient_step();
        let got = [
            s.critic_loss,
            s.human_critic_loss,
            s.actor_loss,
            s.ent_coef,
            s.ent_coef_loss,
        ];
        for (name, (&g, &w)) in [
            "critic",
            "human critic",
            "actor",
            "ent_coef",
            "ent_coef_loss",
        ]
        .iter()
        .zip(got.iter().zip(want))
        {
            let name = format!("update {step} {name} loss");
            worst = worst.max(close(&name, g.into(), w.into(), 0.0, 1e-5));
        }
    }
    let hc = sac.human_critic.as_ref();
    let nets = [
        Some(&sac.actor),
        Some(&sac.q1),
        Some(&sac.q2),
        Some(&sac.q1_target),
        Some(&sac.q2_target),
        hc.map(|hc| &hc.h1),
        hc.map(|hc| &hc.h2),
    ];
    let names = ["actor", "q1", "q2", "q1_target", "q2_target", "h1", "h2"];
    for ((net, name), &want) in nets.into_iter().zip(names).zip(&prints) {
        let (got, scale) = fingerprint(net);
        worst = worst.max(close(name, got, want.into(), scale, 1e-5));
    }
    worst = worst.max(close(
        "log_ent_coef",
        sac.log_ent_coef.into(),
        prints[7].into(),
        0.0,
        1e-5,
    ));
    for (&k, &want) in ACTOR_PROBE.iter().zip(&probe) {
        let got = sac.actor.params()[k];
        worst = worst.max(close(
            &format!("actor[{k}]"),
            got.into(),
            want.into(),
            0.0,
            1e-5,
        ));
    }
    worst
}

#[test]
fn plain_sac_agrees_with_pytorch() {
    crate::rl::kernels::on_every_path(|path| {
        let worst = check(
            reference_sac(None),
            [SAC_LOSSES_0, SAC_LOSSES_1],
            SAC_FINGERPRINTS,
            SAC_ACTOR_PROBE,
        );
        eprintln!("{path}: plain SAC: worst relative error {worst:.2e}");
    });
}

#[test]
fn dref_with_the_authors_mix_agrees_with_pytorch() {
    crate::rl::kernels::on_every_path(|path| {
        let human = HumanCriticConfig {
            lambda: 9.0,
            mix: ActorMix::Authors,
            ..HumanCriticConfig::default()
        };
        let worst = check(
            reference_sac(Some(human)),
            [AUTHORS_LOSSES_0, AUTHORS_LOSSES_1],
            AUTHORS_FINGERPRINTS,
            AUTHORS_ACTOR_PROBE,
        );
        eprintln!("{path}: authors' mix: worst relative error {worst:.2e}");
    });
}

#[test]
fn dref_with_the_paper_mix_and_mask_agrees_with_pytorch() {
    crate::rl::kernels::on_every_path(|path| {
        let human = HumanCriticConfig {
            lambda: 2.0,
            mix: ActorMix::Paper,
            mask: true,
            ..HumanCriticConfig::default()
        };
        let worst = check(
            reference_sac(Some(human)),
            [PAPER_LOSSES_0, PAPER_LOSSES_1],
            PAPER_FINGERPRINTS,
            PAPER_ACTOR_PROBE,
        );
        eprintln!("{path}: paper's mix, masked: worst relative error {worst:.2e}");
    });
}

#[test]
fn sac_with_the_huber_critic_loss_agrees_with_pytorch() {
    crate::rl::kernels::on_every_path(|path| {
        let mut sac = reference_sac(None);
        sac.config.critic_loss = CriticLoss::Huber;
        for r in &mut sac.buffers.batch.rewards {
            *r *= HUBER_REWARD_FACTOR;
        }
        let worst = check(
            sac,
            [HUBER_LOSSES_0, HUBER_LOSSES_1],
            HUBER_FINGERPRINTS,
            HUBER_ACTOR_PROBE,
        );
        eprintln!("{path}: SAC, Huber critic loss: worst relative error {worst:.2e}");
    });
}
