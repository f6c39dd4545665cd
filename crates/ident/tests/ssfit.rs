//! State-space fits: the model response against SciPy, noise-free recovery
//! of known parameters (one and several responses, a shared parameter),
//! noisy sweeps within their Cramér–Rao bounds, a parameter the responses
//! cannot see, and hostile model files.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::{noise, percentile};
use helicon_ident::Complex64;
use helicon_ident::cost::CostOptions;
use helicon_ident::frf::{Frf, WindowSpec, composite, cross_spectra_grid, log_grid, siso};
use helicon_ident::inputs::Sweep;
use helicon_ident::ssfit::{Response, SsModel, SsSpec, cost_at, fit_ss};
use nalgebra::DMatrix;
use std::path::Path;

/// The hover longitudinal u–q–θ model (X_θ = −g fixed), cyclic input δ with
/// a delay, outputs u and q. Truth: X_u = −0.3, M_u = 0.05, M_q = −3,
/// M_δ = 20, X_δ = −4, τ = 0.02 s (stable: Routh 3.3·0.9 > 9.81·0.05).
const TRUTH: [f64; 6] = [-0.3, 0.05, -3.0, 20.0, -4.0, 0.02];

fn hover_toml(start: [f64; 6], responses: &str) -> String {
    format!(
        r#"
states = ["u", "q", "theta"]
inputs = ["delta"]
outputs = ["u", "q"]
[A]
u = ["X_u", 0, -9.81]
q = ["M_u", "M_q", 0.0]
theta = [0, 1, 0]
[B]
u = ["X_d"]
q = ["M_d"]
theta = [0]
[C]
u = [1, 0, 0]
q = [0, 1, 0]
[delay_s]
delta = "tau"
[[parameter]]
name = "X_u"
start = {}
[[parameter]]
name = "M_u"
start = {}
[[parameter]]
name = "M_q"
start = {}
max = 0.0
[[parameter]]
name = "M_d"
start = {}
[[parameter]]
name = "X_d"
start = {}
[[parameter]]
name = "tau"
start = {}
min = 0.0
max = 0.2
{responses}
"#,
        start[0], start[1], start[2], start[3], start[4], start[5]
    )
}

const BOTH: &str = r#"
[[response]]
input = "delta"
output = "u"
frf = "frf.csv"
[[response]]
input = "delta"
output = "q"
frf = "frf.csv"
"#;

fn spec(text: &str) -> SsSpec {
    SsSpec::from_toml_str(text, "model.toml", Path::new("")).unwrap()
}

/// The exact response of `model` at `theta` on `grid` as a Frf (γ² = 1).
fn exact(model: &SsModel, theta: &[f64], input: usize, output: usize, grid: &[f64]) -> Frf {
    let m = model.matrices(theta).unwrap();
    Frf {
        omega_rad_s: grid.to_vec(),
        h: grid
            .iter()
            .map(|w| m.response(*w).unwrap()[(output, input)])
            .collect(),
        coherence: vec![1.0; grid.len()],
        random_error: vec![0.0; grid.len()],
    }
}

fn responses_of(s: &SsSpec, frfs: Vec<Frf>) -> Vec<Response> {
    s.responses
        .iter()
        .zip(frfs)
        .map(|(r, frf)| Response {
            input: s.model.inputs.iter().position(|n| *n == r.input).unwrap(),
            output: s.model.outputs.iter().position(|n| *n == r.output).unwrap(),
            frf,
            omega_min_rad_s: r.omega_min_rad_s,
            omega_max_rad_s: r.omega_max_rad_s,
        })
        .collect()
}

