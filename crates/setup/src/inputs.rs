//! Flight-test inputs, each a pure function of the time since its start
//! (zero before and after): the frequency [`Sweep`] as flown in practice,
//! the [`Multisine`] with Schroeder phases (orthogonal sets for several axes
//! at once), the [`Doublet`] and the [`Input3211`]. Amplitudes are in the
//! unit of the channel they are added to (a servo input in rad).

/// An input program's setting out of its range, or a program that cannot
/// be built (the identification crate reports it as its own error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InputError {
    /// A parameter out of its allowed range.
    #[error("`{field}` = {value}: {rule}")]
    Invalid {
        /// Parameter name, e.g. `sweep.omega_max_rad_s`.
        field: String,
        /// The value given, as text.
        value: String,
        /// The rule broken.
        rule: String,
    },
    /// The program cannot be built as asked, with the reason.
    #[error("{what}: {reason}")]
    Data {
        /// What is concerned, e.g. `multisine`.
        what: String,
        /// Why.
        reason: String,
    },
}

impl InputError {
    /// A number out of range.
    pub fn invalid(field: impl Into<String>, value: f64, rule: impl Into<String>) -> Self {
        InputError::Invalid {
            field: field.into(),
            value: format!("{value}"),
            rule: rule.into(),
        }
    }

    /// A program that cannot be built.
    pub fn data(what: impl Into<String>, reason: impl Into<String>) -> Self {
        InputError::Data {
            what: what.into(),
            reason: reason.into(),
        }
    }
}

/// Result with [`InputError`].
pub type Result<T> = std::result::Result<T, InputError>;

/// `Ok(v)` when `v` is finite and inside `[lo, hi]`, else [`InputError::Invalid`].
fn check_range(field: &str, v: f64, lo: f64, hi: f64) -> Result<f64> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(InputError::invalid(
            field,
            v,
            format!("must be finite and in [{lo}, {hi}]"),
        ))
    }
}
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Exponential-sweep constants of the rotorcraft flight-test practice: the
/// frequency rises as ω_min + C₂(e^{C₁ t/T} − 1)(ω_max − ω_min).
const SWEEP_C1: f64 = 4.0;
/// See [`SWEEP_C1`].
const SWEEP_C2: f64 = 0.0187;

/// A frequency sweep: `low_periods` periods at `omega_min_rad_s`, then an
/// exponential rise reaching `omega_max_rad_s` at the end of the record, the
/// amplitude faded in and out over `fade_s` with half-cosine ramps. The
/// record must last at least five periods of the lowest frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// Amplitude (the channel's unit).
    pub amplitude: f64,
    /// Lowest frequency, rad/s.
    pub omega_min_rad_s: f64,
    /// Highest frequency, rad/s.
    pub omega_max_rad_s: f64,
    /// Record length, s (≥ 5 × 2π/ω_min).
    pub duration_s: f64,
    /// Whole periods flown at ω_min before the rise (2 in practice).
    #[serde(default = "default_low_periods")]
    pub low_periods: f64,
    /// Fade-in and fade-out time, s.
    #[serde(default = "default_fade_s")]
    pub fade_s: f64,
}

fn default_low_periods() -> f64 {
    2.0
}
fn default_fade_s() -> f64 {
    1.0
}

impl Sweep {
    /// A checked sweep with two low-frequency periods and a 1 s fade.
    pub fn new(
        amplitude: f64,
        omega_min_rad_s: f64,
        omega_max_rad_s: f64,
        duration_s: f64,
    ) -> Result<Self> {
        let s = Sweep {
            amplitude,
            omega_min_rad_s,
            omega_max_rad_s,
            duration_s,
            low_periods: default_low_periods(),
            fade_s: default_fade_s(),
        };
        s.check()?;
        Ok(s)
    }

    /// Check every field (see the field docs for the rules).
    pub fn check(&self) -> Result<()> {
        check_range("sweep.amplitude", self.amplitude, -1e6, 1e6)?;
        check_range("sweep.omega_min_rad_s", self.omega_min_rad_s, 1e-4, 1e5)?;
        check_range(
            "sweep.omega_max_rad_s",
            self.omega_max_rad_s,
            self.omega_min_rad_s,
            1e5,
        )?;
        let t_low = 2.0 * PI / self.omega_min_rad_s;
        check_range("sweep.duration_s", self.duration_s, 5.0 * t_low, 1e6).map_err(|_| {
            InputError::invalid(
                "sweep.duration_s",
                self.duration_s,
                format!(
                    "the record must last ≥ 5 periods of omega_min ({:.6} s)",
                    5.0 * t_low
                ),
            )
        })?;
        check_range("sweep.low_periods", self.low_periods, 0.0, 4.0)?;
        if self.low_periods * t_low >= self.duration_s {
            return Err(InputError::invalid(
                "sweep.low_periods",
                self.low_periods,
                "the low-frequency periods must leave time for the rise",
            ));
        }
        check_range("sweep.fade_s", self.fade_s, 0.0, 0.25 * self.duration_s)?;
        Ok(())
    }

