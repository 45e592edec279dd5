//! DRPL's and DRPL-SS's candidate pairs of segments, grouped by abstract state, and a uniform
//! draw among them that never returns a pair already asked (algorithms.md section 3, step 3).
//!
//! Candidates are defined on abstract states, so a run with thousands of segments has millions
//! of candidate segment pairs but only a few hundred state pairs. We never list segment pairs:
//! a state pair is drawn with weight (segment pairs it holds that were not asked yet), then a
//! segment from each side, which is exactly uniform over the remaining segment pairs.

use std::collections::{BTreeMap, HashMap, HashSet};

use rand::Rng;

use crate::scene_graph::AbstractState;

/// Two segment indices, the smaller first: the pair regardless of display order.
pub type SegmentPair = (usize, usize);

pub fn unordered(a: usize, b: usize) -> SegmentPair {
    (a.min(b), a.max(b))
}

/// Segments by abstract state, states in increasing order (so draws are deterministic).
#[derive(Clone, Debug)]
pub struct StateGroups {
    states: Vec<AbstractState>,
    members: Vec<Vec<usize>>,
    /// The group of every segment.
    group_of: Vec<usize>,
}

impl StateGroups {
    /// `states[k]` is segment k's abstract state.
    pub fn new(states: &[AbstractState]) -> Self {
        let mut by_state: BTreeMap<AbstractState, Vec<usize>> = BTreeMap::new();
        for (k, &g) in states.iter().enumerate() {
            by_state.entry(g).or_default().push(k);
        }
        let index: HashMap<AbstractState, usize> =
            by_state.keys().enumerate().map(|(i, &g)| (g, i)).collect();
        Self {
            group_of: states.iter().map(|g| index[g]).collect(),
            states: by_state.keys().copied().collect(),
            members: by_state.into_values().collect(),
        }
    }

    /// Distinct abstract states among the segments.
    pub fn len(&self) -> usize {
        self.states.len()
    }

    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// How many pairs in `asked` fall into each (group, group) pair, smaller group first.
    fn asked_per_group_pair(&self, asked: &HashSet<SegmentPair>) -> HashMap<(usize, usize), u64> {
        let mut counts = HashMap::new();
        for &(a, b) in asked {
            let (ga, gb) = (self.group_of[a], self.group_of[b]);
            *counts.entry((ga.min(gb), ga.max(gb))).or_insert(0) += 1;
        }
        counts
    }
}

/// One state pair and the segment pairs in it that were not asked yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Entry {
    a: usize,
    /// Equal to `a` for DRPL-SS's same-state pairs.
    b: usize,
    remaining: u64,
}

/// The candidate state pairs of one query.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidates {
    /// DRPL's predicate i that the pair differs in; `None` for same-state pairs.
    pub predicate: Option<usize>,
    /// Hamming distance between the two states of every candidate.
    pub hamming: u32,
    entries: Vec<Entry>,
}

impl Candidates {
    /// DRPL's candidates for query `query_index` (0-based) over a graph of `dim` predicates:
    /// i = query_index mod dim; pairs with g\[i\] != g'\[i\] at Hamming distance 1, else at the least
    /// distance there is; if no pair differs in i (or all were asked), the next i. `None` when no
    /// unasked pair differs in any predicate.
    pub fn drpl(
        groups: &StateGroups,
        dim: usize,
        query_index: usize,
        asked: &HashSet<SegmentPair>,
    ) -> Option<Self> {
        let asked = groups.asked_per_group_pair(asked);
        let n = |g: usize| groups.members[g].len() as u64;
        (0..dim).find_map(|offset| {
            let i = (query_index + offset) % dim;
            let mut best: Option<(u32, Vec<Entry>)> = None;
            for a in 0..groups.len() {
                for b in a + 1..groups.len() {
                    let (ga, gb) = (groups.states[a], groups.states[b]);
                    if ga.bit(i) == gb.bit(i) {
                        continue;
                    }
                    let remaining = n(a) * n(b) - asked.get(&(a, b)).copied().unwrap_or(0);
                    if remaining == 0 {
                        continue;
                    }
                    let h = ga.hamming(gb);
                    let entry = Entry { a, b, remaining };
                    match &mut best {
                        Some((best_h, entries)) if h == *best_h => entries.push(entry),
                        Some((best_h, _)) if h > *best_h => {}
                        _ => best = Some((h, vec![entry])),
                    }
                }
            }
            best.map(|(hamming, entries)| Candidates {
                predicate: Some(i),
                hamming,
                entries,
            })
        })
    }

