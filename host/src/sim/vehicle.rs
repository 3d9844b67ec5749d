//! The two-track vehicle: chassis (longitudinal, lateral, yaw), quasi-static load transfer,
//! wheel spin, and a transient Magic Formula tyre at each wheel.
//!
//! ## Equations (body frame at the centre of gravity: x forward, y left, z up; ISO 8855)
//! Chassis, planar (3 DOF), with F the sums of the tyre forces turned into the body frame plus
//! the aerodynamic drag, M the yaw moment of the tyre forces and the tyres' Mz:
//! ```text
//! m·(v̇x − r·vy) = ΣFx,b − ½ρ·CdA·|V|·vx        m·(v̇y + r·vx) = ΣFy,b − ½ρ·CdA·|V|·vy
//! Iz·ṙ = Σ (xi·Fy,b,i − yi·Fx,b,i) + Σ Mz,i
//! Fx,b = Fx·cos δ − Fy·sin δ,   Fy,b = Fx·sin δ + Fy·cos δ   (δ the wheel's steer angle)
//! δ = δcmd − cδ·(Fy,fl + Fy,fr)      (compliance steer, front wheels; rear δ = 0)
//! ```
//! Wheel i at (xi, yi): centre velocity (vx − r·yi, vy + r·xi) turned by −δ into the wheel's
//! ISO-W axes gives Vx, Vsy (= the centre's lateral speed) and Vsx = Vx − Ω·Re; the transient
//! tyre ([`gough::relax::TransientTyre`]) turns them into α', κ' and Fx, Fy, Mz, My.
//!
//! Wheel spin, with the brake torque Tb ≥ 0 and the rolling resistance |My| as Coulomb
//! torques (they stop the wheel but never turn it backwards), and the effective rolling radius
//! from the radial-tyre rule Re = R0 − ρ/3, ρ = Fz,static/Cz:
//! ```text
//! Iw·Ω̇ = Td − Re·Fx − (Tb + |My|)·sign Ω
//! ```
//! Quasi-static load transfer from the tyre forces (drag acts at the CG height, so it moves no
//! load), through a first-order lag τ ([`VehicleParams::load_lag`]) that stands in for the
//! suspension's roll and pitch response; roll centres at the ground, one body mass:
//! ```text
//! Fz,i = m·g·(b or a)/(2L) ∓ m·ax·h/(2L) ∓ m·ay·h·εaxle/taxle + ΔFz,road,i
//! ```
//! (front −, rear + for ax; left −, right + for ay; εf = the front share of the roll
//! stiffness, εr = 1 − εf). Each axle's lateral transfer is capped at its load, so the four
//! loads always sum to m·g on a flat road. Roll angle φ = (roll gradient)·ay; camber
//! γi = ±γstatic − kγ·φ (the wheels follow the body's roll by the fraction kγ).
//!
//! Uneven road: a quarter-car at each wheel, unsprung mass mu on the tyre's vertical stiffness
//! Cz (VERTICAL_STIFFNESS of the file) and damping ct, under the suspension ks, cs to a body held
//! still: `mu·z̈u = ΔFz,road − ks·zu − cs·żu`, `ΔFz,road = Cz·(zr − zu) + ct·(żr − żu)`, the
//! contact force clamped at 0 (the wheel may leave the road).
//!
//! ## Integration
//! Fixed step h. The tyre states advance exactly over the step with the kinematics of the step's
//! start ([`gough::relax`]); then the wheel speeds and the chassis velocities take one
//! semi-implicit (symplectic) Euler step with the new forces, and the positions move with the
//! new velocities. One Magic Formula evaluation per wheel and step. The stiff wheel–tyre
//! longitudinal mode (≈ 50 Hz) needs h ≤ 2 ms ([`MAX_DT`]).
//!
//! ## Running backwards
//! The transient slip of [`gough::relax`] is κ' = −Vsx/|Vx| in both directions and
//! [`gough::mf::eval`] with `Options::transient` takes it as such (no steady-state mirror for
//! Vx < 0), so a tyre sliding backwards takes energy out, as it must.
//!
//! ## What it leaves out
//! Suspension kinematics and compliance (toe, bump steer, caster) beyond the one compliance
//! steer term, roll and pitch as states, the body's heave, Ackermann geometry (both front
//! wheels steer by δ), drivetrain dynamics (the torques act on the wheels directly, an open differential per axle),
//! banked or sloped roads, the effective rolling radius' variation with load (Re is fixed at
//! each wheel's static load).

