//! The measured side: per operating point, the conditioned composite
//! frequency responses of its log (as `crates/sim/tests/excitation.rs` and
//! `docs/ident.md` describe: half-overlapped Hann windows of each length in
//! `windows_s`, every response conditioned on the operating point's
//! `conditioned_on` inputs, the window lengths composited).

use crate::config::{IdentConfig, OperatingPoint, Response};
use crate::error::{ParamIdError, Result};
use helicon_ident::frf::{Frf, WindowSpec, composite, conditioned, cross_spectra_grid, log_grid};
use helicon_model::ConfigError;
use helicon_model::config_error::format_seconds;

/// The fewest samples a spectral window (`windows_s`) may hold.
const MIN_WINDOW_SAMPLES: f64 = 8.0;

/// Each of `cfg.windows_s` holds at least [`MIN_WINDOW_SAMPLES`] samples of
/// `dt_s` and at most half the record of `record_s` (of the log `log`).
fn check_windows(cfg: &IdentConfig, log: &str, dt_s: f64, record_s: f64) -> Result<()> {
    for (i, w) in cfg.windows_s.iter().enumerate() {
        // the spectra's own floor is 4 samples; 8 leaves its half-overlap
        // windows a frequency to resolve
        if *w < MIN_WINDOW_SAMPLES * dt_s {
            return Err(ConfigError::invalid(
                &cfg.file,
                format!("windows_s[{i}]"),
                *w,
                format!(
                    "{log}: a window must hold at least {MIN_WINDOW_SAMPLES} samples ({} s at {} s)",
                    format_seconds(MIN_WINDOW_SAMPLES * dt_s),
                    format_seconds(dt_s)
                ),
            )
            .into());
        }
        if 2.0 * w > record_s {
            return Err(ConfigError::invalid(
                &cfg.file,
                format!("windows_s[{i}]"),
                *w,
                format!("{log}: a window must be at most half the record used ({record_s:.1} s), for averaging"),
            )
            .into());
        }
    }
    Ok(())
}

/// One measured response.
#[derive(Debug, Clone)]
pub struct Measured {
    /// What it is.
    pub response: Response,
    /// Servo index of the input.
    pub input: usize,
    /// Reduced-state row of the output.
    pub state: usize,
    /// The conditioned composite estimate within the response's band.
    pub frf: Frf,
}

/// The measured responses of one operating point.
#[derive(Debug, Clone)]
pub struct PointData {
    /// Operating point name.
    pub name: String,
    /// The log's sample time, s.
    pub sample_time_s: f64,
    /// Responses, in the point's order.
    pub responses: Vec<Measured>,
}

/// A log's columns cut to `[t_start_s, t_end_s]`, checked for a uniform step.
#[derive(Debug, Clone)]
pub struct Record {
    /// Sample time, s.
    pub dt_s: f64,
    /// Time, s.
    pub t_s: Vec<f64>,
    /// The columns, in the order asked.
    pub columns: Vec<Vec<f64>>,
}

