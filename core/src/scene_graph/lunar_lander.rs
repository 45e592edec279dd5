//! Lunar Lander's scene graph, 10 bits as in the authors' code, on observation coordinates:
//! flags at x = -+0.28 with tops at y = 0.235, the pad centre at the origin.
//! The two "above flag" bits are the same test in the authors' graph (one per flag); we keep
//! both so that abstract states match theirs.

use super::{AbstractState, Predicate};

pub const FLAG_X: f32 = 0.28;
pub const FLAG_TOP_Y: f32 = 0.235;
/// Upright means |angle| below this (radians).
pub const UPRIGHT_ANGLE: f32 = 0.5;
/// Gymnasium fires a side engine when |a1| exceeds this.
pub const SIDE_ENGINE_THRESHOLD: f32 = 0.5;

pub const PREDICATES: [Predicate; 10] = [
    Predicate {
        name: "left_of_left_flag",
        label: "lander left of left flag",
    },
    Predicate {
        name: "left_of_right_flag",
        label: "lander left of right flag",
    },
    Predicate {
        name: "left_of_pad_centre",
        label: "lander left of pad centre",
    },
    Predicate {
        name: "above_left_flag",
        label: "lander above left flag",
    },
    Predicate {
        name: "above_right_flag",
        label: "lander above right flag",
    },
    Predicate {
        name: "above_pad",
        label: "lander above pad level",
    },
    Predicate {
        name: "upright",
        label: "lander upright",
    },
    Predicate {
        name: "main_engine_on",
        label: "main engine on",
    },
    Predicate {
        name: "left_engine_on",
        label: "left engine on",
    },
    Predicate {
        name: "right_engine_on",
        label: "right engine on",
    },
];

/// `next_obs` = Gymnasium's 8 observations; `action` = (main, lateral) in [-1, 1].
/// With `side_engines_on_a0` the side-engine bits test a0, as the authors' code does.
pub fn evaluate(next_obs: &[f32], action: &[f32], side_engines_on_a0: bool) -> AbstractState {
    let (x, y, angle) = (next_obs[0], next_obs[1], next_obs[4]);
    let side = if side_engines_on_a0 {
        action[0]
    } else {
        action[1]
    };
    AbstractState::from_bits(&[
        x < -FLAG_X,
        x < FLAG_X,
        x < 0.0,
        y > FLAG_TOP_Y,
        y > FLAG_TOP_Y,
        y > 0.0,
        angle.abs() < UPRIGHT_ANGLE,
        action[0] > 0.0,
        side < -SIDE_ENGINE_THRESHOLD,
        side > SIDE_ENGINE_THRESHOLD,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bits(x: f32, y: f32, angle: f32, a: [f32; 2]) -> String {
        evaluate(&[x, y, 0.0, 0.0, angle, 0.0, 0.0, 0.0], &a, false).to_bit_string(10)
    }

    #[test]
    fn horizontal_bits_on_both_sides_of_each_flag_and_the_centre() {
        assert_eq!(&bits(-0.2801, 0.5, 0.0, [0.0; 2])[..3], "111");
        assert_eq!(&bits(-0.28, 0.5, 0.0, [0.0; 2])[..3], "011");
        assert_eq!(&bits(-0.0001, 0.5, 0.0, [0.0; 2])[..3], "011");
        assert_eq!(&bits(0.0, 0.5, 0.0, [0.0; 2])[..3], "010");
        assert_eq!(&bits(0.2799, 0.5, 0.0, [0.0; 2])[..3], "010");
        assert_eq!(&bits(0.28, 0.5, 0.0, [0.0; 2])[..3], "000");
    }

    #[test]
    fn vertical_bits_on_both_sides_of_flag_top_and_pad() {
        assert_eq!(&bits(0.0, 0.2351, 0.0, [0.0; 2])[3..6], "111");
        assert_eq!(&bits(0.0, 0.235, 0.0, [0.0; 2])[3..6], "001");
        assert_eq!(&bits(0.0, 0.0001, 0.0, [0.0; 2])[3..6], "001");
        assert_eq!(&bits(0.0, 0.0, 0.0, [0.0; 2])[3..6], "000");
    }

    #[test]
    fn upright_on_both_sides_of_half_a_radian() {
        assert_eq!(&bits(0.0, 0.0, 0.4999, [0.0; 2])[6..7], "1");
        assert_eq!(&bits(0.0, 0.0, -0.4999, [0.0; 2])[6..7], "1");
        assert_eq!(&bits(0.0, 0.0, 0.5, [0.0; 2])[6..7], "0");
        assert_eq!(&bits(0.0, 0.0, -0.5001, [0.0; 2])[6..7], "0");
    }

    #[test]
    fn engines_follow_gymnasium_firing_rules() {
        assert_eq!(&bits(0.0, 0.0, 0.0, [0.0001, 0.0])[7..], "100");
        assert_eq!(&bits(0.0, 0.0, 0.0, [0.0, 0.0])[7..], "000");
        assert_eq!(&bits(0.0, 0.0, 0.0, [-1.0, -0.5001])[7..], "010");
        assert_eq!(&bits(0.0, 0.0, 0.0, [-1.0, -0.5])[7..], "000");
        assert_eq!(&bits(0.0, 0.0, 0.0, [-1.0, 0.5])[7..], "000");
        assert_eq!(&bits(0.0, 0.0, 0.0, [-1.0, 0.5001])[7..], "001");
    }

    #[test]
    fn authors_variant_tests_side_engines_on_a0() {
        let obs = [0.0; 8];
        let g = evaluate(&obs, &[0.9, -0.9], true);
        assert_eq!(&g.to_bit_string(10)[7..], "101");
        let g = evaluate(&obs, &[-0.9, 0.9], true);
        assert_eq!(&g.to_bit_string(10)[7..], "010");
    }
}
