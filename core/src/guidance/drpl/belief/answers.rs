//! The recorded answers as one column-major `D x N` buffer of reward differences, and the
//! likelihood pass over it that every Metropolis-Hastings proposal pays for.
//!
//! Each answer is one column `beta * (chosen - other)` for strict answers (so First and Second
//! share one formula) or `beta * (first - second)` for "about equal"; strict columns come first,
//! then equal ones, each group in recording order. With `x = theta . column` every
//! log-probability is a sum of `-softplus(z)` terms plus a constant (see
//! `BeliefConfig::log_probability`), and `softplus(z) = max(z, 0) + ln(1 + e^{-|z|})`.
//!
//! Why this shape: a proposal's cost is this pass. Column-major blocks make `theta . column`
//! a vector loop over answers; the hinges are summed and the `1 + e^{-|z|}` factors (each in
//! (1, 2]) multiplied per block, so a block needs one `ln` rather than an `ln_1p` per answer;
//! and the exponentials use a branch-free polynomial that the compiler vectorises (libm's
//! `exp`, one call per answer, was 60% of an update).

use super::{BeliefConfig, Response};

/// Answers per block: at most 2 factors of at most 2 each, so a block's product stays below
/// 4^64 = 2^128 and its `ln` is exact to rounding. Smaller blocks would let the early exit
/// stop sooner, but each costs an `ln`; 64 timed best for 40 to 200 answers.
const BLOCK: usize = 64;

/// Independent accumulators: two AVX2 vectors (or four SSE2 ones), enough independent chains
/// to hide the exponential's latency.
const LANES: usize = 8;

/// How a stored column enters the likelihood.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Column = beta * (chosen - other): `log P = -softplus(-x)`.
    Strict,
    /// Column = beta * (first - second): `log P = log(e^{2 delta} - 1) - softplus(delta - x)
    /// - softplus(delta + x)`.
    Equal,
}

#[derive(Clone, Debug)]
pub(super) struct Answers {
    dim: usize,
    beta: f64,
    delta: f64,
    /// `log(e^{2 delta} - 1)`, the constant of each "equal" term.
    log_equal: f64,
    /// `dim x len`, column-major: feature k of stored column j at `k * len + j`.
    columns: Vec<f64>,
    /// Kinds in recording order (answer i's column is found by counting its kind before i).
    order: Vec<Kind>,
    /// Strict answers: columns `0..strict`; equal ones: `strict..len`.
    strict: usize,
}

impl Answers {
    pub(super) fn new(dim: usize, config: &BeliefConfig) -> Self {
        Self {
            dim,
            beta: config.beta,
            delta: config.delta,
            log_equal: super::log_equal_constant(config.delta),
            columns: Vec::new(),
            order: Vec::new(),
            strict: 0,
        }
    }

    pub(super) fn len(&self) -> usize {
        self.order.len()
    }

    pub(super) fn push(&mut self, a: &[f64], b: &[f64], response: Response) {
        let (chosen, other, kind) = match response {
            Response::First => (a, b, Kind::Strict),
            Response::Second => (b, a, Kind::Strict),
            Response::Equal => (a, b, Kind::Equal),
        };
        let at = match kind {
            Kind::Strict => self.strict,
            Kind::Equal => self.len(),
        };
        let beta = self.beta;
        let column: Vec<f64> = chosen
            .iter()
            .zip(other)
            .map(|(c, o)| beta * (c - o))
            .collect();
        let len = self.len();
        let mut columns = Vec::with_capacity(self.dim * (len + 1));
        for (k, value) in column.iter().enumerate() {
            let row = &self.columns[k * len..(k + 1) * len];
            columns.extend_from_slice(&row[..at]);
            columns.push(*value);
            columns.extend_from_slice(&row[at..]);
        }
        self.columns = columns;
        self.order.push(kind);
        self.strict += usize::from(kind == Kind::Strict);
    }

