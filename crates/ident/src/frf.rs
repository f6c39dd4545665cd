//! Frequency responses from time histories: the cross-spectral matrix of
//! several channels with overlapped periodic-Hann windows (on the FFT bins,
//! [`cross_spectra_fft`], exactly SciPy's `csd` conventions; or on any
//! frequency grid, [`cross_spectra_grid`]), the conditioned multi-input
//! responses with partial coherences and random errors ([`conditioned`],
//! [`siso`] for one input) and the composite of several window lengths
//! ([`composite`]).
//!
//! Conventions: G_ij = (2/(f_s Σw²)) · mean over segments of conj(X_i) X_j
//! (one-sided density per Hz; the DC and Nyquist FFT bins are not doubled),
//! each segment's mean removed, so H = G_xy / G_xx. Coherences are γ²
//! (0 … 1). The random error ε is the normalised standard deviation of |H|
//! (Bendat & Piersol): ε = √(1 − γ²_{iy·r}) / (|γ_{iy·r}| √(2 (n_d − q + 1)))
//! with γ²_{iy·r} the partial coherence of input i given the others (the
//! ordinary coherence for one input), q the number of inputs and n_d the
//! effective number of
//! independent averages of the overlapped windows (Welch 1967). The phase
//! error is ε rad; the magnitude error is ≈ 8.686 ε dB.

use crate::error::{IdentError, Result};
use crate::spectral::hann;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

/// The taper applied to each window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Taper {
    /// Periodic Hann, each window's mean removed (the default: overlapped
    /// windows of random or multi-sine data).
    Hann,
    /// None, and the mean kept: for one window over a whole record that
    /// starts and ends at rest
    /// (a sweep with fades), where Y = H·X holds exactly and a taper would
    /// only bias the estimate (a Hann taper varies across the system's
    /// memory: ~1 % near a lightly damped resonance, measured in the tests).
    Rectangular,
    /// Flat, with raised-cosine tapers of this many samples at each end,
    /// the mean level under the tapers removed: for one window around one sweep of a
    /// record that is not at rest at its ends (closed loop, turbulence).
    /// Set the tapers where the sweep has not yet started or has ended and
    /// the system has settled: the window is then 1 over everything the
    /// sweep excites, so Y = H·X holds there as for a whole record, and the
    /// tapers keep the record's slow motion at the window's edges from
    /// leaking across the band. A Hann window instead varies across the
    /// system's memory everywhere, a bias of ~0.1 dB that repeats with the
    /// sweep (`helicon-paramid`'s docs measure it).
    Tukey(usize),
}

/// The analysis window: `len` samples, consecutive windows sharing `overlap`
/// samples (CIFER and Welch use half: `len / 2`), tapered by `taper`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WindowSpec {
    /// Window length, samples (≥ 4).
    pub len: usize,
    /// Samples shared by consecutive windows (< `len`).
    pub overlap: usize,
    /// The taper.
    pub taper: Taper,
}

impl WindowSpec {
    /// A Hann window of `len` samples with half overlap.
    pub fn half_overlap(len: usize) -> Self {
        Self {
            len,
            overlap: len / 2,
            taper: Taper::Hann,
        }
    }

    /// One untapered window over a whole record of `len` samples.
    pub fn whole_record(len: usize) -> Self {
        Self {
            len,
            overlap: 0,
            taper: Taper::Rectangular,
        }
    }

    /// The effective number of independent averages n_d these windows give
    /// on a record of `n_samples` (what [`CrossSpectra::n_d`] will hold), or
    /// `None` when the window is invalid or longer than the record. A
    /// conditioned response on q inputs needs n_d ≥ q ([`conditioned`]).
    pub fn effective_averages(&self, n_samples: usize) -> Option<f64> {
        if self.len < 4 || self.overlap >= self.len || n_samples < self.len {
            return None;
        }
        let step = self.len - self.overlap;
        let k = (n_samples - self.len) / step + 1;
        Some(effective_averages(&self.weights(), step, k))
    }

    /// One flat window of `len` samples with raised-cosine tapers of
    /// `taper` samples at each end ([`Taper::Tukey`]).
    pub fn flat_top(len: usize, taper: usize) -> Self {
        Self {
            len,
            overlap: 0,
            taper: Taper::Tukey(taper),
        }
    }

    /// The window's weights.
    pub fn weights(&self) -> Vec<f64> {
        match self.taper {
            Taper::Hann => hann(self.len),
            Taper::Rectangular => vec![1.0; self.len],
            Taper::Tukey(t) => tukey(self.len, t),
        }
    }
}

/// A flat window of `len` samples, 1 except for raised-cosine tapers of
/// `taper` samples at each end (`taper` is capped at half the window):
/// w[n] = ½(1 − cos(πn/taper)) for n < taper, mirrored at the other end.
pub fn tukey(len: usize, taper: usize) -> Vec<f64> {
    let t = taper.min(len / 2);
    (0..len)
        .map(|n| {
            let j = n.min(len - 1 - n);
            if j >= t {
                1.0
            } else {
                0.5 * (1.0 - (PI * j as f64 / t as f64).cos())
            }
        })
        .collect()
}

