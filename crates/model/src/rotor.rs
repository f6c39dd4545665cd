//! Blade-element rotor integrals: main-rotor forces and torques (7.7)–(7.9),
//! (7.21), (7.22), (7.25), (7.26), (D.30)–(D.38), the aerodynamic flap-torque
//! harmonics of both rotors (6.23), and the thrust coefficient (7.30) split
//! into its λ-independent and λ-linear parts for the inflow solver.
//!
//! Blade element quantities (MODEL.md §5), r measured from the hinge, radial
//! position e + r, azimuth Ψ (0 at the tail, positive about body z):
//! * Ut = Ω(e+r) + hẋ sinΨ − hẏ cosΨ, (6.14)
//! * Up = ΩRλ − (hẋ cosΨ + hẏ sinΨ)β − β̇ r + (e+r)(q cosΨ − p sinΨ), (6.17),
//!   with β̇ the full time derivative at Ψ = Ωt,
//! * θb = θ0 − A1,mr cosΨ − B1,mr sinΨ + θt(e+r)/R − K1β, (4.2)/(D.26)/(D.27),
//! * dL = (ρ/2)c Cls (Ut²θb + Ut Up), dD = (ρ/2)c Cd Ut², (6.18)/(6.21), and
//!   dL·φr = (ρ/2)c Cls (Ut θb + Up) Up so nothing is divided by Ut.
//!
//! **Exact quadrature.** The integrands are trigonometric polynomials of
//! degree ≤ 5 in Ψ and polynomials of degree ≤ 3 in r (≤ 4 with twist), so
//! a 6-point uniform azimuth grid (exact below degree 6: a uniform N-point sum
//! of e^{ikΨ} vanishes unless N divides k) times 3-point
//! Gauss–Legendre in r (exact to degree 5) integrates them exactly; the tests
//! compare with the closed forms of MODEL.md §6.3 and with a fine grid.
//!
//! Every output is a polynomial in λ (Up is affine in λ): the single pass
//! below accumulates the coefficients, so the inflow solver and the thesis
//! emulation (flapping on one λ, forces on another) need no second pass.

use nalgebra::Vector3;

/// Azimuth points (exact for trigonometric degree < 6; the integrands reach 5).
pub const N_PSI: usize = 6;
/// Gauss–Legendre points in r (exact to polynomial degree 5).
pub const N_R: usize = 3;

/// A fixed quadrature grid on [r0, r1] × [0, 2π).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// cos Ψ_j.
    pub cos: [f64; N_PSI],
    /// sin Ψ_j.
    pub sin: [f64; N_PSI],
    /// Radial nodes r_k.
    pub r: [f64; N_R],
    /// Radial weights times 1/N_PSI, so Σ_j Σ_k w_k f = ⟨∫ f dr⟩_Ψ.
    pub w: [f64; N_R],
}

impl Grid {
    /// Grid for r ∈ [r0, r1].
    pub fn new(r0: f64, r1: f64) -> Grid {
        let x = [-(0.6f64.sqrt()), 0.0, 0.6f64.sqrt()];
        let wx = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
        let half = 0.5 * (r1 - r0);
        let mid = 0.5 * (r1 + r0);
        let mut g = Grid {
            cos: [0.0; N_PSI],
            sin: [0.0; N_PSI],
            r: [0.0; N_R],
            w: [0.0; N_R],
        };
        for j in 0..N_PSI {
            let psi = 2.0 * std::f64::consts::PI * j as f64 / N_PSI as f64;
            g.cos[j] = psi.cos();
            g.sin[j] = psi.sin();
        }
        for k in 0..N_R {
            g.r[k] = mid + half * x[k];
            g.w[k] = half * wx[k] / N_PSI as f64;
        }
        g
    }
}

/// c0 + c1 λ.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Lin(pub f64, pub f64);

impl Lin {
    /// Value at λ.
    #[inline]
    pub fn at(&self, lambda: f64) -> f64 {
        self.0 + self.1 * lambda
    }
}

/// c0 + c1 λ + c2 λ².
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Quad(pub f64, pub f64, pub f64);

impl Quad {
    /// Value at λ.
    #[inline]
    pub fn at(&self, lambda: f64) -> f64 {
        self.0 + lambda * (self.1 + lambda * self.2)
    }
}

