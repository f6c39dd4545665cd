//! Inflow ratios of the main and tail rotors, thesis (7.29)–(7.33),
//! (7.53)–(7.56), (B.18), (B.28).
//!
//! Momentum theory links the inflow ratio λ to the thrust coefficient:
//! g(λ) = λ − μ_axial + C_T(λ) / (2 √(μ_inplane² + λ²)) = 0, (7.33)/(7.56),
//! where for the main rotor μ_axial = μz and μ_inplane² = μx² + μy², and for
//! the tail rotor μ_axial = μy,tr and μ_inplane² = μx,tr² + μz,tr².
//! Because the blade-element thrust is affine in λ (the perpendicular blade
//! velocity Up is), C_T(λ) = C_T0 + C_T1·λ (MODEL.md §8), and the problem is a
//! scalar root.
//!
//! The solver [`InflowProblem::solve`] cannot diverge: Newton steps on g with
//! the full derivative are accepted only while they stay inside a bracket of
//! h(λ) = 2s(λ)(λ − μ_axial) + C_T(λ) (same sign as g wherever s > 0, and
//! continuous everywhere, even at λ = 0 in pure hover where g has a pole);
//! otherwise it bisects. A bracket always exists because h(±M) = ±∞-like for
//! M = |μ_axial| + C_T1/2 + |C_T0| + 1 (|C_T/(2s)| ≤ |C_T0|/(2M) + C_T1/2 there).

/// Convergence tolerance on |g(λ)| of the Newton fast path: 1e-13, ten times
/// tighter than the 1e-12 the solver guarantees (the bracketed fallback
/// accepts 1e-12). Newton also stops only when |Δλ| ≤ 1e-15·(1 + |λ|).
pub const G_TOL: f64 = 1e-13;

/// Errors of the inflow solver.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum InflowError {
    /// The inputs are not finite (NaN or infinite state or command).
    #[error(
        "inflow: non-finite input (mu_inplane2={mu_inplane2}, mu_axial={mu_axial}, ct0={ct0}, ct1={ct1})"
    )]
    NonFinite {
        /// μ_inplane².
        mu_inplane2: f64,
        /// μ_axial.
        mu_axial: f64,
        /// C_T0.
        ct0: f64,
        /// C_T1.
        ct1: f64,
    },
    /// No convergence within the iteration budget (should not happen: the
    /// bisection fallback halves the bracket every step).
    #[error("inflow: no convergence after {iterations} iterations (|g| = {residual:e})")]
    NoConvergence {
        /// Iterations used.
        iterations: u32,
        /// Final |g|.
        residual: f64,
    },
}

/// One inflow equation: momentum theory with an affine thrust coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InflowProblem {
    /// μ_inplane² (μx² + μy² for the main rotor, μx,tr² + μz,tr² for the tail rotor).
    pub mu_inplane2: f64,
    /// μ_axial (μz for the main rotor, μy,tr for the tail rotor), positive
    /// when the air comes through the disc from the thrust side.
    pub mu_axial: f64,
    /// C_T at λ = 0.
    pub ct0: f64,
    /// dC_T/dλ.
    pub ct1: f64,
}

/// A converged inflow ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InflowSolution {
    /// λ.
    pub lambda: f64,
    /// |g(λ)| at the solution.
    pub residual: f64,
    /// Iterations used (Newton or bisection steps).
    pub iterations: u32,
}

impl InflowProblem {
    /// C_T(λ) = C_T0 + C_T1 λ.
    #[inline]
    pub fn ct(&self, lambda: f64) -> f64 {
        self.ct0 + self.ct1 * lambda
    }

    /// g(λ) of (7.33)/(7.56).
    #[inline]
    pub fn g(&self, lambda: f64) -> f64 {
        let s = (self.mu_inplane2 + lambda * lambda).sqrt();
        lambda - self.mu_axial + self.ct(lambda) / (2.0 * s)
    }

    /// The residual reported for a solution: |g(λ)|, or |h(λ)| where
    /// s = √(μ² + λ²) < 1e-9 (pure axial flow at zero thrust, where g jumps
    /// across λ = 0 and the continuous h has its root at λ = 0: C_T = 0, no
    /// induced velocity).
    pub fn residual(&self, lambda: f64) -> f64 {
        let s = (self.mu_inplane2 + lambda * lambda).sqrt();
        if s < 1e-9 {
            self.h(lambda).abs()
        } else {
            self.g(lambda).abs()
        }
    }

    /// h(λ) = 2s(λ − μ_axial) + C_T(λ): continuous, same sign as g where s > 0.
    #[inline]
    fn h(&self, lambda: f64) -> f64 {
        let s = (self.mu_inplane2 + lambda * lambda).sqrt();
        2.0 * s * (lambda - self.mu_axial) + self.ct(lambda)
    }

