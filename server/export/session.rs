//! A stored session's datasets, read from the store and the data dir: what `GET
//! .../dataset.parquet`, `.../posterior.safetensors`, `.../policy.safetensors` and `dualrep
//! export` return.

use std::path::Path;

use super::policy::{PolicyError, policy_safetensors};
use super::tables::{self, TableError};
use crate::session::QueryKind;
use crate::store::{SessionRow, Store};

/// What a session export can ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Dataset {
    /// Labelled transitions (evaluative sessions) or preference pairs, as Parquet.
    Table,
    /// A preference session's posterior (samples and mean theta), safetensors.
    Posterior,
    /// An evaluative session's policy weights (the actor), safetensors.
    Policy,
}

/// Why an export has nothing to give.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The session has no such thing (a posterior of an evaluative session, no checkpoint).
    #[error("{0}")]
    Missing(String),
    #[error(transparent)]
    Store(#[from] sqlx::Error),
    /// The dataset's table could not be written.
    #[error("{0}")]
    Table(#[from] TableError),
    /// The learner checkpoint gives no policy file.
    #[error("{0}")]
    Policy(#[from] PolicyError),
}

/// The file name an export of `session` goes by.
pub fn file_name(session: &SessionRow, what: Dataset) -> String {
    let kind = query_kind(session);
    match (what, kind) {
        (Dataset::Table, QueryKind::Evaluative) => {
            format!("dualrep-{}-transitions.parquet", session.id)
        }
        (Dataset::Table, QueryKind::Preference) => format!("dualrep-{}-pairs.parquet", session.id),
        (Dataset::Posterior, _) => format!("dualrep-{}-posterior.safetensors", session.id),
        (Dataset::Policy, _) => format!("dualrep-{}-policy.safetensors", session.id),
    }
}

fn query_kind(session: &SessionRow) -> QueryKind {
    session
        .spec()
        .map_or(QueryKind::Evaluative, |s| s.method.query_kind())
}

/// The bytes of `what` for `session`, whose files are under `data_dir`.
pub async fn export(
    store: &Store,
    data_dir: &Path,
    session: &SessionRow,
    what: Dataset,
) -> Result<Vec<u8>, ExportError> {
    let kind = query_kind(session);
    let id = &session.id;
    match what {
        Dataset::Table => {
            let rows = store.dataset_rows(id).await?;
            let people = store.person_answers(id).await?;
            let trainers = store.trainers(id).await?;
            let table = match kind {
                QueryKind::Evaluative => tables::transitions(&rows, &people, &trainers),
                QueryKind::Preference => tables::pairs(&rows, &people, &trainers),
            };
            Ok(table?)
        }
        Dataset::Posterior | Dataset::Policy => {
            let wanted = match what {
                Dataset::Posterior => QueryKind::Preference,
                _ => QueryKind::Evaluative,
            };
            if kind != wanted {
                return Err(ExportError::Missing(format!(
                    "session {id} is a {} session: {} ",
                    kind.as_str(),
                    match kind {
                        QueryKind::Evaluative =>
                            "it has a policy (policy.safetensors), not a posterior",
                        QueryKind::Preference =>
                            "it has a posterior (posterior.safetensors), not a policy",
                    }
                )));
            }
            let file = store
                .latest_checkpoint(id)
                .await?
                .and_then(|c| c.file)
                .ok_or_else(|| {
                    ExportError::Missing(format!(
                        "session {id} has no checkpoint yet (one is taken every checkpoint_every steps, and when a session ends)"
                    ))
                })?;
            let bytes = tokio::fs::read(data_dir.join(&file))
                .await
                .map_err(|e| ExportError::Missing(format!("{file}: {e}")))?;
            match what {
                Dataset::Policy => Ok(policy_safetensors(&bytes)?),
                _ => Ok(bytes),
            }
        }
    }
}
