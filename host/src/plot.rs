//! The one plotting module of the host tool: the bundled font, the error of a failed drawing,
//! axis ranges and tick labels, shared by the PNGs of `gough sim`, `gough gap` and `gough mu`,
//! and the Gough-plot panel ([`gough()`], Fy against Mz) that `gough sim` and `gough mu demo` draw.
//!
//! Text is drawn with a bundled subset of DejaVu Sans (`host/assets/fonts/`, Bitstream Vera
//! licence, see the LICENSE file there), so no system font is looked up.
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();
const FONT_BYTES: &[u8] = include_bytes!("../assets/fonts/DejaVuSans-subset.ttf");

/// Registers the bundled font as "sans-serif" (once); every PNG of the host tool uses it.
pub fn font() -> Result<(), String> {
    let mut res = Ok(());
    FONT.call_once(|| {
        res = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_BYTES)
            .map_err(|_| "bundled font is not a valid TrueType file".to_string());
    });
    res
}

/// The one-line error of a drawing into `path` that failed.
pub fn err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> String + '_ {
    move |e| format!("{}: cannot draw: {e}", path.display())
}

/// The axis range of `vals` (finite values only), padded by 5 % (and never empty);
/// (−1, 1) when there is no finite value.
pub fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05)
        .max(1e-3 * hi.abs().max(lo.abs()))
        .max(1e-9);
    (lo - pad, hi + pad)
}

/// An axis label with as many decimals as the axis span needs (about 2 significant digits).
pub fn tick(v: f64, span: f64) -> String {
    let decimals = (1.0 - span.abs().max(1e-12).log10().floor()).clamp(0.0, 6.0) as usize;
    let s = format!("{v:.decimals$}");
    // "-0" and "-0.00" read as noise.
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// One series of a Gough-plot panel: its legend label (none when empty), its colour and its
/// points (Mz in N·m, Fy in N).
pub struct GoughSeries {
    /// Legend label; an empty label puts no legend entry.
    pub label: String,
    /// Line colour.
    pub colour: RGBColor,
    /// The points, (Mz in N·m, Fy in N).
    pub points: Vec<(f64, f64)>,
}

/// Draws one Gough-plot panel (Fy against Mz, the paper's figure) on `area`: the caption, the
/// axes (Mz in N·m on x, Fy in kN on y, labelled by [`tick`]), the model `curves` (thick lines)
/// and the `trajectories` (thin lines) over them, and a legend when a series has a label.
///
/// `ranges` are the (Mz in N·m, Fy in N) axis ranges; `None` takes [`range`] of the points drawn
/// (give them to share the axes between panels).
pub fn gough<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    curves: &[GoughSeries],
    trajectories: &[GoughSeries],
    ranges: Option<((f64, f64), (f64, f64))>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let all = || curves.iter().chain(trajectories).flat_map(|s| &s.points);
    let ((mlo, mhi), (flo, fhi)) =
        ranges.unwrap_or_else(|| (range(all().map(|p| p.0)), range(all().map(|p| p.1))));
    let (flo, fhi) = (flo / 1e3, fhi / 1e3);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(34)
        .y_label_area_size(52)
        .build_cartesian_2d(mlo..mhi, flo..fhi)?;
    chart
        .configure_mesh()
        .x_labels(5)
        .y_labels(5)
        .x_label_formatter(&|v| tick(*v, mhi - mlo))
        .y_label_formatter(&|v| tick(*v, fhi - flo))
        .x_desc("Mz [N·m]")
        .y_desc("Fy [kN]")
        .label_style(("sans-serif", 11))
        .axis_desc_style(("sans-serif", 13))
        .light_line_style(WHITE)
        .draw()?;
    let series = curves
        .iter()
        .map(|s| (s, 2))
        .chain(trajectories.iter().map(|s| (s, 1)));
    for (s, width) in series {
        let drawn = chart.draw_series(LineSeries::new(
            s.points.iter().map(|&(m, f)| (m, f / 1e3)),
            s.colour.stroke_width(width),
        ))?;
        if !s.label.is_empty() {
            let c = s.colour;
            drawn
                .label(s.label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], c));
        }
    }
    if curves
        .iter()
        .chain(trajectories)
        .any(|s| !s.label.is_empty())
    {
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 11))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
    }
    Ok(())
}
