//! Placing's scene graph: 10 bits, one-hot in four groups, relative to the hoop at (0, 0):
//! Reaching's x and y bands, gripper high or low, gripper open or closed. 36 abstract states.

use super::reaching::{GOAL_HALF_X, GOAL_HALF_Y, band};
use super::{AbstractState, Predicate};

/// Height that splits "high" from "low" (half way up the hoop's walls).
pub const HIGH_Z: f32 = 0.875;

pub const PREDICATES: [Predicate; 10] = [
    Predicate {
        name: "left_of_hoop",
        label: "gripper left of hoop",
    },
    Predicate {
        name: "centred_x",
        label: "gripper above hoop in x",
    },
    Predicate {
        name: "right_of_hoop",
        label: "gripper right of hoop",
    },
    Predicate {
        name: "behind_hoop",
        label: "gripper behind hoop",
    },
    Predicate {
        name: "centred_y",
        label: "gripper above hoop in y",
    },
    Predicate {
        name: "beyond_hoop",
        label: "gripper beyond hoop",
    },
    Predicate {
        name: "high",
        label: "gripper high",
    },
    Predicate {
        name: "low",
        label: "gripper low",
    },
    Predicate {
        name: "gripper_open",
        label: "gripper open",
    },
    Predicate {
        name: "gripper_closed",
        label: "gripper closed",
    },
];

/// `next_obs` = gripper (x, y, z, g) with g = +1 closed, -1 open.
pub fn evaluate(next_obs: &[f32]) -> AbstractState {
    let [x0, x1, x2] = band(next_obs[0], GOAL_HALF_X);
    let [y0, y1, y2] = band(next_obs[1], GOAL_HALF_Y);
    let z = next_obs[2];
    let open = next_obs[3] < 0.0;
    AbstractState::from_bits(&[x0, x1, x2, y0, y1, y2, z > HIGH_Z, z <= HIGH_Z, open, !open])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bits(obs: [f32; 4]) -> String {
        evaluate(&obs).to_bit_string(10)
    }

    #[test]
    fn xy_bands_match_reaching_thresholds() {
        assert_eq!(&bits([-0.0501, 0.0, 1.0, 1.0])[..3], "100");
        assert_eq!(&bits([-0.05, 0.0, 1.0, 1.0])[..3], "010");
        assert_eq!(&bits([0.0501, 0.0, 1.0, 1.0])[..3], "001");
        assert_eq!(&bits([0.0, -0.1251, 1.0, 1.0])[3..6], "100");
        assert_eq!(&bits([0.0, 0.125, 1.0, 1.0])[3..6], "010");
        assert_eq!(&bits([0.0, 0.1251, 1.0, 1.0])[3..6], "001");
    }

    #[test]
    fn height_on_both_sides_of_threshold() {
        assert_eq!(&bits([0.0, 0.0, 0.8751, 1.0])[6..8], "10");
        assert_eq!(&bits([0.0, 0.0, 0.875, 1.0])[6..8], "01");
        assert_eq!(&bits([0.0, 0.0, 0.8749, 1.0])[6..8], "01");
    }

    #[test]
    fn gripper_state_from_last_command_sign() {
        assert_eq!(&bits([0.0, 0.0, 1.0, -1.0])[8..], "10");
        assert_eq!(&bits([0.0, 0.0, 1.0, 1.0])[8..], "01");
    }

    #[test]
    fn one_hot_groups_give_36_states() {
        let mut seen = std::collections::BTreeSet::new();
        for x in [-0.3f32, 0.0, 0.1] {
            for y in [-0.3f32, 0.0, 0.3] {
                for z in [0.85f32, 1.2] {
                    for g in [-1.0f32, 1.0] {
                        seen.insert(evaluate(&[x, y, z, g]));
                    }
                }
            }
        }
        assert_eq!(seen.len(), 36);
    }
}
