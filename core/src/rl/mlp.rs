//! A multi-layer perceptron: `Linear` layers with ReLU between them (optionally a layer norm
//! before each ReLU) and a linear output, its forward pass, its hand-written backward pass, and
//! the parameter plumbing (flat slices, Polyak averaging, names for checkpoints).
//!
//! # Layout
//!
//! Every tensor has the bytes of its PyTorch counterpart:
//!
//! - a batch of activations, PyTorch's row-major `(batch, n)`, is a column-major `n x batch`
//!   [`DMatrix`]: one column per sample, each sample contiguous (what a replay buffer copies in);
//! - a weight, PyTorch's row-major `(n_out, n_in)`, is stored flat; read column-major it is
//!   `W^T`, an `n_in x n_out` matrix.
//!
//! Whatever the layout, each layer's three products contract different pairs of dimensions:
//! forward `z = W x + b`, input gradient `dx = W^T dz`, weight gradient `dW^T += x dz^T`.
//! `rl::kernels` computes them, on the portable path (matrixmultiply) or our own kernels.

use rand::Rng;

use super::kernels::{self, DenseLayer};
use super::layer_norm::{self, LayerNorm};
use super::linear::Linear;
use super::workspace::MlpWorkspace;

/// One named parameter tensor, in PyTorch's `state_dict` order and shape, for checkpoints.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamTensor<'a> {
    /// `layers.{l}.weight` or `layers.{l}.bias`; prefix it with the network's name (`q1.`).
    pub name: String,
    /// `[n_out, n_in]` for a weight, `[n_out]` for a bias.
    pub shape: Vec<usize>,
    /// Row-major values.
    pub data: &'a [f32],
}

/// `n_in -> hidden[0] -> ... -> n_out`, ReLU after every hidden layer, linear output; with
/// [`Mlp::with_layer_norm`], `relu(LayerNorm(z))` after every hidden layer (PyTorch's
/// `Linear -> LayerNorm -> ReLU`).
///
/// All parameters live in one flat vector (and their gradients in a second one of the same
/// layout) so that Adam, Polyak averaging and copying are single loops over one slice, and a
/// checkpoint is a list of sub-slices ([`Mlp::named_parameters`]). Activations live outside, in an
/// [`MlpWorkspace`] sized for one batch, so one network can be evaluated at several batches
/// (SAC's critic at `(s, a)` and at `(s, pi(s))`) while each keeps what its backward pass needs.
///
/// Gradients accumulate, as in PyTorch: call [`Mlp::zero_grad`] before each backward pass whose
/// result should stand alone.
#[derive(Clone, Debug, PartialEq)]
pub struct Mlp {
    layers: Vec<Linear>,
    /// One per hidden layer, or none; their parameters follow every layer's in `params`.
    norms: Vec<LayerNorm>,
    params: Vec<f32>,
    grads: Vec<f32>,
}

impl Mlp {
    /// PyTorch's default initialisation of `nn.Linear`: `kaiming_uniform_(a = sqrt(5))` for the
    /// weight, which is `U(-1/sqrt(n_in), 1/sqrt(n_in))`, and the same bound for the bias.
    /// Draws each layer's weight (row-major) then its bias, in layer order.
    pub fn new<R: Rng + ?Sized>(n_in: usize, hidden: &[usize], n_out: usize, rng: &mut R) -> Self {
        let mut mlp = Self::zeros(n_in, hidden, n_out);
        for layer in &mlp.layers {
            let bound = 1.0 / (layer.n_in as f32).sqrt();
            for p in &mut mlp.params[layer.offset..layer.offset + layer.len()] {
                *p = rng.random_range(-bound..bound);
            }
        }
        mlp
    }

    /// A network whose parameters are all zero (to be overwritten, e.g. from a checkpoint).
    pub fn zeros(n_in: usize, hidden: &[usize], n_out: usize) -> Self {
        let sizes: Vec<usize> = std::iter::once(n_in)
            .chain(hidden.iter().copied())
            .chain(std::iter::once(n_out))
            .collect();
        assert!(
            sizes.iter().all(|&n| n > 0),
            "layer sizes must be positive: {sizes:?}"
        );
        let mut offset = 0;
        let layers: Vec<Linear> = sizes
            .windows(2)
            .map(|pair| {
                let layer = Linear {
                    n_in: pair[0],
                    n_out: pair[1],
                    offset,
                };
                offset += layer.len();
                layer
            })
            .collect();
        Self {
            layers,
            norms: Vec::new(),
            params: vec![0.0; offset],
            grads: vec![0.0; offset],
        }
    }