#[test]
fn model_response_matches_scipy_freqresp() {
    let text = include_str!("fixtures/ssfit_freqresp.json");
    let doc: serde_json::Value = serde_json::from_str(text).unwrap();
    let mat = |v: &serde_json::Value| {
        let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap();
        DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
    };
    let mut worst = 0.0_f64;
    let mut count = 0;
    for m in doc["models"].as_array().unwrap() {
        let mats = helicon_ident::ssfit::Matrices {
            a: mat(&m["a"]),
            b: mat(&m["b"]),
            c: mat(&m["c"]),
            d: mat(&m["d"]),
            delay_s: serde_json::from_value(m["delay_s"].clone()).unwrap(),
        };
        let omega: Vec<f64> = serde_json::from_value(m["omega_rad_s"].clone()).unwrap();
        for r in m["responses"].as_array().unwrap() {
            let (i, o) = (
                r["input"].as_u64().unwrap() as usize,
                r["output"].as_u64().unwrap() as usize,
            );
            let re: Vec<f64> = serde_json::from_value(r["re"].clone()).unwrap();
            let im: Vec<f64> = serde_json::from_value(r["im"].clone()).unwrap();
            let scale = re
                .iter()
                .zip(&im)
                .map(|(a, b)| a.hypot(*b))
                .fold(0.0, f64::max);
            for (k, w) in omega.iter().enumerate() {
                let h = mats.response(*w).unwrap()[(o, i)];
                let e = (h - Complex64::new(re[k], im[k])).norm() / scale;
                worst = worst.max(e);
                count += 1;
            }
        }
    }
    println!("{count} points, worst difference {worst:.2e} of each response's largest |H|");
    assert_eq!(count, 40 * (2 + 6));
    // SciPy goes through a transfer-function polynomial: agreement to
    // round-off of that path, far inside 1e-9.
    assert!(worst < 1e-9, "{worst}");
}

#[test]
fn noise_free_two_responses_give_back_the_parameters() {
    let start = [-0.5, 0.08, -2.0, 14.0, -3.0, 0.05];
    let s = spec(&hover_toml(start, BOTH));
    let grid = log_grid(0.2, 40.0, 80).unwrap();
    let frfs = vec![
        exact(&s.model, &TRUTH, 0, 0, &grid),
        exact(&s.model, &TRUTH, 0, 1, &grid),
    ];
    let fit = fit_ss(&s.model, &responses_of(&s, frfs), &CostOptions::default()).unwrap();
    for (p, t) in fit.parameters.iter().zip(TRUTH) {
        let rel = (p.value - t).abs() / t.abs();
        println!("{} = {:.9} (truth {t}), rel {rel:.1e}", p.name, p.value);
        assert!(rel < 1e-6, "{}: {} vs {t}", p.name, p.value);
    }
    assert!(fit.cost < 1e-12, "{}", fit.cost);
    assert_eq!(fit.responses.len(), 2);
    assert_eq!(fit.responses[0].n_points, 80);
    // the total is the mean of the responses' J
    let mean = (fit.responses[0].cost + fit.responses[1].cost) / 2.0;
    assert!((fit.cost - mean).abs() <= 1e-12 * mean.max(1e-300) + 1e-30);
    assert_eq!(fit.matrices.a[(0, 2)], -9.81);
    assert!((fit.matrices.delay_s[0] - 0.02).abs() < 1e-8);
    // correlation matrix: unit diagonal, symmetric, within [−1, 1]
    for i in 0..6 {
        assert!((fit.correlation[(i, i)] - 1.0).abs() < 1e-12);
        for j in 0..6 {
            assert!((fit.correlation[(i, j)] - fit.correlation[(j, i)]).abs() < 1e-12);
            assert!(fit.correlation[(i, j)].abs() <= 1.0 + 1e-12);
        }
    }
}

