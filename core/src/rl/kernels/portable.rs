//! The portable path: each layer's products through matrixmultiply's `sgemm`, bias, ReLU and
//! masks in plain loops, exactly as every run before the fast kernels computed them (same
//! operations, same order, same bits).
//!
//! `gemm` is `c = alpha a b + beta c` on nalgebra matrices and views of any strides, always
//! through matrixmultiply's `sgemm`. Why not nalgebra's own `gemm`: it calls the same `sgemm`
//! only when every dimension exceeds 5; below that it loops over `axcpy`, which in nalgebra
//! 0.35.0 reads and writes out of bounds when its left operand is a view whose row stride is
//! not 1 (dimforge/nalgebra#1616, open). Our transposed operands are exactly such views, and a
//! critic's scalar output layer is below the threshold. `sgemm` takes arbitrary strides at
//! every size, so one path serves all.
//!
//! Each product is one `sgemm` call, which packs any strides into its own panels:
//!
//! | product | formula | operands |
//! |---|---|---|
//! | forward | `z = W x + b` | `W`: the weight buffer viewed with strides `(n_in, 1)` |
//! | input gradient | `dx = W^T dz` | `W^T`: the weight buffer as stored |
//! | weight gradient | `dW^T += x dz^T` | `dz^T`: the gradient buffer viewed with strides `(n_out, 1)` |

use nalgebra::{DMatrix, DMatrixView, DMatrixViewMut, Dim, Matrix, RawStorage, RawStorageMut};

use crate::rl::linear::Linear;

/// `z = W x + b`, then ReLU if `relu`.
pub(super) fn forward(
    layer: &Linear,
    params: &[f32],
    x: &DMatrix<f32>,
    z: &mut DMatrix<f32>,
    relu: bool,
) {
    gemm(1.0, &layer.w(params), x, 0.0, z);
    let b = layer.bias(params);
    for column in z.as_mut_slice().chunks_exact_mut(layer.n_out) {
        for (v, &b_i) in column.iter_mut().zip(b) {
            *v += b_i;
            // `< 0` rather than `max(0)`: a NaN passes through, as in torch.relu.
            if relu && *v < 0.0 {
                *v = 0.0;
            }
        }
    }
}

/// `dW^T += x dz^T`, `db += ` the sum of `dz` over the batch.
pub(super) fn weight_grad(layer: &Linear, grads: &mut [f32], x: &DMatrix<f32>, dz: &DMatrix<f32>) {
    let batch = x.ncols();
    // dz^T (batch x n_out): the column-major dz buffer read with swapped strides.
    let dz_t =
        DMatrixView::from_slice_with_strides(dz.as_slice(), batch, layer.n_out, layer.n_out, 1);
    let mut dw_t =
        DMatrixViewMut::from_slice(&mut grads[layer.weight_range()], layer.n_in, layer.n_out);
    gemm(1.0, x, &dz_t, 1.0, &mut dw_t);
    let db = &mut grads[layer.bias_range()];
    for column in dz.as_slice().chunks_exact(layer.n_out) {
        for (g, &d) in db.iter_mut().zip(column) {
            *g += d;
        }
    }
}

/// `dx = W^T dz` on `batch` columns (column-major slices), then through the ReLU that produced
/// `h` (`dh/dz = [h > 0]`), if given.
pub(super) fn input_grad(
    layer: &Linear,
    params: &[f32],
    batch: usize,
    dz: &[f32],
    dx: &mut [f32],
    h: Option<&[f32]>,
) {
    let dz = DMatrixView::from_slice(dz, layer.n_out, batch);
    gemm(
        1.0,
        &layer.w_t(params),
        &dz,
        0.0,
        &mut DMatrixViewMut::from_slice(dx, layer.n_in, batch),
    );
    if let Some(h) = h {
        for (g, &h) in dx.iter_mut().zip(h) {
            // A select with an unconditional store, not a conditional store: it vectorises
            // (the branchy form cost a fifth of a Lunar Lander update).
            *g = if h <= 0.0 { 0.0 } else { *g };
        }
    }
}

/// `c = alpha a b + beta c` (if `beta` is 0, `c` is only written). Panics on mismatched shapes.
///
/// matrixmultiply allocates (and frees) a packing buffer inside every call: the one heap
/// allocation of a training step that is not ours to remove.
pub(crate) fn gemm<R1, C1, S1, R2, C2, S2, R3, C3, S3>(
    alpha: f32,
    a: &Matrix<f32, R1, C1, S1>,
    b: &Matrix<f32, R2, C2, S2>,
    beta: f32,
    c: &mut Matrix<f32, R3, C3, S3>,
) where
    R1: Dim,
    C1: Dim,
    S1: RawStorage<f32, R1, C1>,
    R2: Dim,
    C2: Dim,
    S2: RawStorage<f32, R2, C2>,
    R3: Dim,
    C3: Dim,
    S3: RawStorageMut<f32, R3, C3>,
{
    let (m, k) = a.shape();
    let (k_b, n) = b.shape();
    assert_eq!(k, k_b, "gemm: a is {m}x{k}, b is {k_b}x{n}");
    assert_eq!(
        c.shape(),
        (m, n),
        "gemm: a b is {m}x{n}, c is {:?}",
        c.shape()
    );
    let (rsa, csa) = a.strides();
    let (rsb, csb) = b.strides();
    let (rsc, csc) = c.strides();
    // SAFETY: a nalgebra matrix or view is valid for reads of its shape at its strides (views
    // check their buffer when built), and a mutable one for writes without self-overlap; `c` is
    // borrowed mutably, so it aliases neither `a` nor `b`; the shapes agree (asserted above).
    unsafe {
        matrixmultiply::sgemm(
            m,
            k,
            n,
            alpha,
            a.as_ptr(),
            rsa as isize,
            csa as isize,
            b.as_ptr(),
            rsb as isize,
            csb as isize,
            beta,
            c.as_mut_ptr(),
            rsc as isize,
            csc as isize,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DMatrixView, Dyn};

    #[test]
    fn transposed_views_of_every_size_multiply_like_nalgebra_operators() {
        // Sizes on both sides of nalgebra's own threshold (5), with `a` read transposed.
        for (m, k, n) in [(1, 3, 4), (2, 2, 2), (6, 7, 9), (1, 64, 17), (40, 3, 1)] {
            let a_t = DMatrix::from_fn(k, m, |i, j| (i as f32 * 0.3 - j as f32 * 0.7).sin());
            let a =
                DMatrixView::<f32, Dyn, Dyn>::from_slice_with_strides(a_t.as_slice(), m, k, k, 1);
            let b = DMatrix::from_fn(k, n, |i, j| (i as f32 + 2.0 * j as f32).cos());
            let mut c = DMatrix::from_element(m, n, 1.0f32);
            gemm(2.0, &a, &b, 0.5, &mut c);
            let want = a_t.transpose() * &b * 2.0 + DMatrix::from_element(m, n, 0.5f32);
            assert!((c - want).amax() < 1e-5, "{m}x{k}x{n}");
        }
    }
}