/// Kinematic inputs of one blade-element pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BladeInputs {
    /// Ω (rad/s).
    pub omega_rad_s: f64,
    /// Hinge offset e (m); 0 for the teetering stabilizer bar.
    pub hinge_offset_m: f64,
    /// In-plane hub velocity along body x seen by the blades (m/s).
    pub hub_u_m_s: f64,
    /// In-plane hub velocity along body y seen by the blades (m/s).
    pub hub_v_m_s: f64,
    /// Velocity per unit λ in Up (ΩR for the main rotor).
    pub lambda_speed_m_s: f64,
    /// Body roll rate p (rad/s).
    pub p_rad_s: f64,
    /// Body pitch rate q (rad/s).
    pub q_rad_s: f64,
    /// Flapping [a0, a1, b1] (rad); a0 = 0 for the stabilizer bar.
    pub flap_rad: Vector3<f64>,
    /// Flapping rates (rad/s).
    pub flap_rate_rad_s: Vector3<f64>,
    /// Collective θ0 (rad), 0 for the stabilizer bar.
    pub theta0_rad: f64,
    /// Cyclic pitch A (cos Ψ coefficient, enters as −A cos Ψ) (rad).
    pub cyclic_a_rad: f64,
    /// Cyclic pitch B (sin Ψ coefficient, enters as −B sin Ψ) (rad).
    pub cyclic_b_rad: f64,
    /// Twist per unit radial position θt/R (rad/m).
    pub twist_rad_per_m: f64,
    /// Flap-pitch coupling K1.
    pub k1: f64,
    /// (ρ/2) c Cls (kg/m²/rad).
    pub lift_k: f64,
    /// (ρ/2) c Cd (kg/m²); 0 when only flapping is wanted.
    pub drag_k: f64,
}

/// Per-blade integrals as polynomials in λ. Divide nothing, multiply by the
/// number of blades where the thesis sums over blades.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BladeIntegrals {
    /// ⟨∫ dL dr⟩ (N per blade): −hFz/b and the C_T numerator.
    pub lift: Lin,
    /// Aerodynamic flap torque harmonics ⟨τa⟩, 2⟨τa cos Ψ⟩, 2⟨τa sin Ψ⟩ with
    /// τa = ∫ r dL dr, (6.23) (N·m).
    pub flap_torque: [Lin; 3],
    /// ⟨∫ −dD sinΨ + dL(β cosΨ + φr sinΨ)⟩ (N), (7.7).
    pub fx: Quad,
    /// ⟨∫ dD cosΨ + dL(β sinΨ − φr cosΨ)⟩ (N), (7.8).
    pub fy: Quad,
    /// e⟨∫ dL sinΨ⟩ (N·m), (7.21) without the spring.
    pub tx: Lin,
    /// −e⟨∫ dL cosΨ⟩ (N·m), (7.22) without the spring.
    pub ty: Lin,
    /// ⟨∫ −(r+e)(dD − dL φr)⟩ (N·m), (7.25).
    pub tz: Quad,
}

