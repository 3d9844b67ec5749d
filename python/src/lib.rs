//! `gough._gough`: the extension module under the Python package `gough` (python/gough/).
//!
//! It wraps, never re-implements: `.tir` text goes through `gough::tir::parse`, the points of
//! `Tyre.eval` through the core's batches: `f64` in lanes (`gough::mf::eval_batch_lanes`,
//! within 1e-9·FNOMIN of `gough::mf::eval`), or, with `exact` and in `f32`,
//! `gough::mf::eval_batch` (at each point what `gough_host::mfrun::eval_row`, which
//! `gough mf eval` runs, gives, to the bit), a friction
//! log through `gough_host::mu::Method::estimator` (what `gough mu estimate` runs), a gap log through
//! `gough_host::gap::diagnose` (what `gough gap diagnose` runs). The pure-Python layer does the
//! broadcasting and the pandas conversions; this module takes and returns flat `float64` arrays.
use gough::math::{Backend, Libm};
use gough::mf::{self as mf, BatchError, Columns, Options, Outputs, Params};
use gough::proto::Wheel;
use gough_host::gap;
use gough_host::mfrun::{self, Precision};
use gough_host::mu::{self, Method, Sample, Setup};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

create_exception!(
    _gough,
    TirError,
    PyValueError,
    "A `.tir` file that gough cannot read: args are (message, line, key); line 0 means the file as a whole."
);

/// A tyre: the parameters of one `.tir` file (f64).
#[pyclass(module = "gough._gough", frozen)]
pub struct Tyre {
    params: Params<f64>,
    /// The `.tir` text it was read from (the corrected file of `diagnose_gap` is written into it).
    text: String,
    /// The reader's warnings (`line N: ...`).
    #[pyo3(get)]
    warnings: Vec<String>,
}

fn tir_error(name: &str, e: gough::tir::Error) -> PyErr {
    let key = match e.kind.key() {
        Some(k) => k.name().to_string(),
        None => String::new(),
    };
    TirError::new_err((format!("{name}: {e}"), e.line, key))
}

fn parse(text: &str, name: &str) -> PyResult<Tyre> {
    let t = gough::tir::parse(text).map_err(|e| tir_error(name, e))?;
    let mut warnings: Vec<String> = t.warnings.iter().map(|w| w.to_string()).collect();
    if t.warnings_dropped > 0 {
        warnings.push(format!("... and {} more warnings", t.warnings_dropped));
    }
    Ok(Tyre {
        params: t.params,
        text: text.to_string(),
        warnings,
    })
}

#[pymethods]
impl Tyre {
    /// Reads a `.tir` file. Raises `TirError` (a `ValueError`) naming the line and key.
    #[staticmethod]
    fn from_tir(path: std::path::PathBuf) -> PyResult<Tyre> {
        let text = std::fs::read_to_string(&path).map_err(|e| {
            pyo3::exceptions::PyOSError::new_err(format!("{}: cannot read: {e}", path.display()))
        })?;
        parse(&text, &path.display().to_string())
    }

    /// Parses `.tir` text.
    #[staticmethod]
    fn from_text(text: &str) -> PyResult<Tyre> {
        parse(text, "<text>")
    }

    /// FNOMIN \[N\].
    #[getter]
    fn fnomin(&self) -> f64 {
        self.params.fnomin
    }

    /// UNLOADED_RADIUS R0 \[m\].
    #[getter]
    fn unloaded_radius(&self) -> f64 {
        self.params.unloaded_radius
    }

    /// LONGVL \[m/s\].
    #[getter]
    fn longvl(&self) -> f64 {
        self.params.longvl
    }

