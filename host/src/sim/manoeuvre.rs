//! Manoeuvres and the driver that flies them: open-loop steering inputs, a path-following
//! steering controller, a speed controller and brake demands.
//!
//! | name | what | standard it follows |
//! |---|---|---|
//! | `step-steer` | steering-wheel step (500 °/s) at constant speed | ISO 7401 |
//! | `sine-dwell` | 0.7 Hz sine, 500 ms dwell at the second peak, throttle released | FMVSS 126 (ESC) |
//! | `brake-in-turn` | steady circle, then braking with the steering wheel held | ISO 7975 |
//! | `abs-split` | straight full-braking stop, the driver keeps the lane | μ-split ABS test |
//! | `constant-radius` | circle held by the driver while the speed ramps up | ISO 4138 |
//! | `slalom` | sinusoidal path through cones, constant speed | (18 m pitch) |
//! | `coast-down` | straight, no inputs | — |
//!
//! ## Driver
//! - Path following (preview / pure pursuit with integral action and yaw damping): the point
//!   Ld = 3 m + 0.35 s·V ahead along the course (heading + sideslip) has a lateral error e from
//!   the path (> 0 when the path lies to its left), κp is the path's curvature at the car;
//!   `δ = 2L/Ld²·(e + Ki·∫(e − κp·Ld²/2) dt) + Kr·(L/V)·(V·κp − r)`. The pure-pursuit term alone
//!   steers a circle of radius R with δ ≈ L/R; the integral removes the understeer's offset
//!   (a car on the path sees e = κp·Ld²/2 exactly), the last term damps the yaw.
//! - Speed: `Td = m·Re·(a_ff + Kp·(Vt − vx) + Ki·∫(Vt − vx) dt)` clamped to \[0, drive_max\],
//!   with a_ff the ramp's acceleration plus the drag's.
//! - Steering is rate limited (1000 °/s at the steering wheel) and clamped to the lock.
//! - Brake demand: a deceleration demand d turns into a total torque m·d·Re, ramped in over
//!   0.2 s, split front/rear by the brake balance and equally left/right.
//!
//! ## What it leaves out
//! Driver delays and neuromuscular dynamics; gears and engine maps (torque at the wheels);
//! closed-loop steering during the standards' open-loop phases.

use super::vehicle::{Commands, Vehicle, VehicleParams, G};
use std::f64::consts::PI;

/// The manoeuvre names the CLI takes.
pub const MANOEUVRES: [&str; 7] = [
    "step-steer",
    "sine-dwell",
    "brake-in-turn",
    "abs-split",
    "constant-radius",
    "slalom",
    "coast-down",
];

/// A manoeuvre with its parameters. Speeds \[m/s\], angles \[rad\] (steering-wheel angles where
/// named `_sw`), times \[s\], lengths \[m\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Manoeuvre {
    /// Steering-wheel step of `steer_sw` at `at`, rate 500 °/s, speed held at `speed`.
    StepSteer {
        /// Speed \[m/s\].
        speed: f64,
        /// Steering-wheel angle \[rad\], > 0 left.
        steer_sw: f64,
        /// Start of the step \[s\].
        at: f64,
    },
    /// FMVSS 126: from `speed`, throttle released at `at`, δsw = A·sin(2π·0.7·t) to its second
    /// peak, 500 ms dwell there, then back to 0 over the last quarter period.
    SineWithDwell {
        /// Entry speed \[m/s\].
        speed: f64,
        /// Steering-wheel amplitude A \[rad\].
        amplitude_sw: f64,
        /// Start of the sine \[s\].
        at: f64,
    },
    /// Circle of `radius` at `speed` (driver), braking with `decel` from `brake_at` with the
    /// steering wheel held; ends at standstill.
    BrakeInTurn {
        /// Speed \[m/s\].
        speed: f64,
        /// Radius \[m\], > 0 (left turn).
        radius: f64,
        /// Start of braking \[s\].
        brake_at: f64,
        /// Deceleration demand \[m/s²\].
        decel: f64,
    },
    /// Straight full braking (demand `decel`) from `speed` at `brake_at`, the driver keeping
    /// the lane if `driver`; ends at standstill.
    AbsSplit {
        /// Speed \[m/s\].
        speed: f64,
        /// Start of braking \[s\].
        brake_at: f64,
        /// Deceleration demand \[m/s²\] (beyond the road's grip: full braking).
        decel: f64,
        /// Steer to keep the lane (else the steering wheel is held straight).
        driver: bool,
    },
    /// Circle of `radius`, speed ramping from `speed` at `accel`.
    ConstantRadius {
        /// Start speed \[m/s\].
        speed: f64,
        /// Radius \[m\], > 0 (left turn).
        radius: f64,
        /// Speed ramp \[m/s²\].
        accel: f64,
    },
    /// Slalom: path Y = A·sin(π·(X − x0)/pitch) past cones every `pitch`, at `speed`.
    Slalom {
        /// Speed \[m/s\].
        speed: f64,
        /// Cone spacing \[m\].
        pitch: f64,
        /// Lateral amplitude A \[m\].
        amplitude: f64,
        /// Where the slalom starts X0 \[m\].
        start_x: f64,
    },
    /// Straight, no steering, drive or brake.
    CoastDown {
        /// Start speed \[m/s\].
        speed: f64,
    },
}

