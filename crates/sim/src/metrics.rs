//! Closed-loop performance metrics per controlled output.
//!
//! For an output with reference r(t) and response y(t), e = r − y (yaw
//! wrapped). The *excitation* is the last reference change before the end
//! (its size and the time it completes) or, without one, the initial error
//! at t = 0. A reference that moves smoothly (a shaped trajectory, a
//! mission's legs) rather than by the scenario's steps and ramps has its
//! last move found in the flown reference itself ([`last_reference_move`]).
//! Then:
//! * `settling_time_s`: time from the excitation until |e| stays within 1 % of
//!   the excitation size (band ≥ 1e-3 in SI units, so an output that was
//!   never excited settles at 0); `None` ("not settled before the end") when
//!   |e| is outside the band at the end of the run or entered it less than
//!   [`MIN_DWELL_S`] before the end;
//! * `overshoot_pct`: the largest excursion past the target, in % of the
//!   excitation size (0 when the response never crosses it);
//! * `rms_error`, `max_abs_error`: over the whole run.

use serde::Serialize;

/// Metrics of one output.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OutputMetrics {
    /// 1 % settling time from the excitation (s), `None` if not settled.
    pub settling_time_s: Option<f64>,
    /// Overshoot past the target (% of the excitation).
    pub overshoot_pct: f64,
    /// RMS of the error over the run.
    pub rms_error: f64,
    /// Largest |error| over the run.
    pub max_abs_error: f64,
    /// Size of the excitation (reference step or initial error).
    pub excitation: f64,
    /// Time of the excitation (s).
    pub excitation_time_s: f64,
}

/// Minimum settling band (SI units): 1 mm/s or 1 mrad.
pub const MIN_BAND: f64 = 1e-3;

/// How long an output must stay in its band before the record ends to count
/// as settled, s: one that enters it in the last second is "not settled
/// before the end", not settled at the record's end.
pub const MIN_DWELL_S: f64 = 1.0;