/// One pass over the grid computing all per-blade integrals.
pub fn blade_integrals(grid: &Grid, b: &BladeInputs) -> BladeIntegrals {
    let om = b.omega_rad_s;
    let e = b.hinge_offset_m;
    let (a0, a1, b1) = (b.flap_rad.x, b.flap_rad.y, b.flap_rad.z);
    let (a0d, a1d, b1d) = (
        b.flap_rate_rad_s.x,
        b.flap_rate_rad_s.y,
        b.flap_rate_rad_s.z,
    );
    let v = b.lambda_speed_m_s;
    let k = b.lift_k;
    let kd = b.drag_k;
    let mut out = BladeIntegrals::default();
    // Per-call radial constants: position e + r, weights times r and times
    // (e + r), and their sums (the λ-linear and λ² parts integrate in closed form).
    let mut pos = [0.0; N_R];
    let mut wr = [0.0; N_R];
    let mut wpos = [0.0; N_R];
    let (mut sw, mut swr, mut sw_pos, mut swr_pos) = (0.0, 0.0, 0.0, 0.0);
    for kk in 0..N_R {
        pos[kk] = e + grid.r[kk];
        wr[kk] = grid.w[kk] * grid.r[kk];
        wpos[kk] = grid.w[kk] * pos[kk];
        sw += grid.w[kk];
        swr += wr[kk];
        sw_pos += wpos[kk];
        swr_pos += wr[kk] * pos[kk];
    }
    let tw = b.twist_rad_per_m;
    let (mut l0, mut l1) = (0.0, 0.0);
    let mut ft = [(0.0, 0.0); 3];
    let (mut fx0, mut fx1) = (0.0, 0.0);
    let (mut fy0, mut fy1) = (0.0, 0.0);
    let (mut tx0, mut tx1, mut ty0, mut ty1) = (0.0, 0.0, 0.0, 0.0);
    let (mut tz0, mut tz1) = (0.0, 0.0);
    for j in 0..N_PSI {
        let c = grid.cos[j];
        let s = grid.sin[j];
        let beta = a0 - a1 * c + b1 * s;
        let beta_dot = a0d - a1d * c + b1d * s + om * (a1 * s + b1 * c);
        let ut_trans = b.hub_u_m_s * s - b.hub_v_m_s * c;
        let up_beta = -(b.hub_u_m_s * c + b.hub_v_m_s * s) * beta;
        let rates = b.q_rad_s * c - b.p_rad_s * s;
        let theta_cyc = b.theta0_rad - b.cyclic_a_rad * c - b.cyclic_b_rad * s - b.k1 * beta;
        // Sums over r of the λ-independent parts, without the factors k, kd:
        // a = Ut(Ut θ + Up0) (dL/k), cc·Up0 (dL φr/k), cc + Up0 (its λ slope/(kV)), Ut².
        let (mut sa, mut sra, mut sp0, mut sp1, mut sd) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut szp0, mut szd, mut sz1) = (0.0, 0.0, 0.0);
        for kk in 0..N_R {
            let r = grid.r[kk];
            let w = grid.w[kk];
            let ps = pos[kk];
            let ut = om * ps + ut_trans;
            let up0 = up_beta - beta_dot * r + ps * rates;
            let th = theta_cyc + tw * ps;
            let cc = ut * th + up0;
            let a = ut * cc;
            let q0 = cc * up0;
            let q1 = cc + up0;
            let uu = ut * ut;
            sa += w * a;
            sra += wr[kk] * a;
            sp0 += w * q0;
            sp1 += w * q1;
            sd += w * uu;
            szp0 += wpos[kk] * q0;
            szd += wpos[kk] * uu;
            sz1 += wpos[kk] * q1;
        }
        // dL = k(a + Ut V λ): Σ w Ut = Ω Σ w pos + Ut,trans Σ w (exact).
        let sl0 = k * sa;
        let sl1 = k * v * (om * sw_pos + ut_trans * sw);
        let sr0 = k * sra;
        let sr1 = k * v * (om * swr_pos + ut_trans * swr);
        let sp0 = k * sp0;
        let sp1 = k * v * sp1;
        let sd = kd * sd;
        l0 += sl0;
        l1 += sl1;
        ft[0].0 += sr0;
        ft[0].1 += sr1;
        ft[1].0 += 2.0 * sr0 * c;
        ft[1].1 += 2.0 * sr1 * c;
        ft[2].0 += 2.0 * sr0 * s;
        ft[2].1 += 2.0 * sr1 * s;
        fx0 += -sd * s + sl0 * beta * c + sp0 * s;
        fx1 += sl1 * beta * c + sp1 * s;
        fy0 += sd * c + sl0 * beta * s - sp0 * c;
        fy1 += sl1 * beta * s - sp1 * c;
        tx0 += e * sl0 * s;
        tx1 += e * sl1 * s;
        ty0 -= e * sl0 * c;
        ty1 -= e * sl1 * c;
        tz0 += k * szp0 - kd * szd;
        tz1 += k * v * sz1;
    }
    // The λ² parts: dL φr has k V² λ², independent of r and Ψ, so its sin/cos
    // projections (Fx, Fy) vanish over the full circle and the torque gets
    // N_PSI · k V² Σ w (e + r).
    let (fx2, fy2) = (0.0, 0.0);
    let tz2 = N_PSI as f64 * k * v * v * sw_pos;
    out.lift = Lin(l0, l1);
    out.flap_torque = [
        Lin(ft[0].0, ft[0].1),
        Lin(ft[1].0, ft[1].1),
        Lin(ft[2].0, ft[2].1),
    ];
    out.fx = Quad(fx0, fx1, fx2);
    out.fy = Quad(fy0, fy1, fy2);
    out.tx = Lin(tx0, tx1);
    out.ty = Lin(ty0, ty1);
    out.tz = Quad(tz0, tz1, tz2);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute-force reference: fine midpoint grid in Ψ (exact for trig
    /// polynomials anyway) and 200-point composite Simpson in r.
    fn reference(b: &BladeInputs, r0: f64, r1: f64, lambda: f64) -> [f64; 9] {
        let n_psi = 64;
        let n_r = 2000;
        let mut acc = [0.0; 9];
        for j in 0..n_psi {
            let psi = 2.0 * std::f64::consts::PI * (j as f64 + 0.37) / n_psi as f64;
            let (s, c) = psi.sin_cos();
            let (a0, a1, b1) = (b.flap_rad.x, b.flap_rad.y, b.flap_rad.z);
            let beta = a0 - a1 * c + b1 * s;
            let beta_dot = b.flap_rate_rad_s.x - b.flap_rate_rad_s.y * c
                + b.flap_rate_rad_s.z * s
                + b.omega_rad_s * (a1 * s + b1 * c);
            for i in 0..=n_r {
                let r = r0 + (r1 - r0) * i as f64 / n_r as f64;
                let wsimp = if i == 0 || i == n_r {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                let w = wsimp * (r1 - r0) / (3.0 * n_r as f64) / n_psi as f64;
                let pos = b.hinge_offset_m + r;
                let ut = b.omega_rad_s * pos + b.hub_u_m_s * s - b.hub_v_m_s * c;
                let up = b.lambda_speed_m_s * lambda
                    - (b.hub_u_m_s * c + b.hub_v_m_s * s) * beta
                    - beta_dot * r
                    + pos * (b.q_rad_s * c - b.p_rad_s * s);
                let th = b.theta0_rad - b.cyclic_a_rad * c - b.cyclic_b_rad * s
                    + b.twist_rad_per_m * pos
                    - b.k1 * beta;
                let dl = b.lift_k * (ut * ut * th + ut * up);
                let dlphi = b.lift_k * (ut * th + up) * up;
                let dd = b.drag_k * ut * ut;
                let e = b.hinge_offset_m;
                let vals = [
                    dl,
                    r * dl,
                    2.0 * r * dl * c,
                    2.0 * r * dl * s,
                    -dd * s + dl * beta * c + dlphi * s,
                    dd * c + dl * beta * s - dlphi * c,
                    e * dl * s,
                    -e * dl * c,
                    -pos * (dd - dlphi),
                ];
                for (a, v) in acc.iter_mut().zip(vals) {
                    *a += w * v;
                }
            }
        }
        acc
    }

    #[test]
    fn quadrature_is_exact_against_fine_grid() {
        let b = BladeInputs {
            omega_rad_s: 100.0,
            hinge_offset_m: 0.08,
            hub_u_m_s: 7.3,
            hub_v_m_s: -3.1,
            lambda_speed_m_s: 100.0,
            p_rad_s: 0.4,
            q_rad_s: -0.7,
            flap_rad: Vector3::new(0.02, 0.015, -0.011),
            flap_rate_rad_s: Vector3::new(0.3, -0.5, 0.8),
            theta0_rad: 0.13,
            cyclic_a_rad: 0.01,
            cyclic_b_rad: -0.02,
            twist_rad_per_m: -0.05,
            k1: 0.1,
            lift_k: 0.5 * 1.29 * 0.08 * 6.0,
            drag_k: 0.5 * 1.29 * 0.08 * 0.008,
        };
        let grid = Grid::new(0.0, 0.92);
        let bi = blade_integrals(&grid, &b);
        for lambda in [-0.05, 0.0, 0.03] {
            let r = reference(&b, 0.0, 0.92, lambda);
            let ours = [
                bi.lift.at(lambda),
                bi.flap_torque[0].at(lambda),
                bi.flap_torque[1].at(lambda),
                bi.flap_torque[2].at(lambda),
                bi.fx.at(lambda),
                bi.fy.at(lambda),
                bi.tx.at(lambda),
                bi.ty.at(lambda),
                bi.tz.at(lambda),
            ];
            for i in 0..9 {
                // Simpson on a degree ≤ 4 polynomial with 2000 panels: error ~1e-13
                // relative; the scale is the lift magnitude.
                let scale = r[0].abs().max(1.0);
                assert!(
                    (ours[i] - r[i]).abs() < 1e-12 * scale,
                    "i={i}: {} vs {}",
                    ours[i],
                    r[i]
                );
            }
        }
    }
}
