//! The bench's sensor model: what the estimators see of a simulated wheel — its Fy, Mz, Fz, Fx
//! with additive Gaussian noise (seeded) and a pure delay, κ as an ABS controller measures it
//! (noisy), and the exact (delayed) slips a slip sensor would give the peers — and the truth it
//! is measured against (μ under the wheel, utilisation).

use crate::mu::Sample;
use crate::rng::Rng;
use crate::sim::Log;

/// Sensor model of the benchmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensors {
    /// Mz noise rms \[N·m\].
    pub sigma_mz: f64,
    /// Fy, Fx, Fz noise rms as a fraction of Fz.
    pub sigma_rel: f64,
    /// Pure delay \[s\].
    pub delay: f64,
    /// Longitudinal slip noise, rms \[-\].
    pub sigma_kappa: f64,
}

impl Default for Sensors {
    fn default() -> Self {
        Sensors {
            sigma_mz: 2.0,
            sigma_rel: 0.01,
            delay: 0.010,
            sigma_kappa: 0.005,
        }
    }
}

/// One wheel's measured samples (noisy, delayed) and its truth, per logged step.
pub struct WheelTrace {
    /// What the car's sensors measure: Fz, Fy, Mz, Fx with the sensors' noise, Vx and the camber γ
    /// (static plus roll camber, known to an ECU from the suspension kinematics and the roll
    /// estimate), κ from wheel speed and a vehicle-speed estimate (with its noise), as an ABS
    /// controller has it; no slip angle. All delayed.
    pub rows: Vec<Sample>,
    /// The slips (α \[rad\], κ) a slip sensor measures: exact, delayed (the peers' premise,
    /// [`Method::slip_sensor`](crate::mu::Method::slip_sensor)).
    pub slip_sensor: Vec<(f64, f64)>,
    /// True μ under the wheel at the (undelayed) time of each row.
    pub mu_true: Vec<f64>,
    /// True utilisation |F|/(μ·Fz) at each row.
    pub util: Vec<f64>,
}

impl WheelTrace {
    /// Row `i` as the car's sensors measure it, and with `slip_sensor` the slip sensor's α and
    /// κ in place of the ABS's κ (what a method that needs one, [`Method::slip_sensor`](crate::mu::Method::slip_sensor), sees).
    pub fn sample(&self, i: usize, slip_sensor: bool) -> Sample {
        let s = self.rows[i];
        match self.slip_sensor.get(i) {
            Some(&(alpha, kappa)) if slip_sensor => Sample {
                alpha: Some(alpha),
                kappa: Some(kappa),
                ..s
            },
            _ => s,
        }
    }
}

/// Applies the sensor model to wheel `w` of a log.
pub fn measure(log: &Log, w: usize, s: &Sensors, seed: u64) -> WheelTrace {
    let mut n = Rng::new(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(w as u64 + 1),
    );
    let lag = (s.delay / log.dt).round() as usize;
    let recs = &log.records;
    let mut tr = WheelTrace {
        rows: Vec::with_capacity(recs.len()),
        slip_sensor: Vec::with_capacity(recs.len()),
        mu_true: Vec::with_capacity(recs.len()),
        util: Vec::with_capacity(recs.len()),
    };
    // κ's noise has a generator of its own, so that the other channels' noise is unchanged.
    let mut nk = Rng::new(
        seed.wrapping_mul(0xD1B5_4A32_D192_ED03)
            .wrapping_add(w as u64 + 101),
    );
    for (i, r) in recs.iter().enumerate() {
        let src = &recs[i.saturating_sub(lag)].wheels[w];
        let fz = src.fz.max(0.0);
        let sr = s.sigma_rel * fz;
        let fz_meas = fz + sr * n.normal();
        let fy = src.fy + sr * n.normal();
        let mz = src.mz + s.sigma_mz * n.normal();
        let fx = src.fx + sr * n.normal();
        tr.rows.push(Sample {
            t: r.t,
            fz: fz_meas,
            fy,
            mz,
            fx: Some(fx),
            vx: Some(src.vx),
            kappa: Some(src.kappa + s.sigma_kappa * nk.normal()),
            alpha: None,
            gamma: Some(src.gamma),
        });
        tr.slip_sensor.push((src.alpha, src.kappa));
        let now = &r.wheels[w];
        tr.mu_true.push(now.mu_true);
        tr.util.push(if now.fz > 0.0 && now.mu_true > 0.0 {
            now.fx.hypot(now.fy) / (now.mu_true * now.fz)
        } else {
            0.0
        });
    }
    tr
}

#[cfg(test)]
mod tests {
    use super::super::{simulate_case, Case};
    use super::*;
    use crate::tyre::bundled;

    /// The sensor model is what it says: without noise and delay every row is the simulation's
    /// own; the delay shifts the rows by whole steps and the noise has the rms asked for.
    #[test]
    fn the_sensor_model_reaches_the_rows() {
        let with = |sigma_mz, sigma_rel, delay| Sensors {
            sigma_mz,
            sigma_rel,
            delay,
            ..Sensors::default()
        };
        let p = bundled();
        let case = Case::new("step-steer", "mu=0.5").unwrap();
        let log = simulate_case(&p, &case).unwrap();
        let (exact, late, noisy) = (
            with(0.0, 0.0, 0.0),
            with(0.0, 0.0, 0.02),
            with(5.0, 0.02, 0.0),
        );
        let w = 1;
        let (tr, tl, tn) = (
            measure(&log, w, &exact, 1),
            measure(&log, w, &late, 1),
            measure(&log, w, &noisy, 1),
        );
        let (mut se_mz, mut se_fy) = (0.0, 0.0);
        for (i, r) in log.records.iter().enumerate() {
            let x = &r.wheels[w];
            let (a, b, c) = (&tr.rows[i], &tl.rows[i], &tn.rows[i]);
            assert_eq!(
                (a.fz, a.fy, a.mz, a.fx.unwrap()),
                (x.fz, x.fy, x.mz, x.fx),
                "row {i}"
            );
            if i >= 20 {
                assert_eq!(b.mz, tr.rows[i - 20].mz, "row {i}");
            }
            se_mz += (c.mz - x.mz).powi(2);
            se_fy += ((c.fy - x.fy) / (0.02 * x.fz)).powi(2);
        }
        let n = log.records.len() as f64;
        let (rms_mz, rms_fy) = ((se_mz / n).sqrt(), (se_fy / n).sqrt());
        assert!((rms_mz - 5.0).abs() < 0.25, "Mz noise {rms_mz}");
        assert!((rms_fy - 1.0).abs() < 0.05, "Fy noise {rms_fy} of 2 % Fz");
    }
}
