//! Box2D's sleep rule, which is how Gymnasium decides the lander has landed (`not lander.awake`).
//!
//! Box2D (`b2Island::Solve`) puts an island to sleep once every body in it has stayed under
//! `b2_linearSleepTolerance` (0.01 units/s) and `b2_angularSleepTolerance` (2 degrees/s) for
//! `b2_timeToSleep` (0.5 s). The lander's island is the hull and its two legs (the ground is
//! static). Box2D sums the time in `f32`; 25 steps of `1/50` is the first sum reaching 0.5, so
//! we count whole steps. rapier's own sleeping is disabled for these bodies: its thresholds
//! differ, and the episode's outcome must not depend on them.

/// `b2_linearSleepTolerance`, units per second.
pub const LINEAR_SLEEP_TOLERANCE: f32 = 0.01;
/// `b2_angularSleepTolerance`: two degrees per second, in radians per second.
pub const ANGULAR_SLEEP_TOLERANCE: f32 = 2.0 / 180.0 * std::f32::consts::PI;
/// `b2_timeToSleep` (0.5 s) in steps of 1/50 s.
pub const STEPS_TO_SLEEP: u32 = 25;

/// Consecutive quiet steps of the lander's island.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SleepTimer {
    quiet_steps: u32,
}

impl SleepTimer {
    /// Whether one body is quiet by Box2D's test (squared speeds against squared tolerances).
    pub fn is_quiet(linvel: [f32; 2], angvel: f32) -> bool {
        let lin2 = linvel[0] * linvel[0] + linvel[1] * linvel[1];
        lin2 <= LINEAR_SLEEP_TOLERANCE * LINEAR_SLEEP_TOLERANCE
            && angvel * angvel <= ANGULAR_SLEEP_TOLERANCE * ANGULAR_SLEEP_TOLERANCE
    }

    /// Account for one step: `all_quiet` when every body of the island was quiet after the
    /// step, `impulse_applied` when an engine fired before it (Box2D wakes a body on
    /// `ApplyLinearImpulse(.., wake=True)`, which restarts its sleep time). Returns whether the
    /// island is now asleep.
    pub fn update(&mut self, all_quiet: bool, impulse_applied: bool) -> bool {
        if all_quiet && !impulse_applied {
            self.quiet_steps += 1;
        } else {
            self.quiet_steps = 0;
        }
        self.is_asleep()
    }

    pub fn is_asleep(&self) -> bool {
        self.quiet_steps >= STEPS_TO_SLEEP
    }

    #[cfg(test)]
    pub fn quiet_steps(&self) -> u32 {
        self.quiet_steps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sleeps_after_exactly_twenty_five_quiet_steps() {
        let mut t = SleepTimer::default();
        for _ in 0..24 {
            assert!(!t.update(true, false));
        }
        assert!(t.update(true, false));
    }

    #[test]
    fn motion_or_an_impulse_restarts_the_count() {
        let mut t = SleepTimer::default();
        for _ in 0..20 {
            t.update(true, false);
        }
        t.update(false, false);
        assert_eq!(t.quiet_steps(), 0);
        for _ in 0..20 {
            t.update(true, false);
        }
        t.update(true, true);
        assert_eq!(t.quiet_steps(), 0);
    }

    #[test]
    fn tolerances_are_box2ds() {
        assert!(SleepTimer::is_quiet([0.006, 0.007], 0.0));
        assert!(!SleepTimer::is_quiet([0.0, 0.0101], 0.0));
        assert!(SleepTimer::is_quiet([0.0, 0.0], 0.0349));
        assert!(!SleepTimer::is_quiet([0.0, 0.0], -0.035));
    }
}
