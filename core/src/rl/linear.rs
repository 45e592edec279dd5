//! One fully connected layer as a window on a network's flat parameter vector.

use std::ops::Range;

use nalgebra::{DMatrixView, Dyn};

/// One fully connected layer `z = W x + b`: where its weight and bias live in the network's flat
/// parameter vector (weight first, row-major `(n_out, n_in)` as in PyTorch, then the bias).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Linear {
    pub n_in: usize,
    pub n_out: usize,
    /// Index of `W[0][0]` in the flat parameter (and gradient) vector.
    pub offset: usize,
}

impl Linear {
    /// Number of parameters: weight and bias.
    pub fn len(&self) -> usize {
        self.n_out * self.n_in + self.n_out
    }

    /// Always false: a layer has at least one output.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(super) fn weight_range(&self) -> Range<usize> {
        self.offset..self.offset + self.n_out * self.n_in
    }

    pub(super) fn bias_range(&self) -> Range<usize> {
        let start = self.offset + self.n_out * self.n_in;
        start..start + self.n_out
    }

    /// The weight, row-major `(n_out, n_in)`, out of a flat parameter or gradient vector.
    pub fn weight<'a>(&self, flat: &'a [f32]) -> &'a [f32] {
        &flat[self.weight_range()]
    }

    /// The bias, `n_out` values, out of a flat parameter or gradient vector.
    pub fn bias<'a>(&self, flat: &'a [f32]) -> &'a [f32] {
        &flat[self.bias_range()]
    }

    /// `W` (`n_out x n_in`) as a strided view of the row-major weight.
    pub(super) fn w<'a>(&self, flat: &'a [f32]) -> DMatrixView<'a, f32, Dyn, Dyn> {
        DMatrixView::from_slice_with_strides(self.weight(flat), self.n_out, self.n_in, self.n_in, 1)
    }

    /// `W^T` (`n_in x n_out`): the row-major weight read column-major.
    pub(super) fn w_t<'a>(&self, flat: &'a [f32]) -> DMatrixView<'a, f32> {
        DMatrixView::from_slice(self.weight(flat), self.n_in, self.n_out)
    }
}
