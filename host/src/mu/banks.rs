//! The product's estimator on a car: the core's bank (`gough::mu::bank::Bank`) at each wheel,
//! each mounted on its side, and the front-to-rear preview (`gough::mu::preview`) from each front
//! wheel to the rear wheel on its side — put together by the core's own
//! `gough::mu::preview::update`, as the device's `gough::wheel::Car` puts them together. In f64
//! or f32 (the `Libm` backend); nothing of the estimator is re-implemented here.

use super::estimator::{Estimate, Estimator, Sample, Setup};
use gough::math::{Backend, Float, Libm};
use gough::mf::Params;
use gough::mu::bank::Bank;
use gough::mu::calibration::Exported;
use gough::mu::preview::{self, Preview};
use gough::proto::Wheel;

/// The bank at the four wheels of a car, in `F`.
pub struct Banks<F: Float> {
    p: Params<F>,
    banks: [Bank<F>; 4],
    previews: Option<[Preview<F>; 2]>,
}

impl<F: Float> Banks<F>
where
    Libm: Backend<F>,
{
    /// On tyre `p` (cast to `F`), the wheels mounted as `setup.mounted` says, with its preview;
    /// an error if the tyre gives the bank no model or the preview's configuration is not valid.
    pub fn new(p: &Params<f64>, setup: &Setup) -> Result<Self, String> {
        Self::with_config(p, setup, gough::mu::Config::default())
    }

    /// [`Banks::new`] with the bank's configuration `cfg` at every wheel.
    pub fn with_config(
        p: &Params<f64>,
        setup: &Setup,
        cfg: gough::mu::Config<F>,
    ) -> Result<Self, String> {
        let p = p.cast::<F>();
        let new =
            |w: usize| Bank::new::<Libm>(&p, setup.mounted[w], cfg).map_err(|e| e.to_string());
        let banks = [new(0)?, new(1)?, new(2)?, new(3)?];
        let previews = match setup.preview {
            Some(c) => {
                let pv = Preview::new(preview::Config {
                    wheelbase: F::from_f64(c.wheelbase),
                    weight: F::from_f64(c.weight),
                })
                .map_err(|e| format!("wheelbase {}, weight {}: {e}", c.wheelbase, c.weight))?;
                Some([pv.clone(), pv])
            }
            None => None,
        };
        Ok(Banks { p, banks, previews })
    }
}

impl<F: Float> Banks<F> {
    /// Every wheel calibrates on a road of known μ ([`Bank::set_known_surface`]; `None`: the
    /// online calibration); an error for a μ the banks' grid does not hold.
    pub fn set_known_surface(&mut self, mu: Option<f64>) -> Result<(), String> {
        for b in &mut self.banks {
            if !b.set_known_surface(mu.map(F::from_f64)) {
                let top = b.grid().mu_of(gough::mu::CELLS - 1).to_f64();
                return Err(format!(
                    "μ {}: expected a finite μ in (0, {top:.3}] (the estimator's surfaces)",
                    mu.unwrap_or(f64::NAN)
                ));
            }
        }
        Ok(())
    }
}

impl<F: Float> Banks<F> {
    /// Wheel `wheel`'s excited batches on the known road and how many it explained
    /// ([`Bank::known_surface_batches`]).
    pub fn known_surface_batches(&self, wheel: Wheel) -> (u32, u32) {
        self.banks[wheel.index()].known_surface_batches()
    }
}

impl<F: Float> Estimator for Banks<F>
where
    Libm: Backend<F>,
{
    fn update(&mut self, wheel: Wheel, s: &Sample) -> Estimate {
        let c = |x: f64| F::from_f64(x);
        let s = gough::mu::Sample {
            // Wrapping microseconds: only differences are used, so an offset clock gives the
            // same estimates.
            t_us: (s.t * 1e6).round() as i64 as u32,
            fz: c(s.fz),
            fy: c(s.fy),
            mz: c(s.mz),
            fx: s.fx.map(c),
            kappa: s.kappa.map(c),
            vx: s.vx.map(c),
            gamma: s.gamma.map(c),
        };
        let w = wheel.index();
        let e =
            preview::update::<F, Libm>(self.previews.as_mut(), w, &mut self.banks[w], &self.p, &s);
        Estimate {
            mu: e.mu.to_f64(),
            sigma: e.sigma.to_f64(),
            state: e.state,
            change: e.change,
            mismatch: e.mismatch,
        }
    }

    fn calibration(&self, wheel: Wheel) -> Option<Exported> {
        Some(self.banks[wheel.index()].calibration().export::<Libm>())
    }

    fn set_calibration(&mut self, wheel: Wheel, c: &Exported) -> Result<(), String> {
        self.banks[wheel.index()]
            .import_calibration::<Libm>(c)
            .map_err(|e| e.to_string())
    }
}
