//! Was the input of a frequency response excited? A frequency response
//! H = G_uy / G_uu is the helicopter's only where the input u moved for
//! reasons of its own. In closed loop without an excitation the input moves
//! only in answer to the output (u = −K y + …), so the ratio measures the
//! inverse of the controller, with a high coherence, and nothing warns.
//!
//! [`check_excitation`] looks at three things over the analysis band:
//!
//! - the logged excitation (the signal added to the input from outside the
//!   loop, log.csv's `exc_*` columns), when there is one: its RMS, and the
//!   share of the input's autospectrum coherent with it,
//!   ρ = Σ γ²_eu G_uu / Σ G_uu (1: the input is all excitation, 0: all
//!   feedback);
//! - the input's autospectrum G_uu: the share of the band's frequency points
//!   where it is below [`WEAK_INPUT_RATIO`] of its band maximum (gaps a
//!   sweep or multi-sine did not cover);
//! - the coherence of input and output alone says nothing here (feedback
//!   makes it high), which is why the checks above exist.

use crate::error::{IdentError, Result};
use crate::frf::{WindowSpec, cross_spectra_grid};

/// A point where the input autospectrum is below this fraction of its band
/// maximum (−40 dB) counts as not excited.
pub const WEAK_INPUT_RATIO: f64 = 1e-4;

/// Below this share of the input's band power coherent with the logged
/// excitation, the response is dominated by the feedback.
pub const MIN_COHERENT_SHARE: f64 = 0.3;

/// Above this share of band points with a weak input, the band has gaps.
pub const MAX_WEAK_SHARE: f64 = 0.1;

/// What [`check_excitation`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct ExcitationCheck {
    /// RMS of the logged excitation over the record (its units, those of the
    /// input), when one was given.
    pub excitation_rms: Option<f64>,
    /// The share of the input's band power coherent with the excitation
    /// (0 … 1), when the excitation is not zero.
    pub coherent_share: Option<f64>,
    /// The share of band frequency points where the input autospectrum is
    /// below [`WEAK_INPUT_RATIO`] × its band maximum (0 … 1).
    pub weak_share: f64,
    /// RMS of the input about its mean over the record (input units).
    pub input_rms: f64,
    /// What is wrong, worst first; empty when the input was excited.
    pub problems: Vec<ExcitationProblem>,
}

/// A reason the frequency response may not be the helicopter's.
#[derive(Debug, Clone, PartialEq)]
pub enum ExcitationProblem {
    /// The input does not move at all over the record.
    InputConstant,
    /// The logged excitation is zero throughout: in closed loop the input
    /// moved only in answer to the feedback.
    NoExcitation,
    /// Only this share (0 … 1) of the input's band power is coherent with
    /// the excitation: the feedback dominates.
    FeedbackDominated(f64),
    /// This share (0 … 1) of the band's points has a weak input.
    BandGaps(f64),
}

impl std::fmt::Display for ExcitationProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::InputConstant => f.write_str("the input does not move over the record"),
            Self::NoExcitation => f.write_str(
                "the logged excitation is zero throughout: in closed loop the input moved only in answer to the feedback, so the response measures the controller (its inverse), not the helicopter",
            ),
            Self::FeedbackDominated(s) => write!(
                f,
                "only {:.0} % of the input's power in the band is coherent with the excitation: the feedback dominates, and the response leans towards the controller's inverse",
                100.0 * s
            ),
            Self::BandGaps(s) => write!(
                f,
                "the input autospectrum is more than 40 dB below its maximum at {:.0} % of the band's points: the input did not excite them",
                100.0 * s
            ),
        }
    }
}

fn rms_about_mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let m = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len() as f64).sqrt()
}

