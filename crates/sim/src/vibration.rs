//! IMU vibration and the inside of an inertial sensor (thesis §3.3.2 and
//! Appendix A).
//!
//! The thesis's first flight failed because engine vibration saturated the
//! ±2 g accelerometer's *mechanical* sensing element before its internal
//! fifth-order low-pass filter (Figure 3.6): the output stayed inside the
//! range and looked plausible, but its mean moved. This module models that
//! chain, per axis, at an internal rate `oversample` times the IMU rate:
//!
//! ```text
//! truth + vibration ─► mechanical stage ─► clip ±mechanical range ─► internal low-pass ─► sample
//!   (rotor 1/rev, b/rev,   (2nd-order Butterworth,                    (Butterworth, order n,    (every oversample-th
//!    tail rotor, engine)     bandwidth)                                 cut-off; bilinear)         value: aliasing)
//! ```
//!
//! after which the sensor model of [`crate::sensors`] adds scale factor, bias,
//! noise, quantisation and the output range. The vibration is a sum of
//! sinusoids at the rotor and engine frequencies, with per-axis amplitudes
//! given at a reference rotor speed and scaled with the square of the rotor
//! speed (imbalance forces grow as Ω²).
//!
//! The filters are fixed-size (at most [`MAX_SECTIONS`] second-order
//! sections) and a step allocates nothing.

use nalgebra::{Complex, Vector3};
use std::f64::consts::PI;

pub use helicon_setup::vibration::{MAX_FILTER_ORDER, StageConfig, VibrationConfig, VibrationLine};
/// Second-order sections a filter holds.
pub const MAX_SECTIONS: usize = 4;

/// One second-order section, direct form II transposed:
/// `H(z) = (b0 + b1 z⁻¹ + b2 z⁻²) / (1 + a1 z⁻¹ + a2 z⁻²)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Biquad {
    /// Numerator `[b0, b1, b2]`.
    pub b: [f64; 3],
    /// Denominator `[a1, a2]` (a0 = 1).
    pub a: [f64; 2],
    z: [f64; 2],
}

impl Biquad {
    fn new(b: [f64; 3], a: [f64; 2]) -> Self {
        Biquad { b, a, z: [0.0; 2] }
    }

    #[inline]
    fn step(&mut self, x: f64) -> f64 {
        let y = self.b[0] * x + self.z[0];
        self.z[0] = self.b[1] * x - self.a[0] * y + self.z[1];
        self.z[1] = self.b[2] * x - self.a[1] * y;
        y
    }

    /// Put the section at rest with a constant input `x` (output `x·H(1)`).
    fn settle(&mut self, x: f64) {
        let y = x * self.dc_gain();
        self.z[1] = self.b[2] * x - self.a[1] * y;
        self.z[0] = self.b[1] * x - self.a[0] * y + self.z[1];
    }

    fn dc_gain(&self) -> f64 {
        (self.b[0] + self.b[1] + self.b[2]) / (1.0 + self.a[0] + self.a[1])
    }

    fn response(&self, z_inv: Complex<f64>) -> Complex<f64> {
        let num = self.b[0] + z_inv * (self.b[1] + z_inv * self.b[2]);
        let den = 1.0 + z_inv * (self.a[0] + z_inv * self.a[1]);
        num / den
    }
}

/// A digital Butterworth low-pass of order 1..=[`MAX_FILTER_ORDER`]: the
/// analog prototype mapped by the bilinear transform with the cut-off
/// pre-warped (the digital response is −3 dB at the cut-off exactly), as
/// second-order sections (a first-order section last for odd orders).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ButterworthLowPass {
    sections: [Biquad; MAX_SECTIONS],
    n_sections: usize,
    sample_rate_hz: f64,
}

impl ButterworthLowPass {
    /// Design the filter. `order` in 1..=8, `0 < cutoff_hz < sample_rate_hz/2`
    /// (checked by the configuration; out of range here gives `None`).
    pub fn new(order: u32, cutoff_hz: f64, sample_rate_hz: f64) -> Option<Self> {
        let ok = (1..=MAX_FILTER_ORDER).contains(&order)
            && cutoff_hz.is_finite()
            && sample_rate_hz.is_finite()
            && cutoff_hz > 0.0
            && cutoff_hz < 0.5 * sample_rate_hz;
        if !ok {
            return None;
        }
        let n = order as usize;
        let k = (PI * cutoff_hz / sample_rate_hz).tan();
        let mut sections = [Biquad::default(); MAX_SECTIONS];
        let pairs = n / 2;
        for (i, s) in sections.iter_mut().enumerate().take(pairs) {
            // analog pole pair −sin θ ± j cos θ: s² + 2 sin θ s + 1
            let theta = PI * (2 * i + 1) as f64 / (2 * n) as f64;
            let a = 2.0 * theta.sin();
            let d0 = 1.0 + a * k + k * k;
            let kk = k * k / d0;
            *s = Biquad::new(
                [kk, 2.0 * kk, kk],
                [2.0 * (k * k - 1.0) / d0, (1.0 - a * k + k * k) / d0],
            );
        }
        if n % 2 == 1 {
            // analog real pole s = −1
            let d0 = 1.0 + k;
            sections[pairs] = Biquad::new([k / d0, k / d0, 0.0], [(k - 1.0) / d0, 0.0]);
        }
        Some(ButterworthLowPass {
            sections,
            n_sections: pairs + n % 2,
            sample_rate_hz,
        })
    }

