//! Which pair to ask next, per method (algorithms.md section 3, step 3 and the baselines):
//!
//! - DRPL: two segments whose abstract states differ in the cycled predicate i, at Hamming
//!   distance 1 if possible (see `state_pairs`).
//! - DRPL-MI (ours, not the paper's): DRPL's candidates, picked by mutual information; the
//!   same as DRPL with `Acquisition::MutualInformation` (its default, see
//!   [`QueryMethod::default_acquisition`]).
//! - DRPL-SS: two segments with the same abstract state.
//! - Random fragment: two windows of DRPL's mean segment length from two random trajectories.
//! - Full trajectory: two random whole trajectories.
//!
//! The final pick among a method's candidates is uniform (the paper's), or, with
//! `Acquisition::MutualInformation`, the best of up to `MI_CANDIDATES` uniform draws. No pair
//! is asked twice.

use std::collections::HashSet;
use std::fmt;
use std::str::FromStr;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::acquisition::{self, Acquisition};
use super::belief::Belief;
use super::pool::{Clip, ClipKey, QueryPool};
use super::state_pairs::{Candidates, SegmentPair, StateGroups};

/// Candidates scored per query by mutual information.
pub const MI_CANDIDATES: usize = 200;
/// Random draws of windows before a method declares itself out of new pairs.
const WINDOW_TRIES: usize = 1000;

/// How a preference run picks its pairs (Figure 5's legend).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum QueryMethod {
    Drpl,
    /// DRPL whose run defaults to the mutual-information pick among its candidates.
    DrplMi,
    DrplSs,
    Fragment,
    Full,
}

impl QueryMethod {
    pub const ALL: [QueryMethod; 5] = [
        QueryMethod::Drpl,
        QueryMethod::DrplMi,
        QueryMethod::DrplSs,
        QueryMethod::Fragment,
        QueryMethod::Full,
    ];

    pub fn id(self) -> &'static str {
        match self {
            QueryMethod::Drpl => "drpl",
            QueryMethod::DrplMi => "drpl-mi",
            QueryMethod::DrplSs => "drpl-ss",
            QueryMethod::Fragment => "fragment",
            QueryMethod::Full => "full",
        }
    }

    /// The final pick a run of this method makes unless told otherwise: mutual information for
    /// DRPL-MI, the paper's uniform pick for the others. An `acquisition` setting wins over it.
    pub fn default_acquisition(self) -> Acquisition {
        match self {
            QueryMethod::DrplMi => Acquisition::MutualInformation,
            QueryMethod::Drpl | QueryMethod::DrplSs | QueryMethod::Fragment | QueryMethod::Full => {
                Acquisition::Uniform
            }
        }
    }
}

impl fmt::Display for QueryMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// A name that is no [`QueryMethod`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown preference method {0:?}: expected drpl, drpl-mi, drpl-ss, fragment or full")]
pub struct UnknownQueryMethod(pub String);

impl FromStr for QueryMethod {
    type Err = UnknownQueryMethod;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        QueryMethod::ALL
            .into_iter()
            .find(|m| m.id() == s)
            .ok_or_else(|| UnknownQueryMethod(s.to_string()))
    }
}

/// One query: the two clips in display order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QueryPair {
    pub left: Clip,
    pub right: Clip,
    /// DRPL's cycled predicate i that the two states differ in; `None` for the baselines.
    pub predicate: Option<usize>,
}

/// The pair-space a query draws from: segment pairs (DRPL, DRPL-SS) or pairs of windows.
enum Space {
    Segments(Candidates),
    /// Windows of this many steps (at most the trajectory's length); whole trajectories for
    /// `usize::MAX`.
    Windows(usize),
}

/// A drawn candidate, before display order is decided.
struct Drawn {
    first: Clip,
    second: Clip,
    segments: Option<SegmentPair>,
}

pub struct Selector {
    method: QueryMethod,
    acquisition: Acquisition,
    groups: StateGroups,
    asked_segments: HashSet<SegmentPair>,
    asked_clips: HashSet<(ClipKey, ClipKey)>,
    rng: ChaCha8Rng,
}

impl Selector {
    pub fn new(
        method: QueryMethod,
        acquisition: Acquisition,
        pool: &QueryPool,
        rng: ChaCha8Rng,
    ) -> Self {
        let states: Vec<_> = pool.segments().iter().map(|s| s.abstract_state).collect();
        Self {
            method,
            acquisition,
            groups: StateGroups::new(&states),
            asked_segments: HashSet::new(),
            asked_clips: HashSet::new(),
            rng,
        }
    }

    pub fn method(&self) -> QueryMethod {
        self.method
    }

