//! Pair selection on hand-made segment sets: each segment is its own trajectory of `len` steps
//! in one abstract state, so the test decides exactly which states and counts exist.

use std::collections::{HashMap, HashSet};

use rand::SeedableRng;

use super::*;
use crate::guidance::drpl::belief::BeliefConfig;
use crate::guidance::drpl::pool::TrajectoryFeatures;
use crate::scene_graph::AbstractState;

/// One trajectory per `(state bits, steps)`, whose single feature is unique per step.
fn pool_of(segments: &[(u32, usize)]) -> QueryPool {
    let trajs = segments
        .iter()
        .enumerate()
        .map(|(k, &(g, len))| TrajectoryFeatures {
            states: vec![AbstractState(g); len],
            phis: (0..len).map(|t| vec![(k * 100 + t) as f64]).collect(),
        })
        .collect();
    QueryPool::new(1, trajs, 3)
}

fn selector(method: QueryMethod, pool: &QueryPool) -> Selector {
    Selector::new(
        method,
        Acquisition::Uniform,
        pool,
        ChaCha8Rng::seed_from_u64(5),
    )
}

fn belief() -> Belief {
    Belief::new(1, BeliefConfig::default(), 0)
}

fn states(pair: &QueryPair) -> (AbstractState, AbstractState) {
    (
        pair.left.abstract_state.unwrap(),
        pair.right.abstract_state.unwrap(),
    )
}

fn key(pair: &QueryPair) -> (ClipKey, ClipKey) {
    clip_pair_key(&pair.left, &pair.right)
}

#[test]
fn drpl_pairs_differ_in_exactly_the_cycled_predicate() {
    // Every single-bit neighbour exists for every predicate of a 3-bit graph.
    let segs: Vec<(u32, usize)> = (0..8u32).flat_map(|g| [(g, 3), (g, 4)]).collect();
    let pool = pool_of(&segs);
    let mut sel = selector(QueryMethod::Drpl, &pool);
    let b = belief();
    for q in 0..30 {
        let pair = sel.next(&pool, 3, q, &b).unwrap();
        let (gl, gr) = states(&pair);
        assert_eq!(pair.predicate, Some(q % 3));
        assert_eq!(gl.hamming(gr), 1, "query {q}: {gl} vs {gr}");
        assert_ne!(gl.bit(q % 3), gr.bit(q % 3));
    }
}

#[test]
fn drpl_falls_back_to_the_least_hamming_distance() {
    // States 000, 011, 101: no pair is one flip apart. Bit 0 splits 000 from 011 and 101 (both
    // at distance 2), while 011 vs 101 agree on bit 0.
    let pool = pool_of(&[(0b000, 3), (0b011, 3), (0b101, 3), (0b101, 5)]);
    let groups = StateGroups::new(&[
        AbstractState(0b000),
        AbstractState(0b011),
        AbstractState(0b101),
        AbstractState(0b101),
    ]);
    let c = Candidates::drpl(&groups, 3, 0, &HashSet::new()).unwrap();
    assert_eq!((c.predicate, c.hamming, c.remaining()), (Some(0), 2, 3));
    let mut sel = selector(QueryMethod::Drpl, &pool);
    let b = belief();
    for _ in 0..3 {
        let pair = sel.next(&pool, 3, 0, &b).unwrap();
        let (gl, gr) = states(&pair);
        assert_eq!(gl.hamming(gr), 2);
        assert!(gl.0 == 0 || gr.0 == 0, "{gl} vs {gr}");
    }
    // Bit 0's pairs are used up: the next predicate with a pair takes over (bit 1: 000 vs 011,
    // asked already; 011 vs 101 at distance 2).
    let pair = sel.next(&pool, 3, 0, &b).unwrap();
    assert_eq!(pair.predicate, Some(1));
    let (gl, gr) = states(&pair);
    assert_eq!(
        (gl.0.min(gr.0), gl.0.max(gr.0)),
        (0b011, 0b101),
        "the only unasked pair differing in bit 1"
    );
}

#[test]
fn drpl_skips_predicates_no_pair_differs_in() {
    let pool = pool_of(&[(0b00, 3), (0b01, 3)]);
    let mut sel = selector(QueryMethod::Drpl, &pool);
    let pair = sel.next(&pool, 3, 1, &belief()).unwrap();
    assert_eq!(pair.predicate, Some(0));
}