    /// The second-order sections (`[b0 b1 b2 1 a1 a2]` rows as SciPy's `sos`).
    pub fn sections(&self) -> &[Biquad] {
        &self.sections[..self.n_sections]
    }

    /// Filter one sample.
    #[inline]
    pub fn step(&mut self, x: f64) -> f64 {
        let mut y = x;
        for s in &mut self.sections[..self.n_sections] {
            y = s.step(y);
        }
        y
    }

    /// Put the filter at rest with a constant input `x`.
    pub fn settle(&mut self, x: f64) {
        let mut y = x;
        for s in &mut self.sections[..self.n_sections] {
            s.settle(y);
            y *= s.dc_gain();
        }
    }

    /// Gain at zero frequency (1 up to rounding for a Butterworth low-pass).
    pub fn dc_gain(&self) -> f64 {
        self.sections().iter().map(Biquad::dc_gain).product()
    }

    /// Magnitude of the frequency response at `f_hz`.
    pub fn gain_at(&self, f_hz: f64) -> f64 {
        let w = 2.0 * PI * f_hz / self.sample_rate_hz;
        let z_inv = Complex::new(w.cos(), -w.sin());
        self.sections()
            .iter()
            .map(|s| s.response(z_inv))
            .fold(Complex::new(1.0, 0.0), |acc, h| acc * h)
            .norm()
    }
}

/// The mean over a period of `clamp(offset + amplitude·sin θ, lo, hi)`: the
/// closed form of a clipped sinusoid's mean (`lo ≤ hi`, `amplitude ≥ 0`).
///
/// With `c = (limit − offset)/amplitude` clipped to [−1, 1] and `β = asin c`,
/// `E[(c − sin θ)⁺] = (c(π + 2β) + 2 cos β)/(2π)`; the mean is
/// `offset + amplitude·(E[(c_lo − sin θ)⁺] − E[(sin θ − c_hi)⁺])`.
/// A linear filter after the clipping passes this mean times its DC gain.
pub fn clipped_sine_mean(offset: f64, amplitude: f64, lo: f64, hi: f64) -> f64 {
    if amplitude <= 0.0 {
        return offset.clamp(lo, hi);
    }
    if lo >= offset + amplitude {
        return lo;
    }
    if hi <= offset - amplitude {
        return hi;
    }
    let below = |c: f64| {
        let c = c.clamp(-1.0, 1.0);
        let beta = c.asin();
        (c * (PI + 2.0 * beta) + 2.0 * beta.cos()) / (2.0 * PI)
    };
    let c_lo = (lo - offset) / amplitude;
    let c_hi = (hi - offset) / amplitude;
    // E[(sin θ − c)⁺] = E[(−c − sin θ)⁺] by symmetry of sin θ
    offset + amplitude * (below(c_lo) - below(-c_hi))
}

/// The six line frequencies (Hz) of `vib` at these rotor speeds.
fn frequencies_hz(vib: &VibrationConfig, rotor: &RotorSpeeds) -> [f64; 6] {
    let f_mr = rotor.main_rad_s / (2.0 * PI);
    let f_tr = rotor.tail_rad_s / (2.0 * PI);
    let f_fire = f_mr * vib.engine_gear_ratio * vib.engine_firings_per_rev;
    [
        f_mr,
        rotor.main_blades * f_mr,
        f_tr,
        rotor.tail_blades * f_tr,
        f_fire,
        2.0 * f_fire,
    ]
}

/// Rotor speeds and blade counts that set the vibration frequencies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorSpeeds {
    /// Main-rotor speed Ω (rad/s).
    pub main_rad_s: f64,
    /// Main-rotor blades b.
    pub main_blades: f64,
    /// Tail-rotor speed Ωtr (rad/s).
    pub tail_rad_s: f64,
    /// Tail-rotor blades btr.
    pub tail_blades: f64,
}

