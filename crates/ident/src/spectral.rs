//! Welch's averaged periodogram (Welch 1967; periodic Hann window, 50 %
//! overlap, one-sided, per-segment mean removed) for checking turbulence and
//! noise models, on the FFT of [`rustfft`]. The cross spectra of several
//! channels on any frequency grid are in [`crate::frf`].

use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

/// The periodic Hann window of `n` samples (SciPy's `get_window("hann", n)`):
/// `w[i] = 0.5 − 0.5 cos(2π i / n)`.
pub fn hann(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos())
        .collect()
}

/// Forward DFT (e^{−i2πkn/N}) of `x` in place, any length.
pub fn fft(x: &mut [Complex64]) {
    if x.is_empty() {
        return;
    }
    FftPlanner::new().plan_fft_forward(x.len()).process(x);
}

/// Welch one-sided PSD (units²/Hz) of `x` sampled every `dt` s, segments of
/// `seg` samples, periodic Hann window, 50 % overlap (`seg / 2` samples). Bin
/// k is at k/(seg·dt) Hz, k = 0 … seg/2. Empty when `seg < 2` or `x` is
/// shorter than one segment.
pub fn welch_psd(x: &[f64], dt: f64, seg: usize) -> Vec<f64> {
    if seg < 2 || x.len() < seg {
        return Vec::new();
    }
    let w = hann(seg);
    let wss: f64 = w.iter().map(|v| v * v).sum();
    let plan = FftPlanner::new().plan_fft_forward(seg);
    let mut psd = vec![0.0; seg / 2 + 1];
    let (mut count, mut start) = (0, 0);
    let mut buf = vec![Complex64::new(0.0, 0.0); seg];
    while start + seg <= x.len() {
        let mean = x[start..start + seg].iter().sum::<f64>() / seg as f64;
        for i in 0..seg {
            buf[i] = Complex64::new((x[start + i] - mean) * w[i], 0.0);
        }
        plan.process(&mut buf);
        for (k, p) in psd.iter_mut().enumerate() {
            // One-sided: DC and (even seg) Nyquist are not doubled.
            let one_sided = if k == 0 || 2 * k == seg { 1.0 } else { 2.0 };
            *p += one_sided * buf[k].norm_sqr() * dt / wss;
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
        for n in [16usize, 15] {
            let x: Vec<f64> = (0..n)
                .map(|i| (0.3 * i as f64).sin() + 0.1 * i as f64)
                .collect();
            let mut c: Vec<Complex64> = x.iter().map(|v| Complex64::new(*v, 0.0)).collect();
            fft(&mut c);
            for k in 0..n {
                let (mut dr, mut di) = (0.0, 0.0);
                for (j, v) in x.iter().enumerate() {
                    let a = -2.0 * PI * (k * j) as f64 / n as f64;
                    dr += v * a.cos();
                    di += v * a.sin();
                }
                assert!(
                    (c[k].re - dr).abs() < 1e-12 && (c[k].im - di).abs() < 1e-12,
                    "n {n} bin {k}"
                );
            }
        }
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
        assert!(welch_psd(&x[..10], dt, 1000).is_empty());
    }
}
