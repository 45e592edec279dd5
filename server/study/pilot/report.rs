//! A pilot's report: [`PilotReport`] (what `pilot.json` holds), its Markdown (`pilot.md`) and
//! the pool's raw table (`participants.csv`: one row per participant and condition, with the
//! teacher drawn, the position in the participant's order and the scores), so that nothing
//! behind a power figure is hidden.

use serde::Serialize;
use serde_json::{Map, Value};

use super::PilotSpec;
use super::power::{PowerPlan, PowerRow, estimate};
use super::simulate::{PilotRun, Score};
use super::teachers::{TEACHER_KEYS, TeacherRange, TeacherRanges};
use crate::report::stats::{MeanSe, mean_se};
use crate::report::within_subject::{Alternative, Wilcoxon, wilcoxon};
use crate::session::plan::RunConfig;

/// One condition across the pool.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionSummary {
    pub name: String,
    pub method: String,
    pub score: MeanSe,
    /// Percent of steps that asked for feedback (evaluative methods).
    pub feedback_percent: Option<MeanSe>,
}

/// The main contrast across the whole pool: the effect the power figures resample.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoolContrast {
    pub conditions: [String; 2],
    /// First minus second, per participant.
    pub difference: MeanSe,
    /// The test over all the pool's participants at once.
    pub wilcoxon: Wilcoxon,
}

/// One participant of the pool.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParticipantRecord {
    pub participant: usize,
    /// The teacher settings drawn for them.
    pub teacher: Map<String, Value>,
    /// The conditions in the order they met them.
    pub order: Vec<String>,
    /// The session seed, the same in every condition.
    pub seed: u64,
    /// One per condition, in the study's order of conditions.
    pub scores: Vec<Score>,
}

/// `pilot.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PilotReport {
    pub title: String,
    /// `cumulative_reward` (evaluative studies) or `final_alignment` (preference studies).
    pub measure: &'static str,
    pub test: String,
    pub conditions: Vec<String>,
    pub contrast: [String; 2],
    /// The pool's size.
    pub participants: usize,
    pub studies: usize,
    pub alpha: f64,
    pub seed: u64,
    /// The ranges as given, in setting order.
    pub teachers: TeacherRanges,
    pub power: Vec<PowerRow>,
    pub pool: Vec<ConditionSummary>,
    pub pool_contrast: PoolContrast,
    pub notes: Vec<String>,
    pub pool_participants: Vec<ParticipantRecord>,
}

/// The test's description, for the report and `pilot.md`.
const TEST: &str = "two-sided Wilcoxon signed-rank test on the main contrast's paired scores \
(zero differences dropped; exact without ties up to 25 pairs, else the normal approximation with \
tie and continuity correction, as scipy's wilcoxon)";