use super::road::Road;
use gough::math::Libm;
use gough::mf::{self, Input, Options, Output, Params, Side};
use gough::relax::{Kinematics, Operating, TransientTyre};

/// Gravity \[m/s²\].
pub const G: f64 = 9.81;

/// Longest step the wheel–tyre coupling is stable with \[s\].
pub const MAX_DT: f64 = 2e-3;

/// Wheel names in the order of every per-wheel array: front left, front right, rear left,
/// rear right.
pub const WHEELS: [&str; 4] = ["fl", "fr", "rl", "rr"];

/// Vehicle parameters. SI units. The default is a large SUV matching the bundled MF 6.1 tyre
/// (FNOMIN 6752 N, R0 0.39 m): 2200 kg, 2.9 m wheelbase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleParams {
    /// Total mass m \[kg\].
    pub m: f64,
    /// Yaw moment of inertia Iz \[kg·m²\].
    pub i_z: f64,
    /// CG to front axle a \[m\].
    pub a: f64,
    /// CG to rear axle b \[m\].
    pub b: f64,
    /// Front track \[m\].
    pub track_f: f64,
    /// Rear track \[m\].
    pub track_r: f64,
    /// CG height h \[m\].
    pub h: f64,
    /// Front share of the roll stiffness εf \[-\], in \[0, 1\].
    pub roll_share_f: f64,
    /// Roll gradient: body roll per lateral acceleration \[rad/(m/s²)\].
    pub roll_gradient: f64,
    /// Fraction of the body roll the wheels' camber follows kγ \[-\].
    pub roll_camber: f64,
    /// Static camber, negative = top of the wheel towards the car \[rad\].
    pub camber: f64,
    /// Time constant of the load transfer's response τ \[s\] (0: the previous step's forces).
    pub load_lag: f64,
    /// Spin inertia of a wheel with its brake disc and half-shaft Iw \[kg·m²\].
    pub i_w: f64,
    /// Steering ratio (steering-wheel angle / road-wheel angle) \[-\].
    pub steer_ratio: f64,
    /// Largest road-wheel steer angle \[rad\].
    pub steer_max: f64,
    /// Steering compliance: the front wheels steer back by this much per newton of front-axle
    /// side force (steering system and lateral-force compliance steer) \[rad/N\].
    pub steer_compliance: f64,
    /// Front share of the drive torque \[-\] (split equally left/right: open differentials).
    pub drive_share_f: f64,
    /// Largest total drive torque at the wheels \[N·m\].
    pub drive_max: f64,
    /// Front share of the brake torque \[-\].
    pub brake_share_f: f64,
    /// Aerodynamic drag area Cd·A \[m²\].
    pub cd_a: f64,
    /// Air density ρ \[kg/m³\].
    pub rho_air: f64,
    /// Unsprung mass per front wheel \[kg\] (quarter-car, uneven road only).
    pub m_u_f: f64,
    /// Unsprung mass per rear wheel \[kg\].
    pub m_u_r: f64,
    /// Suspension wheel rate ks \[N/m\].
    pub k_s: f64,
    /// Suspension damping at the wheel cs \[N·s/m\].
    pub c_s: f64,
    /// Tyre vertical damping ct \[N·s/m\].
    pub c_t: f64,
}

impl Default for VehicleParams {
    fn default() -> Self {
        VehicleParams {
            m: 2200.0,
            i_z: 4400.0,
            a: 1.35,
            b: 1.55,
            track_f: 1.65,
            track_r: 1.65,
            h: 0.65,
            roll_share_f: 0.6,
            roll_gradient: 0.5f64.to_radians(),
            roll_camber: 0.7,
            camber: -0.5f64.to_radians(),
            load_lag: 0.05,
            i_w: 1.5,
            steer_ratio: 16.0,
            steer_max: 35f64.to_radians(),
            steer_compliance: 0.15f64.to_radians() / 1000.0,
            drive_share_f: 0.4,
            drive_max: 5000.0,
            brake_share_f: 0.65,
            cd_a: 0.95,
            rho_air: 1.2,
            m_u_f: 50.0,
            m_u_r: 45.0,
            k_s: 40_000.0,
            c_s: 3_500.0,
            c_t: 500.0,
        }
    }
}

