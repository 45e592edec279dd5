//! `table.md`: per task a Markdown table of mean ± standard error over seeds, with the paper's
//! published values beside ours for Figure 3. Pure: returns the text, the caller writes it.

use std::collections::BTreeMap;
use std::fmt::Write;

use super::aggregate::{Fig3Method as AggregateRow, Fig3Task, Fig5Method, Fig5Task};
use super::methods::{
    AuthorsRatio, Fig3Method, Published, authors_ratios, display_name, paper_steps, published_fig3,
    published_ratio, task_title,
};
use super::rank_test::mann_whitney_greater;
use super::stats::{MeanSe, mean_se};
use super::within_subject::{WilcoxonMethod, wilcoxon_greater};

/// A cumulative reward as the paper prints it: in thousands with one decimal ("34.1k") when
/// `thousands`, else whole numbers; the error in the same unit. One table section uses one unit
/// (see [`uses_thousands`]) so that its column reads at a glance.
pub fn fmt_reward(m: MeanSe, thousands: bool) -> String {
    if m.mean.is_nan() {
        return "–".into();
    }
    if thousands {
        format!("{:.1}k ± {:.1}k", m.mean / 1000.0, m.se / 1000.0)
    } else {
        format!("{:.0} ± {:.0}", m.mean, m.se)
    }
}

/// Whether a task's rewards are shown in thousands: when any method's mean reaches a thousand.
pub fn uses_thousands(task: &Fig3Task) -> bool {
    task.methods
        .iter()
        .any(|m| m.final_return.mean.abs() >= 1000.0)
}

/// A percentage with one decimal and its standard error: "6.2 ± 0.4 %".
pub fn fmt_pct(m: MeanSe) -> String {
    if m.mean.is_nan() {
        return "–".into();
    }
    format!("{:.1} ± {:.1} %", m.mean, m.se)
}

fn fmt_plain(m: MeanSe, decimals: usize) -> String {
    if m.mean.is_nan() {
        return "–".into();
    }
    format!("{:.*} ± {:.*}", decimals, m.mean, decimals, m.se)
}

/// Steps as "150k" (or the exact number when not a whole thousand).
fn fmt_steps(steps: u64) -> String {
    if steps >= 1000 && steps.is_multiple_of(1000) {
        format!("{}k", steps / 1000)
    } else {
        steps.to_string()
    }
}

const FIG3_INTRO: &str = "\
Cumulative reward summed over all finished episodes at the end of training, mean ± standard \
error over seeds; feedback is the share of environment steps on which the oracle answered. \
A seed learns when 8 or more of its last 10 episodes succeed (Lunar Lander: their mean return \
is 200 or more); frozen is the share of episodes after which the rule had not asked for 10k \
steps while the last 10 episodes failed; a flood is a stretch of consecutive asked steps \
(\">=\": a lower bound read from whole episodes, for runs that predate its measurement). \
\"Paper\" is the published run (algorithms.md, section 2) as plotted, about a quarter of its \
true sum. Our simulators are not the paper's, so compare the ratios to EF-100%: ours (of our \
true sums) beside the paper's.
";

/// `value / reference` to two decimals, or "–" when either is missing or the reference is not
/// positive (a ratio to a negative sum, as Lunar Lander's at 20k steps, reads backwards).
fn fmt_ratio(value: Option<f64>, reference: Option<f64>) -> String {
    match (value, reference) {
        (Some(v), Some(r)) if r > 0.0 && v.is_finite() && r.is_finite() => {
            format!("{:.2}", v / r)
        }
        _ => "–".into(),
    }
}

const AS_RUN_INTRO: &str = "\
These runs ran the authors' runs as run (`profile = \"as-run\"`), so two more columns read them \
against the authors' own result files (`docs/results/authors-runs/`): the ratio over the runs \
each published curve was drawn from, and over every run of the batches those came from.
";

