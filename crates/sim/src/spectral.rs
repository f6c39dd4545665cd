//! Spectral estimation for checking turbulence and noise models: a radix-2
//! FFT and Welch's averaged periodogram (Welch 1967; Hann window, 50 %
//! overlap, one-sided, per-segment mean removed). Analysis code, not a hot path.

use std::f64::consts::PI;

/// In-place iterative radix-2 Cooley–Tukey FFT (forward, e^{−i2πkn/N}).
/// Returns `false` (and leaves the data untouched) unless `re` and `im`
/// have the same power-of-two length.
pub fn fft(re: &mut [f64], im: &mut [f64]) -> bool {
    let n = re.len();
    if n != im.len() || !n.is_power_of_two() {
        return false;
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
        let ang = -2.0 * PI / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (s, c) = (ang * k as f64).sin_cos();
                let (a, b) = (start + k, start + k + len / 2);
                let tr = re[b] * c - im[b] * s;
                let ti = re[b] * s + im[b] * c;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
        }
        len <<= 1;
    }
    true
}

/// Welch one-sided PSD (units²/Hz) of `x` sampled every `dt` s, segments of
/// `seg` samples (a power of two), Hann window, 50 % overlap. Bin k is at
/// k/(seg·dt) Hz. Empty when `seg` is not a power of two ≥ 2 or `x` is
/// shorter than one segment.
pub fn welch_psd(x: &[f64], dt: f64, seg: usize) -> Vec<f64> {
    if seg < 2 || !seg.is_power_of_two() || x.len() < seg {
        return Vec::new();
    }
    let w: Vec<f64> = (0..seg)
        .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / seg as f64).cos())
        .collect();
    let wss: f64 = w.iter().map(|v| v * v).sum();
    let mut psd = vec![0.0; seg / 2 + 1];
    let (mut count, mut start) = (0, 0);
    let mut re = vec![0.0; seg];
    let mut im = vec![0.0; seg];
    while start + seg <= x.len() {
        let mean = x[start..start + seg].iter().sum::<f64>() / seg as f64;
        for i in 0..seg {
            re[i] = (x[start + i] - mean) * w[i];
            im[i] = 0.0;
        }
        fft(&mut re, &mut im);
        for k in 0..=seg / 2 {
            psd[k] += 2.0 * (re[k] * re[k] + im[k] * im[k]) * dt / wss;
        }
        count += 1;
        start += seg / 2;
    }
    psd.iter_mut().for_each(|p| *p /= count as f64);
    psd
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fft_matches_the_direct_dft() {
        let n = 16;
        let x: Vec<f64> = (0..n)
            .map(|i| (0.3 * i as f64).sin() + 0.1 * i as f64)
            .collect();
        let (mut re, mut im) = (x.clone(), vec![0.0; n]);
        assert!(fft(&mut re, &mut im));
        for k in 0..n {
            let (mut dr, mut di) = (0.0, 0.0);
            for (j, v) in x.iter().enumerate() {
                let a = -2.0 * PI * (k * j) as f64 / n as f64;
                dr += v * a.cos();
                di += v * a.sin();
            }
            assert!(
                (re[k] - dr).abs() < 1e-12 && (im[k] - di).abs() < 1e-12,
                "bin {k}"
            );
        }
        assert!(!fft(&mut [0.0; 3], &mut [0.0; 3]));
    }

    #[test]
    fn welch_integrates_to_the_variance() {
        // Parseval: ∫ PSD df = variance. A sinusoid of amplitude 2 has variance 2;
        // Hann leakage spreads it over neighbouring bins but keeps the integral
        // (to ~1 % with 64 segments).
        let dt = 0.01;
        let x: Vec<f64> = (0..65536)
            .map(|i| 2.0 * (2.0 * PI * 5.0 * i as f64 * dt).sin())
            .collect();
        let seg = 2048;
        let psd = welch_psd(&x, dt, seg);
        let df = 1.0 / (seg as f64 * dt);
        let var: f64 = psd.iter().sum::<f64>() * df;
        assert!((var - 2.0).abs() < 0.02, "{var}");
        assert!(welch_psd(&x, dt, 1000).is_empty());
    }
}
