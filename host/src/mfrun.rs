//! `gough mf eval`: the oracle's input columns in, forces/moments out, through the core.
use gough::math::Libm;
use gough::mf::{self, EvalError, Input, Options, Output, Params};

/// Float path of an evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Precision {
    /// f64 on the host: the full-precision path.
    F64,
    /// f32: the device path (same core, `f32`, libm backend).
    F32,
}

/// Input columns, as in the MFeval oracle files.
pub const INPUT_COLUMNS: [&str; 7] = [
    "in_Fz", "in_kappa", "in_alpha", "in_gamma", "in_phit", "in_Vx", "in_P",
];
/// Output columns after the inputs.
pub const OUTPUT_COLUMNS: [&str; 13] = [
    "Fx", "Fy", "Mz", "Mx", "My", "mux", "muy", "Kya", "Kxk", "t", "Mzr", "sigmax", "sigmay",
];

/// One row of inputs: the [`INPUT_COLUMNS`] (`in_phit`, `in_P` optional, 0 when absent;
/// `in_P = 0` means INFLPRES).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
pub struct InputRow {
    /// Vertical load Fz \[N\].
    #[serde(rename = "in_Fz")]
    pub fz: f64,
    /// Longitudinal slip κ.
    #[serde(rename = "in_kappa")]
    pub kappa: f64,
    /// Slip angle α \[rad\].
    #[serde(rename = "in_alpha")]
    pub alpha: f64,
    /// Inclination γ \[rad\].
    #[serde(rename = "in_gamma")]
    pub gamma: f64,
    /// Turn slip φt \[1/m\].
    #[serde(rename = "in_phit", default)]
    pub phit: f64,
    /// Forward speed Vx \[m/s\].
    #[serde(rename = "in_Vx")]
    pub vx: f64,
    /// Inflation pressure \[Pa\] (0: INFLPRES).
    #[serde(rename = "in_P", default)]
    pub p: f64,
}

impl InputRow {
    /// The Magic Formula's input.
    pub fn input(&self) -> Input<f64> {
        Input {
            fz: self.fz,
            kappa: self.kappa,
            alpha: self.alpha,
            gamma: self.gamma,
            phit: self.phit,
            vx: self.vx,
            p: if self.p == 0.0 { None } else { Some(self.p) },
        }
    }

    /// The values in [`INPUT_COLUMNS`] order.
    pub fn values(&self) -> [f64; 7] {
        [
            self.fz, self.kappa, self.alpha, self.gamma, self.phit, self.vx, self.p,
        ]
    }
}

/// Evaluates one row in the requested precision; results widened to f64.
pub fn eval_row(
    p64: &Params<f64>,
    p32: &Params<f32>,
    input: &Input<f64>,
    opts: &Options,
    prec: Precision,
) -> Result<Output<f64>, EvalError> {
    match prec {
        Precision::F64 => mf::eval::<f64, Libm>(p64, input, opts),
        Precision::F32 => {
            let i = Input {
                fz: input.fz as f32,
                kappa: input.kappa as f32,
                alpha: input.alpha as f32,
                gamma: input.gamma as f32,
                phit: input.phit as f32,
                vx: input.vx as f32,
                p: input.p.map(|x| x as f32),
            };
            let o = mf::eval::<f32, Libm>(p32, &i, opts)?;
            Ok(Output {
                fx: o.fx as f64,
                fy: o.fy as f64,
                fz: o.fz as f64,
                mx: o.mx as f64,
                my: o.my as f64,
                mz: o.mz as f64,
                mu_x: o.mu_x as f64,
                mu_y: o.mu_y as f64,
                k_xk: o.k_xk as f64,
                k_ya: o.k_ya as f64,
                t: o.t as f64,
                m_zr: o.m_zr as f64,
                sigma_x: o.sigma_x as f64,
                sigma_y: o.sigma_y as f64,
                kappa: o.kappa as f64,
                flags: o.flags,
            })
        }
    }
}

/// The output columns of one result, in [`OUTPUT_COLUMNS`] order.
pub fn output_values(o: &Output<f64>) -> [f64; 13] {
    [
        o.fx, o.fy, o.mz, o.mx, o.my, o.mu_x, o.mu_y, o.k_ya, o.k_xk, o.t, o.m_zr, o.sigma_x,
        o.sigma_y,
    ]
}
