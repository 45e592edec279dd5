//! Figure 3: cumulative reward against environment steps, one line per method with a shaded
//! standard-error band, the legend naming each method with its mean feedback percentage where
//! the name does not already say it ("DREF (6.2 %)").

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Axis, Panel, TITLE_PX, draw_labelled_line, draw_legend, draw_mesh, padded_range, panel_colors,
    short_number, text,
};
use crate::report::aggregate::{Fig3Method as Row, Fig3Task};
use crate::report::methods::{Fig3Method, display_name, task_title};

/// The legend entry of a method: its paper name, plus its measured feedback percentage for
/// methods whose name does not fix it (DREF). SAC gets none: it never asks.
pub fn legend_label(row: &Row) -> String {
    let name = display_name(&row.method);
    let shows_rate = match Fig3Method::parse(&row.method) {
        Some(kind) => !kind.rate_in_name(),
        None => row.feedback_pct.mean > 0.0,
    };
    if shows_rate && row.feedback_pct.mean.is_finite() {
        format!("{name} ({:.1} %)", row.feedback_pct.mean)
    } else {
        name
    }
}

impl Panel for Fig3Task {
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        draw_panel(area, self)
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    task: &Fig3Task,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let x_max = task
        .methods
        .iter()
        .map(|m| m.steps)
        .max()
        .unwrap_or(1)
        .max(1) as f64;
    let (y_lo, y_hi) = padded_range(task.methods.iter().flat_map(|m| {
        let c = &m.curve;
        c.mean.iter().zip(&c.se).flat_map(|(m, s)| [m - s, m + s])
    }));
    let mut chart = ChartBuilder::on(area)
        .caption(task_title(task.task), text(TITLE_PX))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..x_max, y_lo..y_hi)?;
    let y_span = y_hi - y_lo;
    let x_fmt = |x: &f64| short_number(*x, x_max);
    let y_fmt = |y: &f64| short_number(*y, y_span);
    draw_mesh(
        &mut chart,
        Axis {
            desc: "Environment steps",
            labels: 6,
            format: &x_fmt,
        },
        Axis {
            desc: "Cumulative reward",
            labels: 6,
            format: &y_fmt,
        },
    )?;

    let colors = panel_colors(task.methods.iter().map(|row| row.method.as_str()));
    // Bands first, so that no line is hidden under another method's band.
    for (row, &color) in task.methods.iter().zip(&colors) {
        let c = &row.curve;
        let upper = c.x.iter().zip(c.mean.iter().zip(&c.se));
        let mut outline: Vec<(f64, f64)> = upper.clone().map(|(x, (m, s))| (*x, m + s)).collect();
        outline.extend(upper.rev().map(|(x, (m, s))| (*x, m - s)));
        chart.draw_series(std::iter::once(Polygon::new(
            outline,
            color.mix(0.18).filled(),
        )))?;
    }
    for (row, &color) in task.methods.iter().zip(&colors) {
        let points = row
            .curve
            .x
            .iter()
            .copied()
            .zip(row.curve.mean.iter().copied());
        draw_labelled_line(&mut chart, points, color, legend_label(row))?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    Ok(())
}
