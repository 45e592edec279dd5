//! Lunar Lander critic's 400:300 layer at batch 512 on one thread: each product with our
//! kernels (`avx512`), the `gemm` crate and matrixmultiply, timed one after another in each
//! round (median of single calls, operands cycled through 8 copies as in `layer_rates`), after
//! checking that all three compute the same product.
use std::time::{Duration, Instant};

use dualrep_kernels::{Isa, fma_peak, forward, input_grad, weight_grad};

const N_IN: usize = 400;
const N_OUT: usize = 300;
const BATCH: usize = 512;
const COPIES: usize = 8;

/// `z = W x` (column-major `n_out x batch`; `w` row-major `n_out x n_in`, `x` column-major).
fn gemm_crate_forward(w: &[f32], x: &[f32], z: &mut [f32]) {
    // SAFETY: the strides describe the slices' own layouts and lengths (checked by callers'
    // sizes: N_OUT * N_IN, N_IN * BATCH, N_OUT * BATCH).
    unsafe {
        gemm::gemm(
            N_OUT,
            BATCH,
            N_IN,
            z.as_mut_ptr(),
            N_OUT as isize,
            1,
            false,
            w.as_ptr(),
            1,
            N_IN as isize,
            x.as_ptr(),
            N_IN as isize,
            1,
            0.0,
            1.0,
            false,
            false,
            false,
            gemm::Parallelism::None,
        )
    }
}

/// `dW += dz x^T` (`dw` row-major `n_out x n_in`).
fn gemm_crate_weight_grad(x: &[f32], dz: &[f32], dw: &mut [f32]) {
    // SAFETY: as above.
    unsafe {
        gemm::gemm(
            N_OUT,
            N_IN,
            BATCH,
            dw.as_mut_ptr(),
            1,
            N_IN as isize,
            true,
            dz.as_ptr(),
            N_OUT as isize,
            1,
            x.as_ptr(),
            1,
            N_IN as isize,
            1.0,
            1.0,
            false,
            false,
            false,
            gemm::Parallelism::None,
        )
    }
}

/// `dx = W^T dz` (column-major `n_in x batch`).
fn gemm_crate_input_grad(w: &[f32], dz: &[f32], dx: &mut [f32]) {
    // SAFETY: as above.
    unsafe {
        gemm::gemm(
            N_IN,
            BATCH,
            N_OUT,
            dx.as_mut_ptr(),
            N_IN as isize,
            1,
            false,
            w.as_ptr(),
            N_IN as isize,
            1,
            dz.as_ptr(),
            N_OUT as isize,
            1,
            0.0,
            1.0,
            false,
            false,
            false,
            gemm::Parallelism::None,
        )
    }
}

fn mm_forward(w: &[f32], x: &[f32], z: &mut [f32]) {
    // SAFETY: as above.
    unsafe {
        matrixmultiply::sgemm(
            N_OUT,
            N_IN,
            BATCH,
            1.0,
            w.as_ptr(),
            N_IN as isize,
            1,
            x.as_ptr(),
            1,
            N_IN as isize,
            0.0,
            z.as_mut_ptr(),
            1,
            N_OUT as isize,
        )
    }
}

fn mm_weight_grad(x: &[f32], dz: &[f32], dw: &mut [f32]) {
    // SAFETY: as above.
    unsafe {
        matrixmultiply::sgemm(
            N_OUT,
            BATCH,
            N_IN,
            1.0,
            dz.as_ptr(),
            1,
            N_OUT as isize,
            x.as_ptr(),
            N_IN as isize,
            1,
            1.0,
            dw.as_mut_ptr(),
            N_IN as isize,
            1,
        )
    }
}

fn mm_input_grad(w: &[f32], dz: &[f32], dx: &mut [f32]) {
    // SAFETY: as above.
    unsafe {
        matrixmultiply::sgemm(
            N_IN,
            N_OUT,
            BATCH,
            1.0,
            w.as_ptr(),
            1,
            N_IN as isize,
            dz.as_ptr(),
            1,
            N_OUT as isize,
            0.0,
            dx.as_mut_ptr(),
            1,
            N_IN as isize,
        )
    }
}

fn max_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max)
}

