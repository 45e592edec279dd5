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
const DIMS: (usize, usize, usize) = (N_IN, N_OUT, BATCH);

/// One product `dst (+)= lhs rhs` (`m x k` by `k x n`), each operand given by its row and
/// column strides; `accumulate` keeps the old `dst` (a weight gradient), otherwise it is
/// overwritten.
struct Product {
    name: &'static str,
    m: usize,
    n: usize,
    k: usize,
    dst: (isize, isize),
    lhs: (isize, isize),
    rhs: (isize, isize),
    accumulate: bool,
}

/// Activations are column-major `n x batch`, weights row-major `n_out x n_in` (our layout).
const PRODUCTS: [Product; 3] = [
    // z = W x
    Product {
        name: "forward",
        m: N_OUT,
        n: BATCH,
        k: N_IN,
        dst: (1, N_OUT as isize),
        lhs: (N_IN as isize, 1),
        rhs: (1, N_IN as isize),
        accumulate: false,
    },
    // dW += dz x^T
    Product {
        name: "weight gradient",
        m: N_OUT,
        n: N_IN,
        k: BATCH,
        dst: (N_IN as isize, 1),
        lhs: (1, N_OUT as isize),
        rhs: (N_IN as isize, 1),
        accumulate: true,
    },
    // dx = W^T dz
    Product {
        name: "input gradient",
        m: N_IN,
        n: BATCH,
        k: N_OUT,
        dst: (1, N_IN as isize),
        lhs: (1, N_IN as isize),
        rhs: (1, N_OUT as isize),
        accumulate: false,
    },
];

impl Product {
    fn lens(&self) -> (usize, usize, usize) {
        (self.m * self.k, self.k * self.n, self.m * self.n)
    }

    fn with_gemm_crate(&self, lhs: &[f32], rhs: &[f32], dst: &mut [f32]) {
        assert_eq!((lhs.len(), rhs.len(), dst.len()), self.lens());
        // SAFETY: the strides describe dense layouts of exactly these lengths (asserted).
        unsafe {
            gemm::gemm(
                self.m,
                self.n,
                self.k,
                dst.as_mut_ptr(),
                self.dst.1,
                self.dst.0,
                self.accumulate,
                lhs.as_ptr(),
                self.lhs.1,
                self.lhs.0,
                rhs.as_ptr(),
                self.rhs.1,
                self.rhs.0,
                if self.accumulate { 1.0 } else { 0.0 },
                1.0,
                false,
                false,
                false,
                gemm::Parallelism::None,
            )
        }
    }

    fn with_matrixmultiply(&self, lhs: &[f32], rhs: &[f32], dst: &mut [f32]) {
        assert_eq!((lhs.len(), rhs.len(), dst.len()), self.lens());
        // SAFETY: as above.
        unsafe {
            matrixmultiply::sgemm(
                self.m,
                self.k,
                self.n,
                1.0,
                lhs.as_ptr(),
                self.lhs.0,
                self.lhs.1,
                rhs.as_ptr(),
                self.rhs.0,
                self.rhs.1,
                if self.accumulate { 1.0 } else { 0.0 },
                dst.as_mut_ptr(),
                self.dst.0,
                self.dst.1,
            )
        }
    }

    /// Ours, with its epilogue when `epilogue` (bias and ReLU, bias gradient, ReLU mask by the
    /// layer's input), as the update calls it. `lhs` and `rhs` are the operands as above.
    fn with_ours(&self, lhs: &[f32], rhs: &[f32], dst: &mut [f32], epilogue: bool) {
        match self.name {
            "forward" => {
                let bias = if epilogue { BIAS } else { [0.0; N_OUT] };
                forward(Isa::Avx512, 1, DIMS, lhs, &bias, rhs, dst, epilogue)
            }
            "weight gradient" => {
                let mut db = [0.0; N_OUT];
                weight_grad(Isa::Avx512, 1, DIMS, rhs, lhs, dst, &mut db)
            }
            _ => input_grad(
                Isa::Avx512,
                1,
                DIMS,
                lhs,
                rhs,
                dst,
                epilogue.then_some(&MASK[..]),
            ),
        }
    }
}

/// The forward's bias and the input gradient's ReLU output (half of it positive).
static BIAS: [f32; N_OUT] = [0.01; N_OUT];
static MASK: [f32; N_IN * BATCH] = {
    let mut m = [0.0; N_IN * BATCH];
    let mut i = 0;
    while i < m.len() {
        m[i] = if i % 2 == 0 { 1.0 } else { -1.0 };
        i += 1;
    }
    m
};

fn fill(len: usize, seed: usize) -> Vec<Vec<f32>> {
    (0..COPIES)
        .map(|c| {
            (0..len)
                .map(|i| (((i * 7 + seed * 13 + c) % 97) as f32 - 48.0) / 97.0)
                .collect()
        })
        .collect()
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
    let operands: Vec<_> = PRODUCTS
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (l, r, d) = p.lens();
            (fill(l, 3 * i + 1), fill(r, 3 * i + 2), fill(d, 3 * i + 3))
        })
        .collect();

    // The three libraries compute the same products (no epilogue, gradients from zero).
    for (p, (lhs, rhs, _)) in PRODUCTS.iter().zip(&operands) {
        let out = |f: &dyn Fn(&mut [f32])| {
            let mut dst = vec![0.0; p.lens().2];
            f(&mut dst);
            dst
        };
        let ours = out(&|d| p.with_ours(&lhs[0], &rhs[0], d, false));
        let theirs = out(&|d| p.with_gemm_crate(&lhs[0], &rhs[0], d));
        let mm = out(&|d| p.with_matrixmultiply(&lhs[0], &rhs[0], d));
        println!(
            "{}: max |ours - gemm| {:.1e}, |ours - matrixmultiply| {:.1e}",
            p.name,
            max_abs_diff(&ours, &theirs),
            max_abs_diff(&ours, &mm)
        );
    }

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
    let mut operands = operands;
    for round in 0..rounds {
        let peak = fma_peak::fma_peak_gflops(Isa::Avx512, 1, Duration::from_millis(200));
        println!("round {round}: one-thread AVX-512 FMA peak {peak:.0} GFLOP/s");
        for (p, (lhs, rhs, dst)) in PRODUCTS.iter().zip(&mut operands) {
            let report = |who: &str, f: &mut dyn FnMut(usize)| {
                let t = time(f);
                let g = flop / t / 1e9;
                let name = format!("{who} {}", p.name);
                println!(
                    "  {name:<34} {:6.0} us {g:5.0} GFLOP/s {:.2} of peak",
                    t * 1e6,
                    g / peak
                );
            };
            report("ours (+ epilogue)", &mut |c| {
                p.with_ours(&lhs[c], &rhs[c], &mut dst[c], true)
            });
            report("gemm crate", &mut |c| {
                p.with_gemm_crate(&lhs[c], &rhs[c], &mut dst[c])
            });
            report("matrixmultiply", &mut |c| {
                p.with_matrixmultiply(&lhs[c], &rhs[c], &mut dst[c])
            });
        }
    }
}
