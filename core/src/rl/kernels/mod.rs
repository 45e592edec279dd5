//! The arithmetic of every layer: which kernels compute it, and on how many threads.
//!
//! ## Kernel paths
//!
//! - [`KernelPath::Portable`]: matrixmultiply's `sgemm` and plain loops (`portable.rs`), the
//!   code every run before the fast kernels used. Its results are the same bits on every
//!   machine we run on, and the same as those runs'.
//! - [`KernelPath::Avx512`], [`KernelPath::Avx2`]: our own kernels (the `dualrep-kernels`
//!   crate in `kernels/`), written once over a vector type and compiled for AVX-512 and for
//!   AVX2 + FMA, chosen at run time (the binary itself stays portable x86-64). They fuse bias,
//!   ReLU and the ReLU mask into the products and allocate nothing after their first use.
//!
//! Both fast paths compute every number with the same operations in the same order: each
//! product element is one chain of fused multiply-adds over `k` in order, and the few dot
//! products (layers with at most four outputs, batches of at most four) sum 16 interleaved
//! partial sums in one fixed tree whatever the vector width. So AVX-512 and AVX2 give the same
//! bits (`tests.rs` checks it where both run): a run re-runs bit for bit on either kind of
//! machine on the fast path too, just not bit for bit against the portable path, whose `sgemm`
//! blocks `k` differently (the two agree to f32 rounding).
//!
//! The path of the calling thread is [`current_path`]: a per-thread choice
//! ([`with_path`]) over the process default ([`set_default_path`], else the environment
//! variable `DUALREP_KERNELS`, else the best this CPU has).
//!
//! ## Threads
//!
//! A product can be split over several threads (`dualrep_kernels::team`): each thread computes
//! whole output elements, so results do not depend on the number of threads. The number is
//! [`threads_now`]: the process maximum ([`set_max_threads`], default 1), shared out between
//! the learners that train at once ([`ActiveLearner`]), or a per-thread choice
//! ([`with_threads`]). On two threads, independent networks (the twin critics) run side by
//! side instead, one thread each ([`side_by_side`]).

mod dense;
#[cfg(test)]
mod equivalence_tests;
mod portable;
mod side_by_side;

use std::cell::Cell;
use std::fmt;
use std::str::FromStr;
use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering};

use serde::{Deserialize, Serialize};

// Public for `dualrep bench kernels`, which times each product on each path.
pub(crate) use dense::input_grad_columns;
pub use dense::{DenseLayer, forward_layer, input_grad, weight_grad};
pub use dualrep_kernels::Isa;
pub use side_by_side::side_by_side;

/// Which kernels compute the networks' products.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum KernelPath {
    /// matrixmultiply's `sgemm`: the same bits on every machine, and as every earlier run.
    Portable,
    /// Our kernels on 256-bit AVX2 + FMA (same bits as `avx512`).
    Avx2,
    /// Our kernels on 512-bit AVX-512F (same bits as `avx2`).
    Avx512,
}

impl KernelPath {
    pub const ALL: [KernelPath; 3] = [KernelPath::Portable, KernelPath::Avx2, KernelPath::Avx512];

    pub fn name(self) -> &'static str {
        match self {
            KernelPath::Portable => "portable",
            KernelPath::Avx2 => "avx2",
            KernelPath::Avx512 => "avx512",
        }
    }

    /// Whether this CPU can run the path.
    pub fn is_available(self) -> bool {
        self.isa().is_none_or(Isa::is_available)
    }

    /// The fastest path this CPU runs: AVX-512, else AVX2 + FMA, else portable.
    pub fn best_available() -> Self {
        [KernelPath::Avx512, KernelPath::Avx2]
            .into_iter()
            .find(|p| p.is_available())
            .unwrap_or(KernelPath::Portable)
    }

    /// The instruction set of a fast path (`None` for the portable one).
    pub fn isa(self) -> Option<Isa> {
        match self {
            KernelPath::Portable => None,
            KernelPath::Avx2 => Some(Isa::Avx2),
            KernelPath::Avx512 => Some(Isa::Avx512),
        }
    }

    /// GFLOP/s of `threads` threads running a register-only FMA loop at this path's vector
    /// width. The portable path's is the widest this CPU has: matrixmultiply picks its own
    /// AVX-512 sgemm kernel where the CPU has AVX-512F (else its FMA one), so its ceiling is
    /// that width's (0 without AVX2).
    pub fn fma_peak_gflops(self, threads: usize, budget: std::time::Duration) -> f64 {
        let portable = KernelPath::best_available().isa();
        match self.isa().or(portable) {
            Some(isa) => dualrep_kernels::fma_peak::fma_peak_gflops(isa, threads, budget),
            None => 0.0,
        }
    }

    /// Paths with the same numerics give the same bits: `avx2` and `avx512` ("fma"), or
    /// `portable`.
    pub fn numerics(self) -> &'static str {
        match self {
            KernelPath::Portable => "portable",
            KernelPath::Avx2 | KernelPath::Avx512 => "fma",
        }
    }

    /// The fastest available path whose results are `self`'s bits, if this CPU has one.
    pub fn available_equivalent(self) -> Option<Self> {
        match self {
            KernelPath::Portable => Some(KernelPath::Portable),
            _ => [KernelPath::Avx512, KernelPath::Avx2]
                .into_iter()
                .find(|p| p.is_available()),
        }
    }
}

