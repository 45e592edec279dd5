//! Why a command-line value does not parse: [`ArgError`], what clap prints after "invalid value
//! ... for '--flag'".

/// A command-line value that does not read (the value as given).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ArgError {
    /// `--betas`: neither a number >= 0 nor `rational`.
    #[error("{0:?}: expected a rationality >= 0 or `rational`")]
    Beta(String),
    /// `--acquisition`.
    #[error("unknown acquisition {0:?}: expected uniform or mutual-information")]
    Acquisition(String),
    /// `--set` without `=`.
    #[error("expected key=value, got {0:?}")]
    NotAPair(String),
    /// `--set` with nothing before `=`.
    #[error("empty key in {0:?}")]
    EmptyKey(String),
}