/// The response of `output` to input `which` of `inputs` with instrumental
/// variables (the excitations added to the inputs, one per input): with
/// y = Σ_b H_b u_b + v and v uncorrelated with the instruments e,
/// G_ey = G_eu H, so H = G_eu⁻¹ G_ey at each frequency. A feedback law
/// answering turbulence and sensor noise correlates the inputs with v, which
/// biases the conditioned estimate G_uu⁻¹ G_uy; the instruments are not
/// correlated with v.
///
/// The coherence given is the one that states this estimate's own random
/// error. With the equation error v = y − Σ_b H_b u_b (its spectrum G_vv
/// from the spectra and the estimated H), Ĥ − H = G_eu⁻¹ G_ev has the
/// covariance M G_vv / n_d, M = G_eu⁻¹ G_ee G_eu⁻ᴴ, so the relative random
/// error of |H_w| is √(M_ww G_vv / (2 n_d |H_w|²)); the coherence
/// γ² = |H_w|² / (|H_w|² + M_ww G_vv) gives it through the usual
/// √(1 − γ²)/(|γ| √(2 n_d)) (with e = u it is the ordinary coherence).
/// It is per input and open-loop: under feedback the law hides the
/// disturbance from the output (so the multiple coherence of the output on
/// the excitations stays high) while it moves the servos to cancel it, which
/// is what spoils the estimate; M_ww is large where the excitation `which`
/// moves its servo little against the others. Points where G_eu or G_ee is
/// singular are left out.
pub fn instrumented(
    cs: &helicon_ident::frf::CrossSpectra,
    instruments: &[usize],
    inputs: &[usize],
    output: usize,
    which: usize,
) -> std::result::Result<Frf, helicon_ident::IdentError> {
    use helicon_ident::Complex64;
    use nalgebra::{DMatrix, DVector};
    let q = inputs.len();
    let dof = cs.n_d - q as f64 + 1.0;
    if instruments.len() != q || which >= q || dof.is_nan() || dof < 1.0 {
        return Err(helicon_ident::IdentError::data(
            "instrumented response",
            format!(
                "{} instruments for {q} inputs, {:.2} effective averages: use shorter windows or a longer record",
                instruments.len(),
                cs.n_d
            ),
        ));
    }
    let inverse = |m: DMatrix<Complex64>| -> Option<DMatrix<Complex64>> {
        let scale = (0..m.nrows()).map(|i| m[(i, i)].norm()).fold(0.0, f64::max);
        let inv = m.try_inverse()?;
        let ok = scale > 0.0
            && inv.iter().all(|v| v.re.is_finite() && v.im.is_finite())
            && inv.iter().map(|v| v.norm()).fold(0.0, f64::max) * scale < 1e12;
        ok.then_some(inv)
    };
    let mut f = Frf {
        omega_rad_s: Vec::new(),
        h: Vec::new(),
        coherence: Vec::new(),
        random_error: Vec::new(),
    };
    for (k, &om) in cs.omega_rad_s.iter().enumerate() {
        let geu = DMatrix::from_fn(q, q, |a, b| cs.get(k, instruments[a], inputs[b]));
        let gee = DMatrix::from_fn(q, q, |a, b| cs.get(k, instruments[a], instruments[b]));
        let gey = DVector::from_fn(q, |a, _| cs.get(k, instruments[a], output));
        let gyy = cs.get(k, output, output).re;
        let (Some(ieu), Some(_)) = (inverse(geu), inverse(gee.clone())) else {
            continue;
        };
        let h = &ieu * &gey;
        // equation-error spectrum G_vv = G_yy − 2 Re Σ_b H_b conj(G_uby) + Hᴴ G_uu H
        let guu = DMatrix::from_fn(q, q, |a, b| cs.get(k, inputs[a], inputs[b]));
        let guy = DVector::from_fn(q, |a, _| cs.get(k, inputs[a], output));
        let cross: Complex64 = h.iter().zip(guy.iter()).map(|(hb, g)| hb * g.conj()).sum();
        let gvv = (gyy - 2.0 * cross.re + h.dotc(&(&guu * &h)).re).max(0.0);
        let m_ww = (&ieu * gee * ieu.adjoint())[(which, which)].re;
        let h2 = h[which].norm_sqr();
        let g2 = (h2 / (h2 + m_ww * gvv)).clamp(0.0, 1.0);
        let eps = (1.0 - g2).sqrt() / (g2.sqrt() * (2.0 * dof).sqrt());
        if h[which].re.is_finite() && h[which].im.is_finite() && g2.is_finite() && eps.is_finite() {
            f.omega_rad_s.push(om);
            f.h.push(h[which]);
            f.coherence.push(g2);
            f.random_error.push(eps);
        }
    }
    Ok(f)
}

