//! `--kernels` and `--threads`, global flags of every sub-command: which kernels compute the
//! networks and how many threads one learner may use (`rl::kernels`).

use clap::Args;

use crate::rl::kernels::{self, KernelChoice, KernelPath};

#[derive(Debug, Args)]
pub struct ComputeArgs {
    /// The networks' kernels: auto (the fastest this CPU has: avx512, else avx2), avx512, avx2
    /// (the same results as avx512), or portable (matrixmultiply: the results of every run
    /// before the fast kernels, the same on every machine).
    #[arg(long, global = true, env = "DUALREP_KERNELS", default_value = "auto")]
    pub kernels: KernelChoice,
    /// Threads one learner may use (on two, its twin critics side by side; else its products
    /// split) [default: the cores, at most 2; `reproduce` gives
    /// each run the cores divided by --jobs; `serve` divides them between running sessions].
    #[arg(long, global = true, env = "DUALREP_THREADS", value_parser = clap::value_parser!(u64).range(1..=256))]
    pub threads: Option<u64>,
}

/// What [`ComputeArgs::install`] settled on.
#[derive(Clone, Copy, Debug)]
pub struct Compute {
    pub path: KernelPath,
    /// `--threads` as given, if it was.
    pub threads: Option<usize>,
}

impl Compute {
    /// Threads for one learner that has the machine to itself.
    pub fn threads_alone(&self) -> usize {
        self.threads.unwrap_or_else(|| kernels::cores().min(2))
    }
}

impl ComputeArgs {
    /// Make the choice the process default; refuses kernels this CPU cannot run.
    pub fn install(&self) -> anyhow::Result<Compute> {
        let path = self.kernels.resolve()?;
        kernels::set_default_path(path);
        let compute = Compute {
            path,
            threads: self.threads.map(|n| n as usize),
        };
        kernels::set_max_threads(compute.threads_alone());
        Ok(compute)
    }
}
