//! Flight-test inputs against their definitions: the sweep's instantaneous
//! frequency (numerical derivative of its phase), its fades and record-length
//! rule; the multisine's crest factor, spectrum and orthogonality; the
//! doublet's and 3211's shapes.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ident::frf::{WindowSpec, cross_spectra_fft};
use helicon_ident::inputs::{Doublet, Input, Input3211, Multisine, Sweep};
use std::f64::consts::PI;

#[test]
fn sweep_frequency_rises_from_omega_min_to_omega_max() {
    let s = Sweep::new(0.1, 0.5, 40.0, 90.0).unwrap();
    let t_low = 2.0 * 2.0 * PI / 0.5;
    assert!((s.omega_at(0.0) - 0.5).abs() < 1e-12);
    assert!((s.omega_at(t_low * 0.99) - 0.5).abs() < 1e-12);
    assert!(
        (s.omega_at(90.0) - 40.0).abs() < 1e-9,
        "{}",
        s.omega_at(90.0)
    );
    // Monotonic, and the exponential law at mid-rise:
    // ω = ω_min + C2(e^{C1/2} − 1)/(C2(e^{C1} − 1))·(ω_max − ω_min).
    let mid = t_low + 0.5 * (90.0 - t_low);
    let k = (2.0_f64.exp() - 1.0) / (4.0_f64.exp() - 1.0);
    assert!((s.omega_at(mid) - (0.5 + k * 39.5)).abs() < 1e-9);
    let mut last = 0.0;
    for i in 0..900 {
        let w = s.omega_at(i as f64 * 0.1);
        assert!(w >= last);
        last = w;
    }
    // The value is A sin(phase): count zero crossings between t1 and t2 in the
    // constant-frequency part: ω/π per second.
    let crossings = (0..2000)
        .filter(|i| {
            let (a, b) = (
                s.value(3.0 + *i as f64 * 0.005),
                s.value(3.0 + (*i + 1) as f64 * 0.005),
            );
            a.signum() != b.signum()
        })
        .count();
    assert!(
        (crossings as f64 - 0.5 * 10.0 / PI).abs() <= 1.0,
        "{crossings}"
    );
    // Fades: zero at both ends, full amplitude in between.
    assert_eq!(s.value(0.0), 0.0);
    assert!(s.value(90.0).abs() < 1e-12);
    assert_eq!(s.value(-1.0), 0.0);
    assert_eq!(s.value(91.0), 0.0);
    let peak = (0..9000)
        .map(|i| s.value(i as f64 * 0.01).abs())
        .fold(0.0, f64::max);
    assert!(peak <= 0.1 + 1e-12 && peak > 0.099, "{peak}");
}

#[test]
fn sweep_refuses_records_shorter_than_five_low_periods() {
    // 5 periods of 0.5 rad/s = 62.83 s.
    let e = Sweep::new(0.1, 0.5, 40.0, 60.0).unwrap_err().to_string();
    assert!(
        e.contains("sweep.duration_s") && e.contains("5 periods"),
        "{e}"
    );
    assert!(Sweep::new(0.1, 0.5, 40.0, 63.0).is_ok());
    assert!(Sweep::new(0.1, 5.0, 4.0, 63.0).is_err());
    assert!(Sweep::new(f64::NAN, 0.5, 4.0, 63.0).is_err());
}

#[test]
fn schroeder_multisine_has_a_low_crest_factor_and_a_flat_line_spectrum() {
    let m = Multisine::new(0.2, 20.0, 1.0, 30.0, 1, 0).unwrap();
    let w = m.omegas_rad_s();
    // Harmonics of 2π/20 = 0.314 rad/s between 1 and 30: k = 4 … 95.
    assert_eq!(w.len(), 92);
    let n = 20_000;
    let x: Vec<f64> = (0..n)
        .map(|i| m.value(20.0 * i as f64 / n as f64))
        .collect();
    let peak = x.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let rms = (x.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    // Peak scaled to the amplitude (grid of 16 samples per top period: within 2 %).
    assert!((peak - 0.2).abs() < 0.004, "{peak}");
    // Zero phases would give a crest factor √(2M) = 13.6; Schroeder's stays
    // near that of one sine (√2 = 1.41): below 2.
    let crest = peak / rms;
    assert!(crest < 2.0 && crest > 1.3, "crest factor {crest}");
    // Power only on the chosen harmonics, equal on each (a periodogram over
    // exactly one period with a rectangular window: bins are harmonics).
    let mut buf: Vec<helicon_ident::Complex64> = x
        .iter()
        .map(|v| helicon_ident::Complex64::new(*v, 0.0))
        .collect();
    helicon_ident::spectral::fft(&mut buf);
    let p: Vec<f64> = buf[..200].iter().map(|c| c.norm_sqr()).collect();
    let on: Vec<f64> = (4..=95).map(|k| p[k]).collect();
    let (lo, hi) = on
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(a, b), v| (a.min(*v), b.max(*v)));
    assert!(hi / lo < 1.0 + 1e-9, "line powers {lo} … {hi}");
    let off = (0..200)
        .filter(|k| !(4..=95).contains(k))
        .map(|k| p[k])
        .fold(0.0, f64::max);
    assert!(off < 1e-18 * hi, "{off}");
}

