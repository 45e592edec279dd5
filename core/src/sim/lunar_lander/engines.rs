//! Gymnasium's engine model: which engines an action fires, how hard, and the impulses they
//! apply to the hull, with the random dispersion of the exhaust.

use super::{
    MAIN_ENGINE_POWER, MAIN_ENGINE_Y_LOCATION, SCALE, SIDE_ENGINE_AWAY, SIDE_ENGINE_HEIGHT,
    SIDE_ENGINE_POWER,
};

/// An impulse on the hull, applied at the hull's position plus `offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impulse {
    pub impulse: [f32; 2],
    pub offset: [f32; 2],
}

/// What the engines do in one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Firing {
    /// Main engine throttle in `[0.5, 1]`, 0 when off.
    pub m_power: f32,
    /// Side engine throttle in `[0.5, 1]`, 0 when off.
    pub s_power: f32,
    /// `sign(a1)` when a side engine fires (Gymnasium's `direction`), 0 when off.
    pub direction: f32,
    pub main: Option<Impulse>,
    pub side: Option<Impulse>,
}

impl Firing {
    pub fn any(&self) -> bool {
        self.main.is_some() || self.side.is_some()
    }
}

/// Gymnasium's `step` engine code for the clipped `action`, the hull `angle` and the step's
/// `dispersion` (two `U(-1, 1) / SCALE` draws, made whether the engines fire or not).
pub fn fire(action: [f32; 2], angle: f32, dispersion: [f32; 2]) -> Firing {
    let tip = [angle.sin(), angle.cos()];
    let side = [-tip[1], tip[0]];
    let mut out = Firing::default();

    if action[0] > 0.0 {
        out.m_power = (action[0].clamp(0.0, 1.0) + 1.0) * 0.5;
        let along = MAIN_ENGINE_Y_LOCATION / SCALE + 2.0 * dispersion[0];
        let ox = tip[0] * along + side[0] * dispersion[1];
        let oy = -tip[1] * along - side[1] * dispersion[1];
        let k = MAIN_ENGINE_POWER * out.m_power;
        out.main = Some(Impulse {
            impulse: [-ox * k, -oy * k],
            offset: [ox, oy],
        });
    }

    if action[1].abs() > 0.5 {
        out.direction = action[1].signum();
        out.s_power = action[1].abs().clamp(0.5, 1.0);
        let across = 3.0 * dispersion[1] + out.direction * SIDE_ENGINE_AWAY / SCALE;
        let ox = tip[0] * dispersion[0] + side[0] * across;
        let oy = -tip[1] * dispersion[0] - side[1] * across;
        let k = SIDE_ENGINE_POWER * out.s_power;
        out.side = Some(Impulse {
            impulse: [-ox * k, -oy * k],
            // Gymnasium's application point: the exhaust offset, moved by -17 px along the
            // tip's x and SIDE_ENGINE_HEIGHT along the tip's y.
            offset: [
                ox - tip[0] * 17.0 / SCALE,
                oy + tip[1] * SIDE_ENGINE_HEIGHT / SCALE,
            ],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn main_engine_throttle_and_upright_impulse() {
        let f = fire([1.0, 0.0], 0.0, [0.0, 0.0]);
        assert_eq!(f.m_power, 1.0);
        assert!(f.side.is_none());
        let m = f.main.unwrap();
        // Upright, no dispersion: straight up, 4 px below the origin.
        assert!((m.impulse[1] - MAIN_ENGINE_POWER * 4.0 / SCALE).abs() < 1e-6);
        assert!(m.impulse[0].abs() < 1e-7);
        assert!((m.offset[1] + 4.0 / SCALE).abs() < 1e-7);
        assert_eq!(fire([0.0, 0.0], 0.0, [0.0, 0.0]).main, None);
        assert!((fire([1e-4, 0.0], 0.0, [0.0, 0.0]).m_power - 0.50005).abs() < 1e-7);
    }

    #[test]
    fn side_engines_fire_past_half_throttle() {
        assert!(!fire([0.0, 0.5], 0.0, [0.0, 0.0]).any());
        assert!(!fire([0.0, -0.5], 0.0, [0.0, 0.0]).any());
        let right = fire([0.0, 0.6], 0.0, [0.0, 0.0]);
        assert_eq!((right.direction, right.s_power), (1.0, 0.6));
        // Upright, direction +1: the exhaust leaves on the hull's left, 14 px up, and pushes
        // the hull to the right (and turns it clockwise).
        let r = right.side.unwrap();
        assert!(r.impulse[0] > 0.0 && r.impulse[1].abs() < 1e-7);
        assert!((r.offset[0] + SIDE_ENGINE_AWAY / SCALE).abs() < 1e-6);
        assert!((r.offset[1] - SIDE_ENGINE_HEIGHT / SCALE).abs() < 1e-6);
        let left = fire([0.0, -1.0], 0.0, [0.0, 0.0]);
        assert_eq!((left.direction, left.s_power), (-1.0, 1.0));
        let l = left.side.unwrap();
        assert!((l.impulse[0] + SIDE_ENGINE_POWER * SIDE_ENGINE_AWAY / SCALE).abs() < 1e-6);
        assert!((l.offset[0] - SIDE_ENGINE_AWAY / SCALE).abs() < 1e-6);
    }
}
