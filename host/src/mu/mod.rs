//! Friction estimation on logs and on the vehicle simulation: the product's estimator (the
//! core's `gough::mu::bank` at every wheel, [`banks`]) and the published peers it is compared
//! with ([`peers`]), all behind one interface ([`Estimator`], [`Method`]); the closed-loop
//! benchmark ([`bench`](mod@bench)), its bound ([`bound`]), the identifiability map ([`map`])
//! and the tyre file's calibration ([`calibrate`]). Nothing here re-implements the core's
//! estimator.
pub mod banks;
pub mod bench;
pub mod bound;
pub mod calfile;
pub mod calibrate;
#[cfg(feature = "plot")]
pub mod demo;
pub mod estimator;
pub mod map;
pub mod peers;
pub mod scenario;

pub use estimator::{mounting, Estimate, Estimator, Method, Precision, Sample, Setup};

use crate::csvio;
use gough::proto::Wheel;
use std::path::Path;

/// Reads a log of one wheel or of a car into `(wheel, sample)` rows in the file's order; the
/// error is one line naming file, line and column. Columns `t,fz,fy,mz` required,
/// `fx,vx,kappa,alpha,gamma` optional (a column not in the file is `None` in every sample), and
/// `wheel` (0–3: FL, FR, RL, RR; the wheels' rows interleaved in time): without it every row is
/// the front-left wheel's. Time must increase strictly, per wheel.
pub fn read_log(path: &Path) -> Result<Vec<(Wheel, Sample)>, String> {
    let t = csvio::read::<csvio::WheelRow>(path).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(t.rows.len());
    let mut last = [f64::NEG_INFINITY; 4];
    for (r, line) in t.rows.iter().zip(&t.lines) {
        let w = match r.wheel {
            None => Wheel::FrontLeft,
            Some(w) => Wheel::from_index(w as usize)
                .filter(|_| w.fract() == 0.0 && w >= 0.0)
                .ok_or_else(|| {
                    format!(
                        "{}: line {line}, column wheel: {w} is not 0, 1, 2 or 3",
                        path.display()
                    )
                })?,
        };
        let k = w.index();
        if r.t <= last[k] {
            return Err(format!(
                "{}: line {line}, column t: time does not increase ({} after {}{})",
                path.display(),
                r.t,
                last[k],
                if t.has("wheel") {
                    format!(", wheel {k}")
                } else {
                    String::new()
                }
            ));
        }
        last[k] = r.t;
        out.push((
            w,
            Sample {
                t: r.t,
                fz: r.fz,
                fy: r.fy,
                mz: r.mz,
                fx: r.fx,
                vx: r.vx,
                kappa: r.kappa,
                alpha: r.alpha,
                gamma: r.gamma,
            },
        ));
    }
    Ok(out)
}