    /// The same network with a layer norm before each hidden ReLU, PyTorch's initialisation
    /// (gain 1, bias 0): its parameters go after every layer's, as a module's `layers` then
    /// `norms` lists give them, so the layers keep their offsets and a generator draws the same
    /// layers with or without. No-op on a network that has them already.
    pub fn with_layer_norm(mut self) -> Self {
        if !self.norms.is_empty() {
            return self;
        }
        let last = self.layers.len() - 1;
        for layer in &self.layers[..last] {
            let norm = LayerNorm {
                n: layer.n_out,
                offset: self.params.len(),
            };
            self.params.extend(std::iter::repeat_n(1.0, norm.n));
            self.params.extend(std::iter::repeat_n(0.0, norm.n));
            self.norms.push(norm);
        }
        self.grads = vec![0.0; self.params.len()];
        self
    }

    /// Whether each hidden layer is normalised before its ReLU.
    pub fn has_layer_norm(&self) -> bool {
        !self.norms.is_empty()
    }

    pub fn n_in(&self) -> usize {
        self.layers[0].n_in
    }

    pub fn n_out(&self) -> usize {
        self.layers[self.layers.len() - 1].n_out
    }

    pub fn layers(&self) -> &[Linear] {
        &self.layers
    }

    /// A workspace for batches of `batch` samples (allocates; keep it across updates).
    pub fn workspace(&self, batch: usize) -> MlpWorkspace {
        MlpWorkspace::new(&self.layers, batch, self.has_layer_norm())
    }

    /// All parameters, flat, in PyTorch's `parameters()` order.
    pub fn params(&self) -> &[f32] {
        &self.params
    }

    pub fn params_mut(&mut self) -> &mut [f32] {
        &mut self.params
    }

    /// Accumulated gradients, same layout as [`Mlp::params`].
    pub fn grads(&self) -> &[f32] {
        &self.grads
    }

    pub fn grads_mut(&mut self) -> &mut [f32] {
        &mut self.grads
    }

    /// Parameters to update with their gradients: the pair [`crate::rl::Adam::step`] takes.
    pub fn params_and_grads(&mut self) -> (&mut [f32], &[f32]) {
        (&mut self.params, &self.grads)
    }

    pub fn zero_grad(&mut self) {
        self.grads.fill(0.0);
    }

    /// `self = online` (parameters only), e.g. to initialise a target network.
    pub fn copy_params_from(&mut self, online: &Mlp) {
        assert!(
            self.layers == online.layers && self.norms == online.norms,
            "copy between networks of different shapes"
        );
        self.params.copy_from_slice(&online.params);
    }

    /// Polyak averaging `self = (1 - tau) self + tau online`, written as stable-baselines3's
    /// `polyak_update` (`mul_(1 - tau)` then `add_(online, alpha = tau)`).
    pub fn soft_update_from(&mut self, online: &Mlp, tau: f32) {
        assert!(
            self.layers == online.layers && self.norms == online.norms,
            "Polyak update between networks of different shapes"
        );
        for (target, &param) in self.params.iter_mut().zip(&online.params) {
            *target = *target * (1.0 - tau) + tau * param;
        }
    }

