//! The closed sets stored as text columns (`queries.kind`, `answers.who`, `sessions.status`,
//! `trainers.origin`), bound and read as their enums on either database: a value outside the
//! set is an error where it is read, not a string passed along.

use sqlx::encode::IsNull;
use sqlx::error::BoxDynError;
use sqlx::postgres::{PgArgumentBuffer, PgTypeInfo, PgValueRef};
use sqlx::sqlite::{SqliteArgumentsBuffer, SqliteTypeInfo, SqliteValueRef};
use sqlx::{Postgres, Sqlite};

use super::{Status, TrainerOrigin};
use crate::session::{Answerer, QueryKind};

/// `sqlx::Type`, `Encode` and `Decode` for an enum with `as_str` and `parse`, as text, for the
/// database `$db` (its type info, argument buffer and value types).
macro_rules! text_column {
    ($db:ty, $info:ty, $buffer:ty, $value:ident; $($t:ty),* $(,)?) => {$(
        impl sqlx::Type<$db> for $t {
            fn type_info() -> $info {
                <str as sqlx::Type<$db>>::type_info()
            }
        }

        impl sqlx::Encode<'_, $db> for $t {
            fn encode_by_ref(&self, buf: &mut $buffer) -> Result<IsNull, BoxDynError> {
                <&str as sqlx::Encode<'_, $db>>::encode_by_ref(&self.as_str(), buf)
            }
        }

        impl<'r> sqlx::Decode<'r, $db> for $t {
            fn decode(value: $value<'r>) -> Result<Self, BoxDynError> {
                let text = <&str as sqlx::Decode<'r, $db>>::decode(value)?;
                <$t>::parse(text)
                    .ok_or_else(|| format!("{text:?} is not a {}", stringify!($t)).into())
            }
        }
    )*};
}

text_column!(Sqlite, SqliteTypeInfo, SqliteArgumentsBuffer, SqliteValueRef;
    QueryKind, Answerer, Status, TrainerOrigin);
text_column!(Postgres, PgTypeInfo, PgArgumentBuffer, PgValueRef;
    QueryKind, Answerer, Status, TrainerOrigin);