/// The authors' plotted and all-runs ratios of `kind` on `task`, as two table cells.
fn authors_cells(task: crate::sim::Task, kind: Option<Fig3Method>) -> String {
    let cell = |r: AuthorsRatio| match r.se {
        Some(se) => format!("{:.2} ± {:.2}", r.mean, se),
        None => format!("{:.2}", r.mean),
    };
    match kind.and_then(|k| authors_ratios(task, k)) {
        Some((plotted, all)) => format!(" {} | {} |", cell(plotted), cell(all)),
        None => " – | – |".into(),
    }
}

/// The Figure 3 table: one section per task, rows in legend order, plus a row for every
/// published method this grid has not run (so the paper's column is always complete). With
/// `as_run` (a grid of the authors' runs as run), the authors' plotted and all-runs ratios too.
pub fn fig3_table(tasks: &[Fig3Task], as_run: bool) -> String {
    let mut out = String::from("# Figure 3: cumulative reward during training\n\n");
    out.push_str(FIG3_INTRO);
    if as_run {
        out.push('\n');
        out.push_str(AS_RUN_INTRO);
    }
    for task in tasks {
        let mut steps: Vec<u64> = task.methods.iter().map(|m| m.steps).collect();
        steps.sort_unstable();
        steps.dedup();
        let ours = match steps.as_slice() {
            [one] => fmt_steps(*one),
            [first, .., last] => format!("{}–{}", fmt_steps(*first), fmt_steps(*last)),
            [] => "no".into(),
        };
        let (authors_head, authors_rule) = if as_run {
            (
                " Authors' plotted ratio | Authors' all-runs ratio |",
                "---:|---:|",
            )
        } else {
            ("", "")
        };
        let _ = write!(
            out,
            "\n## {}: {} steps (paper: {})\n\n\
             | Method | Cumulative reward | Feedback | Seeds | Seeds that learn | Frozen | Longest flood after 2k | Ratio to EF-100% | Paper's ratio |{authors_head} Paper |\n\
             |---|---:|---:|---:|---:|---:|---:|---:|---:|{authors_rule}---:|\n",
            task_title(task.task),
            ours,
            fmt_steps(paper_steps(task.task)),
        );
        let authors = |kind: Option<Fig3Method>| {
            if as_run {
                authors_cells(task.task, kind)
            } else {
                String::new()
            }
        };
        let thousands = uses_thousands(task);
        let ef100 = task
            .methods
            .iter()
            .find(|m| Fig3Method::parse(&m.method) == Some(Fig3Method::Ef100))
            .map(|m| m.final_return.mean);
        let mut rows: Vec<(usize, String)> = Vec::new();
        for m in &task.methods {
            let kind = Fig3Method::parse(&m.method);
            let mut name = display_name(&m.method);
            if let Some(Fig3Method::EfMatched(rate)) = kind {
                name.push_str(whose_rate(task, rate));
            }
            let paper = kind.map_or("–".into(), |k| fmt_published(task.task, k));
            let paper_ratio = kind.and_then(|k| published_ratio(task.task, k));
            // Freezes and floods are a query rule's; EF's rate is its definition.
            let (frozen, flood) = if kind.is_none_or(Fig3Method::is_dref) {
                let (n, exact) = m.longest_flood_after_2k;
                (
                    fmt_pct(m.frozen_pct),
                    if exact {
                        n.to_string()
                    } else {
                        format!(">= {n}")
                    },
                )
            } else {
                ("–".into(), "–".into())
            };
            let row = format!(
                "| {name} | {} | {} | {} | {} | {frozen} | {flood} | {} | {} |{} {paper} |\n",
                fmt_reward(m.final_return, thousands),
                fmt_pct(m.feedback_pct),
                m.final_return.n,
                m.seeds_learned,
                fmt_ratio(Some(m.final_return.mean), ef100),
                fmt_ratio(paper_ratio, Some(1.0)),
                authors(kind),
            );
            rows.push((kind.map_or(100, Fig3Method::rank), row));
        }
        let published = [
            Fig3Method::Dref,
            Fig3Method::Ef100,
            Fig3Method::Ef50,
            Fig3Method::Ef25,
            Fig3Method::Sac,
            Fig3Method::EfMatched(f64::NAN),
        ];
        for kind in published {
            // Either DREF row stands for the paper's DREF.
            let have = |k: Fig3Method| rows.iter().any(|(rank, _)| *rank == k.rank());
            let present = match kind {
                Fig3Method::Dref => have(Fig3Method::Dref) || have(Fig3Method::DrefAuthors),
                _ => have(kind),
            };
            if !present {
                let name = match kind {
                    Fig3Method::EfMatched(_) => "EF at DREF's rate".to_string(),
                    Fig3Method::Dref | Fig3Method::DrefAuthors | Fig3Method::DrefMasked => {
                        "DREF".into()
                    }
                    Fig3Method::Ef100 => "EF-100%".into(),
                    Fig3Method::Ef50 => "EF-50%".into(),
                    Fig3Method::Ef25 => "EF-25%".into(),
                    Fig3Method::Sac | Fig3Method::SacUnscaled => "SAC".into(),
                };
                let paper = fmt_published(task.task, kind);
                let ratio = fmt_ratio(published_ratio(task.task, kind), Some(1.0));
                rows.push((
                    kind.rank(),
                    format!(
                        "| {name} | – | – | 0 | – | – | – | – | {ratio} |{} {paper} |\n",
                        authors(Some(match kind {
                            Fig3Method::Dref => Fig3Method::DrefAuthors,
                            other => other,
                        }))
                    ),
                ));
            }
        }
        // Stable: our rows keep their legend order, missing ones slot in at the paper's place.
        rows.sort_by_key(|(rank, _)| *rank);
        for (_, row) in rows {
            out.push_str(&row);
        }
        out.push_str(&dref_against_matched(task));
        out.push_str(&per_run_pacing(task));
    }
    out
}