    /// Hover-like start value: the root of 2λ|λ| ... shifted by μ_axial
    /// (MODEL.md §8): for C_T ≥ 0 the negative root of 2λ² − C_T1 λ − C_T0 = 0,
    /// mirrored otherwise.
    fn start(&self) -> f64 {
        let (a, b) = (self.ct1, self.ct0);
        let disc = (a * a + 8.0 * b.abs()).sqrt();
        let l0 = if b >= 0.0 {
            (a - disc) / 4.0
        } else {
            (-a + disc) / 4.0
        };
        let l0 = if l0 == 0.0 { -1e-3 } else { l0 };
        l0 + self.mu_axial
    }

    /// Solve g(λ) = 0 to |g| < [`G_TOL`] (and |Δλ| ≤ 1e-15 in Newton),
    /// safeguarded by a bracket (module docs). Never returns NaN.
    pub fn solve(&self) -> Result<InflowSolution, InflowError> {
        self.solve_from(None)
    }

    /// As [`InflowProblem::solve`], with Newton started from `hint` (e.g. the
    /// previous time step's λ) when it is finite and on the same side of
    /// λ = 0 as the hover-like start; the converged root is the same, only
    /// the iteration count drops. The bracketed fallback is unchanged.
    pub fn solve_from(&self, hint: Option<f64>) -> Result<InflowSolution, InflowError> {
        if !(self.mu_inplane2.is_finite()
            && self.mu_axial.is_finite()
            && self.ct0.is_finite()
            && self.ct1.is_finite())
        {
            return Err(InflowError::NonFinite {
                mu_inplane2: self.mu_inplane2,
                mu_axial: self.mu_axial,
                ct0: self.ct0,
                ct1: self.ct1,
            });
        }
        let start = self.start();
        let mut lam = match hint {
            Some(h) if h.is_finite() && h * start > 0.0 => h,
            _ => start,
        };
        // Fast path: Newton from the start value (typically 3-5 steps; 1-2 warm).
        let mut iterations = 0u32;
        for _ in 0..12 {
            iterations += 1;
            let s2 = self.mu_inplane2 + lam * lam;
            let s = s2.sqrt();
            let ct = self.ct(lam);
            let g = lam - self.mu_axial + ct / (2.0 * s);
            let dg = 1.0 + self.ct1 / (2.0 * s) - ct * lam / (2.0 * s2 * s);
            if !(dg.is_finite() && dg > 0.0) {
                break;
            }
            let step = g / dg;
            let next = lam - step;
            // Do not let a step jump across λ = 0 when the in-plane speed is tiny
            // (the pole of g in pure axial flow).
            if next * lam < 0.0 && self.mu_inplane2 < 1e-6 {
                break;
            }
            lam = next;
            if step.abs() <= 1e-15 * (1.0 + lam.abs()) {
                let r = self.g(lam).abs();
                if r < G_TOL {
                    return Ok(InflowSolution {
                        lambda: lam,
                        residual: r,
                        iterations,
                    });
                }
            }
        }
        self.solve_bracketed(iterations)
    }