    /// The Magic Formula at each point of equal-length 1-D float64 arrays (the Python layer
    /// broadcasts), the columns of `gough mf eval`: in `f64` and not `exact`, in lanes
    /// (`gough::mf::eval_batch_lanes`: the widest this processor has, each point within
    /// 1e-9·FNOMIN of `mf::eval`); else through the core's batch (`gough::mf::eval_batch`: each
    /// point equals `mfrun::eval_row`'s to the bit). `p` = 0 means INFLPRES. Runs without the
    /// GIL, on `threads` threads (`None`: one per core when there are at least [`PAR_MIN`]
    /// points per thread). Returns `{column: array}`; raises `ValueError` naming the first
    /// point that the core rejects.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (fz, kappa, alpha, gamma, phit, vx, p, mode, f32, threads=None, exact=false))]
    fn _eval<'py>(
        &self,
        py: Python<'py>,
        fz: PyReadonlyArray1<'py, f64>,
        kappa: PyReadonlyArray1<'py, f64>,
        alpha: PyReadonlyArray1<'py, f64>,
        gamma: PyReadonlyArray1<'py, f64>,
        phit: PyReadonlyArray1<'py, f64>,
        vx: PyReadonlyArray1<'py, f64>,
        p: PyReadonlyArray1<'py, f64>,
        mode: u16,
        f32: bool,
        threads: Option<usize>,
        exact: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let opts = options(mode)?;
        let cols = [&fz, &kappa, &alpha, &gamma, &phit, &vx, &p].map(|a| a.as_slice());
        let mut s: Vec<&[f64]> = Vec::with_capacity(7);
        for c in cols {
            s.push(c.map_err(|e| PyValueError::new_err(e.to_string()))?);
        }
        // A column of one value stands for every point (the Python layer's scalars).
        let n = if s.iter().any(|c| c.is_empty()) {
            0
        } else {
            s.iter().map(|c| c.len()).max().unwrap_or(0)
        };
        if s.iter().any(|c| c.len() != n && c.len() != 1) {
            return Err(PyValueError::new_err("inputs of different lengths"));
        }
        let mut out = vec![vec![0.0f64; n]; mfrun::OUTPUT_COLUMNS.len()];
        let params = &self.params;
        let threads = threads.unwrap_or_else(|| {
            let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
            cores.min(n / PAR_MIN).max(1)
        });
        let err = py.detach(|| {
            let cols = [s[0], s[1], s[2], s[3], s[4], s[5], s[6]];
            if f32 {
                batch::<f32>(
                    &params.cast::<f32>(),
                    cols,
                    n,
                    &opts,
                    &mut out,
                    threads,
                    true,
                )
            } else {
                batch::<f64>(params, cols, n, &opts, &mut out, threads, exact)
            }
        });
        if let Err(e) = err {
            return Err(PyValueError::new_err(e.to_string()));
        }
        let d = PyDict::new(py);
        for (name, col) in mfrun::OUTPUT_COLUMNS.iter().zip(out) {
            d.set_item(*name, col.into_pyarray(py))?;
        }
        Ok(d)
    }

    /// The Magic Formula at one point, without numpy: a tuple of the [`mfrun::OUTPUT_COLUMNS`]
    /// as floats (`mfrun::eval_row`, what `gough mf eval` runs). `p` = 0 means INFLPRES.
    #[allow(clippy::too_many_arguments)]
    fn _eval_point<'py>(
        &self,
        py: Python<'py>,
        fz: f64,
        kappa: f64,
        alpha: f64,
        gamma: f64,
        phit: f64,
        vx: f64,
        p: f64,
        mode: u16,
        f32: bool,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let opts = options(mode)?;
        let row = mfrun::InputRow {
            fz,
            kappa,
            alpha,
            gamma,
            phit,
            vx,
            p,
        };
        let o = if f32 {
            mfrun::eval_row(
                &self.params,
                &self.params.cast::<f32>(),
                &row.input(),
                &opts,
                Precision::F32,
            )
        } else {
            gough::mf::eval::<f64, Libm>(&self.params, &row.input(), &opts)
        };
        let o = o.map_err(|e| PyValueError::new_err(format!("point 0: {e}")))?;
        PyTuple::new(py, mfrun::output_values(&o))
    }
}

/// Points per thread below which `Tyre.eval` stays on one thread.
const PAR_MIN: usize = 8192;

fn options(mode: u16) -> PyResult<Options> {
    Options::from_use_mode(mode).ok_or_else(|| {
        PyValueError::new_err(format!(
            "mode {mode}: expected 3 digits, each 1 or 2 (e.g. 111, 211, 121, 221, 112)"
        ))
    })
}

