//! Studies over REST: a researcher creates one; participants join its one link, get their
//! Williams order, consent, train each condition (human sessions nobody answers: each query
//! times out as no feedback), answer the survey after each; bad input is refused by name and
//! loses nothing; results and the tidy table count every participant × condition.

use crate::support::binary::start_serve;
use crate::support::cli::{dualrep_in, refused};
use crate::support::pyarrow_py::read_parquet;
use crate::support::rest::{Reply, call, poll_json};
use crate::support::server::{TOKEN, state};
use axum::http::StatusCode;
use dualrep::http::app;
use dualrep::study::{Ordering, StudyDesign};
use serde_json::{Value, json};

fn study_body(title: &str) -> Value {
    // Fast human sessions: 1,000 steps a second, queries that time out in 20 ms.
    let fast = json!({"pace_hz": 1000, "answer_timeout_s": 0.02, "record": false});
    json!({
        "title": title,
        "conditions": [
            {"name": "ef-100", "task": "reaching", "method": "ef-100", "params": fast},
            {"name": "sac", "task": "reaching", "method": "sac", "params": fast},
            {"name": "ef-50", "task": "reaching", "method": "ef-50", "params": fast}
        ],
        "budget": {"steps": 120},
        "survey": [
            {"id": "E", "text": "Good experience", "points": 5},
            {"id": "trust", "text": "I trust it", "points": 7}
        ]
    })
}

async fn create(router: &axum::Router, title: &str) -> Value {
    let r = call(
        router,
        "POST",
        "/api/studies",
        Some(TOKEN),
        Some(&study_body(title).to_string()),
    )
    .await;
    assert_eq!(
        r.status,
        StatusCode::CREATED,
        "{}",
        String::from_utf8_lossy(&r.body)
    );
    r.json()
}

fn link_token(study: &Value) -> String {
    study["link"]
        .as_str()
        .unwrap()
        .trim_start_matches("/study/")
        .to_string()
}

fn participant_token(view: &Value) -> String {
    let url = view["url"].as_str().unwrap();
    url.split("participant=").nth(1).unwrap().to_string()
}

async fn post(router: &axum::Router, uri: &str, body: Option<Value>) -> Reply {
    let body = body.map(|b| b.to_string());
    call(router, "POST", uri, None, body.as_deref()).await
}

/// The participant's view once their step is no longer `training` (a minute at most).
async fn until_survey(router: &axum::Router, base: &str) -> Value {
    poll_json(router, base, None, |v| v["step"]["step"] != "training").await
}

/// A researcher's GET of the study's `path` (after `/api/studies/{id}`).
async fn of_study(router: &axum::Router, study: &Value, path: &str) -> Reply {
    let uri = format!("/api/studies/{}{path}", study["id"].as_str().unwrap());
    call(router, "GET", &uri, Some(TOKEN), None).await
}