impl fmt::Display for KernelPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for KernelPath {
    type Err = KernelChoiceError;

    fn from_str(s: &str) -> Result<Self, KernelChoiceError> {
        KernelPath::ALL
            .into_iter()
            .find(|p| p.name() == s.trim())
            .ok_or_else(|| KernelChoiceError::Unknown {
                name: s.to_string(),
                or_auto: false,
            })
    }
}

/// Why kernels asked for by name are not the ones to run.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum KernelChoiceError {
    /// No kernels of that name (`or_auto`: where `auto` may be asked for too).
    #[error(
        "unknown kernels {name:?}: expected avx512, avx2 or portable{}",
        if *.or_auto { " or auto" } else { "" }
    )]
    Unknown { name: String, or_auto: bool },
    /// Kernels this CPU cannot run.
    #[error("this CPU cannot run the {0} kernels (it runs {runs})", runs = available_names())]
    Unavailable(KernelPath),
}

/// What a user asks for: the best this CPU has, or one path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelChoice {
    Auto,
    Exactly(KernelPath),
}

impl KernelChoice {
    /// The path to run, or why this CPU cannot run the one asked for.
    pub fn resolve(self) -> Result<KernelPath, KernelChoiceError> {
        match self {
            KernelChoice::Auto => Ok(KernelPath::best_available()),
            KernelChoice::Exactly(p) if p.is_available() => Ok(p),
            KernelChoice::Exactly(p) => Err(KernelChoiceError::Unavailable(p)),
        }
    }
}

impl FromStr for KernelChoice {
    type Err = KernelChoiceError;

    fn from_str(s: &str) -> Result<Self, KernelChoiceError> {
        match s.trim() {
            "auto" => Ok(KernelChoice::Auto),
            other => {
                other
                    .parse()
                    .map(KernelChoice::Exactly)
                    .map_err(|_| KernelChoiceError::Unknown {
                        name: other.to_string(),
                        or_auto: true,
                    })
            }
        }
    }
}

fn available_names() -> String {
    KernelPath::ALL
        .into_iter()
        .filter(|p| p.is_available())
        .map(KernelPath::name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// 0: not set; else 1 + the index in `KernelPath::ALL`.
static DEFAULT_PATH: AtomicU8 = AtomicU8::new(0);

thread_local! {
    static THREAD_PATH: Cell<Option<KernelPath>> = const { Cell::new(None) };
    static THREAD_THREADS: Cell<Option<usize>> = const { Cell::new(None) };
}

/// Make `path` the process default (the CLI does, from `--kernels`).
pub fn set_default_path(path: KernelPath) {
    let index = KernelPath::ALL.iter().position(|&p| p == path).unwrap_or(0);
    DEFAULT_PATH.store(index as u8 + 1, Ordering::Relaxed);
}

/// The process default: set by [`set_default_path`], else `DUALREP_KERNELS` (`auto`,
/// `avx512`, `avx2`, `portable`), else the best path this CPU has. Panics on a
/// `DUALREP_KERNELS` this CPU cannot run, rather than silently computing something else.
pub fn default_path() -> KernelPath {
    match DEFAULT_PATH.load(Ordering::Relaxed) {
        0 => {
            let path = match std::env::var("DUALREP_KERNELS") {
                Ok(s) => s
                    .parse::<KernelChoice>()
                    .and_then(KernelChoice::resolve)
                    .unwrap_or_else(|e| panic!("DUALREP_KERNELS: {e}")),
                Err(_) => KernelPath::best_available(),
            };
            set_default_path(path);
            path
        }
        i => KernelPath::ALL[usize::from(i) - 1],
    }
}

/// The path this thread computes with: its own choice ([`with_path`]) or the default.
pub fn current_path() -> KernelPath {
    THREAD_PATH.get().unwrap_or_else(default_path)
}

/// Run `f` with this thread on `path` (restored afterwards, even on panic). Panics if this
/// CPU cannot run `path`.
pub fn with_path<R>(path: KernelPath, f: impl FnOnce() -> R) -> R {
    assert!(
        path.is_available(),
        "this CPU cannot run the {path} kernels"
    );
    let _restore = Restore(&THREAD_PATH, THREAD_PATH.replace(Some(path)));
    f()
}

/// Run `f` on every kernel path this CPU has (tests, benchmarks), this thread switched to each.
pub fn on_every_path(mut f: impl FnMut(KernelPath)) {
    for path in KernelPath::ALL.into_iter().filter(|p| p.is_available()) {
        with_path(path, || f(path));
    }
}

/// Puts a thread-local back when dropped.
struct Restore<T: Copy + 'static>(&'static std::thread::LocalKey<Cell<T>>, T);

impl<T: Copy + 'static> Drop for Restore<T> {
    fn drop(&mut self) {
        self.0.set(self.1);
    }
}

