//! A forward pass as dot products, for layers with at most four outputs (the critics' and the
//! actor's heads) and batches of at most four (acting, the critics' estimates): a tile kernel
//! would spend most of its lanes on padding there.
//!
//! `z[o, s] = W[o, :] . X[:, s] + b[o]`: both vectors are contiguous. Each dot product sums 16
//! interleaved partial sums (lane `l` takes elements `l, l + 16, ...`, in order) and adds them
//! in [`Isa::group_sum`]'s fixed tree, so any vector width gives the same bits. Tiles of
//! `R x C` dot products share their loads.

use crate::isa::Isa;
use crate::layers::ForwardJob;
use crate::team::Part;

/// # Safety
/// As `layers::forward_part`.
#[inline(always)]
pub(crate) unsafe fn dot_forward<I: Isa>(part: &Part<'_>, job: &ForwardJob<'_>) {
    let (m, n) = (job.n_out, job.batch);
    // Many columns and few rows: whole columns per member; few columns: rows per member.
    if n >= m {
        let cols = part.share(n, 4);
        for s in cols.step_by(4) {
            let c = 4.min(n - s);
            let mut o = 0;
            while o < m {
                let r = 2.min(m - o);
                // A single row (a critic's output) on its own: a 2-row tile would compute it
                // twice.
                if r == 1 {
                    unsafe { dot_tile::<I, 1, 4>(job, o, r, s, c) };
                } else {
                    unsafe { dot_tile::<I, 2, 4>(job, o, r, s, c) };
                }
                o += 2;
            }
        }
    } else {
        let rows = part.share(m, 8);
        for o in rows.step_by(8) {
            let r = 8.min(m - o);
            for s in 0..n {
                unsafe { dot_tile::<I, 8, 1>(job, o, r, s, 1) };
            }
        }
    }
}

/// Outputs `o0..o0 + rows` of samples `s0..s0 + cols` (`rows <= R`, `cols <= C`; the missing
/// ones repeat the last valid row or column and are not stored).
#[inline(always)]
unsafe fn dot_tile<I: Isa, const R: usize, const C: usize>(
    job: &ForwardJob<'_>,
    o0: usize,
    rows: usize,
    s0: usize,
    cols: usize,
) {
    let k = job.n_in;
    let w = job.w.as_ptr();
    let x = job.x.as_ptr();
    let mut w_row = [w; R];
    for (r, p) in w_row.iter_mut().enumerate() {
        *p = unsafe { w.add((o0 + r.min(rows - 1)) * k) };
    }
    let mut x_col = [x; C];
    for (c, p) in x_col.iter_mut().enumerate() {
        *p = unsafe { x.add((s0 + c.min(cols - 1)) * k) };
    }
    let mut acc = [[unsafe { I::group_zero() }; C]; R];
    let mut kk = 0;
    while kk + 16 <= k {
        let mut xs = [unsafe { I::group_zero() }; C];
        for c in 0..C {
            xs[c] = unsafe { I::group_load(x_col[c].add(kk)) };
        }
        for r in 0..R {
            let wv = unsafe { I::group_load(w_row[r].add(kk)) };
            for c in 0..C {
                acc[r][c] = unsafe { I::group_fma(wv, xs[c], acc[r][c]) };
            }
        }
        kk += 16;
    }
    if kk < k {
        let tail = k - kk;
        let mut xs = [unsafe { I::group_zero() }; C];
        for c in 0..C {
            xs[c] = unsafe { I::group_load_first(x_col[c].add(kk), tail) };
        }
        for r in 0..R {
            let wv = unsafe { I::group_load_first(w_row[r].add(kk), tail) };
            for c in 0..C {
                acc[r][c] = unsafe { I::group_fma(wv, xs[c], acc[r][c]) };
            }
        }
    }
    let m = job.n_out;
    for (r, row) in acc.iter().enumerate().take(rows) {
        let o = o0 + r;
        for (c, &sum) in row.iter().enumerate().take(cols) {
            let mut z = unsafe { I::group_sum(sum) } + job.b[o];
            // `< 0` as in the portable path: NaN and -0.0 pass through.
            if job.relu && z < 0.0 {
                z = 0.0;
            }
            unsafe { *job.z.add(o + (s0 + c) * m) = z };
        }
    }
}
