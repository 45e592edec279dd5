//! A DRPL belief update allocates nothing: its 2199 Metropolis-Hastings proposals reuse buffers
//! made when the belief and its answers were created (the suite's counting allocator, whose counters are per thread).

use crate::support::counting_alloc;

use counting_alloc::count;
use dualrep_core::guidance::drpl::belief::{Belief, BeliefConfig, Response};

#[test]
fn a_belief_update_allocates_nothing() {
    let mut belief = Belief::new(6, BeliefConfig::default(), 7);
    for i in 0..40 {
        let a: Vec<f64> = (0..6).map(|k| ((i * 6 + k) as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..6).map(|k| ((i * 6 + k) as f64 * 0.91).cos()).collect();
        let response = [Response::First, Response::Second, Response::Equal][i % 3];
        belief.add_answer(&a, &b, response);
    }
    belief.update(); // warm-up: the first update may size its buffers
    let (allocations, live) = count(|| {
        for _ in 0..5 {
            belief.update();
        }
    });
    assert_eq!(
        (allocations, live),
        (0, 0),
        "allocations and live bytes during 5 updates"
    );
}
