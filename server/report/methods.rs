//! Method names as the CLI spells them (`dref`, `ef-50`, `drpl-ss`, ...) mapped to the paper's
//! names, its order of legend entries, and the published Figure 3 numbers (algorithms.md,
//! section 2) that the table prints beside ours.

use crate::sim::Task;

/// The methods of Figure 3 in the paper's legend order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fig3Method {
    /// The product's DREF (docs/dref.md).
    Dref,
    /// DREF exactly as the authors' code has it: the row that reproduces the paper's.
    DrefAuthors,
    Ef100,
    Ef50,
    Ef25,
    Sac,
    /// Plain SAC at the env's reward scale, where the `Sac` row follows the authors' smaller
    /// one (Reaching); no published counterpart.
    SacUnscaled,
    /// DREF with its human critic regressed on queried steps only; no published counterpart.
    DrefMasked,
    /// EF at DREF's measured feedback rate, in percent: `ef-<p>` for any p other than the three
    /// fixed baselines. The grid names it after the rate it measured, so the name is the rule.
    EfMatched(f64),
}

impl Fig3Method {
    /// The method behind a CLI name, or `None` for a name Figure 3 does not know.
    pub fn parse(method: &str) -> Option<Self> {
        Some(match method {
            "dref" => Self::Dref,
            "dref-authors" => Self::DrefAuthors,
            "ef-100" => Self::Ef100,
            "ef-50" => Self::Ef50,
            "ef-25" => Self::Ef25,
            "sac" => Self::Sac,
            "sac-r100" => Self::SacUnscaled,
            "dref-masked" => Self::DrefMasked,
            other => Self::EfMatched(other.strip_prefix("ef-")?.parse().ok()?),
        })
    }

    /// Position in the legend and the table: the paper's order with the authors' DREF beside
    /// ours, the matched-rate baseline after the paper's rows, our extra rows last.
    pub fn rank(self) -> usize {
        match self {
            Self::Dref => 0,
            Self::DrefAuthors => 1,
            Self::Ef100 => 2,
            Self::Ef50 => 3,
            Self::Ef25 => 4,
            Self::Sac => 5,
            Self::EfMatched(_) => 6,
            Self::SacUnscaled => 7,
            Self::DrefMasked => 8,
        }
    }

    /// The paper's column for this method (DREF, EF-100, EF-50, EF-25, SAC, EF at DREF's
    /// rate), if it has one: both DREF rows are held against the paper's DREF.
    pub fn published_column(self) -> Option<usize> {
        match self {
            Self::Dref | Self::DrefAuthors => Some(0),
            Self::Ef100 => Some(1),
            Self::Ef50 => Some(2),
            Self::Ef25 => Some(3),
            Self::Sac => Some(4),
            Self::EfMatched(_) => Some(5),
            Self::SacUnscaled | Self::DrefMasked => None,
        }
    }

    /// Whether the method asks by DREF's rule (so its feedback rate is measured, not set).
    pub fn is_dref(self) -> bool {
        matches!(self, Self::Dref | Self::DrefAuthors | Self::DrefMasked)
    }

    /// Whether the method's name already says how much feedback it gets (so a legend need not).
    pub fn rate_in_name(self) -> bool {
        !self.is_dref()
    }
}

/// The paper's name of a Figure 3 or Figure 5 method; unknown names are shown as given.
pub fn display_name(method: &str) -> String {
    match method {
        "drpl" => return "DRPL".into(),
        "drpl-mi" => return "DRPL-MI (ours: mutual-information pick)".into(),
        "drpl-ss" => return "DRPL-SS".into(),
        "fragment" => return "Random fragment".into(),
        "full" => return "Full trajectory".into(),
        _ => {}
    }
    match Fig3Method::parse(method) {
        Some(Fig3Method::Dref) => "DREF".into(),
        Some(Fig3Method::DrefAuthors) => "DREF (authors' code)".into(),
        Some(Fig3Method::Sac) => "SAC".into(),
        Some(Fig3Method::SacUnscaled) => "SAC (reward 100)".into(),
        Some(Fig3Method::DrefMasked) => "DREF (authors' code, H on answered steps)".into(),
        Some(_) => format!("EF-{}%", &method["ef-".len()..]),
        None => method.into(),
    }
}

/// Sort key that puts methods in the paper's order, unknown ones after, alphabetically.
pub fn order_key(method: &str) -> (usize, String) {
    let rank = match method {
        "drpl" => 0,
        "drpl-ss" => 1,
        "fragment" => 2,
        "full" => 3,
        // Ours, not the paper's: after the paper's four rows.
        "drpl-mi" => 4,
        _ => Fig3Method::parse(method).map_or(100, Fig3Method::rank),
    };
    (rank, method.to_string())
}

