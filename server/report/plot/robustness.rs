//! The robustness figure: one panel per task of the evaluative sweep (cumulative reward at the
//! end of training against the teacher's error rate, a line per method with standard-error
//! bars), then one panel of the preference sweep (final alignment against the teacher's
//! rationality, a line per task and method, the rational teacher rightmost).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Axis, Panel, TAB10, TICK_PX, TITLE_PX, draw_labelled_line, draw_legend, draw_mesh,
    method_color, padded_range, short_number, text,
};
use crate::report::methods::{display_name, order_key, task_rank, task_title};
use crate::report::robustness::RobustnessTask;

/// A panel of the figure.
pub enum RobustnessPanel {
    /// One task's evaluative sweep.
    Errors(RobustnessTask),
    /// Every task's preference sweep.
    Betas(Vec<RobustnessTask>),
}

/// The panels of `tasks`: the evaluative ones in task order, then the preference one.
pub fn panels(tasks: &[RobustnessTask]) -> Vec<RobustnessPanel> {
    let mut out: Vec<RobustnessPanel> = tasks
        .iter()
        .filter(|t| !t.errors.is_empty())
        .cloned()
        .map(RobustnessPanel::Errors)
        .collect();
    let with_betas: Vec<RobustnessTask> = tasks
        .iter()
        .filter(|t| !t.betas.is_empty())
        .cloned()
        .collect();
    if !with_betas.is_empty() {
        out.push(RobustnessPanel::Betas(with_betas));
    }
    out
}

impl Panel for RobustnessPanel {
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        match self {
            RobustnessPanel::Errors(t) => draw_errors(area, t),
            RobustnessPanel::Betas(ts) => draw_betas(area, ts),
        }
    }
}

fn draw_errors<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    task: &RobustnessTask,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let x_max = task
        .errors
        .iter()
        .map(|c| c.error)
        .max()
        .unwrap_or(0)
        .max(1) as f64;
    let (y_lo, y_hi) = padded_range(task.errors.iter().flat_map(|c| {
        let m = c.cumulative;
        [m.mean - m.se, m.mean + m.se]
    }));
    let steps = task.errors.iter().map(|c| c.steps).min().unwrap_or(0);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{} ({}k steps)", task_title(task.task), steps / 1000),
            text(TITLE_PX),
        )
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .build_cartesian_2d(-1.5..x_max + 1.5, y_lo..y_hi)?;
    let y_span = y_hi - y_lo;
    let x_fmt = |x: &f64| format!("{x:.0} %");
    let y_fmt = |y: &f64| short_number(*y, y_span);
    draw_mesh(
        &mut chart,
        Axis {
            desc: "Teacher's error rate",
            labels: 5,
            format: &x_fmt,
        },
        Axis {
            desc: "Cumulative reward",
            labels: 6,
            format: &y_fmt,
        },
    )?;
    let mut methods: Vec<&str> = task.errors.iter().map(|c| c.method.as_str()).collect();
    methods.sort_by_key(|m| order_key(m));
    methods.dedup();
    for (i, method) in methods.iter().enumerate() {
        let color = method_color(method);
        let cells: Vec<_> = task.errors.iter().filter(|c| c.method == *method).collect();
        // Methods side by side at each error rate, so their bars do not overlap.
        let dodge = (i as f64 - (methods.len() as f64 - 1.0) / 2.0) * 0.5;
        let points: Vec<(f64, f64)> = cells
            .iter()
            .map(|c| (f64::from(c.error) + dodge, c.cumulative.mean))
            .collect();
        chart.draw_series(cells.iter().map(|c| {
            let m = c.cumulative;
            let x = f64::from(c.error) + dodge;
            ErrorBar::new_vertical(
                x,
                m.mean - m.se,
                m.mean,
                m.mean + m.se,
                color.stroke_width(2),
                8,
            )
        }))?;
        chart.draw_series(points.iter().map(|p| Circle::new(*p, 4, color.filled())))?;
        // A method whose name does not fix its feedback rate (DREF) shows it at every point.
        let shows_rate = !method.starts_with("ef-");
        if shows_rate {
            let style = text(TICK_PX - 2).color(&color);
            chart.draw_series(cells.iter().zip(&points).filter_map(|(c, p)| {
                let pct = c.feedback_pct.mean;
                pct.is_finite()
                    .then(|| Text::new(format!("{pct:.0} %"), (p.0 + 0.6, p.1), style.clone()))
            }))?;
        }
        let label = if shows_rate {
            format!("{} (labels: % of steps asked)", display_name(method))
        } else {
            display_name(method)
        };
        draw_labelled_line(&mut chart, points, color, label)?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
    Ok(())
}

