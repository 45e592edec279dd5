//! The tests against scipy, on the datasets of `benches/reference/within_subject_reference.py`
//! (scipy 1.17.1, numpy 2.4.6; its printed values are pasted below), and the parts scipy does
//! not cover: missing cells, Holm by hand, the caution, degenerate inputs.

use super::*;

/// Agreement asked of every statistic and p-value against scipy.
const TOL: f64 = 1e-6;

fn assert_close(got: f64, want: f64, what: &str) {
    assert!(
        (got - want).abs() < TOL,
        "{what}: got {got:.12e}, scipy {want:.12e}"
    );
}

const N6_NO_TIES: [[f64; 3]; 6] = [
    [3.1, 4.7, 5.2],
    [2.4, 3.9, 3.5],
    [4.0, 6.2, 5.1],
    [1.5, 2.3, 4.6],
    [3.3, 3.0, 4.4],
    [2.8, 4.1, 5.9],
];
const N6_LIKERT: [[f64; 3]; 6] = [
    [3.0, 5.0, 6.0],
    [4.0, 4.0, 5.0],
    [2.0, 5.0, 5.0],
    [3.0, 6.0, 7.0],
    [5.0, 4.0, 6.0],
    [3.0, 3.0, 3.0],
];
const N12_NO_TIES: [[f64; 3]; 12] = [
    [12.5, 14.1, 17.3],
    [10.2, 13.8, 12.8],
    [11.7, 11.1, 15.4],
    [9.4, 12.6, 13.0],
    [13.3, 15.9, 16.2],
    [8.8, 9.5, 11.6],
    [12.1, 10.7, 14.8],
    [10.9, 13.4, 12.3],
    [11.2, 14.6, 18.1],
    [9.9, 12.0, 10.3],
    [13.6, 16.7, 15.5],
    [10.4, 11.9, 13.7],
];
const N12_LIKERT: [[f64; 3]; 12] = [
    [2.0, 4.0, 5.0],
    [3.0, 3.0, 6.0],
    [4.0, 5.0, 5.0],
    [1.0, 4.0, 4.0],
    [3.0, 5.0, 7.0],
    [5.0, 4.0, 6.0],
    [2.0, 2.0, 3.0],
    [4.0, 6.0, 6.0],
    [3.0, 5.0, 4.0],
    [2.0, 3.0, 5.0],
    [4.0, 4.0, 4.0],
    [3.0, 6.0, 5.0],
];

/// scipy's numbers for one dataset: Friedman (statistic, p, W), then per pair (0, 1), (0, 2),
/// (1, 2): method, T = min(R+, R-), p, Holm-adjusted p, rank-biserial, non-zero differences.
struct Reference {
    friedman: (f64, f64, f64),
    pairs: [(WilcoxonMethod, f64, f64, f64, f64, usize); 3],
}

use WilcoxonMethod::{Exact, Normal};

// N6_NO_TIES: friedman statistic = 7.000000000000, p = 3.019738342232e-02, W = 0.583333333333
//   (0, 1) exact  n =  6: T = 1.0, p = 6.250000000000e-02, holm = 1.250000000000e-01, rank-biserial = -0.904761904762
//   (0, 2) exact  n =  6: T = 0.0, p = 3.125000000000e-02, holm = 9.375000000000e-02, rank-biserial = -1.000000000000
//   (1, 2) exact  n =  6: T = 4.0, p = 2.187500000000e-01, holm = 2.187500000000e-01, rank-biserial = -0.619047619048
const N6_NO_TIES_SCIPY: Reference = Reference {
    friedman: (7.0, 3.019738342232e-02, 0.583333333333),
    pairs: [
        (Exact, 1.0, 6.25e-02, 1.25e-01, -0.904761904762, 6),
        (Exact, 0.0, 3.125e-02, 9.375e-02, -1.0, 6),
        (Exact, 4.0, 2.1875e-01, 2.1875e-01, -0.619047619048, 6),
    ],
};

// N6_LIKERT: friedman statistic = 7.444444444444, p = 2.418017437647e-02, W = 0.620370370370
//   (0, 1) approx n =  4: T = 1.0, p = 1.974660733580e-01, holm = 1.974660733580e-01, rank-biserial = -0.800000000000
//   (0, 2) approx n =  5: T = 0.0, p = 5.675944638601e-02, holm = 1.702783391580e-01, rank-biserial = -1.000000000000
//   (1, 2) approx n =  4: T = 0.0, p = 8.897301170181e-02, holm = 1.779460234036e-01, rank-biserial = -1.000000000000
const N6_LIKERT_SCIPY: Reference = Reference {
    friedman: (7.444444444444, 2.418017437647e-02, 0.620370370370),
    pairs: [
        (Normal, 1.0, 1.974660733580e-01, 1.974660733580e-01, -0.8, 4),
        (Normal, 0.0, 5.675944638601e-02, 1.702783391580e-01, -1.0, 5),
        (Normal, 0.0, 8.897301170181e-02, 1.779460234036e-01, -1.0, 4),
    ],
};

