//! Figure 5: alignment against the number of queries, one line per method with standard-error
//! bars at every query.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Axis, Panel, TITLE_PX, draw_labelled_line, draw_legend, draw_mesh, padded_range, panel_colors,
    text,
};
use crate::report::aggregate::Fig5Task;
use crate::report::methods::{display_name, task_title};

/// Top of the alignment axis: a cosine never exceeds 1, so the band above it holds the legend
/// without hiding any curve. 1.3 holds the paper's four entries; with more (DRPL-MI beside
/// them), the band grows so that about 6.8 % of the axis height is left per entry.
fn y_top(entries: usize) -> f64 {
    if entries <= 4 {
        return 1.3;
    }
    let share = (0.068 * entries as f64).min(0.8);
    (1.0 + 0.05 * share) / (1.0 - share)
}

/// Horizontal shift between methods' error bars, in queries, so that bars at the same query do
/// not sit on top of each other.
const DODGE: f64 = 0.18;

impl Panel for Fig5Task {
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        draw_panel(area, self)
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    task: &Fig5Task,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let x_max = task
        .methods
        .iter()
        .filter_map(|m| m.curve.x.last().copied())
        .fold(1.0f64, f64::max);
    let (y_lo, y_hi) = padded_range(
        task.methods
            .iter()
            .flat_map(|m| {
                m.curve
                    .mean
                    .iter()
                    .zip(&m.curve.se)
                    .flat_map(|(m, s)| [m - s, m + s])
            })
            // Alignment is a cosine: always show the top of its scale.
            .chain([1.0]),
    );
    let mut chart = ChartBuilder::on(area)
        .caption(task_title(task.task), text(TITLE_PX))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..x_max + 1.0, y_lo..y_top(task.methods.len()).max(y_hi))?;
    let x_fmt = |x: &f64| format!("{x:.0}");
    // No tick labels above 1: that band is the legend's.
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
            desc: "Number of queries",
            labels: 8,
            format: &x_fmt,
        },
        Axis {
            desc: "Alignment",
            labels: 8,
            format: &y_fmt,
        },
    )?;

    let k = task.methods.len() as f64;
    let colors = panel_colors(task.methods.iter().map(|row| row.method.as_str()));
    for (i, (row, &color)) in task.methods.iter().zip(&colors).enumerate() {
        let shift = (i as f64 - (k - 1.0) / 2.0) * DODGE;
        let c = &row.curve;
        let points = || c.x.iter().zip(&c.mean).map(move |(x, m)| (x + shift, *m));
        chart.draw_series(c.x.iter().zip(c.mean.iter().zip(&c.se)).map(|(x, (m, s))| {
            ErrorBar::new_vertical(x + shift, m - s, *m, m + s, color.stroke_width(1), 5)
        }))?;
        draw_labelled_line(&mut chart, points(), color, display_name(&row.method))?;
        chart.draw_series(points().map(|p| Circle::new(p, 2, color.filled())))?;
    }
    // Alignment starts low and rises: the upper left is the corner curves reach last.
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    Ok(())
}
