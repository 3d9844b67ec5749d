//! The bench's and the demo's pictures: μ against time, and the Gough plot of a wheel.

use super::sensors::WheelTrace;
use crate::mu::Estimate;
use crate::sim::Log;
use gough::math::Libm;
use gough::mf::Params;
use gough::mu::State;
use std::path::Path;

/// μ against time: the truth, the utilisation, and each series of estimates (a line; its
/// identifiable samples as dots).
pub fn plot_mu(
    tr: &WheelTrace,
    series: &[(&str, &[Estimate])],
    path: &Path,
    title: &str,
) -> Result<(), String> {
    use plotters::prelude::*;
    crate::plot::font()?;
    let e = |x: &dyn std::fmt::Display| format!("{}: {x}", path.display());
    let root = BitMapBackend::new(path, (900, 450)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let t_end = tr.rows.last().map_or(1.0, |r| r.t);
    let mut ch = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(0.0..t_end, 0.0..1.4)
        .map_err(|x| e(&x))?;
    ch.configure_mesh()
        .x_desc("t [s]")
        .y_desc("μ")
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(|x| e(&x))?;
    let step = (tr.rows.len() / 2000).max(1);
    ch.draw_series(LineSeries::new(
        tr.rows
            .iter()
            .zip(&tr.mu_true)
            .step_by(step)
            .map(|(r, &m)| (r.t, m)),
        BLACK.stroke_width(2),
    ))
    .map_err(|x| e(&x))?
    .label("true μ")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], BLACK));
    ch.draw_series(LineSeries::new(
        tr.rows
            .iter()
            .zip(&tr.util)
            .step_by(step)
            .map(|(r, &u)| (r.t, u.min(1.4))),
        RGBColor(180, 180, 180),
    ))
    .map_err(|x| e(&x))?
    .label("utilisation |F|/(μFz)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], RGBColor(180, 180, 180)));
    let colours = [
        RGBColor(214, 39, 40),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
    ];
    for (k, (name, est)) in series.iter().enumerate() {
        let c = colours[k % 3];
        ch.draw_series(
            tr.rows
                .iter()
                .zip(est.iter())
                .step_by(step)
                .filter(|(_, e)| e.state == State::Identifiable)
                .map(|(r, e)| Circle::new((r.t, e.mu), 1, c.filled())),
        )
        .map_err(|x| e(&x))?
        .label(format!("{name} (identifiable)"))
        .legend(move |(x, y)| Circle::new((x + 7, y), 3, c.filled()));
        ch.draw_series(LineSeries::new(
            tr.rows
                .iter()
                .zip(est.iter())
                .step_by(step)
                .map(|(r, e)| (r.t, e.mu)),
            c.mix(0.5),
        ))
        .map_err(|x| e(&x))?;
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// The Gough plot: the model's Fy–Mz family for μ = 0.1…1.0 at the wheel's mean load, and the
/// wheel's simulated trajectory, as one [`crate::plot::gough`] panel.
pub fn plot_gough(p: &Params<f64>, log: &Log, w: usize, path: &Path) -> Result<(), String> {
    use crate::plot::{self, GoughSeries};
    use gough::mf::{self, Input, Options};
    use plotters::prelude::*;
    plot::font()?;
    let e = plot::err(path);
    let fz_mean =
        log.records.iter().map(|r| r.wheels[w].fz).sum::<f64>() / log.records.len().max(1) as f64;
    let mu0 = log.mu_y0;
    let mut curves = Vec::new();
    for (k, mu) in [0.1, 0.3, 0.5, 0.7, 1.0].into_iter().enumerate() {
        let mut q = p.clone();
        q.lmux = mu / mu0;
        q.lmuy = mu / mu0;
        let points = (-120..=120)
            .filter_map(|i| {
                let a = i as f64 * 0.0025;
                mf::eval::<f64, Libm>(
                    &q,
                    &Input {
                        fz: fz_mean,
                        alpha: a,
                        vx: 20.0,
                        ..Input::default()
                    },
                    &Options {
                        limits: false,
                        ..Options::default()
                    },
                )
                .ok()
                .map(|o| (o.mz, o.fy))
            })
            .collect();
        let c = Palette99::pick(k).to_rgba();
        curves.push(GoughSeries {
            label: format!("μ = {mu}"),
            colour: RGBColor(c.0, c.1, c.2),
            points,
        });
    }
    let step = (log.records.len() / 3000).max(1);
    let trajectory = GoughSeries {
        label: "simulated wheel".into(),
        colour: BLACK,
        points: log
            .records
            .iter()
            .step_by(step)
            .map(|r| (r.wheels[w].mz, r.wheels[w].fy))
            .collect(),
    };
    let root = BitMapBackend::new(path, (700, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    plot::gough(
        &root,
        &format!("Gough plot: model family at Fz = {fz_mean:.0} N, and the wheel's trajectory"),
        &curves,
        &[trajectory],
        None,
    )
    .map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(())
}
