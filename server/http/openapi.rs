//! `GET /api/openapi.json`: the REST API described as OpenAPI 3.1. Kept beside the routes in
//! `http/mod.rs`; a test checks that every route there appears here and the other way round.

use axum::Json;
use serde_json::{Value, json};

/// Every documented operation as `(method, path)`; the test compares it with the router's.
pub const OPERATIONS: [(&str, &str); 23] = [
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
    ("get", "/api/tasks"),
    ("get", "/api/openapi.json"),
    ("get", "/healthz"),
    ("get", "/ws/sessions/{id}"),
];

fn op(summary: &str, auth: bool, responses: Value) -> Value {
    let mut o = json!({"summary": summary, "responses": responses});
    if !auth {
        o["security"] = json!([]);
    }
    o
}

fn id_param() -> Value {
    json!([{"name": "id", "in": "path", "required": true, "schema": {"type": "string"}}])
}

fn ok(description: &str, schema: Value) -> Value {
    json!({
        "200": {"description": description, "content": {"application/json": {"schema": schema}}},
        "default": {"$ref": "#/components/responses/Error"}
    })
}

pub fn document() -> Value {
    let session_ref = json!({"$ref": "#/components/schemas/Session"});
    let mut paths = serde_json::Map::new();
    paths.insert("/api/sessions".into(), json!({
        "post": {
            "summary": "Launch a session",
            "requestBody": {"required": true, "content": {"application/json": {"schema": {"$ref": "#/components/schemas/LaunchRequest"}}}},
            "responses": {
                "201": {"description": "Queued", "content": {"application/json": {"schema": {
                    "type": "object", "required": ["id", "status", "trainer_url"],
                    "properties": {"id": {"type": "string"}, "status": {"$ref": "#/components/schemas/Status"}, "trainer_url": {"type": "string"}}
                }}}},
                "default": {"$ref": "#/components/responses/Error"}
            }
        },
        "get": op("List sessions, newest first", true, ok("Sessions", json!({"type": "array", "items": session_ref.clone()}))),
    }));
    paths.insert("/api/sessions/{id}".into(), json!({
        "parameters": id_param(),
        "get": op("A session: status, progress, answer counts, latest metrics", true, ok("The session", session_ref.clone())),
    }));
    for (action, summary) in [
        ("stop", "Stop a queued or running session"),
        (
            "resume",
            "Resume an interrupted, stopped or failed session; stored answers are replayed, never asked again",
        ),
    ] {
        paths.insert(
            format!("/api/sessions/{{id}}/{action}"),
            json!({
                "parameters": id_param(),
                "post": op(summary, true, ok("The session", session_ref.clone())),
            }),
        );
    }
    paths.insert("/api/sessions/{id}/episodes".into(), json!({
        "parameters": id_param(),
        "get": op("Finished episodes", true, ok("Episodes", json!({"type": "array", "items": {"$ref": "#/components/schemas/Episode"}}))),
    }));
    paths.insert("/api/sessions/{id}/episodes/{episode}/frames".into(), json!({
        "parameters": [id_param()[0].clone(), {"name": "episode", "in": "path", "required": true, "schema": {"type": "integer", "minimum": 0}}],
        "get": op("An episode of a human session as {geometry, frames} for replay", true, ok("The episode's frames", json!({"type": "object", "properties": {"geometry": {"type": "object"}, "frames": {"type": "array"}}}))),
    }));
    paths.insert("/api/sessions/{id}/answers".into(), json!({
        "parameters": id_param(),
        "get": op("Answered queries in the order asked", true, ok("Answers", json!({"type": "array", "items": {"$ref": "#/components/schemas/Answer"}}))),
    }));
    paths.insert("/api/sessions/{id}/alignment".into(), json!({
        "parameters": id_param(),
        "get": op("A preference session's posterior alignment with the synthetic trainer's reward after every answer and undo (empty for evaluative sessions)", true, ok("Alignment by query", json!({"type": "array", "items": {"type": "object", "properties": {
            "queries": {"type": "integer"}, "alignment": {"type": "number"}, "alignment_of_mean": {"type": "number"}
        }}}))),
    }));
    paths.insert("/api/sessions/{id}/export".into(), json!({
        "parameters": [id_param()[0].clone(), {"name": "format", "in": "query", "schema": {"type": "string", "enum": ["jsonl", "csv"], "default": "jsonl"}}],
        "get": op("Download the session: JSONL (session, answers, episodes; `record` names each line) or CSV (answers)", true, json!({
            "200": {"description": "The file", "content": {"application/x-ndjson": {}, "text/csv": {}}},
            "default": {"$ref": "#/components/responses/Error"}
        })),
    }));
    paths.insert("/api/sessions/{id}/recording.rrd".into(), json!({
        "parameters": id_param(),
        "get": op("The session's Rerun recording", true, json!({
            "200": {"description": "An .rrd file (open with `rerun <file>`)", "content": {"application/octet-stream": {}}},
            "default": {"$ref": "#/components/responses/Error"}
        })),
    }));
    paths.insert("/api/sessions/{id}/survey".into(), json!({
        "parameters": id_param(),
        "post": {
            "summary": "Store the trainer's answers to the paper's three 5-point questions (after the session ended); bearer = the session's trainer token or the researcher token",
            "requestBody": {"required": true, "content": {"application/json": {"schema": {"$ref": "#/components/schemas/Survey"}}}},
            "responses": ok("The session, with `survey`", session_ref.clone()),
        },
    }));
    paths.insert("/api/sessions/{id}/trainers".into(), json!({
        "parameters": id_param(),
        "post": {
            "summary": "Invite a named trainer: a link of their own (its token identifies them)",
            "requestBody": {"required": true, "content": {"application/json": {"schema": {"$ref": "#/components/schemas/Name"}}}},
            "responses": {
                "201": {"description": "The trainer and their link", "content": {"application/json": {"schema": {"$ref": "#/components/schemas/TrainerLink"}}}},
                "default": {"$ref": "#/components/responses/Error"}
            }
        },
        "get": op("The session per trainer: answers, time (T), no-feedback count (NFC), latency, survey; the anonymous trainer last", true, ok("Trainers", json!({"type": "array", "items": {"$ref": "#/components/schemas/TrainerStats"}}))),
    }));
    paths.insert("/api/sessions/{id}/join".into(), json!({
        "parameters": id_param(),
        "post": {
            "summary": "A trainer on the session's shared link gives their name and gets a token of their own; bearer = the session's trainer token",
            "security": [],
            "requestBody": {"required": true, "content": {"application/json": {"schema": {"$ref": "#/components/schemas/Name"}}}},
            "responses": {
                "201": {"description": "Joined", "content": {"application/json": {"schema": {"$ref": "#/components/schemas/TrainerLink"}}}},
                "default": {"$ref": "#/components/responses/Error"}
            }
        },
    }));
    paths.insert("/api/sessions/{id}/agreement".into(), json!({
        "parameters": id_param(),
        "get": op("How much the named trainers agree: Krippendorff's alpha (ordinal) over evaluative answers, Fleiss' kappa over preference choices; per session and per pair of trainers", true, ok("Agreement", json!({"type": "object", "properties": {
            "measure": {"type": "string", "enum": ["krippendorff_alpha_ordinal", "fleiss_kappa"]},
            "value": {"type": ["number", "null"]}, "units": {"type": "integer"}, "trainers": {"type": "integer"},
            "pairs": {"type": "array", "items": {"type": "object", "properties": {
                "a": {"type": "integer"}, "b": {"type": "integer"}, "a_name": {"type": "string"}, "b_name": {"type": "string"},
                "value": {"type": ["number", "null"]}, "units": {"type": "integer"}}}}
        }}))),
    }));
    for (file, summary, media) in [
        (
            "dataset.parquet",
            "The session's labelled data as Parquet: each answered query's transition (observation, action, reward, next observation, label, who, latency; evaluative sessions) or pair (both segments' features and abstract states, the choice, who, latency; preference sessions), with each named trainer's own answer",
            "application/vnd.apache.parquet",
        ),
        (
            "posterior.safetensors",
            "A preference session's posterior at its latest checkpoint: `samples` [n, d] and `mean_theta` [d], f64",
            "application/octet-stream",
        ),
        (
            "policy.safetensors",
            "An evaluative session's policy at its latest checkpoint: the actor network's tensors, f32, PyTorch layout",
            "application/octet-stream",
        ),
    ] {
        paths.insert(
            format!("/api/sessions/{{id}}/{file}"),
            json!({
                "parameters": id_param(),
                "get": op(summary, true, json!({
                    "200": {"description": "The file", "content": {media: {}}},
                    "default": {"$ref": "#/components/responses/Error"}
                })),
            }),
        );
    }
    paths.insert("/api/tasks".into(), json!({
        "get": op("Tasks, their scene-graph predicates and defaults", false, ok("Tasks", json!({"type": "object"}))),
    }));
    paths.insert(
        "/api/openapi.json".into(),
        json!({
            "get": op("This document", false, ok("OpenAPI 3.1", json!({"type": "object"}))),
        }),
    );
    paths.insert("/healthz".into(), json!({
        "get": op("Liveness and database check", false, ok("Healthy", json!({"type": "object", "properties": {"status": {"const": "ok"}}}))),
    }));
    paths.insert("/ws/sessions/{id}".into(), json!({
        "parameters": [id_param()[0].clone(), {"name": "token", "in": "query", "required": true, "schema": {"type": "string"}}],
        "get": op("The trainer's websocket (protocol in docs/protocol.md); authorised by the session's trainer token", false, json!({
            "101": {"description": "Switching to the websocket protocol"},
            "default": {"$ref": "#/components/responses/Error"}
        })),
    }));

    json!({
        "openapi": "3.1.0",
        "info": {"title": "dualrep", "version": env!("CARGO_PKG_VERSION"),
                 "description": "Train robot policies in simulation with people's guidance (DREF and DRPL)."},
        "security": [{"bearer": []}],
        "paths": paths,
        "components": {
            "securitySchemes": {"bearer": {"type": "http", "scheme": "bearer", "description": "The researcher token (--token, DUALREP_TOKEN, or <data-dir>/token)"}},
            "responses": {"Error": {"description": "An error", "content": {"application/json": {"schema": {
                "type": "object", "required": ["error"],
                "properties": {"error": {"type": "object", "required": ["code", "message"],
                    "properties": {"code": {"type": "string"}, "message": {"type": "string"}}}}
            }}}}},
            "schemas": {
                "Status": {"type": "string", "enum": ["queued", "running", "waiting", "finished", "failed", "stopped", "interrupted"]},
                "LaunchRequest": {
                    "type": "object", "required": ["task", "method", "trainer"], "additionalProperties": false,
                    "properties": {
                        "task": {"type": "string", "enum": ["reaching", "placing", "lunar-lander"]},
                        "method": {"type": "string", "description": "dref, ef-<percent>, sac, drpl, drpl-ss, fragment or full"},
                        "trainer": {"type": "string", "enum": ["human", "synthetic"]},
                        "seed": {"type": "integer", "minimum": 0, "default": 0},
                        "steps": {"type": "integer", "minimum": 1, "description": "Evaluative methods: environment steps"},
                        "queries": {"type": "integer", "minimum": 1, "description": "Preference methods: queries", "default": 40},
                        "params": {"type": "object", "description": "pace_hz (20), answer_timeout_s (60), checkpoint_every (5000), clip_frames (30), and any hyper-parameter by name"}
                    }
                },
                "Session": {"type": "object", "properties": {
                    "id": {"type": "string"}, "task": {"type": "string"}, "method": {"type": "string"}, "trainer": {"type": "string"},
                    "seed": {"type": "integer"}, "budget": {"type": "integer"}, "unit": {"type": "string", "enum": ["steps", "queries"]},
                    "status": {"$ref": "#/components/schemas/Status"}, "reason": {"type": "string"},
                    "progress": {"type": "integer"}, "params": {"type": "object"},
                    "answers": {"type": "object", "properties": {"total": {"type": "integer"}, "by_trainer": {"type": "integer"}, "timeouts": {"type": "integer"}, "no_feedback": {"type": "integer"}}},
                    "latest": {"type": "object"}, "trainer_url": {"type": "string"},
                    "created_at": {"type": "string"}, "started_at": {"type": "string"}, "ended_at": {"type": "string"},
                    "trainer_seconds": {"type": "number"},
                    "survey": {"oneOf": [{"$ref": "#/components/schemas/Survey"}, {"type": "null"}]}
                }},
                "Survey": {"type": "object", "additionalProperties": false,
                    "required": ["overall_experience", "perceived_intelligence", "cognitive_ease"],
                    "properties": {
                        "overall_experience": {"type": "integer", "minimum": 1, "maximum": 5},
                        "perceived_intelligence": {"type": "integer", "minimum": 1, "maximum": 5},
                        "cognitive_ease": {"type": "integer", "minimum": 1, "maximum": 5}
                    }},
                "Answer": {"type": "object", "required": ["query_id", "kind", "step", "value", "answered_at", "latency_ms"], "properties": {
                    "query_id": {"type": "integer"}, "seq": {"type": "integer"}, "kind": {"type": "string", "enum": ["evaluative", "preference"]},
                    "step": {"type": "integer"}, "abstract_state": {"type": "integer"},
                    "value": {"oneOf": [{"type": "integer", "enum": [1, 0, -1]}, {"type": "string", "enum": ["left", "right", "equal", "skip"]},
                        {"type": "number", "description": "several trainers' mean (combine = mean)"},
                        {"type": "object", "description": "several trainers' preferences (combine = each)", "properties": {"tally": {"type": "object"}}}]},
                    "who": {"type": "string", "enum": ["trainer", "trainers", "synthetic", "timeout"]},
                    "trainer": {"type": ["string", "null"], "description": "the named trainer who gave it"},
                    "trainer_id": {"type": ["integer", "null"]},
                    "asked_at": {"type": "string"}, "answered_at": {"type": "string"}, "latency_ms": {"type": "integer"},
                    "revision": {"type": "integer", "description": "how often an undo changed the answer (0: never); `value` is the answer that stands"}
                }},
                "Name": {"type": "object", "required": ["name"], "additionalProperties": false,
                    "properties": {"name": {"type": "string", "minLength": 1, "maxLength": 40}}},
                "TrainerLink": {"type": "object", "properties": {
                    "id": {"type": "integer"}, "name": {"type": "string"}, "origin": {"type": "string", "enum": ["invited", "joined"]},
                    "token": {"type": "string"}, "trainer_url": {"type": "string"}}},
                "TrainerStats": {"type": "object", "properties": {
                    "id": {"type": ["integer", "null"]}, "name": {"type": ["string", "null"]}, "origin": {"type": ["string", "null"]},
                    "trainer_url": {"type": "string"}, "answers": {"type": "integer"}, "no_feedback": {"type": "integer"},
                    "trainer_seconds": {"type": ["number", "null"]}, "latency_ms_median": {"type": ["number", "null"]},
                    "latency_ms_mean": {"type": ["number", "null"]},
                    "survey": {"oneOf": [{"$ref": "#/components/schemas/Survey"}, {"type": "null"}]}}},
                "Episode": {"type": "object", "properties": {
                    "episode": {"type": "integer"}, "step": {"type": "integer"}, "return": {"type": "number"}, "length": {"type": "integer"},
                    "cumulative_return": {"type": "number"}, "feedback_count": {"type": "integer"}, "feedback_fraction": {"type": "number"},
                    "outcome": {"type": "string"}
                }}
            }
        }
    })
}

pub async fn openapi() -> Json<Value> {
    Json(document())
}
