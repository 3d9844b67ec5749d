//! The one plotting module of the host tool: the bundled font, the error of a failed drawing,
//! axis ranges and tick labels, shared by the PNGs of `gough sim`, `gough gap` and `gough mu`.
//!
//! Text is drawn with a bundled subset of DejaVu Sans (`host/assets/fonts/`, Bitstream Vera
//! licence, see the LICENSE file there), so no system font is looked up.
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
