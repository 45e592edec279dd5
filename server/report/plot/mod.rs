//! The paper-style figures, drawn with plotters into SVG and PNG from the same code.
//!
//! Each figure is one row of panels, one per task in the paper's order. The drawing functions
//! are generic over the plotters backend and take only aggregated numbers; the public `write_*`
//! functions are the only place that touches files (the two paths they are given).

mod fig3;
mod fig5;
pub mod robustness;
pub mod study;

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::font;
use super::methods::{Fig3Method, order_key};

/// Pixels of one panel; a figure is `tasks` panels side by side.
pub const PANEL_SIZE: (u32, u32) = (560, 440);

/// Font sizes in pixels: panel titles, axis descriptions, tick labels, legend.
const TITLE_PX: u32 = 24;
const DESC_PX: u32 = 18;
const TICK_PX: u32 = 15;
const LEGEND_PX: u32 = 15;

/// matplotlib's "tab10" colours: what readers of the paper's figures are used to.
const TAB10: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// A method's colour: fixed by its place in the paper's legend (so DREF and DRPL are blue, as in
/// the paper, and a method keeps its colour across panels); unknown methods share the rest.
fn method_color(method: &str) -> RGBColor {
    // The paper's rows keep the paper's colours (DREF's is ours too), the authors' DREF and EF at
    // DREF's rate fixed ones; any other row a colour of its name.
    let slot = match Fig3Method::parse(method) {
        Some(Fig3Method::DrefAuthors) => Some(6),
        Some(Fig3Method::DrefMasked | Fig3Method::SacUnscaled) => None,
        Some(kind) => kind.published_column(),
        // Figure 5's four and DRPL-MI after them.
        None => Some(order_key(method).0).filter(|rank| *rank < 5),
    };
    if let Some(slot) = slot {
        return TAB10[slot];
    }
    let spread = method
        .bytes()
        .fold(0usize, |h, b| h.wrapping_mul(31) + b as usize);
    TAB10[7 + spread % 3]
}

/// The colours of one panel's rows, in order: each method's own ([`method_color`]), except
/// where an earlier row of the panel already has it (two EF rows at two DREF rows' rates, or
/// two unknown names that hash alike): that row takes the first tab10 colour the panel does not
/// use yet, so no two lines of a panel look alike while it has ten rows or fewer (past ten,
/// the rows that find none keep their own).
fn panel_colors<'a>(methods: impl IntoIterator<Item = &'a str>) -> Vec<RGBColor> {
    let mut taken: Vec<RGBColor> = Vec::new();
    for method in methods {
        let own = method_color(method);
        let color = if taken.contains(&own) {
            TAB10
                .into_iter()
                .find(|c| !taken.contains(c))
                .unwrap_or(own)
        } else {
            own
        };
        taken.push(color);
    }
    taken
}

/// Figure size for `panels` panels (at least one, so an empty grid still makes a figure).
fn figure_size(panels: usize) -> (u32, u32) {
    (PANEL_SIZE.0 * panels.max(1) as u32, PANEL_SIZE.1)
}

/// Fills the figure white and, when there is nothing to plot, says so instead of leaving a
/// blank image that looks like a rendering bug.
fn prepare<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: usize,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    if panels == 0 {
        let (w, h) = root.dim_in_pixel();
        let style = TextStyle::from((FontFamily::SansSerif, DESC_PX).into_font())
            .pos(Pos::new(HPos::Center, VPos::Center));
        root.draw_text("no finished runs yet", &style, (w as i32 / 2, h as i32 / 2))?;
    }
    Ok(())
}

/// One task's panel of a figure.
pub trait Panel {
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>;
}

fn draw_panels<DB: DrawingBackend, P: Panel>(
    root: &DrawingArea<DB, Shift>,
    panels: &[P],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    prepare(root, panels.len())?;
    if panels.is_empty() {
        return Ok(());
    }
    for (area, panel) in root.split_evenly((1, panels.len())).iter().zip(panels) {
        panel.draw(area)?;
    }
    root.present()
}

/// Draws a figure, one panel per task side by side, into `svg` and `png`.
pub fn write_figure<P: Panel>(panels: &[P], svg: &Path, png: &Path) -> anyhow::Result<()> {
    font::ensure_registered();
    let size = figure_size(panels.len());
    draw_panels(&SVGBackend::new(svg, size).into_drawing_area(), panels)?;
    draw_panels(&BitMapBackend::new(png, size).into_drawing_area(), panels)?;
    Ok(())
}

