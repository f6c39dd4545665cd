//! Is the measured responses' random error what it claims to be?
//!
//! The fit weighs every frequency point by its random error ε (from the
//! coherence, [`crate::data::instrumented`]) and its Cramér–Rao bounds rest
//! on those weights. ε is a formula; whether it holds for a given flight
//! programme (closed loop, turbulence, sensor chain, sweeps cut by windows)
//! is an empirical question with a simple answer on a simulator: fly the
//! same flight with several turbulence and sensor-noise seeds, estimate the
//! responses of each, and compare the scatter of the estimates across the
//! flights with the ε each estimate claimed.
//!
//! [`calibrate`] does the comparison for every response of every operating
//! point:
//! - `magnitude_ratio`, `phase_ratio`: at each frequency, the standard
//!   deviation over the flights of ln|H| (of ∠H, rad) divided by the RMS
//!   over the flights of ε; then the RMS of that over the frequencies. 1
//!   means ε is right, below 1 conservative, above 1 optimistic.
//! - `common_offset`: for each flight, the mean over the frequencies of its
//!   ln|H| deviation from the flights' mean in units of ε; the RMS of that
//!   over the flights. Errors independent from one point to the next
//!   average out (≈ `magnitude_ratio`/√points, more with the windows'
//!   correlation of neighbouring points); a value near `magnitude_ratio`
//!   means the flight's error is one gain across the whole band, which the
//!   fit absorbs into the parameters and neither the residuals nor ε show.

use crate::data::PointData;
use crate::error::{ParamIdError, Result};

/// How one response's random error compares with its scatter over flights.
#[derive(Debug, Clone, PartialEq)]
pub struct ResponseCalibration {
    /// Operating point.
    pub operating_point: String,
    /// Response label (`output/input`).
    pub label: String,
    /// Frequencies used (ε ≤ the limit in every flight). With none, the
    /// three figures below are NaN: there is nothing to compare.
    pub points: usize,
    /// RMS over frequencies of sd(ln|H|) / rms(ε).
    pub magnitude_ratio: f64,
    /// RMS over frequencies of sd(∠H) / rms(ε).
    pub phase_ratio: f64,
    /// RMS over flights of the mean over frequencies of the ln|H|
    /// deviation in units of ε.
    pub common_offset: f64,
}

fn mismatch(what: String) -> ParamIdError {
    ParamIdError::Fit(format!("random-error calibration: {what}"))
}

