//! The soft Bellman target: termination masks the bootstrap, truncation does not.

use super::{fill_fixed_batch_and_noise, tiny_config};
use crate::rl::sac::Sac;

#[test]
fn termination_masks_the_bootstrap_and_truncation_does_not() {
    let mut sac = Sac::new(3, 2, tiny_config(&[6, 5], 5, None), 1);
    fill_fixed_batch_and_noise(&mut sac);
    let ent_coef = 0.5;
    sac.compute_target_q_values(ent_coef);
    let b = &sac.buffers;
    let (gamma, y) = (sac.config.gamma, b.target_q_values.clone());
    for (i, &y_i) in y.iter().enumerate() {
        // next_q_value by hand from the target critics' outputs (still in the workspaces).
        let next_q_value =
            b.q1_ws.output()[i].min(b.q2_ws.output()[i]) - ent_coef * b.next_log_pi[i];
        assert!(
            next_q_value.abs() > 1e-3,
            "row {i}: a bootstrap that would be visible"
        );
        let r = b.batch.rewards[i];
        if b.batch.dones[i] == 1.0 {
            assert_eq!(y_i, r, "row {i} terminated: y = r, no bootstrap");
        } else {
            // A truncated transition is stored as not terminated: it bootstraps.
            assert!(
                (y_i - (r + gamma * next_q_value)).abs() < 1e-6,
                "row {i}: y = r + gamma next_q"
            );
        }
    }
    assert_eq!(b.batch.dones, [0.0, 1.0, 0.0, 0.0, 0.0]);
}