impl RotorSpeeds {
    /// The helicopter's rotors (Ω, b, Ωtr = G·Ω, btr).
    pub fn from_params(p: &helicon_model::Params) -> Self {
        RotorSpeeds {
            main_rad_s: p.main_rotor.omega_rad_s,
            main_blades: p.main_rotor.blades,
            tail_rad_s: p.omega_tr_rad_s(),
            tail_blades: p.tail_rotor.blades,
        }
    }
}

impl Default for RotorSpeeds {
    /// The Bergen Twin's (Ω = 100 rad/s, two blades, Ωtr = 650 rad/s, two blades).
    fn default() -> Self {
        RotorSpeeds::from_params(&helicon_model::Params::bergen_twin())
    }
}

/// One axis of a sensor's inside: mechanical stage, clip, internal filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorStage {
    mechanical: ButterworthLowPass,
    range: f64,
    filter: ButterworthLowPass,
    started: bool,
}

impl SensorStage {
    /// The stage of `cfg` at the internal rate; `output_range` stands in for
    /// an absent mechanical range. `None` when a frequency is out of range.
    pub fn new(cfg: &StageConfig, output_range: f64, internal_rate_hz: f64) -> Option<Self> {
        Some(SensorStage {
            mechanical: ButterworthLowPass::new(2, cfg.mechanical_bandwidth_hz, internal_rate_hz)?,
            range: cfg.mechanical_range.unwrap_or(output_range),
            filter: ButterworthLowPass::new(
                cfg.filter_order,
                cfg.filter_cutoff_hz,
                internal_rate_hz,
            )?,
            started: false,
        })
    }

    /// One internal sub-step: the input (sensor unit) through the mechanical
    /// stage, its range and the internal filter. Returns the filter output and
    /// whether the mechanical stage was at its limit.
    #[inline]
    pub fn step(&mut self, x: f64) -> (f64, bool) {
        if !self.started {
            // start at rest at the first input: no switch-on transient
            self.mechanical.settle(x);
            self.filter.settle(x.clamp(-self.range, self.range));
            self.started = true;
        }
        let m = self.mechanical.step(x);
        let clipped = m.abs() > self.range;
        (self.filter.step(m.clamp(-self.range, self.range)), clipped)
    }

    /// The mechanical stage's gain at `f_hz`.
    pub fn mechanical_gain_at(&self, f_hz: f64) -> f64 {
        self.mechanical.gain_at(f_hz)
    }

    /// The internal filter (its DC gain and response).
    pub fn filter(&self) -> &ButterworthLowPass {
        &self.filter
    }

    /// The mechanical range (sensor unit).
    pub fn range(&self) -> f64 {
        self.range
    }
}

/// What the vibration chain saw over the last IMU sample (truth, for
/// analysis: the flight software cannot see it).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageDiagnostics {
    /// Fraction of the sub-steps at which an accelerometer axis's mechanical
    /// stage was at its limit, per axis.
    pub accel_clipped_fraction: [f64; 3],
    /// The same for the gyro.
    pub gyro_clipped_fraction: [f64; 3],
}

/// The vibration at the sensor and the accelerometer and gyro stages: one
/// call per IMU sample gives the values the sensors' outputs sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VibrationChain {
    accel: [SensorStage; 3],
    gyro: [SensorStage; 3],
    /// Per line: the phasor `(cos θ, sin θ)` of its phase and its rotation
    /// per sub-step `(cos ωh, sin ωh)` (no trigonometry per sub-step).
    phasor: [(f64, f64); 6],
    rotation: [(f64, f64); 6],
    /// Per line and axis: the amplitude's in-phase and quadrature parts
    /// (random phase per axis), accelerometer then gyro.
    accel_iq: [[(f64, f64); 3]; 6],
    gyro_iq: [[(f64, f64); 3]; 6],
    oversample: u32,
    diagnostics: StageDiagnostics,
}

/// The inputs [`VibrationChain::new`] needs besides the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainSetup {
    /// IMU output rate (Hz).
    pub imu_rate_hz: f64,
    /// Accelerometer and gyro output ranges (m/s², rad/s).
    pub output_range: (f64, f64),
    /// Rotor speeds.
    pub rotor: RotorSpeeds,
}

