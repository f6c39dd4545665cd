//! Flapping dynamics of the main rotor (6.47) and the stabilizer bar (6.53),
//! by harmonic balance of the blade torque equation (6.1) (MODEL.md §6).
//!
//! Per blade, Ib β̈ = T(Ψ) with
//! T = τa − Ω²(e·mb + Ib)β − Ks β + Ib(−ṗ sinΨ + q̇ cosΨ) + mb·a_n
//!     − 2Ω(p cosΨ + q sinΨ)(e·mb + Ib),
//! the aerodynamic (6.23), centrifugal (6.30), spring (6.31), body-angular
//! (6.36), body-normal (6.40) and Coriolis (6.46) torques, where
//! a_n = hz̈ − hẋ q + hẏ p. With β = a0 − a1 cosΨ + b1 sinΨ (4.5) and Ψ = Ωt,
//! projecting on 1, cosΨ, sinΨ gives (MODEL.md §6.2)
//! ä0 = T0/Ib, ä1 = 2Ω ḃ1 + Ω² a1 − Tc/Ib, b̈1 = −2Ω ȧ1 + Ω² b1 + Ts/Ib,
//! with T0 = ⟨T⟩, Tc = 2⟨T cosΨ⟩, Ts = 2⟨T sinΨ⟩. The aerodynamic harmonics
//! come from the exact quadrature of [`crate::rotor`]; the other torques are
//! projected here in closed form. The stabilizer bar is the same with e = 0,
//! Ks = 0, mb-terms absent (a teetering pair cancels the constant harmonic),
//! so only a1sb, b1sb remain (6.51)–(6.55).
//!
//! [`MainRotorCoefficients`] and [`StabilizerBarCoefficients`] give the thesis
//! form ä + Dȧ + Ka = JΥ + Eλ + G in closed form (MODEL.md §6.3/§6.4, valid
//! for K1 = θt = 0); the tests check the quadrature path against them.

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

/// Non-aerodynamic inputs to the main-rotor flap equations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlapBody {
    /// Body rates [p, q] (rad/s).
    pub p_rad_s: f64,
    /// Pitch rate (rad/s).
    pub q_rad_s: f64,
    /// Body angular accelerations [ṗ, q̇] (rad/s²); zero when the preset has
    /// no body-acceleration torques.
    pub p_dot_rad_s2: f64,
    /// Pitch acceleration (rad/s²).
    pub q_dot_rad_s2: f64,
    /// a_n = hz̈ − hẋ q + hẏ p (m/s²), the hub normal acceleration of (6.40).
    /// Without body-acceleration torques (the `thesis` preset) only the
    /// velocity-product part −hẋ q + hẏ p (MODEL.md §11 item 3).
    pub normal_accel_m_s2: f64,
}

/// Main-rotor flapping accelerations [ä0, ä1, b̈1] (rad/s²) from the
/// aerodynamic torque harmonics `[T0, Tc, Ts]` (N·m) of one blade.
#[allow(clippy::similar_names)]
pub fn main_rotor_accel(
    omega: f64,
    e: f64,
    ib: f64,
    mb: f64,
    ks: f64,
    flap: &Vector3<f64>,
    flap_rate: &Vector3<f64>,
    aero: [f64; 3],
    body: &FlapBody,
) -> Vector3<f64> {
    let (a0, a1, b1) = (flap.x, flap.y, flap.z);
    let (a1d, b1d) = (flap_rate.y, flap_rate.z);
    let iemb = e * mb + ib;
    let stiff = omega * omega * iemb + ks;
    let t0 = aero[0] - stiff * a0 + mb * body.normal_accel_m_s2;
    let tc = aero[1] + stiff * a1 + ib * body.q_dot_rad_s2 - 2.0 * omega * body.p_rad_s * iemb;
    let ts = aero[2] - stiff * b1 - ib * body.p_dot_rad_s2 - 2.0 * omega * body.q_rad_s * iemb;
    Vector3::new(
        t0 / ib,
        2.0 * omega * b1d + omega * omega * a1 - tc / ib,
        -2.0 * omega * a1d + omega * omega * b1 + ts / ib,
    )
}