    /// Removes answer `index`; the others keep their order and exact values.
    pub(super) fn remove(&mut self, index: usize) {
        let kind = self.order[index];
        let before = self.order[..index].iter().filter(|k| **k == kind).count();
        let at = match kind {
            Kind::Strict => before,
            Kind::Equal => self.strict + before,
        };
        let len = self.len();
        let mut columns = Vec::with_capacity(self.dim * (len - 1));
        for k in 0..self.dim {
            let row = &self.columns[k * len..(k + 1) * len];
            columns.extend_from_slice(&row[..at]);
            columns.extend_from_slice(&row[at + 1..]);
        }
        self.columns = columns;
        self.order.remove(index);
        self.strict -= usize::from(kind == Kind::Strict);
    }

    /// Sum of the answers' log-probabilities at theta.
    pub(super) fn log_likelihood(&self, theta: &[f64]) -> f64 {
        self.log_likelihood_above(theta, f64::NEG_INFINITY)
    }

    /// The log-likelihood at theta, or, once a partial sum falls below `floor`, that partial
    /// sum. Every term is <= 0, so a partial sum bounds the total from above: a value below
    /// `floor` is all Metropolis-Hastings needs to reject, and the rest of the pass is skipped.
    pub(super) fn log_likelihood_above(&self, theta: &[f64], floor: f64) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, the only requirement of `pass_avx2`.
            return unsafe { self.pass_avx2(theta, floor) };
        }
        self.pass(theta, floor)
    }

    /// [`pass`](Self::pass) compiled for AVX2: four f64 lanes instead of SSE2's two. The same
    /// operations in the same order (no fused multiply-add), so the results are bit-identical.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn pass_avx2(&self, theta: &[f64], floor: f64) -> f64 {
        self.pass(theta, floor)
    }

    #[inline(always)]
    fn pass(&self, theta: &[f64], floor: f64) -> f64 {
        let len = self.len();
        let equal = len - self.strict;
        // 0 rather than 0 * -inf when delta = 0 and no "equal" answer exists.
        let mut total = if equal == 0 {
            0.0
        } else {
            equal as f64 * self.log_equal
        };
        let mut x = [0.0; BLOCK];
        let mut start = 0;
        while start < len {
            let kind = if start < self.strict {
                Kind::Strict
            } else {
                Kind::Equal
            };
            let end = match kind {
                Kind::Strict => self.strict.min(start + BLOCK),
                Kind::Equal => len.min(start + BLOCK),
            };
            let x = &mut x[..end - start];
            x.fill(0.0);
            for (k, t) in theta.iter().enumerate() {
                let column = &self.columns[k * len + start..k * len + end];
                x.iter_mut().zip(column).for_each(|(x, c)| *x += t * c);
            }
            let (hinge, product) = match kind {
                Kind::Strict => strict_terms(x),
                Kind::Equal => equal_terms(x, self.delta),
            };
            total -= hinge + product.ln();
            if total < floor {
                return total;
            }
            start = end;
        }
        total
    }
}

#[inline(always)]
/// For strict answers (`-softplus(-x)` each): `(sum max(-x, 0), prod (1 + e^{-|x|}))`, in `LANES`
/// interleaved lanes so that the loop runs as SIMD.
fn strict_terms(x: &[f64]) -> (f64, f64) {
    let (mut hinge, mut product) = ([0.0; LANES], [1.0; LANES]);
    let chunks = x.chunks_exact(LANES);
    let rest = chunks.remainder();
    for chunk in chunks {
        for lane in 0..LANES {
            hinge[lane] += (-chunk[lane]).max(0.0);
            product[lane] *= 1.0 + exp_nonpositive(-chunk[lane].abs());
        }
    }
    for &x in rest {
        hinge[0] += (-x).max(0.0);
        product[0] *= 1.0 + exp_nonpositive(-x.abs());
    }
    fold(hinge, product)
}

