//! Adam (Kingma & Ba 2015) as `torch.optim.Adam` computes it on the CPU.

use super::kernels::{self, KernelPath};

/// Adam's hyper-parameters; the defaults are PyTorch's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdamConfig {
    /// Learning rate (PyTorch: 1e-3; SAC's per-task values are in `algorithms.md`).
    pub lr: f64,
    /// Decay of the first-moment estimate.
    pub beta1: f64,
    /// Decay of the second-moment estimate.
    pub beta2: f64,
    /// Added to the bias-corrected `sqrt(v)` in the denominator.
    pub eps: f64,
}

impl Default for AdamConfig {
    fn default() -> Self {
        Self {
            lr: 1e-3,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        }
    }
}

impl AdamConfig {
    pub fn with_lr(lr: f64) -> Self {
        Self {
            lr,
            ..Self::default()
        }
    }
}

/// Adam over a fixed set of parameter groups (flat slices, e.g. one per network: a twin critic
/// is two groups under one optimiser, as SB3's critic optimiser covers `q1` and `q2`).
///
/// Owns the moment estimates, allocated once in [`Adam::new`]; [`Adam::step`] allocates nothing.
/// Gradients belong to the networks, so zeroing them is [`crate::rl::Mlp::zero_grad`].
#[derive(Clone, Debug)]
pub struct Adam {
    pub config: AdamConfig,
    /// Steps taken so far (PyTorch's `state["step"]`, shared by all groups here since every
    /// group is updated at every step).
    t: u64,
    /// First-moment estimate per group.
    m: Vec<Vec<f32>>,
    /// Second-moment estimate per group.
    v: Vec<Vec<f32>>,
}

impl Adam {
    /// An optimiser for groups of the given lengths (e.g. `&[q1.params().len(), q2.params().len()]`).
    pub fn new(config: AdamConfig, group_lens: &[usize]) -> Self {
        Self {
            config,
            t: 0,
            m: group_lens.iter().map(|&n| vec![0.0; n]).collect(),
            v: group_lens.iter().map(|&n| vec![0.0; n]).collect(),
        }
    }

    pub fn steps(&self) -> u64 {
        self.t
    }

    /// Each group's first- and second-moment estimates (PyTorch's `exp_avg`, `exp_avg_sq`),
    /// for checkpoints.
    pub fn moments(&self) -> impl Iterator<Item = (&[f32], &[f32])> {
        self.m.iter().zip(&self.v).map(|(m, v)| (&m[..], &v[..]))
    }

    /// Restore a checkpointed state: the step count, then each group's moments in place.
    pub fn moments_mut(&mut self, steps: u64) -> impl Iterator<Item = (&mut [f32], &mut [f32])> {
        self.t = steps;
        self.m
            .iter_mut()
            .zip(&mut self.v)
            .map(|(m, v)| (&mut m[..], &mut v[..]))
    }

    /// One update of every group, given as `(params, grads)` pairs in the order of
    /// [`Adam::new`] (e.g. `adam.step([q1.params_and_grads(), q2.params_and_grads()])`).
    ///
    /// Follows `torch.optim.adam._single_tensor_adam` operation by operation, so results agree
    /// with PyTorch to f32 rounding:
    ///
    /// ```text
    /// m = lerp(m, g, 1 - beta1)                 // = beta1 m + (1 - beta1) g
    /// v = beta2 v + (1 - beta2) g^2
    /// p -= lr / (1 - beta1^t) * m / (sqrt(v) / sqrt(1 - beta2^t) + eps)
    /// ```
    pub fn step<'a>(&mut self, groups: impl IntoIterator<Item = (&'a mut [f32], &'a [f32])>) {
        self.t += 1;
        let c = self.config;
        // Scalars in f64 as Python computes them, then rounded once to the tensors' f32.
        let t = self.t as f64;
        let step_size = (c.lr / (1.0 - c.beta1.powf(t))) as f32;
        let bias_correction2_sqrt = (1.0 - c.beta2.powf(t)).sqrt() as f32;
        let (one_minus_beta1, beta2, one_minus_beta2, eps) = (
            (1.0 - c.beta1) as f32,
            c.beta2 as f32,
            (1.0 - c.beta2) as f32,
            c.eps as f32,
        );

        let scalars = Scalars {
            one_minus_beta1,
            beta2,
            one_minus_beta2,
            eps,
            step_size,
            bias_correction2_sqrt,
        };
        let path = kernels::current_path();
        let mut count = 0;
        for ((params, grads), (m, v)) in groups.into_iter().zip(self.m.iter_mut().zip(&mut self.v))
        {
            count += 1;
            assert!(
                params.len() == m.len() && grads.len() == m.len(),
                "Adam group {count}: {} params and {} grads for a group of {}",
                params.len(),
                grads.len(),
                m.len()
            );
            step_group(path, params, grads, m, v, scalars);
        }
        assert_eq!(
            count,
            self.m.len(),
            "Adam::step got {count} groups, expected {}",
            self.m.len()
        );
    }
}

/// One step's scalars, as `Adam::step` rounds them.
#[derive(Clone, Copy)]
struct Scalars {
    one_minus_beta1: f32,
    beta2: f32,
    one_minus_beta2: f32,
    eps: f32,
    step_size: f32,
    bias_correction2_sqrt: f32,
}

