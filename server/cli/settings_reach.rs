//! Every key a settings section declares reaches every door by itself: `GET /api/tasks` (and so
//! the dashboard's advanced form, which lists that object's keys), `--set` and TOML. The keys
//! are read from the sections' structs, so a setting added to a section is checked here with no
//! other edit, and one its section does not offer fails.
//!
//! It lives in `cli`, which sits above both `settings` and `http`: a test inside `settings`
//! that read `http` and `cli` would tie the modules into a cycle.

use serde_json::{Value, json};

use super::overrides::read_toml;
use crate::http::tasks::describe;
use crate::settings::Settings;

/// Settings with no default to offer (the server's own applies), and a value to give them.
const NOT_OFFERED: [(&str, &str); 2] = [
    ("rerun_connect", "rerun+http://127.0.0.1:9876/proxy"),
    ("kernels", "portable"),
];

/// The first value `GET /api/tasks` offers for `key`, over every task and family.
fn offered(key: &str) -> Option<Value> {
    let tasks = describe();
    tasks["tasks"].as_array()?.iter().find_map(|task| {
        ["evaluative", "preference"]
            .into_iter()
            .find_map(|family| task["settings"][family].get(key).cloned())
    })
}

#[test]
fn every_key_is_offered_and_reads_from_set_and_toml() {
    let keys = Settings::keys();
    assert!(keys.len() >= 60, "{} keys", keys.len());
    let dir = tempfile::tempdir().unwrap();
    for key in keys {
        let value = match NOT_OFFERED.iter().find(|(k, _)| k == key) {
            Some((_, v)) => Value::String(v.to_string()),
            None => offered(key).unwrap_or_else(|| panic!("GET /api/tasks offers no {key}")),
        };
        let expected = json!({ *key: value });
        // --set key=value, as a person types it.
        let text = match &value {
            Value::String(s) => s.clone(),
            other => other.to_string(),
        };
        let set = Settings::from_pairs([(*key, text.as_str())])
            .unwrap_or_else(|e| panic!("--set {key}={text}: {e}"));
        assert_eq!(serde_json::to_value(&set).unwrap(), expected, "--set {key}");
        // A TOML file's `key = value` line.
        let path = dir.path().join("run.toml");
        let line = toml::Value::try_from(&value).unwrap();
        std::fs::write(&path, format!("{key} = {line}\n")).unwrap();
        let file = read_toml(&path).unwrap_or_else(|e| panic!("TOML {key}: {e:#}"));
        assert_eq!(file, set, "TOML {key}");
        // A launch request's params.
        assert_eq!(
            Settings::from_json(expected.clone()).unwrap(),
            set,
            "params {key}"
        );
    }
}
