//! DRPL's belief over the reward weights theta (r = theta . Phi, ||theta|| = 1): APReL's
//! `SamplingBasedBelief` with a `SoftmaxUser`, sampled by Metropolis-Hastings
//! (algorithms.md section 3, steps 5-6).
//!
//! What follows APReL (`aprel/learning/belief_models.py`, `user_models.py`,
//! `utils/sampling_utils.py`):
//! - Likelihood of a strict answer: `log P(choose j) = beta R_j - logsumexp_k(beta R_k)` over
//!   the pair; of "about equal": the weak-comparison model with `delta` (see [`BeliefConfig`]).
//! - Prior: uniform on `||theta|| <= 1` (log prior 0 or -inf); we allow 1e-9 of slack so that
//!   rounding in the renormalisation never rejects a point on the sphere.
//! - Proposal: `theta + N(0, proposal_std^2 I)`, renormalised to unit length.
//! - Chain: starts at the previous samples' normalised mean, makes
//!   `burn_in + thinning * samples - 1` proposals and keeps the states after `burn_in`,
//!   `burn_in + thinning`, ... proposals (APReL's `samples[burnin::thin]`).
//!
//! Where we differ, for speed only: every answer is stored once as a reward-difference row in
//! one contiguous buffer (`answers`), so a proposal's log-likelihood is one pass over `N x D`
//! numbers that stops early once rejection is certain, and the chain allocates nothing per
//! proposal. Randomness is consumed only by [`Belief::new`] and
//! [`Belief::update`], never by recording or forgetting answers.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

mod answers;

use answers::Answers;

/// Slack on the prior's `||theta|| <= 1`: a renormalised proposal can have norm 1 + 1 ulp.
const PRIOR_SLACK: f64 = 1e-9;

/// Sampling and user-model parameters. Defaults are APReL's (`SoftmaxUser`,
/// `SamplingBasedBelief`, `gaussian_proposal`): 200 + 20 * 100 - 1 = 2199 proposals per update.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeliefConfig {
    /// Rationality of the softmax user.
    pub beta: f64,
    /// Perceivable reward difference of APReL's weak-comparison model ("about equal").
    /// Must be positive for "about equal" answers to have non-zero probability.
    pub delta: f64,
    /// Standard deviation of the Gaussian proposal step, before renormalisation.
    pub proposal_std: f64,
    /// Proposals discarded before the first kept sample.
    pub burn_in: usize,
    /// Proposals between kept samples.
    pub thinning: usize,
    /// Samples kept per update.
    pub samples: usize,
}

impl Default for BeliefConfig {
    fn default() -> Self {
        Self {
            beta: 1.0,
            delta: 0.1,
            proposal_std: 0.05,
            burn_in: 200,
            thinning: 20,
            samples: 100,
        }
    }
}

impl BeliefConfig {
    /// Proposals per update: `burn_in + thinning * samples - 1` (APReL's chain length).
    pub fn proposals(&self) -> usize {
        self.burn_in + self.thinning * self.samples - 1
    }

    /// `log P(response)` under APReL's `SoftmaxUser` for a pair whose reward gap is
    /// `gap = theta . (a - b)` (first minus second).
    ///
    /// With `x = beta * gap`:
    /// - First: `beta R_a - logsumexp(beta R_a, beta R_b) = -softplus(-x)`;
    /// - Second: `-softplus(x)`;
    /// - Equal (APReL's `WeakComparison` with response -1, derived from its three lines:
    ///   `logp_first = -log(1 + exp(delta + r_b - r_a))`, `logp_second = -log(1 + exp(delta +
    ///   r_a - r_b))`, `logp_equal = log(exp(2 delta) - 1) + logp_first + logp_second`):
    ///   `log(e^{2 delta} - 1) - softplus(delta - x) - softplus(delta + x)`.
    ///   Note that delta is not scaled by beta, as in APReL.
    pub fn log_probability(&self, response: Response, gap: f64) -> f64 {
        let x = self.beta * gap;
        match response {
            Response::First => -softplus(-x),
            Response::Second => -softplus(x),
            Response::Equal => log_equal_constant(self.delta) - weak_pair(self.delta, x),
        }
    }

    /// APReL's `WeakComparisonQuery` response distribution, as log-probabilities of
    /// `[First, Second, Equal]`; they sum (in probability) to one:
    /// with `p = 1 / (1 + e^{delta - x})`, `q = 1 / (1 + e^{delta + x})`,
    /// `p + q + (e^{2 delta} - 1) p q = 1`.
    pub fn weak_comparison_log_probabilities(&self, gap: f64) -> [f64; 3] {
        let x = self.beta * gap;
        let first = -softplus(self.delta - x);
        let second = -softplus(self.delta + x);
        [
            first,
            second,
            log_equal_constant(self.delta) + first + second,
        ]
    }