// N12_NO_TIES: friedman statistic = 14.000000000000, p = 9.118819655545e-04, W = 0.583333333333
//   (0, 1) exact  n = 12: T = 4.0, p = 3.417968750000e-03, holm = 6.835937500000e-03, rank-biserial = -0.897435897436
//   (0, 2) exact  n = 12: T = 0.0, p = 4.882812500000e-04, holm = 1.464843750000e-03, rank-biserial = -1.000000000000
//   (1, 2) exact  n = 12: T = 18.0, p = 1.098632812500e-01, holm = 1.098632812500e-01, rank-biserial = -0.538461538462
const N12_NO_TIES_SCIPY: Reference = Reference {
    friedman: (14.0, 9.118819655545e-04, 0.583333333333),
    pairs: [
        (
            Exact,
            4.0,
            3.41796875e-03,
            6.8359375e-03,
            -0.897435897436,
            12,
        ),
        (Exact, 0.0, 4.8828125e-04, 1.46484375e-03, -1.0, 12),
        (
            Exact,
            18.0,
            1.0986328125e-01,
            1.0986328125e-01,
            -0.538461538462,
            12,
        ),
    ],
};

// N12_LIKERT: friedman statistic = 14.307692307692, p = 7.818511710782e-04, W = 0.596153846154
//   (0, 1) approx n =  9: T = 2.0, p = 1.634136208293e-02, holm = 3.268272416585e-02, rank-biserial = -0.911111111111
//   (0, 2) approx n = 11: T = 0.0, p = 3.499658722901e-03, holm = 1.049897616870e-02, rank-biserial = -1.000000000000
//   (1, 2) approx n =  8: T = 5.0, p = 7.488366232799e-02, holm = 7.488366232799e-02, rank-biserial = -0.722222222222
const N12_LIKERT_SCIPY: Reference = Reference {
    friedman: (14.307692307692, 7.818511710782e-04, 0.596153846154),
    pairs: [
        (
            Normal,
            2.0,
            1.634136208293e-02,
            3.268272416585e-02,
            -0.911111111111,
            9,
        ),
        (
            Normal,
            0.0,
            3.499658722901e-03,
            1.049897616870e-02,
            -1.0,
            11,
        ),
        (
            Normal,
            5.0,
            7.488366232799e-02,
            7.488366232799e-02,
            -0.722222222222,
            8,
        ),
    ],
};

fn matrix<const N: usize>(rows: &[[f64; 3]; N]) -> Vec<Vec<Option<f64>>> {
    rows.iter()
        .map(|r| r.iter().map(|&v| Some(v)).collect())
        .collect()
}

fn check_against_scipy(name: &str, result: &WithinSubject, want: &Reference) {
    let f = result.friedman.expect("friedman");
    assert_close(
        f.statistic,
        want.friedman.0,
        &format!("{name} friedman statistic"),
    );
    assert_close(f.p, want.friedman.1, &format!("{name} friedman p"));
    assert_close(f.kendall_w, want.friedman.2, &format!("{name} Kendall's W"));
    assert_eq!((f.df, f.k), (2, 3));
    assert_eq!(result.pairs.len(), 3);
    for (pair, &(method, t, p, p_holm, rbc, n)) in result.pairs.iter().zip(&want.pairs) {
        let what = format!("{name} ({}, {})", pair.a, pair.b);
        assert_eq!(pair.test.method, method, "{what} method");
        assert_eq!(pair.test.n, n, "{what} non-zero differences");
        assert_close(pair.test.statistic, t, &format!("{what} T"));
        assert_close(pair.test.p, p, &format!("{what} p"));
        assert_close(pair.p_holm, p_holm, &format!("{what} Holm p"));
        assert_close(
            pair.test.rank_biserial,
            rbc,
            &format!("{what} rank-biserial"),
        );
    }
}

#[test]
fn matches_scipy_without_ties_n6() {
    let result = within_subject(&matrix(&N6_NO_TIES), 3);
    assert_eq!(
        (result.participants, result.dropped, result.conditions),
        (6, 0, 3)
    );
    check_against_scipy("N6_NO_TIES", &result, &N6_NO_TIES_SCIPY);
}

#[test]
fn matches_scipy_with_ties_and_zeros_n6() {
    let result = within_subject(&matrix(&N6_LIKERT), 3);
    check_against_scipy("N6_LIKERT", &result, &N6_LIKERT_SCIPY);
    // Participant 5 scored all three alike; participant 1 tied the first two.
    assert_eq!(result.pairs[0].test.zeros, 2);
}

