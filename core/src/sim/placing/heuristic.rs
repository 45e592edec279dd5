//! Placing's scripted controller, a stateless function of the observation:
//!
//! 1. Low and not yet over the opening: rise straight up to travel height (never slide
//!    sideways near the hoop's walls).
//! 2. At travel height: fly over the opening's centre, holding travel height.
//! 3. Over the opening: descend to just above the hoop's top, then open the gripper.
//!
//! The descent works with the safety gate rather than against it: near the hoop the gate
//! zeroes any move whose probe `z - 0.07 |a_z|` dips under the no-entry box's top (1.03). A
//! proportional law `a_z = (DROP_Z - z) / Z_SCALE` with `Z_SCALE = 0.1` probes at
//! `0.3 z + 0.7 DROP_Z >= 1.03` for every z above the drop height, so it is never gated (a
//! stiffer law would be, and a stateless controller would then wait forever).

use super::hoop::{LOOKAHEAD, NO_ENTRY};

/// Height at which the gripper crosses the table: the ball's bottom clears the hoop's top.
const TRAVEL_Z: f32 = 1.10;
/// Below this and away from the opening, rise before moving sideways.
const RISE_BELOW_Z: f32 = 1.08;
/// Height the descent aims at, and the height at or under which the gripper opens.
const DROP_Z: f32 = 1.045;
const OPEN_AT_Z: f32 = 1.05;
/// Horizontal distance (per axis) from the opening's centre that counts as "over it".
const XY_TOLERANCE: f32 = 0.01;
/// Distances at which the proportional laws saturate.
const XY_SCALE: f32 = 0.05;
const Z_SCALE: f32 = 0.1;

// The descent law's probe never dips under the no-entry box's top: unsaturated it is a
// weighted mean of z and DROP_Z (weights 1 - L/S and L/S, so L <= S), saturated it is
// z - L >= DROP_Z + S - L.
const _: () = assert!(LOOKAHEAD <= Z_SCALE && DROP_Z >= NO_ENTRY.hi[2]);

fn toward(target: f32, at: f32, scale: f32) -> f32 {
    ((target - at) / scale).clamp(-1.0, 1.0)
}

pub fn heuristic(obs: &[f32]) -> [f32; 4] {
    let (x, y, z, closed) = (obs[0], obs[1], obs[2], obs[3] > 0.0);
    if !closed {
        // Released: stay put and keep the gripper open.
        return [0.0, 0.0, 0.0, -1.0];
    }
    let over = x.abs() <= XY_TOLERANCE && y.abs() <= XY_TOLERANCE;
    let (ax, ay) = (toward(0.0, x, XY_SCALE), toward(0.0, y, XY_SCALE));
    if !over && z < RISE_BELOW_Z {
        return [0.0, 0.0, 1.0, 1.0];
    }
    if !over {
        return [ax, ay, toward(TRAVEL_Z, z, Z_SCALE), 1.0];
    }
    let grip = if z <= OPEN_AT_Z { -1.0 } else { 1.0 };
    [ax, ay, toward(DROP_Z, z, Z_SCALE), grip]
}

#[cfg(test)]
mod tests {
    use super::super::hoop::{STEP_SIZE, gate_allows};
    use super::*;

    #[test]
    fn rises_before_moving_sideways_when_low() {
        assert_eq!(heuristic(&[-0.4, 0.2, 0.9, 1.0]), [0.0, 0.0, 1.0, 1.0]);
        let a = heuristic(&[-0.4, 0.2, 1.2, 1.0]);
        assert_eq!((a[0], a[1], a[3]), (1.0, -1.0, 1.0));
        assert!(a[2] < 0.0);
    }

    #[test]
    fn descent_over_the_opening_is_never_gated() {
        let mut z = 1.65;
        while z > OPEN_AT_Z {
            let a = heuristic(&[0.0, 0.0, z, 1.0]);
            assert!(
                gate_allows(&[0.0, 0.0, z + LOOKAHEAD * a[2]]),
                "gated at z = {z}"
            );
            assert_eq!(a[3], 1.0);
            z += STEP_SIZE * a[2];
        }
        assert_eq!(heuristic(&[0.0, 0.0, z, 1.0])[3], -1.0);
    }

    #[test]
    fn holds_still_once_open() {
        assert_eq!(heuristic(&[0.0, 0.0, 1.05, -1.0]), [0.0, 0.0, 0.0, -1.0]);
    }
}