/// A float path of the batch: `f64` (the columns as they are) or `f32` (converted, as
/// `mfrun::eval_row`'s f32 path converts a point).
trait Path: gough::math::Float + Send + Sync
where
    Libm: Backend<Self>,
{
    fn from64(x: f64) -> Self;

    /// The core's batch on these columns: `mf::eval_batch` with `Libm` when `exact`, else the
    /// fastest the core has for this type.
    fn eval(
        params: &Params<Self>,
        columns: &Columns<'_, Self>,
        opts: &Options,
        out: &mut Outputs<'_, Self>,
        exact: bool,
    ) -> Result<(), BatchError> {
        let _ = exact;
        mf::eval_batch::<Self, Libm>(params, columns, opts, out)
    }
}
impl Path for f64 {
    fn from64(x: f64) -> Self {
        x
    }

    /// Not `exact`: the lanes (`mf::eval_batch_lanes_scaled` without scales, as `gough_lanes`
    /// compiles it for the host's crates).
    fn eval(
        params: &Params<f64>,
        columns: &Columns<'_, f64>,
        opts: &Options,
        out: &mut Outputs<'_, f64>,
        exact: bool,
    ) -> Result<(), BatchError> {
        if exact {
            mf::eval_batch::<f64, Libm>(params, columns, opts, out)
        } else {
            gough_lanes::eval_batch_lanes_scaled(
                mf::Isa::Auto,
                params,
                columns,
                &mf::Scales::default(),
                opts,
                out,
            )
            .map(|_| ())
        }
    }
}
/// No `f32` lanes yet: `f32` is always the scalar batch.
impl Path for f32 {
    fn from64(x: f64) -> Self {
        x as f32
    }
}

/// `mf::eval_batch` over the 7 input columns (fz, κ, α, γ, φt, Vx, p; p = 0: INFLPRES; a
/// column of one value: that value at each of the `n` points) into
/// the 13 output columns of [`mfrun::OUTPUT_COLUMNS`], in `threads` contiguous chunks on
/// scoped threads ([`Path::eval`]: `exact` or not); the first rejected point's error (its index
/// in the whole batch).
fn batch<F: Path>(
    params: &Params<F>,
    cols: [&[f64]; 7],
    n: usize,
    opts: &Options,
    out: &mut [Vec<f64>],
    threads: usize,
    exact: bool,
) -> Result<(), BatchError>
where
    Libm: Backend<F>,
{
    // p = 0 is INFLPRES: the column carries the value `None` would take.
    let inflpres = params.inflpres;
    let conv = |c: &[f64], k: usize| -> Vec<F> {
        let f = |x: f64| {
            if k == 6 && x == 0.0 {
                inflpres
            } else {
                F::from64(x)
            }
        };
        match c {
            [x] => vec![f(*x); n],
            _ => c.iter().map(|&x| f(x)).collect(),
        }
    };
    let ins: Vec<Vec<F>> = cols.iter().enumerate().map(|(k, c)| conv(c, k)).collect();
    let mut res: Vec<Vec<F>> = vec![vec![F::ZERO; n]; 13];
    let chunk = n.div_ceil(threads.max(1)).max(1);
    let run = |start: usize, outs: Vec<&mut [F]>| -> Result<(), BatchError> {
        let end = (start + chunk).min(n);
        let c = |k: usize| &ins[k][start..end];
        let columns = Columns {
            fz: c(0),
            kappa: c(1),
            alpha: c(2),
            gamma: c(3),
            phit: Some(c(4)),
            vx: c(5),
            p: Some(c(6)),
        };
        let mut it = outs.into_iter();
        let mut next = || it.next();
        // In `mfrun::OUTPUT_COLUMNS` order: Fx Fy Mz Mx My mux muy Kya Kxk t Mzr sigmax sigmay.
        let (fx, fy, mz, mx, my, mu_x, mu_y, k_ya, k_xk, t, m_zr, sigma_x, sigma_y) = (
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
            next(),
        );
        let mut o = Outputs {
            fx,
            fy,
            mz,
            mx,
            my,
            mu_x,
            mu_y,
            k_ya,
            k_xk,
            t,
            m_zr,
            sigma_x,
            sigma_y,
            ..Outputs::default()
        };
        F::eval(params, &columns, opts, &mut o, exact).map_err(|e| match e {
            BatchError::Point { index, error } => BatchError::Point {
                index: index + start,
                error,
            },
            e => e,
        })
    };
    // Each thread gets its chunk of every output column.
    let mut per: Vec<Vec<&mut [F]>> = (0..n.div_ceil(chunk)).map(|_| Vec::new()).collect();
    for col in res.iter_mut() {
        for (k, part) in col.chunks_mut(chunk).enumerate() {
            per[k].push(part);
        }
    }
    let result = if per.len() <= 1 {
        per.into_iter().next().map_or(Ok(()), |outs| run(0, outs))
    } else {
        std::thread::scope(|sc| {
            let handles: Vec<_> = per
                .into_iter()
                .enumerate()
                .map(|(k, outs)| {
                    let run = &run;
                    sc.spawn(move || run(k * chunk, outs))
                })
                .collect();
            // The first error in point order: chunks are in order.
            let mut first = Ok(());
            for h in handles {
                let r = h.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
                if first.is_ok() {
                    first = r;
                }
            }
            first
        })
    };
    for (dst, src) in out.iter_mut().zip(&res) {
        for (d, &x) in dst.iter_mut().zip(src) {
            *d = x.to_f64();
        }
    }
    result
}

