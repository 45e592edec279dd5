//! `dualrep export`: a stored session's datasets from a server's data dir, without the server:
//! its labelled transitions or preference pairs (Parquet), a preference session's posterior or
//! an evaluative session's policy (safetensors) - the files the API's `dataset.parquet`,
//! `posterior.safetensors` and `policy.safetensors` give.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;

use crate::export::session::{Dataset, export, file_name};
use crate::store::{DB_FILE, Store};

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The server's data dir (the one `dualrep serve --data-dir` used).
    #[arg(long, default_value = "data")]
    pub data_dir: PathBuf,
    /// The session's id.
    #[arg(long)]
    pub session: String,
    /// table (transitions or pairs, Parquet), posterior or policy (safetensors).
    #[arg(long, value_enum, default_value_t = Dataset::Table)]
    pub what: Dataset,
    /// Where to write it [default: dualrep-<session>-<what>.<ext> in the current directory].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    if !args.data_dir.join(DB_FILE).is_file() {
        bail!(
            "{} holds no dualrep database ({DB_FILE}); give the data dir of `dualrep serve`",
            args.data_dir.display()
        );
    }
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()?
        .block_on(async {
            let store = Store::open(&args.data_dir).await?;
            let Some(session) = store.session(&args.session).await? else {
                bail!("no session {} in {}", args.session, args.data_dir.display());
            };
            let bytes = export(&store, &args.data_dir, &session, args.what).await?;
            let out = args
                .out
                .clone()
                .unwrap_or_else(|| PathBuf::from(file_name(&session, args.what)));
            std::fs::write(&out, &bytes).with_context(|| format!("writing {}", out.display()))?;
            println!("{} ({} bytes)", out.display(), bytes.len());
            Ok(())
        })
}