/// One axis of a panel: its description, how many tick labels, and how they read.
struct Axis<'a> {
    desc: &'a str,
    labels: usize,
    format: &'a dyn Fn(&f64) -> String,
}

/// The mesh every panel draws: both axes described and labelled, and major grid lines only
/// (the minor ones crowd small panels side by side).
fn draw_mesh<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    x: Axis<'_>,
    y: Axis<'_>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_mesh()
        .x_desc(x.desc)
        .y_desc(y.desc)
        .axis_desc_style(text(DESC_PX))
        .label_style(text(TICK_PX))
        .x_labels(x.labels)
        .y_labels(y.labels)
        .x_label_formatter(x.format)
        .y_label_formatter(y.format)
        .light_line_style(TRANSPARENT)
        .bold_line_style(BLACK.mix(0.12))
        .draw()
}

/// One curve drawn as a line, named in the legend by a short stroke of its colour.
fn draw_labelled_line<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    points: impl IntoIterator<Item = (f64, f64)>,
    color: RGBColor,
    label: impl Into<String>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .draw_series(LineSeries::new(points, color.stroke_width(2)))?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3)));
    Ok(())
}

/// The legend of every panel: the same font, a translucent box, placed where curves are not.
fn draw_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    position: SeriesLabelPosition,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font(text(LEGEND_PX))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .draw()
}

/// Axis range that holds `values` with 5 % headroom, always including 0 (a cumulative reward or
/// an alignment is read against zero) and never empty.
fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((0.0f64, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if hi - lo <= f64::EPSILON {
        return (lo - 0.5, hi + 1.0);
    }
    let pad = 0.05 * (hi - lo);
    (if lo < 0.0 { lo - pad } else { lo }, hi + pad)
}

/// Tick label for large numbers: "150k", "12.5k", "-6k"; small ones as they are.
fn short_number(v: f64, span: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if span >= 5_000.0 {
        let k = v / 1000.0;
        if (k - k.round()).abs() < 1e-9 {
            format!("{k:.0}k")
        } else {
            format!("{k:.1}k")
        }
    } else if span >= 10.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}

fn text(px: u32) -> TextStyle<'static> {
    TextStyle::from((FontFamily::SansSerif, px).into_font())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_ranges_include_zero_and_pad() {
        assert_eq!(padded_range([10.0, 20.0].into_iter()), (0.0, 21.0));
        let (lo, hi) = padded_range([-10.0, 10.0, f64::NAN].into_iter());
        assert!((lo + 11.0).abs() < 1e-9 && (hi - 11.0).abs() < 1e-9);
        assert_eq!(padded_range(std::iter::empty()), (-0.5, 1.0));
    }

    #[test]
    fn report_tick_labels_are_short() {
        assert_eq!(short_number(150_000.0, 150_000.0), "150k");
        assert_eq!(short_number(12_500.0, 40_000.0), "12.5k");
        assert_eq!(short_number(-6_000.0, 40_000.0), "-6k");
        assert_eq!(short_number(250.0, 1_000.0), "250");
        assert_eq!(short_number(0.5, 1.0), "0.50");
        assert_eq!(short_number(0.0, 150_000.0), "0");
    }

    #[test]
    fn report_known_methods_keep_the_papers_colours() {
        assert_eq!(method_color("dref"), TAB10[0]);
        assert_eq!(method_color("drpl"), TAB10[0]);
        assert_eq!(method_color("drpl-mi"), TAB10[4]);
        assert_eq!(method_color("sac"), TAB10[4]);
        assert_eq!(method_color("ef-2.5"), TAB10[5]);
        assert_eq!(method_color("dref-authors"), TAB10[6]);
        assert_eq!(method_color("something"), method_color("something"));
    }

    #[test]
    fn report_no_two_rows_of_a_panel_share_a_colour() {
        // Lunar Lander's 150k panel: EF at the authors' DREF's rate and at DREF's.
        let rows = [
            "dref",
            "dref-authors",
            "ef-100",
            "sac",
            "ef-2.12",
            "ef-9.06",
        ];
        let colors = panel_colors(rows);
        assert_eq!(
            colors[..5],
            [TAB10[0], TAB10[6], TAB10[1], TAB10[4], TAB10[5]]
        );
        assert!(!colors[..5].contains(&colors[5]), "{colors:?}");
        // A panel with one EF row keeps its fixed colour.
        assert_eq!(panel_colors(["dref", "ef-6.22"])[1], TAB10[5]);
    }
}