/// Optional overrides of a manoeuvre's defaults (the CLI's flags).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Overrides {
    /// Speed \[m/s\].
    pub speed: Option<f64>,
    /// Steering-wheel angle or amplitude \[rad\].
    pub steer_sw: Option<f64>,
    /// Circle radius \[m\].
    pub radius: Option<f64>,
    /// Deceleration demand \[m/s²\].
    pub decel: Option<f64>,
}

impl Manoeuvre {
    /// The manoeuvre `name` (one of [`MANOEUVRES`]) with its defaults, changed by `o`.
    pub fn by_name(name: &str, o: &Overrides) -> Result<Manoeuvre, String> {
        let check = |what: &str, v: Option<f64>, lo: f64, hi: f64| -> Result<(), String> {
            match v {
                Some(x) if !(x.is_finite() && x >= lo && x <= hi) => {
                    Err(format!("{what} {x} outside [{lo}, {hi}]"))
                }
                _ => Ok(()),
            }
        };
        check("--speed", o.speed, 0.0, 70.0)?;
        check("--radius", o.radius, 5.0, 10_000.0)?;
        check("--decel", o.decel, 0.0, 20.0)?;
        if let Some(s) = o.steer_sw {
            check("--steer", Some(s.to_degrees()), -720.0, 720.0)?;
        }
        let kmh = |v: f64| v / 3.6;
        let m = match name {
            "step-steer" => Manoeuvre::StepSteer {
                speed: o.speed.unwrap_or(kmh(80.0)),
                steer_sw: o.steer_sw.unwrap_or(40f64.to_radians()),
                at: 0.5,
            },
            "sine-dwell" => Manoeuvre::SineWithDwell {
                speed: o.speed.unwrap_or(kmh(80.0)),
                amplitude_sw: o.steer_sw.unwrap_or(120f64.to_radians()),
                at: 1.0,
            },
            "brake-in-turn" => Manoeuvre::BrakeInTurn {
                speed: o.speed.unwrap_or(20.0),
                radius: o.radius.unwrap_or(100.0),
                brake_at: 3.0,
                decel: o.decel.unwrap_or(5.0),
            },
            "abs-split" => Manoeuvre::AbsSplit {
                speed: o.speed.unwrap_or(kmh(100.0)),
                brake_at: 0.3,
                decel: o.decel.unwrap_or(1.2 * G),
                driver: true,
            },
            "constant-radius" => Manoeuvre::ConstantRadius {
                speed: o.speed.unwrap_or(10.0),
                radius: o.radius.unwrap_or(100.0),
                accel: 0.3,
            },
            "slalom" => Manoeuvre::Slalom {
                speed: o.speed.unwrap_or(kmh(60.0)),
                pitch: 18.0,
                amplitude: 1.0,
                start_x: 20.0,
            },
            "coast-down" => Manoeuvre::CoastDown {
                speed: o.speed.unwrap_or(kmh(100.0)),
            },
            _ => {
                return Err(format!(
                    "unknown manoeuvre '{name}' (one of: {})",
                    MANOEUVRES.join(", ")
                ))
            }
        };
        Ok(m)
    }

