//! The API's surface pinned: every operation is in the served OpenAPI document (and nothing
//! else is), in the README, routed, and public or behind the researcher's token as documented.

use crate::support::rest::call;
use crate::support::server::{TOKEN, state};
use axum::http::StatusCode;
use dualrep::http::{app, openapi};
use serde_json::{Value, json};

/// The API's operations: the document is generated from the router, so this pins the surface.
const OPERATIONS: [(&str, &str); 33] = [
    ("post", "/api/sessions"),
    ("get", "/api/sessions"),
    ("get", "/api/sessions/{id}"),
    ("post", "/api/sessions/{id}/stop"),
    ("post", "/api/sessions/{id}/resume"),
    ("get", "/api/sessions/{id}/episodes"),
    ("get", "/api/sessions/{id}/episodes/{episode}/frames"),
    ("get", "/api/sessions/{id}/answers"),
    ("get", "/api/sessions/{id}/alignment"),
    ("get", "/api/sessions/{id}/export"),
    ("get", "/api/sessions/{id}/recording.rrd"),
    ("post", "/api/sessions/{id}/survey"),
    ("post", "/api/sessions/{id}/trainers"),
    ("get", "/api/sessions/{id}/trainers"),
    ("post", "/api/sessions/{id}/join"),
    ("get", "/api/sessions/{id}/agreement"),
    ("get", "/api/sessions/{id}/dataset.parquet"),
    ("get", "/api/sessions/{id}/posterior.safetensors"),
    ("get", "/api/sessions/{id}/policy.safetensors"),
    ("post", "/api/studies"),
    ("get", "/api/studies"),
    ("get", "/api/studies/{id}"),
    ("get", "/api/studies/{id}/results"),
    ("get", "/api/studies/{id}/table"),
    ("post", "/api/study-links/{link}/participants"),
    ("get", "/api/study-links/{link}/participants/{token}"),
    (
        "post",
        "/api/study-links/{link}/participants/{token}/consent",
    ),
    ("post", "/api/study-links/{link}/participants/{token}/start"),
    (
        "post",
        "/api/study-links/{link}/participants/{token}/survey",
    ),
    ("get", "/api/tasks"),
    ("get", "/api/openapi.json"),
    ("get", "/healthz"),
    ("get", "/ws/sessions/{id}"),
];

/// The README's list of the API names every operation, so that a route cannot go undocumented.
#[test]
fn the_readme_lists_every_operation() {
    let readme = std::fs::read_to_string(crate::support::server::root().join("README.md")).unwrap();
    let missing: Vec<String> = OPERATIONS
        .iter()
        .map(|(method, path)| format!("`{} {path}`", method.to_uppercase()))
        .filter(|op| !readme.contains(op.as_str()))
        .collect();
    assert!(missing.is_empty(), "README.md does not list {missing:?}");
}

/// Every `$ref` in `v`.
fn refs(v: &Value, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            if let Some(Value::String(r)) = m.get("$ref") {
                out.push(r.clone());
            }
            m.values().for_each(|x| refs(x, out));
        }
        Value::Array(a) => a.iter().for_each(|x| refs(x, out)),
        _ => {}
    }
}

#[tokio::test]
async fn the_openapi_document_lists_exactly_the_routes() {
    let dir = tempfile::tempdir().unwrap();
    let router = app(state(dir.path()).await);
    // The served document is the generated one.
    let served = call(&router, "GET", "/api/openapi.json", None, None).await;
    assert_eq!(served.status, StatusCode::OK);
    let doc = served.json();
    assert_eq!(doc, openapi::document());
    assert_eq!(doc["openapi"], "3.1.0");
    let paths = doc["paths"].as_object().unwrap();
    for (method, path) in OPERATIONS {
        assert!(
            paths.get(path).and_then(|p| p.get(method)).is_some(),
            "{method} {path} undocumented"
        );
    }
    let documented: usize = paths
        .values()
        .map(|p| {
            p.as_object()
                .unwrap()
                .keys()
                .filter(|k| *k != "parameters")
                .count()
        })
        .sum();
    assert_eq!(documented, OPERATIONS.len());
    // Every schema a route names is in the document; the launch request's params are the one
    // settings list.
    let mut named = Vec::new();
    refs(&doc, &mut named);
    for r in &named {
        let name = r.trim_start_matches("#/components/schemas/");
        assert!(
            doc["components"]["schemas"].get(name).is_some(),
            "{r} is not in the document"
        );
    }
    let schemas = &doc["components"]["schemas"];
    assert!(schemas["Settings"]["properties"]["pace_hz"].is_object());
    assert!(schemas["LaunchRequest"].to_string().contains("Settings"));
    // An episode row's feedback and cumulative return are totals over the session so far.
    for field in ["cumulative_return", "feedback_count", "feedback_fraction"] {
        let about = schemas["EpisodeRow"]["properties"][field]["description"]
            .as_str()
            .unwrap_or_default();
        assert!(about.starts_with("A running total"), "{field}: {about:?}");
    }
    // Public routes need no token; the others take the researcher's bearer token.
    for (method, path) in OPERATIONS {
        let public = paths[path][method]["security"] == json!([{}]);
        let expect_public = matches!(
            path,
            "/api/tasks" | "/api/openapi.json" | "/healthz" | "/ws/sessions/{id}"
        ) || path.starts_with("/api/study-links/");
        assert_eq!(public, expect_public, "{method} {path}");
    }
    // Every documented route answers something other than the API's 404.
    for (method, path) in OPERATIONS {
        let uri = path
            .replace("{id}", "nosuch")
            .replace("{episode}", "0")
            .replace("{link}", "nosuch")
            .replace("{token}", "nosuch");
        let r = call(&router, &method.to_uppercase(), &uri, Some(TOKEN), None).await;
        let unrouted = r.status == StatusCode::NOT_FOUND
            && r.json()["error"]["message"]
                .as_str()
                .unwrap()
                .contains("no such API route");
        assert!(!unrouted, "{method} {path} is documented but not routed");
    }
}