#[tokio::test]
async fn participants_follow_their_williams_order_and_the_results_count_each_of_them() {
    let dir = tempfile::tempdir().unwrap();
    let router = app(state(dir.path()).await);
    let study = create(&router, "Reaching with people").await;
    let other = create(&router, "Another study").await;
    let link = link_token(&study);
    let design = StudyDesign {
        conditions: vec!["ef-100".into(), "sac".into(), "ef-50".into()],
        ordering: Ordering::Williams,
        seed: 0,
    };

    let mut participants = Vec::new();
    for number in 0..3 {
        let r = post(
            &router,
            &format!("/api/study-links/{link}/participants"),
            None,
        )
        .await;
        assert_eq!(r.status, StatusCode::CREATED);
        let v = r.json();
        assert_eq!(v["step"]["step"], "consent");
        let order: Vec<String> = serde_json::from_value(v["ordering"].clone()).unwrap();
        assert_eq!(order, design.order_for(number), "participant {number}");
        participants.push((participant_token(&v), order));
    }

    // A token used with another study's link is refused, and nothing moves.
    let (token0, _) = &participants[0];
    let wrong = format!(
        "/api/study-links/{}/participants/{token0}",
        link_token(&other)
    );
    call(&router, "GET", &wrong, None, None)
        .await
        .assert_error(StatusCode::FORBIDDEN, "forbidden");

    // Participants 0 and 1 go through every condition; participant 2 abandons after starting
    // their first.
    for (i, (token, order)) in participants.iter().enumerate() {
        let base = format!("/api/study-links/{link}/participants/{token}");
        post(&router, &format!("{base}/start"), None)
            .await
            .assert_error(StatusCode::CONFLICT, "conflict");
        let v = post(&router, &format!("{base}/consent"), None).await.json();
        assert_eq!(v["step"], json!({"step": "ready", "position": 0}));
        let rounds = if i == 2 { 1 } else { order.len() };
        for (position, condition) in order.iter().enumerate().take(rounds) {
            let v = post(&router, &format!("{base}/start"), None).await.json();
            assert_eq!(v["step"]["step"], "training", "{v}");
            assert_eq!(v["step"]["position"], position);
            // A reload mid-condition (or a second click) continues the same session.
            let again = post(&router, &format!("{base}/start"), None).await.json();
            assert_eq!(again["step"]["session_id"], v["step"]["session_id"]);
            if i == 2 {
                break;
            }
            let v = until_survey(&router, &base).await;
            assert_eq!(v["step"]["step"], "survey", "{v}");
            assert_eq!(v["step"]["ended_early"], false);
            // Bad answers are refused by name; nothing is stored.
            let bad = [
                (
                    json!({"condition": condition, "answers": {"E": 6, "trust": 3}}),
                    "answers.E: must be 1 to 5, got 6",
                ),
                (
                    json!({"condition": condition, "answers": {"E": 3}}),
                    "answers.trust: missing",
                ),
                (
                    json!({"condition": "nope", "answers": {"E": 3, "trust": 3}}),
                    "condition: \"nope\" is not a condition of this study",
                ),
                (
                    json!({"condition": condition, "answers": {"E": 3, "trust": 3, "x": 1}}),
                    "answers.x: not a question",
                ),
            ];
            for (body, message) in bad {
                let r = post(&router, &format!("{base}/survey"), Some(body)).await;
                r.assert_error(StatusCode::BAD_REQUEST, "bad_request");
                let text = r.json()["error"]["message"].as_str().unwrap().to_string();
                assert!(text.starts_with(message), "{text}");
            }
            let next = order.get(position + 1).cloned();
            let other_condition = order.iter().find(|c| *c != condition).unwrap();
            post(
                &router,
                &format!("{base}/survey"),
                Some(json!({"condition": other_condition, "answers": {"E": 3, "trust": 3}})),
            )
            .await
            .assert_error(StatusCode::CONFLICT, "conflict");
            let v = post(
                &router,
                &format!("{base}/survey"),
                Some(json!({"condition": condition, "answers": {"E": 1 + i as i64, "trust": 7}})),
            )
            .await
            .json();
            match next {
                Some(_) => assert_eq!(
                    v["step"],
                    json!({"step": "ready", "position": position + 1})
                ),
                None => assert_eq!(v["step"], json!({"step": "done"})),
            }
        }
    }

    let detail = of_study(&router, &study, "").await.json();
    assert_eq!(detail["participants"], 3);
    assert_eq!(detail["participants_detail"][2]["step"]["step"], "training");

    let results = of_study(&router, &study, "/results").await.json();
    assert_eq!(results["participants"], 3);
    assert_eq!(results["complete"], 2);
    for c in results["conditions"].as_array().unwrap() {
        let surveyed = c["survey"]["E"]["n"].as_u64().unwrap();
        assert_eq!(surveyed, 2, "{c}");
        assert_eq!(c["survey"]["trust"]["counts"].as_array().unwrap().len(), 7);
        assert!(c["curve"]["mean"].as_array().unwrap().len() > 2);
    }
    let sac = &results["conditions"][1];
    assert_eq!(sac["name"], "sac");
    assert_eq!(sac["feedback_pct"]["mean"], 0.0);
    assert_eq!(results["tests"][0]["measure"], "cumulative_reward");
    assert_eq!(results["tests"][0]["tests"]["participants"], 2);
    assert!(results["tests"][0]["tests"]["caution"].is_string());

    let csv = of_study(&router, &study, "/table?format=csv").await;
    assert_eq!(csv.content_type, "text/csv");
    let text = String::from_utf8(csv.body).unwrap();
    // Two participants × three conditions, and the abandoned one's first session.
    assert_eq!(text.lines().count(), 1 + 7, "{text}");
    assert!(
        text.lines()
            .next()
            .unwrap()
            .ends_with("survey_E,survey_trust")
    );
    let parquet = of_study(&router, &study, "/table?format=parquet").await;
    assert_eq!(&parquet.body[..4], b"PAR1");
    of_study(&router, &study, "/table?format=xlsx")
        .await
        .assert_error(StatusCode::BAD_REQUEST, "bad_request");

    // `dualrep report study` from the data dir writes the same results, the table (read back by
    // pyarrow) and the figure.
    let out = dir.path().join("report");
    let id = study["id"].as_str().unwrap();
    let data = dir.path().to_str().unwrap();
    let report = |id: &str| {
        let args = [
            "report",
            "study",
            "--data-dir",
            data,
            "--study",
            id,
            "--out",
            out.to_str().unwrap(),
        ];
        dualrep_in(&args, None)
    };
    let run = report(id);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    // The same numbers as the route (ef-50 is left out: the participant who abandoned it still
    // has its session running, so its numbers move between the two reads).
    for c in 0..2 {
        assert_eq!(written["conditions"][c], results["conditions"][c]);
    }
    let table = read_parquet(&out.join("table.parquet"));
    assert_eq!(table["num_rows"], 7);
    assert_eq!(table["columns"]["survey_trust"], "int64");
    let svg = std::fs::read_to_string(out.join("figure.svg")).unwrap();
    assert!(svg.contains("cumulative reward") && svg.contains("ef-50"));
    assert!(std::fs::metadata(out.join("figure.png")).unwrap().len() > 1000);
    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(
        summary.contains("3 participants, 2 with every condition"),
        "{summary}"
    );
    assert!(refused(&report("nope")).contains("no study nope"));
}

