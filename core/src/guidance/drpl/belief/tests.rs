use super::*;

const TOL: f64 = 1e-12;

/// theta = (0.6, 0.8), a = (1, 0), b = (0, 1): R_a = 0.6, R_b = 0.8, gap = R_a - R_b = -0.2.
const THETA: [f64; 2] = [0.6, 0.8];
const A: [f64; 2] = [1.0, 0.0];
const B: [f64; 2] = [0.0, 1.0];

fn one_answer(beta: f64, response: Response) -> Belief {
    let config = BeliefConfig {
        beta,
        ..BeliefConfig::default()
    };
    let mut belief = Belief::new(2, config, 0);
    belief.add_answer(&A, &B, response);
    belief
}

#[test]
fn strict_and_equal_likelihoods_match_hand_computed_values_beta_1() {
    // First:  0.6 - ln(e^0.6 + e^0.8) = -ln(1 + e^0.2)  = -ln(2.2214028) = -0.7981388693815918
    // Second: 0.8 - ln(e^0.6 + e^0.8) = -ln(1 + e^-0.2) = -ln(1.8187308) = -0.5981388693815918
    // Equal (delta = 0.1): ln(e^0.2 - 1) - ln(1 + e^(0.1 + 0.2)) - ln(1 + e^(0.1 - 0.2))
    //   = ln(0.2214028) - ln(2.3498588) - ln(1.9048374)
    //   = -1.5077718009705199 - 0.8543552444685272 - 0.6443966600735709 = -3.006523705512618
    let cases = [
        (Response::First, -0.798_138_869_381_591_8),
        (Response::Second, -0.598_138_869_381_591_8),
        (Response::Equal, -3.006_523_705_512_618),
    ];
    for (response, expected) in cases {
        let got = one_answer(1.0, response).log_likelihood(&THETA);
        assert!(
            (got - expected).abs() < TOL,
            "{response:?}: {got} vs {expected}"
        );
        let direct = BeliefConfig::default().log_probability(response, -0.2);
        assert!((direct - expected).abs() < TOL, "{response:?}: {direct}");
    }
}

#[test]
fn strict_and_equal_likelihoods_match_hand_computed_values_beta_2() {
    // beta = 2 scales the rewards: x = 2 * (-0.2) = -0.4; delta stays 0.1 (APReL does not scale it).
    // First:  -ln(1 + e^0.4)  = -0.9130152523999527
    // Second: -ln(1 + e^-0.4) = -0.5130152523999526
    // Equal:  ln(e^0.2 - 1) - ln(1 + e^0.5) - ln(1 + e^-0.3)
    //   = -1.5077718009705199 - 0.9740769841801067 - 0.5543552444685270 = -3.036204029619154
    let cases = [
        (Response::First, -0.913_015_252_399_952_7),
        (Response::Second, -0.513_015_252_399_952_6),
        (Response::Equal, -3.036_204_029_619_154),
    ];
    for (response, expected) in cases {
        let got = one_answer(2.0, response).log_likelihood(&THETA);
        assert!(
            (got - expected).abs() < TOL,
            "{response:?}: {got} vs {expected}"
        );
    }
}

#[test]
fn answers_add_up_and_weak_comparison_probabilities_sum_to_one() {
    let mut belief = one_answer(1.0, Response::First);
    belief.add_answer(&A, &B, Response::Second);
    belief.add_answer(&A, &B, Response::Equal);
    let sum = -0.798_138_869_381_591_8 - 0.598_138_869_381_591_8 - 3.006_523_705_512_618;
    assert!((belief.log_likelihood(&THETA) - sum).abs() < TOL);
    assert_eq!(belief.answers(), 3);

    let config = BeliefConfig::default();
    for gap in [-30.0, -1.3, -0.2, 0.0, 0.7, 25.0] {
        let total: f64 = config
            .weak_comparison_log_probabilities(gap)
            .iter()
            .map(|l| l.exp())
            .sum();
        assert!((total - 1.0).abs() < 1e-12, "gap {gap}: {total}");
    }
    // Extreme gaps stay finite (stable softplus, no overflow in the product).
    let mut far = Belief::new(2, config, 0);
    for _ in 0..600 {
        far.add_answer(&[500.0, 0.0], &[0.0, 0.0], Response::Second);
    }
    let ll = far.log_likelihood(&[1.0, 0.0]);
    assert!((ll - -600.0 * 500.0).abs() < 1e-6, "{ll}");
}

