//! `--plots DIR`: PNG residual maps before and after the winning effect.
//!
//! - `DIR/residuals.png`: measured − sim for Fx, Fy, Mz (rows) against α, κ, Fz, Vx, γ and time
//!   (columns); grey the sim, blue the sim with the winning effect (held-out: each block
//!   predicted by parameters fitted on the others). At most 2000 points per series (even stride).
//! - `DIR/map_alpha_fz.png`: the RMS residual in noise units, summed over the channels, on an
//!   α × Fz grid (quantile bins), before (left) and after (right); white is the noise floor,
//!   red ≥ 20× it (log scale).
//!
//! Fonts, ranges and labels: [`crate::plot`].

use super::cv::Score;
use super::effects::{resid, Ctx, Spec};
use super::sim::Out;
use super::stats;
use crate::plot::{err, font, range};
use plotters::prelude::*;
use std::path::Path;

const MAX_POINTS: usize = 2000;

/// Draws the residual maps of the sim (and of the winning effect, if any) into `dir`.
pub fn residual_maps(dir: &Path, ctx: &Ctx, winner: Option<(&Spec, &Score)>) -> Result<(), String> {
    font()?;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: cannot create: {e}", dir.display()))?;
    let log = ctx.log;
    let before = resid(log, &ctx.base.out);
    let after: Option<&[Out]> = winner.map(|(_, s)| s.heldout_resid.as_slice());
    let name = winner.map(|(sp, _)| sp.effect.name()).unwrap_or("none");
    scatter(&dir.join("residuals.png"), ctx, &before, after, name)?;
    heatmap(&dir.join("map_alpha_fz.png"), ctx, &before, after, name)
}

fn scatter(
    path: &Path,
    ctx: &Ctx,
    before: &[Out],
    after: Option<&[Out]>,
    name: &str,
) -> Result<(), String> {
    let log = ctx.log;
    let vars: [(&str, &[f64]); 6] = [
        ("α [rad]", &log.alpha),
        ("κ [-]", &log.kappa),
        ("Fz [N]", &log.fz),
        ("Vx [m/s]", &log.vx),
        ("γ [rad]", &log.gamma),
        ("t [s]", &log.t),
    ];
    let chans = ["Fx [N]", "Fy [N]", "Mz [N m]"];
    let stride = log.len().div_ceil(MAX_POINTS).max(1);
    let rows: Vec<usize> = (0..log.len()).step_by(stride).collect();
    let root = BitMapBackend::new(path, (1800, 760)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let (title, body) = root.split_vertically(40);
    title
        .draw_text(
            &format!("measured − sim: grey the sim, blue with '{name}' (held-out)"),
            &("sans-serif", 20).into_text_style(&title),
            (10, 10),
        )
        .map_err(err(path))?;
    let panels = body.split_evenly((3, vars.len()));
    for (k, area) in panels.iter().enumerate() {
        let (c, v) = (k / vars.len(), k % vars.len());
        let x = vars[v].1;
        let xr = range(rows.iter().map(|&i| x[i]));
        let yr = range(
            rows.iter()
                .map(|&i| before[i][c])
                .chain(rows.iter().filter_map(|&i| after.map(|a| a[i][c]))),
        );
        let mut chart = ChartBuilder::on(area)
            .margin(6)
            .x_label_area_size(28)
            .y_label_area_size(52)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err(path))?;
        chart
            .configure_mesh()
            .x_desc(vars[v].0)
            .y_desc(chans[c])
            .x_labels(4)
            .y_labels(5)
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            .draw()
            .map_err(err(path))?;
        let grey = RGBColor(150, 150, 150).mix(0.5);
        chart
            .draw_series(
                rows.iter()
                    .map(|&i| Circle::new((x[i], before[i][c]), 1, grey.filled())),
            )
            .map_err(err(path))?;
        if let Some(a) = after {
            let blue = RGBColor(31, 119, 180).mix(0.6);
            chart
                .draw_series(
                    rows.iter()
                        .map(|&i| Circle::new((x[i], a[i][c]), 1, blue.filled())),
                )
                .map_err(err(path))?;
        }
    }
    root.present().map_err(err(path))
}