/// Read `names` from the log at `path` (a `log.csv` or a flight computer's
/// ULog, [`crate::source`]), keep `[t0, t1]`, check that the control law
/// drove the servos throughout (a log with a `servo_source` column,
/// [`crate::source::servo_spans`]), that the step is uniform (to 1e-6 of
/// its median) and equals `expected_dt_s` (the control period, to 1e-6):
/// the model's responses are those of a command held over one control
/// period. `field` names the log's entry in the IDENT.toml `file`; every
/// error names both.
pub fn read_record(
    path: &std::path::Path,
    names: &[&str],
    t0: Option<f64>,
    t1: Option<f64>,
    expected_dt_s: f64,
    file: &str,
    field: &str,
) -> Result<Record> {
    let table = crate::source::read_log(path, names, expected_dt_s).map_err(|source| {
        ParamIdError::LogOf {
            file: file.to_string(),
            field: field.to_string(),
            source: Box::new(source),
        }
    })?;
    let t = table.column("t_s");
    let keep: Vec<usize> = (0..t.len())
        .filter(|&k| t0.is_none_or(|a| t[k] >= a) && t1.is_none_or(|b| t[k] <= b))
        .collect();
    let log = path.display().to_string();
    let ts: Vec<f64> = keep.iter().map(|&k| t[k]).collect();
    if let Some(source) = &table.servo_source {
        let used: Vec<f64> = keep.iter().map(|&k| source[k]).collect();
        let spans = crate::source::servo_spans(&ts, &used);
        if !spans.is_empty() {
            return Err(ParamIdError::NotLawDriven {
                file: file.to_string(),
                field: field.to_string(),
                log,
                spans,
            });
        }
    }
    if keep.len() < 64 {
        return Err(ConfigError::invalid(
            file,
            field,
            keep.len() as f64,
            format!("{log}: needs at least 64 samples in the time span used"),
        )
        .into());
    }
    let mut steps: Vec<f64> = ts.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let dt = steps[steps.len() / 2];
    let invalid_step = |rule: String| ConfigError::Invalid {
        file: file.to_string(),
        field: field.to_string(),
        value: format_seconds(dt),
        rule: format!("{log}: {rule}"),
    };
    if (steps[0] - dt).abs() > 1e-6 * dt || (steps[steps.len() - 1] - dt).abs() > 1e-6 * dt {
        return Err(invalid_step(format!(
            "the time step varies ({} to {} s): identification needs a uniform log (no decimation gaps)",
            format_seconds(steps[0]),
            format_seconds(steps[steps.len() - 1])
        ))
        .into());
    }
    if (dt - expected_dt_s).abs() > 1e-6 * expected_dt_s {
        return Err(invalid_step(format!(
            "the log's step must be the control period control.sample_time_s = {} s (log every sample)",
            format_seconds(expected_dt_s)
        ))
        .into());
    }
    let mut columns = Vec::with_capacity(names.len());
    for n in names {
        let c = table.column(n);
        columns.push(keep.iter().map(|&k| c[k]).collect());
    }
    Ok(Record {
        dt_s: dt,
        t_s: ts,
        columns,
    })
}

