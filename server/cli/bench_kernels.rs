//! `dualrep bench kernels`: each of a layer's three products alone, on every kernel path this
//! CPU runs, in GFLOP/s and as a fraction of the FMA peak at that path's vector width; one JSON
//! object per line. Where the update's time goes, product by product. Each time is the best of
//! rounds of ten calls, so that other work on the machine does not blur the comparison.

use std::time::{Duration, Instant};

use clap::Args;
use nalgebra::DMatrix;
use serde::Serialize;

use crate::rl::Linear;
use crate::rl::kernels::{self, DenseLayer, KernelPath, forward_layer, input_grad, weight_grad};

#[derive(Debug, Args)]
pub struct KernelBenchArgs {
    /// Layers as n_in:n_out, comma-separated [default: Lunar Lander's critic: 10:400,400:300,300:1].
    #[arg(long, default_value = "10:400,400:300,300:1")]
    pub layers: String,
    #[arg(long, default_value_t = 512)]
    pub batch: usize,
    /// Seconds per product and path.
    #[arg(long, default_value_t = 1.0)]
    pub seconds: f64,
    /// Kernel paths to time [default: every one this CPU runs].
    #[arg(long, value_delimiter = ',')]
    pub paths: Vec<KernelPath>,
    /// Products to time: forward, weight_grad, input_grad [default: all three].
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "forward,weight_grad,input_grad"
    )]
    pub products: Vec<String>,
    /// Cycle through this many copies of the operands, so that they come from as far in the
    /// memory hierarchy as in an update (8 of Lunar Lander's layers are more than its L2).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=64))]
    pub copies: u64,
}

const PRODUCTS: [&str; 3] = ["forward", "weight_grad", "input_grad"];

#[derive(Serialize)]
struct ProductBench {
    kernels: KernelPath,
    threads: usize,
    product: &'static str,
    n_in: usize,
    n_out: usize,
    batch: usize,
    microseconds: f64,
    gflops: f64,
    fraction_of_fma_peak: f64,
}

pub fn run(args: KernelBenchArgs, threads: usize) -> anyhow::Result<()> {
    let layers: Vec<(usize, usize)> = args
        .layers
        .split(',')
        .map(|pair| {
            let (a, b) = pair
                .split_once(':')
                .ok_or_else(|| anyhow::anyhow!("--layers: expected n_in:n_out, got {pair:?}"))?;
            Ok((a.trim().parse()?, b.trim().parse()?))
        })
        .collect::<anyhow::Result<_>>()?;
    if args.batch == 0 || layers.iter().any(|&(a, b)| a == 0 || b == 0) {
        anyhow::bail!("sizes must be positive");
    }
    if let Some(bad) = args
        .products
        .iter()
        .find(|p| !PRODUCTS.contains(&p.as_str()))
    {
        anyhow::bail!("--products: unknown {bad:?}; expected {PRODUCTS:?}");
    }
    let paths: Vec<KernelPath> = if args.paths.is_empty() {
        KernelPath::ALL
            .into_iter()
            .filter(|p| p.is_available())
            .collect()
    } else {
        args.paths.clone()
    };
    if let Some(p) = paths.iter().find(|p| !p.is_available()) {
        anyhow::bail!("this CPU cannot run the {p} kernels");
    }
    let budget = Duration::from_secs_f64(args.seconds);
    for path in paths {
        let peak = path.fma_peak_gflops(threads, budget.min(Duration::from_millis(500)));
        kernels::with_path(path, || {
            kernels::with_threads(threads, || {
                for &(n_in, n_out) in &layers {
                    for product in PRODUCTS
                        .into_iter()
                        .filter(|p| args.products.iter().any(|q| q == p))
                    {
                        let seconds = time_product(
                            product,
                            n_in,
                            n_out,
                            args.batch,
                            args.copies as usize,
                            budget,
                        );
                        let gflops = 2.0 * (n_in * n_out * args.batch) as f64 / seconds / 1e9;
                        let line = ProductBench {
                            kernels: path,
                            threads,
                            product,
                            n_in,
                            n_out,
                            batch: args.batch,
                            microseconds: seconds * 1e6,
                            gflops,
                            fraction_of_fma_peak: gflops / peak,
                        };
                        println!("{}", serde_json::to_string(&line).expect("serialises"));
                    }
                }
            })
        });
    }
    Ok(())
}

/// The operands of one product.
struct Operands {
    params: Vec<f32>,
    grads: Vec<f32>,
    x: DMatrix<f32>,
    dz: DMatrix<f32>,
    z: DMatrix<f32>,
    dx: DMatrix<f32>,
}

/// Seconds per call of one product, on the calling thread's path.
fn time_product(
    product: &str,
    n_in: usize,
    n_out: usize,
    batch: usize,
    copies: usize,
    budget: Duration,
) -> f64 {
    let layer = Linear {
        n_in,
        n_out,
        offset: 0,
    };
    let mut operands: Vec<Operands> = (0..copies)
        .map(|c| Operands {
            params: (0..layer.len())
                .map(|i| ((i + c) as f32 * 0.37).sin() * 0.1)
                .collect(),
            grads: vec![0.0f32; layer.len()],
            x: DMatrix::from_fn(n_in, batch, |i, j| {
                ((i * 7 + j * 3 + c) as f32 * 0.11).cos()
            }),
            dz: DMatrix::from_fn(n_out, batch, |i, j| ((i * 5 + j + c) as f32 * 0.13).sin()),
            z: DMatrix::zeros(n_out, batch),
            dx: DMatrix::zeros(n_in, batch),
        })
        .collect();
    let mut next = 0;
    let mut call = || {
        let o = &mut operands[next];
        next = (next + 1) % copies;
        let d = DenseLayer {
            layer: &layer,
            params: &o.params,
        };
        match product {
            "forward" => forward_layer(d, &o.x, &mut o.z, true),
            "weight_grad" => weight_grad(&layer, &mut o.grads, &o.x, &o.dz),
            _ => input_grad(d, &o.dz, &mut o.dx, Some(&o.x)),
        }
    };
    call();
    // The best of rounds of 10 calls: other processes on the machine only ever slow a round.
    let start = Instant::now();
    let mut best = f64::INFINITY;
    while start.elapsed() < budget {
        let round = Instant::now();
        for _ in 0..10 {
            call();
        }
        best = best.min(round.elapsed().as_secs_f64() / 10.0);
    }
    best
}
