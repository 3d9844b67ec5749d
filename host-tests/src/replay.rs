//! `gough replay`: a measurement log → the device (as CAN frames) → the device's answers.
//!
//! LOG columns: `t,fz,fy,mz` required; `fx,vx,alpha,kappa,gamma,wheel` optional (SI, rad, ISO-W;
//! `t` in s, `wheel` 0..3 = FL, FR, RL, RR, default 0). RESULTS columns: `t,wheel,fx,fy,mz,flags,ack`
//! then `mu,sigma,state` (empty until the firmware runs the estimator). `ack` is empty when the
//! device answered with forces, else the reason it did not (`NoSlip`, `EvalError`, ...).
use crate::csvio::{self, CsvError};
use crate::device::Device;
use gough::math::Libm;
use gough::mf::{self, Options, Params};
use gough::proto::{AckCode, Forces, Measurement, Msg, MsgType, Wheel};
use std::collections::VecDeque;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

/// Required log columns.
pub const REQUIRED: [&str; 4] = ["t", "fz", "fy", "mz"];
/// Optional log columns.
pub const OPTIONAL: [&str; 6] = ["fx", "vx", "alpha", "kappa", "gamma", "wheel"];
/// Result columns.
pub const RESULT_COLUMNS: [&str; 10] = [
    "t", "wheel", "fx", "fy", "mz", "flags", "ack", "mu", "sigma", "state",
];

/// One log row as the protocol's measurement.
pub fn read_log(path: &Path) -> Result<Vec<Measurement>, CsvError> {
    let opt: Vec<(&str, f64)> = OPTIONAL.iter().map(|&c| (c, 0.0)).collect();
    let t = csvio::read(path, &REQUIRED, &opt)?;
    let mut out = Vec::with_capacity(t.rows.len());
    for (row, &line) in t.rows.iter().zip(&t.lines) {
        let g = |i: usize| row.get(i).copied().unwrap_or(0.0);
        let o = |k: usize| {
            if t.present.get(k).copied().unwrap_or(false) {
                Some(g(4 + k) as f32)
            } else {
                None
            }
        };
        let err = |msg: String| CsvError {
            file: path.to_path_buf(),
            line,
            column: None,
            msg,
        };
        let ts = g(0);
        if !(0.0..=4294.967295).contains(&ts) {
            return Err(err(format!(
                "t = {ts} s is outside 0..4294.967295 s (a u32 of microseconds)"
            )));
        }
        let w = g(9);
        let wheel = Wheel::from_index(w as usize)
            .filter(|_| w.fract() == 0.0 && w >= 0.0)
            .ok_or_else(|| err(format!("wheel = {w}: expected 0, 1, 2 or 3")))?;
        out.push(Measurement {
            wheel,
            t_us: (ts * 1e6).round() as u32,
            fz: g(1) as f32,
            fy: g(2) as f32,
            mz: g(3) as f32,
            fx: o(0),
            vx: o(1),
            omega: None,
            delta: None,
            alpha: o(2),
            kappa: o(3),
            gamma: o(4),
        });
    }
    Ok(out)
}

/// The device's answer to one measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Answer {
    /// Predicted forces.
    Forces(Forces),
    /// No forces, and why.
    Ack(AckCode),
}

/// Streams `log` to the device, at most `window` measurements in flight; one answer per row.
pub fn stream(dev: &mut Device, log: &[Measurement], window: usize) -> Result<Vec<Answer>, String> {
    let mut out = Vec::with_capacity(log.len());
    let mut in_flight: VecDeque<usize> = VecDeque::new();
    let mut next = 0usize;
    while out.len() < log.len() {
        while next < log.len() && in_flight.len() < window.max(1) {
            dev.send(&Msg::Measurement(log[next]))?;
            in_flight.push_back(next);
            next += 1;
        }
        let m = dev.recv(Duration::from_secs(10))?;
        let ans = match m {
            Msg::Forces(f) => Answer::Forces(f),
            Msg::Ack(a) if a.of == MsgType::Measurement as u8 => Answer::Ack(a.code),
            _ => continue,
        };
        let Some(i) = in_flight.pop_front() else {
            return Err("the device answered a measurement that was not sent".into());
        };
        if let Answer::Forces(f) = ans {
            if f.t_us != log[i].t_us || f.wheel != log[i].wheel {
                return Err(format!(
                    "answer out of order: row {} has t_us {}, the answer {}",
                    i + 1,
                    log[i].t_us,
                    f.t_us
                ));
            }
        }
        out.push(ans);
    }
    Ok(out)
}

/// The host's f32 run of the same core on one measurement: what the device must answer.
pub fn host_f32(p: &Params<f32>, m: &Measurement) -> Answer {
    let Some(input) = m.mf_input(p) else {
        return Answer::Ack(AckCode::NoSlip);
    };
    match mf::eval::<f32, Libm>(p, &input, &Options::default()) {
        Ok(o) => Answer::Forces(Forces {
            wheel: m.wheel,
            t_us: m.t_us,
            fx: o.fx,
            fy: o.fy,
            mz: o.mz,
            flags: o.flags.0,
        }),
        Err(_) => Answer::Ack(AckCode::EvalError),
    }
}

/// Distance in units in the last place between two f32 (0 when equal; large across signs).
pub fn ulps(a: f32, b: f32) -> u64 {
    if a == b {
        return 0;
    }
    let key = |x: f32| {
        let i = x.to_bits() as i32;
        if i < 0 {
            i64::from(i32::MIN) - i64::from(i)
        } else {
            i64::from(i)
        }
    };
    (key(a) - key(b)).unsigned_abs()
}

/// Compares device answers with the host's f32 run; the largest ulp distance over fx, fy, mz,
/// or an error naming the first row that differs in kind.
pub fn compare(p: &Params<f32>, log: &[Measurement], got: &[Answer]) -> Result<u64, String> {
    let mut worst = 0;
    for (i, (m, g)) in log.iter().zip(got).enumerate() {
        match (host_f32(p, m), g) {
            (Answer::Forces(h), Answer::Forces(d)) => {
                worst = worst
                    .max(ulps(h.fx, d.fx))
                    .max(ulps(h.fy, d.fy))
                    .max(ulps(h.mz, d.mz));
                if h.flags != d.flags {
                    return Err(format!(
                        "row {}: flags {} (host) vs {} (device)",
                        i + 1,
                        h.flags,
                        d.flags
                    ));
                }
            }
            (Answer::Ack(a), Answer::Ack(b)) if a == *b => {}
            (h, d) => return Err(format!("row {}: host {h:?}, device {d:?}", i + 1)),
        }
    }
    Ok(worst)
}

/// Writes the RESULTS file (atomically: temporary file, then rename).
pub fn write_results(path: &Path, log: &[Measurement], got: &[Answer]) -> std::io::Result<()> {
    let mut s = String::new();
    s.push_str(&RESULT_COLUMNS.join(","));
    s.push('\n');
    for (m, a) in log.iter().zip(got) {
        let t = f64::from(m.t_us) * 1e-6;
        let _ = match a {
            Answer::Forces(f) => writeln!(
                s,
                "{t},{},{:e},{:e},{:e},{},,,,",
                m.wheel.index(),
                f.fx,
                f.fy,
                f.mz,
                f.flags
            ),
            Answer::Ack(c) => writeln!(s, "{t},{},,,,,{c:?},,,", m.wheel.index()),
        };
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("csv.tmp");
    std::fs::write(&tmp, s)?;
    std::fs::rename(&tmp, path)
}
