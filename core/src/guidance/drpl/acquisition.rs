//! Acquisition: how DRPL makes its final pick among the candidate pairs (algorithms.md
//! section 4, "Beyond the paper"). The paper picks uniformly; APReL's mutual information is the
//! alternative, scored over the belief's samples.

use serde::{Deserialize, Serialize};

use super::belief::{Belief, Response};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Acquisition {
    /// Uniformly among the candidates \[paper\].
    #[default]
    Uniform,
    /// The candidate with the highest mutual information with the belief \[aprel\].
    #[serde(alias = "mutual-information")]
    MutualInformation,
}

/// Mutual information (bits) between the answer to "a (first) or b (second)?" and theta under
/// the belief, as APReL's `mutual_information` computes it over a sampling-based belief:
/// with `p[m][r]` the probability of response r under sample m (M samples),
/// `I = (1 / M) sum_{m, r} p[m][r] log2(M p[m][r] / sum_m' p[m'][r])`.
///
/// The response set is the query's: {first, second} under the softmax user, or, with
/// `allow_equal`, APReL's `WeakComparisonQuery` set {first, second, equal} with its delta model.
/// Terms with `p = 0` contribute 0 (their limit).
pub fn mutual_information(belief: &Belief, a: &[f64], b: &[f64], allow_equal: bool) -> f64 {
    assert_eq!(a.len(), belief.dim(), "first segment's feature count");
    assert_eq!(b.len(), belief.dim(), "second segment's feature count");
    let config = belief.config();
    let diff: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let probabilities: Vec<[f64; 3]> = belief
        .samples()
        .map(|theta| {
            let gap: f64 = theta.iter().zip(&diff).map(|(t, d)| t * d).sum();
            if allow_equal {
                config.weak_comparison_log_probabilities(gap).map(f64::exp)
            } else {
                [
                    config.log_probability(Response::First, gap).exp(),
                    config.log_probability(Response::Second, gap).exp(),
                    0.0,
                ]
            }
        })
        .collect();
    let m = probabilities.len() as f64;
    let mut totals = [0.0; 3];
    for p in &probabilities {
        totals.iter_mut().zip(p).for_each(|(t, p)| *t += p);
    }
    let mut information = 0.0;
    for p in &probabilities {
        for (&p, &total) in p.iter().zip(&totals) {
            if p > 0.0 {
                information += p * (m * p / total).log2();
            }
        }
    }
    information / m
}

#[cfg(test)]
mod tests {
    use super::super::belief::BeliefConfig;
    use super::*;

    fn two_sample_belief() -> Belief {
        // burn_in 0, thinning 1, 2 samples, and no answers: the samples are whatever the
        // chain visits; we only need them fixed, and the formula checked against them.
        let config = BeliefConfig {
            burn_in: 0,
            thinning: 1,
            samples: 2,
            ..BeliefConfig::default()
        };
        let mut belief = Belief::new(2, config, 5);
        belief.update();
        belief
    }

    #[test]
    fn matches_the_formula_on_two_samples() {
        let belief = two_sample_belief();
        let (a, b) = ([1.0, -0.5], [-0.2, 0.7]);
        let samples: Vec<&[f64]> = belief.samples().collect();
        let sigmoid = |x: f64| 1.0 / (1.0 + (-x).exp());
        let p: Vec<[f64; 2]> = samples
            .iter()
            .map(|t| {
                let gap = t[0] * (a[0] - b[0]) + t[1] * (a[1] - b[1]);
                [sigmoid(gap), sigmoid(-gap)]
            })
            .collect();
        let mut expected = 0.0;
        for r in 0..2 {
            let total = p[0][r] + p[1][r];
            for pm in &p {
                expected += pm[r] * (2.0 * pm[r] / total).log2();
            }
        }
        expected /= 2.0;
        let got = mutual_information(&belief, &a, &b, false);
        assert!((got - expected).abs() < 1e-12, "{got} vs {expected}");
    }

    #[test]
    fn is_zero_for_identical_segments_and_bounded_by_the_response_entropy() {
        let mut belief = Belief::new(3, BeliefConfig::default(), 1);
        belief.update(); // no answers: samples spread over the sphere
        let a = [0.4, -1.0, 2.0];
        assert!(mutual_information(&belief, &a, &a, false).abs() < 1e-12);
        assert!(mutual_information(&belief, &a, &a, true).abs() < 1e-12);
        let b = [-1.0, 0.5, -2.0];
        let strict = mutual_information(&belief, &a, &b, false);
        let weak = mutual_information(&belief, &a, &b, true);
        assert!(strict > 0.05 && strict <= 1.0, "{strict}");
        assert!(weak > 0.05 && weak <= 3f64.log2(), "{weak}");
    }

    #[test]
    fn prefers_pairs_the_samples_disagree_on() {
        let mut belief = Belief::new(2, BeliefConfig::default(), 2);
        // Teach "feature 0 is good": the samples agree about feature 0, not feature 1.
        for _ in 0..30 {
            belief.add_answer(&[1.0, 0.0], &[-1.0, 0.0], Response::First);
        }
        belief.update();
        let settled = mutual_information(&belief, &[2.0, 0.0], &[-2.0, 0.0], false);
        let open = mutual_information(&belief, &[0.0, 2.0], &[0.0, -2.0], false);
        assert!(open > settled, "open {open} vs settled {settled}");
    }

    #[test]
    fn acquisition_serialises_in_snake_case() {
        let json = serde_json::to_string(&Acquisition::MutualInformation).unwrap();
        assert_eq!(json, "\"mutual_information\"");
    }
}
