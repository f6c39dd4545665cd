//! Helpers shared by the integration tests: seeded noise, an RK4 simulation of
//! a continuous second-order-plus-delay system driven by a continuous input,
//! percentiles.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::Complex64;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// `n` samples of N(0, σ²) from `seed`.
pub fn noise(seed: u64, sigma: f64, n: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let d = Normal::new(0.0, sigma).unwrap();
    (0..n).map(|_| d.sample(&mut rng)).collect()
}

/// The second-order system ωn²/(s² + 2ζωn s + ωn²) e^{−τs}.
#[derive(Clone, Copy)]
pub struct SecondOrder {
    pub wn: f64,
    pub zeta: f64,
    pub delay_s: f64,
}

impl SecondOrder {
    /// H(jω).
    pub fn h(&self, w: f64) -> Complex64 {
        let s = Complex64::new(0.0, w);
        let wn2 = self.wn * self.wn;
        wn2 / (s * s + 2.0 * self.zeta * self.wn * s + wn2) * (-s * self.delay_s).exp()
    }

    /// The response to the continuous input `u` (zero before 0), sampled every
    /// `dt` for `n` samples, RK4 with `sub` steps per sample (the input is
    /// evaluated at the delayed continuous time, not held).
    pub fn simulate(&self, u: &dyn Fn(f64) -> f64, dt: f64, n: usize, sub: usize) -> Vec<f64> {
        let h = dt / sub as f64;
        let wn2 = self.wn * self.wn;
        let f = |t: f64, x: [f64; 2]| {
            let ud = u(t - self.delay_s);
            [x[1], wn2 * (ud - x[0]) - 2.0 * self.zeta * self.wn * x[1]]
        };
        let mut x = [0.0; 2];
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            out.push(x[0]);
            for j in 0..sub {
                let t = i as f64 * dt + j as f64 * h;
                let k1 = f(t, x);
                let k2 = f(
                    t + h / 2.0,
                    [x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]],
                );
                let k3 = f(
                    t + h / 2.0,
                    [x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]],
                );
                let k4 = f(t + h, [x[0] + h * k3[0], x[1] + h * k3[1]]);
                for c in 0..2 {
                    x[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
                }
            }
        }
        out
    }
}

/// The p-quantile (0 … 1) of `v` (nearest rank).
pub fn percentile(v: &[f64], p: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = ((p * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}