    /// Instantaneous frequency at `t_s` after the start, rad/s.
    pub fn omega_at(&self, t_s: f64) -> f64 {
        let t_low = self.low_periods * 2.0 * PI / self.omega_min_rad_s;
        if t_s <= t_low {
            return self.omega_min_rad_s;
        }
        let t_rise = self.duration_s - t_low;
        let tau = (t_s - t_low).min(t_rise);
        let k = SWEEP_C2 * ((SWEEP_C1 * tau / t_rise).exp() - 1.0) / rise_end_gain();
        self.omega_min_rad_s + k * (self.omega_max_rad_s - self.omega_min_rad_s)
    }

    /// The phase ∫ω dt in closed form, rad.
    fn phase(&self, t_s: f64) -> f64 {
        let t_low = self.low_periods * 2.0 * PI / self.omega_min_rad_s;
        let w0 = self.omega_min_rad_s;
        if t_s <= t_low {
            return w0 * t_s;
        }
        let t_rise = self.duration_s - t_low;
        let tau = t_s - t_low;
        let c = SWEEP_C2 / rise_end_gain() * (self.omega_max_rad_s - w0);
        w0 * t_s + c * (t_rise / SWEEP_C1 * ((SWEEP_C1 * tau / t_rise).exp() - 1.0) - tau)
    }

    /// The input at `t_s` after the start (zero outside the record).
    pub fn value(&self, t_s: f64) -> f64 {
        if !(0.0..=self.duration_s).contains(&t_s) {
            return 0.0;
        }
        self.amplitude * fade(t_s, self.duration_s, self.fade_s) * self.phase(t_s).sin()
    }
}

/// C₂(e^{C₁} − 1): the rise reaches exactly ω_max at the end of the record
/// (the classic constants give 1.002; normalising removes the 0.2 % excess).
fn rise_end_gain() -> f64 {
    SWEEP_C2 * (SWEEP_C1.exp() - 1.0)
}

/// Half-cosine fade-in and fade-out envelope over `fade_s` at both ends.
fn fade(t_s: f64, duration_s: f64, fade_s: f64) -> f64 {
    if fade_s <= 0.0 {
        return 1.0;
    }
    let edge = t_s.min(duration_s - t_s).max(0.0);
    if edge >= fade_s {
        1.0
    } else {
        0.5 - 0.5 * (PI * edge / fade_s).cos()
    }
}

/// A multisine: harmonics of the base frequency 2π/`period_s` between
/// `omega_min_rad_s` and `omega_max_rad_s`, equal power, Schroeder phases
/// (low crest factor), scaled so its peak over a period is `amplitude`,
/// repeated `repeats` times. With `axes` > 1 the harmonics are dealt out in
/// turn to the axes (`axis` takes every `axes`-th one): the signals of the
/// axes are then orthogonal over every whole period, so several axes can be
/// excited at once and still be told apart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Multisine {
    /// Peak amplitude (the channel's unit).
    pub amplitude: f64,
    /// Period of the signal, s (its frequency resolution is 2π/period).
    pub period_s: f64,
    /// Lowest frequency, rad/s.
    pub omega_min_rad_s: f64,
    /// Highest frequency, rad/s.
    pub omega_max_rad_s: f64,
    /// Periods flown.
    #[serde(default = "default_repeats")]
    pub repeats: u32,
    /// Axes excited at once (1: all harmonics on this signal).
    #[serde(default = "default_axes")]
    pub axes: u32,
    /// This signal's axis, 0 … axes−1.
    #[serde(default)]
    pub axis: u32,
    /// Harmonic numbers and phases (rad) of this axis, filled by [`Multisine::prepare`].
    #[serde(skip)]
    harmonics: Vec<(f64, f64)>,
    /// Scale making the peak equal to the amplitude, filled by [`Multisine::prepare`].
    #[serde(skip)]
    scale: f64,
}

/// Most harmonics one multisine axis may carry (flight-test multisines use
/// tens to hundreds; the bound keeps the peak search under ~0.3 s).
pub const MAX_HARMONICS: usize = 1000;