impl VehicleParams {
    /// Wheelbase L = a + b \[m\].
    pub fn wheelbase(&self) -> f64 {
        self.a + self.b
    }

    /// Wheel centre positions (x, y) in the body frame \[m\], in [`WHEELS`] order.
    pub fn wheel_positions(&self) -> [(f64, f64); 4] {
        let (tf, tr) = (self.track_f / 2.0, self.track_r / 2.0);
        [(self.a, tf), (self.a, -tf), (-self.b, tr), (-self.b, -tr)]
    }

    /// Static wheel loads \[N\], in [`WHEELS`] order.
    pub fn static_loads(&self) -> [f64; 4] {
        let l = self.wheelbase();
        let f = self.m * G * self.b / l / 2.0;
        let r = self.m * G * self.a / l / 2.0;
        [f, f, r, r]
    }

    /// Checks that every parameter is finite and in its physical range.
    pub fn validate(&self) -> Result<(), String> {
        let pos = [
            ("m", self.m),
            ("i_z", self.i_z),
            ("a", self.a),
            ("b", self.b),
            ("track_f", self.track_f),
            ("track_r", self.track_r),
            ("h", self.h),
            ("i_w", self.i_w),
            ("steer_ratio", self.steer_ratio),
            ("steer_max", self.steer_max),
            ("m_u_f", self.m_u_f),
            ("m_u_r", self.m_u_r),
            ("k_s", self.k_s),
        ];
        for (n, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("vehicle parameter {n} = {v} must be > 0"));
            }
        }
        let nonneg = [
            ("load_lag", self.load_lag),
            ("drive_max", self.drive_max),
            ("cd_a", self.cd_a),
            ("rho_air", self.rho_air),
            ("c_s", self.c_s),
            ("c_t", self.c_t),
            ("roll_gradient", self.roll_gradient),
            ("roll_camber", self.roll_camber),
            ("steer_compliance", self.steer_compliance),
        ];
        for (n, v) in nonneg {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("vehicle parameter {n} = {v} must be ≥ 0"));
            }
        }
        let shares = [
            ("roll_share_f", self.roll_share_f),
            ("drive_share_f", self.drive_share_f),
            ("brake_share_f", self.brake_share_f),
        ];
        for (n, v) in shares {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("vehicle parameter {n} = {v} must be in [0, 1]"));
            }
        }
        if !self.camber.is_finite() {
            return Err("vehicle parameter camber is not finite".into());
        }
        Ok(())
    }
}

/// What the driver and the brake system ask of the wheels over one step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Commands {
    /// Road-wheel steer angle δ of both front wheels \[rad\], > 0 to the left.
    pub steer: f64,
    /// Drive torque per wheel \[N·m\] (> 0 forwards), in [`WHEELS`] order.
    pub drive: [f64; 4],
    /// Brake torque magnitude per wheel \[N·m\], ≥ 0, in [`WHEELS`] order.
    pub brake: [f64; 4],
}

/// What one wheel saw and produced over a step. ISO-W at the contact point, SI, radians.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WheelRecord {
    /// Forward speed of the wheel centre Vx \[m/s\].
    pub vx: f64,
    /// Longitudinal slip speed Vsx = Vx − Ω·Re \[m/s\].
    pub vsx: f64,
    /// Lateral slip speed Vsy \[m/s\].
    pub vsy: f64,
    /// Kinematic slip angle α = atan(Vsy/|Vx|) \[rad\] (what the sensors see).
    pub alpha: f64,
    /// Kinematic longitudinal slip κ = −Vsx/|Vx| \[-\] (what an ABS sees; 0 below 0.1 m/s).
    pub kappa: f64,
    /// Transient slip angle α' that the Magic Formula got \[rad\].
    pub alpha_t: f64,
    /// Transient longitudinal slip κ' that the Magic Formula got \[-\].
    pub kappa_t: f64,
    /// Inclination γ \[rad\].
    pub gamma: f64,
    /// Vertical load Fz \[N\].
    pub fz: f64,
    /// Longitudinal force Fx \[N\].
    pub fx: f64,
    /// Lateral force Fy \[N\].
    pub fy: f64,
    /// Aligning moment Mz \[N·m\].
    pub mz: f64,
    /// Road friction under the wheel μ \[-\] (docs/architecture.md's μ).
    pub mu_true: f64,
    /// Wheel angular speed Ω \[rad/s\] (> 0 rolling forwards).
    pub omega: f64,
    /// Net applied torque drive − brake \[N·m\] (the brake's sign as it acts: against Ω).
    pub torque: f64,
}