/// A coupled two-input system with one stability derivative shared by two
/// cells: the fit gives it back from the four responses.
#[test]
fn noise_free_shared_parameter_two_inputs() {
    let text = r#"
states = ["p", "q"]
inputs = ["lat", "lon"]
outputs = ["p", "q"]
[A]
p = ["L_p", "K"]
q = ["K", "M_q"]
[B]
p = ["L_lat", 0.5]
q = [0.0, "M_lon"]
[C]
p = [1, 0]
q = [0, 1]
[[parameter]]
name = "L_p"
start = -4.0
[[parameter]]
name = "M_q"
start = -1.0
[[parameter]]
name = "K"
start = 0.3
[[parameter]]
name = "L_lat"
start = 30.0
[[parameter]]
name = "M_lon"
start = 10.0
[[response]]
input = "lat"
output = "p"
frf = "a.csv"
[[response]]
input = "lat"
output = "q"
frf = "a.csv"
[[response]]
input = "lon"
output = "p"
frf = "b.csv"
[[response]]
input = "lon"
output = "q"
frf = "b.csv"
"#;
    let s = spec(text);
    let truth = [-6.0, -2.0, 1.5, 45.0, 18.0];
    let grid = log_grid(0.5, 50.0, 60).unwrap();
    let frfs = s
        .responses
        .iter()
        .map(|r| {
            let i = s.model.inputs.iter().position(|n| *n == r.input).unwrap();
            let o = s.model.outputs.iter().position(|n| *n == r.output).unwrap();
            exact(&s.model, &truth, i, o, &grid)
        })
        .collect();
    let fit = fit_ss(&s.model, &responses_of(&s, frfs), &CostOptions::default()).unwrap();
    for (p, t) in fit.parameters.iter().zip(truth) {
        assert!(
            (p.value - t).abs() < 1e-6 * t.abs(),
            "{}: {}",
            p.name,
            p.value
        );
    }
    assert_eq!(fit.matrices.a[(0, 1)], fit.matrices.a[(1, 0)]);
    assert_eq!(fit.responses.len(), 4);
}

/// 120 s sweep 0.4 → 25 rad/s on δ through the true model (RK4, the input
/// evaluated at the delayed continuous time), output noise, composite of
/// 60, 30, 15 and 7.5 s Hann windows on 100 points 0.5–25 rad/s.
fn noisy_frfs(seed: u64, sigma_u: f64, sigma_q: f64) -> Vec<Frf> {
    let dt = 0.01;
    let sweep = Sweep::new(0.02, 0.4, 25.0, SWEEP_S).unwrap();
    let n = (SWEEP_S / dt) as usize + 400;
    let [xu, mu, mq, md, xd, tau] = TRUTH;
    let f = |t: f64, x: [f64; 3]| {
        let d = sweep.value(t - tau);
        [
            xu * x[0] - 9.81 * x[2] + xd * d,
            mu * x[0] + mq * x[1] + md * d,
            x[1],
        ]
    };
    let sub = 4;
    let h = dt / sub as f64;
    let mut x = [0.0; 3];
    let (mut yu, mut yq, mut ud) = (Vec::new(), Vec::new(), Vec::new());
    let add =
        |a: [f64; 3], b: [f64; 3], s: f64| [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]];
    for i in 0..n {
        let t0 = i as f64 * dt;
        ud.push(sweep.value(t0));
        yu.push(x[0]);
        yq.push(x[1]);
        for j in 0..sub {
            let t = t0 + j as f64 * h;
            let k1 = f(t, x);
            let k2 = f(t + h / 2.0, add(x, k1, h / 2.0));
            let k3 = f(t + h / 2.0, add(x, k2, h / 2.0));
            let k4 = f(t + h, add(x, k3, h));
            for c in 0..3 {
                x[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
            }
        }
    }
    let nu = noise(seed, sigma_u, n);
    let nq = noise(seed + 1000, sigma_q, n);
    let yu: Vec<f64> = yu.iter().zip(nu).map(|(a, b)| a + b).collect();
    let yq: Vec<f64> = yq.iter().zip(nq).map(|(a, b)| a + b).collect();
    let grid = log_grid(0.5, 25.0, GRID_POINTS).unwrap();
    let lens = [12_000usize, 6000, 3000, 1500, 750];
    let secs: Vec<f64> = lens.iter().map(|l| *l as f64 * dt).collect();
    let spectra: Vec<_> = lens
        .iter()
        .map(|&l| {
            cross_spectra_grid(&[&ud, &yu, &yq], dt, WindowSpec::half_overlap(l), &grid).unwrap()
        })
        .collect();
    [1, 2]
        .iter()
        .map(|&o| {
            let parts: Vec<Frf> = spectra.iter().map(|cs| siso(cs, 0, o).unwrap()).collect();
            composite(&parts, &secs).unwrap()
        })
        .collect()
}