#[tokio::test]
async fn a_study_that_cannot_run_is_refused_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let router = app(state(dir.path()).await);
    let mut body = study_body("t");
    body["conditions"][1]["params"] = json!({"env_timeout_s": 5});
    let r = call(
        &router,
        "POST",
        "/api/studies",
        Some(TOKEN),
        Some(&body.to_string()),
    )
    .await;
    r.assert_error(StatusCode::UNPROCESSABLE_ENTITY, "invalid_session");
    let message = r.json()["error"]["message"].as_str().unwrap().to_string();
    assert!(message.contains("conditions[1] (sac)"), "{message}");

    let mut body = study_body("t");
    body["ordering"] = json!("latin");
    let r = call(
        &router,
        "POST",
        "/api/studies",
        Some(TOKEN),
        Some(&body.to_string()),
    )
    .await;
    r.assert_error(StatusCode::BAD_REQUEST, "bad_request");
    assert!(
        r.json()["error"]["message"]
            .as_str()
            .unwrap()
            .contains("ordering")
    );

    call(
        &router,
        "POST",
        "/api/studies",
        None,
        Some(&study_body("t").to_string()),
    )
    .await
    .assert_error(StatusCode::UNAUTHORIZED, "unauthorized");
    post(&router, "/api/study-links/nope/participants", None)
        .await
        .assert_error(StatusCode::NOT_FOUND, "not_found");
    let studies = call(&router, "GET", "/api/studies", Some(TOKEN), None)
        .await
        .json();
    assert_eq!(studies, json!([]));
}

#[test]
fn the_cli_creates_and_lists_studies_on_a_running_server() {
    let data = tempfile::tempdir().unwrap();
    let (mut server, url) = start_serve(data.path(), TOKEN, &[], std::process::Stdio::inherit());
    let spec = data.path().join("study.json");
    std::fs::write(&spec, study_body("From the CLI").to_string()).unwrap();
    let spec = spec.to_str().unwrap();
    let create = dualrep_in(
        &[
            "study", "create", "--addr", &url, "--token", TOKEN, "--spec", spec,
        ],
        None,
    );
    let stdout = String::from_utf8_lossy(&create.stdout).to_string();
    assert!(
        create.status.success(),
        "{}",
        String::from_utf8_lossy(&create.stderr)
    );
    assert!(
        stdout.contains(&format!("participant link: {url}/study/")),
        "{stdout}"
    );
    let list = dualrep_in(&["study", "list", "--addr", &url, "--token", TOKEN], None);
    assert!(String::from_utf8_lossy(&list.stdout).contains("From the CLI"));
    // A study the server refuses is refused by the CLI with the server's message.
    let mut bad = study_body("Bad");
    bad["survey"] = json!([]);
    let bad_spec = data.path().join("bad.json");
    std::fs::write(&bad_spec, bad.to_string()).unwrap();
    let out = dualrep_in(
        &[
            "study",
            "create",
            "--addr",
            &url,
            "--token",
            TOKEN,
            "--spec",
            bad_spec.to_str().unwrap(),
        ],
        None,
    );
    let stderr = refused(&out);
    assert!(
        stderr.contains("survey: needs at least one question"),
        "{stderr}"
    );
    let _ = server.kill();
    let _ = server.wait();
}