/// Vehicle-level quantities of a step. World frame for position and heading, body frame for
/// the rest.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VehicleRecord {
    /// CG position X \[m\] (world; the start heading).
    pub x: f64,
    /// CG position Y \[m\] (world; left of the start heading).
    pub y: f64,
    /// Heading ψ \[rad\].
    pub yaw: f64,
    /// Forward speed vx \[m/s\] (body).
    pub vx: f64,
    /// Lateral speed vy \[m/s\] (body).
    pub vy: f64,
    /// Yaw rate r \[rad/s\].
    pub r: f64,
    /// Longitudinal acceleration ax \[m/s²\] as an accelerometer at the CG reads it (ΣF/m).
    pub ax: f64,
    /// Lateral acceleration ay \[m/s²\] (ΣF/m, body y).
    pub ay: f64,
    /// Road-wheel steer angle δ of the front wheels, after the compliance steer \[rad\].
    pub steer: f64,
}

/// One logged step: the state at `t` and the forces acting over \[t, t + h\].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Record {
    /// Time t \[s\].
    pub t: f64,
    /// Vehicle quantities.
    pub vehicle: VehicleRecord,
    /// Wheels in [`WHEELS`] order.
    pub wheels: [WheelRecord; 4],
}

/// One wheel's state.
#[derive(Debug, Clone)]
pub struct WheelState {
    /// Angular speed Ω \[rad/s\].
    pub omega: f64,
    /// Effective rolling radius Re \[m\] (fixed, at the static load).
    pub re: f64,
    /// The transient tyre (deflection states).
    pub tyre: TransientTyre<f64>,
    /// The tyre's parameters with λμx, λμy set for the road under it.
    pub params: Params<f64>,
    /// Road friction the parameters are scaled for.
    pub mu: f64,
    /// Unsprung mass displacement zu \[m\] (quarter-car).
    pub z_u: f64,
    /// Unsprung mass velocity żu \[m/s\].
    pub zd_u: f64,
    options: Options,
    sign: f64,
}

/// Initial state of a run.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Initial {
    /// Forward speed \[m/s\] (≥ 0).
    pub speed: f64,
    /// Yaw rate \[rad/s\] (a car starting on a circle: V/R).
    pub yaw_rate: f64,
}

/// The vehicle: parameters and state. Advance it with [`Vehicle::step`].
#[derive(Debug, Clone)]
pub struct Vehicle {
    /// Parameters.
    pub p: VehicleParams,
    /// Time \[s\].
    pub t: f64,
    /// CG X \[m\] (world).
    pub x: f64,
    /// CG Y \[m\] (world).
    pub y: f64,
    /// Heading ψ \[rad\].
    pub yaw: f64,
    /// Forward speed \[m/s\] (body).
    pub vx: f64,
    /// Lateral speed \[m/s\] (body).
    pub vy: f64,
    /// Yaw rate \[rad/s\].
    pub r: f64,
    /// Wheels in [`WHEELS`] order.
    pub wheels: [WheelState; 4],
    /// The tyre file's μy at FNOMIN, γ = 0, nominal pressure (docs/architecture.md's μy0).
    pub mu_y0: f64,
    /// The record of the last step.
    pub last: Record,
    /// Accelerations (tyre forces / m) the load transfer uses, after the lag \[m/s²\].
    ax_lt: f64,
    ay_lt: f64,
    /// Front-axle side force of the last step (wheel axes) \[N\], for the compliance steer.
    fy_front: f64,
    base_lmux: f64,
    base_lmuy: f64,
    positions: [(f64, f64); 4],
    static_fz: [f64; 4],
}

/// μy0: the file's μy at Fz = FNOMIN, zero camber, nominal pressure (docs/architecture.md).
pub fn mu_y0(tyre: &Params<f64>) -> Result<f64, String> {
    let p = if tyre.nompres > 0.0 {
        Some(tyre.nompres)
    } else {
        None
    };
    let out = mf::eval::<f64, Libm>(
        tyre,
        &Input {
            fz: tyre.fnomin,
            vx: tyre.longvl.max(1.0),
            p,
            ..Input::default()
        },
        &Options::default(),
    )
    .map_err(|e| format!("tyre: μy0 at FNOMIN: {e}"))?;
    if !(out.mu_y.is_finite() && out.mu_y > 0.0) {
        return Err(format!("tyre: μy0 at FNOMIN is {}, not > 0", out.mu_y));
    }
    Ok(out.mu_y)
}

