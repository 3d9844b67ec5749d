//! The one interface of the host's friction estimators: a measured [`Sample`] of a wheel in,
//! that wheel's [`Estimate`] out ([`Estimator`]), and [`Method`], which of them.
//!
//! The product's estimator ([`Method::Bank`]: `gough::mu::bank` at every wheel with the
//! front-to-rear preview, [`super::banks::Banks`]) and the published peers it is compared with
//! ([`Method::HsuGerdes`], [`Method::SlipSlope`]: [`super::peers`]) all implement it; the bench,
//! `gough mu estimate`, `gough mu bound`, `gough mu map`, the gap diagnosis's μ part and Python's
//! `estimate_mu` run them through it. An estimator runs on a car: the samples of its wheels in
//! the order they were measured (each wheel's in time order), so that an estimator that couples
//! the wheels (the bank's preview hands what a front wheel read to the rear wheel behind it)
//! sees them as the device does; one wheel's log is wheel `FrontLeft` alone.

use gough::mf::{Params, Side};
use gough::mu::calibration::Exported;
use gough::mu::preview;
use gough::mu::State;
use gough::proto::Wheel;

/// One measured sample of a wheel, SI, ISO-W at the contact point, in the wheel's own axes
/// (the estimator mirrors the tyre for the side it is mounted on, [`Setup::mounted`]). `None`:
/// not measured. What each estimator reads of it is its own: the bank never reads `alpha`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// Time \[s\]; only differences are used (each wheel's strictly increasing).
    pub t: f64,
    /// Vertical load Fz \[N\].
    pub fz: f64,
    /// Lateral force Fy \[N\].
    pub fy: f64,
    /// Aligning torque Mz \[N·m\].
    pub mz: f64,
    /// Longitudinal force Fx \[N\].
    pub fx: Option<f64>,
    /// Forward speed Vx \[m/s\].
    pub vx: Option<f64>,
    /// Longitudinal slip κ \[-\].
    pub kappa: Option<f64>,
    /// Slip angle α \[rad\] (a slip sensor's; the peers' premise).
    pub alpha: Option<f64>,
    /// Inclination γ \[rad\].
    pub gamma: Option<f64>,
}

/// What an estimator reports after a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// μ \[-\] on the tyre file's scale (a road of friction μ scales the tyre by λμx = λμy =
    /// μ/μy0); the prior in [`State::Fallback`].
    pub mu: f64,
    /// Standard deviation of μ \[-\] by the estimator's own account.
    pub sigma: f64,
    /// What the estimate rests on (the core's three states, for every method).
    pub state: State,
    /// A change of surface was declared at this sample.
    pub change: bool,
    /// The estimator says its model does not explain the data (the bank's
    /// `gough::mu::Estimate::mismatch`; never set by the peers).
    pub mismatch: bool,
}

/// A friction estimator on a car's samples.
pub trait Estimator {
    /// Takes the next sample of wheel `wheel` (the wheels' samples interleaved as measured,
    /// each wheel's in time order); returns that wheel's estimate.
    fn update(&mut self, wheel: Wheel, s: &Sample) -> Estimate;

    /// Wheel `wheel`'s calibration of the tyre (`gough::mu::calibration`), if the method
    /// calibrates (the bank; the peers do not).
    fn calibration(&self, _wheel: Wheel) -> Option<Exported> {
        None
    }

    /// Wheel `wheel`'s estimator starts from calibration `c` (a warm start); an error saying
    /// why when it refuses it (the core's check) or the method does not calibrate.
    fn set_calibration(&mut self, _wheel: Wheel, _c: &Exported) -> Result<(), String> {
        Err("this method keeps no calibration of the tyre".into())
    }

    /// Runs over a log of `(wheel, sample)` pairs in order: an estimate per pair.
    fn run(&mut self, log: &[(Wheel, Sample)]) -> Vec<Estimate> {
        log.iter().map(|(w, s)| self.update(*w, s)).collect()
    }
}

/// Which estimator. The bench lists them in this order, the product last.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Hsu, Laws & Gerdes (2010): the pneumatic trail with the slip angle ([`super::peers::HsuGerdes`]).
    HsuGerdes,
    /// Gustafsson (1997): the longitudinal slip slope ([`super::peers::SlipSlope`]).
    SlipSlope,
    /// The product's estimator: the exact-model bank of the core (`gough::mu::bank`) at every
    /// wheel, with the front-to-rear preview when the setup asks for it; reads Fy, Mz, Fz, Fx,
    /// κ, Vx, γ — never α ([`super::banks::Banks`]).
    Bank,
}

impl Method {
    /// Every method, in the bench's order.
    pub const ALL: [Method; 3] = [Method::HsuGerdes, Method::SlipSlope, Method::Bank];