/// Metrics from time samples `t` and errors `e` (same length), with the
/// excitation at `t_exc` of size `size` (≥ 0). `band_scale` sets the 1 %
/// band of an output that was not excited itself (size below [`MIN_BAND`]):
/// the run's largest excitation, as the thesis's "every state settles within
/// 1 %" of a unit initial condition; its overshoot is reported as 0.
pub fn output_metrics(
    t: &[f64],
    e: &[f64],
    t_exc: f64,
    size: f64,
    band_scale: f64,
) -> OutputMetrics {
    let n = e.len().min(t.len());
    let rms_error = if n == 0 {
        0.0
    } else {
        (e[..n].iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt()
    };
    let max_abs_error = e[..n].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let excited = size >= MIN_BAND;
    let band = if excited {
        0.01 * size
    } else {
        0.01 * band_scale
    }
    .max(MIN_BAND);
    // sign of the approach: the error at the excitation points towards the target
    let k0 = t[..n].iter().position(|&ti| ti >= t_exc).unwrap_or(n);
    let sign0 = if k0 < n && excited {
        e[k0].signum()
    } else {
        0.0
    };
    let mut last_out: Option<usize> = None;
    let mut overshoot: f64 = 0.0;
    for k in k0..n {
        if e[k].abs() > band {
            last_out = Some(k);
        }
        // crossing past the target: the error changes sign relative to the start
        if sign0 != 0.0 && e[k] * sign0 < 0.0 {
            overshoot = overshoot.max(e[k].abs());
        }
    }
    let settled_at_end = n > 0 && e[n - 1].abs() <= band;
    let settling_time_s = if !settled_at_end {
        None
    } else {
        match last_out {
            None => Some(0.0),
            // inside the band only for the record's last moments: not
            // known to stay there (a record that ends early)
            Some(k) if t[n - 1] - t[(k + 1).min(n - 1)] < MIN_DWELL_S => None,
            Some(k) => Some((t[(k + 1).min(n - 1)] - t_exc).max(0.0)),
        }
    };
    OutputMetrics {
        settling_time_s,
        overshoot_pct: if size > 0.0 {
            100.0 * overshoot / size
        } else {
            0.0
        },
        rms_error,
        max_abs_error,
        excitation: size,
        excitation_time_s: t_exc,
    }
}

/// The last move of a flown reference `r(t)` (heading: `wrap` the
/// differences into ±π): the move ends at the last sample where `r`
/// changed and begins where `r` last stood still for [`MIN_DWELL_S`] before
/// it (shorter pauses belong to the move). Returns `(t_start_s, t_end_s,
/// size)`, the size the largest distance of `r` over the move from where it
/// ended (a step from a to b: |b − a|; a turn out and back: how far it went
/// out); `None` when `r` never changed.
pub fn last_reference_move(t: &[f64], r: &[f64], wrap: bool) -> Option<(f64, f64, f64)> {
    let n = t.len().min(r.len());
    let diff = |a: f64, b: f64| {
        let d = a - b;
        if wrap {
            helicon_core::frames::wrap_pi(d)
        } else {
            d
        }
    };
    // a change of a rounding error is no change
    let moved = |k: usize| diff(r[k], r[k - 1]).abs() > 1e-12 * r[k].abs().max(1.0);
    let end = (1..n).rev().find(|&k| moved(k))?;
    let mut start = end - 1;
    let mut k = end;
    while k > 0 {
        if moved(k) {
            start = k - 1;
        } else if t[start] - t[k] >= MIN_DWELL_S {
            break;
        }
        k -= 1;
    }
    let size = (start..=end).fold(0.0f64, |m, i| m.max(diff(r[i], r[end]).abs()));
    Some((t[start], t[end], size))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_move_of_a_smooth_reference_is_found_in_the_flown_reference() {
        let t: Vec<f64> = (0..2001).map(|k| f64::from(k) * 0.01).collect();
        // a ramp 0 → 3 over 2–5 s, held, then out to 1.5 and back over 10–12 s
        // with a 0.5 s pause at the top
        let r: Vec<f64> = t
            .iter()
            .map(|&t| match t {
                t if t < 2.0 => 0.0,
                t if t < 5.0 => t - 2.0,
                t if t < 10.0 => 3.0,
                t if t < 11.0 => 3.0 + 1.5 * (t - 10.0),
                t if t < 11.5 => 4.5,
                t if t < 12.5 => 4.5 - 1.5 * (t - 11.5),
                _ => 3.0,
            })
            .collect();
        let (t0, t1, size) = last_reference_move(&t, &r, false).unwrap();
        assert!(
            (t0 - 10.0).abs() < 0.011 && (t1 - 12.5).abs() < 0.011,
            "{t0} {t1}"
        );
        assert!((size - 1.5).abs() < 0.02, "{size}");
        // the ramp alone
        let (t0, t1, size) = last_reference_move(&t[..900], &r[..900], false).unwrap();
        assert!(
            (t0 - 2.0).abs() < 0.011 && (t1 - 5.0).abs() < 0.011,
            "{t0} {t1}"
        );
        assert!((size - 3.0).abs() < 0.011, "{size}");
        // a heading turned through ±π is a small move, not 2π
        let h = [3.1, 3.12, -3.13, -3.12, -3.12];
        let (_, _, size) = last_reference_move(&[0.0, 1.0, 2.0, 3.0, 4.0], &h, true).unwrap();
        assert!(
            (size - (2.0 * std::f64::consts::PI - 6.22)).abs() < 1e-9,
            "{size}"
        );
        assert!(last_reference_move(&t, &vec![2.0; t.len()], false).is_none());
    }

    #[test]
    fn first_order_step_settles_at_ln_100_tau() {
        // e(t) = exp(−t/τ) after a unit step at t = 1: |e| < 1 % after τ ln 100.
        let tau = 0.5;
        let t: Vec<f64> = (0..4000).map(|k| k as f64 * 0.0025).collect();
        let e: Vec<f64> = t
            .iter()
            .map(|&ti| {
                if ti < 1.0 {
                    0.0
                } else {
                    (-(ti - 1.0) / tau).exp()
                }
            })
            .collect();
        let m = output_metrics(&t, &e, 1.0, 1.0, 1.0);
        let expected = tau * 100f64.ln();
        assert!(
            (m.settling_time_s.unwrap() - expected).abs() < 0.003,
            "{m:?}"
        );
        assert_eq!(m.overshoot_pct, 0.0);
        assert!((m.max_abs_error - 1.0).abs() < 1e-12);
    }

    #[test]
    fn underdamped_overshoot_and_unsettled() {
        // step response of a 2nd-order system: e = 1 − y =
        // exp(−ζωt)(cos ωd t + ζ/√(1−ζ²) sin ωd t); overshoot exp(−ζπ/√(1−ζ²))
        let (z, w): (f64, f64) = (0.3, 4.0);
        let wd = w * (1.0 - z * z).sqrt();
        let t: Vec<f64> = (0..4000).map(|k| k as f64 * 0.0025).collect();
        let c = z / (1.0 - z * z).sqrt();
        let e: Vec<f64> = t
            .iter()
            .map(|&ti| (-z * w * ti).exp() * ((wd * ti).cos() + c * (wd * ti).sin()))
            .collect();
        let m = output_metrics(&t, &e, 0.0, 1.0, 1.0);
        let expected = 100.0 * (-z * std::f64::consts::PI / (1.0 - z * z).sqrt()).exp();
        // sampled at 2.5 ms: the peak is hit to within (ωd·dt)²/2 relative
        assert!(
            (m.overshoot_pct - expected).abs() < 0.05,
            "{} vs {expected}",
            m.overshoot_pct
        );
        // a run that ends outside the band has no settling time
        let m = output_metrics(&t[..200], &e[..200], 0.0, 1.0, 1.0);
        assert!(m.settling_time_s.is_none());
        // nor one that enters it less than MIN_DWELL_S before the end
        let settled = output_metrics(&t, &e, 0.0, 1.0, 1.0)
            .settling_time_s
            .unwrap();
        let k_in = t.iter().position(|&ti| ti >= settled).unwrap();
        let just = ((settled + 0.5 * MIN_DWELL_S) / 0.0025) as usize;
        assert!(
            output_metrics(&t[..just], &e[..just], 0.0, 1.0, 1.0)
                .settling_time_s
                .is_none()
        );
        let later = ((settled + 1.5 * MIN_DWELL_S) / 0.0025) as usize;
        assert!(later < t.len() && k_in < later);
        let m = output_metrics(&t[..later], &e[..later], 0.0, 1.0, 1.0);
        assert!((m.settling_time_s.unwrap() - settled).abs() < 1e-12);
    }
}