#[inline(always)]
/// For "about equal" answers (`-softplus(delta - x) - softplus(delta + x)` each, constant
/// apart): the same sums over both softplus terms.
fn equal_terms(x: &[f64], delta: f64) -> (f64, f64) {
    let (mut hinge, mut product) = ([0.0; LANES], [1.0; LANES]);
    for (i, &x) in x.iter().enumerate() {
        let (z1, z2) = (delta - x, delta + x);
        hinge[i % LANES] += z1.max(0.0) + z2.max(0.0);
        product[i % LANES] *=
            (1.0 + exp_nonpositive(-z1.abs())) * (1.0 + exp_nonpositive(-z2.abs()));
    }
    fold(hinge, product)
}

#[inline(always)]
fn fold(hinge: [f64; LANES], product: [f64; LANES]) -> (f64, f64) {
    (hinge.iter().sum(), product.iter().product())
}

/// `e^z` for `z <= 0` (-inf and anything below -700 give ~1e-304, which is 0 next to the 1 it
/// is added to), branch-free so that it vectorises; relative error below 1e-15.
///
/// `e^z = 2^n e^r` with `n = round(z / ln 2)` and `|r| <= ln(2) / 2`, `r` from a two-part
/// `ln 2` (Cody-Waite); `e^r` is its Taylor series to degree 12 (truncation error
/// `0.35^13 / 13! < 2e-16`); `2^n` is built in the exponent bits.
#[inline(always)]
fn exp_nonpositive(z: f64) -> f64 {
    const LOG2_E: f64 = std::f64::consts::LOG2_E;
    const LN2_HI: f64 = 6.931_471_803_691_238e-1; // ln 2 with its low 32 bits cleared
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10; // ln 2 - LN2_HI
    // 1.5 * 2^52: adding it rounds to an integer, held in the low mantissa bits.
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    // Taylor coefficients 1/k!, k = 12 down to 2.
    const C: [f64; 11] = [
        1.0 / 479_001_600.0,
        1.0 / 39_916_800.0,
        1.0 / 3_628_800.0,
        1.0 / 362_880.0,
        1.0 / 40_320.0,
        1.0 / 5_040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        1.0 / 2.0,
    ];
    let z = z.max(-700.0);
    let shifted = z * LOG2_E + SHIFT;
    let n = shifted - SHIFT;
    let r = (z - n * LN2_HI) - n * LN2_LO;
    let mut p = C[0];
    for c in &C[1..] {
        p = p * r + c;
    }
    let e_r = (p * r + 1.0) * r + 1.0;
    // The low bits of `shifted` hold n (two's complement); n + 1023 in [1, 1023] is 2^n's
    // biased exponent, and the shift drops everything above it.
    let two_n = f64::from_bits(shifted.to_bits().wrapping_add(1023) << 52);
    e_r * two_n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_matches_libm_to_1e15_relative() {
        let mut worst: f64 = 0.0;
        for i in 0..=700_000 {
            let z = -(i as f64) * 1e-3 - 1e-7 * (i % 7) as f64;
            let (fast, libm) = (exp_nonpositive(z), z.exp());
            worst = worst.max(((fast - libm) / libm).abs());
        }
        assert!(worst < 1e-15, "worst relative error {worst:e}");
        assert_eq!(exp_nonpositive(0.0), 1.0);
        assert!(exp_nonpositive(f64::NEG_INFINITY) < 1e-300);
        assert!(exp_nonpositive(-1e6) >= 0.0);
    }

    #[test]
    fn early_exit_returns_a_bound_below_the_floor_or_the_exact_value() {
        let config = BeliefConfig::default();
        let mut answers = Answers::new(2, &config);
        for i in 0..100 {
            let response = [Response::First, Response::Second, Response::Equal][i % 3];
            answers.push(&[1.0, i as f64 * 0.01], &[0.0, 1.0], response);
        }
        let theta = [0.6, 0.8];
        let exact = answers.log_likelihood(&theta);
        assert_eq!(answers.log_likelihood_above(&theta, exact - 1.0), exact);
        let bound = answers.log_likelihood_above(&theta, -1.0);
        assert!(bound < -1.0 && bound >= exact, "{bound} vs {exact}");
    }
}
