//! A ChaCha8 generator's whole state as plain data (key, stream, position), so checkpoints can
//! store every random stream of a run and resume it exactly where it stopped.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Why a stored [`RngState`] does not give a generator back.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("word_pos {word_pos:?} is not a number")]
pub struct RngStateError {
    /// The stored position, as it reads.
    pub word_pos: String,
}

/// Key, stream and position in the stream. The position is a u128, which JSON numbers cannot
/// carry exactly, so it travels as a decimal string.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RngState {
    pub seed: [u8; 32],
    pub stream: u64,
    pub word_pos: String,
}

impl RngState {
    pub fn of(rng: &ChaCha8Rng) -> Self {
        Self {
            seed: rng.get_seed(),
            stream: rng.get_stream(),
            word_pos: rng.get_word_pos().to_string(),
        }
    }

    /// The generator, positioned where [`RngState::of`] found it.
    pub fn restore(&self) -> Result<ChaCha8Rng, RngStateError> {
        let word_pos: u128 = self.word_pos.parse().map_err(|_| RngStateError {
            word_pos: self.word_pos.clone(),
        })?;
        let mut rng = ChaCha8Rng::from_seed(self.seed);
        rng.set_stream(self.stream);
        rng.set_word_pos(word_pos);
        Ok(rng)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn a_restored_generator_continues_the_same_stream() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let _: [u64; 5] = rng.random();
        let _: u32 = rng.random(); // odd position inside a block
        let state = serde_json::to_string(&RngState::of(&rng)).unwrap();
        let mut restored = serde_json::from_str::<RngState>(&state)
            .unwrap()
            .restore()
            .unwrap();
        let expected: [u64; 8] = rng.random();
        assert_eq!(restored.random::<[u64; 8]>(), expected);
        let bad = RngState {
            word_pos: "x".into(),
            ..RngState::of(&rng)
        };
        assert_eq!(
            bad.restore().unwrap_err().to_string(),
            r#"word_pos "x" is not a number"#
        );
    }
}