/// `n` random Gaussian feature pairs answered by the deterministic oracle of the spec.
fn oracle_answers(
    theta: &[f64],
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<(Vec<f64>, Vec<f64>, Response)> {
    (0..n)
        .map(|_| {
            let a: Vec<f64> = (0..theta.len())
                .map(|_| rng.sample(StandardNormal))
                .collect();
            let b: Vec<f64> = (0..theta.len())
                .map(|_| rng.sample(StandardNormal))
                .collect();
            let response = if dot(theta, &a) > dot(theta, &b) {
                Response::First
            } else {
                Response::Second
            };
            (a, b, response)
        })
        .collect()
}

/// Mean alignment (over samples, then of the mean) after 60 answers, one update per answer as
/// DRPL's query loop does, averaged over three seeds.
fn recovered_alignment(dim: usize) -> (f64, f64) {
    let seeds = 3;
    let (mut samples, mut mean) = (0.0, 0.0);
    for seed in 0..seeds {
        let mut rng = ChaCha8Rng::seed_from_u64(100 + seed);
        let theta = random_unit_vector(dim, &mut rng);
        let mut belief = Belief::new(dim, BeliefConfig::default(), seed);
        for (a, b, response) in oracle_answers(&theta, 60, &mut rng) {
            belief.add_answer(&a, &b, response);
            belief.update();
        }
        let (s, m) = (belief.alignment(&theta), belief.alignment_of_mean(&theta));
        assert!(s > 0.85, "dim {dim} seed {seed}: alignment {s}");
        samples += s / seeds as f64;
        mean += m / seeds as f64;
    }
    (samples, mean)
}

#[test]
fn metropolis_hastings_recovers_theta_in_4_dimensions() {
    let (samples, mean) = recovered_alignment(4);
    eprintln!("dim 4: alignment {samples:.3}, of mean {mean:.3}");
    assert!(samples > 0.9, "{samples}");
    assert!(mean > samples);
}

#[test]
fn metropolis_hastings_recovers_theta_in_6_dimensions() {
    let (samples, mean) = recovered_alignment(6);
    eprintln!("dim 6: alignment {samples:.3}, of mean {mean:.3}");
    assert!(samples > 0.9, "{samples}");
    assert!(mean > samples);
}

#[test]
fn without_answers_alignment_is_near_zero_on_average() {
    let trials = 40;
    let (mut prior, mut updated) = (0.0, 0.0);
    for seed in 0..trials {
        let mut rng = ChaCha8Rng::seed_from_u64(1000 + seed);
        let theta = random_unit_vector(6, &mut rng);
        let mut belief = Belief::new(6, BeliefConfig::default(), seed);
        prior += belief.alignment(&theta) / trials as f64;
        belief.update();
        updated += belief.alignment(&theta) / trials as f64;
    }
    eprintln!("no answers: alignment {prior:.3} (prior draws), {updated:.3} (after update)");
    assert!(prior.abs() < 0.05, "{prior}");
    assert!(updated.abs() < 0.15, "{updated}");
}

fn fixed_answers(belief: &mut Belief, n: usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let theta = random_unit_vector(belief.dim(), &mut rng);
    for (a, b, response) in oracle_answers(&theta, n, &mut rng) {
        belief.add_answer(&a, &b, response);
    }
}

fn sample_bits(belief: &Belief) -> Vec<u64> {
    belief.samples().flatten().map(|x| x.to_bits()).collect()
}

#[test]
fn same_seed_and_answers_give_identical_samples() {
    let run = || {
        let mut belief = Belief::new(5, BeliefConfig::default(), 42);
        fixed_answers(&mut belief, 10);
        belief.update();
        belief.add_answer(&[1.0; 5], &[0.0; 5], Response::Equal);
        belief.update();
        sample_bits(&belief)
    };
    assert_eq!(run(), run());
    let mut other = Belief::new(5, BeliefConfig::default(), 43);
    fixed_answers(&mut other, 10);
    other.update();
    other.add_answer(&[1.0; 5], &[0.0; 5], Response::Equal);
    other.update();
    assert_ne!(
        run(),
        sample_bits(&other),
        "a different seed gives a different chain"
    );
}

/// Recording and forgetting answers consume no randomness and touch no sample, so a belief
/// that got an answer and then forgot it (before resampling) has the same RNG position, the
/// same chain start and the same answer buffer as one that never got it: its next update is
/// bit-identical. (Forgetting an answer already folded into an update cannot be bit-exact:
/// the chain restarts from a mean that saw it, and only burn-in washes that out.)
#[test]
fn remove_then_update_equals_never_having_added() {
    let extra = ([0.3, -1.0, 2.0, 0.5], [1.0, 0.2, -0.4, 0.0]);

    let mut with = Belief::new(4, BeliefConfig::default(), 9);
    let mut without = Belief::new(4, BeliefConfig::default(), 9);
    fixed_answers(&mut with, 5);
    fixed_answers(&mut without, 5);
    with.update();
    without.update();

    // An answer in the middle of the buffer: later rows must keep their order and values.
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let theta = random_unit_vector(4, &mut rng);
    let more = oracle_answers(&theta, 4, &mut rng);
    with.add_answer(&extra.0, &extra.1, Response::First);
    for (a, b, response) in &more {
        with.add_answer(a, b, *response);
        without.add_answer(a, b, *response);
    }
    with.remove_answer(5);
    assert_eq!(with.answers(), without.answers());
    assert_eq!(
        with.log_likelihood(&theta).to_bits(),
        without.log_likelihood(&theta).to_bits()
    );

    with.update();
    without.update();
    assert_eq!(sample_bits(&with), sample_bits(&without));
}

#[test]
fn samples_are_unit_vectors_and_an_update_makes_exactly_2199_proposals() {
    let mut belief = Belief::new(6, BeliefConfig::default(), 3);
    assert_eq!(belief.config().proposals(), 2199);
    fixed_answers(&mut belief, 20);
    for _ in 0..3 {
        assert_eq!(belief.run_chain(), 2199);
        assert_eq!(belief.samples().count(), 100);
        for sample in belief.samples() {
            assert!((dot(sample, sample).sqrt() - 1.0).abs() < 1e-12);
        }
    }
    let mean = belief.mean();
    assert!(dot(&mean, &mean).sqrt() <= 1.0 + 1e-12);
}

#[test]
fn custom_chain_lengths_keep_the_configured_samples() {
    let config = BeliefConfig {
        burn_in: 0,
        thinning: 1,
        samples: 7,
        ..BeliefConfig::default()
    };
    let mut belief = Belief::new(3, config, 0);
    fixed_answers(&mut belief, 3);
    assert_eq!(belief.run_chain(), 6);
    assert_eq!(belief.samples().count(), 7);
}
