//! Reaching's scene graph: 6 bits, one-hot in two groups (x band, y band) around the goal area.
//! Nine abstract states; "centred in x" and "centred in y" together are exactly success.

use super::{AbstractState, Predicate};

/// Half widths of the goal area, the band edges of both groups.
pub const GOAL_HALF_X: f32 = 0.05;
pub const GOAL_HALF_Y: f32 = 0.125;

pub const PREDICATES: [Predicate; 6] = [
    Predicate {
        name: "left_of_goal",
        label: "gripper left of goal",
    },
    Predicate {
        name: "centred_x",
        label: "gripper centred in x",
    },
    Predicate {
        name: "right_of_goal",
        label: "gripper right of goal",
    },
    Predicate {
        name: "behind_goal",
        label: "gripper behind goal",
    },
    Predicate {
        name: "centred_y",
        label: "gripper centred in y",
    },
    Predicate {
        name: "beyond_goal",
        label: "gripper beyond goal",
    },
];

/// The three one-hot bits of a band `[-half, half]`: below, inside (edges included), above.
pub(crate) fn band(v: f32, half: f32) -> [bool; 3] {
    [v < -half, (-half..=half).contains(&v), v > half]
}

/// `next_obs` = gripper (x, y).
pub fn evaluate(next_obs: &[f32]) -> AbstractState {
    let [x0, x1, x2] = band(next_obs[0], GOAL_HALF_X);
    let [y0, y1, y2] = band(next_obs[1], GOAL_HALF_Y);
    AbstractState::from_bits(&[x0, x1, x2, y0, y1, y2])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bits(x: f32, y: f32) -> String {
        evaluate(&[x, y]).to_bit_string(6)
    }

    /// The sim's goal test and this graph's "centred in x and in y" are one region.
    #[test]
    fn goal_matches_the_sims_goal() {
        use crate::sim::reaching as sim;
        assert_eq!(
            (GOAL_HALF_X, GOAL_HALF_Y),
            (sim::GOAL_HALF_X, sim::GOAL_HALF_Y)
        );
        for p in [
            [0.05, 0.0],
            [0.0501, 0.0],
            [0.0, -0.125],
            [0.0, -0.1251],
            [0.3, 0.3],
        ] {
            let bits = evaluate(&p).to_bit_string(6);
            let centred = &bits[1..2] == "1" && &bits[4..5] == "1";
            assert_eq!(sim::in_goal(p), centred, "{p:?}");
        }
    }

    #[test]
    fn x_band_on_both_sides_of_each_threshold() {
        assert_eq!(&bits(-0.0501, 0.0)[..3], "100");
        assert_eq!(&bits(-0.05, 0.0)[..3], "010");
        assert_eq!(&bits(0.05, 0.0)[..3], "010");
        assert_eq!(&bits(0.0501, 0.0)[..3], "001");
    }

    #[test]
    fn y_band_on_both_sides_of_each_threshold() {
        assert_eq!(&bits(0.0, -0.1251)[3..], "100");
        assert_eq!(&bits(0.0, -0.125)[3..], "010");
        assert_eq!(&bits(0.0, 0.125)[3..], "010");
        assert_eq!(&bits(0.0, 0.1251)[3..], "001");
    }

    #[test]
    fn exactly_one_bit_per_group_gives_nine_states() {
        let mut seen = std::collections::BTreeSet::new();
        for x in [-0.3f32, 0.0, 0.3] {
            for y in [-0.3f32, 0.0, 0.3] {
                let g = evaluate(&[x, y]);
                assert_eq!((g.0 & 0b111).count_ones(), 1);
                assert_eq!((g.0 >> 3).count_ones(), 1);
                seen.insert(g);
            }
        }
        assert_eq!(seen.len(), 9);
    }
}