    fn validate(&self) {
        assert!(self.beta.is_finite(), "beta must be finite");
        assert!(self.delta >= 0.0, "delta must be non-negative");
        assert!(
            self.proposal_std.is_finite() && self.proposal_std > 0.0,
            "proposal_std must be positive"
        );
        assert!(self.thinning >= 1, "thinning must be at least 1");
        assert!(self.samples >= 1, "samples must be at least 1");
    }
}

/// A trainer's answer to "which segment is better?". "Skip" never reaches the belief.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Response {
    First,
    Second,
    Equal,
}

/// A set of posterior samples of theta and the answers that define the posterior.
#[derive(Clone, Debug)]
pub struct Belief {
    dim: usize,
    config: BeliefConfig,
    rng: ChaCha8Rng,
    answers: Answers,
    /// `samples x dim`, row-major; each row unit length.
    samples: Vec<f64>,
    /// Chain state and proposal, preallocated so that `update` allocates nothing.
    current: Vec<f64>,
    proposal: Vec<f64>,
}

impl Belief {
    /// A belief holding `config.samples` draws from the prior (uniform directions) until the
    /// first [`update`](Self::update).
    pub fn new(dim: usize, config: BeliefConfig, seed: u64) -> Self {
        assert!(dim >= 1, "theta needs at least one feature");
        config.validate();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut samples = vec![0.0; config.samples * dim];
        for sample in samples.chunks_exact_mut(dim) {
            fill_random_unit(sample, &mut rng);
        }
        Self {
            dim,
            config,
            rng,
            answers: Answers::new(dim, &config),
            samples,
            current: vec![0.0; dim],
            proposal: vec![0.0; dim],
        }
    }

    pub fn dim(&self) -> usize {
        self.dim
    }

    pub fn config(&self) -> &BeliefConfig {
        &self.config
    }

    pub fn answers(&self) -> usize {
        self.answers.len()
    }

    /// Record an answer on features a (first) and b (second); does not resample.
    pub fn add_answer(&mut self, a: &[f64], b: &[f64], response: Response) {
        assert_eq!(a.len(), self.dim, "first segment's feature count");
        assert_eq!(b.len(), self.dim, "second segment's feature count");
        self.answers.push(a, b, response);
    }

    /// Forget answer `index` (a trainer's undo); does not resample. The remaining answers keep
    /// their order and exact values, and no randomness is consumed, so an undo before the next
    /// update leaves no trace: the next update equals one on a belief that never had the answer.
    pub fn remove_answer(&mut self, index: usize) {
        assert!(index < self.answers(), "no answer {index}");
        self.answers.remove(index);
    }

    /// Metropolis-Hastings from the previous normalised mean: burn_in + thinning * samples - 1
    /// proposals (APReL's `create_samples`).
    pub fn update(&mut self) {
        self.run_chain();
    }

    /// The chain behind [`update`](Self::update); returns how many proposals it made (the
    /// tests' hook on the chain length).
    fn run_chain(&mut self) -> usize {
        let BeliefConfig {
            proposal_std,
            burn_in,
            thinning,
            ..
        } = self.config;
        let total = self.config.proposals();

        // APReL starts from `self.mean`, the previous samples' mean normalised; before the
        // first update those are prior draws, whose normalised mean is itself uniform.
        self.current.fill(0.0);
        for sample in self.samples.chunks_exact(self.dim) {
            self.current
                .iter_mut()
                .zip(sample)
                .for_each(|(c, s)| *c += s);
        }
        if !normalise(&mut self.current) {
            fill_random_unit(&mut self.current, &mut self.rng);
        }
        let mut current_logprob =
            log_prior(&self.current) + self.answers.log_likelihood(&self.current);

        let mut made = 0;
        for step in 0..=total {
            if step > 0 {
                for (p, c) in self.proposal.iter_mut().zip(&self.current) {
                    *p = c + proposal_std * self.rng.sample::<f64, _>(StandardNormal);
                }
                normalise(&mut self.proposal);
                // APReL accepts iff ln(u) < next - current; we draw u first and test
                // next > current + ln(u), so the likelihood pass can stop as soon as its
                // partial sum (an upper bound) is below that floor: same decisions, less work.
                let floor = current_logprob + self.rng.random::<f64>().ln();
                let prior = log_prior(&self.proposal);
                // Skip the likelihood outside the prior: the proposal is rejected either way.
                let proposal_logprob = if prior.is_finite() {
                    prior
                        + self
                            .answers
                            .log_likelihood_above(&self.proposal, floor - prior)
                } else {
                    f64::NEG_INFINITY
                };
                if proposal_logprob > floor {
                    std::mem::swap(&mut self.current, &mut self.proposal);
                    current_logprob = proposal_logprob;
                }
                made += 1;
            }
            if step >= burn_in && (step - burn_in) % thinning == 0 {
                let j = (step - burn_in) / thinning;
                self.samples[j * self.dim..(j + 1) * self.dim].copy_from_slice(&self.current);
            }
        }
        made
    }

