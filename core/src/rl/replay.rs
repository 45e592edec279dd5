//! The replay buffer: preallocated, f32, one row per transition, with the human feedback H
//! stored beside the environment reward (DREF's `(s, a, r, H, s', terminated)`).
//!
//! Storage is sample-major (one transition's observation is contiguous), which is exactly the
//! layout of a column-major `features x batch` matrix, so a sampled batch feeds the networks
//! without a transpose.

use rand::Rng;

/// One transition, borrowed from the caller.
#[derive(Clone, Copy, Debug)]
pub struct Transition<'a> {
    pub obs: &'a [f32],
    pub action: &'a [f32],
    pub reward: f32,
    /// Human feedback in {-1, 0, +1}; 0 when nobody was asked.
    pub human: f32,
    pub next_obs: &'a [f32],
    /// A true end of the MDP: masks the bootstrap. Truncation (time limit) is not termination.
    pub terminated: bool,
}

/// A sampled minibatch, preallocated for `size` transitions and refilled in place.
#[derive(Clone, Debug)]
pub struct Batch {
    pub size: usize,
    /// `size x obs_dim`, one observation after another.
    pub obs: Vec<f32>,
    pub actions: Vec<f32>,
    pub rewards: Vec<f32>,
    pub human: Vec<f32>,
    pub next_obs: Vec<f32>,
    /// 1.0 where the transition terminated, else 0.0 (so `1 - done` masks the bootstrap).
    pub dones: Vec<f32>,
}

impl Batch {
    pub fn new(size: usize, obs_dim: usize, act_dim: usize) -> Self {
        Self {
            size,
            obs: vec![0.0; size * obs_dim],
            actions: vec![0.0; size * act_dim],
            rewards: vec![0.0; size],
            human: vec![0.0; size],
            next_obs: vec![0.0; size * obs_dim],
            dones: vec![0.0; size],
        }
    }
}

/// Why bytes do not read back as a [`ReplayBuffer`] of a [`ReplayLayout`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReplayBytesError {
    /// A layout no buffer has (no capacity, more rows than room, a head out of place).
    #[error("replay layout {0:?} is inconsistent")]
    InconsistentLayout(ReplayLayout),
    /// Not as many bytes as the layout's rows take.
    #[error("replay bytes: expected {expected} for {rows} rows, found {found}")]
    Length {
        expected: usize,
        rows: usize,
        found: usize,
    },
}

/// A buffer's shape and fill, stored beside its bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ReplayLayout {
    pub capacity: usize,
    pub len: usize,
    pub head: usize,
    pub obs_dim: usize,
    pub act_dim: usize,
}

/// A ring buffer of transitions; the oldest are overwritten once it is full.
#[derive(Clone, Debug)]
pub struct ReplayBuffer {
    obs_dim: usize,
    act_dim: usize,
    capacity: usize,
    len: usize,
    /// Where the next transition goes.
    head: usize,
    obs: Vec<f32>,
    actions: Vec<f32>,
    rewards: Vec<f32>,
    human: Vec<f32>,
    next_obs: Vec<f32>,
    dones: Vec<f32>,
    /// The slots whose H is not 0, in slot order: what a human critic with a batch of its own
    /// draws from (`answer_replay`). Derived from `human`, so a checkpoint need not store it.
    answered: Vec<usize>,
}