/// Stabilizer-bar flapping accelerations [ä1sb, b̈1sb] (rad/s²) from the
/// aerodynamic harmonics `[Tc, Ts]` of one paddle (6.53).
pub fn stabilizer_bar_accel(
    omega: f64,
    ib_sb: f64,
    flap: &Vector2<f64>,
    flap_rate: &Vector2<f64>,
    aero: [f64; 2],
    body: &FlapBody,
) -> Vector2<f64> {
    let stiff = omega * omega * ib_sb;
    let tc =
        aero[0] + stiff * flap.x + ib_sb * body.q_dot_rad_s2 - 2.0 * omega * body.p_rad_s * ib_sb;
    let ts =
        aero[1] - stiff * flap.y - ib_sb * body.p_dot_rad_s2 - 2.0 * omega * body.q_rad_s * ib_sb;
    Vector2::new(
        2.0 * omega * flap_rate.y + omega * omega * flap.x - tc / ib_sb,
        -2.0 * omega * flap_rate.x + omega * omega * flap.y + ts / ib_sb,
    )
}

/// Closed-form coefficients of ä + Dȧ + Ka = JΥmr + Eλ + G, (6.47), for
/// K1 = θt = 0 (MODEL.md §6.3). Υmr = [θ0, A1,mr, B1,mr].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MainRotorCoefficients {
    /// D (1/s).
    pub d: Matrix3<f64>,
    /// K (1/s²).
    pub k: Matrix3<f64>,
    /// J (1/s²).
    pub j: Matrix3<f64>,
    /// E (1/s²).
    pub e: Vector3<f64>,
    /// G (rad/s²), including the body-acceleration terms given.
    pub g: Vector3<f64>,
}

/// Main-rotor parameters needed by the closed forms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MainRotorConsts {
    /// Ω (rad/s).
    pub omega: f64,
    /// R (m).
    pub radius: f64,
    /// e (m).
    pub e: f64,
    /// Ib (kg·m²).
    pub ib: f64,
    /// mb (kg·m).
    pub mb: f64,
    /// Ks (N·m/rad).
    pub ks: f64,
    /// ρ Cls c / (2 Ib) (the 𝒜 of MODEL.md §6.3).
    pub a_cal: f64,
}

impl MainRotorCoefficients {
    /// Evaluate at advance ratios μx, μy, rates p, q and the body-acceleration
    /// terms of `body` (MODEL.md §6.3).
    pub fn new(c: &MainRotorConsts, mu_x: f64, mu_y: f64, body: &FlapBody) -> Self {
        let (om, r, e) = (c.omega, c.radius, c.e);
        let l = r - e;
        let m1 = l * l / 2.0;
        let m2 = l * l * l / 3.0;
        let m3 = l * l * l * l / 4.0;
        let pp = e * m2 + m3;
        let qq = e * m1 + m2;
        let ss = e * e * m1 + 2.0 * e * m2 + m3;
        let a = c.a_cal;
        let o2a = om * om * a;
        let (mx, my) = (mu_x, mu_y);
        let d = Matrix3::new(
            om * a * pp,
            om * a * r * m2 * my / 2.0,
            om * a * r * m2 * mx / 2.0,
            om * a * r * m2 * my,
            om * a * pp,
            -2.0 * om,
            om * a * r * m2 * mx,
            2.0 * om,
            om * a * pp,
        );
        let base = c.ks / c.ib + om * om * e * c.mb / c.ib;
        let k = Matrix3::new(
            om * om * (1.0 + e * c.mb / c.ib) + c.ks / c.ib,
            -o2a * r * e * m1 * mx / 2.0,
            o2a * r * e * m1 * my / 2.0,
            -o2a * r * qq * mx,
            base - o2a * r * r * m1 * mx * my / 2.0,
            o2a * (r * r * m1 * (my * my - mx * mx) / 4.0 - pp),
            o2a * r * qq * my,
            o2a * (r * r * m1 * (my * my - mx * mx) / 4.0 + pp),
            base + o2a * r * r * m1 * mx * my / 2.0,
        );
        let j = Matrix3::new(
            o2a * (r * r * m1 * (mx * mx + my * my) / 2.0 + ss),
            o2a * r * qq * my,
            -o2a * r * qq * mx,
            2.0 * o2a * r * qq * my,
            o2a * (r * r * m1 * (mx * mx + 3.0 * my * my) / 4.0 + ss),
            -o2a * r * r * m1 * mx * my / 2.0,
            2.0 * o2a * r * qq * mx,
            o2a * r * r * m1 * mx * my / 2.0,
            -o2a * (r * r * m1 * (3.0 * mx * mx + my * my) / 4.0 + ss),
        );
        let ev = Vector3::new(o2a * r * qq, o2a * r * r * m1 * my, o2a * r * r * m1 * mx);
        let (p, q) = (body.p_rad_s, body.q_rad_s);
        let f = 1.0 + e * c.mb / c.ib;
        let g = Vector3::new(
            -(om * a * r * qq / 2.0) * (mx * p + my * q) + (c.mb / c.ib) * body.normal_accel_m_s2,
            -om * a * ss * q + 2.0 * om * f * p - body.q_dot_rad_s2,
            -om * a * ss * p - 2.0 * om * f * q - body.p_dot_rad_s2,
        );
        MainRotorCoefficients { d, k, j, e: ev, g }
    }

