//! GFLOP/s of each product of Lunar Lander's critic layers at batch 512 on one thread, with
//! operands cycled through 8 copies (so that they come from as far as in an update), and the
//! one-thread FMA peak: a quick loop for tuning the kernels without building the service. Then
//! the forward product on squares (64 to 2048 cubed), to set beside a vendor sgemm's rate
//! on large shapes (`benches/reference/blas_products.py`).
//!     cargo run --release -p dualrep-kernels --example layer_rates [avx512|avx2] [seconds]
use std::time::{Duration, Instant};

use dualrep_kernels::{Isa, fma_peak, forward, input_grad, weight_grad};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let isa = match args.get(1).map(String::as_str) {
        Some("avx2") => Isa::Avx2,
        _ => Isa::Avx512,
    };
    let seconds: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.3);
    let peak = fma_peak::fma_peak_gflops(isa, 1, Duration::from_millis(200));
    println!("{isa:?}: FMA peak {peak:.0} GFLOP/s");
    let batch = 512;
    let mut total_s = 0.0;
    for (n_in, n_out) in [(10, 400), (400, 300), (300, 1)] {
        let copies = 8;
        let fill = |len: usize, seed: usize| -> Vec<Vec<f32>> {
            (0..copies)
                .map(|c| {
                    (0..len)
                        .map(|i| (((i * 7 + seed * 13 + c) % 97) as f32 - 48.0) / 97.0)
                        .collect()
                })
                .collect()
        };
        let w = fill(n_in * n_out, 1);
        let b = fill(n_out, 2);
        let x = fill(n_in * batch, 3);
        let mut z = fill(n_out * batch, 4);
        let dz = fill(n_out * batch, 5);
        let mut dw = fill(n_in * n_out, 6);
        let mut db = fill(n_out, 7);
        let mut dx = fill(n_in * batch, 8);
        let flop = 2.0 * (n_in * n_out * batch) as f64;
        let time = |f: &mut dyn FnMut(usize)| median_seconds(seconds, &mut |i| f(i % copies));
        let t_f = time(&mut |c| {
            forward(
                isa,
                1,
                (n_in, n_out, batch),
                &w[c],
                &b[c],
                &x[c],
                &mut z[c],
                true,
            )
        });
        let t_w = time(&mut |c| {
            weight_grad(
                isa,
                1,
                (n_in, n_out, batch),
                &x[c],
                &dz[c],
                &mut dw[c],
                &mut db[c],
            )
        });
        let t_i = time(&mut |c| {
            input_grad(
                isa,
                1,
                (n_in, n_out, batch),
                &w[c],
                &dz[c],
                &mut dx[c],
                Some(&x[c]),
            )
        });
        total_s += t_f + t_w + t_i;
        println!(
            "{n_in:>4}:{n_out:<4} forward {:6.1} us {:5.0} GFLOP/s ({:.2}) | weight grad {:6.1} us {:5.0} ({:.2}) | input grad {:6.1} us {:5.0} ({:.2})",
            t_f * 1e6,
            flop / t_f / 1e9,
            flop / t_f / 1e9 / peak,
            t_w * 1e6,
            flop / t_w / 1e9,
            flop / t_w / 1e9 / peak,
            t_i * 1e6,
            flop / t_i / 1e9,
            flop / t_i / 1e9 / peak,
        );
    }
    println!("sum of the nine: {:.1} us", total_s * 1e6);
    let rates: Vec<String> = [64, 128, 256, 1024, 2048]
        .iter()
        .map(|&n| {
            let (w, b, x) = (vec![0.01f32; n * n], vec![0.0f32; n], vec![0.02f32; n * n]);
            let mut z = vec![0.0f32; n * n];
            let t = median_seconds(seconds, &mut |_| {
                forward(isa, 1, (n, n, n), &w, &b, &x, &mut z, false)
            });
            format!("{n}^3 {:.0}", 2.0 * (n * n * n) as f64 / t / 1e9)
        })
        .collect();
    println!("square forward products, GFLOP/s: {}", rates.join(", "));
}

/// The median of single calls of `f(call index)` over `seconds`: robust to the other processes
/// of a shared machine.
fn median_seconds(seconds: f64, f: &mut dyn FnMut(usize)) -> f64 {
    let start = Instant::now();
    let mut times = Vec::new();
    while start.elapsed().as_secs_f64() < seconds || times.len() < 3 {
        let t = Instant::now();
        f(times.len());
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}
