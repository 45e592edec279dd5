//! The core's clock right after different kinds of work, read from a chain of dependent integer
//! multiplications (three cycles each on every recent x86 core, whatever the vector width or
//! the power state; a chain of additions of a constant is not used, since newer Intel cores
//! fold those at renaming and run several per cycle): is a matrix product held to a lower
//! clock than the FMA loop whose rate `bench sac` calls the peak? The VM exposes no cycle
//! counters, so this is the only clock it can read.
//!     cargo run --release -p dualrep-kernels --example clock_probe [rounds]
use std::time::{Duration, Instant};

use dualrep_kernels::{Isa, fma_peak, forward};

/// Dependent multiplications per turn of the chain's loop, and the cycles each takes.
const CHAIN: u64 = 100;
const LATENCY: u64 = 3;
/// Turns: 2.4 million cycles, about 0.6 ms, shorter than a clock change takes.
const TURNS: u64 = 8_000;

/// GHz of the core running the chain now.
fn chain_ghz() -> f64 {
    let t = Instant::now();
    #[cfg(target_arch = "x86_64")]
    // SAFETY: registers only.
    unsafe {
        let (mut x, mut n) = (3u64, TURNS);
        std::arch::asm!(
            "2:",
            ".rept {chain}",
            "imul {x}, {x}",
            ".endr",
            "dec {n}",
            "jnz 2b",
            x = inout(reg) x,
            n = inout(reg) n,
            chain = const CHAIN,
            options(nomem, nostack),
        );
        std::hint::black_box((x, n));
    }
    (CHAIN * LATENCY * TURNS) as f64 / t.elapsed().as_secs_f64() / 1e9
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(15);
    let isa = Isa::Avx512;
    let busy = Duration::from_millis(60);
    // Lunar Lander's large layer at batch 512, and a large square.
    let (n_in, n_out, batch) = (400, 300, 512);
    let (w, b, x) = (
        vec![0.01f32; n_in * n_out],
        vec![0.0f32; n_out],
        vec![0.02f32; n_in * batch],
    );
    let mut z = vec![0.0f32; n_out * batch];
    let n = 1024;
    let (ws, bs, xs) = (vec![0.01f32; n * n], vec![0.0f32; n], vec![0.02f32; n * n]);
    let mut zs = vec![0.0f32; n * n];
    let mut idle = Vec::new();
    let mut after_fma = Vec::new();
    let mut after_layer = Vec::new();
    let mut after_square = Vec::new();
    let (mut peak, mut layer_rate, mut square_rate) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds {
        std::thread::sleep(Duration::from_millis(30));
        idle.push(chain_ghz());

        peak.push(fma_peak::fma_peak_gflops(isa, 1, busy));
        after_fma.push(chain_ghz());

        let (start, mut calls) = (Instant::now(), 0);
        while start.elapsed() < busy {
            forward(isa, 1, (n_in, n_out, batch), &w, &b, &x, &mut z, true);
            calls += 1;
        }
        let flop = 2.0 * (n_in * n_out * batch * calls) as f64;
        layer_rate.push(flop / start.elapsed().as_secs_f64() / 1e9);
        after_layer.push(chain_ghz());

        let (start, mut calls) = (Instant::now(), 0);
        while start.elapsed() < busy {
            forward(isa, 1, (n, n, n), &ws, &bs, &xs, &mut zs, false);
            calls += 1;
        }
        square_rate.push(2.0 * (n * n * n * calls) as f64 / start.elapsed().as_secs_f64() / 1e9);
        after_square.push(chain_ghz());
    }
    let (peak, layer_rate, square_rate) = (median(peak), median(layer_rate), median(square_rate));
    println!("medians of {rounds} rounds, clock from a chain of dependent multiplications:");
    println!("  idle 30 ms               {:.2} GHz", median(idle));
    println!(
        "  after the FMA loop       {:.2} GHz   (loop {peak:.0} GFLOP/s)",
        median(after_fma)
    );
    println!(
        "  after 400:300 forwards   {:.2} GHz   ({layer_rate:.0} GFLOP/s, {:.2} of the loop)",
        median(after_layer),
        layer_rate / peak
    );
    println!(
        "  after 1024^3 forwards    {:.2} GHz   ({square_rate:.0} GFLOP/s, {:.2} of the loop)",
        median(after_square),
        square_rate / peak
    );
}
