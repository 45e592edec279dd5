//! A human-subject study's figure (the paper's Figure 4): the cumulative reward per condition
//! against environment steps, mean ± s.e. over participants as a line and a band; then the
//! survey, one group of bars per question, a bar per condition at its mean answer with ± s.e.
//! whiskers. The numbers come in already aggregated (the CLI turns a study's results into these
//! two panels), so this module knows nothing about studies.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    Axis, Panel, TITLE_PX, draw_labelled_line, draw_legend, draw_mesh, method_color, padded_range,
    short_number, text,
};

/// One condition's mean curve.
#[derive(Clone, Debug, PartialEq)]
pub struct ConditionCurve {
    pub name: String,
    pub steps: Vec<f64>,
    pub mean: Vec<f64>,
    pub se: Vec<f64>,
}

/// One question's bars: per condition (in the curves' order) the mean answer and its s.e.
#[derive(Clone, Debug, PartialEq)]
pub struct QuestionBars {
    pub question: String,
    pub points: u8,
    /// (condition, mean, s.e.); NaN where nobody answered.
    pub bars: Vec<(String, f64, f64)>,
}

/// The two panels of a study's figure.
#[derive(Clone, Debug, PartialEq)]
pub enum StudyPanel {
    Curves {
        title: String,
        curves: Vec<ConditionCurve>,
    },
    Survey {
        title: String,
        questions: Vec<QuestionBars>,
    },
}

impl Panel for StudyPanel {
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        match self {
            StudyPanel::Curves { title, curves } => draw_curves(area, title, curves),
            StudyPanel::Survey { title, questions } => draw_survey(area, title, questions),
        }
    }
}

fn draw_curves<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    curves: &[ConditionCurve],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let x_max = curves
        .iter()
        .filter_map(|c| c.steps.last().copied())
        .fold(1.0f64, f64::max);
    let (y_lo, y_hi) = padded_range(curves.iter().flat_map(|c| {
        c.mean
            .iter()
            .zip(&c.se)
            .flat_map(|(m, s)| [m - s.max(0.0), m + s.max(0.0)])
    }));
    let mut chart = ChartBuilder::on(area)
        .caption(title, text(TITLE_PX))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..x_max, y_lo..y_hi)?;
    draw_mesh(
        &mut chart,
        Axis {
            desc: "environment steps",
            labels: 6,
            format: &|v| short_number(*v, x_max),
        },
        Axis {
            desc: "cumulative reward",
            labels: 6,
            format: &|v| short_number(*v, y_hi - y_lo),
        },
    )?;
    for c in curves {
        let color = method_color(&c.name);
        let finite = |v: &f64| if v.is_finite() { *v } else { 0.0 };
        let upper = c
            .steps
            .iter()
            .zip(&c.mean)
            .zip(&c.se)
            .map(|((x, m), s)| (*x, m + finite(s)));
        let lower = c
            .steps
            .iter()
            .zip(&c.mean)
            .zip(&c.se)
            .map(|((x, m), s)| (*x, m - finite(s)));
        let band: Vec<(f64, f64)> = upper.chain(lower.rev()).collect();
        chart.draw_series(std::iter::once(Polygon::new(
            band,
            color.mix(0.18).filled(),
        )))?;
        let points = c.steps.iter().copied().zip(c.mean.iter().copied());
        draw_labelled_line(&mut chart, points, color, c.name.clone())?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

fn draw_survey<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    questions: &[QuestionBars],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let groups = questions.len().max(1) as f64;
    let top = questions.iter().map(|q| q.points).max().unwrap_or(5) as f64;
    let mut chart = ChartBuilder::on(area)
        .caption(title, text(TITLE_PX))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..groups, 0.0..top + 0.5)?;
    let names: Vec<String> = questions.iter().map(|q| q.question.clone()).collect();
    draw_mesh(
        &mut chart,
        Axis {
            desc: "question",
            labels: 0,
            format: &|_| String::new(),
        },
        Axis {
            desc: "answer (mean ± s.e.)",
            labels: top as usize + 1,
            format: &|v| format!("{v:.0}"),
        },
    )?;
    for (g, q) in questions.iter().enumerate() {
        let n = q.bars.len().max(1) as f64;
        let width = 0.8 / n;
        chart.draw_series(std::iter::once(Text::new(
            names[g].clone(),
            (g as f64 + 0.4, -0.05 * top),
            text(15),
        )))?;
        for (i, (condition, mean, se)) in q.bars.iter().enumerate() {
            if !mean.is_finite() {
                continue;
            }
            let color = method_color(condition);
            let x0 = g as f64 + 0.1 + i as f64 * width;
            let bar = Rectangle::new([(x0, 0.0), (x0 + width * 0.9, *mean)], color.filled());
            let series = chart.draw_series(std::iter::once(bar))?;
            if g == 0 {
                let name = condition.clone();
                series.label(name).legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 18, y + 6)], color.filled())
                });
            }
            if se.is_finite() && *se > 0.0 {
                let mid = x0 + width * 0.45;
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(mid, mean - se), (mid, mean + se)],
                    BLACK.stroke_width(2),
                )))?;
            }
        }
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::plot::write_figure;

    #[test]
    fn a_study_figure_is_written_as_svg_and_png() {
        let dir = tempfile::tempdir().unwrap();
        let curve = |name: &str, k: f64| ConditionCurve {
            name: name.into(),
            steps: vec![0.0, 50.0, 100.0],
            mean: vec![0.0, 5.0 * k, 10.0 * k],
            se: vec![0.0, 1.0, f64::NAN],
        };
        let panels = [
            StudyPanel::Curves {
                title: "Reaching".into(),
                curves: vec![curve("dref", 2.0), curve("sac", 1.0)],
            },
            StudyPanel::Survey {
                title: "Survey".into(),
                questions: vec![QuestionBars {
                    question: "E".into(),
                    points: 5,
                    bars: vec![
                        ("dref".into(), 4.0, 0.5),
                        ("sac".into(), f64::NAN, f64::NAN),
                    ],
                }],
            },
        ];
        let (svg, png) = (dir.path().join("f.svg"), dir.path().join("f.png"));
        write_figure(&panels, &svg, &png).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.contains("dref") && text.contains("cumulative reward"));
        assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    }
}