fn heatmap(
    path: &Path,
    ctx: &Ctx,
    before: &[Out],
    after: Option<&[Out]>,
    name: &str,
) -> Result<(), String> {
    let log = ctx.log;
    const NB: usize = 8;
    let qa: Vec<f64> = (0..=NB)
        .map(|k| stats::quantile(&log.alpha, k as f64 / NB as f64))
        .collect();
    let qf: Vec<f64> = (0..=NB)
        .map(|k| stats::quantile(&log.fz, k as f64 / NB as f64))
        .collect();
    let bin = |e: &[f64], v: f64| (1..NB).take_while(|&k| v >= e[k]).count();
    let grid = |r: &[Out]| -> Vec<Vec<f64>> {
        let mut s = vec![vec![0.0; NB]; NB];
        let mut n = vec![vec![0usize; NB]; NB];
        for (i, ri) in r.iter().enumerate() {
            let (a, f) = (bin(&qa, log.alpha[i]), bin(&qf, log.fz[i]));
            s[a][f] += (0..3).map(|c| (ri[c] / ctx.noise[c]).powi(2)).sum::<f64>() / 3.0;
            n[a][f] += 1;
        }
        (0..NB)
            .map(|a| {
                (0..NB)
                    .map(|f| {
                        if n[a][f] > 0 {
                            (s[a][f] / n[a][f] as f64).sqrt()
                        } else {
                            f64::NAN
                        }
                    })
                    .collect()
            })
            .collect()
    };
    let root = BitMapBackend::new(path, (1100, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let (title, body) = root.split_vertically(40);
    title
        .draw_text(
            "RMS residual / noise floor on an α × Fz grid (log scale: white = noise, red ≥ 20× noise)",
            &("sans-serif", 18).into_text_style(&title),
            (10, 10),
        )
        .map_err(err(path))?;
    let halves = body.split_evenly((1, 2));
    let sets: [(&str, Option<&[Out]>); 2] = [("sim", Some(before)), (name, after)];
    for (area, (label, r)) in halves.iter().zip(sets) {
        let mut chart = ChartBuilder::on(area)
            .caption(
                if r.is_some() {
                    label.to_string()
                } else {
                    "no winning effect".to_string()
                },
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(60)
            .build_cartesian_2d(0f64..NB as f64, 0f64..NB as f64)
            .map_err(err(path))?;
        let fmt_a = |x: &f64| format!("{:.3}", qa[(x.round() as usize).min(NB)]);
        let fmt_f = |y: &f64| format!("{:.0}", qf[(y.round() as usize).min(NB)]);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("α [rad] (bin edges)")
            .y_desc("Fz [N] (bin edges)")
            .x_labels(NB + 1)
            .y_labels(NB + 1)
            .x_label_formatter(&fmt_a)
            .y_label_formatter(&fmt_f)
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(err(path))?;
        let Some(r) = r else { continue };
        let g = grid(r);
        chart
            .draw_series(
                (0..NB)
                    .flat_map(|a| (0..NB).map(move |f| (a, f)))
                    .map(|(a, f)| {
                        let v = g[a][f];
                        let col = if v.is_finite() {
                            let w = (v.max(1.0).ln() / 20f64.ln()).clamp(0.0, 1.0);
                            RGBColor(255, (255.0 * (1.0 - w)) as u8, (255.0 * (1.0 - w)) as u8)
                        } else {
                            RGBColor(220, 220, 220)
                        };
                        Rectangle::new(
                            [(a as f64, f as f64), (a as f64 + 1.0, f as f64 + 1.0)],
                            col.filled(),
                        )
                    }),
            )
            .map_err(err(path))?;
    }
    root.present().map_err(err(path))
}