fn default_repeats() -> u32 {
    1
}
fn default_axes() -> u32 {
    1
}

impl Multisine {
    /// A checked and prepared multisine.
    pub fn new(
        amplitude: f64,
        period_s: f64,
        omega_min_rad_s: f64,
        omega_max_rad_s: f64,
        axes: u32,
        axis: u32,
    ) -> Result<Self> {
        let mut m = Multisine {
            amplitude,
            period_s,
            omega_min_rad_s,
            omega_max_rad_s,
            repeats: 1,
            axes,
            axis,
            harmonics: Vec::new(),
            scale: 0.0,
        };
        m.prepare()?;
        Ok(m)
    }

    /// Check the fields, choose the harmonics and Schroeder phases
    /// φ_k = −π k(k−1)/M (k = 1 … M over this axis's harmonics, equal power)
    /// and the peak scale. Needed after deserialising.
    pub fn prepare(&mut self) -> Result<()> {
        check_range("multisine.amplitude", self.amplitude, -1e6, 1e6)?;
        check_range("multisine.period_s", self.period_s, 1e-3, 1e5)?;
        check_range("multisine.omega_min_rad_s", self.omega_min_rad_s, 0.0, 1e5)?;
        check_range(
            "multisine.omega_max_rad_s",
            self.omega_max_rad_s,
            self.omega_min_rad_s,
            1e5,
        )?;
        if self.repeats == 0 || self.repeats > 10_000 {
            return Err(InputError::invalid(
                "multisine.repeats",
                self.repeats as f64,
                "1 … 10000",
            ));
        }
        if self.axes == 0 || self.axes > 16 || self.axis >= self.axes {
            return Err(InputError::invalid(
                "multisine.axis",
                self.axis as f64,
                format!(
                    "axes in 1 … 16 and axis in 0 … axes−1 (axes = {})",
                    self.axes
                ),
            ));
        }
        let w0 = 2.0 * PI / self.period_s;
        let k_lo = (self.omega_min_rad_s / w0).ceil().max(1.0) as u64;
        let k_hi = (self.omega_max_rad_s / w0).floor() as u64;
        // Refuse a huge band before enumerating it (no hang, no huge allocation).
        if k_hi >= k_lo && (k_hi - k_lo) / u64::from(self.axes) >= MAX_HARMONICS as u64 {
            return Err(InputError::invalid(
                "multisine.omega_max_rad_s",
                self.omega_max_rad_s,
                format!(
                    "more than {MAX_HARMONICS} harmonics of 2π/period = {w0:.6} rad/s per axis"
                ),
            ));
        }
        let ks: Vec<u64> = (k_lo..=k_hi)
            .filter(|k| (k - k_lo) % u64::from(self.axes) == u64::from(self.axis))
            .collect();
        if ks.is_empty() || ks.len() > MAX_HARMONICS {
            return Err(InputError::invalid(
                "multisine.omega_max_rad_s",
                self.omega_max_rad_s,
                format!(
                    "the band must hold 1 … {MAX_HARMONICS} harmonics of 2π/period = {w0:.6} rad/s for this axis"
                ),
            ));
        }
        let m = ks.len() as f64;
        self.harmonics = ks
            .iter()
            .enumerate()
            .map(|(i, k)| {
                let j = (i + 1) as f64;
                (*k as f64, -PI * j * (j - 1.0) / m)
            })
            .collect();
        // Peak over one period on a grid of 16 samples per period of the top harmonic.
        let n = (16 * k_hi.max(1)).clamp(256, 1 << 18) as usize;
        self.scale = 1.0;
        let peak = (0..n)
            .map(|i| self.raw(self.period_s * i as f64 / n as f64).abs())
            .fold(0.0, f64::max);
        if peak.is_nan() || peak <= 0.0 {
            return Err(InputError::data(
                "multisine",
                "the signal is identically zero",
            ));
        }
        self.scale = 1.0 / peak;
        Ok(())
    }

    fn raw(&self, t_s: f64) -> f64 {
        let w0 = 2.0 * PI / self.period_s;
        self.scale
            * self
                .harmonics
                .iter()
                .map(|(k, phi)| (k * w0 * t_s + phi).cos())
                .sum::<f64>()
    }

    /// The harmonics (rad/s) this axis carries.
    pub fn omegas_rad_s(&self) -> Vec<f64> {
        let w0 = 2.0 * PI / self.period_s;
        self.harmonics.iter().map(|(k, _)| k * w0).collect()
    }

    /// Length of the record, s.
    pub fn duration_s(&self) -> f64 {
        self.period_s * f64::from(self.repeats)
    }