const SWEEP_S: f64 = 240.0;
const GRID_POINTS: usize = 40;
const SIGMA_U: f64 = 0.02;
const SIGMA_Q: f64 = 0.01;

#[test]
fn noisy_sweeps_fit_within_their_cramer_rao_bounds() {
    let start = [-0.5, 0.08, -2.0, 14.0, -3.0, 0.05];
    // u/δ below 1 rad/s, near the lightly damped phugoid, carries a leakage
    // bias of the Hann windows (+20 to +30 % in magnitude at 0.5–0.9 rad/s,
    // 2 to 4 random errors): its band starts at 1 rad/s.
    let bands = BOTH.replacen(
        "output = \"u\"\nfrf = \"frf.csv\"",
        "output = \"u\"\nfrf = \"frf.csv\"\nomega_min_rad_s = 1.0\nomega_max_rad_s = 5.0",
        1,
    );
    assert_ne!(bands, BOTH);
    let s = spec(&hover_toml(start, &bands));
    let mut z_all = Vec::new();
    for seed in [1, 2, 3] {
        let frfs = noisy_frfs(seed, SIGMA_U, SIGMA_Q);
        let resp = responses_of(&s, frfs);
        let fit = fit_ss(&s.model, &resp, &CostOptions::default()).unwrap();
        let (j_truth, _) = cost_at(&s.model, &resp, &CostOptions::default(), &TRUTH).unwrap();
        println!("seed {seed}: J at the truth {j_truth:.3}");
        for (p, t) in fit.parameters.iter().zip(TRUTH) {
            let z = (p.value - t).abs() / p.cramer_rao;
            println!(
                "seed {seed} {}: {:.5} ± {:.5} (CR {:.2} %, I {:.2} %) truth {t}: {z:.2} bounds {:?}",
                p.name, p.value, p.cramer_rao, p.cramer_rao_pct, p.insensitivity_pct, p.flags
            );
            assert!(p.insensitivity_pct <= p.cramer_rao_pct + 1e-12);
            z_all.push(z);
        }
        println!(
            "seed {seed}: J = {:.3} (u {:.3}, q {:.3})",
            fit.cost, fit.responses[0].cost, fit.responses[1].cost
        );
    }
    let (p50, p90, max) = (
        percentile(&z_all, 0.5),
        percentile(&z_all, 0.9),
        percentile(&z_all, 1.0),
    );
    let within2 = z_all.iter().filter(|z| **z <= 2.0).count();
    println!(
        "|error|/CR over 18 estimates: median {p50:.2}, p90 {p90:.2}, max {max:.2}; {within2} of 18 within 2 bounds"
    );
    // A Gaussian error with the bound as its σ would give a median 0.67 and
    // a p90 1.64. Measured: median 1.02, p90 3.05, max 3.30, 12 of 18
    // within 2 bounds. Two causes, both measured: the same pipeline on
    // noise-free sweeps (σ = 1e-5) already puts M_u 5 % high (the Hann
    // windows' leakage near the lightly damped phugoid) and M_d 0.4 % high,
    // and with noise M_d is 0.3 to 2 % high in every seed, a bias of the
    // composite estimates (the same fit with a constant γ² moves M_d by
    // < 0.1 %). The bound covers the random part only.
    assert!(p50 < 1.5, "{p50}");
    assert!(max < 3.5, "{max}");
    assert!(within2 >= 11, "{within2}");
}

