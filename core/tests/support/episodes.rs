//! Driving an env to the end of its episode with one action held.

use dualrep_core::sim::{Env, Step};

/// Step `env` with `action` until the episode ends; the last step and how many steps it took.
pub fn run_until_done(env: &mut dyn Env, action: &[f32]) -> (Step, u32) {
    for n in 1..=2000 {
        let step = env.step(action);
        if step.done() {
            return (step, n);
        }
    }
    panic!("no end in 2000 steps");
}
