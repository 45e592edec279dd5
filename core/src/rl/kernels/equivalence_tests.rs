//! The fast kernels against the portable path (to f32 rounding), against each other (bit for
//! bit: AVX-512 and AVX2 give the same numbers) and against themselves on more threads (bit
//! for bit), on shapes that exercise every edge: tiles with short rows and columns, single
//! vectors, dot products, `k` below and above 16.

use nalgebra::DMatrix;

use crate::rl::kernels::{
    DenseLayer, KernelPath, forward_layer, input_grad, weight_grad, with_path, with_threads,
};
use crate::rl::linear::Linear;

fn fast_paths() -> Vec<KernelPath> {
    [KernelPath::Avx2, KernelPath::Avx512]
        .into_iter()
        .filter(|p| p.is_available())
        .collect()
}

fn values(n: usize, seed: f32) -> Vec<f32> {
    (0..n)
        .map(|i| ((i as f32 * 0.618 + seed) * 1.7).sin())
        .collect()
}

/// Everything one layer's three products give: z, dW and db (added to a non-zero start), dx.
fn layer_outputs(
    path: KernelPath,
    threads: usize,
    n_in: usize,
    n_out: usize,
    batch: usize,
) -> Vec<Vec<f32>> {
    let layer = Linear {
        n_in,
        n_out,
        offset: 3,
    };
    let params = values(3 + layer.len(), 0.1);
    let x = DMatrix::from_vec(n_in, batch, values(n_in * batch, 0.7));
    let dz = DMatrix::from_vec(n_out, batch, values(n_out * batch, 0.3));
    let h = DMatrix::from_vec(n_in, batch, values(n_in * batch, 0.9));
    with_path(path, || {
        with_threads(threads, || {
            let d = DenseLayer {
                layer: &layer,
                params: &params,
            };
            let mut z = DMatrix::from_element(n_out, batch, 9.0f32);
            forward_layer(d, &x, &mut z, true);
            let mut z_linear = DMatrix::from_element(n_out, batch, 9.0f32);
            forward_layer(d, &x, &mut z_linear, false);
            let mut grads = values(3 + layer.len(), 0.5);
            weight_grad(&layer, &mut grads, &x, &dz);
            let mut dx = DMatrix::from_element(n_in, batch, 9.0f32);
            input_grad(d, &dz, &mut dx, Some(&h));
            let mut dx_linear = DMatrix::from_element(n_in, batch, 9.0f32);
            input_grad(d, &dz, &mut dx_linear, None);
            vec![
                z.as_slice().to_vec(),
                z_linear.as_slice().to_vec(),
                grads,
                dx.as_slice().to_vec(),
                dx_linear.as_slice().to_vec(),
            ]
        })
    })
}

/// `(n_in, n_out, batch)`. The last three are large enough to be shared out over threads on
/// the dot-product and narrow paths.
const SHAPES: [(usize, usize, usize); 18] = [
    // A full row tile and a short one of two vectors (70 = 48 + 22 rows on AVX-512).
    (24, 70, 20),
    (10, 400, 64),
    (400, 300, 37),
    (300, 1, 50),
    (300, 4, 20),
    (8, 400, 1),
    (400, 300, 1),
    (300, 4, 3),
    (3, 5, 5),
    (17, 33, 13),
    // k of 19, 35 and 23: three steps before the first whole turn of an unrolled tile's loop.
    (19, 35, 23),
    (64, 64, 32),
    (1, 1, 1),
    (40, 17, 100),
    (400, 300, 64),
    (2000, 700, 3),
    (1000, 4, 1100),
    (4000, 1, 1100),
];

#[test]
fn fast_kernels_agree_with_the_portable_path() {
    for path in fast_paths() {
        for (n_in, n_out, batch) in SHAPES {
            let fast = layer_outputs(path, 1, n_in, n_out, batch);
            let portable = layer_outputs(KernelPath::Portable, 1, n_in, n_out, batch);
            for (which, (f, p)) in fast.iter().zip(&portable).enumerate() {
                for (i, (a, b)) in f.iter().zip(p).enumerate() {
                    let tolerance =
                        1e-5 * (1.0 + b.abs()) * (n_in.max(n_out).max(batch) as f32).sqrt();
                    assert!(
                        (a - b).abs() <= tolerance || (a.is_nan() && b.is_nan()),
                        "{path} ({n_in}, {n_out}, {batch}) output {which}[{i}]: {a} vs {b}"
                    );
                }
            }
        }
    }
}

fn bits(outputs: &[Vec<f32>]) -> Vec<Vec<u32>> {
    outputs
        .iter()
        .map(|v| v.iter().map(|x| x.to_bits()).collect())
        .collect()
}

#[test]
fn avx512_and_avx2_give_the_same_bits_on_any_number_of_threads() {
    let paths = fast_paths();
    for (n_in, n_out, batch) in SHAPES {
        let mut reference = None;
        for &path in &paths {
            for threads in [1, 2, 3] {
                let got = bits(&layer_outputs(path, threads, n_in, n_out, batch));
                match &reference {
                    None => reference = Some(got),
                    Some(want) => assert!(
                        *want == got,
                        "{path} on {threads} threads, shape ({n_in}, {n_out}, {batch})"
                    ),
                }
            }
        }
    }
}