    /// The posterior samples, each unit length.
    pub fn samples(&self) -> impl Iterator<Item = &[f64]> {
        self.samples.chunks_exact(self.dim)
    }

    /// Mean of the samples (not normalised; APReL's `mean` normalises it).
    pub fn mean(&self) -> Vec<f64> {
        let mut mean = vec![0.0; self.dim];
        for sample in self.samples() {
            mean.iter_mut().zip(sample).for_each(|(m, s)| *m += s);
        }
        let n = self.config.samples as f64;
        mean.iter_mut().for_each(|m| *m /= n);
        mean
    }

    /// Mean over samples of `cos(theta_i, theta_true)` (the spec's alignment metric; NaN when
    /// `theta_true` is zero). APReL's own `assessing.cosine_similarity` scores the normalised
    /// mean instead: that is [`alignment_of_mean`](Self::alignment_of_mean).
    pub fn alignment(&self, theta_true: &[f64]) -> f64 {
        assert_eq!(theta_true.len(), self.dim, "theta_true's size");
        let norm = dot(theta_true, theta_true).sqrt();
        let total: f64 = self
            .samples()
            .map(|s| dot(s, theta_true) / (norm * dot(s, s).sqrt()))
            .sum();
        total / self.config.samples as f64
    }

    /// `cos(mean, theta_true)`.
    pub fn alignment_of_mean(&self, theta_true: &[f64]) -> f64 {
        assert_eq!(theta_true.len(), self.dim, "theta_true's size");
        let mean = self.mean();
        dot(&mean, theta_true) / (dot(&mean, &mean) * dot(theta_true, theta_true)).sqrt()
    }

    /// Log-likelihood of all recorded answers at theta (no prior).
    pub fn log_likelihood(&self, theta: &[f64]) -> f64 {
        assert_eq!(theta.len(), self.dim, "theta's size");
        self.answers.log_likelihood(theta)
    }
}

/// A direction uniform on the unit sphere: a normalised standard Gaussian
/// (APReL's `get_random_normalized_vector`).
pub fn random_unit_vector(dim: usize, rng: &mut impl Rng) -> Vec<f64> {
    let mut v = vec![0.0; dim];
    fill_random_unit(&mut v, rng);
    v
}

fn fill_random_unit(v: &mut [f64], rng: &mut impl Rng) {
    assert!(!v.is_empty(), "a direction needs at least one dimension");
    loop {
        for e in v.iter_mut() {
            *e = rng.sample(StandardNormal);
        }
        if normalise(v) {
            return;
        }
    }
}

/// Scales `v` to unit length; false (leaving `v` as it was) if its norm is zero or not finite.
fn normalise(v: &mut [f64]) -> bool {
    let norm = dot(v, v).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return false;
    }
    let inverse = 1.0 / norm; // one division, not D: this runs once per proposal
    v.iter_mut().for_each(|e| *e *= inverse);
    true
}

/// APReL's `uniform_logprior` with slack: 0 inside the unit ball, -inf outside.
fn log_prior(theta: &[f64]) -> f64 {
    if dot(theta, theta).sqrt() <= 1.0 + PRIOR_SLACK {
        0.0
    } else {
        f64::NEG_INFINITY
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `ln(1 + e^z)` without overflow.
fn softplus(z: f64) -> f64 {
    z.max(0.0) + (-z.abs()).exp().ln_1p()
}

/// `softplus(delta - x) + softplus(delta + x)`: minus the two weak-comparison factors.
fn weak_pair(delta: f64, x: f64) -> f64 {
    softplus(delta - x) + softplus(delta + x)
}

/// `ln(e^{2 delta} - 1)`: -inf when delta = 0 ("equal" then has probability zero).
fn log_equal_constant(delta: f64) -> f64 {
    (2.0 * delta).exp_m1().ln()
}

#[cfg(test)]
mod tests;