fn main() {
    let seconds: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.3);
    let rounds: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2);
    let fill = |len: usize, seed: usize| -> Vec<Vec<f32>> {
        (0..COPIES)
            .map(|c| {
                (0..len)
                    .map(|i| (((i * 7 + seed * 13 + c) % 97) as f32 - 48.0) / 97.0)
                    .collect()
            })
            .collect()
    };
    let w = fill(N_IN * N_OUT, 1);
    let x = fill(N_IN * BATCH, 3);
    let dz = fill(N_OUT * BATCH, 5);
    let zero_bias = vec![0.0; N_OUT];
    let dims = (N_IN, N_OUT, BATCH);

    // The three libraries compute the same products (no bias, no ReLU, gradients from zero).
    let (mut ours, mut theirs, mut mm) = (
        vec![0.0; N_OUT * BATCH],
        vec![0.0; N_OUT * BATCH],
        vec![0.0; N_OUT * BATCH],
    );
    forward(
        Isa::Avx512,
        1,
        dims,
        &w[0],
        &zero_bias,
        &x[0],
        &mut ours,
        false,
    );
    gemm_crate_forward(&w[0], &x[0], &mut theirs);
    mm_forward(&w[0], &x[0], &mut mm);
    println!(
        "forward: max |ours - gemm| {:.1e}, |ours - matrixmultiply| {:.1e}",
        max_abs_diff(&ours, &theirs),
        max_abs_diff(&ours, &mm)
    );
    let (mut ours, mut theirs, mut mm) = (
        vec![0.0; N_IN * N_OUT],
        vec![0.0; N_IN * N_OUT],
        vec![0.0; N_IN * N_OUT],
    );
    weight_grad(
        Isa::Avx512,
        1,
        dims,
        &x[0],
        &dz[0],
        &mut ours,
        &mut vec![0.0; N_OUT],
    );
    gemm_crate_weight_grad(&x[0], &dz[0], &mut theirs);
    mm_weight_grad(&x[0], &dz[0], &mut mm);
    println!(
        "weight gradient: max |ours - gemm| {:.1e}, |ours - matrixmultiply| {:.1e}",
        max_abs_diff(&ours, &theirs),
        max_abs_diff(&ours, &mm)
    );
    let (mut ours, mut theirs, mut mm) = (
        vec![0.0; N_IN * BATCH],
        vec![0.0; N_IN * BATCH],
        vec![0.0; N_IN * BATCH],
    );
    input_grad(Isa::Avx512, 1, dims, &w[0], &dz[0], &mut ours, None);
    gemm_crate_input_grad(&w[0], &dz[0], &mut theirs);
    mm_input_grad(&w[0], &dz[0], &mut mm);
    println!(
        "input gradient: max |ours - gemm| {:.1e}, |ours - matrixmultiply| {:.1e}",
        max_abs_diff(&ours, &theirs),
        max_abs_diff(&ours, &mm)
    );

    let b = fill(N_OUT, 2);
    let mut z = fill(N_OUT * BATCH, 4);
    let mut dw = fill(N_IN * N_OUT, 6);
    let mut db = fill(N_OUT, 7);
    let mut dx = fill(N_IN * BATCH, 8);
    let flop = 2.0 * (N_IN * N_OUT * BATCH) as f64;
    let time = |f: &mut dyn FnMut(usize)| {
        // The median of single calls: robust to the other processes of a shared machine.
        let start = Instant::now();
        let mut times = Vec::new();
        while start.elapsed().as_secs_f64() < seconds {
            let t = Instant::now();
            f(times.len() % COPIES);
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        times[times.len() / 2]
    };
    for round in 0..rounds {
        let peak = fma_peak::fma_peak_gflops(Isa::Avx512, 1, Duration::from_millis(200));
        println!("round {round}: one-thread AVX-512 FMA peak {peak:.0} GFLOP/s");
        let report = |name: &str, t: f64| {
            let g = flop / t / 1e9;
            println!(
                "  {name:<40} {:6.0} us {g:5.0} GFLOP/s {:.2} of peak",
                t * 1e6,
                g / peak
            );
        };
        report(
            "ours forward (+ bias, ReLU)",
            time(&mut |c| forward(Isa::Avx512, 1, dims, &w[c], &b[c], &x[c], &mut z[c], true)),
        );
        report(
            "gemm crate forward (product only)",
            time(&mut |c| gemm_crate_forward(&w[c], &x[c], &mut z[c])),
        );
        report(
            "matrixmultiply forward (product only)",
            time(&mut |c| mm_forward(&w[c], &x[c], &mut z[c])),
        );
        report(
            "ours weight gradient (+ bias gradient)",
            time(&mut |c| weight_grad(Isa::Avx512, 1, dims, &x[c], &dz[c], &mut dw[c], &mut db[c])),
        );
        report(
            "gemm crate weight gradient",
            time(&mut |c| gemm_crate_weight_grad(&x[c], &dz[c], &mut dw[c])),
        );
        report(
            "matrixmultiply weight gradient",
            time(&mut |c| mm_weight_grad(&x[c], &dz[c], &mut dw[c])),
        );
        report(
            "ours input gradient (+ ReLU mask)",
            time(&mut |c| input_grad(Isa::Avx512, 1, dims, &w[c], &dz[c], &mut dx[c], Some(&x[c]))),
        );
        report(
            "gemm crate input gradient (product only)",
            time(&mut |c| gemm_crate_input_grad(&w[c], &dz[c], &mut dx[c])),
        );
        report(
            "matrixmultiply input gradient",
            time(&mut |c| mm_input_grad(&w[c], &dz[c], &mut dx[c])),
        );
    }
}
