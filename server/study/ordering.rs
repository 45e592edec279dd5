//! The order in which a participant meets the conditions of a within-subject study.
//!
//! Every participant trains with every method, so whatever the first session teaches (the UI,
//! the task, fatigue by the third) would favour the methods met later. Counterbalancing spreads
//! those carry-over effects evenly over the conditions:
//!
//! - [`Ordering::Williams`]: rows of a Williams design, a balanced Latin square. Every condition
//!   appears once in every position, and every condition immediately follows every other equally
//!   often (first-order carry-over balance). For an even number of conditions one square of n
//!   rows does this; for an odd number the standard construction leaves each ordered pair
//!   following either twice or not at all (and for n = 3, 5, 7 no balanced square of n rows
//!   exists), so the design is the square followed by its mirror image, 2n rows, in which every
//!   ordered pair follows twice.
//!   Participant i gets row i mod rows: a study balances fully when its size is a multiple of
//!   the row count.
//! - [`Ordering::Random`]: a shuffle per participant, from a ChaCha8 stream that the study seed
//!   and the participant index alone determine, so the order can be recomputed at any time.
//! - [`Ordering::Fixed`]: the conditions in the order given (a pilot, or a design that wants a
//!   fixed order on purpose).

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// How a study orders its conditions for each participant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ordering {
    /// Rows of a Williams design ([`williams_rows`]), participant i on row i mod rows.
    #[default]
    Williams,
    /// A seeded shuffle per participant ([`random_order`]).
    Random,
    /// The conditions in the order given.
    Fixed,
}

impl Ordering {
    /// The condition indices, in order, that participant `participant` meets in a study of
    /// `n` conditions. `seed` is the study's seed; only [`Ordering::Random`] reads it.
    pub fn order(self, n: usize, participant: usize, seed: u64) -> Vec<usize> {
        match self {
            Ordering::Williams => {
                let mut rows = williams_rows(n);
                if rows.is_empty() {
                    return Vec::new();
                }
                let row = participant % rows.len();
                rows.swap_remove(row)
            }
            Ordering::Random => random_order(n, participant, seed),
            Ordering::Fixed => (0..n).collect(),
        }
    }

    /// How many participants it takes for every order of the design to be used equally often:
    /// the Williams design's row count; `None` for the other two (a fixed order is trivially
    /// balanced by one, a random one never exactly).
    pub fn balanced_block(self, n: usize) -> Option<usize> {
        match self {
            Ordering::Williams => Some(williams_rows(n).len()),
            Ordering::Random | Ordering::Fixed => None,
        }
    }
}

/// The rows of a Williams design for `n` conditions, each a permutation of `0..n`: n rows for
/// even n, 2n (the square, then each row reversed) for odd n ≥ 3. Empty for n = 0, the one
/// row `[0]` for n = 1.
///
/// The standard construction (Williams 1949; Bradley 1958): the first row is
/// 0, 1, n-1, 2, n-2, 3, ... (alternately up from the bottom and down from the top), and row r
/// adds r to every entry, mod n. In the first row the steps between neighbours are
/// +1, -2, +3, -4, ... which, mod n, are all different for even n; adding r shifts a pair but
/// keeps its step, so each ordered pair (a, b) appears as neighbours exactly once.
pub fn williams_rows(n: usize) -> Vec<Vec<usize>> {
    match n {
        0 => return Vec::new(),
        // One condition: nothing to balance, and its mirror would be the same row.
        1 => return vec![vec![0]],
        _ => {}
    }
    let mut first = Vec::with_capacity(n);
    first.push(0);
    let (mut low, mut high) = (1, n - 1);
    for j in 1..n {
        if j % 2 == 1 {
            first.push(low);
            low += 1;
        } else {
            first.push(high);
            high -= 1;
        }
    }
    let mut rows: Vec<Vec<usize>> = (0..n)
        .map(|r| first.iter().map(|c| (c + r) % n).collect())
        .collect();
    if n % 2 == 1 {
        let mirrored: Vec<Vec<usize>> = rows
            .iter()
            .map(|row| row.iter().rev().copied().collect())
            .collect();
        rows.extend(mirrored);
    }
    rows
}