    /// The input at `t_s` after the start (zero outside the record, and zero
    /// everywhere before [`Multisine::prepare`]).
    pub fn value(&self, t_s: f64) -> f64 {
        if !(0.0..=self.duration_s()).contains(&t_s) {
            return 0.0;
        }
        self.amplitude * self.raw(t_s)
    }
}

/// A doublet: +`amplitude` for `pulse_s`, then −`amplitude` for `pulse_s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Doublet {
    /// Amplitude (the channel's unit).
    pub amplitude: f64,
    /// Length of each half, s.
    pub pulse_s: f64,
}

/// A 3-2-1-1: +A for 3Δt, −A for 2Δt, +A for Δt, −A for Δt.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Input3211 {
    /// Amplitude (the channel's unit).
    pub amplitude: f64,
    /// The unit pulse length Δt, s.
    pub pulse_s: f64,
}

/// Value of a sequence of pulses of lengths `units × pulse_s` and signs `signs`.
fn pulses(t_s: f64, amplitude: f64, pulse_s: f64, units: &[f64], signs: &[f64]) -> f64 {
    if t_s < 0.0 {
        return 0.0;
    }
    let mut end = 0.0;
    for (u, s) in units.iter().zip(signs) {
        end += u * pulse_s;
        if t_s < end {
            return s * amplitude;
        }
    }
    0.0
}

impl Doublet {
    /// Check the fields.
    pub fn check(&self) -> Result<()> {
        check_range("doublet.amplitude", self.amplitude, -1e6, 1e6)?;
        check_range("doublet.pulse_s", self.pulse_s, 1e-4, 1e5)?;
        Ok(())
    }
    /// Length, s.
    pub fn duration_s(&self) -> f64 {
        2.0 * self.pulse_s
    }
    /// The input at `t_s` after the start.
    pub fn value(&self, t_s: f64) -> f64 {
        pulses(t_s, self.amplitude, self.pulse_s, &[1.0, 1.0], &[1.0, -1.0])
    }
}

impl Input3211 {
    /// Check the fields.
    pub fn check(&self) -> Result<()> {
        check_range("3211.amplitude", self.amplitude, -1e6, 1e6)?;
        check_range("3211.pulse_s", self.pulse_s, 1e-4, 1e5)?;
        Ok(())
    }
    /// Length, s.
    pub fn duration_s(&self) -> f64 {
        7.0 * self.pulse_s
    }
    /// The input at `t_s` after the start.
    pub fn value(&self, t_s: f64) -> f64 {
        pulses(
            t_s,
            self.amplitude,
            self.pulse_s,
            &[3.0, 2.0, 1.0, 1.0],
            &[1.0, -1.0, 1.0, -1.0],
        )
    }
}

/// Any of the flight-test inputs, tagged by `kind` in TOML/JSON
/// (`sweep`, `multisine`, `doublet`, `3211`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Input {
    /// [`Sweep`].
    Sweep(Sweep),
    /// [`Multisine`].
    Multisine(Multisine),
    /// [`Doublet`].
    Doublet(Doublet),
    /// [`Input3211`].
    #[serde(rename = "3211")]
    I3211(Input3211),
}

impl Input {
    /// Check (and for a multisine prepare) the input.
    pub fn prepare(&mut self) -> Result<()> {
        match self {
            Input::Sweep(s) => s.check(),
            Input::Multisine(m) => m.prepare(),
            Input::Doublet(d) => d.check(),
            Input::I3211(d) => d.check(),
        }
    }
    /// Length, s.
    pub fn duration_s(&self) -> f64 {
        match self {
            Input::Sweep(s) => s.duration_s,
            Input::Multisine(m) => m.duration_s(),
            Input::Doublet(d) => d.duration_s(),
            Input::I3211(d) => d.duration_s(),
        }
    }
    /// The input at `t_s` after its start (zero outside).
    pub fn value(&self, t_s: f64) -> f64 {
        match self {
            Input::Sweep(s) => s.value(t_s),
            Input::Multisine(m) => m.value(t_s),
            Input::Doublet(d) => d.value(t_s),
            Input::I3211(d) => d.value(t_s),
        }
    }
    /// Sampled every `dt_s` from 0 to the end of the record (inclusive of the
    /// last whole sample).
    pub fn sample(&self, dt_s: f64) -> Vec<f64> {
        let n = (self.duration_s() / dt_s).floor() as usize + 1;
        (0..n).map(|i| self.value(i as f64 * dt_s)).collect()
    }
}
