//! JSON from clients (REST bodies, websocket messages), read with errors that say *where* it
//! went wrong. serde_json alone says "expected value at line 1 column 122" for a `NaN`, which
//! leaves a person counting characters; here every error names the field it is in
//! (`params.hidden[1]`), and a NaN or an infinity is called what it is.

use serde::de::DeserializeOwned;

/// Why a client's JSON was refused; the text names the field.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum JsonInputError {
    /// Not JSON at all (a `NaN`, a missing quote, a cut-off body).
    #[error("{0}")]
    Syntax(String),
    /// JSON, but not the shape expected (a wrong type, an unknown or missing field).
    #[error("{0}")]
    Shape(String),
}

/// Parse `text` as a `T`.
pub fn from_str<T: DeserializeOwned>(text: &str) -> Result<T, JsonInputError> {
    let mut de = serde_json::Deserializer::from_str(text);
    let value = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| refusal(text, e.path().to_string(), e.into_inner()))?;
    de.end().map_err(|e| refusal(text, String::from("."), e))?;
    Ok(value)
}

/// [`from_str`] on bytes (a request body).
pub fn from_slice<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, JsonInputError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        JsonInputError::Syntax(format!(
            "the body is not UTF-8 text (byte {} is not), so not JSON",
            e.valid_up_to()
        ))
    })?;
    from_str(text)
}

/// [`from_str`] on JSON already parsed (a message whose other fields were read first).
pub fn from_value<T: DeserializeOwned>(value: serde_json::Value) -> Result<T, JsonInputError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        JsonInputError::Shape(format!("{}: {}", field_name(&path), e.into_inner()))
    })
}

fn refusal(text: &str, path: String, e: serde_json::Error) -> JsonInputError {
    use serde_json::error::Category;
    match e.classify() {
        Category::Syntax | Category::Eof | Category::Io => {
            // The path serde tracked stops where buffering began (tagged enums); the text
            // itself says which field the bad character is in.
            let offset = byte_offset(text, e.line(), e.column());
            let path = path_at(text, offset);
            let found = text[offset.min(text.len())..].trim_start();
            let hint = if ["NaN", "nan", "Infinity", "-Infinity", "inf", "-inf"]
                .iter()
                .any(|t| found.starts_with(t))
            {
                " (NaN and infinities are not JSON numbers: send a finite number)".to_string()
            } else if e.to_string().starts_with("number out of range") {
                " (a number too large for a 64-bit float: send a finite number)".to_string()
            } else {
                let near: String = found.chars().take(16).collect();
                if near.is_empty() {
                    String::new()
                } else {
                    format!(" (near {near:?})")
                }
            };
            JsonInputError::Syntax(format!("{}: not valid JSON: {e}{hint}", field_name(&path)))
        }
        Category::Data => JsonInputError::Shape(format!("{}: {e}", field_name(&path))),
    }
}

/// `field "params.c"`, or `the message` for the whole document.
fn field_name(path: &str) -> String {
    if path.is_empty() || path == "." {
        "the message".to_string()
    } else {
        format!("field \"{path}\"")
    }
}

/// The byte offset of serde_json's 1-based (line, column); clamped to the text.
fn byte_offset(text: &str, line: usize, column: usize) -> usize {
    let line_start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    // serde_json counts columns in bytes, and an error can point into a character of more
    // than one byte; slicing there would panic, so step back to the character's start.
    let mut offset = (line_start + column.saturating_sub(1)).min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

/// The path of the value that `text[offset..]` is in, as `a.b[2].c` ("" at the top), read
/// from `text[..offset]`: which objects and arrays are open there, under which keys.
pub fn path_at(text: &str, offset: usize) -> String {
    enum Open {
        Object { key: Option<String> },
        Array { index: usize },
    }
    let mut open: Vec<Open> = Vec::new();
    let (mut in_string, mut escaped) = (false, false);
    let mut string = String::new();
    let mut last_string: Option<String> = None;
    let prefix = text.get(..offset).unwrap_or(text);
    for c in prefix.chars() {
        if in_string {
            match c {
                _ if escaped => {
                    escaped = false;
                    string.push(c);
                }
                '\\' => escaped = true,
                '"' => {
                    in_string = false;
                    last_string = Some(std::mem::take(&mut string));
                }
                _ => string.push(c),
            }
            continue;
        }
        match c {
            '"' => in_string = true,
            '{' => open.push(Open::Object { key: None }),
            '[' => open.push(Open::Array { index: 0 }),
            '}' | ']' => {
                open.pop();
            }
            ':' => {
                if let Some(Open::Object { key }) = open.last_mut() {
                    *key = last_string.take();
                }
            }
            ',' => match open.last_mut() {
                Some(Open::Array { index }) => *index += 1,
                Some(Open::Object { key }) => *key = None,
                None => {}
            },
            _ => {}
        }
    }
    let mut path = String::new();
    for o in &open {
        match o {
            Open::Object { key: Some(k) } => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(k);
            }
            // Between members (a bad key): the object itself.
            Open::Object { key: None } => break,
            Open::Array { index } => path.push_str(&format!("[{index}]")),
        }
    }
    path
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)] // read by serde only
    struct Launch {
        task: String,
        params: std::collections::BTreeMap<String, serde_json::Value>,
    }

    #[test]
    fn a_nan_is_named_with_its_field() {
        let text = r#"{"task": "reaching", "params": {"hidden": [64, NaN], "c": 0.2}}"#;
        let e = from_str::<Launch>(text).unwrap_err();
        let JsonInputError::Syntax(m) = e else {
            panic!("{e:?}")
        };
        assert!(
            m.starts_with("field \"params.hidden[1]\": not valid JSON"),
            "{m}"
        );
        assert!(m.contains("NaN and infinities are not JSON numbers"), "{m}");
    }

    #[test]
    fn a_wrong_type_and_an_unknown_field_are_named() {
        let e = from_str::<Launch>(r#"{"task": 3, "params": {}}"#).unwrap_err();
        assert!(
            matches!(&e, JsonInputError::Shape(m) if m.starts_with("field \"task\": invalid type")),
            "{e:?}"
        );
        let e = from_str::<Launch>(r#"{"task": "x", "params": {}, "tsak": 1}"#).unwrap_err();
        assert!(e.to_string().contains("tsak"), "{e}");
    }

    #[test]
    fn paths_follow_objects_arrays_and_strings_with_brackets() {
        let text = r#"{"a": {"b": [1, {"c": "]{,"}, 3]}, "d": "#;
        assert_eq!(path_at(text, text.len()), "d");
        let inner = text.find("3]").unwrap();
        assert_eq!(path_at(text, inner), "a.b[2]");
        assert_eq!(path_at("", 0), "");
    }

    #[test]
    fn trailing_text_and_cut_off_bodies_are_refused() {
        assert!(matches!(
            from_str::<Launch>(r#"{"task": "x", "params": {}} x"#),
            Err(JsonInputError::Syntax(_))
        ));
        let e = from_str::<Launch>(r#"{"task": "x", "params": {"c": "#).unwrap_err();
        assert!(e.to_string().starts_with("field \"params.c\""), "{e}");
    }

    #[test]
    fn an_error_inside_a_character_of_several_bytes_is_refused_not_a_panic() {
        // Found by protocol's property test: serde_json's byte column points into `¡`.
        for text in [
            "\"\u{a1}",
            "{\"task\": \"\u{a1}",
            "\u{a1}",
            "[\"\u{1F916}\"",
            "{\"\u{e9}\u{e9}\": 1,",
        ] {
            assert!(from_str::<Launch>(text).is_err(), "{text:?}");
        }
    }
}
