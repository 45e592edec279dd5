//! The abstract states the learner visited in its last W steps, for DREF's rank test among
//! recent visits (`docs/dref.md`). The authors rank a state among every state that has ever had
//! feedback; that ranking moves only when the rule asks, so once the learner stays in states
//! ranked below the top k it never asks again (it "freezes"). Ranked among the states it visits
//! now, the current state competes with its neighbours in time, and the best-ranked of those
//! are always askable.

use std::collections::{BTreeMap, VecDeque};

use serde::{Deserialize, Serialize};

use crate::scene_graph::AbstractState;

/// The last `window` visits in order, and how often each state occurs among them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecentVisits {
    window: usize,
    order: VecDeque<AbstractState>,
    /// Visits per state among `order`; a state leaves the map when its last visit leaves the
    /// window. A `BTreeMap` so that iteration (and so every tie) is in one order everywhere.
    counts: BTreeMap<AbstractState, u32>,
}

impl RecentVisits {
    /// An empty window of `window` steps (at least one).
    pub fn new(window: usize) -> Self {
        let window = window.max(1);
        Self {
            window,
            order: VecDeque::with_capacity(window),
            counts: BTreeMap::new(),
        }
    }

    pub fn window(&self) -> usize {
        self.window
    }

    /// Record a visit of `g`; the oldest visit leaves once the window is full.
    pub fn push(&mut self, g: AbstractState) {
        if self.order.len() == self.window
            && let Some(old) = self.order.pop_front()
            && let Some(n) = self.counts.get_mut(&old)
        {
            *n -= 1;
            if *n == 0 {
                self.counts.remove(&old);
            }
        }
        self.order.push_back(g);
        *self.counts.entry(g).or_default() += 1;
    }

    /// The distinct states visited in the window, in ascending order.
    pub fn states(&self) -> impl Iterator<Item = AbstractState> + '_ {
        self.counts.keys().copied()
    }

    /// Visits of `g` in the window.
    pub fn visits(&self, g: AbstractState) -> u32 {
        self.counts.get(&g).copied().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_exactly_the_last_window_visits() {
        let (a, b, c) = (AbstractState(1), AbstractState(2), AbstractState(3));
        let mut recent = RecentVisits::new(3);
        for g in [a, a, b] {
            recent.push(g);
        }
        assert_eq!(recent.states().collect::<Vec<_>>(), [a, b]);
        assert_eq!((recent.visits(a), recent.visits(b)), (2, 1));
        recent.push(c); // the first `a` leaves
        assert_eq!((recent.visits(a), recent.visits(c)), (1, 1));
        recent.push(c); // the second `a` leaves: a is no longer recent
        assert_eq!(recent.states().collect::<Vec<_>>(), [b, c]);
        assert_eq!(recent.visits(a), 0);
    }

    #[test]
    fn survives_a_serde_round_trip() {
        let mut recent = RecentVisits::new(4);
        for g in [5, 6, 5, 7, 8] {
            recent.push(AbstractState(g));
        }
        let back: RecentVisits =
            serde_json::from_str(&serde_json::to_string(&recent).unwrap()).unwrap();
        assert_eq!(back, recent);
    }
}