    /// ä = −Dȧ − Ka + JΥ + Eλ + G.
    pub fn accel(
        &self,
        a: &Vector3<f64>,
        a_dot: &Vector3<f64>,
        upsilon: &Vector3<f64>,
        lambda: f64,
    ) -> Vector3<f64> {
        -self.d * a_dot - self.k * a + self.j * upsilon + self.e * lambda + self.g
    }
}

/// Closed-form stabilizer-bar coefficients of (6.53) (MODEL.md §6.4),
/// Υsb = [A1, B1]; `r_scale` is Ro for the thesis scaling, R for physical.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilizerBarCoefficients {
    /// Dsb (1/s).
    pub d: Matrix2<f64>,
    /// Ksb (1/s²).
    pub k: Matrix2<f64>,
    /// Jsb (1/s²).
    pub j: Matrix2<f64>,
    /// Esb (1/s²).
    pub e: Vector2<f64>,
    /// Gsb (rad/s²).
    pub g: Vector2<f64>,
}

impl StabilizerBarCoefficients {
    /// Evaluate; `a_cal_sb` = ρ Cls,sb csb / (2 Ib,sb), `r_scale` the
    /// velocity-normalising radius (MODEL.md §6.4), μ normalised by ΩR.
    pub fn new(
        omega: f64,
        a_cal_sb: f64,
        ri: f64,
        ro: f64,
        r_scale: f64,
        mu_x: f64,
        mu_y: f64,
        body: &FlapBody,
    ) -> Self {
        let n1 = (ro * ro - ri * ri) / 2.0;
        let n3 = (ro.powi(4) - ri.powi(4)) / 4.0;
        let om = omega;
        let a = a_cal_sb;
        let o2a = om * om * a;
        let rs2n1 = r_scale * r_scale * n1;
        let (mx, my) = (mu_x, mu_y);
        let d = Matrix2::new(om * a * n3, -2.0 * om, 2.0 * om, om * a * n3);
        let k = Matrix2::new(
            -o2a * rs2n1 * mx * my / 2.0,
            o2a * (rs2n1 * (my * my - mx * mx) / 4.0 - n3),
            o2a * (rs2n1 * (my * my - mx * mx) / 4.0 + n3),
            o2a * rs2n1 * mx * my / 2.0,
        );
        let j = Matrix2::new(
            o2a * (rs2n1 * (mx * mx + 3.0 * my * my) / 4.0 + n3),
            -o2a * rs2n1 * mx * my / 2.0,
            o2a * rs2n1 * mx * my / 2.0,
            -o2a * (rs2n1 * (3.0 * mx * mx + my * my) / 4.0 + n3),
        );
        let e = Vector2::new(o2a * rs2n1 * my, o2a * rs2n1 * mx);
        let (p, q) = (body.p_rad_s, body.q_rad_s);
        let g = Vector2::new(
            -om * a * n3 * q + 2.0 * om * p - body.q_dot_rad_s2,
            -om * a * n3 * p - 2.0 * om * q - body.p_dot_rad_s2,
        );
        StabilizerBarCoefficients { d, k, j, e, g }
    }

    /// ä = −Dȧ − Ka + JΥ + Eλ + G.
    pub fn accel(
        &self,
        a: &Vector2<f64>,
        a_dot: &Vector2<f64>,
        upsilon: &Vector2<f64>,
        lambda: f64,
    ) -> Vector2<f64> {
        -self.d * a_dot - self.k * a + self.j * upsilon + self.e * lambda + self.g
    }
}