/// The averaged cross-spectral matrix of several channels on a frequency grid.
#[derive(Debug, Clone)]
pub struct CrossSpectra {
    /// Frequencies, rad/s.
    pub omega_rad_s: Vec<f64>,
    /// Number of channels.
    pub n_channels: usize,
    /// G, frequency-major then row-major n×n: G[k][i][j] = scaled mean conj(X_i) X_j.
    g: Vec<Complex64>,
    /// Number of windows averaged.
    pub segments: usize,
    /// Effective number of independent averages (≤ `segments` with overlap).
    pub n_d: f64,
    /// Window length, s.
    pub window_s: f64,
}

impl CrossSpectra {
    /// G_ij at frequency index `k` (units of channel i × channel j per Hz).
    pub fn get(&self, k: usize, i: usize, j: usize) -> Complex64 {
        let n = self.n_channels;
        self.g[k * n * n + i * n + j]
    }
}

impl CrossSpectra {
    /// The spectra of several records of the same channels on the same grid
    /// (separate experiments: one sweep per input, each from rest) merged as
    /// one average over all their windows. This is how correlated or
    /// one-at-a-time inputs become separable: each record alone may have a
    /// singular input matrix (a single whole-record window is rank one).
    pub fn merge(parts: &[CrossSpectra]) -> Result<CrossSpectra> {
        let first = parts
            .first()
            .ok_or_else(|| IdentError::data("merge", "no spectra given"))?;
        if parts
            .iter()
            .any(|p| p.omega_rad_s != first.omega_rad_s || p.n_channels != first.n_channels)
        {
            return Err(IdentError::data(
                "merge",
                "the spectra differ in frequency grid or channel count",
            ));
        }
        let total: usize = parts.iter().map(|p| p.segments).sum();
        let mut g = vec![Complex64::new(0.0, 0.0); first.g.len()];
        for p in parts {
            let wgt = p.segments as f64 / total as f64;
            g.iter_mut().zip(&p.g).for_each(|(a, b)| *a += b * wgt);
        }
        Ok(CrossSpectra {
            omega_rad_s: first.omega_rad_s.clone(),
            n_channels: first.n_channels,
            g,
            segments: total,
            n_d: parts.iter().map(|p| p.n_d).sum(),
            window_s: parts.iter().map(|p| p.window_s).fold(0.0, f64::max),
        })
    }
}

/// Check the channels and window; the segment starts and per-segment means.
fn prepare(channels: &[&[f64]], dt_s: f64, spec: WindowSpec) -> Result<(Vec<usize>, Vec<f64>)> {
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(IdentError::invalid("dt_s", dt_s, "must be finite and > 0"));
    }
    let n = channels.first().map_or(0, |c| c.len());
    if channels.is_empty() {
        return Err(IdentError::data("channels", "none given"));
    }
    for (c, x) in channels.iter().enumerate() {
        if x.len() != n {
            return Err(IdentError::data(
                format!("channel {c}"),
                format!("{} samples where channel 0 has {n}", x.len()),
            ));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(IdentError::data(
                format!("channel {c}"),
                format!("sample {i} is not finite"),
            ));
        }
    }
    if spec.len < 4 || spec.overlap >= spec.len {
        return Err(IdentError::invalid(
            "window.len",
            spec.len as f64,
            format!("≥ 4 samples and more than the overlap ({})", spec.overlap),
        ));
    }
    if n < spec.len {
        return Err(IdentError::data(
            "channels",
            format!("{n} samples, shorter than one window of {}", spec.len),
        ));
    }
    let step = spec.len - spec.overlap;
    let starts: Vec<usize> = (0..=(n - spec.len) / step).map(|s| s * step).collect();
    let mut means = Vec::with_capacity(starts.len() * channels.len());
    for &s in &starts {
        for x in channels {
            // The whole-record window keeps the mean: removing it would break
            // Y = H·X off the FFT bins.
            means.push(match spec.taper {
                Taper::Hann => x[s..s + spec.len].iter().sum::<f64>() / spec.len as f64,
                // the level under the tapers, where the record is at rest
                // (or as near as it gets): Y = H·X then holds across the
                // flat part, which a whole-window mean would break
                Taper::Tukey(t) => edge_mean(&x[s..s + spec.len], t),
                Taper::Rectangular => 0.0,
            });
        }
    }
    Ok((starts, means))
}

/// The mean of `w` under tapers of `t` samples at each end (at least 1 and
/// at most half of `w`): the record's level where the window is at rest.
fn edge_mean(w: &[f64], t: usize) -> f64 {
    let n = w.len();
    let t = t.clamp(1, (n / 2).max(1));
    (w[..t].iter().sum::<f64>() + w[n - t..].iter().sum::<f64>()) / (2 * t) as f64
}