/// The report of `spec`'s pilot from its `runs` and their `scores` (in the same order).
///
/// # Panics
/// If a participant lacks a condition's score.
pub fn build(spec: &PilotSpec, runs: &[PilotRun], scores: &[Score]) -> PilotReport {
    let k = spec.study.conditions.len();
    let mut matrix: Vec<Vec<Option<Score>>> = vec![vec![None; k]; spec.participants];
    for (run, score) in runs.iter().zip(scores) {
        matrix[run.participant][run.condition] = Some(*score);
    }
    let design = spec.study.design();
    let pool_participants: Vec<ParticipantRecord> = matrix
        .into_iter()
        .enumerate()
        .map(|(participant, row)| ParticipantRecord {
            participant,
            teacher: spec.teacher(participant),
            order: design
                .order_for(participant)
                .into_iter()
                .map(String::from)
                .collect(),
            seed: spec
                .study
                .session_spec(0, participant)
                .map_or(0, |s| s.seed),
            scores: row
                .into_iter()
                .map(|s| s.expect("every participant trained every condition"))
                .collect(),
        })
        .collect();
    let values: Vec<Vec<f64>> = pool_participants
        .iter()
        .map(|p| p.scores.iter().map(|s| s.score).collect())
        .collect();
    let [a, b] = spec.contrast();
    let plan = PowerPlan {
        ns: spec.ns.clone(),
        studies: spec.studies,
        alpha: spec.alpha,
        seed: spec.seed,
    };
    let power = estimate(&values, [a, b], &plan);
    let column = |j: usize| -> Vec<f64> { values.iter().map(|r| r[j]).collect() };
    let pool = spec
        .study
        .conditions
        .iter()
        .enumerate()
        .map(|(j, c)| {
            let percents: Option<Vec<f64>> = pool_participants
                .iter()
                .map(|p| p.scores[j].feedback_percent)
                .collect();
            ConditionSummary {
                name: c.name.clone(),
                method: c.method.to_string(),
                score: mean_se(&column(j)),
                feedback_percent: percents.map(|v| mean_se(&v)),
            }
        })
        .collect();
    let differences: Vec<f64> = values.iter().map(|r| r[a] - r[b]).collect();
    let names = spec.study.contrast().map(String::from);
    let pool_contrast = PoolContrast {
        difference: mean_se(&differences),
        wilcoxon: wilcoxon(&column(a), &column(b), Alternative::TwoSided),
        conditions: names.clone(),
    };
    let preference = runs
        .first()
        .is_some_and(|r| matches!(r.config, RunConfig::Preference(_)));
    PilotReport {
        title: spec.study.title.clone(),
        measure: if preference {
            "final_alignment"
        } else {
            "cumulative_reward"
        },
        test: TEST.to_string(),
        conditions: design.conditions.clone(),
        contrast: names,
        participants: spec.participants,
        studies: spec.studies,
        alpha: spec.alpha,
        seed: spec.seed,
        teachers: spec.teachers.clone(),
        notes: notes(spec, &power),
        power,
        pool,
        pool_contrast,
        pool_participants,
    }
}

fn notes(spec: &PilotSpec, power: &[PowerRow]) -> Vec<String> {
    let p = spec.participants;
    let mut notes = vec![
        format!(
            "Bootstrap power: each simulated study draws n of the pool's {p} simulated \
             participants with replacement. It takes the pool for the population, so it is \
             optimistic when the pool is small; a participant drawn twice gives tied \
             differences, and the test then uses its normal approximation."
        ),
        format!(
            "Subsample power: n distinct participants of the pool (n <= {p} only); at n = {p} \
             every simulated study is the whole pool, so its share is 0 or 1."
        ),
        "Simulated participants differ only in their teacher's settings and their seed: they \
         do not learn, tire or carry anything from one condition to the next, so real people \
         will vary more and the real power will be lower."
            .to_string(),
    ];
    let hopeless: Vec<String> = power
        .iter()
        .filter(|r| r.exact_p_floor >= spec.alpha)
        .map(|r| r.n.to_string())
        .collect();
    if !hopeless.is_empty() {
        notes.push(format!(
            "n = {}: the exact two-sided Wilcoxon test cannot give p < {} with so few pairs \
             (its smallest p is 2 / 2^n), so these sizes can only come out significant through \
             ties.",
            hopeless.join(", "),
            spec.alpha
        ));
    }
    notes
}

fn fmt_share(share: Option<super::power::Share>) -> String {
    share.map_or("-".to_string(), |s| {
        format!("{:.3} ± {:.3}", s.power, s.mc_se)
    })
}

fn fmt_mean_se(m: MeanSe) -> String {
    let digits = match m.mean.abs() {
        x if x >= 1000.0 => 0,
        x if x >= 10.0 => 1,
        _ => 3,
    };
    format!("{:.*} ± {:.*}", digits, m.mean, digits, m.se)
}

fn fmt_range(range: &TeacherRange) -> String {
    match range {
        TeacherRange::Fixed(v) => format!("{v} (fixed)"),
        TeacherRange::Uniform([low, high]) => format!("uniform in [{low}, {high}]"),
    }
}