/// Per run of each row that asks by a rule: whether it learnt, its feedback, its share of
/// frozen episodes and its longest flood after the first 2k steps.
fn per_run_pacing(task: &Fig3Task) -> String {
    let mut out = String::new();
    for m in &task.methods {
        if !Fig3Method::parse(&m.method).is_none_or(Fig3Method::is_dref) || m.runs.is_empty() {
            continue;
        }
        let _ = write!(
            out,
            "\n{}, per run:\n\n| seed | learns | feedback | frozen | longest flood after 2k |\n\
             |---|---|---:|---:|---:|\n",
            display_name(&m.method)
        );
        for r in &m.runs {
            let (flood, exact) = r.longest_flood_after_2k;
            let _ = writeln!(
                out,
                "| {} | {} | {:.2} % | {:.1} % | {}{flood} |",
                r.seed,
                if r.learned { "yes" } else { "no" },
                r.feedback_pct,
                r.frozen_pct,
                if exact { "" } else { ">= " },
            );
        }
    }
    out
}

/// How far (percentage points) an EF row's rate may lie from DREF's mean rate and still be
/// "EF at its rate": the grid names the row after the rate to two decimals (`matched_ef_method`),
/// a run named by hand may carry one (EF-8.9 for a DREF at 8.89 %).
const MATCHED_RATE_TOLERANCE_PP: f64 = 0.05;

/// The row of `task` nearest `rate` (percentage points) among those `rate_of` gives one, if it
/// lies within [`MATCHED_RATE_TOLERANCE_PP`].
fn nearest_rate(
    task: &Fig3Task,
    rate: f64,
    rate_of: impl Fn(&AggregateRow) -> Option<f64>,
) -> Option<&AggregateRow> {
    let distance = |m: &AggregateRow| rate_of(m).map_or(f64::INFINITY, |p| (p - rate).abs());
    task.methods
        .iter()
        .filter(|m| distance(m) <= MATCHED_RATE_TOLERANCE_PP + 1e-9)
        .min_by(|a, b| distance(a).total_cmp(&distance(b)))
}

