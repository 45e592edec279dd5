//! A fully connected layer's three products, on the calling thread's kernel path and with
//! [`super::threads_now`] threads. Shapes: `x`, `z`, `dz`, `dx`, `h` are column-major
//! `n x batch` (one column per sample); the weight is row-major `n_out x n_in` in a network's
//! flat parameter (or gradient) vector at the layer's offset.

use nalgebra::DMatrix;

use super::{current_path, portable, threads_now};
use crate::rl::linear::Linear;

/// A layer and the parameter vector it lives in.
#[derive(Clone, Copy)]
pub struct DenseLayer<'a> {
    pub layer: &'a Linear,
    pub params: &'a [f32],
}

/// `z = W x + b`, then ReLU if `relu`.
pub fn forward_layer(d: DenseLayer<'_>, x: &DMatrix<f32>, z: &mut DMatrix<f32>, relu: bool) {
    let DenseLayer { layer, params } = d;
    assert_eq!(x.nrows(), layer.n_in, "layer input");
    assert_eq!(z.shape(), (layer.n_out, x.ncols()), "layer output");
    match current_path().isa() {
        None => portable::forward(layer, params, x, z, relu),
        Some(isa) => dualrep_kernels::forward(
            isa,
            threads_now(),
            (layer.n_in, layer.n_out, x.ncols()),
            layer.weight(params),
            layer.bias(params),
            x.as_slice(),
            z.as_mut_slice(),
            relu,
        ),
    }
}

/// `dW^T += x dz^T` and `db += ` the sum of `dz` over the batch, into the gradient vector
/// `grads` (laid out like the parameters).
pub fn weight_grad(layer: &Linear, grads: &mut [f32], x: &DMatrix<f32>, dz: &DMatrix<f32>) {
    assert_eq!(x.nrows(), layer.n_in, "layer input");
    assert_eq!(
        dz.shape(),
        (layer.n_out, x.ncols()),
        "layer output gradient"
    );
    assert!(grads.len() >= layer.offset + layer.len(), "gradient vector");
    match current_path().isa() {
        None => portable::weight_grad(layer, grads, x, dz),
        Some(isa) => {
            let (dw, db) = grads[layer.offset..layer.offset + layer.len()]
                .split_at_mut(layer.n_in * layer.n_out);
            dualrep_kernels::weight_grad(
                isa,
                threads_now(),
                (layer.n_in, layer.n_out, x.ncols()),
                x.as_slice(),
                dz.as_slice(),
                dw,
                db,
            );
        }
    }
}

/// `dx = W^T dz`, then zero where `h <= 0` if `h` (the ReLU output that was this layer's input)
/// is given.
pub fn input_grad(
    d: DenseLayer<'_>,
    dz: &DMatrix<f32>,
    dx: &mut DMatrix<f32>,
    h: Option<&DMatrix<f32>>,
) {
    // The column version checks every length against these shapes.
    input_grad_columns(
        d,
        dz.ncols(),
        dz.as_slice(),
        dx.as_mut_slice(),
        h.map(|h| h.as_slice()),
    );
}

/// [`input_grad`] on `batch` columns held in plain slices (column-major, `n x batch`), such as
/// the first columns of a workspace's buffers. Each output column depends on the same column of
/// `dz` (and `h`) only, on every path, so a column computes the same bits in a batch of any size.
pub(crate) fn input_grad_columns(
    d: DenseLayer<'_>,
    batch: usize,
    dz: &[f32],
    dx: &mut [f32],
    h: Option<&[f32]>,
) {
    let DenseLayer { layer, params } = d;
    assert_eq!(dz.len(), layer.n_out * batch, "layer output gradient");
    assert_eq!(dx.len(), layer.n_in * batch, "layer input gradient");
    assert!(h.is_none_or(|h| h.len() == dx.len()), "ReLU output");
    match current_path().isa() {
        None => portable::input_grad(layer, params, batch, dz, dx, h),
        Some(isa) => dualrep_kernels::input_grad(
            isa,
            threads_now(),
            (layer.n_in, layer.n_out, batch),
            layer.weight(params),
            dz,
            dx,
            h,
        ),
    }
}
