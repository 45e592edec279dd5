//! Gymnasium's scripted lander (`gymnasium.envs.box2d.lunar_lander.heuristic`), continuous
//! variant: a PD controller that tilts towards the pad and hovers at a height proportional to
//! the horizontal offset, then only brakes the fall once a leg touches.

/// The action for Gymnasium's 8-dimensional observation `s`.
pub fn heuristic(s: &[f32]) -> [f32; 2] {
    assert!(s.len() >= 8, "LunarLander observations have 8 entries");
    // Point towards the centre, but no more than 0.4 rad (22 degrees).
    let angle_targ = (s[0] * 0.5 + s[2] * 1.0).clamp(-0.4, 0.4);
    // Hover higher the further away from the pad the lander is.
    let hover_targ = 0.55 * s[0].abs();
    let mut angle_todo = (angle_targ - s[4]) * 0.5 - s[5] * 1.0;
    let mut hover_todo = (hover_targ - s[1]) * 0.5 - s[3] * 0.5;
    if s[6] != 0.0 || s[7] != 0.0 {
        // Once a leg touches, only slow the fall.
        angle_todo = 0.0;
        hover_todo = -s[3] * 0.5;
    }
    [
        (hover_todo * 20.0 - 1.0).clamp(-1.0, 1.0),
        (-angle_todo * 20.0).clamp(-1.0, 1.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falling_upright_over_the_pad_fires_the_main_engine_only() {
        let a = heuristic(&[0.0, 0.2, 0.0, -0.5, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(a[0], 1.0);
        assert_eq!(a[1], 0.0);
    }

    #[test]
    fn tilted_left_turns_back_with_the_side_engine() {
        // Positive angle (counter-clockwise): angle_todo < 0, so a1 > 0.
        let a = heuristic(&[0.0, 1.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0]);
        assert_eq!(a[1], 1.0);
        // hover_todo = -0.5 -> a0 = -11, clipped.
        assert_eq!(a[0], -1.0);
    }

    #[test]
    fn leg_contact_ignores_the_angle_and_brakes_the_fall() {
        let a = heuristic(&[0.3, 0.0, 0.1, -0.04, 0.3, 0.1, 1.0, 0.0]);
        assert_eq!(a[1], 0.0);
        assert!((a[0] - (0.02 * 20.0 - 1.0)).abs() < 1e-6);
    }
}
