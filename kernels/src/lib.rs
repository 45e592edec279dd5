//! # dualrep-kernels
//!
//! The fast path of dualrep's networks: a fully connected layer's three products (forward with
//! bias and ReLU, weight gradient with the bias gradient, input gradient through the ReLU) on
//! AVX-512 or AVX2 + FMA, chosen at run time, on one or more threads. A crate of its own so
//! that test builds optimise it like the other numeric crates (`Cargo.toml`), where the
//! kernels would otherwise run a hundred times slower.
//!
//! ## Layout
//!
//! - [`team`]: the calling thread plus parked helpers, sharing out one product.
//! - `layers.rs`: the three products as team jobs; `gemm.rs`: one member's share of a product
//!   (packing, cache blocking) around `tile.rs`, the one tile kernel; `dot.rs`: dot products
//!   for layers or batches of at most four.
//! - `isa.rs`: the vector operations everything is written in, implemented by `avx512.rs`
//!   and `avx2.rs`; `scratch.rs`: per-thread packing memory; `cache.rs`: the L2 size.
//! - [`fma_peak`]: the core's measured FMA peak.
//! - `examples/layer_rates.rs`: each product of Lunar Lander's critic timed alone, for tuning
//!   tile shapes without building the service.
//!
//! ## Numerics
//!
//! Every product element is one chain of fused multiply-adds over `k` in order, from 0, then
//! the epilogue (`+ b`, ReLU, mask, or `+` the old gradient); dot products sum 16 interleaved
//! partial sums in one fixed tree. No choice of tile, vector width, cache blocking or thread
//! count changes those operations, so [`Isa::Avx512`] and [`Isa::Avx2`] give the same bits on
//! any number of threads.
//!
//! Layouts: activations are column-major `n x batch` (one column per sample), weights
//! row-major `n_out x n_in` (PyTorch's), so a weight's bytes read column-major are `W^T`.

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
mod cache;
mod dot;
pub mod fma_peak;
mod gemm;
mod isa;
mod layers;
mod scratch;
pub mod team;
mod tile;

use layers::{BackwardJob, ForwardJob, InputGradJob};
use team::Part;

/// The instruction sets the kernels are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    /// AVX-512F: 16 lanes, 48 x 8 tiles.
    Avx512,
    /// AVX2 + FMA: 8 lanes, 16 x 6 tiles.
    Avx2,
}