#[test]
fn orthogonal_multisines_share_no_frequency_and_are_uncorrelated() {
    let axes: Vec<Multisine> = (0..3)
        .map(|a| Multisine::new(0.1, 10.0, 0.5, 25.0, 3, a).unwrap())
        .collect();
    let n = 8000;
    let sig: Vec<Vec<f64>> = axes
        .iter()
        .map(|m| {
            (0..n)
                .map(|i| m.value(10.0 * i as f64 / n as f64))
                .collect()
        })
        .collect();
    for a in 0..3 {
        for b in 0..3 {
            let dot: f64 = sig[a].iter().zip(&sig[b]).map(|(x, y)| x * y).sum::<f64>() / n as f64;
            if a == b {
                assert!(dot > 1e-4);
            } else {
                assert!(dot.abs() < 1e-15, "axes {a},{b}: {dot}");
                let (wa, wb) = (axes[a].omegas_rad_s(), axes[b].omegas_rad_s());
                assert!(wa.iter().all(|w| wb.iter().all(|v| (w - v).abs() > 0.1)));
            }
        }
    }
    assert!(Multisine::new(0.1, 10.0, 0.5, 25.0, 3, 3).is_err());
    assert!(
        Multisine::new(0.1, 10.0, 0.1, 0.5, 1, 0).is_err(),
        "no harmonic in the band"
    );
}

#[test]
fn doublet_and_3211_have_their_shapes() {
    let d = Doublet {
        amplitude: 0.05,
        pulse_s: 0.5,
    };
    d.check().unwrap();
    assert_eq!(d.value(0.25), 0.05);
    assert_eq!(d.value(0.75), -0.05);
    assert_eq!(d.value(1.01), 0.0);
    assert_eq!(d.value(-0.01), 0.0);
    let s = Input3211 {
        amplitude: 1.0,
        pulse_s: 0.2,
    };
    s.check().unwrap();
    let dt = 1e-4;
    let vals: Vec<f64> = (0..15_000)
        .map(|i| s.value((i as f64 + 0.5) * dt))
        .collect();
    // 3Δt up, 2Δt down, Δt up, Δt down: integral (3 − 2 + 1 − 1)Δt = 0.2.
    let integral: f64 = vals.iter().sum::<f64>() * dt;
    assert!((integral - 0.2).abs() < 1e-9, "{integral}");
    let signs: Vec<f64> = [0.3, 0.7, 1.1, 1.3].iter().map(|t| s.value(*t)).collect();
    assert_eq!(signs, vec![1.0, -1.0, 1.0, -1.0]);
    assert!((s.duration_s() - 1.4).abs() < 1e-12);
    assert!(
        Doublet {
            amplitude: 1.0,
            pulse_s: 0.0
        }
        .check()
        .is_err()
    );
}

#[test]
fn inputs_read_from_toml_by_kind() {
    let t: Input = toml::from_str("kind = \"3211\"\namplitude = 0.1\npulse_s = 0.3\n").unwrap();
    assert!((t.duration_s() - 2.1).abs() < 1e-12);
    let mut m: Input = toml::from_str(
        "kind = \"multisine\"\namplitude = 0.1\nperiod_s = 10\nomega_min_rad_s = 1\nomega_max_rad_s = 10\nrepeats = 2",
    )
    .unwrap();
    m.prepare().unwrap();
    assert!((m.duration_s() - 20.0).abs() < 1e-12);
    assert!(m.value(3.0).abs() > 0.0);
    let bad: Result<Input, _> =
        toml::from_str("kind = \"sweep\"\namplitude = 0.1\nomega_min = 1\n");
    assert!(bad.is_err());
    // A sampled sweep carries its power below ω_max: the Welch spectrum above
    // 2 ω_max holds < 1 % of the total.
    let mut s: Input = toml::from_str(
        "kind = \"sweep\"\namplitude = 1\nomega_min_rad_s = 1\nomega_max_rad_s = 20\nduration_s = 60",
    )
    .unwrap();
    s.prepare().unwrap();
    let x = s.sample(0.01);
    let cs = cross_spectra_fft(&[&x], 0.01, WindowSpec::half_overlap(1024)).unwrap();
    let (mut lo, mut hi) = (0.0, 0.0);
    for (k, w) in cs.omega_rad_s.iter().enumerate() {
        if *w > 40.0 {
            hi += cs.get(k, 0, 0).re
        } else {
            lo += cs.get(k, 0, 0).re
        }
    }
    assert!(hi < 0.01 * lo, "{hi} {lo}");
}