static MAX_THREADS: AtomicUsize = AtomicUsize::new(1);
static ACTIVE_LEARNERS: AtomicUsize = AtomicUsize::new(0);

/// The most threads one learner may use (default 1).
pub fn set_max_threads(n: usize) {
    MAX_THREADS.store(n.max(1), Ordering::Relaxed);
}

pub fn max_threads() -> usize {
    MAX_THREADS.load(Ordering::Relaxed)
}

static CORES: AtomicUsize = AtomicUsize::new(0);

/// The cores of this machine as the OS offers them to this process (asked once: asking reads
/// files, which allocates).
pub fn cores() -> usize {
    match CORES.load(Ordering::Relaxed) {
        0 => {
            let n = std::thread::available_parallelism().map_or(1, usize::from);
            CORES.store(n, Ordering::Relaxed);
            n
        }
        n => n,
    }
}

/// Marks a learner as training while it lives (the server holds one per running session), so
/// that learners training at once share the cores instead of each taking all of them.
pub struct ActiveLearner(());

impl ActiveLearner {
    pub fn register() -> Self {
        ACTIVE_LEARNERS.fetch_add(1, Ordering::Relaxed);
        ActiveLearner(())
    }
}

impl Drop for ActiveLearner {
    fn drop(&mut self) {
        ACTIVE_LEARNERS.fetch_sub(1, Ordering::Relaxed);
    }
}

/// Threads for the next product on this thread: its own choice ([`with_threads`]), else the
/// process maximum, at most the cores divided between the learners registered as active.
pub fn threads_now() -> usize {
    if let Some(n) = THREAD_THREADS.get() {
        return n;
    }
    let active = ACTIVE_LEARNERS.load(Ordering::Relaxed).max(1);
    max_threads().min((cores() / active).max(1))
}

/// Run `f` with this thread's products on `n` threads (restored afterwards).
pub fn with_threads<R>(n: usize, f: impl FnOnce() -> R) -> R {
    let _restore = Restore(&THREAD_THREADS, THREAD_THREADS.replace(Some(n.max(1))));
    f()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_nonsense_is_refused() {
        for p in KernelPath::ALL {
            assert_eq!(p.name().parse::<KernelPath>().unwrap(), p);
            assert_eq!(
                p.name().parse::<KernelChoice>().unwrap(),
                KernelChoice::Exactly(p)
            );
        }
        assert_eq!("auto".parse::<KernelChoice>().unwrap(), KernelChoice::Auto);
        assert_eq!(
            " sse".parse::<KernelPath>().unwrap_err().to_string(),
            r#"unknown kernels " sse": expected avx512, avx2 or portable"#
        );
        assert_eq!(
            " sse".parse::<KernelChoice>().unwrap_err().to_string(),
            r#"unknown kernels "sse": expected avx512, avx2 or portable or auto"#
        );
        assert!(KernelPath::Portable.is_available());
        assert!(KernelChoice::Auto.resolve().unwrap().is_available());
    }

    #[test]
    fn thread_choices_are_scoped() {
        let outside = current_path();
        with_path(KernelPath::Portable, || {
            assert_eq!(current_path(), KernelPath::Portable);
            with_threads(3, || assert_eq!(threads_now(), 3));
        });
        assert_eq!(current_path(), outside);
        assert_eq!(
            KernelPath::Avx2.numerics(),
            KernelPath::Avx512.numerics(),
            "the two fast paths give the same bits"
        );
    }
}