    /// The CLI name.
    pub fn name(&self) -> &'static str {
        match self {
            Manoeuvre::StepSteer { .. } => "step-steer",
            Manoeuvre::SineWithDwell { .. } => "sine-dwell",
            Manoeuvre::BrakeInTurn { .. } => "brake-in-turn",
            Manoeuvre::AbsSplit { .. } => "abs-split",
            Manoeuvre::ConstantRadius { .. } => "constant-radius",
            Manoeuvre::Slalom { .. } => "slalom",
            Manoeuvre::CoastDown { .. } => "coast-down",
        }
    }

    /// Entry speed \[m/s\].
    pub fn speed(&self) -> f64 {
        match *self {
            Manoeuvre::StepSteer { speed, .. }
            | Manoeuvre::SineWithDwell { speed, .. }
            | Manoeuvre::BrakeInTurn { speed, .. }
            | Manoeuvre::AbsSplit { speed, .. }
            | Manoeuvre::ConstantRadius { speed, .. }
            | Manoeuvre::Slalom { speed, .. }
            | Manoeuvre::CoastDown { speed } => speed,
        }
    }

    /// The initial yaw rate: V/R on a circle, else 0 \[rad/s\].
    pub fn initial_yaw_rate(&self) -> f64 {
        match *self {
            Manoeuvre::BrakeInTurn { speed, radius, .. }
            | Manoeuvre::ConstantRadius { speed, radius, .. } => speed / radius,
            _ => 0.0,
        }
    }

    /// Default duration \[s\].
    pub fn default_duration(&self) -> f64 {
        match self {
            Manoeuvre::StepSteer { .. } => 5.0,
            Manoeuvre::SineWithDwell { .. } => 6.0,
            Manoeuvre::BrakeInTurn { .. } => 10.0,
            Manoeuvre::AbsSplit { .. } => 15.0,
            Manoeuvre::ConstantRadius { .. } => 40.0,
            Manoeuvre::Slalom { .. } => 12.0,
            Manoeuvre::CoastDown { .. } => 20.0,
        }
    }

    /// The road spec a manoeuvre runs on when none is given (`None`: the file's surface).
    pub fn default_road(&self) -> Option<&'static str> {
        match self {
            Manoeuvre::AbsSplit { .. } => Some("split=0.9/0.2"),
            _ => None,
        }
    }

    /// Does the run end when the vehicle has stopped?
    pub fn ends_at_standstill(&self) -> bool {
        matches!(
            self,
            Manoeuvre::BrakeInTurn { .. } | Manoeuvre::AbsSplit { .. }
        )
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), String> {
        let bad = |what: &str, v: f64| format!("{}: {what} = {v} is out of range", self.name());
        match *self {
            Manoeuvre::BrakeInTurn { radius, .. } | Manoeuvre::ConstantRadius { radius, .. }
                if !(radius.is_finite() && radius >= 5.0) =>
            {
                Err(bad("radius", radius))
            }
            Manoeuvre::Slalom {
                pitch, amplitude, ..
            } if !(pitch.is_finite() && pitch > 1.0 && amplitude.is_finite()) => {
                Err(bad("pitch", pitch))
            }
            m if !(m.speed().is_finite() && m.speed() >= 0.0) => Err(bad("speed", m.speed())),
            _ => Ok(()),
        }
    }
}

/// A path for the steering controller, starting at the origin heading along +X.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Path {
    /// The X axis.
    Line,
    /// A left-hand circle of this radius through the origin, centre (0, R).
    Circle(f64),
    /// Y = 0 up to X0, then Y = A·E·sin(k·(X − X0)), k = 2π/wavelength, E ramping 0 → 1 over
    /// the first half wavelength (a smooth entry).
    Sine {
        /// X0 \[m\].
        x0: f64,
        /// A \[m\].
        amplitude: f64,
        /// Wavelength \[m\].
        wavelength: f64,
    },
}

impl Path {
    /// Lateral error of the point (px, py) \[m\]: > 0 when the path lies to the left of the
    /// point (seen along +X, or along the circle).
    pub fn error(&self, px: f64, py: f64) -> f64 {
        match *self {
            Path::Line => -py,
            Path::Circle(r) => px.hypot(py - r) - r,
            Path::Sine { .. } => {
                let (y, dy, _) = self.sine(px);
                (y - py) / dy.hypot(1.0)
            }
        }
    }

    /// Path curvature \[1/m\] (> 0 turning left) near the point (px, py).
    pub fn curvature(&self, px: f64) -> f64 {
        match *self {
            Path::Line => 0.0,
            Path::Circle(r) => 1.0 / r,
            Path::Sine { .. } => {
                let (_, dy, ddy) = self.sine(px);
                ddy / (1.0 + dy * dy).powf(1.5)
            }
        }
    }

