//! `dualrep study`: tools for human-subject studies. `study create` and `study list` talk to a
//! running server (`study_server`); `study pilot` runs a study's design with
//! simulated participants and estimates its power at several sizes (`study::pilot`), writing
//! `pilot.json`, `pilot.md` and `participants.csv` into `--out` and the tables to stdout.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use super::output::write_atomically;
use crate::session::load_task_expert;
use crate::study::pilot::simulate::{self, Experts, PilotRun, Score};
use crate::study::pilot::{Format, Overrides, PilotFile, PilotSpec, parse_value, report};

#[derive(Debug, Args)]
pub struct StudyArgs {
    #[command(subcommand)]
    pub what: StudyWhat,
}

#[derive(Debug, Subcommand)]
pub enum StudyWhat {
    /// A power estimate before anyone is recruited: the study run with simulated participants,
    /// and the share of simulated studies in which its main contrast is significant at each n.
    Pilot(PilotArgs),
    /// Create a study on a running server from its spec file; prints its participant link.
    Create(super::study_server::CreateArgs),
    /// The studies of a running server: id, participants, link, title.
    List(super::study_server::ListArgs),
}

#[derive(Debug, Args)]
pub struct PilotArgs {
    /// The pilot file (.toml or .json): `study` (the study as POSTed, or its file's path),
    /// `teachers` (e.g. teacher_beta = [0.5, 5.0]), and optionally participants, ns, studies,
    /// alpha, seed.
    #[arg(long)]
    pub spec: PathBuf,
    /// Output directory (created): pilot.json, pilot.md, participants.csv.
    #[arg(long)]
    pub out: PathBuf,
    /// Simulated participants in the pool, each training every condition [default: the
    /// file's, else the largest n].
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..=1000))]
    pub participants: Option<u64>,
    /// Simulated studies per n [default: the file's, else 1000].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub studies: Option<u64>,
    /// Study sizes, comma-separated [default: the file's, else 4,6,8,12,16].
    #[arg(long, value_delimiter = ',')]
    pub ns: Option<Vec<usize>>,
    /// Seeds the teachers' draws and the resampling [default: the file's, else the study's].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Runs training at once, one thread each [default: the number of CPUs].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub jobs: Option<u64>,
    /// Load the synthetic teacher's experts (`<task>.safetensors`) from this folder instead of
    /// the ones inside the binary, as `serve --models-dir` does.
    #[arg(long)]
    pub models_dir: Option<PathBuf>,
}

pub fn run(args: StudyArgs) -> anyhow::Result<()> {
    match args.what {
        StudyWhat::Pilot(args) => pilot(args),
        StudyWhat::Create(args) => {
            let spec = read_value(&args.spec)?;
            super::study_server::create(args, spec)
        }
        StudyWhat::List(args) => super::study_server::list(args),
    }
}

/// A JSON or TOML file as a JSON value.
fn read_value(path: &Path) -> anyhow::Result<serde_json::Value> {
    let format = path
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Format::of_extension)
        .with_context(|| format!("{}: expected a .toml or .json file", path.display()))?;
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    parse_value(&text, format).with_context(|| format!("reading {}", path.display()))
}

fn read_spec(args: &PilotArgs) -> anyhow::Result<PilotSpec> {
    let file = PilotFile::from_value(read_value(&args.spec)?)
        .with_context(|| format!("reading {}", args.spec.display()))?;
    let study = match file.study_path() {
        Some(relative) => {
            let path = args.spec.parent().unwrap_or(Path::new(".")).join(relative);
            read_value(&path).with_context(|| format!("{}: study", args.spec.display()))?
        }
        None => file.study.clone(),
    };
    let overrides = Overrides {
        participants: args.participants.map(|p| p as usize),
        ns: args.ns.clone(),
        studies: args.studies.map(|k| k as usize),
        seed: args.seed,
    };
    PilotSpec::new(file, study, overrides).with_context(|| format!("{}", args.spec.display()))
}

fn load_experts(runs: &[PilotRun], models_dir: Option<&Path>) -> anyhow::Result<Experts> {
    simulate::tasks_needing_experts(runs)
        .into_iter()
        .map(|task| Ok((task, load_task_expert(models_dir, task)?)))
        .collect()
}

fn pilot(args: PilotArgs) -> anyhow::Result<()> {
    let spec = read_spec(&args)?;
    let runs = spec.runs()?;
    let experts = load_experts(&runs, args.models_dir.as_deref())?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let jobs = args.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, usize::from),
        |j| j as usize,
    );
    let names: Vec<&str> = spec
        .study
        .conditions
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    eprintln!(
        "{}: {} simulated participants x {} conditions = {} runs, {jobs} at a time",
        spec.study.title,
        spec.participants,
        names.len(),
        runs.len()
    );
    let start = Instant::now();
    let done = AtomicUsize::new(0);
    let total = runs.len();
    let on_done = |run: &PilotRun, result: &Result<Score, String>| {
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        let what = match result {
            Ok(s) => match s.feedback_percent {
                Some(f) => format!("{:.1}, feedback {f:.2} %", s.score),
                None => format!("{:.3}", s.score),
            },
            Err(e) => format!("failed: {e}"),
        };
        eprintln!(
            "[{n}/{total}] participant {} {}: {what} ({:.0} s)",
            run.participant,
            names[run.condition],
            start.elapsed().as_secs_f64()
        );
    };
    let results = simulate::run_all(&runs, &experts, jobs, &on_done);
    let mut scores = Vec::with_capacity(results.len());
    for (run, result) in runs.iter().zip(results) {
        match result {
            Ok(score) => scores.push(score),
            Err(e) => bail!(
                "participant {} in {}: {e}",
                run.participant,
                names[run.condition]
            ),
        }
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    let report = report::build(&spec, &runs, &scores);
    let mut json = serde_json::to_value(&report)?;
    json["wall_seconds"] = serde_json::json!(wall_seconds);
    write_atomically(
        &args.out.join("pilot.json"),
        &serde_json::to_vec_pretty(&json)?,
    )?;
    let md = report.markdown();
    write_atomically(&args.out.join("pilot.md"), md.as_bytes())?;
    write_atomically(
        &args.out.join("participants.csv"),
        report.participants_csv().as_bytes(),
    )?;
    print!("{md}");
    eprintln!(
        "trained {total} runs in {wall_seconds:.0} s; wrote pilot.json, pilot.md and participants.csv to {}",
        args.out.display()
    );
    Ok(())
}
