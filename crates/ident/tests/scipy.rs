//! The cross spectra, auto spectra and coherence against SciPy's
//! `csd`/`welch`/`coherence` (fixture from tools/gen_ident_fixtures.py),
//! identical windows and overlap, agreement 1e-9 of each array's largest
//! value (both compute the same sums in double precision; the observed
//! differences are ~1e-15).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::frf::{Taper, WindowSpec, cross_spectra_fft, cross_spectra_grid, siso};
use serde_json::Value;

fn arr(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn close(name: &str, ours: &[f64], theirs: &[f64]) -> f64 {
    assert_eq!(ours.len(), theirs.len(), "{name}: length");
    let scale = theirs.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let worst = ours
        .iter()
        .zip(theirs)
        .map(|(a, b)| (a - b).abs() / scale)
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "{name}: worst relative difference {worst:e}");
    worst
}

#[test]
fn spectra_and_coherence_agree_with_scipy_to_1e_9() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/scipy_csd.json"
    ))
    .unwrap();
    let doc: Value = serde_json::from_str(&text).unwrap();
    let (x, y) = (arr(&doc["x"]), arr(&doc["y"]));
    let dt = 1.0 / doc["fs_hz"].as_f64().unwrap();
    let cases = doc["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 3);
    let mut worst = 0.0_f64;
    for c in cases {
        let spec = WindowSpec {
            len: c["nperseg"].as_u64().unwrap() as usize,
            overlap: c["noverlap"].as_u64().unwrap() as usize,
            taper: Taper::Hann,
        };
        let cs = cross_spectra_fft(&[&x, &y], dt, spec).unwrap();
        let n = cs.omega_rad_s.len();
        let f: Vec<f64> = cs
            .omega_rad_s
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect();
        worst = worst.max(close("f", &f, &arr(&c["f_hz"])));
        let csr = &cs;
        let g = |i, j| (0..n).map(move |k| csr.get(k, i, j));
        worst = worst.max(close(
            "pxx",
            &g(0, 0).map(|v| v.re).collect::<Vec<_>>(),
            &arr(&c["pxx"]),
        ));
        worst = worst.max(close(
            "pyy",
            &g(1, 1).map(|v| v.re).collect::<Vec<_>>(),
            &arr(&c["pyy"]),
        ));
        worst = worst.max(close(
            "pxy.re",
            &g(0, 1).map(|v| v.re).collect::<Vec<_>>(),
            &arr(&c["pxy_re"]),
        ));
        worst = worst.max(close(
            "pxy.im",
            &g(0, 1).map(|v| v.im).collect::<Vec<_>>(),
            &arr(&c["pxy_im"]),
        ));
        // Coherence: SciPy's over all bins; ours drops none here (all finite).
        let frf = siso(&cs, 0, 1).unwrap();
        assert_eq!(frf.len(), n);
        worst = worst.max(close("coherence", &frf.coherence, &arr(&c["cxy"])));

        // The direct evaluation on the FFT bins (all but DC and Nyquist, which
        // the grid counts one-sided twice) equals the FFT path.
        let inner: Vec<f64> = cs.omega_rad_s[1..n - 1].to_vec();
        let gs = cross_spectra_grid(&[&x, &y], dt, spec, &inner).unwrap();
        let a: Vec<f64> = (0..inner.len())
            .flat_map(|k| [gs.get(k, 0, 1).re, gs.get(k, 0, 1).im, gs.get(k, 1, 1).re])
            .collect();
        let b: Vec<f64> = (1..n - 1)
            .flat_map(|k| [cs.get(k, 0, 1).re, cs.get(k, 0, 1).im, cs.get(k, 1, 1).re])
            .collect();
        worst = worst.max(close("grid vs fft", &a, &b));
    }
    println!("worst relative difference to SciPy: {worst:e}");
}
