//! Bounded nonlinear least squares: Levenberg–Marquardt with box constraints by projection.
//!
//! minimise ½·Σ r_k(θ)² subject to lo ≤ θ ≤ hi. The Jacobian is taken by forward differences
//! (step 1e-4 of each parameter's scale, turned inward at a bound); the damped normal equations
//! (JᵀJ + λ·diag(JᵀJ) + ridge)·δ = −Jᵀr are solved by Gaussian elimination with partial pivoting
//! (at most a handful of parameters), and θ + δ is projected onto the box. A parameter the data
//! do not touch (a zero column of J) gets a zero step from the ridge: it stays where it started,
//! which is the sim's own value. The cost function may refuse a point (`None`: the model failed
//! there); that counts as an infinitely bad step. Every loop has a constant bound.

/// The result of a fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// Parameters at the best point found.
    pub theta: Vec<f64>,
    /// ½·Σ r² there.
    pub cost: f64,
    /// Jacobians evaluated.
    pub iterations: usize,
}

/// Bounds and scales of a fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Bounds {
    /// Lower bounds.
    pub lo: Vec<f64>,
    /// Upper bounds.
    pub hi: Vec<f64>,
    /// Typical magnitude of each parameter (sets the difference step).
    pub scale: Vec<f64>,
}

fn cost_of(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|v| v * v).sum::<f64>()
}

