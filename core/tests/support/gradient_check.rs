//! What the networks' gradient tests share (`rl_gradients.rs`, `rl_layer_norm.rs`): the analytic
//! pass under test, central differences of an independent f64 evaluation, and the comparisons
//! against them and against PyTorch's printed values.

use dualrep_core::rl::{Mlp, MlpWorkspace, mse_loss};

/// Half-width of the central differences, on an f64 evaluation: small enough to cross a ReLU
/// kink only by bad luck, large enough for f64 rounding (1e-16 of the loss, divided by the step)
/// to stay near 1e-10.
pub const STEP: f64 = 1e-6;

/// zero_grad, forward, MSE against `target`, backward with the input gradient; returns the loss.
pub fn forward_backward(mlp: &mut Mlp, ws: &mut MlpWorkspace, target: &[f32]) -> f32 {
    mlp.zero_grad();
    mlp.forward(ws);
    let (out, grad) = ws.output_and_grad_mut();
    let loss = mse_loss(out.as_slice(), target, grad.as_mut_slice());
    mlp.backward_with_input_grad(ws);
    loss
}

/// [`forward_backward`], then (dL/dparams, dL/dinput).
pub fn analytic(mlp: &mut Mlp, ws: &mut MlpWorkspace, target: &[f32]) -> (Vec<f32>, Vec<f32>) {
    forward_backward(mlp, ws, target);
    (mlp.grads().to_vec(), ws.input_grad().as_slice().to_vec())
}

/// PyTorch's `nn.LayerNorm` eps.
const LAYER_NORM_EPS: f64 = 1e-5;

/// The MSE of `mlp` against `target` with its parameters and input replaced by `params` and
/// `input` (column-major `n_in x batch`), in f64 with plain loops over PyTorch's row-major
/// weights: a second, independent forward pass, precise enough that its central differences
/// measure only the f32 rounding of the analytic gradient. A layer-normed network's gains and
/// biases follow every layer's parameters; its variance is the biased one, as PyTorch's.
pub fn mse_f64(mlp: &Mlp, target: &[f32], params: &[f64], input: &[f64]) -> f64 {
    let layers = mlp.layers();
    let mut norm_at = layers.iter().map(|l| l.len()).sum::<usize>();
    let norms: Vec<usize> = match mlp.has_layer_norm() {
        false => Vec::new(),
        true => layers[..layers.len() - 1]
            .iter()
            .map(|l| {
                norm_at += 2 * l.n_out;
                norm_at - 2 * l.n_out
            })
            .collect(),
    };
    let mut sum = 0.0;
    for (sample, target) in input
        .chunks_exact(mlp.n_in())
        .zip(target.chunks_exact(mlp.n_out()))
    {
        let mut x = sample.to_vec();
        for (l, layer) in layers.iter().enumerate() {
            let (w, b) = (layer.offset, layer.offset + layer.n_out * layer.n_in);
            let z: Vec<f64> = (0..layer.n_out)
                .map(|o| {
                    let row = &params[w + o * layer.n_in..w + (o + 1) * layer.n_in];
                    params[b + o] + row.iter().zip(&x).map(|(w, x)| w * x).sum::<f64>()
                })
                .collect();
            let hidden = l + 1 < layers.len();
            x = match norms.get(l) {
                _ if !hidden => z,
                None => z.iter().map(|v| v.max(0.0)).collect(),
                Some(&at) => {
                    let n = z.len() as f64;
                    let mean = z.iter().sum::<f64>() / n;
                    let var = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
                    let inv = 1.0 / (var + LAYER_NORM_EPS).sqrt();
                    let (gain, bias) = (&params[at..], &params[at + z.len()..]);
                    let normed = z.iter().enumerate();
                    normed
                        .map(|(j, v)| (gain[j] * (v - mean) * inv + bias[j]).max(0.0))
                        .collect()
                }
            };
        }
        sum += x
            .iter()
            .zip(target)
            .map(|(o, &y)| (o - f64::from(y)).powi(2))
            .sum::<f64>();
    }
    sum / target.len() as f64
}

