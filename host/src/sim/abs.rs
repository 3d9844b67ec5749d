//! A simple slip-controlling ABS: per wheel, a three-phase (dump / hold / apply) control of the
//! brake torque on slip thresholds with hysteresis.
//!
//! Per wheel, with the driver's demand Tdem and the wheel's kinematic slip κ = −Vsx/|Vx|:
//! ```text
//! κ < −κdump            → Tb ← max(0, Tb − Ṫdump·h)           (dump: the wheel is locking)
//! −κdump ≤ κ ≤ −κapply  → hold (once the wheel has been in control)
//! κ > −κapply           → Tb ← min(Tdem, Tb + Ṫapply·h)        (re-apply)
//! ```
//! Until a wheel first crosses κdump, and below [`AbsParams::v_min`], Tb = Tdem. Tb never
//! exceeds the demand. The rates stand in for the hydraulic modulator's dump and build rates.
//!
//! Two standard yaw-moment measures for μ-split (each can be turned off):
//! - select-low on the rear axle: both rear wheels get the lower of their two torques;
//! - yaw-moment build-up delay (GMA) on the front axle: the difference between the front
//!   torques may grow at most at [`AbsParams::gma_rate`] from the start of braking.
//!
//! ## What it leaves out
//! A reference-speed estimator (the ABS is given each wheel centre's true speed over ground),
//! wheel-acceleration thresholds, pressure hydraulics (torque is the controlled quantity).

/// ABS tuning. Slips are magnitudes \[-\], rates in N·m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbsParams {
    /// Slip magnitude above which the brake torque is dumped κdump.
    pub slip_dump: f64,
    /// Slip magnitude below which the brake torque is re-applied κapply (< `slip_dump`).
    pub slip_apply: f64,
    /// Dump rate Ṫdump \[N·m/s\].
    pub dump_rate: f64,
    /// Re-apply rate Ṫapply \[N·m/s\].
    pub apply_rate: f64,
    /// Speed below which the ABS lets the driver's demand through \[m/s\].
    pub v_min: f64,
    /// Rear axle select-low.
    pub select_low_rear: bool,
    /// Growth rate of the allowed front left/right torque difference \[N·m/s\] (0: no limit).
    pub gma_rate: f64,
}

impl Default for AbsParams {
    fn default() -> Self {
        AbsParams {
            slip_dump: 0.15,
            slip_apply: 0.07,
            dump_rate: 60_000.0,
            apply_rate: 12_000.0,
            v_min: 2.0,
            select_low_rear: true,
            gma_rate: 4_000.0,
        }
    }
}

/// ABS state: the brake torque it lets through per wheel and whether it is in control.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Abs {
    /// Tuning.
    pub params: AbsParams,
    torque: [f64; 4],
    active: [bool; 4],
    braking: f64,
}

impl Abs {
    /// A passive ABS.
    pub fn new(params: AbsParams) -> Abs {
        Abs {
            params,
            torque: [0.0; 4],
            active: [false; 4],
            braking: 0.0,
        }
    }

    /// Is the ABS controlling wheel `i` (it has dumped since the demand was last released)?
    pub fn active(&self, i: usize) -> bool {
        self.active.get(i).copied().unwrap_or(false)
    }

    /// The brake torques \[N·m\] for the driver's `demand` \[N·m\], each wheel's kinematic slip
    /// `kappa` and forward speed `vx` \[m/s\], over a step `dt` \[s\].
    pub fn update(
        &mut self,
        demand: &[f64; 4],
        kappa: &[f64; 4],
        vx: &[f64; 4],
        dt: f64,
    ) -> [f64; 4] {
        let q = self.params;
        for i in 0..4 {
            let dem = demand[i].max(0.0);
            if dem == 0.0 || vx[i].abs() < q.v_min {
                self.active[i] = false;
                self.torque[i] = dem;
                continue;
            }
            let slip = -kappa[i]; // > 0 braking
            if slip > q.slip_dump {
                self.active[i] = true;
                self.torque[i] = (self.torque[i] - q.dump_rate * dt).max(0.0);
            } else if !self.active[i] {
                self.torque[i] = dem;
            } else if slip < q.slip_apply {
                self.torque[i] = (self.torque[i] + q.apply_rate * dt).min(dem);
            }
            self.torque[i] = self.torque[i].min(dem);
        }
        let mut out = self.torque;
        if demand.iter().any(|&d| d > 0.0) {
            self.braking += dt;
        } else {
            self.braking = 0.0;
        }
        if q.select_low_rear {
            let low = out[2].min(out[3]);
            out[2] = low;
            out[3] = low;
        }
        if q.gma_rate > 0.0 {
            let allowed = q.gma_rate * self.braking;
            let (lo, hi) = if out[0] <= out[1] { (0, 1) } else { (1, 0) };
            out[hi] = out[hi].min(out[lo] + allowed);
        }
        out
    }
}