/// μ, σ and the state names of an estimator run.
type Estimates<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Vec<&'static str>,
);

/// `gough mu estimate` on columns (NaN = not logged; `has_fx` says whether Fx was logged), by
/// the same estimator (`gough_host::mu::Method::estimator`); with `wheel` (0–3 per row) a car's
/// log, each wheel mounted on its side, and with `wheelbase` \[m\] the bank's front-to-rear
/// preview. Returns (mu, sigma, state names).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (tyre, t, fz, fy, mz, fx, vx, kappa, alpha, gamma, has_fx, method="bank", precision="f64", wheel=None, wheelbase=None, calibration_in=None, calibration_out=None))]
fn _estimate_mu<'py>(
    py: Python<'py>,
    tyre: &Tyre,
    t: PyReadonlyArray1<'py, f64>,
    fz: PyReadonlyArray1<'py, f64>,
    fy: PyReadonlyArray1<'py, f64>,
    mz: PyReadonlyArray1<'py, f64>,
    fx: PyReadonlyArray1<'py, f64>,
    vx: PyReadonlyArray1<'py, f64>,
    kappa: PyReadonlyArray1<'py, f64>,
    alpha: PyReadonlyArray1<'py, f64>,
    gamma: PyReadonlyArray1<'py, f64>,
    has_fx: bool,
    method: &str,
    precision: &str,
    wheel: Option<PyReadonlyArray1<'py, f64>>,
    wheelbase: Option<f64>,
    calibration_in: Option<std::path::PathBuf>,
    calibration_out: Option<std::path::PathBuf>,
) -> PyResult<Estimates<'py>> {
    let method = Method::from_name(method).map_err(PyValueError::new_err)?;
    let prec = match precision {
        "f64" => mu::Precision::F64,
        "f32" => mu::Precision::F32,
        p => {
            return Err(PyValueError::new_err(format!(
                "precision '{p}': expected f64 or f32"
            )))
        }
    };
    let arr = |a: &PyReadonlyArray1<'py, f64>| -> PyResult<Vec<f64>> {
        Ok(a.as_slice()
            .map_err(|e| PyValueError::new_err(e.to_string()))?
            .to_vec())
    };
    let (t, fz, fy, mz) = (arr(&t)?, arr(&fz)?, arr(&fy)?, arr(&mz)?);
    let (fx, vx, kappa, alpha, gamma) = (
        arr(&fx)?,
        arr(&vx)?,
        arr(&kappa)?,
        arr(&alpha)?,
        arr(&gamma)?,
    );
    let n = t.len();
    if [&fz, &fy, &mz, &fx, &vx, &kappa, &alpha, &gamma]
        .iter()
        .any(|c| c.len() != n)
    {
        return Err(PyValueError::new_err("columns of different lengths"));
    }
    let wheels: Vec<Wheel> = match &wheel {
        None => vec![Wheel::FrontLeft; n],
        Some(w) => {
            let w = arr(w)?;
            if w.len() != n {
                return Err(PyValueError::new_err("columns of different lengths"));
            }
            w.iter()
                .enumerate()
                .map(|(i, &x)| {
                    Wheel::from_index(x as usize)
                        .filter(|_| x.fract() == 0.0 && x >= 0.0)
                        .ok_or_else(|| {
                            PyValueError::new_err(format!(
                                "row {i}, column wheel: {x} is not 0, 1, 2 or 3"
                            ))
                        })
                })
                .collect::<PyResult<_>>()?
        }
    };
    if (calibration_in.is_some() || calibration_out.is_some()) && !method.couples_wheels() {
        return Err(PyValueError::new_err(format!(
            "calibration_in/calibration_out are the bank's; the {} method keeps no calibration",
            method.name()
        )));
    }
    let car = wheels.iter().any(|&w| w != Wheel::FrontLeft) || wheelbase.is_some();
    if car && !method.couples_wheels() {
        return Err(PyValueError::new_err(
            "a log of several wheels, or a wheelbase, needs method 'bank'",
        ));
    }
    let mut last = [f64::NEG_INFINITY; 4];
    let mut log = Vec::with_capacity(n);
    // A column the log does not have is all NaN (the Python layer fills it so): not measured.
    let opt = |x: f64| x.is_finite().then_some(x);
    for i in 0..n {
        for (name, v) in [("t", t[i]), ("fz", fz[i]), ("fy", fy[i]), ("mz", mz[i])] {
            if !v.is_finite() {
                return Err(PyValueError::new_err(format!(
                    "row {i}, column {name}: not a finite number ({v})"
                )));
            }
        }
        let w = wheels[i];
        if t[i] <= last[w.index()] {
            return Err(PyValueError::new_err(format!(
                "row {i}, column t: time does not increase ({} after {})",
                t[i],
                last[w.index()]
            )));
        }
        last[w.index()] = t[i];
        log.push((
            w,
            Sample {
                t: t[i],
                fz: fz[i],
                fy: fy[i],
                mz: mz[i],
                fx: if has_fx { Some(fx[i]) } else { None },
                vx: opt(vx[i]),
                kappa: opt(kappa[i]),
                alpha: opt(alpha[i]),
                gamma: opt(gamma[i]),
            },
        ));
    }
    let preview = match wheelbase {
        Some(l) => {
            let c = gough::mu::preview::Config::with_wheelbase(l);
            gough::mu::preview::Preview::new(c)
                .map_err(|e| PyValueError::new_err(format!("wheelbase {l}: {e}")))?;
            Some(c)
        }
        None => None,
    };
    // A car's log mounts each wheel on its side, as `gough mu estimate` does; one wheel's log
    // is taken as the file describes the tyre.
    let setup = Setup {
        precision: prec,
        mounted: mu::mounting(&wheels, None),
        preview,
    };
    let params = &tyre.params;
    let est = py
        .detach(|| -> Result<_, String> {
            let mut e = method.estimator(params, &setup)?;
            if let Some(path) = &calibration_in {
                mu::calfile::load_into(e.as_mut(), path)?;
            }
            let est = e.run(&log);
            if let Some(path) = &calibration_out {
                mu::calfile::save_from(e.as_ref(), &wheels, path)?;
            }
            Ok(est)
        })
        .map_err(PyValueError::new_err)?;
    let m: Vec<f64> = est.iter().map(|e| e.mu).collect();
    let s: Vec<f64> = est.iter().map(|e| e.sigma).collect();
    let st: Vec<&'static str> = est.iter().map(|e| e.state.name()).collect();
    Ok((m.into_pyarray(py), s.into_pyarray(py), st))
}