    /// Bracketed fallback: find the sign change of h nearest to the start
    /// value, then safeguarded Newton/bisection on it.
    fn solve_bracketed(&self, used: u32) -> Result<InflowSolution, InflowError> {
        let m = self.mu_axial.abs() + 0.5 * self.ct1.abs() + self.ct0.abs() + 1.0;
        let l0 = self.start().clamp(-m, m);
        // Expand geometrically around the start value until h changes sign.
        let h0 = self.h(l0);
        let (mut lo, mut hi);
        let mut width = 1e-3;
        loop {
            let a = (l0 - width).max(-m);
            let b = (l0 + width).min(m);
            let (ha, hb) = (self.h(a), self.h(b));
            if ha <= 0.0 && h0 >= 0.0 {
                lo = a;
                hi = l0;
                break;
            }
            if h0 <= 0.0 && hb >= 0.0 {
                lo = l0;
                hi = b;
                break;
            }
            if ha <= 0.0 && hb >= 0.0 {
                lo = a;
                hi = b;
                break;
            }
            if a <= -m && b >= m {
                // h(−M) < 0 < h(M) by construction; reaching here means non-finite.
                return Err(InflowError::NoConvergence {
                    iterations: used,
                    residual: f64::NAN,
                });
            }
            width *= 2.0;
        }
        // Safeguarded Newton (rtsafe) on g within [lo, hi] where h(lo) ≤ 0 ≤ h(hi).
        let mut lam = 0.5 * (lo + hi);
        let mut iterations = used;
        for _ in 0..200 {
            iterations += 1;
            let hv = self.h(lam);
            if hv < 0.0 {
                lo = lam;
            } else {
                hi = lam;
            }
            let s2 = self.mu_inplane2 + lam * lam;
            let s = s2.sqrt();
            let ct = self.ct(lam);
            let g = lam - self.mu_axial + ct / (2.0 * s);
            let r = self.residual(lam);
            if r < G_TOL {
                return Ok(InflowSolution {
                    lambda: lam,
                    residual: r,
                    iterations,
                });
            }
            let dg = 1.0 + self.ct1 / (2.0 * s) - ct * lam / (2.0 * s2 * s);
            let newton = lam - g / dg;
            let next = if dg.is_finite() && dg > 0.0 && newton > lo && newton < hi && s > 0.0 {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if (next - lam).abs() <= 1e-16 * (1.0 + lam.abs())
                || hi - lo <= 1e-16 * (1.0 + lam.abs())
            {
                let r = self.residual(next);
                return if r < 1e-12 && r.is_finite() {
                    Ok(InflowSolution {
                        lambda: next,
                        residual: r,
                        iterations,
                    })
                } else {
                    Err(InflowError::NoConvergence {
                        iterations,
                        residual: r,
                    })
                };
            }
            lam = next;
        }
        Err(InflowError::NoConvergence {
            iterations,
            residual: self.g(lam).abs(),
        })
    }

    /// The thesis implementation's iteration (7.33)/(D.32), (7.56)/(D.41):
    /// `n` plain Newton–Raphson steps from `lambda_in`, with C_T re-evaluated
    /// at each iterate and treated as a constant in the derivative
    /// f′ = 1 − C_T λ / (2(μ² + λ²)^{3/2}), as printed (MODEL.md §8).
    pub fn thesis_iterate(&self, lambda_in: f64, n: u32) -> f64 {
        let mut lam = lambda_in;
        for _ in 0..n {
            let s2 = self.mu_inplane2 + lam * lam;
            let s = s2.sqrt();
            let ct = self.ct(lam);
            let f = lam - self.mu_axial + ct / (2.0 * s);
            let df = 1.0 - ct * lam / (2.0 * s2 * s);
            lam -= f / df;
        }
        lam
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn pure_hover_matches_momentum_closed_form() {
        // μ = 0: λ = −√(C_T/2) with C_T = C_T0 + C_T1 λ → 2λ² = C_T0 + C_T1 λ.
        let p = InflowProblem {
            mu_inplane2: 0.0,
            mu_axial: 0.0,
            ct0: 0.0031,
            ct1: 0.0137,
        };
        let sol = p.solve().unwrap();
        let exact = (p.ct1 - (p.ct1 * p.ct1 + 8.0 * p.ct0).sqrt()) / 4.0;
        assert!(
            (sol.lambda - exact).abs() <= 1e-12 * exact.abs(),
            "{} vs {exact}",
            sol.lambda
        );
        assert!(sol.residual < 1e-12);
    }

    #[test]
    fn climb_matches_momentum_closed_form() {
        // Constant C_T (C_T1 = 0), axial climb μz < 0: λ = μz/2 − √((μz/2)² + C_T/2).
        let p = InflowProblem {
            mu_inplane2: 0.0,
            mu_axial: -0.03,
            ct0: 0.004,
            ct1: 0.0,
        };
        let exact = -0.015 - (0.015f64.powi(2) + 0.002).sqrt();
        assert!((p.solve().unwrap().lambda - exact).abs() < 1e-14);
    }

    #[test]
    fn thesis_iteration_fixed_point_is_the_root() {
        let p = InflowProblem {
            mu_inplane2: 0.0025,
            mu_axial: 0.001,
            ct0: 0.003,
            ct1: 0.012,
        };
        let sol = p.solve().unwrap();
        assert!((p.thesis_iterate(sol.lambda, 7) - sol.lambda).abs() < 1e-15);
        // From a perturbed start the plain iteration does not reach the root in 7 steps
        // exactly, but moves towards it.
        let it = p.thesis_iterate(sol.lambda + 1e-3, 7);
        assert!((it - sol.lambda).abs() < 1e-3);
    }

    #[test]
    fn zero_thrust_in_pure_axial_flow_gives_zero_inflow() {
        // All-zero state: C_T0 = 0, μ = 0 → g jumps at λ = 0; the root of the
        // continuous h is λ = 0 (no thrust, no induced velocity).
        let p = InflowProblem {
            mu_inplane2: 0.0,
            mu_axial: 0.0,
            ct0: 0.0,
            ct1: 0.0137,
        };
        let sol = p.solve().unwrap();
        // |h| < 1e-13 with h ≈ C_T1·λ: |λ| < 1e-11 (vi < 1e-9 m/s).
        assert!(sol.lambda.abs() < 1e-10, "{}", sol.lambda);
    }

    #[test]
    fn non_finite_is_an_error_not_nan() {
        let p = InflowProblem {
            mu_inplane2: f64::NAN,
            mu_axial: 0.0,
            ct0: 0.003,
            ct1: 0.01,
        };
        assert!(matches!(p.solve(), Err(InflowError::NonFinite { .. })));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]
        #[test]
        fn always_converges(mu_x in -0.3f64..0.3, mu_y in -0.3f64..0.3, mu_z in -0.2f64..0.2,
                            ct0 in -0.02f64..0.03, ct1 in 0.0f64..0.05) {
            let p = InflowProblem { mu_inplane2: mu_x * mu_x + mu_y * mu_y, mu_axial: mu_z, ct0, ct1 };
            let sol = p.solve().unwrap();
            prop_assert!(sol.lambda.is_finite());
            prop_assert!(p.g(sol.lambda).abs() < 1e-12, "g = {}", p.g(sol.lambda));
        }
    }
}