    /// DRPL-SS's candidates: two distinct segments with the same abstract state.
    pub fn same_state(groups: &StateGroups, asked: &HashSet<SegmentPair>) -> Option<Self> {
        let asked = groups.asked_per_group_pair(asked);
        let entries: Vec<Entry> = (0..groups.len())
            .filter_map(|a| {
                let n = groups.members[a].len() as u64;
                let remaining =
                    n * n.saturating_sub(1) / 2 - asked.get(&(a, a)).copied().unwrap_or(0);
                (remaining > 0).then_some(Entry { a, b: a, remaining })
            })
            .collect();
        (!entries.is_empty()).then_some(Candidates {
            predicate: None,
            hamming: 0,
            entries,
        })
    }

    /// Segment pairs left among the candidates.
    pub fn remaining(&self) -> u64 {
        self.entries.iter().map(|e| e.remaining).sum()
    }

    /// The (first, second) abstract states of every candidate state pair.
    pub fn state_pairs(&self, groups: &StateGroups) -> Vec<(AbstractState, AbstractState)> {
        self.entries
            .iter()
            .map(|e| (groups.states[e.a], groups.states[e.b]))
            .collect()
    }

    /// A segment pair uniformly among those not in `excluded`, or `None` when none is left.
    /// `excluded` must hold the pairs these candidates were built without plus every pair this
    /// method returned since (the caller adds each one), so the counts stay exact.
    pub fn draw(
        &mut self,
        groups: &StateGroups,
        excluded: &HashSet<SegmentPair>,
        rng: &mut impl Rng,
    ) -> Option<SegmentPair> {
        loop {
            let total = self.remaining();
            if total == 0 {
                return None;
            }
            let mut r = rng.random_range(0..total);
            let k = self
                .entries
                .iter()
                .position(|e| {
                    let hit = r < e.remaining;
                    r = r.saturating_sub(e.remaining);
                    hit
                })
                .expect("r < total");
            let entry = self.entries[k];
            let pick = pick_pair(
                &groups.members[entry.a],
                &groups.members[entry.b],
                entry.a == entry.b,
                excluded,
                rng,
            );
            match pick {
                Some(pair) => {
                    self.entries[k].remaining -= 1;
                    return Some(pair);
                }
                // Only if `excluded` was not kept as documented; do not loop forever.
                None => self.entries[k].remaining = 0,
            }
        }
    }
}

/// A uniform pair (one of `a`, one of `b`, distinct members when `same`, i.e. `a` and `b` are
/// one group) that is not in `excluded`: rejection while few are excluded, else listing the rest.
fn pick_pair(
    a: &[usize],
    b: &[usize],
    same: bool,
    excluded: &HashSet<SegmentPair>,
    rng: &mut impl Rng,
) -> Option<SegmentPair> {
    if a.is_empty() || b.is_empty() || (same && a.len() < 2) {
        return None;
    }
    for _ in 0..64 {
        let i = rng.random_range(0..a.len());
        let j = if same {
            // Uniform over the other members.
            let j = rng.random_range(0..a.len() - 1);
            if j >= i { j + 1 } else { j }
        } else {
            rng.random_range(0..b.len())
        };
        let pair = unordered(a[i], b[j]);
        if !excluded.contains(&pair) {
            return Some(pair);
        }
    }
    let rest: Vec<SegmentPair> = a
        .iter()
        .enumerate()
        .flat_map(|(i, &x)| {
            b.iter()
                .enumerate()
                .filter(move |&(j, _)| !same || j > i)
                .map(move |(_, &y)| unordered(x, y))
        })
        .filter(|p| !excluded.contains(p))
        .collect();
    (!rest.is_empty()).then(|| rest[rng.random_range(0..rest.len())])
}
