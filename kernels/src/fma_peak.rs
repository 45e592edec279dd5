//! The core's peak rate of fused multiply-adds, measured: a loop of independent FMAs on
//! registers only (no memory, no matrix), enough of them in flight to fill every FMA pipe for
//! its latency. What a matrix product could reach at best on this machine, on the vector width
//! of a kernel path.

use std::time::{Duration, Instant};

use crate::Isa;

/// GFLOP/s (2 per lane per FMA) of `threads` threads each running the FMA loop of `isa`'s
/// vector width at once for about `budget`.
pub fn fma_peak_gflops(isa: Isa, threads: usize, budget: Duration) -> f64 {
    assert!(isa.is_available(), "this CPU cannot run {isa:?}");
    let per_thread: Vec<f64> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads.max(1))
            .map(|_| scope.spawn(move || one_thread(isa, budget)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("FMA loop thread"))
            .collect()
    });
    per_thread.iter().sum()
}

/// GFLOP/s of one thread's loop: the best of short rounds, since other processes on the core
/// can only slow a round down.
fn one_thread(path: Isa, budget: Duration) -> f64 {
    let round = 1 << 17;
    run(path, round);
    let start = Instant::now();
    let mut best = 0.0f64;
    while start.elapsed() < budget {
        let t = Instant::now();
        let flops = run(path, round);
        best = best.max(flops / t.elapsed().as_secs_f64() / 1e9);
    }
    best
}

/// `iterations` rounds of the loop; returns the flops done.
fn run(path: Isa, iterations: u64) -> f64 {
    let seed = std::hint::black_box(0.999_f32);
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `fma_peak_gflops` checked that the CPU runs `path`.
    unsafe {
        let lanes = match path {
            Isa::Avx512 => {
                std::hint::black_box(x86::avx512(seed, iterations));
                16
            }
            Isa::Avx2 => {
                std::hint::black_box(x86::avx2(seed, iterations));
                8
            }
        };
        (iterations * x86::ACCUMULATORS as u64 * lanes * 2) as f64
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (seed, iterations);
        0.0
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// Independent FMA chains: two pipes times a latency of up to 5 cycles needs 10; 12 leave
    /// a margin and fit AVX2's 16 registers with the two constants.
    pub const ACCUMULATORS: usize = 12;

    #[target_feature(enable = "avx512f,avx2,fma")]
    pub unsafe fn avx512(seed: f32, iterations: u64) -> f32 {
        let (mul, add) = (_mm512_set1_ps(seed), _mm512_set1_ps(1e-3));
        let mut acc = [_mm512_set1_ps(seed); ACCUMULATORS];
        for _ in 0..iterations {
            for a in &mut acc {
                // x -> 0.999 x + 0.001 stays near 1: no overflow, no denormals.
                *a = _mm512_fmadd_ps(*a, mul, add);
            }
        }
        let mut sum = _mm512_setzero_ps();
        for a in acc {
            sum = _mm512_add_ps(sum, a);
        }
        _mm512_reduce_add_ps(sum)
    }

    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn avx2(seed: f32, iterations: u64) -> f32 {
        let (mul, add) = (_mm256_set1_ps(seed), _mm256_set1_ps(1e-3));
        let mut acc = [_mm256_set1_ps(seed); ACCUMULATORS];
        for _ in 0..iterations {
            for a in &mut acc {
                *a = _mm256_fmadd_ps(*a, mul, add);
            }
        }
        let mut sum = _mm256_setzero_ps();
        for a in acc {
            sum = _mm256_add_ps(sum, a);
        }
        let mut lanes = [0.0f32; 8];
        // SAFETY: `lanes` holds 8 floats.
        unsafe { _mm256_storeu_ps(lanes.as_mut_ptr(), sum) };
        lanes.iter().sum()
    }
}