impl ReplayBuffer {
    /// Allocates everything now: pushing and sampling never allocate.
    pub fn new(capacity: usize, obs_dim: usize, act_dim: usize) -> Self {
        assert!(capacity > 0, "replay capacity must be positive");
        Self {
            obs_dim,
            act_dim,
            capacity,
            len: 0,
            head: 0,
            obs: vec![0.0; capacity * obs_dim],
            actions: vec![0.0; capacity * act_dim],
            rewards: vec![0.0; capacity],
            human: vec![0.0; capacity],
            next_obs: vec![0.0; capacity * obs_dim],
            dones: vec![0.0; capacity],
            answered: Vec::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// Store a transition and return its slot, so that its H can be relabelled later (an undo).
    pub fn push(&mut self, t: Transition<'_>) -> usize {
        assert_eq!(t.obs.len(), self.obs_dim);
        assert_eq!(t.next_obs.len(), self.obs_dim);
        assert_eq!(t.action.len(), self.act_dim);
        let i = self.head;
        self.obs[i * self.obs_dim..(i + 1) * self.obs_dim].copy_from_slice(t.obs);
        self.next_obs[i * self.obs_dim..(i + 1) * self.obs_dim].copy_from_slice(t.next_obs);
        self.actions[i * self.act_dim..(i + 1) * self.act_dim].copy_from_slice(t.action);
        self.rewards[i] = t.reward;
        self.set_human_in(i, t.human);
        self.dones[i] = if t.terminated { 1.0 } else { 0.0 };
        self.head = (self.head + 1) % self.capacity;
        self.len = (self.len + 1).min(self.capacity);
        i
    }

    /// Whether the transition in `slot` was stored as terminal (no bootstrap past it).
    pub fn terminated(&self, slot: usize) -> bool {
        self.dones[slot] != 0.0
    }

    /// Replace the human feedback stored in `slot`.
    pub fn set_human(&mut self, slot: usize, human: f32) {
        assert!(slot < self.len, "slot {slot} not filled");
        self.set_human_in(slot, human);
    }

    /// `human[slot] = human`, keeping `answered` (sorted by slot) in step with it.
    fn set_human_in(&mut self, slot: usize, human: f32) {
        let was = self.human[slot] != 0.0;
        self.human[slot] = human;
        match (was, human != 0.0, self.answered.binary_search(&slot)) {
            (false, true, Err(at)) => self.answered.insert(at, slot),
            (true, false, Ok(at)) => {
                self.answered.remove(at);
            }
            _ => {}
        }
    }

    /// How many stored transitions have an answer (H != 0).
    pub fn answered_len(&self) -> usize {
        self.answered.len()
    }

    pub fn human(&self, slot: usize) -> f32 {
        self.human[slot]
    }

    /// The action stored in `slot`.
    pub fn action(&self, slot: usize) -> &[f32] {
        &self.actions[slot * self.act_dim..(slot + 1) * self.act_dim]
    }

    /// The filled rows as little-endian f32 bytes, array after array (observations, actions,
    /// rewards, H, next observations, dones), for a run's checkpoint; with [`ReplayLayout`].
    pub fn to_bytes(&self) -> (ReplayLayout, Vec<u8>) {
        let layout = ReplayLayout {
            capacity: self.capacity,
            len: self.len,
            head: self.head,
            obs_dim: self.obs_dim,
            act_dim: self.act_dim,
        };
        let mut bytes = Vec::with_capacity(self.len * self.row_floats() * 4);
        for (array, width) in self.arrays() {
            for v in &array[..self.len * width] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        (layout, bytes)
    }

    /// The buffer [`ReplayBuffer::to_bytes`] described; an error if the bytes do not fit the
    /// layout.
    pub fn from_bytes(layout: &ReplayLayout, bytes: &[u8]) -> Result<Self, ReplayBytesError> {
        let ReplayLayout {
            capacity,
            len,
            head,
            obs_dim,
            act_dim,
        } = *layout;
        if capacity == 0 || len > capacity || head >= capacity || (len < capacity && head != len) {
            return Err(ReplayBytesError::InconsistentLayout(*layout));
        }
        let mut buffer = Self::new(capacity, obs_dim, act_dim);
        if bytes.len() != len * buffer.row_floats() * 4 {
            return Err(ReplayBytesError::Length {
                expected: len * buffer.row_floats() * 4,
                rows: len,
                found: bytes.len(),
            });
        }
        let mut floats = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]));
        for (array, width) in buffer.arrays_mut() {
            for (slot, v) in array[..len * width].iter_mut().zip(&mut floats) {
                *slot = v;
            }
        }
        buffer.len = len;
        buffer.head = head;
        buffer.answered = (0..len).filter(|&i| buffer.human[i] != 0.0).collect();
        Ok(buffer)
    }

    fn row_floats(&self) -> usize {
        2 * self.obs_dim + self.act_dim + 3
    }

    fn arrays(&self) -> [(&[f32], usize); 6] {
        [
            (&self.obs, self.obs_dim),
            (&self.actions, self.act_dim),
            (&self.rewards, 1),
            (&self.human, 1),
            (&self.next_obs, self.obs_dim),
            (&self.dones, 1),
        ]
    }

    fn arrays_mut(&mut self) -> [(&mut [f32], usize); 6] {
        [
            (&mut self.obs, self.obs_dim),
            (&mut self.actions, self.act_dim),
            (&mut self.rewards, 1),
            (&mut self.human, 1),
            (&mut self.next_obs, self.obs_dim),
            (&mut self.dones, 1),
        ]
    }

