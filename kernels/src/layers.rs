//! A layer's three products as jobs for the thread team, each member computing its own output
//! elements (so the results do not depend on how many members there are):
//!
//! | job | product | `A` | `B` |
//! |---|---|---|---|
//! | forward | `Z = W X`, then `+ b`, ReLU | `W` packed into row tiles | `X`, down its columns |
//! | weight gradient | `dW^T += X dZ^T`, `db += dZ 1` | `X` as stored | `dZ^T`, along its rows |
//! | input gradient | `dX = W^T dZ`, masked by the ReLU | the weight as stored (`W^T`) | `dZ`, down its columns |
//!
//! Activations are column-major `n x batch` and weights row-major `n_out x n_in` (see
//! `rl::mlp`): `A` is packed in every case (`gemm.rs`), which for the forward pass gathers
//! `W`'s rows into columns. A layer with at most four outputs, or a batch of at most four, is
//! a handful of dot products instead (`dot.rs`).

use crate::dot::dot_forward;
use crate::gemm::{ASource, Product, product};
use crate::isa::Isa;
use crate::team::Part;
use crate::tile::Epilogue;

/// `Z = W X + b` (ReLU if `relu`) for `W` row-major `n_out x n_in` and `X`, `Z` column-major.
pub(crate) struct ForwardJob<'a> {
    pub n_in: usize,
    pub n_out: usize,
    pub batch: usize,
    pub w: &'a [f32],
    pub b: &'a [f32],
    pub x: &'a [f32],
    pub z: *mut f32,
    pub relu: bool,
    /// Room for the packed `W`: `gemm::packed_len(n_out, n_in)` floats.
    pub pack: *mut f32,
}

/// `dW^T += X dZ^T` and `db += ` the row sums of `dZ`.
pub(crate) struct BackwardJob<'a> {
    pub n_in: usize,
    pub n_out: usize,
    pub batch: usize,
    pub x: &'a [f32],
    pub dz: &'a [f32],
    pub dw: *mut f32,
    pub db: *mut f32,
    /// Room for the packed `X`: `gemm::packed_len(n_in, batch)` floats.
    pub pack: *mut f32,
}

/// `dX = W^T dZ`, then zero where `h <= 0` if `h` is given.
pub(crate) struct InputGradJob<'a> {
    pub n_in: usize,
    pub n_out: usize,
    pub batch: usize,
    pub w: &'a [f32],
    pub dz: &'a [f32],
    pub dx: *mut f32,
    pub h: Option<&'a [f32]>,
    /// Room for the packed `W^T`: `gemm::packed_len(n_in, n_out)` floats.
    pub pack: *mut f32,
}

// SAFETY: members write disjoint elements of the outputs behind the raw pointers (their own
// tiles of `Z`, `dW`, `db`, `dX`, their own row tiles of the pack), which the caller borrowed
// mutably for the job's duration; everything else is read-only.
unsafe impl Sync for ForwardJob<'_> {}
unsafe impl Sync for BackwardJob<'_> {}
unsafe impl Sync for InputGradJob<'_> {}

/// # Safety
/// The job's slices hold their shapes, its pointers are writable for them, and the caller is
/// compiled for `I`.
#[inline(always)]
pub(crate) unsafe fn forward_part<
    I: Isa,
    const MV: usize,
    const NR: usize,
    const NMV: usize,
    const WMV: usize,
    const WNR: usize,
>(
    part: &Part<'_>,
    job: &ForwardJob<'_>,
) {
    let (m, n, k) = (job.n_out, job.batch, job.n_in);
    if m <= 4 || n <= 4 {
        unsafe { dot_forward::<I>(part, job) };
        return;
    }
    let p = Product {
        m,
        n,
        k,
        a: ASource::Rows {
            ptr: job.w.as_ptr(),
            ld: k,
        },
        a_pack: job.pack,
        b: job.x.as_ptr(),
        b_ks: 1,
        b_js: k,
        b_cols: true,
        c: job.z,
        c_js: m,
        c_is: 1,
        epilogue: Epilogue::Bias {
            bias: job.b.as_ptr(),
            relu: job.relu,
        },
    };
    unsafe { product::<I, MV, NR, NMV, WMV, WNR>(part, &p) };
}

/// # Safety
/// As [`forward_part`].
#[inline(always)]
pub(crate) unsafe fn weight_grad_part<
    I: Isa,
    const MV: usize,
    const NR: usize,
    const NMV: usize,
    const WMV: usize,
    const WNR: usize,
>(
    part: &Part<'_>,
    job: &BackwardJob<'_>,
) {
    let (m, n, k) = (job.n_in, job.n_out, job.batch);
    // The bias gradient: each member sums its share of the outputs over the batch, in order.
    let outputs = part.share(n, 16);
    if !outputs.is_empty() {
        let db =
            unsafe { std::slice::from_raw_parts_mut(job.db.add(outputs.start), outputs.len()) };
        for column in job.dz.chunks_exact(n) {
            for (g, &d) in db.iter_mut().zip(&column[outputs.clone()]) {
                *g += d;
            }
        }
    }
    // With few inputs (a first layer), dW^T would be one short row tile per column: compute
    // dW = dZ X^T instead, with the same sums, and write it row-major.
    let p = if m <= I::LANES && n > m {
        Product {
            m: n,
            n: m,
            k,
            a: ASource::Columns {
                ptr: job.dz.as_ptr(),
                ld: n,
            },
            a_pack: job.pack,
            b: job.x.as_ptr(),
            b_ks: m,
            b_js: 1,
            b_cols: false,
            c: job.dw,
            c_js: 1,
            c_is: m,
            epilogue: Epilogue::Accumulate,
        }
    } else {
        Product {
            m,
            n,
            k,
            a: ASource::Columns {
                ptr: job.x.as_ptr(),
                ld: m,
            },
            a_pack: job.pack,
            b: job.dz.as_ptr(),
            b_ks: n,
            b_js: 1,
            b_cols: false,
            c: job.dw,
            c_js: m,
            c_is: 1,
            epilogue: Epilogue::Accumulate,
        }
    };
    unsafe { product::<I, MV, NR, NMV, WMV, WNR>(part, &p) };
}

/// # Safety
/// As [`forward_part`].
#[inline(always)]
pub(crate) unsafe fn input_grad_part<
    I: Isa,
    const MV: usize,
    const NR: usize,
    const NMV: usize,
    const WMV: usize,
    const WNR: usize,
>(
    part: &Part<'_>,
    job: &InputGradJob<'_>,
) {
    let (m, n, k) = (job.n_in, job.batch, job.n_out);
    let p = Product {
        m,
        n,
        k,
        a: ASource::Columns {
            ptr: job.w.as_ptr(),
            ld: m,
        },
        a_pack: job.pack,
        b: job.dz.as_ptr(),
        b_ks: 1,
        b_js: k,
        b_cols: true,
        c: job.dx,
        c_js: m,
        c_is: 1,
        epilogue: match job.h {
            Some(h) => Epilogue::Mask { h: h.as_ptr() },
            None => Epilogue::Store,
        },
    };
    unsafe { product::<I, MV, NR, NMV, WMV, WNR>(part, &p) };
}
