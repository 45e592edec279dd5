//! The buffers of one forward and backward pass at a fixed batch size.

use nalgebra::DMatrix;

use super::linear::Linear;

/// Every activation and every activation gradient of one network shape at one batch size,
/// allocated once by [`crate::rl::Mlp::workspace`]. Forward, backward and Adam then allocate
/// nothing of their own: all products write into these buffers.
///
/// Matrices are column-major `n x batch`, one column per sample (the bytes of a PyTorch
/// `(batch, n)` tensor). With sizes `n_0 = n_in, n_1, ..., n_L = n_out`:
///
/// - `activations[0]` is the input, written by the caller through [`MlpWorkspace::input_mut`];
///   `activations[l]` for `0 < l < L` is the ReLU output of hidden layer `l`; `activations[L]`
///   is the linear output.
/// - `grads[l]` is dL/d `activations[l]`: the caller writes `grads[L]`
///   ([`MlpWorkspace::output_grad_mut`]); the backward pass overwrites the others, a hidden one
///   with the gradient already through its ReLU, and `grads[0]` only when the input gradient is
///   asked for.
///
/// A workspace fits any network of its shape: SAC's twin critics can share one, as long as each
/// critic's backward pass runs before the other's forward pass overwrites the activations.
#[derive(Clone, Debug)]
pub struct MlpWorkspace {
    batch: usize,
    sizes: Vec<usize>,
    pub(super) activations: Vec<DMatrix<f32>>,
    pub(super) grads: Vec<DMatrix<f32>>,
}

impl MlpWorkspace {
    pub(super) fn new(layers: &[Linear], batch: usize) -> Self {
        assert!(batch > 0, "empty batch");
        let sizes: Vec<usize> = std::iter::once(layers[0].n_in)
            .chain(layers.iter().map(|l| l.n_out))
            .collect();
        let buffers = || {
            sizes
                .iter()
                .map(|&n| DMatrix::zeros(n, batch))
                .collect::<Vec<_>>()
        };
        Self {
            batch,
            activations: buffers(),
            grads: buffers(),
            sizes,
        }
    }

    /// Panics unless this workspace was made for a network with these layers.
    pub(super) fn check_shape(&self, layers: &[Linear]) {
        let same = self.sizes.len() == layers.len() + 1
            && self.sizes[0] == layers[0].n_in
            && layers
                .iter()
                .zip(&self.sizes[1..])
                .all(|(layer, &n)| layer.n_out == n);
        assert!(
            same,
            "workspace of sizes {:?} used with layers {layers:?}",
            self.sizes
        );
    }

    pub fn batch(&self) -> usize {
        self.batch
    }

    /// The input batch, `n_in x batch`: write it here before [`crate::rl::Mlp::forward`].
    pub fn input_mut(&mut self) -> &mut DMatrix<f32> {
        &mut self.activations[0]
    }

    pub fn input(&self) -> &DMatrix<f32> {
        &self.activations[0]
    }

    /// The network's output, `n_out x batch`, after a forward pass.
    pub fn output(&self) -> &DMatrix<f32> {
        &self.activations[self.activations.len() - 1]
    }

    /// Layer `l`'s output (`l = 0` is the input, the last one is the output): for hidden layers,
    /// after the ReLU.
    pub fn activation(&self, l: usize) -> &DMatrix<f32> {
        &self.activations[l]
    }

    /// dL/d output, `n_out x batch`: write it before a backward pass.
    pub fn output_grad_mut(&mut self) -> &mut DMatrix<f32> {
        let last = self.grads.len() - 1;
        &mut self.grads[last]
    }

    /// The output and its gradient buffer together, for a loss that reads one and writes the
    /// other (see [`crate::rl::mse_loss`]).
    pub fn output_and_grad_mut(&mut self) -> (&DMatrix<f32>, &mut DMatrix<f32>) {
        let last = self.grads.len() - 1;
        (&self.activations[last], &mut self.grads[last])
    }

    /// dL/d input, `n_in x batch`, after a backward pass that asked for it.
    pub fn input_grad(&self) -> &DMatrix<f32> {
        &self.grads[0]
    }

    /// Copy what an input-gradient pass reads, the hidden ReLU outputs and dL/d output, of the
    /// samples `columns` of `from` into this workspace's first `columns.len()` columns.
    pub(super) fn gather_for_input_grad(&mut self, from: &MlpWorkspace, columns: &[usize]) {
        assert_eq!(self.sizes, from.sizes, "workspaces of different shapes");
        assert!(
            columns.len() <= self.batch,
            "more columns than this batch holds"
        );
        let last = self.sizes.len() - 1;
        let hidden = self.activations[1..last]
            .iter_mut()
            .zip(&from.activations[1..last]);
        let output_grad = std::iter::once((&mut self.grads[last], &from.grads[last]));
        for (to, from) in hidden.chain(output_grad) {
            let n = to.nrows();
            let (to, from) = (to.as_mut_slice(), from.as_slice());
            for (c, &j) in columns.iter().enumerate() {
                to[c * n..(c + 1) * n].copy_from_slice(&from[j * n..(j + 1) * n]);
            }
        }
    }
}