    /// Fill `batch` with transitions drawn uniformly with replacement.
    pub fn sample<R: Rng>(&self, rng: &mut R, batch: &mut Batch) {
        assert!(!self.is_empty(), "sampling an empty replay buffer");
        for b in 0..batch.size {
            let i = rng.random_range(0..self.len);
            self.copy_row(i, batch, b);
        }
    }

    /// Fill `batch` with answered transitions (H != 0), drawn uniformly with replacement among
    /// them. While none has an answer nothing is drawn and the batch's H is all 0: a batch
    /// without feedback, which the masked critic already skips.
    pub fn sample_answered<R: Rng>(&self, rng: &mut R, batch: &mut Batch) {
        self.sample_answered_first(rng, batch, self.answered.len());
    }

    /// [`ReplayBuffer::sample_answered`] among the first `first` answered slots by slot number
    /// (by time, until the buffer wraps), or all of them if there are fewer.
    pub fn sample_answered_first<R: Rng>(&self, rng: &mut R, batch: &mut Batch, first: usize) {
        let among = &self.answered[..first.min(self.answered.len())];
        if among.is_empty() {
            batch.human.fill(0.0);
            return;
        }
        for b in 0..batch.size {
            let i = among[rng.random_range(0..among.len())];
            self.copy_row(i, batch, b);
        }
    }