/// Solves `a·x = b` (n×n, row-major) by Gaussian elimination with partial pivoting; `None` if
/// singular.
pub fn solve(mut a: Vec<f64>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    if a.len() != n * n {
        return None;
    }
    for col in 0..n {
        let piv =
            (col..n).max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))?;
        if a[piv * n + col].abs() < 1e-300 {
            return None;
        }
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        for i in col + 1..n {
            let f = a[i * n + col] / a[col * n + col];
            if f != 0.0 {
                for k in col..n {
                    a[i * n + k] -= f * a[col * n + k];
                }
                b[i] -= f * b[col];
            }
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| a[i * n + k] * x[k]).sum();
        x[i] = (b[i] - s) / a[i * n + i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Levenberg–Marquardt from `start` within `bounds`, at most `max_iter` Jacobians.
/// `None` when the residuals cannot be evaluated at the (projected) start.
pub fn levenberg_marquardt<F>(
    mut resid: F,
    start: &[f64],
    bounds: &Bounds,
    max_iter: usize,
) -> Option<Fit>
where
    F: FnMut(&[f64]) -> Option<Vec<f64>>,
{
    let p = start.len();
    let clamp = |th: &mut [f64]| {
        for ((x, lo), hi) in th.iter_mut().zip(&bounds.lo).zip(&bounds.hi) {
            *x = x.clamp(*lo, *hi);
        }
    };
    let mut theta = start.to_vec();
    clamp(&mut theta);
    let mut r = resid(&theta)?;
    let mut cost = cost_of(&r);
    let m = r.len();
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < max_iter {
        iterations += 1;
        // Forward-difference Jacobian, column by column.
        let mut jac = vec![0.0; m * p];
        for j in 0..p {
            let mut h = 1e-4 * bounds.scale[j].abs().max(1e-12);
            if theta[j] + h > bounds.hi[j] {
                h = -h;
            }
            let mut th = theta.clone();
            th[j] += h;
            let h = th[j] - theta[j];
            if h == 0.0 {
                continue;
            }
            match resid(&th) {
                Some(rj) if rj.len() == m => {
                    for k in 0..m {
                        jac[k * p + j] = (rj[k] - r[k]) / h;
                    }
                }
                _ => {}
            }
        }
        let mut a = vec![0.0; p * p];
        let mut g = vec![0.0; p];
        for k in 0..m {
            let row = &jac[k * p..(k + 1) * p];
            for i in 0..p {
                g[i] += row[i] * r[k];
                for j in 0..p {
                    a[i * p + j] += row[i] * row[j];
                }
            }
        }
        let dmax = (0..p).map(|i| a[i * p + i]).fold(0.0, f64::max);
        if dmax == 0.0 {
            break; // the data do not depend on any parameter
        }
        let mut improved = false;
        for attempt in 0..8 {
            let mut aa = a.clone();
            for i in 0..p {
                aa[i * p + i] += lambda * a[i * p + i] + 1e-12 * dmax;
            }
            let Some(delta) = solve(aa, g.iter().map(|v| -v).collect()) else {
                lambda *= 10.0;
                continue;
            };
            let mut th = theta.clone();
            for j in 0..p {
                th[j] += delta[j];
            }
            clamp(&mut th);
            // The Gauss-Newton model's predicted decrease of the projected step: when it is a
            // negligible part of the cost, the fit has converged (no evaluation spent on it).
            let d: Vec<f64> = (0..p).map(|j| th[j] - theta[j]).collect();
            let ad: f64 = (0..p)
                .map(|i| d[i] * (0..p).map(|j| a[i * p + j] * d[j]).sum::<f64>())
                .sum();
            let predicted = -(0..p).map(|j| g[j] * d[j]).sum::<f64>() - 0.5 * ad;
            if attempt == 0 && predicted <= 1e-9 * cost {
                break;
            }
            let step: f64 = (0..p)
                .map(|j| ((th[j] - theta[j]) / bounds.scale[j].abs().max(1e-12)).powi(2))
                .sum::<f64>()
                .sqrt();
            if step < 1e-10 {
                break;
            }
            match resid(&th) {
                Some(rn) if rn.len() == m && cost_of(&rn) < cost => {
                    let c = cost_of(&rn);
                    let rel = (cost - c) / cost.max(1e-300);
                    theta = th;
                    r = rn;
                    cost = c;
                    lambda = (lambda / 3.0).max(1e-9);
                    improved = rel > 1e-9 && step > 1e-8;
                    break;
                }
                _ => lambda *= 4.0,
            }
        }
        if !improved {
            break;
        }
    }
    Some(Fit {
        theta,
        cost,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_an_exponential_and_respects_bounds() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|&t| 2.0 * (-0.7 * t).exp()).collect();
        let b = Bounds {
            lo: vec![0.0, 0.0],
            hi: vec![10.0, 5.0],
            scale: vec![1.0, 1.0],
        };
        let f = levenberg_marquardt(
            |th| {
                Some(
                    t.iter()
                        .zip(&y)
                        .map(|(&t, &y)| th[0] * (-th[1] * t).exp() - y)
                        .collect(),
                )
            },
            &[1.0, 0.1],
            &b,
            50,
        )
        .unwrap();
        assert!(
            (f.theta[0] - 2.0).abs() < 1e-6 && (f.theta[1] - 0.7).abs() < 1e-6,
            "{f:?}"
        );
        let b2 = Bounds {
            hi: vec![1.5, 5.0],
            ..b
        };
        let f = levenberg_marquardt(
            |th| {
                Some(
                    t.iter()
                        .zip(&y)
                        .map(|(&t, &y)| th[0] * (-th[1] * t).exp() - y)
                        .collect(),
                )
            },
            &[1.0, 0.1],
            &b2,
            50,
        )
        .unwrap();
        assert!(
            f.theta[0] <= 1.5 && (f.theta[0] - 1.5).abs() < 1e-9,
            "{f:?}"
        );
    }

    #[test]
    fn an_untouched_parameter_stays_put() {
        let b = Bounds {
            lo: vec![-5.0, -5.0],
            hi: vec![5.0, 5.0],
            scale: vec![1.0, 1.0],
        };
        let f = levenberg_marquardt(
            |th| Some(vec![th[0] - 3.0, th[0] - 3.0]),
            &[0.0, 0.25],
            &b,
            20,
        )
        .unwrap();
        assert!(
            (f.theta[0] - 3.0).abs() < 1e-6 && f.theta[1] == 0.25,
            "{f:?}"
        );
    }
}
