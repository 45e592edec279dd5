//! The REST handlers through `app().oneshot(...)`: auth, launch validation, the error shape, and
//! a synthetic preference session from launch to export. The API's self-description (the
//! OpenAPI document and the README's list) is in `api_surface`.

use crate::support::rest::{call, poll_json};
use crate::support::server::{TOKEN, state, state_with};
use axum::http::StatusCode;
use dualrep::http::app;
use serde_json::{Value, json};

/// The session once it is neither queued nor running (a minute at most).
async fn settled(router: &axum::Router, id: &str) -> Value {
    let uri = format!("/api/sessions/{id}");
    poll_json(router, &uri, Some(TOKEN), |s| {
        s["status"] != "queued" && s["status"] != "running"
    })
    .await
}

#[tokio::test]
async fn researcher_routes_need_the_token_and_public_ones_do_not() {
    let dir = tempfile::tempdir().unwrap();
    let router = app(state(dir.path()).await);
    call(&router, "GET", "/api/sessions", None, None)
        .await
        .assert_error(StatusCode::UNAUTHORIZED, "unauthorized");
    call(&router, "GET", "/api/sessions", Some("wrong"), None)
        .await
        .assert_error(StatusCode::UNAUTHORIZED, "unauthorized");
    let ok = call(&router, "GET", "/api/sessions", Some(TOKEN), None).await;
    assert_eq!((ok.status, ok.json()), (StatusCode::OK, json!([])));
    let health = call(&router, "GET", "/healthz", None, None).await;
    assert_eq!(
        (health.status, health.json()["status"].clone()),
        (StatusCode::OK, json!("ok"))
    );
    let tasks = call(&router, "GET", "/api/tasks", None, None).await.json();
    let placing = tasks["tasks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == "placing")
        .unwrap();
    assert!(
        placing["predicates"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["label"].as_str().unwrap().contains("above hoop"))
    );
    call(&router, "GET", "/api/nothing-here", Some(TOKEN), None)
        .await
        .assert_error(StatusCode::NOT_FOUND, "not_found");
    call(&router, "GET", "/api/sessions/nope", Some(TOKEN), None)
        .await
        .assert_error(StatusCode::NOT_FOUND, "not_found");
}

#[tokio::test]
async fn bad_launch_requests_get_clear_errors_and_nothing_is_stored() {
    let dir = tempfile::tempdir().unwrap();
    let router = app(state(dir.path()).await);
    let post = |body: &'static str| {
        let router = router.clone();
        async move { call(&router, "POST", "/api/sessions", Some(TOKEN), Some(body)).await }
    };
    post("{not json")
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    post(r#"{"task":"reaching","method":"dref","trainer":"human","seed":"one"}"#)
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    post(r#"{"task":"mars","method":"dref","trainer":"human"}"#)
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    post(r#"{"task":"reaching","method":"magic","trainer":"human"}"#)
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    post(r#"{"task":"reaching","method":"dref","trainer":"robot"}"#)
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    post(r#"{"task":"reaching","method":"dref","trainer":"human","colour":"red"}"#)
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    post(r#"{"task":"reaching","method":"drpl","trainer":"human","steps":5}"#)
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    let r = post(r#"{"task":"reaching","method":"dref","trainer":"human","steps":0}"#).await;
    r.assert_error(StatusCode::UNPROCESSABLE_ENTITY, "invalid_session");
    let r =
        post(r#"{"task":"reaching","method":"dref","trainer":"human","params":{"hidden":"wide"}}"#)
            .await;
    r.assert_error(StatusCode::UNPROCESSABLE_ENTITY, "invalid_session");
    assert!(
        r.json()["error"]["message"]
            .as_str()
            .unwrap()
            .contains("hidden")
    );
    post(r#"{"task":"reaching","method":"dref","trainer":"human","params":{"pace_hz":0}}"#)
        .await
        .assert_error(StatusCode::UNPROCESSABLE_ENTITY, "invalid_session");
    // A NaN is not JSON: the error names the field it is in, not only a column.
    let r = post(
        r#"{"task":"reaching","method":"dref","trainer":"human","params":{"pace_hz":20,"c":NaN}}"#,
    )
    .await;
    r.assert_error(StatusCode::BAD_REQUEST, "bad_request");
    let message = r.json()["error"]["message"].as_str().unwrap().to_string();
    assert!(message.starts_with("field \"params.c\""), "{message}");
    assert!(message.contains("NaN"), "{message}");
    let r = post(r#"{"task":"reaching","method":"dref","trainer":"human","seed":"one"}"#).await;
    let message = r.json()["error"]["message"].as_str().unwrap().to_string();
    assert!(message.contains("\"seed\""), "{message}");
    // Oversized bodies are refused before parsing.
    let big = format!(
        r#"{{"task":"reaching","method":"dref","trainer":"human","params":{{"x":"{}"}}}}"#,
        "a".repeat(100_000)
    );
    call(&router, "POST", "/api/sessions", Some(TOKEN), Some(&big))
        .await
        .assert_error(StatusCode::PAYLOAD_TOO_LARGE, "payload_too_large");
    let list = call(&router, "GET", "/api/sessions", Some(TOKEN), None).await;
    assert_eq!(list.json(), json!([]));
}

#[tokio::test]
async fn a_synthetic_drpl_session_runs_to_its_end_and_exports() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let router = app(st);
    let r = call(
        &router,
        "POST",
        "/api/sessions",
        Some(TOKEN),
        Some(r#"{"task":"reaching","method":"drpl","trainer":"synthetic","seed":2,"queries":6,"params":{"trajectories":12}}"#),
    )
    .await;
    assert_eq!(
        r.status,
        StatusCode::CREATED,
        "{}",
        String::from_utf8_lossy(&r.body)
    );
    let created = r.json();
    let id = created["id"].as_str().unwrap().to_string();
    assert!(
        created["trainer_url"]
            .as_str()
            .unwrap()
            .starts_with(&format!("/train/{id}?token="))
    );
    let session = settled(&router, &id).await;
    assert_eq!(session["status"], "finished", "{session}");
    assert_eq!(session["progress"], 6);
    assert_eq!(session["unit"], "queries");
    assert_eq!(session["answers"]["total"], 6);
    assert!(session["latest"]["alignment"].as_f64().unwrap() > -1.0);
    let answers = call(
        &router,
        "GET",
        &format!("/api/sessions/{id}/answers"),
        Some(TOKEN),
        None,
    )
    .await
    .json();
    let answers = answers.as_array().unwrap();
    assert_eq!(answers.len(), 6);
    for (i, a) in answers.iter().enumerate() {
        // Queries are named by the session's query number.
        assert_eq!(a["query_id"], i);
        assert!(a.get("seq").is_none(), "one id per query: {a}");
        assert_eq!(a["kind"], "preference");
        assert_eq!(a["who"], "synthetic");
        assert!(["left", "right", "equal", "skip"].contains(&a["value"].as_str().unwrap()));
        for field in ["step", "answered_at", "latency_ms"] {
            assert!(!a[field].is_null(), "{field} missing in {a}");
        }
    }
    // The alignment curve: one point per answered query, the last one the session's latest.
    let curve = call(
        &router,
        "GET",
        &format!("/api/sessions/{id}/alignment"),
        Some(TOKEN),
        None,
    )
    .await
    .json();
    let curve = curve.as_array().unwrap();
    let queries: Vec<u64> = curve
        .iter()
        .map(|p| p["queries"].as_u64().unwrap())
        .collect();
    assert_eq!(queries, vec![1, 2, 3, 4, 5, 6]);
    assert_eq!(curve[5]["alignment"], session["latest"]["alignment"]);
    assert!(
        curve
            .iter()
            .all(|p| p["alignment_of_mean"].as_f64().unwrap().abs() <= 1.0)
    );
    let csv = call(
        &router,
        "GET",
        &format!("/api/sessions/{id}/export?format=csv"),
        Some(TOKEN),
        None,
    )
    .await;
    assert_eq!(csv.content_type, "text/csv");
    let text = String::from_utf8(csv.body).unwrap();
    assert_eq!(text.lines().count(), 7);
    assert!(text.starts_with("query_id,kind,step"));
    let jsonl = call(
        &router,
        "GET",
        &format!("/api/sessions/{id}/export?format=jsonl"),
        Some(TOKEN),
        None,
    )
    .await;
    let records: Vec<Value> = String::from_utf8(jsonl.body)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records[0]["record"], "session");
    assert_eq!(
        records.iter().filter(|r| r["record"] == "answer").count(),
        6
    );
    call(
        &router,
        "GET",
        &format!("/api/sessions/{id}/export?format=xml"),
        Some(TOKEN),
        None,
    )
    .await
    .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    // The trainer answers the three questions once the session has ended.
    let trainer_token = created["trainer_url"]
        .as_str()
        .unwrap()
        .split("token=")
        .nth(1)
        .unwrap()
        .to_string();
    let survey_uri = format!("/api/sessions/{id}/survey");
    let good = r#"{"overall_experience":4,"perceived_intelligence":3,"cognitive_ease":5}"#;
    call(&router, "POST", &survey_uri, Some("nope"), Some(good))
        .await
        .assert_error(StatusCode::FORBIDDEN, "forbidden");
    call(
        &router,
        "POST",
        &survey_uri,
        Some(&trainer_token),
        Some(r#"{"overall_experience":6,"perceived_intelligence":3,"cognitive_ease":5}"#),
    )
    .await
    .assert_error(StatusCode::BAD_REQUEST, "bad_request");
    let saved = call(
        &router,
        "POST",
        &survey_uri,
        Some(&trainer_token),
        Some(good),
    )
    .await;
    assert_eq!(saved.status, StatusCode::OK);
    assert_eq!(
        saved.json()["survey"],
        serde_json::from_str::<Value>(good).unwrap()
    );
    // A finished session cannot be stopped, and resumes only from interrupted/stopped/failed.
    call(
        &router,
        "POST",
        &format!("/api/sessions/{id}/stop"),
        Some(TOKEN),
        None,
    )
    .await
    .assert_error(StatusCode::CONFLICT, "conflict");
    call(
        &router,
        "POST",
        &format!("/api/sessions/{id}/resume"),
        Some(TOKEN),
        None,
    )
    .await
    .assert_error(StatusCode::CONFLICT, "conflict");
}

#[tokio::test]
async fn a_session_whose_thread_cannot_start_fails_and_can_be_resumed() {
    // A petabyte of stack is more than any machine maps: the real spawn fails.
    let dir = tempfile::tempdir().unwrap();
    let st = state_with(dir.path(), |c| c.session_stack_size = Some(1 << 50)).await;
    let router = app(st);
    let r = call(
        &router,
        "POST",
        "/api/sessions",
        Some(TOKEN),
        Some(r#"{"task":"reaching","method":"sac","trainer":"synthetic","steps":10}"#),
    )
    .await;
    assert_eq!(r.status, StatusCode::CREATED);
    let id = r.json()["id"].as_str().unwrap().to_string();
    let s = settled(&router, &id).await;
    assert_eq!(s["status"], "failed", "{s}");
    assert!(
        s.to_string().contains("thread could not start"),
        "the reason is kept: {s}"
    );
    // Not stuck in memory: a resume is accepted, and fails the same clear way.
    let resumed = call(
        &router,
        "POST",
        &format!("/api/sessions/{id}/resume"),
        Some(TOKEN),
        None,
    )
    .await;
    assert!(resumed.status.is_success(), "{}", resumed.status);
    assert_eq!(settled(&router, &id).await["status"], "failed");
}

#[tokio::test]
async fn a_session_launched_with_record_false_runs_and_writes_no_recording() {
    let dir = tempfile::tempdir().unwrap();
    let router = app(state(dir.path()).await);
    let r = call(
        &router,
        "POST",
        "/api/sessions",
        Some(TOKEN),
        Some(
            r#"{"task":"reaching","method":"sac","trainer":"synthetic","steps":50,"params":{"record":false}}"#,
        ),
    )
    .await;
    assert_eq!(
        r.status,
        StatusCode::CREATED,
        "{}",
        String::from_utf8_lossy(&r.body)
    );
    let id = r.json()["id"].as_str().unwrap().to_string();
    let s = settled(&router, &id).await;
    assert_eq!(s["status"], "finished", "{s}");
    assert_eq!(s["params"]["record"], false, "{s}");
    // The kernels it computed with are recorded at launch, for a resume to replay with.
    let kernels = s["params"]["kernels"].as_str().unwrap_or_default();
    assert!(["portable", "avx2", "avx512"].contains(&kernels), "{s}");
    assert!(
        !dir.path()
            .join("recordings")
            .join(format!("{id}.rrd"))
            .exists()
    );
    call(
        &router,
        "GET",
        &format!("/api/sessions/{id}/recording.rrd"),
        Some(TOKEN),
        None,
    )
    .await
    .assert_error(StatusCode::NOT_FOUND, "not_found");
}