#[test]
fn matches_scipy_without_ties_n12() {
    let result = within_subject(&matrix(&N12_NO_TIES), 3);
    check_against_scipy("N12_NO_TIES", &result, &N12_NO_TIES_SCIPY);
    assert!(result.caution.is_none(), "{:?}", result.caution);
}

#[test]
fn matches_scipy_with_ties_and_zeros_n12() {
    let result = within_subject(&matrix(&N12_LIKERT), 3);
    check_against_scipy("N12_LIKERT", &result, &N12_LIKERT_SCIPY);
}

#[test]
fn one_sided_greater_matches_scipy() {
    // SEEDS_EXACT greater exact n = 7: R+ = 25.0, p = 3.906250000000e-02, rank-biserial = 0.785714285714
    let x = [0.82, 0.75, 0.92, 0.68, 0.88, 0.79, 0.85];
    let y = [0.71, 0.77, 0.8, 0.62, 0.74, 0.7, 0.86];
    let t = wilcoxon_greater(&x, &y);
    assert_eq!(
        (t.method, t.n, t.alternative),
        (Exact, 7, Alternative::Greater)
    );
    assert_close(t.statistic, 25.0, "SEEDS_EXACT R+");
    assert_close(t.p, 3.906250000000e-02, "SEEDS_EXACT p");
    assert_close(t.rank_biserial, 0.785714285714, "SEEDS_EXACT rank-biserial");
    // The other way round (scipy: R+ = 3, p = 0.9765625): every sign pattern but the three
    // with R+ of 0, 1 or 2.
    let back = wilcoxon_greater(&y, &x);
    assert_close(back.statistic, 3.0, "SEEDS_EXACT reversed R+");
    assert_close(back.p, 125.0 / 128.0, "SEEDS_EXACT reversed p");

    // SEEDS_TIES greater approx n = 8: R+ = 34.0, p = 1.263558088844e-02, rank-biserial = 0.888888888889
    let x = [5.0, 6.0, 4.0, 7.0, 6.0, 5.0, 8.0, 6.0, 5.0, 7.0];
    let y = [4.0, 5.0, 4.0, 5.0, 6.0, 3.0, 6.0, 4.0, 6.0, 5.0];
    let t = wilcoxon_greater(&x, &y);
    assert_eq!((t.method, t.n, t.zeros), (Normal, 8, 2));
    assert_close(t.statistic, 34.0, "SEEDS_TIES R+");
    assert_close(t.p, 1.263558088844e-02, "SEEDS_TIES p");
    assert_close(t.rank_biserial, 0.888888888889, "SEEDS_TIES rank-biserial");

    // SEEDS_LARGE greater approx n = 30: R+ = 353.0, p = 6.789707519224e-03, rank-biserial = 0.518279569892
    let x: Vec<f64> = (1..=30)
        .map(|i| if i % 4 == 0 { -i } else { i } as f64)
        .collect();
    let t = wilcoxon_greater(&x, &[0.0; 30]);
    assert_eq!(
        (t.method, t.n),
        (Normal, 30),
        "past {EXACT_MAX_N}: normal even without ties"
    );
    assert_close(t.statistic, 353.0, "SEEDS_LARGE R+");
    assert_close(t.p, 6.789707519224e-03, "SEEDS_LARGE p");
    assert_close(t.rank_biserial, 0.518279569892, "SEEDS_LARGE rank-biserial");
}

#[test]
fn a_participant_with_a_missing_cell_is_dropped_and_counted() {
    let mut scores = matrix(&N6_NO_TIES);
    // Two more participants, each missing one score (one by a gap, one by a short row), a NaN
    // and a row too long: all four are left out, and the rest give the complete data's numbers.
    scores.insert(2, vec![Some(1.0), None, Some(9.0)]);
    scores.push(vec![Some(8.0), Some(1.0)]);
    scores.push(vec![Some(f64::NAN), Some(1.0), Some(2.0)]);
    scores.push(vec![Some(1.0); 4]);
    let cases = complete_cases(&scores, 3);
    assert_eq!(cases.dropped, vec![2, 7, 8, 9]);
    assert_eq!(cases.kept, vec![0, 1, 3, 4, 5, 6]);
    let result = within_subject(&scores, 3);
    assert_eq!((result.participants, result.dropped), (6, 4));
    check_against_scipy("N6_NO_TIES + incomplete", &result, &N6_NO_TIES_SCIPY);
}

