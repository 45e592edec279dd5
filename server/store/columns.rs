//! The closed sets stored as text columns (`queries.kind`, `answers.who`, `sessions.status`,
//! `trainers.origin`),
//! bound and read as their enums: a value outside the set is an error where it is read, not a
//! string passed along.

use sqlx::Sqlite;
use sqlx::encode::IsNull;
use sqlx::error::BoxDynError;
use sqlx::sqlite::{SqliteArgumentsBuffer, SqliteTypeInfo, SqliteValueRef};

use super::{Status, TrainerOrigin};
use crate::session::{Answerer, QueryKind};

/// `sqlx::Type`, `Encode` and `Decode` for an enum with `as_str` and `parse`, as TEXT.
macro_rules! text_column {
    ($($t:ty),* $(,)?) => {$(
        impl sqlx::Type<Sqlite> for $t {
            fn type_info() -> SqliteTypeInfo {
                <str as sqlx::Type<Sqlite>>::type_info()
            }
        }

        impl sqlx::Encode<'_, Sqlite> for $t {
            fn encode_by_ref(&self, args: &mut SqliteArgumentsBuffer) -> Result<IsNull, BoxDynError> {
                <&str as sqlx::Encode<'_, Sqlite>>::encode_by_ref(&self.as_str(), args)
            }
        }

        impl<'r> sqlx::Decode<'r, Sqlite> for $t {
            fn decode(value: SqliteValueRef<'r>) -> Result<Self, BoxDynError> {
                let text = <&str as sqlx::Decode<'r, Sqlite>>::decode(value)?;
                <$t>::parse(text)
                    .ok_or_else(|| format!("{text:?} is not a {}", stringify!($t)).into())
            }
        }
    )*};
}

text_column!(QueryKind, Answerer, Status, TrainerOrigin);