/// A uniformly random order of `0..n` for participant `participant`: ChaCha8 seeded with the
/// study seed, on the stream numbered by the participant, so participants' orders are
/// independent of each other and of how many participants there are.
pub fn random_order(n: usize, participant: usize, seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(participant as u64);
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rng);
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_permutation(row: &[usize], n: usize) -> bool {
        let mut sorted = row.to_vec();
        sorted.sort_unstable();
        sorted == (0..n).collect::<Vec<_>>()
    }

    #[test]
    fn williams_rows_are_latin_and_carry_over_balanced() {
        for n in 2..=8 {
            let rows = williams_rows(n);
            let expected_rows = if n % 2 == 0 { n } else { 2 * n };
            assert_eq!(rows.len(), expected_rows, "n = {n}");
            for row in &rows {
                assert!(is_permutation(row, n), "n = {n}: {row:?}");
            }
            // Each condition equally often in each position (once per square).
            for position in 0..n {
                let mut count = vec![0; n];
                for row in &rows {
                    count[row[position]] += 1;
                }
                let per_square = rows.len() / n;
                assert!(
                    count.iter().all(|&c| c == per_square),
                    "n = {n}, position {position}: {count:?}"
                );
            }
            // Each ordered pair (a, b), a != b, equally often as neighbours (a then b).
            let mut follows = vec![vec![0; n]; n];
            for row in &rows {
                for w in row.windows(2) {
                    follows[w[0]][w[1]] += 1;
                }
            }
            let expected = rows.len() * (n - 1) / (n * (n - 1));
            for (a, successors) in follows.iter().enumerate() {
                for (b, &count) in successors.iter().enumerate() {
                    let want = if a == b { 0 } else { expected };
                    assert_eq!(count, want, "n = {n}: {a} then {b}");
                }
            }
        }
    }

    #[test]
    fn williams_square_for_four_is_the_textbook_one() {
        assert_eq!(
            williams_rows(4),
            vec![
                vec![0, 1, 3, 2],
                vec![1, 2, 0, 3],
                vec![2, 3, 1, 0],
                vec![3, 0, 2, 1],
            ]
        );
        assert_eq!(williams_rows(1), vec![vec![0]]);
        assert!(williams_rows(0).is_empty());
    }

    #[test]
    fn participants_cycle_through_the_williams_rows() {
        let rows = williams_rows(3);
        assert_eq!(Ordering::Williams.balanced_block(3), Some(6));
        for participant in 0..13 {
            assert_eq!(
                Ordering::Williams.order(3, participant, 99),
                rows[participant % 6]
            );
        }
        assert!(Ordering::Williams.order(0, 5, 0).is_empty());
    }

    #[test]
    fn random_order_is_reproducible_from_its_seed() {
        for participant in 0..20 {
            let a = Ordering::Random.order(5, participant, 42);
            assert!(is_permutation(&a, 5));
            assert_eq!(a, random_order(5, participant, 42));
        }
        // Pinned, so that a change in the stream or the shuffle (which would reorder an
        // ongoing study's participants) fails here rather than silently.
        assert_eq!(random_order(5, 0, 42), PINNED_SEED_42_PARTICIPANT_0);
        // Participants and seeds get different orders (not always, but over 20 of them).
        let by_participant: std::collections::HashSet<Vec<usize>> =
            (0..20).map(|p| random_order(5, p, 42)).collect();
        assert!(by_participant.len() > 5, "{by_participant:?}");
        let by_seed: std::collections::HashSet<Vec<usize>> =
            (0..20).map(|s| random_order(5, 3, s)).collect();
        assert!(by_seed.len() > 5, "{by_seed:?}");
    }

    const PINNED_SEED_42_PARTICIPANT_0: [usize; 5] = [2, 1, 0, 4, 3];

    #[test]
    fn fixed_keeps_the_given_order() {
        assert_eq!(Ordering::Fixed.order(4, 7, 1), vec![0, 1, 2, 3]);
        assert_eq!(Ordering::Fixed.balanced_block(4), None);
    }

    #[test]
    fn serde_names_are_snake_case() {
        for (ordering, name) in [
            (Ordering::Williams, "\"williams\""),
            (Ordering::Random, "\"random\""),
            (Ordering::Fixed, "\"fixed\""),
        ] {
            assert_eq!(serde_json::to_string(&ordering).unwrap(), name);
            assert_eq!(serde_json::from_str::<Ordering>(name).unwrap(), ordering);
        }
        assert!(serde_json::from_str::<Ordering>("\"latin\"").is_err());
    }
}