/// A frozen network's pass (`backward_input`) after [`analytic`] gives the bits of the input
/// gradient `analytic` gave, and leaves every parameter gradient at zero.
pub fn assert_frozen_pass_is_the_same(
    mlp: &mut Mlp,
    ws: &mut MlpWorkspace,
    target: &[f32],
    what: &str,
) {
    let (_, input_grad) = analytic(mlp, ws, target);
    mlp.zero_grad();
    // Same input, and the same output gradient as `analytic` left in the workspace.
    mlp.forward(ws);
    mlp.backward_input(ws);
    assert_eq!(ws.input_grad().as_slice(), &input_grad[..], "{what}");
    assert!(mlp.grads().iter().all(|&g| g == 0.0), "{what}");
}

/// Central differences of `loss(params, input)` at the network's parameters and the
/// workspace's input: (dL/dparams, dL/dinput).
pub fn central_differences(
    mlp: &Mlp,
    ws: &MlpWorkspace,
    loss: impl Fn(&[f64], &[f64]) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let params = mlp.params().iter().map(|&p| f64::from(p)).collect();
    let input = ws.input().iter().map(|&x| f64::from(x)).collect();
    let mut point: [Vec<f64>; 2] = [params, input];
    let mut derivative = [Vec::new(), Vec::new()];
    for which in 0..2 {
        for i in 0..point[which].len() {
            let original = point[which][i];
            point[which][i] = original + STEP;
            let plus = loss(&point[0], &point[1]);
            point[which][i] = original - STEP;
            let minus = loss(&point[0], &point[1]);
            point[which][i] = original;
            derivative[which].push((plus - minus) / (2.0 * STEP));
        }
    }
    let [d_params, d_input] = derivative;
    (d_params, d_input)
}

/// Largest |analytic - numeric| / max(|analytic|, |numeric|, 1e-4) over all coordinates;
/// panics past `tolerance`. The floor keeps gradients within f32 rounding of zero from
/// counting as large relative errors.
pub fn check(name: &str, analytic: &[f32], numeric: &[f64], tolerance: f64) -> f64 {
    assert_eq!(analytic.len(), numeric.len());
    let mut worst = 0.0f64;
    for (i, (&a, &n)) in analytic.iter().zip(numeric).enumerate() {
        let a = f64::from(a);
        let err = (a - n).abs() / a.abs().max(n.abs()).max(1e-4);
        assert!(
            err <= tolerance,
            "{name}[{i}]: analytic {a:e}, central difference {n:e}"
        );
        worst = worst.max(err);
    }
    assert!(
        numeric.iter().any(|&n| n.abs() > 1e-3),
        "{name}: all gradients near zero"
    );
    eprintln!(
        "{name}: {} coordinates, max relative error {worst:.2e}",
        analytic.len()
    );
    worst
}

/// Each value within `tolerance` of PyTorch's, relative (absolute below 1e-2); returns the worst.
pub fn assert_close(name: &str, got: &[f32], want: &[f32], tolerance: f32) -> f32 {
    assert_eq!(got.len(), want.len());
    let mut worst = 0.0f32;
    for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
        let err = (g - w).abs() / w.abs().max(1e-2);
        assert!(err <= tolerance, "{name}[{i}]: {g:e}, PyTorch {w:e}");
        worst = worst.max(err);
    }
    eprintln!("{name}: max deviation from PyTorch {worst:.2e} (relative, absolute below 1e-2)");
    worst
}

/// An input batch (column-major `n_in x batch`) and a target (`n_out x batch`) from the formulas
/// the gradient tests use: `2 sin(0.7 k + seed)` and `cos(0.3 k)`.
pub fn fill_problem(ws: &mut MlpWorkspace, n_out: usize, seed: u64) -> Vec<f32> {
    for (k, x) in ws.input_mut().iter_mut().enumerate() {
        *x = (0.7 * k as f32 + seed as f32).sin() * 2.0;
    }
    (0..n_out * ws.batch())
        .map(|k| (0.3 * k as f32).cos())
        .collect()
}
