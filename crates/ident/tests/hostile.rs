//! Bad input gives a typed error, never a panic, a NaN or an infinity.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::fit::{CostOptions, TfStructure, fit_tf, simulate, theil};
use helicon_ident::frf::{
    CrossSpectra, Frf, WindowSpec, composite, conditioned, cross_spectra_fft, cross_spectra_grid,
    log_grid, siso,
};
use helicon_ident::inputs::{Multisine, Sweep};

#[test]
fn spectra_refuse_bad_channels_and_windows() {
    let x: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.1).sin()).collect();
    let mut bad = x.clone();
    bad[500] = f64::NAN;
    let e = cross_spectra_fft(&[&x, &bad], 0.01, WindowSpec::half_overlap(100))
        .unwrap_err()
        .to_string();
    assert!(e.contains("channel 1") && e.contains("sample 500"), "{e}");
    assert!(cross_spectra_fft(&[&x, &x[..999]], 0.01, WindowSpec::half_overlap(100)).is_err());
    assert!(cross_spectra_fft(&[&x], 0.0, WindowSpec::half_overlap(100)).is_err());
    assert!(cross_spectra_fft(&[&x], f64::INFINITY, WindowSpec::half_overlap(100)).is_err());
    assert!(cross_spectra_fft(&[&x], 0.01, WindowSpec::half_overlap(2000)).is_err());
    assert!(
        cross_spectra_fft(
            &[&x],
            0.01,
            WindowSpec {
                len: 100,
                overlap: 100,
                taper: helicon_ident::frf::Taper::Hann
            }
        )
        .is_err()
    );
    assert!(cross_spectra_fft(&[], 0.01, WindowSpec::half_overlap(100)).is_err());
    // Grid beyond Nyquist, negative or NaN.
    for w in [400.0, -1.0, f64::NAN] {
        assert!(
            cross_spectra_grid(&[&x], 0.01, WindowSpec::half_overlap(100), &[1.0, w]).is_err(),
            "{w}"
        );
    }
    assert!(
        log_grid(0.0, 1.0, 10).is_err()
            && log_grid(2.0, 1.0, 10).is_err()
            && log_grid(1.0, 2.0, 1).is_err()
    );
}

#[test]
fn responses_of_silent_or_repeated_channels_are_empty_or_refused() {
    let zero = vec![0.0; 1000];
    let y: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.3).cos()).collect();
    let grid = log_grid(1.0, 100.0, 20).unwrap();
    let cs = cross_spectra_grid(&[&zero, &y], 0.01, WindowSpec::half_overlap(200), &grid).unwrap();
    // A silent input: no point is estimable; none is returned, nothing non-finite.
    let f = siso(&cs, 0, 1).unwrap();
    assert!(f.is_empty());
    assert!(conditioned(&cs, &[0, 0], 1).is_err());
    assert!(conditioned(&cs, &[0], 0).is_err());
    assert!(conditioned(&cs, &[5], 1).is_err());
    assert!(conditioned(&cs, &[], 1).is_err());
    // A silent output: H = 0, coherence 0, the point dropped (ε infinite).
    let cs = cross_spectra_grid(&[&y, &zero], 0.01, WindowSpec::half_overlap(200), &grid).unwrap();
    let f = siso(&cs, 0, 1).unwrap();
    assert!(
        f.h.iter().chain(f.h.iter()).all(|h| h.re.is_finite())
            && f.random_error.iter().all(|e| e.is_finite())
    );
    assert!(composite(&[], &[]).is_err());
    assert!(CrossSpectra::merge(&[]).is_err());
}

#[test]
fn fits_refuse_unusable_responses() {
    let grid = log_grid(1.0, 10.0, 20).unwrap();
    let frf = Frf {
        h: grid
            .iter()
            .map(|w| helicon_ident::Complex64::new(1.0, -*w))
            .collect(),
        coherence: vec![0.5; 20],
        random_error: vec![0.1; 20],
        omega_rad_s: grid,
    };
    let st = TfStructure {
        num_order: 0,
        den_order: 1,
        delay: false,
    };
    // Every point below the coherence threshold.
    let e = fit_tf(&frf, st, &CostOptions::default(), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("0 points"), "{e}");
    let loose = CostOptions {
        min_coherence: 0.0,
        ..CostOptions::default()
    };
    assert!(
        fit_tf(&frf, st, &loose, Some(&[1.0])).is_err(),
        "start of the wrong length"
    );
    assert!(fit_tf(&frf, st, &loose, Some(&[f64::NAN, 1.0])).is_err());
    let fit = fit_tf(&frf, st, &loose, None).unwrap();
    assert!(
        fit.params
            .iter()
            .chain(&fit.cramer_rao)
            .all(|v| v.is_finite())
    );
    assert!(simulate(&fit, &[1.0; 10], 0.0).is_err());
    let mut broken = fit.clone();
    broken.den.clear();
    assert!(simulate(&broken, &[1.0; 10], 0.01).is_err());
    assert!(theil(&[1.0], &[1.0, 2.0]).is_err());
}

#[test]
fn inputs_refuse_bad_numbers() {
    assert!(Sweep::new(0.1, f64::INFINITY, 10.0, 100.0).is_err());
    assert!(Sweep::new(0.1, 1.0, f64::NAN, 100.0).is_err());
    assert!(Multisine::new(0.1, f64::NAN, 1.0, 10.0, 1, 0).is_err());
    assert!(Multisine::new(0.1, 10.0, 1.0, 10.0, 0, 0).is_err());
    // A band holding too many harmonics is refused, not allocated.
    assert!(Multisine::new(0.1, 1e5, 0.0, 1e5, 1, 0).is_err());
}

/// The Cramér–Rao bounds refuse a cost that is no sum of squares, a
/// threshold outside [0, 1), and a residual correlation that is not finite
/// (before: a negative cost gave bounds of 0, a NaN threshold infinite
/// bounds, silently).
#[test]
fn accuracy_refuses_bad_costs_thresholds_and_correlations() {
    use helicon_ident::cost::{accuracy, accuracy_correlated};
    use helicon_ident::frf::composite_correlation;
    use nalgebra::DMatrix;
    let jac = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, -1.0]);
    assert!(accuracy(&jac, 1.0, 1e-12).is_ok());
    for cost in [-1.0, f64::NAN, f64::INFINITY] {
        let e = accuracy(&jac, cost, 1e-12).unwrap_err().to_string();
        assert!(e.contains("cost"), "{cost}: {e}");
    }
    for thr in [-1e-3, 1.0, f64::NAN] {
        let e = accuracy(&jac, 1.0, thr).unwrap_err().to_string();
        assert!(e.contains("threshold"), "{thr}: {e}");
    }
    // a correlation matrix built from a NaN frequency: refused, not R = 1
    let rho = composite_correlation(f64::NAN, 2.0, &[12.0]);
    let jrj = DMatrix::from_row_slice(2, 2, &[1.0, rho, rho, 1.0]);
    assert!(accuracy_correlated(&jac, 1.0, 1e-12, Some(&jrj)).is_err());
}
