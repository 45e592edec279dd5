//! The abstract state g: a bit vector over a scene graph's predicates.

use std::fmt;

use serde::{Deserialize, Serialize};

/// Bit `i` is predicate `i` of the task's scene graph. Graphs have at most 32 predicates, so the
/// state is one `u32`: cheap to copy, hash and use as a map key.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct AbstractState(pub u32);

impl AbstractState {
    /// Pack predicate values, predicate 0 first.
    pub fn from_bits(bits: &[bool]) -> Self {
        assert!(bits.len() <= 32, "a scene graph has at most 32 predicates");
        Self(
            bits.iter()
                .enumerate()
                .fold(0, |acc, (i, &b)| acc | (u32::from(b) << i)),
        )
    }

    /// Whether predicate `i` holds.
    pub fn bit(self, i: usize) -> bool {
        i < 32 && (self.0 >> i) & 1 == 1
    }

    /// Number of predicates in which the two states differ.
    pub fn hamming(self, other: Self) -> u32 {
        (self.0 ^ other.0).count_ones()
    }

    /// The state as a string of `dim` characters '0'/'1', predicate 0 first.
    pub fn to_bit_string(self, dim: usize) -> String {
        (0..dim)
            .map(|i| if self.bit(i) { '1' } else { '0' })
            .collect()
    }
}

impl fmt::Display for AbstractState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#x}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packs_bits_in_predicate_order() {
        let g = AbstractState::from_bits(&[true, false, true]);
        assert_eq!(g.0, 0b101);
        assert!(g.bit(0) && !g.bit(1) && g.bit(2) && !g.bit(3));
        assert_eq!(g.to_bit_string(4), "1010");
    }

    #[test]
    fn hamming_counts_differing_predicates() {
        let a = AbstractState::from_bits(&[true, false, true, false]);
        let b = AbstractState::from_bits(&[true, true, false, false]);
        assert_eq!(a.hamming(b), 2);
        assert_eq!(a.hamming(a), 0);
    }

    #[test]
    fn works_as_a_map_key() {
        let mut counts = std::collections::HashMap::new();
        *counts.entry(AbstractState(3)).or_insert(0) += 1;
        *counts
            .entry(AbstractState::from_bits(&[true, true]))
            .or_insert(0) += 1;
        assert_eq!(counts[&AbstractState(3)], 2);
    }
}