/// Effective number of independent averages of `k` windows `w` shifted by
/// `step` samples (Welch 1967, eq. for overlapped segments):
/// 1/n_d = (1/k)[1 + 2 Σ_{m=1}^{k−1} (1 − m/k) ρ(m·step)²],
/// ρ(s) = Σ w[n]w[n+s] / Σ w².
fn effective_averages(w: &[f64], step: usize, k: usize) -> f64 {
    let wss: f64 = w.iter().map(|v| v * v).sum();
    let mut sum = 1.0;
    for m in 1..k {
        let s = m * step;
        if s >= w.len() {
            break;
        }
        let rho: f64 = w[..w.len() - s]
            .iter()
            .zip(&w[s..])
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / wss;
        sum += 2.0 * (1.0 - m as f64 / k as f64) * rho * rho;
    }
    k as f64 / sum
}

/// Add conj(X_i) X_j × `scale` to the n×n block `g`.
fn accumulate(g: &mut [Complex64], x: &[Complex64], scale: f64) {
    let n = x.len();
    for i in 0..n {
        let xi = x[i].conj() * scale;
        for j in 0..n {
            g[i * n + j] += xi * x[j];
        }
    }
}

/// The cross-spectral matrix on the FFT bins ω_k = 2πk/(len·dt),
/// k = 0 … len/2, identical in convention to SciPy's
/// `csd(x_i, x_j, fs, window="hann", nperseg=len, noverlap=overlap,
/// detrend="constant", scaling="density")` (whose result is conj(X_i) X_j).
pub fn cross_spectra_fft(channels: &[&[f64]], dt_s: f64, spec: WindowSpec) -> Result<CrossSpectra> {
    let (starts, means) = prepare(channels, dt_s, spec)?;
    let (l, nc) = (spec.len, channels.len());
    let nf = l / 2 + 1;
    let w = spec.weights();
    let wss: f64 = w.iter().map(|v| v * v).sum();
    let plan = FftPlanner::new().plan_fft_forward(l);
    let mut bufs = vec![Complex64::new(0.0, 0.0); l * nc];
    let mut scratch = vec![Complex64::new(0.0, 0.0); plan.get_inplace_scratch_len()];
    let mut g = vec![Complex64::new(0.0, 0.0); nf * nc * nc];
    let mut xk = vec![Complex64::new(0.0, 0.0); nc];
    let kseg = starts.len() as f64;
    for (s, &start) in starts.iter().enumerate() {
        for (c, x) in channels.iter().enumerate() {
            let m = means[s * nc + c];
            let buf = &mut bufs[c * l..(c + 1) * l];
            for i in 0..l {
                buf[i] = Complex64::new((x[start + i] - m) * w[i], 0.0);
            }
            plan.process_with_scratch(buf, &mut scratch);
        }
        for k in 0..nf {
            for c in 0..nc {
                xk[c] = bufs[c * l + k];
            }
            let one_sided = if k == 0 || 2 * k == l { 1.0 } else { 2.0 };
            let scale = one_sided * dt_s / wss / kseg;
            accumulate(&mut g[k * nc * nc..(k + 1) * nc * nc], &xk, scale);
        }
    }
    Ok(CrossSpectra {
        omega_rad_s: (0..nf)
            .map(|k| 2.0 * PI * k as f64 / (l as f64 * dt_s))
            .collect(),
        n_channels: nc,
        g,
        segments: starts.len(),
        n_d: effective_averages(&w, l - spec.overlap, starts.len()),
        window_s: l as f64 * dt_s,
    })
}

/// (Σ x·a, Σ x·b) over equal-length slices, eight independent accumulators
/// per sum so the compiler can vectorise and pipeline (a single running sum
/// is bound by the add latency: 6× slower, measured).
fn dot2(x: &[f64], a: &[f64], b: &[f64]) -> (f64, f64) {
    const L: usize = 8;
    let (mut sa, mut sb) = ([0.0; L], [0.0; L]);
    let (xc, ac, bc) = (x.chunks_exact(L), a.chunks_exact(L), b.chunks_exact(L));
    let (xr, ar, br) = (xc.remainder(), ac.remainder(), bc.remainder());
    for ((xv, av), bv) in xc.zip(ac).zip(bc) {
        for i in 0..L {
            sa[i] += xv[i] * av[i];
            sb[i] += xv[i] * bv[i];
        }
    }
    let (mut ra, mut rb) = (sa.iter().sum::<f64>(), sb.iter().sum::<f64>());
    for ((xv, av), bv) in xr.iter().zip(ar).zip(br) {
        ra += xv * av;
        rb += xv * bv;
    }
    (ra, rb)
}

/// Samples between exact re-evaluations of the rotating phasor (bounds its
/// rounding drift to ~1e-13).
const REANCHOR: usize = 256;