    /// The pair of query `query_index` (0-based; DRPL cycles its predicate with it), or `None`
    /// when the method has no unasked pair left. `belief` is read only by mutual information.
    /// `dim` is the scene graph's number of predicates.
    pub fn next(
        &mut self,
        pool: &QueryPool,
        dim: usize,
        query_index: usize,
        belief: &Belief,
    ) -> Option<QueryPair> {
        let mut space = match self.method {
            QueryMethod::Drpl | QueryMethod::DrplMi => Space::Segments(Candidates::drpl(
                &self.groups,
                dim,
                query_index,
                &self.asked_segments,
            )?),
            QueryMethod::DrplSs => {
                Space::Segments(Candidates::same_state(&self.groups, &self.asked_segments)?)
            }
            QueryMethod::Fragment => Space::Windows(pool.fragment_length()),
            QueryMethod::Full => Space::Windows(usize::MAX),
        };
        let predicate = match &space {
            Space::Segments(c) => c.predicate,
            Space::Windows(_) => None,
        };
        let wanted = match self.acquisition {
            Acquisition::Uniform => 1,
            Acquisition::MutualInformation => MI_CANDIDATES,
        };
        // Pairs drawn in this round join the exclusions so that the round's draws are distinct.
        let mut segs = self.asked_segments.clone();
        let mut clips = self.asked_clips.clone();
        let mut drawn: Vec<Drawn> = Vec::new();
        while drawn.len() < wanted {
            let Some(d) = self.draw(&mut space, pool, &segs, &clips) else {
                break;
            };
            if let Some(p) = d.segments {
                segs.insert(p);
            }
            clips.insert(clip_pair_key(&d.first, &d.second));
            drawn.push(d);
        }
        let best = match self.acquisition {
            Acquisition::Uniform => drawn.into_iter().next()?,
            Acquisition::MutualInformation => {
                let scores: Vec<f64> = drawn
                    .iter()
                    .map(|d| {
                        acquisition::mutual_information(
                            belief,
                            &d.first.features,
                            &d.second.features,
                            false,
                        )
                    })
                    .collect();
                // The first of the best, so that ties keep the uniform draw's order.
                let k =
                    (0..scores.len()).reduce(|b, k| if scores[k] > scores[b] { k } else { b })?;
                drawn.swap_remove(k)
            }
        };
        if let Some(p) = best.segments {
            self.asked_segments.insert(p);
        }
        self.asked_clips
            .insert(clip_pair_key(&best.first, &best.second));
        // Which side is shown left is a coin flip, so a trainer's side bias cannot favour a method.
        let (left, right) = if self.rng.random::<bool>() {
            (best.second, best.first)
        } else {
            (best.first, best.second)
        };
        Some(QueryPair {
            left,
            right,
            predicate,
        })
    }

    fn draw(
        &mut self,
        space: &mut Space,
        pool: &QueryPool,
        segs: &HashSet<SegmentPair>,
        clips: &HashSet<(ClipKey, ClipKey)>,
    ) -> Option<Drawn> {
        match space {
            Space::Segments(c) => {
                let (a, b) = c.draw(&self.groups, segs, &mut self.rng)?;
                Some(Drawn {
                    first: pool.segment_clip(a),
                    second: pool.segment_clip(b),
                    segments: Some((a, b)),
                })
            }
            Space::Windows(len) => {
                let (first, second) = draw_windows(pool, *len, clips, &mut self.rng)?;
                Some(Drawn {
                    first,
                    second,
                    segments: None,
                })
            }
        }
    }
}

/// The unordered identity of a pair of clips.
fn clip_pair_key(a: &Clip, b: &Clip) -> (ClipKey, ClipKey) {
    let (ka, kb) = (a.key(), b.key());
    (ka.min(kb), ka.max(kb))
}

/// Two windows of `len` steps (the whole trajectory when shorter) at uniform offsets in two
/// distinct random non-empty trajectories, not in `asked`. `None` after `WINDOW_TRIES` draws
/// that were all asked already (or with fewer than two trajectories).
fn draw_windows(
    pool: &QueryPool,
    len: usize,
    asked: &HashSet<(ClipKey, ClipKey)>,
    rng: &mut impl Rng,
) -> Option<(Clip, Clip)> {
    let usable: Vec<usize> = (0..pool.trajectories())
        .filter(|&t| pool.trajectory_len(t) > 0)
        .collect();
    if usable.len() < 2 {
        return None;
    }
    let window = |t: usize, rng: &mut dyn rand::RngCore| {
        let n = pool.trajectory_len(t);
        let l = len.min(n);
        let start = rng.random_range(0..=n - l);
        (t, start, start + l)
    };
    for _ in 0..WINDOW_TRIES {
        let i = rng.random_range(0..usable.len());
        let j = (i + rng.random_range(1..usable.len())) % usable.len();
        let a = window(usable[i], rng);
        let b = window(usable[j], rng);
        if !asked.contains(&(a.min(b), a.max(b))) {
            return Some((
                pool.window_clip(a.0, a.1..a.2),
                pool.window_clip(b.0, b.1..b.2),
            ));
        }
    }
    None
}

#[cfg(test)]
#[path = "selection_tests.rs"]
mod tests;
