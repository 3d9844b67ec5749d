//! Small statistics of the diagnosis: RMSE, robust scale, the noise floor, a radix-2 FFT.

/// Root mean square of `x` (0 for an empty slice).
pub fn rms(x: impl IntoIterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for v in x {
        s += v * v;
        n += 1;
    }
    if n == 0 {
        0.0
    } else {
        (s / n as f64).sqrt()
    }
}

/// Mean (0 for an empty slice).
pub fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        0.0
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    }
}

/// Sample standard deviation (0 for fewer than two values).
pub fn sd(x: &[f64]) -> f64 {
    if x.len() < 2 {
        return 0.0;
    }
    let m = mean(x);
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

/// Median (NaN-free input; 0 for an empty slice).
pub fn median(x: &[f64]) -> f64 {
    quantile(x, 0.5)
}

/// The q-quantile by linear interpolation between order statistics (0 for an empty slice).
pub fn quantile(x: &[f64], q: f64) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    v[lo] + (pos - lo as f64) * (v[hi] - v[lo])
}

/// Noise floor of a residual \[its unit\]: the standard deviation of its white (sample-to-sample
/// independent) part, from the second differences d_i = r_{i+1} − 2·r_i + r_{i−1}. For white
/// noise of variance σ², var(d) = 6σ²; a gap that is smooth on the scale of a sample (the model's
/// errors follow the slowly varying inputs) hardly enters d. The scale of d is taken robustly,
/// 1.4826·MAD (a normal's σ), so a few spikes do not raise the floor: σ = 1.4826·MAD(d)/√6.
pub fn noise_floor(r: &[f64]) -> f64 {
    if r.len() < 3 {
        return 0.0;
    }
    let d: Vec<f64> = r.windows(3).map(|w| w[2] - 2.0 * w[1] + w[0]).collect();
    let m = median(&d);
    let dev: Vec<f64> = d.iter().map(|v| (v - m).abs()).collect();
    1.4826 * median(&dev) / 6f64.sqrt()
}

/// In-place radix-2 complex FFT (`re`, `im` of length a power of two).
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    if n < 2 || !n.is_power_of_two() || im.len() != n {
        return;
    }
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let ang = -2.0 * std::f64::consts::PI / len as f64;
        let (wr, wi) = (ang.cos(), ang.sin());
        for start in (0..n).step_by(len) {
            let (mut cr, mut ci) = (1.0, 0.0);
            for k in 0..len / 2 {
                let (a, b) = (start + k, start + k + len / 2);
                let tr = re[b] * cr - im[b] * ci;
                let ti = re[b] * ci + im[b] * cr;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
                let nr = cr * wr - ci * wi;
                ci = cr * wi + ci * wr;
                cr = nr;
            }
        }
        len <<= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn noise_floor_of_white_noise_ignores_a_smooth_signal() {
        let mut rng = Rng::new(7);
        let r: Vec<f64> = (0..20000)
            .map(|i| 3.0 * rng.normal() + 500.0 * (i as f64 * 0.002).sin())
            .collect();
        let s = noise_floor(&r);
        assert!((s - 3.0).abs() < 0.15, "{s}");
    }

    #[test]
    fn fft_matches_parseval_and_a_pure_tone() {
        let n = 64;
        let mut re: Vec<f64> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * 5.0 * i as f64 / n as f64).cos())
            .collect();
        let mut im = vec![0.0; n];
        let e_t: f64 = re.iter().map(|v| v * v).sum();
        fft(&mut re, &mut im);
        let e_f: f64 = re.iter().zip(&im).map(|(a, b)| a * a + b * b).sum::<f64>() / n as f64;
        assert!((e_t - e_f).abs() < 1e-9);
        assert!((re[5] - n as f64 / 2.0).abs() < 1e-9 && (re[n - 5] - n as f64 / 2.0).abs() < 1e-9);
    }
}