/// (1) A gain on an output that no fitted response uses: the responses do
/// not depend on it at all; it is reported with an infinite bound and
/// flagged, and the others are still given back. (2) From q/δ alone above
/// 3 rad/s (noisy sweeps), the speed derivatives X_u and M_u act through
/// the phugoid, far below the band: they are flagged by CIFER's guidelines
/// while M_q and M_δ meet them.
#[test]
fn a_parameter_the_responses_cannot_see_is_flagged() {
    let start = [-0.5, 0.08, -2.0, 14.0, -3.0, 0.05];
    let text = hover_toml(start, BOTH)
        .replace(
            "outputs = [\"u\", \"q\"]",
            "outputs = [\"u\", \"q\", \"theta_m\"]",
        )
        .replace(
            "q = [0, 1, 0]\n",
            "q = [0, 1, 0]\ntheta_m = [0, 0, \"K_theta\"]\n",
        )
        + "[[parameter]]\nname = \"K_theta\"\nstart = 1.3\n";
    let s = spec(&text);
    let mut truth = TRUTH.to_vec();
    truth.push(1.0);
    let grid = log_grid(0.2, 40.0, 80).unwrap();
    let frfs = vec![
        exact(&s.model, &truth, 0, 0, &grid),
        exact(&s.model, &truth, 0, 1, &grid),
    ];
    let fit = fit_ss(&s.model, &responses_of(&s, frfs), &CostOptions::default()).unwrap();
    let k = &fit.parameters[6];
    println!(
        "{}: {} CR {} flags {:?}",
        k.name, k.value, k.cramer_rao, k.flags
    );
    assert_eq!(k.name, "K_theta");
    assert!(k.cramer_rao.is_infinite() && k.insensitivity_pct.is_infinite());
    assert!(
        k.flags.iter().any(|f| f.contains("not identifiable")),
        "{:?}",
        k.flags
    );
    assert_eq!(k.value, 1.3, "left at its start");
    assert!(fit.correlation[(6, 0)].is_nan() && fit.correlation[(0, 0)] == 1.0);
    for (p, t) in fit.parameters.iter().zip(TRUTH) {
        assert!(
            (p.value - t).abs() < 1e-6 * t.abs(),
            "{}: {}",
            p.name,
            p.value
        );
        assert!(p.flags.is_empty(), "{}: {:?}", p.name, p.flags);
    }

    // (2) q/δ alone, 3–25 rad/s, noisy.
    let q_only = "[[response]]\ninput = \"delta\"\noutput = \"q\"\nfrf = \"frf.csv\"\nomega_min_rad_s = 3.0\n";
    let s = spec(&hover_toml(start, q_only));
    let frfs = noisy_frfs(1, SIGMA_U, SIGMA_Q);
    let fit = fit_ss(
        &s.model,
        &responses_of(&s, vec![frfs[1].clone()]),
        &CostOptions::default(),
    )
    .unwrap();
    for p in &fit.parameters {
        println!(
            "q only: {} = {:.4} CR {:.1} % I {:.1} % {:?}",
            p.name, p.value, p.cramer_rao_pct, p.insensitivity_pct, p.flags
        );
    }
    for name in ["X_u", "M_u"] {
        let p = fit.parameters.iter().find(|p| p.name == name).unwrap();
        assert!(
            p.cramer_rao_pct > 20.0 && !p.flags.is_empty(),
            "{name}: {p:?}"
        );
    }
    for name in ["M_q", "M_d"] {
        let p = fit.parameters.iter().find(|p| p.name == name).unwrap();
        assert!(p.flags.is_empty(), "{name}: {p:?}");
    }
}

