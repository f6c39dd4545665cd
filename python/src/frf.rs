//! Frequency responses from time histories, as `helicon ident frf`
//! computes them from a log's columns: a uniform sample time (an irregular
//! time column resampled linearly at its median step, refused when it goes
//! backwards or has a gap over 5 steps), Hann windows of record/2,
//! record/4, … (`windows` of them, ≥ 32 samples, each with enough averages
//! for the inputs), the cross spectra on a log-spaced grid, the responses
//! conditioned on the other inputs, and their composite over the windows.

use crate::error::{Error, Result};
use helicon_ident::frf::{WindowSpec, composite, conditioned, cross_spectra_grid, log_grid};
use std::f64::consts::PI;

/// Settings of [`frf`] (the CLI's flags and defaults).
#[derive(Debug, Clone, PartialEq)]
pub struct FrfOptions {
    /// Lowest frequency, rad/s (default: two periods in the longest window).
    pub omega_min: Option<f64>,
    /// Highest frequency, rad/s (default: 0.4 × the Nyquist frequency).
    pub omega_max: Option<f64>,
    /// Frequency points, log spaced (2 … 10000).
    pub points: usize,
    /// Window lengths composited: record/2, record/4, … (1 … 8).
    pub windows: usize,
    /// Longest window used, s.
    pub max_window_s: Option<f64>,
}

impl Default for FrfOptions {
    fn default() -> Self {
        FrfOptions {
            omega_min: None,
            omega_max: None,
            points: 200,
            windows: 5,
            max_window_s: None,
        }
    }
}

/// One response: the columns of `frf.csv`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Response {
    /// ω, rad/s.
    pub omega_rad_s: Vec<f64>,
    /// |H|, dB.
    pub mag_db: Vec<f64>,
    /// ∠H, degrees, unwrapped.
    pub phase_deg: Vec<f64>,
    /// γ², 0 … 1.
    pub coherence: Vec<f64>,
    /// Normalised random error ε.
    pub random_error: Vec<f64>,
}

/// The sample time of `t`; an irregular `t` resamples `cols` in place.
fn uniform(t: &[f64], cols: &mut [Vec<f64>]) -> Result<f64> {
    if t.len() < 2 {
        return Err(Error::new(format!(
            "t: {} sample(s); need a record",
            t.len()
        )));
    }
    if let Some(i) = t.iter().position(|v| !v.is_finite()) {
        return Err(Error::new(format!("t[{i}] = {} is not finite", t[i])));
    }
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if let Some(i) = steps.iter().position(|d| d.is_nan() || *d <= 0.0) {
        return Err(Error::new(format!(
            "t does not increase at index {} ({} then {})",
            i + 1,
            t[i],
            t[i + 1]
        )));
    }
    steps.sort_by(f64::total_cmp);
    let dt = steps[steps.len() / 2];
    let (lo, hi) = (steps[0], steps[steps.len() - 1]);
    if hi > 5.0 * dt {
        return Err(Error::new(format!(
            "t has a gap of {hi} s (the median step is {dt} s): a drop-out the spectra cannot bridge; cut the record"
        )));
    }
    if hi - lo <= 1e-6 * dt {
        return Ok(dt);
    }
    let n = ((t[t.len() - 1] - t[0]) / dt).floor() as usize + 1;
    for c in cols.iter_mut() {
        let old = std::mem::take(c);
        let mut j = 0;
        for k in 0..n {
            let tk = t[0] + k as f64 * dt;
            while j + 2 < t.len() && t[j + 1] < tk {
                j += 1;
            }
            let f = ((tk - t[j]) / (t[j + 1] - t[j])).clamp(0.0, 1.0);
            c.push(old[j] + f * (old[j + 1] - old[j]));
        }
    }
    Ok(dt)
}

/// The window lengths (samples) of the CLI.
fn window_lengths(o: &FrfOptions, n: usize, dt: f64, nin: usize) -> Result<Vec<usize>> {
    if let Some(m) = o.max_window_s
        && !(m.is_finite() && m > 0.0)
    {
        return Err(Error::new(format!(
            "max_window_s = {m}: must be finite and > 0"
        )));
    }
    let mut lens = Vec::new();
    let mut left_out = Vec::new();
    for l in (1..=o.windows).map(|k| n >> k).filter(|l| *l >= 32) {
        let secs = l as f64 * dt;
        if let Some(m) = o.max_window_s
            && secs > m
        {
            left_out.push(format!("{secs:.3} s (over max_window_s)"));
            continue;
        }
        let nd = WindowSpec::half_overlap(l)
            .effective_averages(n)
            .unwrap_or(0.0);
        if nd < nin as f64 {
            left_out.push(format!("{secs:.3} s ({nd:.2} averages)"));
            continue;
        }
        lens.push(l);
    }
    if lens.is_empty() {
        if left_out.is_empty() {
            return Err(Error::new(format!(
                "{n} samples: too short for a 32-sample window"
            )));
        }
        return Err(Error::new(format!(
            "no window qualifies: {} ({nin} input(s) need at least {nin} effective averages per window); raise windows for shorter windows, or condition on fewer inputs",
            left_out.join(", ")
        )));
    }
    Ok(lens)
}

