//! PNG plots of a [`Log`]: the main signals against time, and the Gough plot (Fy against Mz)
//! per wheel.
//!
//! Fonts, ranges and labels: [`crate::plot`].

use super::{Log, Record, WHEELS};
use crate::plot::{self, err, font, range, tick, GoughSeries};
use plotters::prelude::*;
use std::path::Path;

/// At most this many points per series (the log is thinned by a fixed stride).
const MAX_POINTS: usize = 3000;
const WHEEL_COLOURS: [RGBColor; 4] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// The value a series takes from a record.
type Getter<'a> = Box<dyn Fn(&Record) -> f64 + 'a>;

/// A panel: a title and series of (name, colour, value of a record).
struct Panel<'a> {
    title: &'a str,
    series: Vec<(String, RGBColor, Getter<'a>)>,
}

fn per_wheel<'a>(title: &'a str, f: impl Fn(&super::WheelRecord) -> f64 + Copy + 'a) -> Panel<'a> {
    Panel {
        title,
        series: (0..4)
            .map(|i| {
                let g: Getter = Box::new(move |r: &Record| f(&r.wheels[i]));
                (WHEELS[i].to_string(), WHEEL_COLOURS[i], g)
            })
            .collect(),
    }
}

fn vehicle<'a>(title: &'a str, f: impl Fn(&Record) -> f64 + 'a) -> Panel<'a> {
    Panel {
        title,
        series: vec![("".into(), BLACK, Box::new(f))],
    }
}

/// Draws the main signals against time into `path` (PNG, `w`×`h` pixels).
pub fn signals(log: &Log, title: &str, path: &Path, (w, h): (u32, u32)) -> Result<(), String> {
    font()?;
    let stride = log.records.len().div_ceil(MAX_POINTS).max(1);
    let recs: Vec<&Record> = log.records.iter().step_by(stride).collect();
    let panels = vec![
        vehicle("speed vx [m/s]", |r| r.vehicle.vx),
        vehicle("steer δ (road wheel) [°]", |r| {
            r.vehicle.steer.to_degrees()
        }),
        vehicle("yaw rate r [°/s]", |r| r.vehicle.r.to_degrees()),
        Panel {
            title: "acceleration [m/s²]",
            series: vec![
                ("ax".into(), RED, Box::new(|r: &Record| r.vehicle.ax)),
                ("ay".into(), BLUE, Box::new(|r: &Record| r.vehicle.ay)),
            ],
        },
        per_wheel("Fz [kN]", |w| w.fz / 1e3),
        per_wheel("Fx [kN]", |w| w.fx / 1e3),
        per_wheel("Fy [kN]", |w| w.fy / 1e3),
        per_wheel("Mz [N·m]", |w| w.mz),
        per_wheel("κ (wheel slip) [-]", |w| w.kappa),
        per_wheel("α (slip angle) [°]", |w| w.alpha.to_degrees()),
        per_wheel("μ under the wheel [-]", |w| w.mu_true),
        per_wheel("torque drive − brake [kN·m]", |w| w.torque / 1e3),
    ];
    let e = err(path);
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(&e)?;
    let areas = root.split_evenly((4, 3));
    let t0 = recs.first().map_or(0.0, |r| r.t);
    let t1 = recs.last().map_or(1.0, |r| r.t).max(t0 + 1e-3);
    for (panel, area) in panels.iter().zip(areas.iter()) {
        let (lo, hi) = range(
            panel
                .series
                .iter()
                .flat_map(|(_, _, f)| recs.iter().map(move |r| f(r))),
        );
        let mut chart = ChartBuilder::on(area)
            .caption(panel.title, ("sans-serif", 15))
            .margin(6)
            .x_label_area_size(22)
            .y_label_area_size(48)
            .build_cartesian_2d(t0..t1, lo..hi)
            .map_err(&e)?;
        chart
            .configure_mesh()
            .x_labels(6)
            .y_labels(5)
            .x_label_formatter(&|v| tick(*v, t1 - t0))
            .y_label_formatter(&|v| tick(*v, hi - lo))
            .label_style(("sans-serif", 11))
            .light_line_style(WHITE)
            .draw()
            .map_err(&e)?;
        for (name, colour, f) in &panel.series {
            let s = chart
                .draw_series(LineSeries::new(recs.iter().map(|r| (r.t, f(r))), colour))
                .map_err(&e)?;
            if !name.is_empty() {
                let c = *colour;
                s.label(name.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], c));
            }
        }
        if panel.series.len() > 1 {
            chart
                .configure_series_labels()
                .label_font(("sans-serif", 11))
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(&e)?;
        }
    }
    root.present().map_err(&e)?;
    Ok(())
}

/// Draws the Gough plot (Fy against Mz, the paper's figure) of each wheel into `path`: one
/// [`crate::plot::gough`] panel per wheel, on shared axes.
pub fn gough(log: &Log, title: &str, path: &Path, (w, h): (u32, u32)) -> Result<(), String> {
    font()?;
    let stride = log.records.len().div_ceil(MAX_POINTS).max(1);
    let recs: Vec<&Record> = log.records.iter().step_by(stride).collect();
    let e = err(path);
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(&e)?;
    let areas = root.split_evenly((2, 2));
    let ranges = (
        range(recs.iter().flat_map(|r| r.wheels.iter().map(|w| w.mz))),
        range(recs.iter().flat_map(|r| r.wheels.iter().map(|w| w.fy))),
    );
    for (i, area) in areas.iter().enumerate() {
        let trajectory = GoughSeries {
            label: String::new(),
            colour: WHEEL_COLOURS[i],
            points: recs
                .iter()
                .map(|r| (r.wheels[i].mz, r.wheels[i].fy))
                .collect(),
        };
        plot::gough(
            area,
            &format!("{}: Fy against Mz", WHEELS[i]),
            &[],
            &[trajectory],
            Some(ranges),
        )
        .map_err(&e)?;
    }
    root.present().map_err(&e)?;
    Ok(())
}
