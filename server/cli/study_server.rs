//! `dualrep study create` and `dualrep study list`: a running server's studies over its REST
//! API (`POST /api/studies`, `GET /api/studies`), for researchers who script their studies.
//! The spec file is the JSON (or TOML) a researcher would POST; the server checks it, so the
//! CLI and the API refuse the same studies with the same messages.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;

#[derive(Debug, Args)]
pub struct ServerArgs {
    /// The server's address, e.g. http://localhost:8080.
    #[arg(long, default_value = "http://127.0.0.1:8080")]
    pub addr: String,
    /// The researcher token [default: $DUALREP_TOKEN].
    #[arg(long, env = "DUALREP_TOKEN", hide_env_values = true)]
    pub token: String,
}

#[derive(Debug, Args)]
pub struct CreateArgs {
    #[command(flatten)]
    pub server: ServerArgs,
    /// The study (.json or .toml): title, conditions, budget, survey, consent, ordering
    /// (README, "Running a study").
    #[arg(long)]
    pub spec: PathBuf,
}

#[derive(Debug, Args)]
pub struct ListArgs {
    #[command(flatten)]
    pub server: ServerArgs,
}

fn runtime() -> anyhow::Result<tokio::runtime::Runtime> {
    Ok(tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?)
}

/// The server's JSON answer, or its error message.
async fn answer(response: reqwest::Response, what: &str) -> anyhow::Result<serde_json::Value> {
    let status = response.status();
    let body: serde_json::Value = response
        .json()
        .await
        .with_context(|| format!("{what}: the server's answer is not JSON ({status})"))?;
    if !status.is_success() {
        let message = body["error"]["message"].as_str().unwrap_or("no message");
        bail!("{what}: the server refused ({status}): {message}");
    }
    Ok(body)
}

fn url(server: &ServerArgs, path: &str) -> String {
    format!("{}{path}", server.addr.trim_end_matches('/'))
}

pub fn create(args: CreateArgs, spec: serde_json::Value) -> anyhow::Result<()> {
    runtime()?.block_on(async {
        let response = reqwest::Client::new()
            .post(url(&args.server, "/api/studies"))
            .bearer_auth(&args.server.token)
            .json(&spec)
            .send()
            .await
            .with_context(|| format!("reaching {}", args.server.addr))?;
        let study = answer(response, &format!("creating {}", args.spec.display())).await?;
        let link = study["link"].as_str().unwrap_or_default();
        println!("study {} created", study["id"].as_str().unwrap_or_default());
        println!("participant link: {}", url(&args.server, link));
        println!("{study}");
        Ok(())
    })
}

pub fn list(args: ListArgs) -> anyhow::Result<()> {
    runtime()?.block_on(async {
        let response = reqwest::Client::new()
            .get(url(&args.server, "/api/studies"))
            .bearer_auth(&args.server.token)
            .send()
            .await
            .with_context(|| format!("reaching {}", args.server.addr))?;
        let studies = answer(response, "listing studies").await?;
        for s in studies.as_array().into_iter().flatten() {
            println!(
                "{}  {:>3} participants  {}  {}",
                s["id"].as_str().unwrap_or_default(),
                s["participants"],
                url(&args.server, s["link"].as_str().unwrap_or_default()),
                s["title"].as_str().unwrap_or_default(),
            );
        }
        Ok(())
    })
}