/// Whose rate an "EF at a rate" row carries, as its name's suffix: the DREF row of the table
/// whose mean rate it is, or, where no row of this table asks at it, a rule's that is not shown
/// (an earlier default's or an ablation's: EF-2.51 on Placing is an earlier default's, 121.5k at
/// 2.51 %).
fn whose_rate(task: &Fig3Task, rate: f64) -> &'static str {
    let dref_rate = |m: &AggregateRow| {
        Fig3Method::parse(&m.method)
            .is_some_and(Fig3Method::is_dref)
            .then_some(m.feedback_pct.mean)
    };
    match nearest_rate(task, rate, dref_rate).and_then(|m| Fig3Method::parse(&m.method)) {
        Some(Fig3Method::Dref) => " (DREF's rate)",
        Some(Fig3Method::DrefAuthors) => " (the authors' DREF's rate)",
        Some(Fig3Method::DrefMasked) => " (the masked authors' DREF's rate)",
        _ => " (a DREF's rate not in this table)",
    }
}

/// For each DREF row with an "EF at its rate" row beside it: whether DREF's seeds lie above
/// EF's, by the one-sided exact Mann-Whitney U test over seeds.
fn dref_against_matched(task: &Fig3Task) -> String {
    let mut out = String::new();
    let ef_rate = |m: &AggregateRow| match Fig3Method::parse(&m.method) {
        Some(Fig3Method::EfMatched(p)) => Some(p),
        _ => None,
    };
    for dref in &task.methods {
        if !Fig3Method::parse(&dref.method).is_some_and(Fig3Method::is_dref) {
            continue;
        }
        let Some(ef) = nearest_rate(task, dref.feedback_pct.mean, ef_rate) else {
            continue;
        };
        if let Some(t) = mann_whitney_greater(&dref.finals, &ef.finals) {
            let _ = write!(
                out,
                "\n{} above {} (its rate): one-sided exact Mann-Whitney U = {:.1} over {} and {} \
                 seeds, p = {:.4}.\n",
                display_name(&dref.method),
                display_name(&ef.method),
                t.u,
                t.n_a,
                t.n_b,
                t.p_one_sided
            );
        }
    }
    out
}

fn fmt_published(task: crate::sim::Task, method: Fig3Method) -> String {
    match published_fig3(task, method) {
        Some(Published {
            cumulative_k,
            feedback_pct: Some(pct),
        }) => format!("{cumulative_k:.1}k ({pct:.1} %)"),
        Some(p) => format!("{:.1}k", p.cumulative_k),
        None => "–".into(),
    }
}

const FIG5_INTRO: &str = "\
After the last query, mean ± standard error over seeds, each seed with its own true reward \
weights: *alignment* is the mean over posterior samples of the cosine between sampled and true \
weights (what the figure plots); *alignment of mean* is the cosine between the posterior mean \
and the true weights, which is what APReL's `cosine_similarity` (the paper's alignment score) \
computes. The paper publishes no table; its text reports DRPL converging to about 0.8 or more \
on every task and beating all baselines, with DRPL-SS second. DRPL-MI is ours, not the paper's: \
DRPL with a mutual-information pick among its candidate pairs instead of the uniform one \
(`acquisition = mutual_information`), the paper's DRPL left as it is.