/// The cross-spectral matrix on any frequency grid `omega_rad_s` (each ≥ 0,
/// below the Nyquist frequency π/dt): each window's DFT evaluated directly at
/// the grid frequencies, `X(ω) = Σ w[n](x[n] − x̄) e^{−iωn·dt}`, so that on the
/// FFT bins it equals [`cross_spectra_fft`] (every ω > 0 counted one-sided).
/// Cost ∝ grid points × samples × channels: a 200-point grid is as fast as
/// a chirp-z transform would be and needs no padding or interpolation.
pub fn cross_spectra_grid(
    channels: &[&[f64]],
    dt_s: f64,
    spec: WindowSpec,
    omega_rad_s: &[f64],
) -> Result<CrossSpectra> {
    let (starts, means) = prepare(channels, dt_s, spec)?;
    let nyquist = PI / dt_s;
    if let Some(w) = omega_rad_s
        .iter()
        .find(|w| !(w.is_finite() && **w >= 0.0 && **w <= nyquist))
    {
        return Err(IdentError::invalid(
            "omega_rad_s",
            *w,
            format!("grid frequencies must be in [0, π/dt = {nyquist}] rad/s"),
        ));
    }
    let (l, nc) = (spec.len, channels.len());
    let w = spec.weights();
    let wss: f64 = w.iter().map(|v| v * v).sum();
    let mut g = vec![Complex64::new(0.0, 0.0); omega_rad_s.len() * nc * nc];
    let kseg = starts.len() as f64;
    // Frequencies are independent: spread over the rayon pool.
    g.par_chunks_mut(nc * nc)
        .zip(omega_rad_s.par_iter())
        .for_each_init(
            || {
                (
                    vec![0.0; l],
                    vec![0.0; l],
                    vec![Complex64::new(0.0, 0.0); nc],
                )
            },
            |(kr, ki, xk), (gk, &om)| {
                let theta = om * dt_s;
                let (ds, dc) = theta.sin_cos();
                let (mut c, mut s) = (1.0, 0.0);
                for n in 0..l {
                    if n % REANCHOR == 0 {
                        (s, c) = (theta * n as f64).sin_cos();
                    }
                    kr[n] = w[n] * c;
                    ki[n] = -w[n] * s;
                    (c, s) = (c * dc - s * ds, s * dc + c * ds);
                }
                let (sr, si): (f64, f64) = (kr.iter().sum(), ki.iter().sum());
                let one_sided = if om > 0.0 { 2.0 } else { 1.0 };
                let scale = one_sided * dt_s / wss / kseg;
                for (sg, &start) in starts.iter().enumerate() {
                    for (ch, x) in channels.iter().enumerate() {
                        let (re, im) = dot2(&x[start..start + l], kr, ki);
                        let m = means[sg * nc + ch];
                        xk[ch] = Complex64::new(re - m * sr, im - m * si);
                    }
                    accumulate(gk, xk, scale);
                }
            },
        );
    Ok(CrossSpectra {
        omega_rad_s: omega_rad_s.to_vec(),
        n_channels: nc,
        g,
        segments: starts.len(),
        n_d: effective_averages(&w, l - spec.overlap, starts.len()),
        window_s: l as f64 * dt_s,
    })
}

/// A frequency response from one input to one output (`Frf::default()`:
/// no points yet).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Frf {
    /// Frequencies, rad/s (increasing).
    pub omega_rad_s: Vec<f64>,
    /// H(jω), output unit per input unit.
    pub h: Vec<Complex64>,
    /// γ² (ordinary for one input, partial for a conditioned input), 0 … 1.
    pub coherence: Vec<f64>,
    /// Normalised random error ε of |H| (and of ∠H in rad).
    pub random_error: Vec<f64>,
}

impl Frf {
    /// |H| in dB.
    pub fn mag_db(&self) -> Vec<f64> {
        self.h.iter().map(|h| 20.0 * h.norm().log10()).collect()
    }

    /// ∠H in degrees, unwrapped along the frequency axis outward from the
    /// most coherent point, whose phase lies in (−180, 180].
    pub fn phase_deg(&self) -> Vec<f64> {
        let raw: Vec<f64> = self.h.iter().map(|h| h.arg().to_degrees()).collect();
        // unwrapped outward from the most coherent point (its phase in
        // (−180°, 180°]): the turns noisy, incoherent points pick up stay
        // among them instead of shifting the coherent band
        let coh = |k: usize| {
            self.coherence
                .get(k)
                .copied()
                .filter(|c| c.is_finite())
                .unwrap_or(-1.0)
        };
        let Some(k0) = (0..raw.len()).max_by(|&a, &b| coh(a).total_cmp(&coh(b))) else {
            return Vec::new();
        };
        let up = unwrap_deg(&raw[k0..]);
        let down: Vec<f64> = raw[..=k0].iter().rev().copied().collect();
        let mut out: Vec<f64> = unwrap_deg(&down).into_iter().rev().collect();
        out.extend_from_slice(&up[1..]);
        out
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.omega_rad_s.len()
    }

    /// No points.
    pub fn is_empty(&self) -> bool {
        self.omega_rad_s.is_empty()
    }