/// The paper's panel order: Lunar-Lander, Reaching-Sim, Placing-Sim.
pub fn task_rank(task: Task) -> usize {
    match task {
        Task::LunarLander => 0,
        Task::Reaching => 1,
        Task::Placing => 2,
    }
}

/// The paper's panel title of a task.
pub fn task_title(task: Task) -> &'static str {
    match task {
        Task::LunarLander => "Lunar-Lander",
        Task::Reaching => "Reaching-Sim",
        Task::Placing => "Placing-Sim",
    }
}

/// Environment steps of the published curves (algorithms.md, section 1).
pub fn paper_steps(task: Task) -> u64 {
    match task {
        Task::LunarLander => 150_000,
        Task::Reaching | Task::Placing => 100_000,
    }
}

/// DREF's feedback rate in percent as the paper's text states it (section 4.1), used for
/// "EF at DREF's rate" when DREF itself is not in the grid.
pub fn paper_dref_rate(task: Task) -> f64 {
    match task {
        Task::LunarLander => 6.2,
        Task::Reaching => 1.6,
        Task::Placing => 8.4,
    }
}

/// A published Figure 3 result: final cumulative reward in thousands, and DREF's feedback rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Published {
    pub cumulative_k: f64,
    pub feedback_pct: Option<f64>,
}

/// The published value of `method` on `task` (algorithms.md, section 2, "What the published
/// runs show"), if the paper has that row.
pub fn published_fig3(task: Task, method: Fig3Method) -> Option<Published> {
    // Columns: DREF, EF-100, EF-50, EF-25, SAC, EF at DREF's rate.
    let (row, dref_rate) = match task {
        Task::LunarLander => ([34.1, 29.1, 24.2, 18.7, 17.6, -6.0], 6.3),
        Task::Reaching => ([11.4, 11.4, 10.4, 9.6, 6.2, 10.2], 1.6),
        Task::Placing => ([43.3, 43.6, 23.4, 23.7, 16.4, 10.1], 8.4),
    };
    Some(Published {
        cumulative_k: row[method.published_column()?],
        feedback_pct: (method.published_column() == Some(0)).then_some(dref_rate),
    })
}

/// The paper's ratio of `method`'s cumulative reward to EF-100's on `task` (the plotted values
/// are all about a quarter of the true sums, so their ratios are the true ones).
pub fn published_ratio(task: Task, method: Fig3Method) -> Option<f64> {
    let ef100 = published_fig3(task, Fig3Method::Ef100)?.cumulative_k;
    Some(published_fig3(task, method)?.cumulative_k / ef100)
}

/// A ratio to EF-100 with its standard error over runs, where the decoding gives one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AuthorsRatio {
    pub mean: f64,
    pub se: Option<f64>,
}

/// The authors' own ratios to EF-100, decoded from their result files
/// (`docs/results/authors-runs/summary.csv`, `benches/reference/authors_runs.py`): over the runs
/// each published curve was drawn from, and over every run of the batches those came from.
/// Rows: the authors' DREF, EF-100, EF-50, EF-25, SAC, EF at DREF's rate. EF-50's and EF-25's
/// are ratios of means (the decoding gives no error for them).
pub fn authors_ratios(task: Task, method: Fig3Method) -> Option<(AuthorsRatio, AuthorsRatio)> {
    let r = |mean: f64, se: f64| AuthorsRatio { mean, se: Some(se) };
    let plain = |mean: f64| AuthorsRatio { mean, se: None };
    let row = match method {
        Fig3Method::DrefAuthors => 0,
        Fig3Method::Ef100 => 1,
        Fig3Method::Ef50 => 2,
        Fig3Method::Ef25 => 3,
        Fig3Method::Sac | Fig3Method::SacUnscaled => 4,
        Fig3Method::EfMatched(_) => 5,
        Fig3Method::Dref | Fig3Method::DrefMasked => return None,
    };
    let table: [(AuthorsRatio, AuthorsRatio); 6] = match task {
        Task::LunarLander => [
            (r(1.170, 0.117), r(0.924, 0.149)),
            (r(1.0, 0.0), r(1.0, 0.0)),
            (plain(0.760), plain(0.753)),
            (plain(0.642), plain(0.433)),
            (r(0.603, 0.066), r(0.603, 0.066)),
            (r(-0.205, 0.109), r(-0.205, 0.109)),
        ],
        Task::Reaching => [
            (r(0.995, 0.026), r(0.815, 0.031)),
            (r(1.0, 0.0), r(1.0, 0.0)),
            (plain(0.907), plain(0.927)),
            (plain(0.840), plain(0.926)),
            (r(0.543, 0.043), r(0.584, 0.031)),
            (r(0.892, 0.054), r(0.900, 0.055)),
        ],
        Task::Placing => [
            (r(0.992, 0.083), r(0.921, 0.345)),
            (r(1.0, 0.0), r(1.0, 0.0)),
            (plain(0.536), plain(1.255)),
            (plain(0.543), plain(0.517)),
            (r(0.376, 0.102), r(0.457, 0.210)),
            (r(0.232, 0.094), r(0.395, 0.194)),
        ],
    };
    Some(table[row])
}

