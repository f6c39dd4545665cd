//! Time-domain verification started from the logged state: truth-b's
//! hover identification flight (demo programme, hover only, 20 points to
//! stay short), verified on the doublet flight.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::Params;
use helicon_paramid::config::{InitialState, Spectra, WindSource};
use helicon_paramid::demo::{DemoOptions, TRUTHS, run_demo};
use helicon_paramid::verify::{VerificationResult, verify};

/// Mean Theil coefficient of the cyclic outputs (meas_p, meas_q) over the
/// windows: (start model, identified model).
fn cyclic_theil(v: &[VerificationResult]) -> (f64, f64) {
    let o: Vec<_> = v
        .iter()
        .flat_map(|r| r.outputs.iter())
        .filter(|o| o.output != "meas_r")
        .collect();
    let n = o.len() as f64;
    (
        o.iter().map(|o| o.theil_start).sum::<f64>() / n,
        o.iter().map(|o| o.theil_identified).sum::<f64>() / n,
    )
}

#[test]
fn logged_start_verifies_the_identified_model_better() {
    let truth = Params::from_toml_str(TRUTHS[1].1, TRUTHS[1].0).unwrap();
    let dir = std::env::temp_dir().join(format!("helicon-paramid-verify-{}", std::process::id()));
    let opts = DemoOptions {
        flights: vec!["hover".into()],
        seed: Some(3),
        points: 20,
        // the start of the Bergen Twin's rotor values, as these figures were
        // measured: with the ground-measured start the start model already
        // verifies at 0.082 and this hover-only fit (20 points) moves it to
        // 0.161 (docs/paramid.md)
        ground: false,
        // the overlapped windows, as these figures were measured: their
        // estimate is the more precise of the two (docs/paramid.md), which
        // a hover-only fit of 20 points needs
        spectra: Spectra::Welch,
        ..DemoOptions::default()
    };
    let id = run_demo(&truth, &dir, &opts).unwrap();
    let mut cfg = id.config.clone();
    let n = cfg.verification.len();
    assert_eq!(n, 4);

    // the simulator's log has the true state and the wind: the default
    // flies both
    for v in &id.verification {
        assert_eq!(v.initial_state, InitialState::Logged);
        assert_eq!(v.wind, WindSource::Logged);
    }
    let (start, identified) = cyclic_theil(&id.verification);
    println!("logged state, logged wind: Theil p,q start {start:.3}, identified {identified:.3}");
    assert!(identified < 0.7 * start, "{identified} vs {start}");

    // independent check of the replay: the true parameters flown from the
    // logged state in the logged wind reproduce the log up to the sensor
    // noise of meas_* (Theil 0.004–0.03 measured, every output incl. r)
    let exact: Vec<_> = (0..n)
        .map(|i| verify(&cfg, i, &truth, &truth).unwrap())
        .collect();
    for o in exact.iter().flat_map(|r| r.outputs.iter()) {
        assert!(
            o.theil_start < 0.06,
            "truth replay {}: {}",
            o.output,
            o.theil_start
        );
    }

    // a real flight: the estimate at the first sample, still air
    for v in &mut cfg.verification {
        v.initial_state = Some(InitialState::Estimate);
        v.wind = Some(WindSource::Still);
    }
    let est: Vec<_> = (0..n)
        .map(|i| verify(&cfg, i, &cfg.start, &id.identified).unwrap())
        .collect();
    let (es, ei) = cyclic_theil(&est);
    // the model's own trim, still air (the former verification)
    for v in &mut cfg.verification {
        v.initial_state = Some(InitialState::Trim);
    }
    let trim: Vec<_> = (0..n)
        .map(|i| verify(&cfg, i, &cfg.start, &id.identified).unwrap())
        .collect();
    let (ts, ti) = cyclic_theil(&trim);
    println!(
        "estimate, still: start {es:.3}, identified {ei:.3}; trim, still: start {ts:.3}, identified {ti:.3}"
    );
    assert!(ei < es, "estimate start: {ei} vs {es}");
    assert!(
        ei < ti,
        "the estimated start verifies better than the trim: {ei} vs {ti}"
    );
    assert!(
        identified < ei,
        "the logged wind helps: {identified} vs {ei}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