#[test]
fn no_pair_is_asked_twice_until_none_is_left() {
    let segs = [(0b0, 3), (0b0, 4), (0b1, 3), (0b1, 5), (0b1, 6)];
    let b = belief();
    // DRPL: 2 x 3 cross pairs. DRPL-SS: 1 + 3 same-state pairs. Full: C(5, 2) trajectories.
    for (method, total) in [
        (QueryMethod::Drpl, 6),
        (QueryMethod::DrplSs, 4),
        (QueryMethod::Full, 10),
    ] {
        let pool = pool_of(&segs);
        let mut sel = selector(method, &pool);
        let mut seen = HashSet::new();
        for q in 0..total {
            let pair = sel
                .next(&pool, 1, q, &b)
                .unwrap_or_else(|| panic!("{method} {q}"));
            assert!(
                seen.insert(key(&pair)),
                "{method}: repeated {:?}",
                key(&pair)
            );
        }
        assert!(sel.next(&pool, 1, total, &b).is_none(), "{method}");
    }
}

#[test]
fn drpl_ss_pairs_share_their_state() {
    let segs: Vec<(u32, usize)> = (0..4u32).flat_map(|g| [(g, 3), (g, 4), (g, 5)]).collect();
    let pool = pool_of(&segs);
    let mut sel = selector(QueryMethod::DrplSs, &pool);
    let b = belief();
    for q in 0..12 {
        let pair = sel.next(&pool, 2, q, &b).unwrap();
        let (gl, gr) = states(&pair);
        assert_eq!(gl, gr);
        assert_ne!(pair.left.key(), pair.right.key());
        assert_eq!(pair.predicate, None);
    }
    assert!(sel.next(&pool, 2, 12, &b).is_none());
}

#[test]
fn fragments_have_the_rounded_mean_segment_length() {
    // Segment lengths 3, 4, 4, 20: mean 7.75 -> 8.
    let pool = pool_of(&[(0, 3), (1, 4), (2, 4), (3, 20)]);
    assert_eq!(pool.fragment_length(), 8);
    let mut sel = selector(QueryMethod::Fragment, &pool);
    let b = belief();
    for q in 0..20 {
        let pair = sel.next(&pool, 2, q, &b).unwrap();
        for clip in [&pair.left, &pair.right] {
            let n = pool.trajectory_len(clip.trajectory);
            assert_eq!(clip.len(), n.min(8), "{clip:?}");
            assert!(clip.end <= n && clip.abstract_state.is_none());
        }
        assert_ne!(pair.left.trajectory, pair.right.trajectory);
    }
}

#[test]
fn full_trajectories_are_whole() {
    let pool = pool_of(&[(0, 3), (1, 4), (2, 9)]);
    let mut sel = selector(QueryMethod::Full, &pool);
    let pair = sel.next(&pool, 2, 0, &belief()).unwrap();
    for clip in [&pair.left, &pair.right] {
        assert_eq!(
            (clip.start, clip.end),
            (0, pool.trajectory_len(clip.trajectory))
        );
    }
}

#[test]
fn state_pairs_are_weighted_by_their_segment_pairs() {
    // Bit 0 splits 00|01 (1 x 3 segment pairs) and 10|11 (1 x 1): uniform over the 4 segment
    // pairs gives the first state pair 3/4 of the draws, not 1/2.
    let g = [0b00, 0b01, 0b01, 0b01, 0b10, 0b11].map(AbstractState);
    let groups = StateGroups::new(&g);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut counts: HashMap<SegmentPair, u32> = HashMap::new();
    for _ in 0..8000 {
        let mut c = Candidates::drpl(&groups, 2, 0, &HashSet::new()).unwrap();
        *counts
            .entry(c.draw(&groups, &HashSet::new(), &mut rng).unwrap())
            .or_default() += 1;
    }
    let keys: HashSet<_> = counts.keys().copied().collect();
    assert_eq!(keys, HashSet::from([(0, 1), (0, 2), (0, 3), (4, 5)]));
    for n in counts.values() {
        assert!((1800..2200).contains(n), "{counts:?}");
    }
}

#[test]
fn mutual_information_picks_a_valid_new_pair() {
    let segs: Vec<(u32, usize)> = (0..4u32).flat_map(|g| [(g, 3), (g, 4)]).collect();
    let pool = pool_of(&segs);
    let b = belief();
    for method in QueryMethod::ALL {
        let mut sel = Selector::new(
            method,
            Acquisition::MutualInformation,
            &pool,
            ChaCha8Rng::seed_from_u64(2),
        );
        let mut seen = HashSet::new();
        for q in 0..4 {
            let pair = sel.next(&pool, 2, q, &b).unwrap();
            assert!(seen.insert(key(&pair)), "{method}");
        }
    }
}

#[test]
fn method_names_round_trip() {
    for m in QueryMethod::ALL {
        assert_eq!(m.id().parse::<QueryMethod>().unwrap(), m);
        assert_eq!(
            serde_json::to_string(&m).unwrap(),
            format!("\"{}\"", m.id())
        );
    }
    assert!("drpl_ss".parse::<QueryMethod>().is_err());
}