    /// Y, dY/dX, d²Y/dX² of the sine path at X (zeros for the other paths).
    fn sine(&self, px: f64) -> (f64, f64, f64) {
        let Path::Sine {
            x0,
            amplitude: a,
            wavelength,
        } = *self
        else {
            return (0.0, 0.0, 0.0);
        };
        let xi = px - x0;
        if xi <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let k = 2.0 * PI / wavelength;
        let half = wavelength / 2.0;
        let (e, de) = if xi < half {
            (xi / half, 1.0 / half)
        } else {
            (1.0, 0.0)
        };
        let (s, c) = (k * xi).sin_cos();
        (
            a * e * s,
            a * (de * s + e * k * c),
            a * (2.0 * de * k * c - e * k * k * s),
        )
    }
}

/// The driver: controller states for steering and speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Driver {
    /// The manoeuvre flown.
    pub manoeuvre: Manoeuvre,
    path_int: f64,
    speed_int: f64,
    steer: f64,
    held_steer: Option<f64>,
}

/// Integral gain of the path controller \[1/s\] relative to the proportional gain.
const PATH_KI: f64 = 0.5;
/// Preview distance Ld = PREVIEW_L0 + PREVIEW_T·V \[m\], \[s\].
const PREVIEW_L0: f64 = 3.0;
const PREVIEW_T: f64 = 0.35;
/// Yaw-rate feedback, as a fraction of the neutral-steer angle L·Δr/V \[-\].
const YAW_KR: f64 = 2.0;
/// Speed controller gains: \[1/s\] and \[1/s²\].
const SPEED_KP: f64 = 1.0;
const SPEED_KI: f64 = 0.3;
/// Steering-wheel rate limit \[rad/s\].
const STEER_RATE_SW: f64 = 1000.0 * PI / 180.0;
/// Step-steer rate at the steering wheel \[rad/s\] (ISO 7401: ≥ 200 °/s; 500 °/s here).
const STEP_RATE_SW: f64 = 500.0 * PI / 180.0;
/// Brake demand ramp-in time \[s\].
const BRAKE_RAMP: f64 = 0.2;

impl Driver {
    /// A driver for `m`, steering straight.
    pub fn new(m: Manoeuvre) -> Driver {
        Driver {
            manoeuvre: m,
            path_int: 0.0,
            speed_int: 0.0,
            steer: 0.0,
            held_steer: None,
        }
    }

    /// The path the driver follows at time `t`, if any.
    fn path(&self, t: f64) -> Option<Path> {
        match self.manoeuvre {
            Manoeuvre::BrakeInTurn {
                radius, brake_at, ..
            } if t < brake_at => Some(Path::Circle(radius)),
            Manoeuvre::ConstantRadius { radius, .. } => Some(Path::Circle(radius)),
            Manoeuvre::AbsSplit { driver: true, .. } => Some(Path::Line),
            Manoeuvre::Slalom {
                pitch,
                amplitude,
                start_x,
                ..
            } => Some(Path::Sine {
                x0: start_x,
                amplitude,
                wavelength: 2.0 * pitch,
            }),
            _ => None,
        }
    }

    /// Path-following steer (module doc).
    fn follow(&mut self, path: Path, v: &Vehicle, dt: f64) -> f64 {
        let l = v.p.wheelbase();
        let speed = v.speed();
        let ld = PREVIEW_L0 + PREVIEW_T * speed;
        // Preview along the course (heading + sideslip), so a car on the path with its
        // velocity along it sees exactly the path's own offset κ·Ld²/2.
        let course = v.yaw + if speed > 0.5 { v.vy.atan2(v.vx) } else { 0.0 };
        let (s, c) = course.sin_cos();
        let e = path.error(v.x + ld * c, v.y + ld * s);
        let kappa = path.curvature(v.x);
        let kp = 2.0 * l / (ld * ld);
        self.path_int += (e - kappa * ld * ld / 2.0) * dt;
        // Anti-windup: the integral alone may not ask for more than the lock.
        let lim = v.p.steer_max / (kp * PATH_KI);
        self.path_int = self.path_int.clamp(-lim, lim);
        let yaw_damping = YAW_KR * l / speed.max(5.0) * (speed * kappa - v.r);
        kp * (e + PATH_KI * self.path_int) + yaw_damping
    }

    /// Open-loop steering-wheel angle at `t` \[rad\], if the manoeuvre prescribes one.
    fn open_loop_sw(&self, t: f64) -> Option<f64> {
        match self.manoeuvre {
            Manoeuvre::StepSteer { steer_sw, at, .. } => {
                Some((STEP_RATE_SW * (t - at)).clamp(0.0, steer_sw.abs()) * steer_sw.signum())
            }
            Manoeuvre::SineWithDwell {
                amplitude_sw, at, ..
            } => Some(sine_with_dwell(t - at, amplitude_sw)),
            Manoeuvre::CoastDown { .. } | Manoeuvre::AbsSplit { driver: false, .. } => Some(0.0),
            _ => None,
        }
    }

