//! The buffers of one forward and backward pass at a fixed batch size.

use nalgebra::DMatrix;

use super::layer_norm::NormCache;
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
/// - `norms[l]`, for a network with layer norms ([`crate::rl::Mlp::with_layer_norm`]), what hidden
///   layer `l + 1`'s norm keeps for its backward pass; empty otherwise.
///
/// A workspace fits any network of its shape: SAC's twin critics can share one, as long as each
/// critic's backward pass runs before the other's forward pass overwrites the activations. One
/// made for a network with layer norms also fits the same shape without them.
#[derive(Clone, Debug)]
pub struct MlpWorkspace {
    batch: usize,
    sizes: Vec<usize>,
    pub(super) activations: Vec<DMatrix<f32>>,
    pub(super) grads: Vec<DMatrix<f32>>,
    pub(super) norms: Vec<NormCache>,
}

impl MlpWorkspace {
    pub(super) fn new(layers: &[Linear], batch: usize, layer_norm: bool) -> Self {
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
        let last = sizes.len() - 1;
        let norms = match layer_norm {
            true => sizes[1..last]
                .iter()
                .map(|&n| NormCache::new(n, batch))
                .collect(),
            false => Vec::new(),
        };
        Self {
            batch,
            activations: buffers(),
            grads: buffers(),
            norms,
            sizes,
        }
    }

    /// Panics unless this workspace was made for a network with these layers (and layer norms,
    /// if `layer_norm`).
    pub(super) fn check_shape(&self, layers: &[Linear], layer_norm: bool) {
        assert!(
            !layer_norm || !self.norms.is_empty(),
            "a workspace without layer norms used with a network that has them"
        );
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

    /// Copy what an input-gradient pass reads, the hidden ReLU outputs, what their layer norms
    /// kept (for a network with them, `layer_norm`), and dL/d output, of the samples `columns`
    /// of `from` into this workspace's first `columns.len()` columns.
    pub(super) fn gather_for_input_grad(
        &mut self,
        from: &MlpWorkspace,
        columns: &[usize],
        layer_norm: bool,
    ) {
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
            gather_columns(to.as_mut_slice(), from.as_slice(), n, columns);
        }
        // A workspace with norms may serve a network without them (SAC's twins share one):
        // what a plain network never wrote is not copied.
        if layer_norm {
            assert!(
                !self.norms.is_empty() && !from.norms.is_empty(),
                "gathering layer norms from or into a workspace without them"
            );
            for ((to, from), &n) in self.norms.iter_mut().zip(&from.norms).zip(&self.sizes[1..]) {
                gather_columns(&mut to.normalized, &from.normalized, n, columns);
                gather_columns(&mut to.inv_std, &from.inv_std, 1, columns);
            }
        }
    }
}

/// Column `columns[c]` of `from` into column `c` of `to`, both column-major with `n` rows.
fn gather_columns(to: &mut [f32], from: &[f32], n: usize, columns: &[usize]) {
    for (c, &j) in columns.iter().enumerate() {
        to[c * n..(c + 1) * n].copy_from_slice(&from[j * n..(j + 1) * n]);
    }
}