#[test]
fn hostile_model_files_name_the_file_and_field() {
    let good = hover_toml([-0.5, 0.08, -2.0, 14.0, -3.0, 0.05], BOTH);
    spec(&good);
    let cases: [(&str, &str, &str); 12] = [
        (
            "q = [\"M_u\", \"M_q\", 0.0]",
            "q = [\"M_u\", \"M_qq\", 0.0]",
            "A.q[1]",
        ),
        (
            "q = [\"M_u\", \"M_q\", 0.0]",
            "q = [\"M_u\", \"M_q\"]",
            "A.q",
        ),
        ("theta = [0, 1, 0]\n", "", "A.theta"),
        ("u = [\"X_d\"]", "u = [\"X_d\", 1.0]", "B.u"),
        ("u = [1, 0, 0]", "u = [1, 0, 0]\nw = [0, 0, 1]", "C.w"),
        ("start = -0.5", "start = nan", "parameter[0].start"),
        ("max = 0.0", "max = 0.0\nmin = 1.0", "parameter[2].min"),
        (
            "min = 0.0\nmax = 0.2",
            "min = 0.3\nmax = 0.2",
            "parameter[5].min",
        ),
        ("delta = \"tau\"", "delta = -0.01", "delay_s.delta"),
        ("output = \"q\"", "output = \"r\"", "response[1].output"),
        ("name = \"tau\"", "name = \"tau2\"", "delay_s.delta"),
        (
            "inputs = [\"delta\"]",
            "inputs = [\"delta\"]\ngain = 3",
            "gain",
        ),
    ];
    for (from, to, field) in cases {
        assert!(good.contains(from), "{from}");
        let text = good.replacen(from, to, 1);
        let e = SsSpec::from_toml_str(&text, "model.toml", Path::new(""))
            .unwrap_err()
            .to_string();
        println!("{e}");
        assert!(
            e.contains("model.toml") && e.contains(field),
            "{field}: {e}"
        );
    }
    // a misspelt key: the nearest valid one suggested
    let e = SsSpec::from_toml_str(
        &good.replacen("frf = \"frf.csv\"", "frff = \"frf.csv\"", 1),
        "model.toml",
        Path::new(""),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("model.toml") && e.contains("did you mean `frf`?"),
        "{e}"
    );
    // an unused parameter, a response band upside down
    let e = SsSpec::from_toml_str(
        &(good.clone() + "[[parameter]]\nname = \"Z_w\"\nstart = -1.0\n"),
        "model.toml",
        Path::new(""),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("parameter[6].name") && e.contains("Z_w"), "{e}");
    let e = SsSpec::from_toml_str(
        &good.replacen(
            "frf = \"frf.csv\"",
            "frf = \"frf.csv\"\nomega_min_rad_s = 5.0\nomega_max_rad_s = 1.0",
            1,
        ),
        "model.toml",
        Path::new(""),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("response[0].omega_max_rad_s"), "{e}");
    // a model built in code: non-square A, a NaN parameter vector
    let mut m = spec(&good).model;
    m.a[1].pop();
    let e = m.check().unwrap_err().to_string();
    assert!(e.contains("A[1]"), "{e}");
    let m = spec(&good).model;
    assert!(m.matrices(&[f64::NAN; 6]).is_err());
    assert!(m.matrices(&[1.0; 5]).is_err());
    // a response the model lacks, a response without coherent points
    let grid = log_grid(1.0, 10.0, 10).unwrap();
    let mut f = exact(&m, &TRUTH, 0, 1, &grid);
    let bad = Response {
        input: 0,
        output: 7,
        frf: f.clone(),
        omega_min_rad_s: 0.0,
        omega_max_rad_s: f64::INFINITY,
    };
    assert!(fit_ss(&m, &[bad], &CostOptions::default()).is_err());
    f.coherence.iter_mut().for_each(|c| *c = 0.3);
    let low = Response {
        input: 0,
        output: 1,
        frf: f,
        omega_min_rad_s: 0.0,
        omega_max_rad_s: f64::INFINITY,
    };
    let e = fit_ss(&m, &[low], &CostOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no point with γ² > 0.6"), "{e}");
}