    /// The points at indices `keep`, in that order (an index beyond the
    /// last point is skipped).
    pub fn select(&self, keep: &[usize]) -> Frf {
        let keep: Vec<usize> = keep.iter().copied().filter(|&k| k < self.len()).collect();
        Frf {
            omega_rad_s: keep.iter().map(|&k| self.omega_rad_s[k]).collect(),
            h: keep.iter().map(|&k| self.h[k]).collect(),
            coherence: keep.iter().map(|&k| self.coherence[k]).collect(),
            random_error: keep.iter().map(|&k| self.random_error[k]).collect(),
        }
    }
}

/// Unwrap a phase in degrees: successive jumps brought into (−180, 180].
pub fn unwrap_deg(p: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(p.len());
    let mut offset = 0.0;
    for (i, v) in p.iter().enumerate() {
        if i > 0 {
            let d: f64 = v + offset - out[i - 1];
            // The whole turns n with d − 360n in (−180, 180].
            offset -= 360.0 * ((d - 180.0) / 360.0).ceil();
        }
        out.push(v + offset);
    }
    out
}

/// One input to one output: [`conditioned`] with one input.
pub fn siso(cs: &CrossSpectra, input: usize, output: usize) -> Result<Frf> {
    let (mut f, _) = conditioned(cs, &[input], output)?;
    f.pop()
        .ok_or_else(|| IdentError::data("frequency response", "no input"))
}

/// Reciprocal condition (smallest over largest |diagonal of the LU factor|,
/// a cheap proxy) below which an input spectral matrix counts as singular.
const SINGULAR_RCOND: f64 = 1e-12;

/// The responses from several (possibly correlated) inputs to one output,
/// each conditioned on the others: H = G_xx⁻¹ G_xy at every frequency, with
/// each input's partial coherence and random error, and the multiple
/// coherence γ²_{y:x} (returned beside, on the grid of `cs`). Points where the
/// inputs' matrix is singular (an input without power, or inputs fully
/// correlated), or where a result is not finite, are left out of that
/// response. Errors on bad channel indices, repeated inputs or too few
/// averages (n_d < q).
pub fn conditioned(
    cs: &CrossSpectra,
    inputs: &[usize],
    output: usize,
) -> Result<(Vec<Frf>, Vec<f64>)> {
    let q = inputs.len();
    let nc = cs.n_channels;
    if q == 0 || inputs.iter().chain([&output]).any(|&c| c >= nc) {
        return Err(IdentError::data(
            "frequency response",
            format!(
                "inputs {inputs:?} and output {output} must be distinct channels of the {nc} given"
            ),
        ));
    }
    for (a, i) in inputs.iter().enumerate() {
        if inputs[..a].contains(i) || *i == output {
            return Err(IdentError::data(
                "frequency response",
                format!("channel {i} given twice"),
            ));
        }
    }
    let dof = cs.n_d - q as f64 + 1.0;
    if dof.is_nan() || dof < 1.0 {
        return Err(IdentError::data(
            "frequency response",
            format!(
                "{:.2} effective averages for {q} inputs: use shorter windows or a longer record",
                cs.n_d
            ),
        ));
    }
    let mut out: Vec<Frf> = (0..q).map(|_| Frf::default()).collect();
    let mut multiple = Vec::with_capacity(cs.omega_rad_s.len());
    for (k, &om) in cs.omega_rad_s.iter().enumerate() {
        let gxx = DMatrix::from_fn(q, q, |a, b| cs.get(k, inputs[a], inputs[b]));
        let gxy = DVector::from_fn(q, |a, _| cs.get(k, inputs[a], output));
        let gyy = cs.get(k, output, output).re;
        let Some(inv) = checked_inverse(&gxx) else {
            multiple.push(0.0);
            continue;
        };
        let h = &inv * &gxy;
        let gamma_mult = (gxy.dotc(&h).re / gyy).clamp(0.0, 1.0);
        multiple.push(if gamma_mult.is_finite() {
            gamma_mult
        } else {
            0.0
        });
        for a in 0..q {
            // Input a conditioned on the others: G_aa·r = 1/(G_xx⁻¹)_aa; the
            // output conditioned on the others: G_yy·r = G_yy − g_ryᴴ G_rr⁻¹ g_ry.
            let g_aa_r = 1.0 / inv[(a, a)].re;
            let gyy_r = if q == 1 {
                gyy
            } else {
                let rest: Vec<usize> = (0..q).filter(|&b| b != a).collect();
                let grr = DMatrix::from_fn(q - 1, q - 1, |i, j| gxx[(rest[i], rest[j])]);
                let gry = DVector::from_fn(q - 1, |i, _| gxy[rest[i]]);
                match checked_inverse(&grr) {
                    Some(ir) => gyy - gry.dotc(&(ir * &gry)).re,
                    None => f64::NAN,
                }
            };
            let partial = (h[a].norm_sqr() * g_aa_r / gyy_r).clamp(0.0, 1.0);
            let eps = (1.0 - partial).sqrt() / (partial.sqrt() * (2.0 * dof).sqrt());
            if h[a].re.is_finite() && h[a].im.is_finite() && partial.is_finite() && eps.is_finite()
            {
                let f = &mut out[a];
                f.omega_rad_s.push(om);
                f.h.push(h[a]);
                f.coherence.push(partial);
                f.random_error.push(eps);
            }
        }
    }
    Ok((out, multiple))
}