/// Check the excitation of `input` (sampled every `dt_s` s) on the frequency
/// grid `omega_rad_s`, with spectra over Hann windows of `window` samples
/// (half overlap); `excitation` is the logged signal added to the input from
/// outside the loop, when the log has one (same length as `input`).
///
/// # Errors
/// [`IdentError`] when the lengths differ or the window does not fit the
/// record (as [`cross_spectra_grid`]).
pub fn check_excitation(
    input: &[f64],
    excitation: Option<&[f64]>,
    dt_s: f64,
    window: usize,
    omega_rad_s: &[f64],
) -> Result<ExcitationCheck> {
    if let Some(e) = excitation
        && e.len() != input.len()
    {
        return Err(IdentError::Data {
            what: "excitation".into(),
            reason: format!("{} samples, the input {}", e.len(), input.len()),
        });
    }
    let input_rms = rms_about_mean(input);
    let scale = input.iter().fold(0.0_f64, |m, v| m.max(v.abs())).max(1.0);
    let mut check = ExcitationCheck {
        excitation_rms: excitation.map(rms_about_mean),
        coherent_share: None,
        weak_share: 0.0,
        input_rms,
        problems: Vec::new(),
    };
    if input_rms <= 1e-12 * scale {
        check.weak_share = 1.0;
        check.problems.push(ExcitationProblem::InputConstant);
        return Ok(check);
    }
    // excitation first (channel 0) when there is one, the input last
    let mut chans: Vec<&[f64]> = Vec::new();
    let exc_live = excitation.filter(|e| {
        let s = e.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        s > 1e-12 * scale
    });
    if let Some(e) = exc_live {
        chans.push(e);
    }
    chans.push(input);
    let u = chans.len() - 1;
    let cs = cross_spectra_grid(&chans, dt_s, WindowSpec::half_overlap(window), omega_rad_s)?;
    let guu: Vec<f64> = (0..omega_rad_s.len()).map(|k| cs.get(k, u, u).re).collect();
    let peak = guu.iter().fold(0.0_f64, |m, g| m.max(*g));
    let weak = guu.iter().filter(|g| **g < WEAK_INPUT_RATIO * peak).count();
    check.weak_share = weak as f64 / guu.len().max(1) as f64;
    if excitation.is_some() && exc_live.is_none() {
        check.problems.push(ExcitationProblem::NoExcitation);
    }
    if exc_live.is_some() {
        let (mut coherent, mut total) = (0.0, 0.0);
        for (k, g) in guu.iter().enumerate() {
            let gee = cs.get(k, 0, 0).re;
            let geu = cs.get(k, 0, u).norm_sqr();
            if gee > 0.0 && *g > 0.0 {
                coherent += (geu / (gee * g)).min(1.0) * g;
            }
            total += g;
        }
        let share = if total > 0.0 { coherent / total } else { 0.0 };
        check.coherent_share = Some(share);
        if share < MIN_COHERENT_SHARE {
            check
                .problems
                .push(ExcitationProblem::FeedbackDominated(share));
        }
    }
    if check.weak_share > MAX_WEAK_SHARE {
        check
            .problems
            .push(ExcitationProblem::BandGaps(check.weak_share));
    }
    Ok(check)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frf::log_grid;

    /// A first-order plant y' = −y + u under proportional feedback
    /// u = −k y + e + d: with e = 0 the input is all feedback.
    fn closed_loop(exc_amplitude: f64, n: usize, dt: f64) -> (Vec<f64>, Vec<f64>) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (mut y, mut u, mut e) = (0.0, Vec::with_capacity(n), Vec::with_capacity(n));
        for i in 0..n {
            let t = i as f64 * dt;
            // a sweep 1 → 20 rad/s over the record
            let w = 1.0 + 19.0 * t / (n as f64 * dt);
            let ek = exc_amplitude * (w * t).sin();
            let d: f64 = StandardNormal.sample(&mut rng);
            let uk = -2.0 * y + ek;
            y += dt * (-y + uk + d);
            u.push(uk);
            e.push(ek);
        }
        (u, e)
    }

    #[test]
    fn closed_loop_without_excitation_is_flagged() {
        let dt = 0.01;
        let grid = log_grid(1.0, 20.0, 40).unwrap();
        let (u, e) = closed_loop(0.0, 20_000, dt);
        let c = check_excitation(&u, Some(&e), dt, 2000, &grid).unwrap();
        assert_eq!(c.problems, vec![ExcitationProblem::NoExcitation]);
        assert_eq!(c.excitation_rms, Some(0.0));
        assert!(c.coherent_share.is_none());
    }

    #[test]
    fn an_excited_input_passes() {
        let dt = 0.01;
        let grid = log_grid(1.0, 20.0, 40).unwrap();
        let (u, e) = closed_loop(1.0, 20_000, dt);
        let c = check_excitation(&u, Some(&e), dt, 2000, &grid).unwrap();
        let share = c.coherent_share.unwrap();
        assert!(share > MIN_COHERENT_SHARE, "{share}");
        assert!(c.problems.is_empty(), "{:?}", c.problems);
        // a tenth of that excitation: the disturbance the feedback answers dominates
        let (u, e) = closed_loop(0.1, 20_000, dt);
        let c = check_excitation(&u, Some(&e), dt, 2000, &grid).unwrap();
        assert!(
            matches!(c.problems.as_slice(), [ExcitationProblem::FeedbackDominated(s)] if *s < MIN_COHERENT_SHARE),
            "{:?}",
            c.problems
        );
    }

    #[test]
    fn a_constant_input_and_band_gaps_are_flagged() {
        let dt = 0.01;
        let grid = log_grid(1.0, 40.0, 40).unwrap();
        let c = check_excitation(&vec![0.3; 4000], None, dt, 1000, &grid).unwrap();
        assert_eq!(c.problems, vec![ExcitationProblem::InputConstant]);
        // a pure 2 rad/s sine excites one point of the band
        let s: Vec<f64> = (0..8000).map(|i| (2.0 * i as f64 * dt).sin()).collect();
        let c = check_excitation(&s, None, dt, 4000, &grid).unwrap();
        assert!(
            matches!(c.problems.as_slice(), [ExcitationProblem::BandGaps(g)] if *g > 0.5),
            "{:?}",
            c.problems
        );
    }

    #[test]
    fn lengths_must_agree() {
        let grid = log_grid(1.0, 20.0, 10).unwrap();
        assert!(check_excitation(&[1.0; 100], Some(&[0.0; 99]), 0.01, 50, &grid).is_err());
    }
}