/// The responses of each of `outputs` to `input`, conditioned on
/// `conditioned_on`, all sampled at the times `t` (s). Every channel must
/// have `t`'s length and be finite.
pub fn frf(
    t: &[f64],
    input: &[f64],
    conditioned_on: &[&[f64]],
    outputs: &[&[f64]],
    o: &FrfOptions,
) -> Result<Vec<Response>> {
    if o.windows == 0 || o.windows > 8 {
        return Err(Error::new(format!(
            "windows = {}: must be 1 … 8",
            o.windows
        )));
    }
    if o.points < 2 || o.points > 10_000 {
        return Err(Error::new(format!(
            "points = {}: must be 2 … 10000",
            o.points
        )));
    }
    if outputs.is_empty() {
        return Err(Error::new("no output channel"));
    }
    let named = std::iter::once(("u", input))
        .chain(conditioned_on.iter().map(|c| ("conditioned_on", *c)))
        .chain(outputs.iter().map(|c| ("y", *c)));
    let mut cols = Vec::new();
    for (what, c) in named {
        if c.len() != t.len() {
            return Err(Error::new(format!(
                "{what}: {} samples, t has {}",
                c.len(),
                t.len()
            )));
        }
        if let Some(i) = c.iter().position(|v| !v.is_finite()) {
            return Err(Error::new(format!("{what}[{i}] = {} is not finite", c[i])));
        }
        cols.push(c.to_vec());
    }
    let dt = uniform(t, &mut cols)?;
    let n = cols[0].len();
    let nin = 1 + conditioned_on.len();
    let lens = window_lengths(o, n, dt, nin)?;
    let omega_min = o.omega_min.unwrap_or(4.0 * PI / (lens[0] as f64 * dt));
    let omega_max = o.omega_max.unwrap_or(0.4 * PI / dt);
    let nyquist = PI / dt;
    if omega_max > nyquist {
        return Err(Error::new(format!(
            "omega_max = {omega_max}: above the Nyquist frequency π/dt = {nyquist} rad/s (sample time {dt} s)"
        )));
    }
    let grid = log_grid(omega_min, omega_max, o.points).map_err(|e| {
        Error::from(e).context(&format!("omega_min {omega_min} and omega_max {omega_max}"))
    })?;
    let chans: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    let inputs: Vec<usize> = (0..nin).collect();
    let mut per_output = vec![Vec::new(); outputs.len()];
    for &l in &lens {
        let cs = cross_spectra_grid(&chans, dt, WindowSpec::half_overlap(l), &grid)
            .map_err(|e| Error::from(e).context(&format!("window of {l} samples")))?;
        for (k, parts) in per_output.iter_mut().enumerate() {
            let (mut f, _) = conditioned(&cs, &inputs, nin + k)
                .map_err(|e| Error::from(e).context(&format!("output {k}")))?;
            if f.is_empty() {
                return Err(Error::new(format!("output {k}: no response")));
            }
            parts.push(f.swap_remove(0));
        }
    }
    let secs: Vec<f64> = lens.iter().map(|l| *l as f64 * dt).collect();
    let mut out = Vec::with_capacity(outputs.len());
    for (k, parts) in per_output.iter().enumerate() {
        let f =
            composite(parts, &secs).map_err(|e| Error::from(e).context(&format!("output {k}")))?;
        let r = Response {
            mag_db: f.mag_db(),
            phase_deg: f.phase_deg(),
            omega_rad_s: f.omega_rad_s,
            coherence: f.coherence,
            random_error: f.random_error,
        };
        for (j, w) in r.omega_rad_s.iter().enumerate() {
            let row = [
                w,
                &r.mag_db[j],
                &r.phase_deg[j],
                &r.coherence[j],
                &r.random_error[j],
            ];
            if row.iter().any(|v| !v.is_finite()) {
                return Err(Error::new(format!(
                    "output {k} at {w} rad/s: a non-finite value (zero response?)"
                )));
            }
        }
        out.push(r);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = 2·u of a random-ish input: |H| = 6 dB at every frequency.
    #[test]
    fn a_gain_of_two() {
        let n = 4096;
        let dt = 0.01;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
        let mut s: u64 = 7;
        let u: Vec<f64> = (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let y: Vec<f64> = u.iter().map(|v| 2.0 * v).collect();
        let r = frf(&t, &u, &[], &[&y], &FrfOptions::default()).unwrap();
        assert_eq!(r[0].omega_rad_s.len(), 200);
        assert!(
            r[0].mag_db
                .iter()
                .all(|m| (m - 20.0 * 2f64.log10()).abs() < 1e-9)
        );
        assert!(r[0].coherence.iter().all(|c| *c > 0.999));
    }

    #[test]
    fn bad_records_are_refused() {
        let t = [0.0, 0.1, 0.1, 0.3];
        let e = frf(&t, &[0.0; 4], &[], &[&[0.0; 4]], &FrfOptions::default()).unwrap_err();
        assert!(e.message().contains("does not increase"), "{e}");
        let t: Vec<f64> = (0..10).map(f64::from).collect();
        let e = frf(&t, &[0.0; 9], &[], &[&[0.0; 10]], &FrfOptions::default()).unwrap_err();
        assert!(e.message().contains("u: 9 samples"), "{e}");
        let e = frf(&t, &[0.0; 10], &[], &[&[0.0; 10]], &FrfOptions::default()).unwrap_err();
        assert!(e.message().contains("too short"), "{e}");
        let mut y = vec![0.0; 10];
        y[3] = f64::NAN;
        let e = frf(&t, &[0.0; 10], &[], &[&y], &FrfOptions::default()).unwrap_err();
        assert!(e.message().contains("y[3]"), "{e}");
    }
}
