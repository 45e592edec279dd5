//! The store's tests on both databases: each test body runs on SQLite (a file in a temporary
//! data dir, as `dualrep serve` opens it) and on PostgreSQL (a fresh database on the tests'
//! throwaway cluster, `support::postgres`).

use dualrep::store::{NewSession, Store};

/// Each test body, as `sqlite::<name>` and `postgres::<name>`.
macro_rules! on_both {
    ($($name:ident),* $(,)?) => {
        mod sqlite {
            $(
                #[tokio::test]
                async fn $name() {
                    let dir = tempfile::tempdir().unwrap();
                    super::$name(dualrep::store::Store::open(dir.path()).await.unwrap()).await;
                }
            )*
        }
        mod postgres {
            $(
                #[tokio::test]
                async fn $name() {
                    let Some(db) = crate::support::postgres::database().await else {
                        return;
                    };
                    super::$name(dualrep::store::Store::connect(&db.url).await.unwrap()).await;
                }
            )*
        }
    };
}

pub(crate) use on_both;

/// `store` with one human DREF session on Reaching, `id`.
pub async fn store_with_session(store: Store, id: &str) -> Store {
    store
        .insert_session(NewSession {
            id,
            task: "reaching",
            method: "dref",
            trainer: "human",
            seed: 3,
            budget: 100,
            config: &serde_json::json!({"task": "reaching"}),
            trainer_token: "tok",
        })
        .await
        .unwrap();
    store
}
