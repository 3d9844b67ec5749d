//! A run asked for by names and numbers, as `gough sim`'s flags and Python's `gough.simulate`
//! ask for it: [`Spec`], turned into a checked [`SimConfig`] by [`Spec::config`].

use super::{AbsParams, Manoeuvre, Overrides, Road, SimConfig};

/// A run by names and numbers; `None`: the manoeuvre's default. Every error of
/// [`Spec::config`] names the `gough sim` flag of the value it refuses (an unknown manoeuvre
/// lists the known ones).
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// Manoeuvre: one of [`super::MANOEUVRES`].
    pub manoeuvre: String,
    /// Road in [`Road::parse`]'s grammar (`None`: the manoeuvre's default road, or the tyre
    /// file's own surface).
    pub road: Option<String>,
    /// Entry speed \[m/s\].
    pub speed: Option<f64>,
    /// Simulated time \[s\] (runs that end at standstill may stop earlier).
    pub duration: Option<f64>,
    /// Fixed step \[s\] (1 ms by default).
    pub dt: Option<f64>,
    /// Steering-wheel angle or amplitude \[deg\].
    pub steer_deg: Option<f64>,
    /// Circle radius \[m\].
    pub radius: Option<f64>,
    /// Deceleration demand \[m/s²\].
    pub decel: Option<f64>,
    /// The ABS on (`false`: the brake torque goes straight to the wheels, which may lock).
    pub abs: bool,
    /// Log every n-th step, n ≥ 1 (every step by default).
    pub log_every: Option<usize>,
}

impl Spec {
    /// Manoeuvre `manoeuvre` with its defaults, the ABS on.
    pub fn new(manoeuvre: impl Into<String>) -> Spec {
        Spec {
            manoeuvre: manoeuvre.into(),
            road: None,
            speed: None,
            duration: None,
            dt: None,
            steer_deg: None,
            radius: None,
            decel: None,
            abs: true,
            log_every: None,
        }
    }

    /// The simulation's configuration: every number finite, the manoeuvre's own ranges
    /// ([`Manoeuvre::by_name`]), the road parsed, `log_every` ≥ 1. The step's and the
    /// duration's ranges are checked when the run starts (`simulate`).
    pub fn config(&self) -> Result<SimConfig, String> {
        for (flag, v) in [
            ("--speed", self.speed),
            ("--duration", self.duration),
            ("--dt", self.dt),
            ("--steer", self.steer_deg),
            ("--radius", self.radius),
            ("--decel", self.decel),
        ] {
            if let Some(v) = v.filter(|v| !v.is_finite()) {
                return Err(format!("{flag} {v} is not a finite number"));
            }
        }
        let o = Overrides {
            speed: self.speed,
            steer_sw: self.steer_deg.map(f64::to_radians),
            radius: self.radius,
            decel: self.decel,
        };
        let mut cfg = SimConfig::new(Manoeuvre::by_name(&self.manoeuvre, &o)?);
        if let Some(spec) = &self.road {
            cfg.road = Road::parse(spec).map_err(|e| format!("--road: {e}"))?;
        }
        if let Some(d) = self.duration {
            cfg.duration = d;
        }
        if let Some(dt) = self.dt {
            cfg.dt = dt;
        }
        if let Some(n) = self.log_every {
            if n == 0 {
                return Err("--log-every 0: expected an integer ≥ 1".into());
            }
            cfg.log_every = n;
        }
        cfg.abs = self.abs.then(AbsParams::default);
        Ok(cfg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A spec with only its manoeuvre is the manoeuvre's own configuration; each value reaches
    /// its field; a value that is not a number, a manoeuvre the simulation does not have, a bad
    /// road or no logging are errors naming the flag.
    #[test]
    fn a_spec_is_the_configuration_it_names() {
        let plain = Spec::new("step-steer").config().unwrap();
        assert_eq!(
            plain,
            SimConfig::new(Manoeuvre::by_name("step-steer", &Overrides::default()).unwrap())
        );
        let c = Spec {
            road: Some("mu=0.8".into()),
            speed: Some(20.0),
            duration: Some(1.5),
            dt: Some(5e-4),
            steer_deg: Some(30.0),
            abs: false,
            log_every: Some(10),
            ..Spec::new("step-steer")
        }
        .config()
        .unwrap();
        assert_eq!(c.road, Road::parse("mu=0.8").unwrap());
        assert_eq!((c.duration, c.dt, c.log_every), (1.5, 5e-4, 10));
        assert_eq!(c.abs, None);
        assert_eq!(
            c.manoeuvre,
            Manoeuvre::by_name(
                "step-steer",
                &Overrides {
                    speed: Some(20.0),
                    steer_sw: Some(30f64.to_radians()),
                    ..Overrides::default()
                }
            )
            .unwrap()
        );
        for (bad, flag) in [
            (
                Spec {
                    dt: Some(f64::NAN),
                    ..Spec::new("slalom")
                },
                "--dt",
            ),
            (
                Spec {
                    speed: Some(f64::INFINITY),
                    ..Spec::new("slalom")
                },
                "--speed",
            ),
            (Spec::new("moonwalk"), "unknown manoeuvre 'moonwalk'"),
            (
                Spec {
                    road: Some("mu=abc".into()),
                    ..Spec::new("slalom")
                },
                "--road",
            ),
            (
                Spec {
                    log_every: Some(0),
                    ..Spec::new("slalom")
                },
                "--log-every",
            ),
        ] {
            let e = bad.config().unwrap_err();
            assert!(e.starts_with(flag), "{e}");
        }
    }
}
