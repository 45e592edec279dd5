//! The moon's surface, drawn as Gymnasium's `LunarLander.reset` draws it: eleven chunks with
//! uniform random heights, a flat helipad in the middle, then a three-point smoothing.

use rand::Rng;

use super::{H, W};

/// Number of terrain chunks (Gymnasium's `CHUNKS`).
pub const CHUNKS: usize = 11;
/// Helipad height before smoothing (Gymnasium: `H / 4`); the flags stand on it.
pub const HELIPAD_Y: f32 = H / 4.0;

/// One episode's terrain: the polyline the ground is made of and the helipad's extent.
#[derive(Clone, Debug, PartialEq)]
pub struct Terrain {
    /// `(chunk_x[i], smooth_y[i])`, left to right, in world units.
    pub points: [[f32; 2]; CHUNKS],
    pub helipad_x1: f32,
    pub helipad_x2: f32,
}

impl Terrain {
    /// Draw a terrain: exactly `CHUNKS + 1` uniform draws from `rng`, as Gymnasium makes.
    pub fn generate(rng: &mut impl Rng) -> Self {
        let mut height = [0.0f32; CHUNKS + 1];
        for h in &mut height {
            *h = rng.random_range(0.0..f64::from(H / 2.0)) as f32;
        }
        Self::from_heights(height)
    }

    /// Gymnasium's construction from the raw heights: flatten the five chunks around the
    /// middle to the helipad height, then average each chunk with its neighbours.
    pub fn from_heights(mut height: [f32; CHUNKS + 1]) -> Self {
        let mid = CHUNKS / 2;
        for h in &mut height[mid - 2..=mid + 2] {
            *h = HELIPAD_Y;
        }
        let chunk_x = |i: usize| W / (CHUNKS - 1) as f32 * i as f32;
        let mut points = [[0.0f32; 2]; CHUNKS];
        for (i, p) in points.iter_mut().enumerate() {
            // Gymnasium indexes `height[i - 1]` in Python, so chunk 0 wraps around to the
            // extra (twelfth) height, which is also chunk 10's right neighbour.
            let left = height[(i + CHUNKS) % (CHUNKS + 1)];
            *p = [chunk_x(i), 0.33 * (left + height[i] + height[i + 1])];
        }
        Self {
            points,
            helipad_x1: chunk_x(mid - 1),
            helipad_x2: chunk_x(mid + 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn helipad_is_flat_at_three_point_three_between_eight_and_twelve() {
        let t = Terrain::generate(&mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!((t.helipad_x1, t.helipad_x2), (8.0, 12.0));
        for p in &t.points[4..=6] {
            assert!((p[1] - 3.3).abs() < 1e-5, "pad point {p:?}");
        }
        assert_eq!(t.points[0][0], 0.0);
        assert!((t.points[CHUNKS - 1][0] - W).abs() < 1e-5);
    }

    #[test]
    fn first_chunk_wraps_to_the_last_height_like_python() {
        let mut h = [1.0f32; CHUNKS + 1];
        h[CHUNKS] = 4.0;
        let t = Terrain::from_heights(h);
        assert!((t.points[0][1] - 0.33 * 6.0).abs() < 1e-6);
        assert!((t.points[CHUNKS - 1][1] - 0.33 * 6.0).abs() < 1e-6);
        assert!((t.points[1][1] - 0.33 * 3.0).abs() < 1e-6);
    }

    #[test]
    fn heights_stay_within_zero_and_half_the_world() {
        for seed in 0..20 {
            let t = Terrain::generate(&mut ChaCha8Rng::seed_from_u64(seed));
            for p in &t.points {
                assert!(p[1] >= 0.0 && p[1] <= 0.99 * H / 2.0 + 1e-4);
            }
        }
    }
}
