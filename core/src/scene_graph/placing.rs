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

/// The graph the authors' published Placing runs used (issue 33; their
/// `robosuite_pipeline_optim_active_tamer_rl_ballbasket.py` at commits f2ff175 and 5dce179, of
/// 2022-06-05/06): 8 bits, no gripper bits, and the "above"/"below" pair reading
/// `'z': newState[0][1]`, i.e. the sign of **y**. Above/below then split only the centred y band
/// (behind implies below, beyond implies above): 3 x 4 = 12 reachable cells, not 36. The
/// authors' comparisons are strict (x exactly at +-0.05 sets no x bit), and so are these.
pub const AS_RUN_PREDICATES: [Predicate; 8] = [
    PREDICATES[0],
    PREDICATES[1],
    PREDICATES[2],
    PREDICATES[3],
    PREDICATES[4],
    PREDICATES[5],
    Predicate {
        name: "above_as_run",
        label: "gripper \"above\" hoop (as run: y > 0)",
    },
    Predicate {
        name: "below_as_run",
        label: "gripper \"below\" hoop (as run: y < 0)",
    },
];

/// The as-run graph on `next_obs` = gripper (x, y, z, g) relative to the hoop.
pub fn evaluate_as_run(next_obs: &[f32]) -> AbstractState {
    let (x, y) = (next_obs[0], next_obs[1]);
    let (hx, hy) = (GOAL_HALF_X, GOAL_HALF_Y);
    AbstractState::from_bits(&[
        x < -hx,
        x > -hx && x < hx,
        x > hx,
        y < -hy,
        y > -hy && y < hy,
        y > hy,
        y > 0.0,
        y < 0.0,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_as_run_graph_has_the_authors_twelve_cells_on_a_sweep() {
        // A sweep over the table at every height and gripper state: z and g never matter. (Off
        // the lines x = +-0.05, y = 0 and y = +-0.125, where strict comparisons set fewer bits.)
        let mut seen = std::collections::BTreeSet::new();
        for i in 0..40 {
            for j in 0..40 {
                for (z, g) in [(0.8f32, -1.0f32), (1.2, 1.0)] {
                    let (x, y) = (-0.3777 + 0.019 * i as f32, -0.3493 + 0.0175 * j as f32);
                    let a = evaluate_as_run(&[x, y, z, g]);
                    assert_eq!(a, evaluate_as_run(&[x, y, 1.0, 1.0]));
                    seen.insert(a);
                }
            }
        }
        assert_eq!(seen.len(), 12, "{seen:?}");
    }

    #[test]
    fn the_as_run_graph_on_a_scripted_path_reads_y_for_above() {
        // From the home pose (-0.23, 0) ... sideways to the hoop, then beyond it in y.
        let path = [
            ([-0.23f32, 0.0, 1.0, 1.0], "10001000"), // y = 0: neither "above" nor "below"
            ([-0.23, 0.01, 0.9, 1.0], "10001010"),
            ([0.0, -0.01, 1.2, -1.0], "01001001"),
            ([0.0, -0.2, 1.2, -1.0], "01010001"),
            ([0.1, 0.2, 0.8, 1.0], "00100110"),
        ];
        for (obs, bits) in path {
            assert_eq!(evaluate_as_run(&obs).to_bit_string(8), bits, "{obs:?}");
        }
    }

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