Below each table, DRPL and DRPL-MI against each baseline (and DRPL-MI against DRPL): the final \
alignments paired by seed (a seed's runs share their trajectories and true reward), over the \
seeds both rows have; the mean of the differences ± its standard error; the seeds on which the \
first row is higher; and the one-sided Wilcoxon signed-rank p that the first lies above the \
second (exact without ties, zero differences dropped).
";

/// The rows the paired tests put first, each with the rows it is tested against.
const FIG5_PAIRED: [(&str, &[&str]); 2] = [
    ("drpl", &["drpl-ss", "fragment", "full"]),
    ("drpl-mi", &["drpl-ss", "fragment", "full", "drpl"]),
];

/// A method's name without its parenthesised note ("DRPL-MI", not "DRPL-MI (ours: ...)").
fn short_name(method: &str) -> String {
    let name = display_name(method);
    match name.split_once(" (") {
        Some((short, _)) => short.to_string(),
        None => name,
    }
}

/// A p-value to two significant digits: "0.012", "4.8e-6".
fn fmt_p(p: f64) -> String {
    if p < 0.001 {
        format!("{p:.1e}")
    } else {
        format!("{p:.3}")
    }
}

/// One paired line: whether `x`'s final alignments lie above `y`'s, seed by seed, by the
/// one-sided Wilcoxon signed-rank test over the seeds both have; `None` without such seeds.
pub fn fig5_paired_line(x: &Fig5Method, y: &Fig5Method) -> Option<String> {
    let of_y: BTreeMap<u64, f64> = y.finals_by_seed.iter().copied().collect();
    let mut pairs: Vec<(u64, f64, f64)> = x
        .finals_by_seed
        .iter()
        .filter_map(|&(seed, a)| of_y.get(&seed).map(|&b| (seed, a, b)))
        .collect();
    if pairs.is_empty() {
        return None;
    }
    pairs.sort_by_key(|&(seed, _, _)| seed);
    let (xs, ys): (Vec<f64>, Vec<f64>) = pairs.iter().map(|&(_, a, b)| (a, b)).unzip();
    let differences: Vec<f64> = pairs.iter().map(|&(_, a, b)| a - b).collect();
    let d = mean_se(&differences);
    let wins = differences.iter().filter(|&&d| d > 0.0).count();
    let t = wilcoxon_greater(&xs, &ys);
    let mut notes = Vec::new();
    if t.zeros > 0 {
        notes.push(format!("{} tied seeds dropped", t.zeros));
    }
    if t.method == WilcoxonMethod::Normal {
        notes.push("normal approximation".to_string());
    }
    let notes = if notes.is_empty() {
        String::new()
    } else {
        format!(" ({})", notes.join(", "))
    };
    Some(format!(
        "{} above {}: one-sided paired Wilcoxon signed-rank over {} seeds (paired by seed), \
         mean difference {:+.3} ± {:.3}, wins {wins} of {}, p = {}{notes}.",
        short_name(&x.method),
        short_name(&y.method),
        pairs.len(),
        d.mean,
        d.se,
        pairs.len(),
        fmt_p(t.p),
    ))
}

/// Every paired line of one task ([`FIG5_PAIRED`]), for the rows it has.
fn fig5_paired(task: &Fig5Task) -> String {
    let row = |name: &str| task.methods.iter().find(|m| m.method == name);
    let mut out = String::new();
    for (first, others) in FIG5_PAIRED {
        let Some(x) = row(first) else { continue };
        for line in others
            .iter()
            .filter_map(|other| row(other))
            .filter_map(|y| fig5_paired_line(x, y))
        {
            let _ = writeln!(out, "- {line}");
        }
    }
    if out.is_empty() {
        out
    } else {
        format!("\n{out}")
    }
}

/// The Figure 5 table: one section per task, rows in legend order.
pub fn fig5_table(tasks: &[Fig5Task]) -> String {
    let mut out = String::from("# Figure 5: alignment of the learnt reward\n\n");
    out.push_str(FIG5_INTRO);
    for task in tasks {
        let queries = task
            .methods
            .iter()
            .filter_map(|m| m.curve.x.last())
            .fold(0.0f64, |a, &b| a.max(b));
        let _ = write!(
            out,
            "\n## {}: {} queries\n\n\
             | Method | Final alignment | Alignment of mean | Mean segment length | Seeds |\n\
             |---|---:|---:|---:|---:|\n",
            task_title(task.task),
            queries,
        );
        for m in &task.methods {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} |",
                display_name(&m.method),
                fmt_plain(m.final_alignment, 3),
                fmt_plain(m.final_alignment_of_mean, 3),
                fmt_plain(m.segment_length, 1),
                m.final_alignment.n,
            );
        }
        out.push_str(&fig5_paired(task));
    }
    out
}

#[cfg(test)]
#[path = "table_tests.rs"]
mod tests;