    /// Slot `i` into row `b` of `batch`.
    fn copy_row(&self, i: usize, batch: &mut Batch, b: usize) {
        let (od, ad) = (self.obs_dim, self.act_dim);
        batch.obs[b * od..(b + 1) * od].copy_from_slice(&self.obs[i * od..(i + 1) * od]);
        batch.next_obs[b * od..(b + 1) * od].copy_from_slice(&self.next_obs[i * od..(i + 1) * od]);
        batch.actions[b * ad..(b + 1) * ad].copy_from_slice(&self.actions[i * ad..(i + 1) * ad]);
        batch.rewards[b] = self.rewards[i];
        batch.human[b] = self.human[i];
        batch.dones[b] = self.dones[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn push_marked(buf: &mut ReplayBuffer, mark: f32, terminated: bool) -> usize {
        buf.push(Transition {
            obs: &[mark, mark + 0.5],
            action: &[-mark],
            reward: mark * 10.0,
            human: 0.0,
            next_obs: &[mark + 1.0, mark + 1.5],
            terminated,
        })
    }

    #[test]
    fn sampled_rows_keep_each_transition_together() {
        let mut buf = ReplayBuffer::new(8, 2, 1);
        for m in 0..5 {
            push_marked(&mut buf, m as f32, m == 4);
        }
        let mut batch = Batch::new(64, 2, 1);
        buf.sample(&mut ChaCha8Rng::seed_from_u64(0), &mut batch);
        for b in 0..64 {
            let m = batch.obs[2 * b];
            assert!((0.0..5.0).contains(&m));
            assert_eq!(batch.obs[2 * b + 1], m + 0.5);
            assert_eq!(batch.actions[b], -m);
            assert_eq!(batch.rewards[b], m * 10.0);
            assert_eq!(batch.next_obs[2 * b], m + 1.0);
            assert_eq!(batch.dones[b], if m == 4.0 { 1.0 } else { 0.0 });
        }
    }

    #[test]
    fn a_full_buffer_overwrites_the_oldest() {
        let mut buf = ReplayBuffer::new(3, 2, 1);
        let slots: Vec<usize> = (0..5)
            .map(|m| push_marked(&mut buf, m as f32, false))
            .collect();
        assert_eq!(slots, vec![0, 1, 2, 0, 1]);
        assert_eq!(buf.len(), 3);
        let mut batch = Batch::new(200, 2, 1);
        buf.sample(&mut ChaCha8Rng::seed_from_u64(1), &mut batch);
        let mut seen: Vec<f32> = batch.rewards.clone();
        seen.sort_by(f32::total_cmp);
        seen.dedup();
        assert_eq!(seen, vec![20.0, 30.0, 40.0], "the two oldest are gone");
    }

    #[test]
    fn human_feedback_can_be_relabelled() {
        let mut buf = ReplayBuffer::new(4, 2, 1);
        let slot = push_marked(&mut buf, 1.0, false);
        buf.set_human(slot, -1.0);
        assert_eq!(buf.human(slot), -1.0);
        let mut batch = Batch::new(4, 2, 1);
        buf.sample(&mut ChaCha8Rng::seed_from_u64(2), &mut batch);
        assert!(batch.human.iter().all(|&h| h == -1.0));
    }

    /// The answered slots follow every way H changes: a push with an answer, a relabel (an
    /// undo to 0 and a late answer), an overwrite of the oldest, and a checkpoint's bytes.
    #[test]
    fn answered_draws_come_from_answered_slots_only() {
        let mut buf = ReplayBuffer::new(4, 2, 1);
        let mut batch = Batch::new(64, 2, 1);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        push_marked(&mut buf, 0.0, false);
        batch.human.fill(1.0);
        buf.sample_answered(&mut rng, &mut batch);
        assert!(
            batch.human.iter().all(|&h| h == 0.0),
            "nothing answered yet: a batch without feedback"
        );
        let drawn = |buf: &ReplayBuffer, rng: &mut ChaCha8Rng, batch: &mut Batch| {
            buf.sample_answered(rng, batch);
            let mut marks: Vec<f32> = batch.obs.iter().step_by(2).copied().collect();
            marks.sort_by(f32::total_cmp);
            marks.dedup();
            assert!(batch.human.iter().all(|&h| h != 0.0));
            marks
        };
        let answered = |buf: &mut ReplayBuffer, mark: f32, human: f32| {
            buf.push(Transition {
                obs: &[mark, mark + 0.5],
                action: &[-mark],
                reward: 0.0,
                human,
                next_obs: &[mark, mark],
                terminated: false,
            })
        };
        answered(&mut buf, 1.0, 1.0);
        let late = push_marked(&mut buf, 2.0, false);
        answered(&mut buf, 3.0, -1.0);
        assert_eq!(drawn(&buf, &mut rng, &mut batch), vec![1.0, 3.0]);
        buf.set_human(late, 1.0);
        buf.set_human(1, 0.0);
        assert_eq!(buf.answered_len(), 2);
        assert_eq!(drawn(&buf, &mut rng, &mut batch), vec![2.0, 3.0]);
        // Slot 0 (mark 0, silent) is overwritten by an answered 4, then slot 1 by a silent 5.
        answered(&mut buf, 4.0, 1.0);
        push_marked(&mut buf, 5.0, false);
        assert_eq!(drawn(&buf, &mut rng, &mut batch), vec![2.0, 3.0, 4.0]);
        let (layout, bytes) = buf.to_bytes();
        let back = ReplayBuffer::from_bytes(&layout, &bytes).unwrap();
        assert_eq!(back.answered, buf.answered);
        answered(&mut buf, 6.0, 1.0); // overwrites the answered 2 in slot 2
        assert_eq!(drawn(&buf, &mut rng, &mut batch), vec![3.0, 4.0, 6.0]);
    }

    #[test]
    fn bytes_round_trip_a_partial_and_a_wrapped_buffer() {
        for pushes in [2, 5] {
            let mut buf = ReplayBuffer::new(3, 2, 1);
            for m in 0..pushes {
                push_marked(&mut buf, m as f32, m % 2 == 1);
            }
            buf.set_human(0, 1.0);
            let (layout, bytes) = buf.to_bytes();
            let mut back = ReplayBuffer::from_bytes(&layout, &bytes).unwrap();
            assert_eq!((back.len(), back.head), (buf.len(), buf.head));
            let (mut a, mut b) = (Batch::new(32, 2, 1), Batch::new(32, 2, 1));
            buf.sample(&mut ChaCha8Rng::seed_from_u64(3), &mut a);
            back.sample(&mut ChaCha8Rng::seed_from_u64(3), &mut b);
            assert_eq!((a.obs, a.human, a.dones), (b.obs, b.human, b.dones));
            // The next push lands in the same slot in both.
            assert_eq!(
                push_marked(&mut back, 9.0, false),
                push_marked(&mut buf, 9.0, false)
            );
            let short = ReplayBuffer::from_bytes(&layout, &bytes[4..]).unwrap_err();
            assert_eq!(
                short.to_string(),
                format!(
                    "replay bytes: expected {} for {} rows, found {}",
                    bytes.len(),
                    layout.len,
                    bytes.len() - 4
                )
            );
            let bad = ReplayLayout { head: 3, ..layout };
            assert_eq!(
                ReplayBuffer::from_bytes(&bad, &bytes).unwrap_err(),
                ReplayBytesError::InconsistentLayout(bad)
            );
        }
    }
}