fn beta_label(beta: Option<f64>) -> String {
    beta.map_or("rational".into(), |b| format!("{b}"))
}

fn draw_betas<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    tasks: &[RobustnessTask],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    // The rationalities as evenly spaced categories, rising, the rational teacher last.
    let mut betas: Vec<Option<f64>> = tasks
        .iter()
        .flat_map(|t| t.betas.iter().map(|c| c.beta))
        .collect();
    betas.sort_by(|a, b| {
        a.unwrap_or(f64::INFINITY)
            .partial_cmp(&b.unwrap_or(f64::INFINITY))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    betas.dedup();
    let position = |beta: Option<f64>| betas.iter().position(|b| *b == beta).unwrap_or(0) as f64;
    let labels = betas.clone();
    // Alignment is a cosine: 0 and 1 always show; a very irrational teacher may go below 0.
    let y_lo = tasks
        .iter()
        .flat_map(|t| &t.betas)
        .map(|c| c.final_alignment.mean - c.final_alignment.se)
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::min)
        - 0.05;
    let mut chart = ChartBuilder::on(area)
        .caption("DRPL against the teacher's beta", text(TITLE_PX))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(56)
        .build_cartesian_2d(-0.5..(betas.len() as f64 - 0.5).max(0.5), y_lo..1.3)?;
    let x_fmt = |x: &f64| {
        let i = x.round();
        if (x - i).abs() < 1e-6 && i >= 0.0 {
            labels
                .get(i as usize)
                .map_or(String::new(), |b| beta_label(*b))
        } else {
            String::new()
        }
    };
    let y_fmt = |y: &f64| {
        if *y > 1.0 + 1e-9 {
            String::new()
        } else {
            format!("{y:.1}")
        }
    };
    draw_mesh(
        &mut chart,
        Axis {
            desc: "Teacher's rationality (teacher_beta)",
            labels: betas.len().max(2),
            format: &x_fmt,
        },
        Axis {
            desc: "Final alignment",
            labels: 8,
            format: &y_fmt,
        },
    )?;
    let mut tasks: Vec<&RobustnessTask> = tasks.iter().collect();
    tasks.sort_by_key(|t| task_rank(t.task));
    for (i, t) in tasks.iter().enumerate() {
        let mut methods: Vec<&str> = t.betas.iter().map(|c| c.method.as_str()).collect();
        methods.sort_by_key(|m| order_key(m));
        methods.dedup();
        for (j, method) in methods.iter().enumerate() {
            let color = TAB10[(3 * i + j + 1) % TAB10.len()];
            let cells: Vec<_> = t.betas.iter().filter(|c| c.method == *method).collect();
            let dodge = (i as f64 - (tasks.len() as f64 - 1.0) / 2.0) * 0.08;
            let points: Vec<(f64, f64)> = cells
                .iter()
                .map(|c| (position(c.beta) + dodge, c.final_alignment.mean))
                .collect();
            chart.draw_series(cells.iter().map(|c| {
                let m = c.final_alignment;
                let x = position(c.beta) + dodge;
                ErrorBar::new_vertical(
                    x,
                    m.mean - m.se,
                    m.mean,
                    m.mean + m.se,
                    color.stroke_width(2),
                    8,
                )
            }))?;
            let label = if methods.len() > 1 {
                format!("{} {}", task_title(t.task), display_name(method))
            } else {
                task_title(t.task).to_string()
            };
            draw_labelled_line(&mut chart, points, color, label)?;
        }
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    Ok(())
}