/// The measured responses of operating point `index` of `cfg`.
pub fn measure(cfg: &IdentConfig, index: usize) -> Result<PointData> {
    let op: &OperatingPoint = &cfg.operating_points[index];
    let field = format!("operating_point[{index}].log");
    let mut names: Vec<&str> = op.conditioned_on.iter().map(String::as_str).collect();
    let nq = names.len();
    names.extend(op.instruments.iter().map(String::as_str));
    let inst: Vec<usize> = (nq..names.len()).collect();
    for r in &op.response {
        if !names.contains(&r.output.as_str()) {
            names.push(&r.output);
        }
    }
    let rec = read_record(
        &op.log,
        &names,
        op.t_start_s,
        op.t_end_s,
        cfg.start.control.sample_time_s,
        &cfg.file,
        &field,
    )?;
    let log = op.log.display().to_string();
    let record_s = rec.dt_s * rec.t_s.len() as f64;
    check_windows(cfg, &log, rec.dt_s, record_s)?;
    let lo = op
        .response
        .iter()
        .map(|r| r.omega_min_rad_s)
        .fold(f64::INFINITY, f64::min);
    let hi = op
        .response
        .iter()
        .map(|r| r.omega_max_rad_s)
        .fold(0.0, f64::max);
    let nyq = std::f64::consts::PI / rec.dt_s;
    if hi >= nyq {
        return Err(ConfigError::invalid(
            &cfg.file,
            format!("operating_point[{index}].response"),
            hi,
            format!("omega_max_rad_s must be below the log's Nyquist frequency {nyq:.1} rad/s"),
        )
        .into());
    }
    let frf_err = |what: String| {
        let file = log.clone();
        move |source| ParamIdError::Frf {
            file,
            what,
            source: Box::new(source),
        }
    };
    let grid = log_grid(lo, hi, cfg.points).map_err(frf_err("grid".into()))?;
    let refs: Vec<&[f64]> = rec.columns.iter().map(Vec::as_slice).collect();
    let spectra = cfg
        .windows_s
        .iter()
        .map(|w| {
            let spec = WindowSpec::half_overlap((w / rec.dt_s).round() as usize);
            cross_spectra_grid(&refs, rec.dt_s, spec, &grid)
                .map_err(frf_err(format!("spectra of {w} s windows")))
        })
        .collect::<Result<Vec<_>>>()?;
    let cond: Vec<usize> = (0..nq).collect();
    let mut responses = Vec::with_capacity(op.response.len());
    for r in &op.response {
        let (Some(input), Some(state)) = (r.input_index(), r.state_index()) else {
            return Err(ParamIdError::Fit(format!(
                "response {} unchecked",
                r.label()
            )));
        };
        let out = names.iter().position(|n| *n == r.output).unwrap_or(0);
        let pos = op
            .conditioned_on
            .iter()
            .position(|c| *c == r.input)
            .unwrap_or(0);
        let parts = spectra
            .iter()
            .map(|cs| {
                if inst.is_empty() {
                    conditioned(cs, &cond, out)
                        .map(|(mut v, _)| v.swap_remove(pos))
                        .map_err(frf_err(r.label()))
                } else {
                    instrumented(cs, &inst, &cond, out, pos).map_err(frf_err(r.label()))
                }
            })
            .collect::<Result<Vec<_>>>()?;
        let c = composite(&parts, &cfg.windows_s).map_err(frf_err(r.label()))?;
        let keep: Vec<usize> = (0..c.len())
            .filter(|&k| {
                c.omega_rad_s[k] >= r.omega_min_rad_s * (1.0 - 1e-12)
                    && c.omega_rad_s[k] <= r.omega_max_rad_s * (1.0 + 1e-12)
            })
            .collect();
        let frf = Frf {
            omega_rad_s: keep.iter().map(|&k| c.omega_rad_s[k]).collect(),
            h: keep.iter().map(|&k| c.h[k]).collect(),
            coherence: keep.iter().map(|&k| c.coherence[k]).collect(),
            random_error: keep.iter().map(|&k| c.random_error[k]).collect(),
        };
        responses.push(Measured {
            response: r.clone(),
            input,
            state,
            frf,
        });
    }
    Ok(PointData {
        name: op.name.clone(),
        sample_time_s: rec.dt_s,
        responses,
    })
}

/// Noise-free "measurements": the responses of the model with parameters
/// `truth` at every operating point of `cfg`, on its log-spaced grid of each
/// response's band (γ² = 1, no random error), sampled at the control
/// period. For checking the identification against a known answer.
pub fn from_model(cfg: &IdentConfig, truth: &helicon_model::Params) -> Result<Vec<PointData>> {
    let ts = cfg.start.control.sample_time_s;
    cfg.operating_points
        .iter()
        .map(|op| {
            let grids = op
                .response
                .iter()
                .map(|r| {
                    log_grid(r.omega_min_rad_s, r.omega_max_rad_s, cfg.points).map_err(|source| {
                        ParamIdError::Frf {
                            file: cfg.file.clone(),
                            what: r.label(),
                            source: Box::new(source),
                        }
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            let wanted: Vec<(usize, usize, &[f64])> = op
                .response
                .iter()
                .zip(&grids)
                .map(|(r, g)| {
                    (
                        r.input_index().unwrap_or(0),
                        r.state_index().unwrap_or(0),
                        g.as_slice(),
                    )
                })
                .collect();
            let target = crate::linear::target(op.velocity_ned_m_s, op.yaw_rad);
            let (h, _) =
                crate::linear::point_responses(truth, cfg.preset, &target, &op.name, ts, &wanted)?;
            let responses = op
                .response
                .iter()
                .zip(grids)
                .zip(h)
                .map(|((r, g), h)| Measured {
                    response: r.clone(),
                    input: r.input_index().unwrap_or(0),
                    state: r.state_index().unwrap_or(0),
                    frf: Frf {
                        coherence: vec![1.0; g.len()],
                        random_error: vec![0.0; g.len()],
                        omega_rad_s: g,
                        h,
                    },
                })
                .collect();
            Ok(PointData {
                name: op.name.clone(),
                sample_time_s: ts,
                responses,
            })
        })
        .collect()
}