impl Isa {
    /// Whether this CPU runs the set.
    pub fn is_available(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            let avx2 = std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma");
            match self {
                Isa::Avx2 => avx2,
                Isa::Avx512 => avx2 && std::arch::is_x86_feature_detected!("avx512f"),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }
}

fn check(isa: Isa) {
    assert!(
        isa.is_available(),
        "this CPU cannot run the {isa:?} kernels"
    );
}

/// Multiply-adds below which a product stays on the calling thread: handing out work costs
/// microseconds (more when a helper has to be woken), a product this small takes tens.
const MIN_MACS_TO_SHARE: usize = 4 << 20;

/// Threads for a product of `macs` multiply-adds when `threads` are allowed.
fn members(threads: usize, macs: usize) -> usize {
    if macs < MIN_MACS_TO_SHARE {
        1
    } else {
        threads.max(1)
    }
}

/// Run `part` of a job on `isa`; the per-set functions are compiled for their instructions.
macro_rules! on_isa {
    ($isa:expr, $part:ident, $job:ident, $f:ident) => {{
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `check` saw the CPU run `isa`; the caller asserted the shapes, and the
        // buffers behind the job's pointers are borrowed for the whole job.
        unsafe {
            match $isa {
                Isa::Avx512 => avx512::$f($part, $job),
                Isa::Avx2 => avx2::$f($part, $job),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = ($part, $job);
    }};
}

/// `z = W x + b`, then ReLU if `relu`: `w` row-major `n_out x n_in`, `x` column-major
/// `n_in x batch`, `z` column-major `n_out x batch`.
#[allow(clippy::too_many_arguments)]
pub fn forward(
    isa: Isa,
    threads: usize,
    (n_in, n_out, batch): (usize, usize, usize),
    w: &[f32],
    b: &[f32],
    x: &[f32],
    z: &mut [f32],
    relu: bool,
) {
    check(isa);
    assert!(n_in > 0 && n_out > 0 && batch > 0, "empty layer");
    assert!(
        w.len() == n_in * n_out && b.len() == n_out,
        "weight and bias"
    );
    assert!(
        x.len() == n_in * batch && z.len() == n_out * batch,
        "input and output"
    );
    let job = ForwardJob {
        n_in,
        n_out,
        batch,
        w,
        b,
        x,
        z: z.as_mut_ptr(),
        relu,
        pack: scratch::a_scratch(gemm::packed_len(n_out, n_in)),
    };
    let job = &job;
    let threads = members(threads, n_in * n_out * batch);
    team::run(threads, &|part: &Part<'_>| {
        on_isa!(isa, part, job, forward_part)
    });
}

/// `dW^T += x dz^T` and `db += ` the sum of `dz` over the batch: `x` column-major
/// `n_in x batch`, `dz` column-major `n_out x batch`, `dw` the row-major `n_out x n_in` weight
/// gradient, `db` the bias gradient.
#[allow(clippy::too_many_arguments)]
pub fn weight_grad(
    isa: Isa,
    threads: usize,
    (n_in, n_out, batch): (usize, usize, usize),
    x: &[f32],
    dz: &[f32],
    dw: &mut [f32],
    db: &mut [f32],
) {
    check(isa);
    assert!(n_in > 0 && n_out > 0 && batch > 0, "empty layer");
    assert!(
        x.len() == n_in * batch && dz.len() == n_out * batch,
        "input and output gradient"
    );
    assert!(
        dw.len() == n_in * n_out && db.len() == n_out,
        "weight and bias gradient"
    );
    let job = BackwardJob {
        n_in,
        n_out,
        batch,
        x,
        dz,
        dw: dw.as_mut_ptr(),
        db: db.as_mut_ptr(),
        pack: scratch::a_scratch(gemm::packed_len(n_in.max(n_out), batch)),
    };
    let job = &job;
    let threads = members(threads, n_in * n_out * batch);
    team::run(threads, &|part: &Part<'_>| {
        on_isa!(isa, part, job, weight_grad_part)
    });
}

/// `dx = W^T dz`, then zero where `h <= 0` if `h` (the ReLU output that was the layer's input,
/// laid out like `dx`) is given: `w` row-major `n_out x n_in`, `dz` column-major
/// `n_out x batch`, `dx` column-major `n_in x batch`.
#[allow(clippy::too_many_arguments)]
pub fn input_grad(
    isa: Isa,
    threads: usize,
    (n_in, n_out, batch): (usize, usize, usize),
    w: &[f32],
    dz: &[f32],
    dx: &mut [f32],
    h: Option<&[f32]>,
) {
    check(isa);
    assert!(n_in > 0 && n_out > 0 && batch > 0, "empty layer");
    assert!(
        w.len() == n_in * n_out && dz.len() == n_out * batch,
        "weight and output gradient"
    );
    assert!(dx.len() == n_in * batch, "input gradient");
    assert!(h.is_none_or(|h| h.len() == n_in * batch), "ReLU output");
    let job = InputGradJob {
        n_in,
        n_out,
        batch,
        w,
        dz,
        dx: dx.as_mut_ptr(),
        h,
        pack: scratch::a_scratch(gemm::packed_len(n_in, n_out)),
    };
    let job = &job;
    let threads = members(threads, n_in * n_out * batch);
    team::run(threads, &|part: &Part<'_>| {
        on_isa!(isa, part, job, input_grad_part)
    });
}