impl Vehicle {
    /// A vehicle at the origin heading along +X, wheels rolling freely, tyres undeflected.
    pub fn new(
        p: VehicleParams,
        tyre: &Params<f64>,
        road: &Road,
        init: Initial,
    ) -> Result<Vehicle, String> {
        p.validate()?;
        if !(init.speed.is_finite() && init.speed >= 0.0 && init.yaw_rate.is_finite()) {
            return Err(format!(
                "initial speed {} must be finite and ≥ 0",
                init.speed
            ));
        }
        if !(tyre.fnomin > 0.0 && tyre.unloaded_radius > 0.0) {
            return Err("tyre: FNOMIN and UNLOADED_RADIUS must be > 0".into());
        }
        let mu_y0 = mu_y0(tyre)?;
        let positions = p.wheel_positions();
        let static_fz = p.static_loads();
        let c_z = vertical_stiffness(tyre);
        let mk = |i: usize| -> WheelState {
            let yi = positions[i].1;
            let left = yi > 0.0;
            // Re = R0 − ρ/3, ρ = Fz/Cz: the radial-tyre rule of thumb at the static load.
            let re = tyre.unloaded_radius - static_fz[i] / c_z / 3.0;
            let u = init.speed - init.yaw_rate * yi;
            WheelState {
                omega: u / re,
                re,
                tyre: TransientTyre::new(tyre),
                params: tyre.clone(),
                mu: f64::NAN,
                z_u: 0.0,
                zd_u: 0.0,
                options: Options {
                    transient: true,
                    mounted: Some(if left { Side::Left } else { Side::Right }),
                    ..Options::default()
                },
                sign: if left { 1.0 } else { -1.0 },
            }
        };
        let wheels = [mk(0), mk(1), mk(2), mk(3)];
        let mut v = Vehicle {
            p,
            t: 0.0,
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            vx: init.speed,
            vy: 0.0,
            r: init.yaw_rate,
            wheels,
            mu_y0,
            last: Record::default(),
            ax_lt: 0.0,
            ay_lt: init.speed * init.yaw_rate,
            fy_front: 0.0,
            base_lmux: tyre.lmux,
            base_lmuy: tyre.lmuy,
            positions,
            static_fz,
        };
        v.update_mu(road);
        Ok(v)
    }

    /// Speed over ground |V| \[m/s\].
    pub fn speed(&self) -> f64 {
        self.vx.hypot(self.vy)
    }

    /// World position of wheel `i`'s centre \[m\].
    pub fn wheel_position(&self, i: usize) -> (f64, f64) {
        let (xi, yi) = self.positions[i];
        let (s, c) = self.yaw.sin_cos();
        (self.x + xi * c - yi * s, self.y + xi * s + yi * c)
    }

    /// Forward speed of each wheel centre along its own heading \[m/s\] for the commanded
    /// steer `steer` (the compliance steer is applied here as in [`Vehicle::step`]).
    pub fn wheel_speeds(&self, steer: f64) -> [f64; 4] {
        let steer = steer - self.p.steer_compliance * self.fy_front;
        let mut out = [0.0; 4];
        for (i, o) in out.iter_mut().enumerate() {
            let (xi, yi) = self.positions[i];
            let d = if i < 2 { steer } else { 0.0 };
            let (s, c) = d.sin_cos();
            *o = (self.vx - self.r * yi) * c + (self.vy + self.r * xi) * s;
        }
        out
    }

    /// Kinematic slip κ = −Vsx/|Vx| of each wheel now (what an ABS computes) \[-\].
    pub fn wheel_slips(&self, steer: f64) -> [f64; 4] {
        let v = self.wheel_speeds(steer);
        let mut k = [0.0; 4];
        for i in 0..4 {
            k[i] = kinematic_kappa(v[i], v[i] - self.wheels[i].omega * self.wheels[i].re);
        }
        k
    }