/// `gough gap diagnose` on columns: returns the report as JSON text (the Python layer makes it
/// a dict). `opt` holds the optional columns p, phit, mu (None when not logged).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (tyre, cols, p, phit, mu, tir_name, log_name, fit_rows=None, write_tir=None, exact=false))]
fn _diagnose_gap(
    py: Python<'_>,
    tyre: &Tyre,
    cols: Vec<PyReadonlyArray1<'_, f64>>,
    p: Option<PyReadonlyArray1<'_, f64>>,
    phit: Option<PyReadonlyArray1<'_, f64>>,
    mu: Option<PyReadonlyArray1<'_, f64>>,
    tir_name: &str,
    log_name: &str,
    fit_rows: Option<usize>,
    write_tir: Option<std::path::PathBuf>,
    exact: bool,
) -> PyResult<String> {
    let v = |a: &PyReadonlyArray1<'_, f64>| -> PyResult<Vec<f64>> {
        Ok(a.as_slice()
            .map_err(|e| PyValueError::new_err(e.to_string()))?
            .to_vec())
    };
    if cols.len() != gap::log::REQUIRED.len() {
        return Err(PyValueError::new_err(
            "expected the columns t,vx,alpha,kappa,gamma,fz,fx,fy,mz",
        ));
    }
    let c: Vec<Vec<f64>> = cols.iter().map(v).collect::<PyResult<_>>()?;
    let n = c[0].len();
    if c.iter().any(|x| x.len() != n) {
        return Err(PyValueError::new_err("columns of different lengths"));
    }
    let log = gap::log::Log {
        t: c[0].clone(),
        vx: c[1].clone(),
        alpha: c[2].clone(),
        kappa: c[3].clone(),
        gamma: c[4].clone(),
        fz: c[5].clone(),
        meas: (0..n).map(|i| [c[6][i], c[7][i], c[8][i]]).collect(),
        p: p.as_ref().map(v).transpose()?,
        phit: phit.as_ref().map(v).transpose()?,
        mu: mu.as_ref().map(v).transpose()?,
        lines: (0..n).map(|i| i + 2).collect(),
    };
    log.validate(log_name).map_err(PyValueError::new_err)?;
    let params = tyre.params.clone();
    let d = py
        .detach(|| {
            gap::diagnose(
                params,
                &log,
                tir_name,
                log_name,
                &gap::Options {
                    progress: false,
                    plots: None,
                    fit_rows,
                    exact,
                },
            )
        })
        .map_err(PyValueError::new_err)?;
    if let Some(out) = &write_tir {
        gough_host::gap::tirfile::write_corrected(&tyre.text, out, d.corrected.as_ref())
            .map_err(PyValueError::new_err)?;
    }
    serde_json::to_string(&d.report).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `gough sim` without files: the manoeuvre's log as (column names, rows × columns array). The