impl VibrationChain {
    /// The chain of `vib` with the stages `accel`, `gyro`; `phases` gives one
    /// uniform [0, 1) number per line, axis and sensor (36) for the random
    /// phases. `None` when a frequency is out of range (the configuration's
    /// validation reports which).
    pub fn new(
        vib: &VibrationConfig,
        accel: &StageConfig,
        gyro: &StageConfig,
        setup: &ChainSetup,
        mut phases: impl FnMut() -> f64,
    ) -> Option<Self> {
        let fs = setup.imu_rate_hz * f64::from(vib.oversample);
        let a = SensorStage::new(accel, setup.output_range.0, fs)?;
        let g = SensorStage::new(gyro, setup.output_range.1, fs)?;
        let scale = (setup.rotor.main_rad_s / vib.reference_rotor_speed_rad_s).powi(2);
        let freqs = frequencies_hz(vib, &setup.rotor);
        let mut accel_iq = [[(0.0, 0.0); 3]; 6];
        let mut gyro_iq = [[(0.0, 0.0); 3]; 6];
        for (l, (_, line)) in vib.lines().iter().enumerate() {
            let scale = scale * vib.transmissibility(freqs[l]);
            for i in 0..3 {
                let pa = 2.0 * PI * phases();
                let pg = 2.0 * PI * phases();
                let (aa, ag) = (scale * line.accel_m_s2[i], scale * line.gyro_rad_s[i]);
                accel_iq[l][i] = (aa * pa.cos(), aa * pa.sin());
                gyro_iq[l][i] = (ag * pg.cos(), ag * pg.sin());
            }
        }
        Some(VibrationChain {
            accel: [a; 3],
            gyro: [g; 3],
            phasor: [(1.0, 0.0); 6],
            rotation: freqs.map(|f| {
                let (s, c) = (2.0 * PI * f / fs).sin_cos();
                (c, s)
            }),
            accel_iq,
            gyro_iq,
            oversample: vib.oversample,
            diagnostics: StageDiagnostics::default(),
        })
    }

    /// Run the sub-steps of one IMU sample with the true specific force and
    /// rates held, and return what the accelerometer and gyro outputs sample
    /// (before scale factor, bias, noise, quantisation and output range).
    pub fn step(
        &mut self,
        f_body_m_s2: &Vector3<f64>,
        omega_body_rad_s: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let mut out_a = Vector3::zeros();
        let mut out_g = Vector3::zeros();
        let mut clipped_a = [0u32; 3];
        let mut clipped_g = [0u32; 3];
        for _ in 0..self.oversample {
            let mut va = *f_body_m_s2;
            let mut vg = *omega_body_rad_s;
            for l in 0..6 {
                let (c0, s0) = self.phasor[l];
                let (cr, sr) = self.rotation[l];
                let (c, s) = (c0 * cr - s0 * sr, s0 * cr + c0 * sr);
                self.phasor[l] = (c, s);
                for i in 0..3 {
                    let (ia, qa) = self.accel_iq[l][i];
                    let (ig, qg) = self.gyro_iq[l][i];
                    va[i] += ia * s + qa * c;
                    vg[i] += ig * s + qg * c;
                }
            }
            for i in 0..3 {
                let (ya, ca) = self.accel[i].step(va[i]);
                let (yg, cg) = self.gyro[i].step(vg[i]);
                out_a[i] = ya;
                out_g[i] = yg;
                clipped_a[i] += u32::from(ca);
                clipped_g[i] += u32::from(cg);
            }
        }
        // keep the phasors on the unit circle (one Newton step on |z| = 1)
        for z in &mut self.phasor {
            let k = 1.5 - 0.5 * (z.0 * z.0 + z.1 * z.1);
            *z = (z.0 * k, z.1 * k);
        }
        let n = f64::from(self.oversample);
        self.diagnostics = StageDiagnostics {
            accel_clipped_fraction: clipped_a.map(|c| f64::from(c) / n),
            gyro_clipped_fraction: clipped_g.map(|c| f64::from(c) / n),
        };
        (out_a, out_g)
    }

    /// What the mechanical stages saw over the last sample.
    pub fn diagnostics(&self) -> StageDiagnostics {
        self.diagnostics
    }

