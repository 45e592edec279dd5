//! Where a grid command's runs run: `--executor local` (child processes on this machine, the
//! default) or `--executor slurm` (`sbatch` job arrays on a cluster), with each one's options.
//! Flattened into every grid command, so each gets both executors the same way.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, bail};
use clap::Args;

use crate::report::local::LocalPool;
use crate::report::runner::{Executor, Waiting};
use crate::report::slurm::SlurmExecutor;
use crate::report::slurm::script::ArraySettings;
use crate::rl::kernels;

/// The executors a grid can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExecutorKind {
    /// Child processes on this machine, `--jobs` at a time.
    Local,
    /// One `sbatch` job array per submission, one task per run.
    Slurm,
}

#[derive(Debug, Args)]
pub struct ExecutorArgs {
    /// Where the runs run: `local` (child processes here) or `slurm` (sbatch job arrays; see
    /// the README's "Running the grids on a cluster").
    #[arg(long, value_enum, default_value_t = ExecutorKind::Local)]
    pub executor: ExecutorKind,
    /// Runs at once [default: local: the number of CPUs; slurm: as many as Slurm starts]; with
    /// slurm, the cap applies to each submitted array (`--array=...%J`).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub jobs: Option<u64>,
    /// The dualrep binary each run executes [default: this one]; with slurm, its path on the
    /// compute nodes.
    #[arg(long)]
    pub program: Option<PathBuf>,
    /// Submit and return at once instead of waiting; the same command again waits for the runs
    /// (and submits EF at DREF's rate once DREF's runs have finished).
    #[arg(long, help_heading = "Slurm")]
    pub no_wait: bool,
    /// The partition to run in (sbatch --partition).
    #[arg(long, help_heading = "Slurm")]
    pub partition: Option<String>,
    /// Each run's time limit in Slurm's format (sbatch --time), e.g. 2:00:00.
    #[arg(long, help_heading = "Slurm")]
    pub time: Option<String>,
    /// CPUs per run (sbatch --cpus-per-task) [default: 1].
    #[arg(long, help_heading = "Slurm", value_parser = clap::value_parser!(u32).range(1..))]
    pub cpus_per_task: Option<u32>,
    /// One more sbatch argument, as one word (repeatable), e.g. --sbatch-arg=--qos=long.
    #[arg(
        long = "sbatch-arg",
        value_name = "ARG",
        allow_hyphen_values = true,
        help_heading = "Slurm"
    )]
    pub sbatch_args: Vec<String>,
    /// Seconds between looks at the queue while waiting [default: 10].
    #[arg(long, value_name = "SECONDS", help_heading = "Slurm")]
    pub poll: Option<f64>,
}

impl ExecutorArgs {
    /// Runs at once with the local executor: --jobs, else the number of CPUs.
    fn local_jobs(&self) -> usize {
        self.jobs.map_or_else(
            || std::thread::available_parallelism().map_or(1, usize::from),
            |j| j as usize,
        )
    }

    /// Threads each run's learner computes on: `threads` where given, else its share of the
    /// cores (local: the cores divided by the runs at once, 1 to 2; slurm: --cpus-per-task).
    pub fn threads_per_run(&self, threads: Option<usize>) -> usize {
        threads.unwrap_or_else(|| match self.executor {
            ExecutorKind::Local => (kernels::cores() / self.local_jobs()).clamp(1, 2),
            ExecutorKind::Slurm => self.cpus_per_task.unwrap_or(1) as usize,
        })
    }

    /// The executor for a grid in `out`, checked before anything runs; `job_name` names its
    /// Slurm arrays, and every run gets `env` in its environment.
    pub fn build(
        &self,
        out: &Path,
        job_name: &str,
        env: &[(String, String)],
    ) -> anyhow::Result<(Box<dyn Executor>, Waiting)> {
        let program = match &self.program {
            Some(p) => p.clone(),
            None => std::env::current_exe().context("finding the dualrep binary to run")?,
        };
        if self.executor == ExecutorKind::Local {
            if let Some(option) = self.slurm_option_given() {
                bail!("{option} is for --executor slurm");
            }
            let pool = LocalPool::new(&program, self.local_jobs()).with_env(env);
            return Ok((Box::new(pool), Waiting::UntilDone));
        }
        for (option, value) in [("--partition", &self.partition), ("--time", &self.time)] {
            if let Some(v) = value
                && (v.is_empty() || v.chars().any(|c| c.is_whitespace() || c.is_control()))
            {
                bail!("{option} {v:?}: expected one word");
            }
        }
        if let Some(bad) = self.sbatch_args.iter().find(|a| !a.starts_with('-')) {
            bail!("--sbatch-arg {bad:?}: expected an sbatch option such as --qos=long");
        }
        let poll = self.poll.unwrap_or(10.0);
        if !(poll.is_finite() && poll > 0.0) {
            bail!("--poll {poll}: expected a number of seconds above 0");
        }
        if !program.exists() {
            eprintln!(
                "note: {} is not on this machine; it must be the dualrep binary's path on the \
                 compute nodes",
                program.display()
            );
        }
        let settings = ArraySettings {
            job_name: job_name.to_string(),
            program,
            partition: self.partition.clone(),
            time: self.time.clone(),
            cpus_per_task: self.cpus_per_task.unwrap_or(1),
            max_running: self.jobs.map(|j| j as usize),
            extra: self.sbatch_args.clone(),
            env: env.to_vec(),
        };
        let executor = SlurmExecutor::new(settings, out, Duration::from_secs_f64(poll))?;
        let waiting = if self.no_wait {
            Waiting::NoWait
        } else {
            Waiting::UntilDone
        };
        Ok((Box::new(executor), waiting))
    }

    /// The first Slurm-only option given, for the error when the executor is local.
    fn slurm_option_given(&self) -> Option<&'static str> {
        [
            (self.no_wait, "--no-wait"),
            (self.partition.is_some(), "--partition"),
            (self.time.is_some(), "--time"),
            (self.cpus_per_task.is_some(), "--cpus-per-task"),
            (!self.sbatch_args.is_empty(), "--sbatch-arg"),
            (self.poll.is_some(), "--poll"),
        ]
        .into_iter()
        .find_map(|(given, name)| given.then_some(name))
    }
}