    /// Sets each wheel's λμx, λμy for the road under it: λμ = λμ,file·μ/μy0.
    fn update_mu(&mut self, road: &Road) {
        for i in 0..4 {
            let (wx, wy) = self.wheel_position(i);
            let mu = road.mu(wx, wy, self.mu_y0);
            let w = &mut self.wheels[i];
            if mu != w.mu {
                w.mu = mu;
                w.params.lmux = self.base_lmux * mu / self.mu_y0;
                w.params.lmuy = self.base_lmuy * mu / self.mu_y0;
            }
        }
    }

    /// Advances the vehicle by `dt` \[s\] under `cmd`; the step's record is in [`Vehicle::last`].
    pub fn step(&mut self, cmd: &Commands, road: &Road, dt: f64) -> Result<(), String> {
        let p = self.p;
        self.update_mu(road);
        let l = p.wheelbase();
        // Quasi-static load transfer (module doc).
        let long = p.m * self.ax_lt * p.h / l / 2.0; // per wheel, + rear / − front
        let axle_f = self.static_fz[0] * 2.0 - 2.0 * long;
        let axle_r = self.static_fz[2] * 2.0 + 2.0 * long;
        let lat_f = (p.m * self.ay_lt * p.h * p.roll_share_f / p.track_f)
            .clamp(-axle_f.max(0.0) / 2.0, axle_f.max(0.0) / 2.0);
        let lat_r = (p.m * self.ay_lt * p.h * (1.0 - p.roll_share_f) / p.track_r)
            .clamp(-axle_r.max(0.0) / 2.0, axle_r.max(0.0) / 2.0);
        let mut fz = [
            axle_f / 2.0 - lat_f,
            axle_f / 2.0 + lat_f,
            axle_r / 2.0 - lat_r,
            axle_r / 2.0 + lat_r,
        ];
        let phi = p.roll_gradient * self.ay_lt; // roll angle, > 0 leaning right
        let (sy, cy) = self.yaw.sin_cos();
        // Compliance steer from the last step's front side force (explicit; its loop gain
        // c·Cα,axle ≈ 0.5 is well inside the one-step-delay stability bound of 1).
        let steer = cmd.steer - p.steer_compliance * self.fy_front;
        let (sd, cd) = steer.sin_cos();
        let mut rec = Record {
            t: self.t,
            vehicle: VehicleRecord {
                x: self.x,
                y: self.y,
                yaw: self.yaw,
                vx: self.vx,
                vy: self.vy,
                r: self.r,
                steer,
                ..VehicleRecord::default()
            },
            wheels: [WheelRecord::default(); 4],
        };
        let (mut fxb, mut fyb, mut mzb) = (0.0, 0.0, 0.0);
        let flat = road.is_flat();
        let (mut fx_tyres, mut fy_tyres) = (0.0, 0.0);
        let mut fy_front = 0.0;
        for i in 0..4 {
            let (xi, yi) = self.positions[i];
            let (s, c) = if i < 2 { (sd, cd) } else { (0.0, 1.0) };
            // Wheel-centre velocity, body frame, then the wheel's ISO-W axes.
            let (u, w) = (self.vx - self.r * yi, self.vy + self.r * xi);
            let vxw = u * c + w * s;
            let vyw = -u * s + w * c;
            let wheel = &mut self.wheels[i];
            if !flat {
                // Quarter-car on the road profile (module doc), semi-implicit Euler.
                let wx = self.x + xi * cy - yi * sy;
                let xdot = u * cy - w * sy; // dX/dt of the wheel centre
                let hgt = road.height(wx, yi > 0.0);
                let (zr, zrd) = (hgt.z, hgt.slope * xdot);
                let c_z = vertical_stiffness(&wheel.params);
                let d_fz = (c_z * (zr - wheel.z_u) + p.c_t * (zrd - wheel.zd_u)).max(-fz[i]);
                let m_u = if i < 2 { p.m_u_f } else { p.m_u_r };
                let acc = (d_fz - p.k_s * wheel.z_u - p.c_s * wheel.zd_u) / m_u;
                wheel.zd_u += dt * acc;
                wheel.z_u += dt * wheel.zd_u;
                fz[i] += d_fz;
            }
            fz[i] = fz[i].max(0.0);
            let gamma = wheel.sign * p.camber - p.roll_camber * phi;
            let vsx = vxw - wheel.omega * wheel.re;
            let op = Operating {
                kin: Kinematics {
                    vx: vxw,
                    vsx,
                    vsy: vyw,
                },
                fz: fz[i],
                gamma,
                phit: 0.0,
                p: None,
            };
            let (out, slips): (Output<f64>, _) = wheel
                .tyre
                .step::<Libm>(&wheel.params, &wheel.options, dt, &op)
                .map_err(|e| {
                    format!(
                        "t = {:.3} s, wheel {}: tyre step failed: {e:?}",
                        self.t, WHEELS[i]
                    )
                })?;
            let omega0 = wheel.omega;
            // Wheel spin: drive and tyre torque, then brake and rolling resistance as Coulomb
            // torques that can stop the wheel but not reverse it.
            let om_free = wheel.omega + dt / p.i_w * (cmd.drive[i] - wheel.re * out.fx);
            let resist = (cmd.brake[i].max(0.0) + out.my.abs()) * dt / p.i_w;
            let om_new = if om_free.abs() <= resist {
                0.0
            } else {
                om_free - resist.copysign(om_free)
            };
            let brake_sign = if wheel.omega != 0.0 {
                wheel.omega.signum()
            } else {
                om_free.signum()
            };
            wheel.omega = om_new;
            // Forces into the body frame.
            let fxi = out.fx * c - out.fy * s;
            let fyi = out.fx * s + out.fy * c;
            fxb += fxi;
            fyb += fyi;
            mzb += xi * fyi - yi * fxi + out.mz;
            fx_tyres += fxi;
            fy_tyres += fyi;
            if i < 2 {
                fy_front += out.fy;
            }
            rec.wheels[i] = WheelRecord {
                vx: vxw,
                vsx,
                vsy: vyw,
                alpha: vyw.atan2(vxw.abs()),
                kappa: kinematic_kappa(vxw, vsx),
                alpha_t: slips.alpha,
                kappa_t: slips.kappa,
                gamma,
                fz: fz[i],
                fx: out.fx,
                fy: out.fy,
                mz: out.mz,
                mu_true: wheel.mu,
                omega: omega0,
                torque: cmd.drive[i] - cmd.brake[i].max(0.0) * brake_sign,
            };
        }
        // Aerodynamic drag at the CG (moves no load).
        let v = self.speed();
        let k_d = 0.5 * p.rho_air * p.cd_a * v;
        fxb -= k_d * self.vx;
        fyb -= k_d * self.vy;
        let (ax, ay) = (fxb / p.m, fyb / p.m);
        rec.vehicle.ax = ax;
        rec.vehicle.ay = ay;
        // Semi-implicit Euler: velocities with the step's forces, positions with the new ones.
        let (vx0, vy0) = (self.vx, self.vy);
        self.vx += dt * (ax + self.r * vy0);
        self.vy += dt * (ay - self.r * vx0);
        self.r += dt * mzb / p.i_z;
        self.yaw += dt * self.r;
        let (sy, cy) = self.yaw.sin_cos();
        self.x += dt * (self.vx * cy - self.vy * sy);
        self.y += dt * (self.vx * sy + self.vy * cy);
        // Load-transfer accelerations through the lag.
        let (ax_t, ay_t) = (fx_tyres / p.m, fy_tyres / p.m);
        let w = if p.load_lag > 0.0 {
            1.0 - (-dt / p.load_lag).exp()
        } else {
            1.0
        };
        self.ax_lt += w * (ax_t - self.ax_lt);
        self.ay_lt += w * (ay_t - self.ay_lt);
        self.fy_front = fy_front;
        self.t += dt;
        if !(self.vx.is_finite() && self.vy.is_finite() && self.r.is_finite()) {
            return Err(format!(
                "t = {:.3} s: the vehicle state is not finite",
                self.t
            ));
        }
        self.last = rec;
        Ok(())
    }
}

/// κ = −Vsx/|Vx| (ISO-W), 0 below 0.1 m/s where it means nothing.
pub fn kinematic_kappa(vx: f64, vsx: f64) -> f64 {
    if vx.abs() < 0.1 {
        0.0
    } else {
        -vsx / vx.abs()
    }
}

/// The tyre's vertical stiffness Cz \[N/m\]: VERTICAL_STIFFNESS, or (files without it) the
/// stiffness that deflects the tyre by 5 % of R0 at FNOMIN.
pub fn vertical_stiffness(tyre: &Params<f64>) -> f64 {
    if tyre.vertical_stiffness > 0.0 {
        tyre.vertical_stiffness
    } else {
        tyre.fnomin / (0.05 * tyre.unloaded_radius)
    }
}