/// Compare the scatter of the same responses estimated from several
/// flights (`runs[flight][operating point]`, at least 3 flights, the same
/// points, responses and frequencies in each) with their random errors,
/// using the frequencies where every flight's ε is at most
/// `max_random_error` (ln|H| and ∠H are near Gaussian only for small ε).
pub fn calibrate(
    runs: &[Vec<PointData>],
    max_random_error: f64,
) -> Result<Vec<ResponseCalibration>> {
    if runs.len() < 3 {
        return Err(mismatch(format!(
            "needs at least 3 flights, got {}",
            runs.len()
        )));
    }
    if !(max_random_error.is_finite() && max_random_error > 0.0) {
        return Err(mismatch(format!(
            "max_random_error must be a positive number, got {max_random_error}"
        )));
    }
    let first = &runs[0];
    let mut out = Vec::new();
    for (p, point) in first.iter().enumerate() {
        for (r, resp) in point.responses.iter().enumerate() {
            let omega = &resp.frf.omega_rad_s;
            let mut series = Vec::with_capacity(runs.len());
            for (f, run) in runs.iter().enumerate() {
                let m = run
                    .get(p)
                    .and_then(|pd| pd.responses.get(r))
                    .filter(|m| m.response == resp.response && &m.frf.omega_rad_s == omega)
                    .ok_or_else(|| {
                        mismatch(format!(
                            "flight {f} has not the points, responses and frequencies of flight 0 ({} {})",
                            point.name,
                            resp.response.label()
                        ))
                    })?;
                series.push(&m.frf);
            }
            let n = series.len() as f64;
            let used: Vec<usize> = (0..omega.len())
                .filter(|&k| {
                    series.iter().all(|s| {
                        let e = s.random_error[k];
                        e.is_finite() && e > 0.0 && e <= max_random_error && s.h[k].norm() > 0.0
                    })
                })
                .collect();
            let (mut sum_m, mut sum_p) = (0.0, 0.0);
            let mut offsets = vec![0.0; series.len()];
            for &k in &used {
                let ln: Vec<f64> = series.iter().map(|s| s.h[k].norm().ln()).collect();
                // phase relative to flight 0's, so that no wrap splits them
                let ph: Vec<f64> = series
                    .iter()
                    .map(|s| (s.h[k] / series[0].h[k]).arg())
                    .collect();
                let eps = (series
                    .iter()
                    .map(|s| s.random_error[k].powi(2))
                    .sum::<f64>()
                    / n)
                    .sqrt();
                let (mean_ln, sd_ln) = mean_sd(&ln);
                let (_, sd_ph) = mean_sd(&ph);
                sum_m += (sd_ln / eps).powi(2);
                sum_p += (sd_ph / eps).powi(2);
                for (o, (l, s)) in offsets.iter_mut().zip(ln.iter().zip(&series)) {
                    *o += (l - mean_ln) / s.random_error[k];
                }
            }
            let m = used.len() as f64;
            let common = if used.is_empty() {
                f64::NAN
            } else {
                // deviations from the flights' mean: n/(n−1) for the variance
                (offsets.iter().map(|o| (o / m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            };
            out.push(ResponseCalibration {
                operating_point: point.name.clone(),
                label: resp.response.label(),
                points: used.len(),
                magnitude_ratio: (sum_m / m).sqrt(),
                phase_ratio: (sum_p / m).sqrt(),
                common_offset: common,
            });
        }
    }
    Ok(out)
}

/// Mean and sample standard deviation.
fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::config::Response;
    use crate::data::Measured;
    use helicon_ident::Complex64;
    use helicon_ident::frf::Frf;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// `flights` synthetic estimates of one response, 40 points, ε = 0.02:
    /// each point's ln|H| and ∠H scattered by `scale`·ε independently, plus
    /// one gain per flight of `gain`·ε common to all its points.
    fn synthetic(flights: usize, scale: f64, gain: f64, seed: u64) -> Vec<Vec<PointData>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let omega: Vec<f64> = (0..40).map(|k| 1.5 + 0.5 * k as f64).collect();
        let eps = 0.02;
        (0..flights)
            .map(|_| {
                let g: f64 = StandardNormal.sample(&mut rng);
                let h = omega
                    .iter()
                    .map(|w| {
                        let a: f64 = StandardNormal.sample(&mut rng);
                        let b: f64 = StandardNormal.sample(&mut rng);
                        let h0 = Complex64::new(1.0, 0.0) / Complex64::new(1.0, *w / 5.0);
                        h0 * Complex64::from_polar(
                            (scale * eps * a + gain * eps * g).exp(),
                            scale * eps * b,
                        )
                    })
                    .collect();
                vec![PointData {
                    name: "hover".into(),
                    sample_time_s: 0.0025,
                    responses: vec![Measured {
                        response: Response {
                            input: "S_lat".into(),
                            output: "meas_p".into(),
                            omega_min_rad_s: 1.5,
                            omega_max_rad_s: 21.0,
                        },
                        input: 1,
                        state: 0,
                        frf: Frf {
                            omega_rad_s: omega.clone(),
                            h,
                            coherence: vec![0.99; 40],
                            random_error: vec![eps; 40],
                        },
                    }],
                    sweep_windows_s: Vec::new(),
                }]
            })
            .collect()
    }

    /// Scatter exactly as claimed: both ratios ≈ 1 (40 points × 30 flights:
    /// the ratio's own sampling error is ~2 %, tolerance 10 %), the common
    /// offset ≈ 1/√40 = 0.16 (tolerance 0.1 to 0.25).
    #[test]
    fn calibrated_scatter_gives_ratios_of_one() {
        let c = calibrate(&synthetic(30, 1.0, 0.0, 1), 0.2).unwrap();
        assert_eq!(c.len(), 1);
        let c = &c[0];
        assert_eq!(c.points, 40);
        assert!((c.magnitude_ratio - 1.0).abs() < 0.1, "{c:?}");
        assert!((c.phase_ratio - 1.0).abs() < 0.1, "{c:?}");
        assert!(c.common_offset > 0.1 && c.common_offset < 0.25, "{c:?}");
    }

    /// Twice the claimed scatter reads 2; a per-flight gain of 1.5 ε shows
    /// in the common offset (≈ 1.5) and in the magnitude, not the phase.
    #[test]
    fn optimistic_error_and_a_common_gain_are_seen() {
        let c = &calibrate(&synthetic(30, 2.0, 0.0, 2), 0.2).unwrap()[0];
        assert!((c.magnitude_ratio - 2.0).abs() < 0.2, "{c:?}");
        assert!((c.phase_ratio - 2.0).abs() < 0.2, "{c:?}");
        let c = &calibrate(&synthetic(30, 1.0, 1.5, 3), 0.2).unwrap()[0];
        assert!(c.common_offset > 1.1 && c.common_offset < 2.0, "{c:?}");
        assert!(c.magnitude_ratio > 1.5, "{c:?}");
        assert!((c.phase_ratio - 1.0).abs() < 0.1, "{c:?}");
    }

    #[test]
    fn too_few_flights_or_different_grids_are_refused() {
        let e = calibrate(&synthetic(2, 1.0, 0.0, 4), 0.2).unwrap_err();
        assert!(e.to_string().contains("at least 3 flights"), "{e}");
        let mut runs = synthetic(3, 1.0, 0.0, 5);
        runs[2][0].responses[0].frf.omega_rad_s[3] = 9.9;
        let e = calibrate(&runs, 0.2).unwrap_err();
        assert!(e.to_string().contains("flight 2"), "{e}");
        let e = calibrate(&synthetic(3, 1.0, 0.0, 6), f64::NAN).unwrap_err();
        assert!(e.to_string().contains("max_random_error"), "{e}");
    }
}