#[test]
fn holm_steps_down_and_stays_monotone() {
    // By hand: sorted 0.01, 0.02, 0.04, 0.5 -> 4 * 0.01, max(0.04, 3 * 0.02), max(.., 2 * 0.04),
    // max(.., 0.5), reported in input order.
    let adjusted = holm(&[0.04, 0.5, 0.01, 0.02]);
    let want = [0.08, 0.5, 0.04, 0.06];
    for (got, want) in adjusted.iter().zip(want) {
        assert!((got - want).abs() < 1e-15, "{adjusted:?}");
    }
    // Capped at 1, and a later p never adjusted below an earlier one.
    assert_eq!(holm(&[0.6, 0.3]), vec![0.6, 0.6]);
    assert_eq!(holm(&[0.9, 0.9]), vec![1.0, 1.0]);
    assert!(holm(&[]).is_empty());
}

#[test]
fn exact_distribution_counts_every_sign_pattern() {
    for n in 0..=EXACT_MAX_N {
        let counts = signed_rank_counts(n);
        assert_eq!(counts.iter().sum::<f64>(), 2f64.powi(n as i32), "n = {n}");
        // Symmetric about n (n + 1) / 4.
        let reversed: Vec<f64> = counts.iter().rev().copied().collect();
        assert_eq!(counts, reversed, "n = {n}");
    }
    // n = 4: sums 0..=10 reached by 1 1 1 2 2 2 2 2 1 1 1 subsets.
    assert_eq!(
        signed_rank_counts(4),
        vec![1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 1.0, 1.0, 1.0]
    );
}

#[test]
fn caution_names_the_smallest_reachable_p() {
    assert_eq!(
        caution(4, 3).as_deref(),
        Some(
            "with n = 4 participants the smallest two-sided Wilcoxon p is 0.125; no pair can \
             reach 0.05 (with ties the normal approximation is used instead, which is \
             unreliable at this size)"
        )
    );
    assert!(
        caution(5, 1)
            .unwrap()
            .contains("is 0.0625; no pair can reach 0.05")
    );
    // n = 6 reaches 0.03125 alone, but not after Holm over three pairs (0.09375)...
    let six = caution(6, 3).unwrap();
    assert!(
        six.contains("0.03125, 0.09375 after Holm's correction over 3 pairs"),
        "{six}"
    );
    // ...while a single pair, or seven participants over three pairs, can.
    assert_eq!(caution(6, 1), None);
    assert_eq!(caution(7, 3), None);
    assert!(caution(0, 3).unwrap().contains("no participant"));
    // The whole analysis carries it: the smallest exact p of N6_NO_TIES is the floor itself.
    let result = within_subject(&matrix(&N6_NO_TIES), 3);
    assert_eq!(
        result.pairs[1].test.p,
        smallest_exact_p(6, Alternative::TwoSided)
    );
    assert_eq!(result.caution, caution(6, 3));
    assert_eq!(smallest_exact_p(6, Alternative::Greater), 1.0 / 64.0);
}

#[test]
fn degenerate_inputs_give_no_signal_not_nan() {
    // Every participant scored everything alike: no ranks, no Friedman, p = 1 for each pair.
    let flat = vec![vec![Some(4.0); 3]; 5];
    let result = within_subject(&flat, 3);
    assert!(result.friedman.is_none());
    for pair in &result.pairs {
        assert_eq!((pair.test.n, pair.test.zeros), (0, 5));
        assert_eq!(
            (pair.test.p, pair.p_holm, pair.test.rank_biserial),
            (1.0, 1.0, 0.0)
        );
    }
    // Nobody complete, or nothing at all.
    let result = within_subject(&[vec![None, Some(1.0)], vec![Some(2.0), None]], 2);
    assert_eq!((result.participants, result.dropped), (0, 2));
    assert!(result.friedman.is_none());
    assert!(within_subject(&[], 0).pairs.is_empty());
    assert_eq!(within_subject(&[], 4).pairs.len(), 6);
    // Two conditions are enough for Friedman (scipy asks for three; the formula does not).
    let two = friedman(&[vec![1.0, 2.0], vec![1.0, 3.0], vec![2.0, 1.0]]).unwrap();
    assert_eq!((two.df, two.k, two.n), (1, 2, 3));
    // R = (4, 5): (12 / 18 * 41 - 27) = 1/3.
    assert!((two.statistic - 1.0 / 3.0).abs() < 1e-12);
}

#[test]
fn serializes_for_the_api() {
    let result = within_subject(&matrix(&N6_NO_TIES), 3);
    let json = serde_json::to_value(&result).unwrap();
    assert_eq!(json["pairs"][0]["test"]["method"], "exact");
    assert_eq!(json["pairs"][0]["test"]["alternative"], "two_sided");
    assert_eq!(json["friedman"]["df"], 2);
    assert!(json["caution"].is_string());
}
