//! The transient-filter bench's stream: the no-FPU bench's build script computes its f64
//! reference on the host, the bench runs the same steps on the device in f32 and Q31.32.
use crate::points::input;

/// Point `i` of the transient-filter bench's stream (one 1 ms step per point of the Magic
/// Formula grid, `input`): its kinematics (Vx, Vsx = κ·Vx, Vsy = tan α·Vx) and the relaxation
/// lengths of `mf::eval` there (0 where the evaluation fails). build.rs takes it in f64 for the
/// reference, the bench in the device's `F`.
pub fn filter_point<F: gough::math::Float, M: gough::math::Backend<F>>(
    p: &gough::mf::Params<F>,
    i: usize,
) -> (gough::relax::Kinematics<F>, gough::relax::Sigma<F>) {
    use gough::relax::{Kinematics, Sigma};
    let x = input::<F>(i);
    let opts = gough::mf::Options {
        moments: false,
        ..gough::mf::Options::default()
    };
    let sigma = gough::mf::eval::<F, M>(p, &x, &opts).map_or(Sigma::default(), |o| Sigma {
        sigma_kappa: o.sigma_x,
        sigma_alpha: o.sigma_y,
    });
    let kin = Kinematics {
        vx: x.vx,
        vsx: x.kappa * x.vx,
        vsy: M::tan(x.alpha) * x.vx,
    };
    (kin, sigma)
}