/// numbers go into the library's run specification (`gough_host::sim::Spec`), which `gough sim`
/// fills from its flags; its errors name those flags.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (tyre, manoeuvre, road=None, speed=None, duration=None, dt=None, steer=None, radius=None, decel=None, abs=true, log_every=None))]
fn _simulate<'py>(
    py: Python<'py>,
    tyre: &Tyre,
    manoeuvre: String,
    road: Option<String>,
    speed: Option<f64>,
    duration: Option<f64>,
    dt: Option<f64>,
    steer: Option<f64>,
    radius: Option<f64>,
    decel: Option<f64>,
    abs: bool,
    log_every: Option<usize>,
) -> PyResult<(Vec<String>, Bound<'py, numpy::PyArray2<f64>>)> {
    let spec = gough_host::sim::Spec {
        manoeuvre,
        road,
        speed,
        duration,
        dt,
        steer_deg: steer,
        radius,
        decel,
        abs,
        log_every,
    };
    let cfg = spec.config().map_err(PyValueError::new_err)?;
    let params = &tyre.params;
    let log = py
        .detach(|| gough_host::sim::simulate(&cfg, params, false))
        .map_err(PyValueError::new_err)?;
    let rows: Vec<Vec<f64>> = log.records.iter().map(gough_host::sim::Log::row).collect();
    let a =
        numpy::PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((gough_host::sim::columns(), a))
}