    /// Parameter tensors with PyTorch names (`layers.0.weight`, `layers.0.bias`, ...), as a
    /// `ModuleList` of `nn.Linear` called `layers` would name them, then the layer norms'
    /// (`norms.0.weight`, `norms.0.bias`, ...) as a second `ModuleList` called `norms` would.
    pub fn named_parameters(&self) -> impl Iterator<Item = ParamTensor<'_>> {
        let layers = self.layers.iter().enumerate().flat_map(move |(l, layer)| {
            [
                ParamTensor {
                    name: format!("layers.{l}.weight"),
                    shape: vec![layer.n_out, layer.n_in],
                    data: layer.weight(&self.params),
                },
                ParamTensor {
                    name: format!("layers.{l}.bias"),
                    shape: vec![layer.n_out],
                    data: layer.bias(&self.params),
                },
            ]
        });
        let norms = self.norms.iter().enumerate().flat_map(move |(l, norm)| {
            [
                ParamTensor {
                    name: format!("norms.{l}.weight"),
                    shape: vec![norm.n],
                    data: &self.params[norm.gain_range()],
                },
                ParamTensor {
                    name: format!("norms.{l}.bias"),
                    shape: vec![norm.n],
                    data: &self.params[norm.bias_range()],
                },
            ]
        });
        layers.chain(norms)
    }

    /// Forward pass of the batch in `ws.input_mut()`; the result is `ws.output()`. Keeps every
    /// hidden activation in `ws` for the backward pass. Allocates nothing of its own (on the
    /// portable path each product does, inside `sgemm`: see the module map of `rl`).
    pub fn forward(&self, ws: &mut MlpWorkspace) {
        ws.check_shape(&self.layers, self.has_layer_norm());
        let last = self.layers.len() - 1;
        for (l, layer) in self.layers.iter().enumerate() {
            let (before, after) = ws.activations.split_at_mut(l + 1);
            let d = DenseLayer {
                layer,
                params: &self.params,
            };
            let norm = self.norms.get(l);
            kernels::forward_layer(d, &before[l], &mut after[0], l < last && norm.is_none());
            if let Some(norm) = norm {
                layer_norm::forward_relu(
                    norm,
                    &self.params,
                    after[0].as_mut_slice(),
                    &mut ws.norms[l],
                );
            }
        }
    }

    /// Backward pass from `ws.output_grad_mut()` (dL/d output, written by the caller after
    /// [`Mlp::forward`]): accumulates dL/d parameters into [`Mlp::grads`]. Does not compute the
    /// input gradient (that saves the first layer's third product).
    pub fn backward(&mut self, ws: &mut MlpWorkspace) {
        let grads = Some(&mut self.grads[..]);
        backward(&self.layers, &self.norms, &self.params, grads, ws, false);
    }

    /// [`Mlp::backward`] plus dL/d input into `ws.input_grad()`.
    pub fn backward_with_input_grad(&mut self, ws: &mut MlpWorkspace) {
        let grads = Some(&mut self.grads[..]);
        backward(&self.layers, &self.norms, &self.params, grads, ws, true);
    }

    /// dL/d input into `ws.input_grad()` only, the parameter gradients untouched: a frozen
    /// network, such as SAC's critic inside the actor loss. Takes `&self`, so the borrow checker
    /// proves the critic unchanged.
    pub fn backward_input(&self, ws: &mut MlpWorkspace) {
        backward(&self.layers, &self.norms, &self.params, None, ws, true);
    }

    /// [`Mlp::backward_input`] of the samples `columns` of `ws` only (after a forward pass and
    /// with dL/d output written there), computed in `sub`: column `c` of `sub.input_grad()` is
    /// then dL/d input of sample `columns[c]`, the same bits as the whole batch's pass gives it.
    /// For a loss whose gradient reaches this network from some samples only (the twin a
    /// `min` picks), this skips the rest, whose input gradient is exactly zero.
    pub fn backward_input_columns(
        &self,
        ws: &MlpWorkspace,
        columns: &[usize],
        sub: &mut MlpWorkspace,
    ) {
        ws.check_shape(&self.layers, self.has_layer_norm());
        sub.gather_for_input_grad(ws, columns, self.has_layer_norm());
        let m = columns.len();
        for (l, layer) in self.layers.iter().enumerate().rev() {
            let (below, above) = sub.grads.split_at_mut(l + 1);
            if let Some(norm) = self.norms.get(l) {
                let dy = above[0].as_mut_slice();
                layer_norm::backward(norm, &self.params, None, dy, &sub.norms[l], m);
            }
            let dz = &above[0].as_slice()[..layer.n_out * m];
            let dx = &mut below[l].as_mut_slice()[..layer.n_in * m];
            let relu_output = (l > 0).then(|| &sub.activations[l].as_slice()[..layer.n_in * m]);
            let d = DenseLayer {
                layer,
                params: &self.params,
            };
            kernels::input_grad_columns(d, m, dz, dx, relu_output);
        }
    }
}

/// Layer by layer from the output: `ws.grads[l + 1]` holds dL/dz of layer `l` (for a hidden layer,
/// dL/dh already masked by the ReLU derivative, and taken back through the layer norm first if
/// there is one), from which come `dW^T += x dz^T`, `db += sum over the batch of dz`, and
/// `dx = W^T dz`.
fn backward(
    layers: &[Linear],
    norms: &[LayerNorm],
    params: &[f32],
    mut param_grads: Option<&mut [f32]>,
    ws: &mut MlpWorkspace,
    input_grad: bool,
) {
    ws.check_shape(layers, !norms.is_empty());
    let batch = ws.batch();
    for (l, layer) in layers.iter().enumerate().rev() {
        let (below, above) = ws.grads.split_at_mut(l + 1);
        if let Some(norm) = norms.get(l) {
            let dy = above[0].as_mut_slice();
            let grads = param_grads.as_deref_mut();
            layer_norm::backward(norm, params, grads, dy, &ws.norms[l], batch);
        }
        let dz = &above[0];
        if let Some(grads) = param_grads.as_deref_mut() {
            kernels::weight_grad(layer, grads, &ws.activations[l], dz);
        }
        if l == 0 && !input_grad {
            continue;
        }
        // Through the ReLU that produced x (h = max(z, 0), so dh/dz = [h > 0]) below the output.
        let relu_output = (l > 0).then(|| &ws.activations[l]);
        kernels::input_grad(DenseLayer { layer, params }, dz, &mut below[l], relu_output);
    }
}

#[cfg(test)]
mod tests;