/// The inverse of a Hermitian input matrix, `None` when (near) singular.
fn checked_inverse(m: &DMatrix<Complex64>) -> Option<DMatrix<Complex64>> {
    let scale = (0..m.nrows()).map(|i| m[(i, i)].re).fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    let lu = m.clone().lu();
    let u = lu.u();
    let dmin = (0..u.nrows())
        .map(|i| u[(i, i)].norm())
        .fold(f64::INFINITY, f64::min);
    if dmin.is_nan() || dmin <= SINGULAR_RCOND * scale {
        return None;
    }
    let inv = lu.try_inverse()?;
    inv.iter()
        .all(|v| v.re.is_finite() && v.im.is_finite())
        .then_some(inv)
}

/// The composite of responses estimated with several window lengths on one
/// frequency grid (as CIFER's COMPOSITE): at each frequency, the windows
/// that hold at least two of its periods (ω ≥ 4π/T_win) are averaged with
/// weights 1/ε². H and γ² are the weighted means; the random error is the
/// weighted mean of the windows' ε, an upper bound of the standard deviation
/// of the average whatever the correlation between windows (they share the
/// data). `parts[i]` was estimated with windows of `window_s[i]` seconds.
/// Frequencies no window may estimate are left out.
pub fn composite(parts: &[Frf], window_s: &[f64]) -> Result<Frf> {
    if parts.is_empty() || parts.len() != window_s.len() {
        return Err(IdentError::data(
            "composite",
            format!(
                "{} responses for {} window lengths",
                parts.len(),
                window_s.len()
            ),
        ));
    }
    let mut grid: Vec<f64> = parts
        .iter()
        .flat_map(|p| p.omega_rad_s.iter().copied())
        .collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let mut out = Frf::default();
    for om in grid {
        let (mut sw, mut sh, mut sg, mut se) = (0.0, Complex64::new(0.0, 0.0), 0.0, 0.0);
        for (p, &tw) in parts.iter().zip(window_s) {
            if om < 4.0 * PI / tw {
                continue;
            }
            let Ok(i) = p.omega_rad_s.binary_search_by(|v| v.total_cmp(&om)) else {
                continue;
            };
            let e = p.random_error[i].max(1e-12);
            let w = 1.0 / (e * e);
            sw += w;
            sh += p.h[i] * w;
            sg += p.coherence[i] * w;
            se += e * w;
        }
        if sw > 0.0 && sw.is_finite() {
            out.omega_rad_s.push(om);
            out.h.push(sh / sw);
            out.coherence.push(sg / sw);
            out.random_error.push(se / sw);
        }
    }
    if out.is_empty() {
        return Err(IdentError::data(
            "composite",
            "no frequency holds two periods in any window",
        ));
    }
    Ok(out)
}

/// The correlation of two estimates at frequencies `delta_rad_s` apart made
/// with a Hann window `window_s` long: the normalised transform of the
/// squared window, |Σ w²(t) e^{−jδt}| / Σ w²(t) (the covariance of the
/// windowed transforms of white noise at ω and ω + δ), in closed form for the
/// continuous window, w² = 3/8 + ½ cos(Ωt) + ⅛ cos(2Ωt) about its centre,
/// Ω = 2π/T:
/// ρ(δ) = |D(δ) + ⅔[D(δ−Ω) + D(δ+Ω)] + ⅙[D(δ−2Ω) + D(δ+2Ω)]|,
/// D(ν) = sin(νT/2)/(νT/2). It is 1 at δ = 0, 2/3 one bin apart (δ = Ω),
/// 1/6 two bins apart — the textbook correlations of Hann-windowed DFT bins
/// — and 0 at three and more whole bins, with sidelobes below 1 % between.
/// Averaging half-overlapped segments does not change it. NaN for a
/// non-finite `delta_rad_s` or a `window_s` that is not finite and > 0 (so
/// a caller's finiteness check sees it, rather than a correlation of 1).
pub fn hann_correlation(delta_rad_s: f64, window_s: f64) -> f64 {
    if !(delta_rad_s.is_finite() && window_s.is_finite() && window_s > 0.0) {
        return f64::NAN;
    }
    let d = |nu: f64| {
        let x = 0.5 * nu * window_s;
        if x.abs() < 1e-9 { 1.0 } else { x.sin() / x }
    };
    let om = 2.0 * PI / window_s;
    let r = d(delta_rad_s)
        + 2.0 / 3.0 * (d(delta_rad_s - om) + d(delta_rad_s + om))
        + 1.0 / 6.0 * (d(delta_rad_s - 2.0 * om) + d(delta_rad_s + 2.0 * om));
    r.abs().min(1.0)
}