/// `gough.Signer.seal`: the secured encoding (the core's `proto::auth::Signer`) of the encoded
/// message `message` for CAN identifier `can_id`, with the device key, MAC length and the
/// signer's freshness (`epoch`, last `counter`); returns it and the new (epoch, counter).
#[pyfunction]
fn _seal(
    key: &[u8],
    mac_len: u8,
    epoch: u32,
    counter: u32,
    can_id: u16,
    message: &[u8],
) -> PyResult<(Vec<u8>, u32, u32)> {
    use gough::proto::{Key, MacLen, Msg, Signer, MAX_MSG_LEN};
    let key: [u8; 16] = key
        .try_into()
        .map_err(|_| PyValueError::new_err("key: 16 bytes"))?;
    let mac_len =
        MacLen::new(mac_len).ok_or_else(|| PyValueError::new_err("mac_len: 4..8 bytes"))?;
    let msg = Msg::decode(message)
        .map_err(|e| PyValueError::new_err(format!("not a message of this protocol: {e}")))?;
    let mut s = Signer::new(Key::new(key), mac_len, epoch, counter);
    let mut out = [0u8; MAX_MSG_LEN];
    let n = s
        .seal(can_id, &msg, &mut out)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (e, c) = s.freshness();
    Ok((out.get(..n).unwrap_or(&[]).to_vec(), e, c))
}

/// `gough.Verifier`: the core's `proto::auth::Verifier` checking the secured answers of a device
/// that authenticates every message (`Policy::All`): its key, MAC length, epoch and the
/// device's transmit counter to continue above.
#[pyclass(module = "gough._gough")]
struct _Verifier(gough::proto::Verifier);

#[pymethods]
impl _Verifier {
    #[new]
    fn new(key: &[u8], mac_len: u8, epoch: u32, counter: u32) -> PyResult<Self> {
        use gough::proto::{Key, MacLen, Policy, Verifier};
        let key: [u8; 16] = key
            .try_into()
            .map_err(|_| PyValueError::new_err("key: 16 bytes"))?;
        let mac_len =
            MacLen::new(mac_len).ok_or_else(|| PyValueError::new_err("mac_len: 4..8 bytes"))?;
        let mut v = Verifier::new(Key::new(key), mac_len, epoch).with_policy(Policy::All);
        v.set_counter(counter);
        Ok(_Verifier(v))
    }

    /// Checks the encoded message `message` received on `can_id`: `(True, plain)` with the
    /// message's unsecured encoding, or `(False, code)` with the refusal's `AckCode` name.
    /// ValueError when `message` is not a message of this protocol.
    fn open(&mut self, can_id: u16, message: &[u8]) -> PyResult<(bool, Vec<u8>)> {
        use gough::proto::MAX_MSG_LEN;
        match self.0.open(can_id, message) {
            Ok(m) => {
                let mut out = [0u8; MAX_MSG_LEN];
                let n = m
                    .encode(&mut out)
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                Ok((true, out.get(..n).unwrap_or(&[]).to_vec()))
            }
            Err(Ok(r)) => Ok((false, format!("{:?}", r.code).into_bytes())),
            Err(Err(e)) => Err(PyValueError::new_err(format!(
                "not a message of this protocol: {e}"
            ))),
        }
    }

    /// (accepted, missing, bad_mac, stale, epoch, highest counter accepted).
    fn counts(&self) -> (u32, u32, u32, u32, u32, u32) {
        let s = self.0.status();
        (
            s.accepted, s.missing, s.bad_mac, s.stale, s.epoch, s.counter,
        )
    }
}

/// The extension module.
#[pymodule]
fn _gough(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Tyre>()?;
    m.add_class::<_Verifier>()?;
    m.add_function(wrap_pyfunction!(_estimate_mu, m)?)?;
    m.add_function(wrap_pyfunction!(_diagnose_gap, m)?)?;
    m.add_function(wrap_pyfunction!(_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(_seal, m)?)?;
    m.add("TirError", m.py().get_type::<TirError>())?;
    m.add("OUTPUT_COLUMNS", mfrun::OUTPUT_COLUMNS.to_vec())?;
    Ok(())
}