    /// The accelerometer's stage (one axis; all three are alike).
    pub fn accel_stage(&self) -> &SensorStage {
        &self.accel[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_matches_quadrature() {
        // mean of the clipped wave by a fine midpoint rule
        for &(o, a, lo, hi) in &[
            (-1.0, 0.5, -2.0, 2.0),
            (-1.0, 1.5, -2.0, 2.0),
            (-1.0, 3.7, -2.0, 2.0),
            (0.3, 10.0, -2.0, 2.0),
            (-1.0, 1.0, -2.0, 2.0),
            (5.0, 1.0, -2.0, 2.0),
        ] {
            let n = 200_000;
            let q: f64 = (0..n)
                .map(|k| {
                    let th = 2.0 * PI * (k as f64 + 0.5) / n as f64;
                    (o + a * th.sin()).clamp(lo, hi)
                })
                .sum::<f64>()
                / n as f64;
            let c = clipped_sine_mean(o, a, lo, hi);
            assert!((c - q).abs() < 1e-8, "{o} {a}: {c} vs {q}");
        }
    }

    #[test]
    fn butterworth_is_minus_3_db_at_cutoff_and_unity_at_dc() {
        for order in 1..=8 {
            let f = ButterworthLowPass::new(order, 50.0, 8000.0).unwrap();
            assert!((f.dc_gain() - 1.0).abs() < 1e-12);
            assert!((f.gain_at(50.0) - 0.5f64.sqrt()).abs() < 1e-12);
        }
        assert!(ButterworthLowPass::new(9, 50.0, 8000.0).is_none());
        assert!(ButterworthLowPass::new(5, 4000.0, 8000.0).is_none());
    }

    /// A line comes out at its frequency (engine firing: gear ratio ×
    /// firings × Ω/2π) with its amplitude scaled by (Ω/Ω_ref)² and the
    /// stages' gains; the phasor recursion keeps it over 20 000 sub-steps.
    #[test]
    fn a_line_has_its_frequency_and_amplitude() {
        let mut vib = VibrationConfig {
            oversample: 1,
            ..VibrationConfig::default()
        };
        for l in [
            &mut vib.main_1p,
            &mut vib.main_bp,
            &mut vib.tail_1p,
            &mut vib.tail_bp,
            &mut vib.engine_2f,
        ] {
            *l = VibrationLine::default();
        }
        vib.engine_1f = VibrationLine {
            accel_m_s2: [0.0, 0.0, 3.0],
            gyro_rad_s: [0.0; 3],
        };
        let stage = StageConfig {
            mechanical_range: Some(1e3),
            mechanical_bandwidth_hz: 2000.0,
            filter_order: 2,
            filter_cutoff_hz: 2000.0,
        };
        let rotor = RotorSpeeds {
            main_rad_s: 200.0,
            main_blades: 2.0,
            tail_rad_s: 1300.0,
            tail_blades: 2.0,
        };
        let fs = 10_000.0;
        let setup = ChainSetup {
            imu_rate_hz: fs,
            output_range: (1e3, 1e3),
            rotor,
        };
        let mut chain = VibrationChain::new(&vib, &stage, &stage, &setup, || 0.25).unwrap();
        let f = 200.0 / (2.0 * PI) * 8.0 * 2.0;
        let st = chain.accel_stage();
        let expected = 4.0 * 3.0 * st.mechanical_gain_at(f) * st.filter().gain_at(f);
        let (mut re, mut im, mut n) = (0.0, 0.0, 0.0);
        for k in 0..20_000 {
            let (a, _) = chain.step(&Vector3::zeros(), &Vector3::zeros());
            if k >= 1000 {
                let w = 2.0 * PI * f * f64::from(k) / fs;
                re += a.z * w.cos();
                im += a.z * w.sin();
                n += 1.0;
            }
            assert_eq!((a.x, a.y), (0.0, 0.0));
        }
        let amplitude = 2.0 * (re * re + im * im).sqrt() / n;
        assert!(
            (amplitude / expected - 1.0).abs() < 1e-3,
            "{amplitude} vs {expected}"
        );

        // on an isolator at 100 Hz, ζ = 0.1: scaled by its transmissibility
        vib.isolator_natural_frequency_hz = Some(100.0);
        let mut isolated = VibrationChain::new(&vib, &stage, &stage, &setup, || 0.25).unwrap();
        let (r, z2r) = (f / 100.0, 0.2 * f / 100.0);
        let t = ((1.0 + z2r * z2r) / ((1.0 - r * r).powi(2) + z2r * z2r)).sqrt();
        let (mut re, mut im) = (0.0, 0.0);
        for k in 0..20_000 {
            let (a, _) = isolated.step(&Vector3::zeros(), &Vector3::zeros());
            if k >= 1000 {
                let w = 2.0 * PI * f * f64::from(k) / fs;
                re += a.z * w.cos();
                im += a.z * w.sin();
            }
        }
        let isolated_amplitude = 2.0 * (re * re + im * im).sqrt() / n;
        assert!(t < 0.1, "{t}"); // 0.057: the line is isolated
        assert!(
            (isolated_amplitude / (expected * t) - 1.0).abs() < 1e-3,
            "{isolated_amplitude} vs {}",
            expected * t
        );
    }
}