/// The correlation of two estimates at frequencies `delta_rad_s` apart made
/// with one flat window of `window_s` (a [`Taper::Tukey`] window whose
/// tapers are short against it, taken as a rectangle of the same Σw²·dt):
/// |sin(δT/2)/(δT/2)|, the normalised transform of the squared window as in
/// [`hann_correlation`]. NaN for a non-finite `delta_rad_s` or a `window_s`
/// that is not finite and > 0.
pub fn flat_correlation(delta_rad_s: f64, window_s: f64) -> f64 {
    if !(delta_rad_s.is_finite() && window_s.is_finite() && window_s > 0.0) {
        return f64::NAN;
    }
    let x = 0.5 * delta_rad_s * window_s;
    if x.abs() < 1e-9 {
        1.0
    } else {
        (x.sin() / x).abs()
    }
}

/// The correlation of a composite estimate's points at `omega_a_rad_s` and
/// `omega_b_rad_s` (see [`composite`]): the mean of [`hann_correlation`]
/// over the window lengths that hold two periods of both frequencies (the
/// composite's windows there); 0 when none does. NaN when a frequency is
/// not finite and > 0 or a window is not finite and > 0.
pub fn composite_correlation(omega_a_rad_s: f64, omega_b_rad_s: f64, window_s: &[f64]) -> f64 {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !(positive(omega_a_rad_s)
        && positive(omega_b_rad_s)
        && window_s.iter().all(|w| positive(*w)))
    {
        return f64::NAN;
    }
    let lo = omega_a_rad_s.min(omega_b_rad_s);
    let (mut sum, mut n) = (0.0, 0usize);
    for &tw in window_s {
        if lo >= 4.0 * PI / tw {
            sum += hann_correlation((omega_a_rad_s - omega_b_rad_s).abs(), tw);
            n += 1;
        }
    }
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// `n` frequencies spaced logarithmically from `lo` to `hi` rad/s.
pub fn log_grid(lo: f64, hi: f64, n: usize) -> Result<Vec<f64>> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) || n < 2 {
        return Err(IdentError::invalid(
            "omega range",
            lo,
            format!("need 0 < omega_min < omega_max (= {hi}) and ≥ 2 points"),
        ));
    }
    let r = (hi / lo).ln() / (n - 1) as f64;
    Ok((0..n).map(|i| lo * (r * i as f64).exp()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A noisy, incoherent first point does not shift the coherent band by
    /// a turn: the phase is unwrapped outward from the most coherent point.
    #[test]
    fn phase_is_unwrapped_from_the_most_coherent_point() {
        let deg = |d: f64| Complex64::from_polar(1.0, d.to_radians());
        // an incoherent point at 170°, then a coherent band falling from
        // −60° to −120° (the first point's branch would put it at 300°)
        let f = Frf {
            omega_rad_s: vec![1.0, 2.0, 3.0, 4.0, 5.0],
            h: vec![deg(170.0), deg(-60.0), deg(-80.0), deg(-100.0), deg(-120.0)],
            coherence: vec![0.05, 0.9, 0.95, 0.9, 0.9],
            random_error: vec![0.1; 5],
        };
        let p = f.phase_deg();
        for (got, want) in p[1..].iter().zip([-60.0, -80.0, -100.0, -120.0]) {
            assert!((got - want).abs() < 1e-9, "{p:?}");
        }
        // the incoherent point within half a turn of its neighbour
        assert!((p[0] - p[1]).abs() <= 180.0, "{p:?}");
        assert!(Frf::default().phase_deg().is_empty());
    }

    /// Hostile arguments give NaN, never a plausible correlation (before:
    /// a NaN frequency difference gave 1, a NaN frequency 0).
    #[test]
    fn correlations_of_non_finite_or_non_positive_arguments_are_nan() {
        for (d, w) in [
            (f64::NAN, 12.0),
            (f64::INFINITY, 12.0),
            (0.5, 0.0),
            (0.5, -12.0),
            (0.5, f64::NAN),
            (0.5, f64::INFINITY),
        ] {
            assert!(hann_correlation(d, w).is_nan(), "{d} {w}");
        }
        for (a, b, w) in [
            (f64::NAN, 2.0, vec![12.0]),
            (2.0, f64::INFINITY, vec![12.0]),
            (-2.0, 2.0, vec![12.0]),
            (2.0, 2.1, vec![12.0, 0.0]),
            (2.0, 2.1, vec![f64::NAN]),
        ] {
            assert!(composite_correlation(a, b, &w).is_nan(), "{a} {b} {w:?}");
        }
        // the good arguments still give the textbook values
        assert!((hann_correlation(2.0 * PI / 12.0, 12.0) - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(composite_correlation(2.0, 2.0, &[12.0]), 1.0);
    }

    #[test]
    fn hann_correlation_is_the_squared_windows_transform() {
        // against the sum over a sampled Hann window (400 Hz, 12 s): the
        // closed form is for the continuous window, so agreement is to the
        // sampling's O(dt/T) and better
        let (t_w, dt) = (12.0, 1.0 / 400.0);
        let n = (t_w / dt) as usize;
        let w2: Vec<f64> = (0..n)
            .map(|k| (PI * (k as f64 + 0.5) / n as f64).sin().powi(4))
            .collect();
        let total: f64 = w2.iter().sum();
        for delta in [0.0, 0.1, 0.26, 0.52, 0.8, 1.3, 1.57, 2.5] {
            let (mut re, mut im) = (0.0, 0.0);
            for (k, v) in w2.iter().enumerate() {
                let ph = delta * (k as f64 + 0.5) * dt;
                re += v * ph.cos();
                im -= v * ph.sin();
            }
            let sum = (re * re + im * im).sqrt() / total;
            let closed = hann_correlation(delta, t_w);
            assert!((sum - closed).abs() < 1e-4, "δ {delta}: {sum} vs {closed}");
        }
        assert!((hann_correlation(0.0, t_w) - 1.0).abs() < 1e-15);
        // the textbook correlations of Hann-windowed DFT bins: 2/3 one bin
        // apart, 1/6 two bins apart, 0 from three whole bins on
        let bin = 2.0 * PI / t_w;
        assert!((hann_correlation(bin, t_w) - 2.0 / 3.0).abs() < 1e-12);
        assert!((hann_correlation(2.0 * bin, t_w) - 1.0 / 6.0).abs() < 1e-12);
        assert!(hann_correlation(3.0 * bin, t_w) < 1e-12);
        // the composite: windows that do not hold two periods are left out
        assert_eq!(composite_correlation(0.5, 0.6, &[6.0]), 0.0);
        let both = composite_correlation(2.2, 2.3, &[12.0, 6.0]);
        let mean = 0.5 * (hann_correlation(0.1, 12.0) + hann_correlation(0.1, 6.0));
        assert!((both - mean).abs() < 1e-15);
        assert!(
            (composite_correlation(1.5, 1.6, &[12.0, 6.0]) - hann_correlation(0.1, 12.0)).abs()
                < 1e-15
        );
    }

    #[test]
    fn unwrap_removes_jumps() {
        let p = [170.0, -170.0, -150.0, 179.0, -179.0];
        let u = unwrap_deg(&p);
        assert_eq!(u, vec![170.0, 190.0, 210.0, 179.0, 181.0]);
    }

    #[test]
    fn welch_n_d_matches_the_known_hann_figure() {
        // Hann, 50 % overlap: ρ(L/2) = 1/6 exactly (periodic window), so for
        // many segments 1/n_d → (1 + 2/36)/K.
        let w = hann(1024);
        let nd = effective_averages(&w, 512, 1000);
        let expected = 1000.0 / (1.0 + 2.0 * (1.0 - 1.0 / 1000.0) / 36.0);
        assert!((nd - expected).abs() < 1e-6 * expected, "{nd} {expected}");
        assert_eq!(effective_averages(&w, 1024, 7), 7.0);
    }

    #[test]
    fn window_spec_tells_the_averages_the_spectra_will_hold() {
        let x: Vec<f64> = (0..4561).map(|i| (i as f64 * 0.37).sin()).collect();
        for len in [4560 / 2, 4561 / 4, 100] {
            let spec = WindowSpec::half_overlap(len);
            let cs = cross_spectra_grid(&[&x], 0.01, spec, &[1.0, 2.0]).unwrap();
            assert_eq!(spec.effective_averages(x.len()), Some(cs.n_d), "{len}");
        }
        // record/2 on a record of 4561 samples: 2 whole windows, 3 with
        // overlap, below the 4 that four conditioned inputs need
        let nd = WindowSpec::half_overlap(4561 / 2)
            .effective_averages(4561)
            .unwrap();
        assert!(nd > 2.8 && nd < 3.0, "{nd}");
        assert_eq!(
            WindowSpec::half_overlap(5000).effective_averages(4561),
            None
        );
    }

    /// `select` keeps the listed points, in order, every field together,
    /// and skips an index beyond the last.
    #[test]
    fn select_keeps_the_listed_points_of_every_field() {
        let f = Frf {
            omega_rad_s: vec![1.0, 2.0, 3.0],
            h: vec![
                Complex64::new(1.0, 0.0),
                Complex64::new(0.0, 2.0),
                Complex64::new(3.0, 0.0),
            ],
            coherence: vec![0.9, 0.8, 0.7],
            random_error: vec![0.1, 0.2, 0.3],
        };
        let s = f.select(&[2, 0, 7]);
        assert_eq!(s.omega_rad_s, vec![3.0, 1.0]);
        assert_eq!(
            s.h,
            vec![Complex64::new(3.0, 0.0), Complex64::new(1.0, 0.0)]
        );
        assert_eq!(s.coherence, vec![0.7, 0.9]);
        assert_eq!(s.random_error, vec![0.3, 0.1]);
        assert!(f.select(&[]).is_empty());
    }
}
