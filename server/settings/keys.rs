//! The keys of a section, read from its struct (so that no list of names is typed by hand),
//! and reading a section out of the one flat object of settings.

use serde::Serialize;
use serde::de::{self, Deserialize, DeserializeOwned, Deserializer, Visitor};

use super::SettingsError;

/// The keys a section reads, in its fields' order: the names serde's derive passes to
/// `deserialize_struct`, caught by a deserializer that only listens.
pub(super) fn of<'de, T: Deserialize<'de>>() -> &'static [&'static str] {
    struct Listener<'a>(&'a mut &'static [&'static str]);

    impl<'de> Deserializer<'de> for Listener<'_> {
        type Error = de::value::Error;

        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
            Err(de::Error::custom("a section is a struct"))
        }

        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _name: &'static str,
            fields: &'static [&'static str],
            _visitor: V,
        ) -> Result<V::Value, Self::Error> {
            *self.0 = fields;
            Err(de::Error::custom("only listening"))
        }

        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes
            byte_buf option unit unit_struct newtype_struct seq tuple tuple_struct map enum
            identifier ignored_any
        }
    }

    let mut fields: &'static [&'static str] = &[];
    let _ = T::deserialize(Listener(&mut fields));
    fields
}

/// The keys of `section` that are set (given, not `None`), in its fields' order.
pub(super) fn set<T: Serialize + for<'de> Deserialize<'de>>(section: &T) -> Vec<&'static str> {
    let given = serde_json::to_value(section).unwrap_or_default();
    of::<T>()
        .iter()
        .copied()
        .filter(|k| given.get(k).is_some())
        .collect()
}

/// The first key of `section` that is set: what a family check names.
pub(super) fn first_set<T: Serialize + for<'de> Deserialize<'de>>(
    section: &T,
) -> Option<&'static str> {
    set(section).into_iter().next()
}

/// Refuses a key no section reads, as serde would: named, with the list of known keys.
pub(super) fn refuse_unknown(
    map: &serde_json::Map<String, serde_json::Value>,
    known: &'static [&'static str],
) -> Result<(), SettingsError> {
    match map.keys().find(|k| !known.contains(&k.as_str())) {
        None => Ok(()),
        Some(key) => Err(SettingsError::UnknownKey {
            key: key.clone(),
            known,
        }),
    }
}

/// A section out of the flat object of every setting (it skips the other sections' keys); a
/// value's error names its key.
pub(super) fn read<T: DeserializeOwned>(object: &serde_json::Value) -> Result<T, SettingsError> {
    serde_path_to_error::deserialize(object).map_err(|e| {
        let path = e.path().to_string();
        SettingsError::Unreadable {
            key: (path != ".").then_some(path),
            reason: e.into_inner().to_string(),
        }
    })
}

/// How serde names a value of the wrong type (`integer `3``).
pub(super) fn unexpected(value: &serde_json::Value) -> String {
    use serde_json::Value;
    match value {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("boolean `{b}`"),
        Value::Number(n) if n.is_f64() => format!("floating point `{n}`"),
        Value::Number(n) => format!("integer `{n}`"),
        Value::String(s) => format!("string {s:?}"),
        Value::Array(_) => "sequence".into(),
        Value::Object(_) => "map".into(),
    }
}