impl PilotReport {
    /// `pilot.md`.
    pub fn markdown(&self) -> String {
        let mut md = format!("# Pilot: {}\n\n", self.title);
        let [a, b] = &self.contrast;
        let measure = match self.measure {
            "final_alignment" => "the reward's alignment after the last query (Figure 6)",
            _ => "the cumulative reward over the session (Figure 4)",
        };
        md += &format!(
            "A power estimate from {} simulated participants, each training every condition \
             with a synthetic teacher. Main contrast: **{a}** vs **{b}**, scored by {measure}. \
             Test: {}, significant at p < {}. {} simulated studies per n; seed {}.\n\n",
            self.participants, self.test, self.alpha, self.studies, self.seed
        );
        if self.teachers.is_empty() {
            md += "Teachers: every simulated teacher as the conditions set it (by default perfect).\n\n";
        } else {
            md += "Teachers, drawn per participant:\n\n";
            for (key, range) in self.teachers.ranges() {
                md += &format!("- `{key}`: {}\n", fmt_range(range));
            }
            md += "\n";
        }
        md += "## Power\n\n";
        md += "Share of simulated studies significant (± Monte-Carlo s.e.).\n\n";
        let friedman = self.conditions.len() >= 3;
        md += "| n | Wilcoxon, bootstrap | Wilcoxon, subsample |";
        if friedman {
            md += " Friedman, bootstrap | Friedman, subsample |";
        }
        md += " smallest exact p |\n|---|---|---|";
        if friedman {
            md += "---|---|";
        }
        md += "---|\n";
        for row in &self.power {
            md += &format!(
                "| {} | {} | {} |",
                row.n,
                fmt_share(Some(row.bootstrap)),
                fmt_share(row.subsample)
            );
            if friedman {
                md += &format!(
                    " {} | {} |",
                    fmt_share(row.friedman_bootstrap),
                    fmt_share(row.friedman_subsample)
                );
            }
            md += &format!(" {:.4} |\n", row.exact_p_floor);
        }
        md += &format!("\n## The pool (n = {})\n\n", self.participants);
        md += &format!(
            "| condition | method | {} | feedback % |\n|---|---|---|---|\n",
            self.measure
        );
        for c in &self.pool {
            md += &format!(
                "| {} | {} | {} | {} |\n",
                c.name,
                c.method,
                fmt_mean_se(c.score),
                c.feedback_percent.map_or("-".to_string(), fmt_mean_se)
            );
        }
        let pc = &self.pool_contrast;
        md += &format!(
            "\n{a} − {b}, per participant: {} (mean ± s.e.); over the whole pool Wilcoxon p = \
             {:.4}, rank-biserial r = {:.2}.\n\n",
            fmt_mean_se(pc.difference),
            pc.wilcoxon.p,
            pc.wilcoxon.rank_biserial
        );
        md += "## Notes\n\n";
        for note in &self.notes {
            md += &format!("- {note}\n");
        }
        md += "\nEvery participant's teacher, order and scores: `participants.csv`.\n";
        md
    }

    /// `participants.csv`: one row per participant and condition.
    pub fn participants_csv(&self) -> String {
        let mut w = csv::Writer::from_writer(Vec::new());
        let mut header = vec!["participant", "seed", "position", "condition"];
        header.extend(TEACHER_KEYS);
        header.extend([
            self.measure,
            "feedback_count",
            "feedback_percent",
            "episodes",
        ]);
        w.write_record(&header).expect("writing to memory");
        for p in &self.pool_participants {
            for (position, name) in p.order.iter().enumerate() {
                let j = self
                    .conditions
                    .iter()
                    .position(|c| c == name)
                    .expect("the order names the conditions");
                let s = &p.scores[j];
                let mut row = vec![
                    p.participant.to_string(),
                    p.seed.to_string(),
                    position.to_string(),
                    name.clone(),
                ];
                row.extend(TEACHER_KEYS.iter().map(|k| match p.teacher.get(*k) {
                    None => String::new(),
                    Some(Value::String(word)) => word.clone(),
                    Some(v) => v.to_string(),
                }));
                row.extend([
                    s.score.to_string(),
                    s.feedback_count.to_string(),
                    s.feedback_percent.map_or(String::new(), |f| f.to_string()),
                    s.episodes.to_string(),
                ]);
                w.write_record(&row).expect("writing to memory");
            }
        }
        String::from_utf8(w.into_inner().expect("writing to memory")).expect("UTF-8 in, UTF-8 out")
    }
}