    /// Target speed at `t` and whether the speed controller drives at all.
    fn speed_target(&self, t: f64) -> Option<(f64, f64)> {
        match self.manoeuvre {
            Manoeuvre::StepSteer { speed, .. } | Manoeuvre::Slalom { speed, .. } => {
                Some((speed, 0.0))
            }
            Manoeuvre::SineWithDwell { speed, at, .. } if t < at => Some((speed, 0.0)),
            Manoeuvre::BrakeInTurn {
                speed, brake_at, ..
            } if t < brake_at => Some((speed, 0.0)),
            Manoeuvre::AbsSplit {
                speed, brake_at, ..
            } if t < brake_at => Some((speed, 0.0)),
            Manoeuvre::ConstantRadius { speed, accel, .. } => Some((speed + accel * t, accel)),
            _ => None,
        }
    }

    /// Total brake torque demand at `t` \[N·m\].
    fn brake_demand(&self, t: f64, v: &Vehicle) -> f64 {
        let (at, decel) = match self.manoeuvre {
            Manoeuvre::BrakeInTurn {
                brake_at, decel, ..
            }
            | Manoeuvre::AbsSplit {
                brake_at, decel, ..
            } => (brake_at, decel),
            _ => return 0.0,
        };
        if t < at {
            return 0.0;
        }
        let ramp = ((t - at) / BRAKE_RAMP).min(1.0);
        let re = v.wheels.iter().map(|w| w.re).sum::<f64>() / 4.0;
        ramp * v.p.m * decel * re
    }

    /// The commands for the step starting at `t` (before any ABS).
    pub fn command(&mut self, t: f64, v: &Vehicle, dt: f64) -> Commands {
        let p: &VehicleParams = &v.p;
        // Steering.
        let want = if let Some(sw) = self.open_loop_sw(t) {
            sw / p.steer_ratio
        } else if let Some(path) = self.path(t) {
            self.follow(path, v, dt)
        } else {
            // Steering wheel held where it was (braking in a turn).
            *self.held_steer.get_or_insert(self.steer)
        };
        let max_rate = STEER_RATE_SW / p.steer_ratio * dt;
        self.steer = (self.steer + (want - self.steer).clamp(-max_rate, max_rate))
            .clamp(-p.steer_max, p.steer_max);
        // Drive.
        let re = v.wheels.iter().map(|w| w.re).sum::<f64>() / 4.0;
        let drive_total = match self.speed_target(t) {
            Some((vt, a_ff)) => {
                let err = vt - v.vx;
                let drag = 0.5 * p.rho_air * p.cd_a * v.vx * v.vx / p.m;
                let raw = a_ff + drag + SPEED_KP * err + SPEED_KI * self.speed_int;
                let cmd = p.m * re * raw;
                // Integrate only while not saturated (anti-windup).
                if cmd > 0.0 && cmd < p.drive_max {
                    self.speed_int += err * dt;
                }
                cmd.clamp(0.0, p.drive_max)
            }
            None => 0.0,
        };
        let (df, dr) = (
            drive_total * p.drive_share_f / 2.0,
            drive_total * (1.0 - p.drive_share_f) / 2.0,
        );
        let brake_total = self.brake_demand(t, v);
        let (bf, br) = (
            brake_total * p.brake_share_f / 2.0,
            brake_total * (1.0 - p.brake_share_f) / 2.0,
        );
        Commands {
            steer: self.steer,
            drive: [df, df, dr, dr],
            brake: [bf, bf, br, br],
        }
    }
}

/// FMVSS 126 steering-wheel angle at time τ after the start \[rad\]: A·sin(2π·f·τ) for
/// 0 ≤ τ < 3/(4f), −A for the 0.5 s dwell, then A·sin(2π·f·(τ − 0.5)) up to τ = 1/f + 0.5,
/// 0 outside; f = 0.7 Hz.
pub fn sine_with_dwell(tau: f64, a: f64) -> f64 {
    let f = 0.7;
    let dwell = 0.5;
    let t3 = 0.75 / f;
    if tau < 0.0 {
        0.0
    } else if tau < t3 {
        a * (2.0 * PI * f * tau).sin()
    } else if tau < t3 + dwell {
        -a
    } else if tau < 1.0 / f + dwell {
        a * (2.0 * PI * f * (tau - dwell)).sin()
    } else {
        0.0
    }
}