/// The name under which the grid runs EF at a rate of `pct` percent: `ef-6.2`, `ef-0.35`.
/// Two decimals at most, trailing zeros dropped, never one of the fixed baselines' names.
pub fn matched_ef_method(pct: f64) -> String {
    let mut s = format!("{pct:.2}");
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.pop();
    }
    // A rate that rounds to 100, 50 or 25 must still read as the matched baseline.
    if matches!(s.as_str(), "100" | "50" | "25") {
        s.push_str(".0");
    }
    format!("ef-{s}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_method_names_parse_and_display() {
        assert_eq!(Fig3Method::parse("dref"), Some(Fig3Method::Dref));
        assert_eq!(
            Fig3Method::parse("dref-authors"),
            Some(Fig3Method::DrefAuthors)
        );
        assert_eq!(Fig3Method::parse("ef-50"), Some(Fig3Method::Ef50));
        assert_eq!(
            Fig3Method::parse("ef-6.2"),
            Some(Fig3Method::EfMatched(6.2))
        );
        assert_eq!(Fig3Method::parse("drpl"), None);
        assert_eq!(Fig3Method::parse("ef-x"), None);
        assert_eq!(display_name("ef-100"), "EF-100%");
        assert_eq!(display_name("ef-6.2"), "EF-6.2%");
        assert_eq!(display_name("drpl-ss"), "DRPL-SS");
        assert_eq!(
            display_name("drpl-mi"),
            "DRPL-MI (ours: mutual-information pick)"
        );
        assert_eq!(display_name("mystery"), "mystery");
    }

    #[test]
    fn report_methods_sort_in_the_papers_order() {
        let mut m = vec![
            "sac",
            "ef-6.2",
            "ef-25",
            "dref-authors",
            "dref",
            "zz",
            "ef-100",
            "ef-50",
        ];
        m.sort_by_key(|s| order_key(s));
        assert_eq!(
            m,
            [
                "dref",
                "dref-authors",
                "ef-100",
                "ef-50",
                "ef-25",
                "sac",
                "ef-6.2",
                "zz"
            ]
        );
    }

    #[test]
    fn report_matched_method_names_round_trip() {
        assert_eq!(matched_ef_method(6.2), "ef-6.2");
        assert_eq!(matched_ef_method(6.249), "ef-6.25");
        assert_eq!(matched_ef_method(0.0), "ef-0");
        assert_eq!(matched_ef_method(50.001), "ef-50.0");
        assert_eq!(
            Fig3Method::parse(&matched_ef_method(1.6)),
            Some(Fig3Method::EfMatched(1.6))
        );
    }

    #[test]
    fn report_published_values_match_algorithms_md() {
        let ll = published_fig3(Task::LunarLander, Fig3Method::Dref).unwrap();
        assert_eq!(ll.cumulative_k, 34.1);
        assert_eq!(ll.feedback_pct, Some(6.3));
        assert_eq!(
            published_fig3(Task::LunarLander, Fig3Method::DrefAuthors),
            Some(ll)
        );
        let p = published_fig3(Task::Placing, Fig3Method::EfMatched(8.4)).unwrap();
        assert_eq!((p.cumulative_k, p.feedback_pct), (10.1, None));
        assert_eq!(
            published_fig3(Task::Reaching, Fig3Method::Sac)
                .unwrap()
                .cumulative_k,
            6.2
        );
        assert_eq!(
            published_fig3(Task::Reaching, Fig3Method::SacUnscaled),
            None
        );
        // algorithms.md's ratio rows, to two decimals.
        let r = |t, m| (published_ratio(t, m).unwrap() * 100.0).round() / 100.0;
        assert_eq!(r(Task::Reaching, Fig3Method::Sac), 0.54);
        assert_eq!(r(Task::Placing, Fig3Method::Sac), 0.38);
        assert_eq!(r(Task::LunarLander, Fig3Method::Dref), 1.17);
        assert_eq!(r(Task::Placing, Fig3Method::EfMatched(8.4)), 0.23);
    }
}