    /// Its name on the command line, in Python and in the bench's tables.
    pub const fn name(self) -> &'static str {
        match self {
            Method::HsuGerdes => "hsu-gerdes",
            Method::SlipSlope => "slip-slope",
            Method::Bank => "bank",
        }
    }

    /// The method named `name` (as [`Method::name`] spells it); the error lists the names.
    pub fn from_name(name: &str) -> Result<Method, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
                format!("method '{name}': expected {}", names.join(", "))
            })
    }

    /// One line of what it is (`gough mu estimate --help`).
    pub const fn about(self) -> &'static str {
        match self {
            Method::HsuGerdes => "Hsu, Laws & Gerdes (2010): pneumatic trail with the slip angle",
            Method::SlipSlope => "Gustafsson (1997): longitudinal slip slope",
            Method::Bank => {
                "the exact-model bank of the core (gough::mu::bank; Fy, Mz, Fz, Fx, κ, Vx, γ — never α): the product's estimator"
            }
        }
    }

    /// Whether the method needs a slip sensor (α, κ measured directly, as an optical sensor
    /// does): the peers' premise. The bench gives such a method the exact (delayed) slips,
    /// the bank the κ an ABS controller has (from wheel speed, with noise).
    pub const fn slip_sensor(self) -> bool {
        !matches!(self, Method::Bank)
    }

    /// Whether the method couples the wheels (reads a car's log as a car). The peers are
    /// per-wheel estimators and read one wheel's log.
    pub const fn couples_wheels(self) -> bool {
        matches!(self, Method::Bank)
    }

    /// The estimator of this method on tyre `p`, set up by `setup`; an error if the tyre gives
    /// it no model (a peer's calibration, the bank's μy0) or the setup is not valid.
    pub fn estimator(self, p: &Params<f64>, setup: &Setup) -> Result<Box<dyn Estimator>, String> {
        match self {
            Method::HsuGerdes => {
                let e =
                    super::peers::HsuGerdes::new(p).ok_or("the tyre gives no Hsu-Gerdes model")?;
                Ok(Box::new(super::peers::EachWheel::new(e)))
            }
            Method::SlipSlope => {
                let e = super::peers::SlipSlope::new(p)
                    .ok_or("the tyre gives no slip-slope calibration")?;
                Ok(Box::new(super::peers::EachWheel::new(e)))
            }
            Method::Bank => match setup.precision {
                Precision::F64 => Ok(Box::new(super::banks::Banks::<f64>::new(p, setup)?)),
                Precision::F32 => Ok(Box::new(super::banks::Banks::<f32>::new(p, setup)?)),
            },
        }
    }
}

impl clap::ValueEnum for Method {
    fn value_variants<'a>() -> &'a [Self] {
        &Method::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.about()))
    }
}

/// Float path of the bank (the peers run in f64).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Precision {
    /// f64 (host).
    F64,
    /// f32 (the device's).
    F32,
}

/// How an estimator is set up on a car (what the bank uses of it; the peers take the signals
/// as they are).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// Float path of the bank.
    pub precision: Precision,
    /// The side the tyre is mounted on at wheels FL, FR, RL, RR (`None`: as the file describes
    /// it; [`mounting`]).
    pub mounted: [Option<Side>; 4],
    /// The front-to-rear preview (`None`: every wheel alone).
    pub preview: Option<preview::Config<f64>>,
}

impl Setup {
    /// A car: each wheel on its side (`gough::proto::Wheel::side`, as `gough::wheel::Car` on the
    /// device), f64, with `preview`.
    pub fn car(preview: Option<preview::Config<f64>>) -> Setup {
        Setup {
            precision: Precision::F64,
            mounted: Wheel::ALL.map(|w| Some(w.side())),
            preview,
        }
    }

    /// One wheel on `side` (`None`: as the file describes the tyre), f64, no preview.
    pub fn one_wheel(side: Option<Side>) -> Setup {
        Setup {
            precision: Precision::F64,
            mounted: [side; 4],
            preview: None,
        }
    }
}

/// How the tyre is mounted on the wheels of a log whose rows are of `wheels`: a car's log (a
/// wheel other than FL) each wheel on its side (`gough::proto::Wheel::side`, as
/// `gough::wheel::Car` on the device), one wheel's log on `side` (`None`: as the file
/// describes the tyre).
pub fn mounting(wheels: &[Wheel], side: Option<Side>) -> [Option<Side>; 4] {
    if wheels.iter().any(|&w| w != Wheel::FrontLeft) {
        Wheel::ALL.map(|w| Some(w.side()))
    } else {
        [side; 4]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The command line, Python and the bench spell the methods one way: the clap values are
    /// [`Method::name`]s, and every name reads back; another name is an error listing them.
    #[test]
    fn a_method_has_one_name() {
        use clap::ValueEnum;
        for m in Method::ALL {
            let v = m.to_possible_value().unwrap();
            assert_eq!(v.get_name(), m.name());
            assert_eq!(Method::from_name(m.name()), Ok(m));
            assert_eq!(Method::from_str(m.name(), false), Ok(m));
        }
        let e = Method::from_name("gough").unwrap_err();
        assert_eq!(e, "method 'gough': expected hsu-gerdes, slip-slope, bank");
        assert_eq!(Method::ALL.last(), Some(&Method::Bank));
    }
}