/// Elements below which a group is not shared out over threads.
const MIN_SHARED: usize = 1 << 15;

/// One group's update on `path`: the same operations on every element whatever the path (the
/// fast paths only compile the loop for wider vectors) and whatever the number of threads.
fn step_group(
    path: KernelPath,
    params: &mut [f32],
    grads: &[f32],
    m: &mut [f32],
    v: &mut [f32],
    s: Scalars,
) {
    let threads = kernels::threads_now();
    if path == KernelPath::Portable || threads < 2 || params.len() < MIN_SHARED {
        return step_chunk(path, params, grads, m, v, s);
    }
    let n = params.len();
    let (p, m, v) = (
        SharedMut(params.as_mut_ptr()),
        SharedMut(m.as_mut_ptr()),
        SharedMut(v.as_mut_ptr()),
    );
    dualrep_kernels::team::run(threads, &|part| {
        let range = part.share(n, 16);
        // SAFETY: members take disjoint ranges of the three buffers, borrowed mutably by this
        // call until every member is done.
        let slice = |x: &SharedMut| unsafe {
            std::slice::from_raw_parts_mut(x.0.add(range.start), range.len())
        };
        step_chunk(
            path,
            slice(&p),
            &grads[range.clone()],
            slice(&m),
            slice(&v),
            s,
        );
    });
}

/// A mutable buffer shared by a team whose members each touch their own part.
struct SharedMut(*mut f32);
// SAFETY: see the one use, in `step_group`.
unsafe impl Sync for SharedMut {}

fn step_chunk(
    path: KernelPath,
    p: &mut [f32],
    g: &[f32],
    m: &mut [f32],
    v: &mut [f32],
    s: Scalars,
) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a path is only ever current on a CPU that runs it.
    unsafe {
        match path {
            KernelPath::Avx512 => return step_avx512(p, g, m, v, s),
            KernelPath::Avx2 => return step_avx2(p, g, m, v, s),
            KernelPath::Portable => {}
        }
    }
    step_elements(p, g, m, v, s);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn step_avx512(p: &mut [f32], g: &[f32], m: &mut [f32], v: &mut [f32], s: Scalars) {
    step_elements(p, g, m, v, s);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn step_avx2(p: &mut [f32], g: &[f32], m: &mut [f32], v: &mut [f32], s: Scalars) {
    step_elements(p, g, m, v, s);
}

/// `torch.optim.adam._single_tensor_adam`'s arithmetic, element by element (no operation here
/// may fuse into an FMA: Rust never contracts `a * b + c`).
#[inline(always)]
fn step_elements(params: &mut [f32], grads: &[f32], m: &mut [f32], v: &mut [f32], s: Scalars) {
    for (((p, &g), m), v) in params
        .iter_mut()
        .zip(grads)
        .zip(m.iter_mut())
        .zip(v.iter_mut())
    {
        // torch.lerp with weight < 0.5 is `start + weight * (end - start)`.
        *m += s.one_minus_beta1 * (g - *m);
        *v = *v * s.beta2 + s.one_minus_beta2 * g * g;
        let denom = v.sqrt() / s.bias_correction2_sqrt + s.eps;
        *p += -s.step_size * (*m / denom);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_path_and_thread_count_steps_to_the_same_bits() {
        let n = 100_003;
        let grads: Vec<f32> = (0..n).map(|i| ((i as f32) * 0.77).sin() * 1e-2).collect();
        let mut results = Vec::new();
        kernels::on_every_path(|path| {
            for threads in [1, 2] {
                let mut params: Vec<f32> = (0..n).map(|i| (i as f32 * 0.1).cos()).collect();
                let mut adam = Adam::new(AdamConfig::with_lr(0.01), &[n]);
                kernels::with_threads(threads, || {
                    for _ in 0..3 {
                        adam.step([(&mut params[..], &grads[..])]);
                    }
                });
                let bits: Vec<u32> = params.iter().map(|x| x.to_bits()).collect();
                results.push((path, threads, bits));
            }
        });
        for (path, threads, bits) in &results {
            assert!(*bits == results[0].2, "{path} on {threads} threads");
        }
    }

    #[test]
    fn first_step_moves_each_parameter_by_lr_against_its_gradient_sign() {
        // After one step m / sqrt(v) is g / |g| once bias-corrected, so |delta| = lr (up to eps).
        let mut adam = Adam::new(AdamConfig::with_lr(0.01), &[3, 1]);
        let (mut a, mut b) = ([1.0f32, 1.0, 1.0], [5.0f32]);
        adam.step([
            (&mut a[..], &[2.0f32, -1e-3, 0.0][..]),
            (&mut b[..], &[-40.0f32][..]),
        ]);
        assert!((a[0] - 0.99).abs() < 1e-6, "{a:?}");
        assert!((a[1] - 1.01).abs() < 1e-6, "{a:?}");
        assert_eq!(a[2], 1.0, "zero gradient, no move");
        assert!((b[0] - 5.01).abs() < 1e-6, "{b:?}");
        assert_eq!(adam.steps(), 1);
    }

    #[test]
    #[should_panic(expected = "expected 2")]
    fn a_missing_group_is_an_error() {
        let mut adam = Adam::new(AdamConfig::default(), &[1, 1]);
        let mut p = [0.0f32];
        adam.step([(&mut p[..], &[1.0f32][..])]);
    }
}
