//! `helicon sensors shaker`: the accelerometer on a one-axis exciter (thesis
//! Appendix A), its output and moving average, and the hidden-saturation map
//! over frequency and amplitude.

use crate::sensors::params_from;
use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use helicon_sim::plot::{Figure, HLine, LinePlot, Panel, Series};
use helicon_sim::sensors::SensorConfig;
use helicon_sim::shaker::{ShakerConfig, ShakerSample, ideal_part, shake};
use std::path::PathBuf;

/// An accelerometer axis.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisArg {
    /// Body x (forward).
    X,
    /// Body y (right).
    Y,
    /// Body z (down; reads −1 g at rest).
    Z,
}

/// Arguments of `helicon sensors shaker`.
#[derive(Args, Debug)]
pub struct ShakerArgs {
    /// Excited axis (gravity lies along z: z reads −1 g at rest, x and y 0).
    #[arg(long, value_enum, default_value_t = AxisArg::Z)]
    pub axis: AxisArg,
    /// Excitation frequency (Hz).
    #[arg(long)]
    pub freq_hz: f64,
    /// Excitation amplitude, zero to peak, in g (local gravity).
    #[arg(long)]
    pub amplitude_g: f64,
    /// Output and mechanical range of the part (± g; the thesis's first part: 2).
    #[arg(long, default_value_t = 2.0)]
    pub range_g: f64,
    /// Sensor configuration TOML: `imu.rate_hz`, `imu.accel` noise and bias,
    /// `[imu.accel_stage]` (filter order and cut-off, mechanical bandwidth),
    /// `imu.vibration.oversample` (default: `helicon sensors config`).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// An ideal part: no noise, bias, scale-factor error or quantisation
    /// (the sweep always uses one).
    #[arg(long)]
    pub ideal: bool,
    /// Helicopter parameters TOML: local gravity `environment.g_m_s2`, the
    /// unit g (default: the Bergen Twin's, 9.82 m/s² as in the thesis's figures).
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Duration of the run (s); the first 0.5 s settle the filters.
    // `--duration-s`: the old spelling
    #[arg(
        long = "duration",
        alias = "duration-s",
        value_name = "S",
        default_value_t = 5.0
    )]
    pub duration_s: f64,
    /// Output samples shown in the figure (the thesis's figures show 500).
    #[arg(long, default_value_t = 500)]
    pub plot_samples: usize,
    /// Frequencies of the sweep (Hz), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "5,10,20,40,80,160,320,640"
    )]
    pub sweep_freq_hz: Vec<f64>,
    /// Largest amplitude of the sweep (g); 17 amplitudes from 0.
    #[arg(long, default_value_t = 4.0)]
    pub sweep_max_g: f64,
    /// Skip the sweep.
    #[arg(long)]
    pub no_sweep: bool,
    /// Output folder: shaker.csv, shaker.{png,svg}, summary.json, map.csv, map.{png,svg}.
    #[arg(long)]
    pub out: PathBuf,
}

const SHAKER_SETTLE_S: f64 = 0.5;

fn shaker_config(args: &ShakerArgs, g: f64) -> Result<ShakerConfig> {
    let file_cfg = match &args.config {
        Some(p) => SensorConfig::from_file(p)?,
        None => SensorConfig::default(),
    };
    if !(args.range_g.is_finite() && args.range_g > 0.0 && args.range_g <= 1000.0) {
        bail!(
            "--range-g {} is invalid (allowed: 0 < range <= 1000)",
            helicon_sim::scenario::num(args.range_g)
        );
    }
    let range = args.range_g * g;
    let mut sensors = if args.ideal {
        ideal_part(file_cfg, range)
    } else {
        let mut c = file_cfg;
        c.imu.accel.range = range;
        c.imu.accel.resolution = c.imu.accel.resolution.min(2.0 * range / 65536.0);
        c.imu.accel_stage.mechanical_range = Some(range);
        c
    };
    sensors.imu.vibration.enabled = true;
    Ok(ShakerConfig {
        sensors,
        axis: match args.axis {
            AxisArg::X => 0,
            AxisArg::Y => 1,
            AxisArg::Z => 2,
        },
        freq_hz: args.freq_hz,
        amplitude_m_s2: args.amplitude_g * g,
        gravity_m_s2: g,
        duration_s: args.duration_s,
        settle_s: SHAKER_SETTLE_S,
    })
}

/// Centred moving average over `window` samples (shorter at the ends).
fn moving_average(y: &[f64], window: usize) -> Vec<f64> {
    let mut prefix = Vec::with_capacity(y.len() + 1);
    prefix.push(0.0);
    for v in y {
        prefix.push(prefix[prefix.len() - 1] + v);
    }
    let half = window / 2;
    (0..y.len())
        .map(|k| {
            let a = k.saturating_sub(half);
            let b = (k + half + 1).min(y.len());
            (prefix[b] - prefix[a]) / (b - a) as f64
        })
        .collect()
}

/// `helicon sensors shaker`.
pub fn run_shaker(args: &ShakerArgs) -> Result<()> {
    let g = params_from(&args.params)?.environment.g_m_s2;
    let cfg = shaker_config(args, g)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut samples = Vec::new();
    let summary = shake(&cfg, |s| samples.push(*s))?;
    let rate = cfg.sensors.imu.rate_hz;
    // the moving average: at least 0.1 s and two excitation periods
    let window = ((0.1f64).max(2.0 / args.freq_hz) * rate).round().max(1.0) as usize;
    let ys: Vec<f64> = samples.iter().map(|s| s.output_m_s2 / g).collect();
    let avg = moving_average(&ys, window);
    let path = args.out.join("shaker.csv");
    let mut w = csv::Writer::from_path(&path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    w.write_record(["t_s", "output_g", "moving_average_g", "clipped_fraction"])?;
    for ((s, y), a) in samples.iter().zip(&ys).zip(&avg) {
        w.write_record([
            s.t_s.to_string(),
            y.to_string(),
            a.to_string(),
            s.clipped_fraction.to_string(),
        ])?;
    }
    w.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    shaker_figure(args, &cfg, &samples, &ys, &avg, window)?;
    let json = serde_json::json!({
        "axis": format!("{:?}", args.axis).to_lowercase(),
        "freq_hz": args.freq_hz,
        "amplitude_g": args.amplitude_g,
        "range_g": args.range_g,
        "g_m_s2": g,
        "ideal": args.ideal,
        "filter_order": cfg.sensors.imu.accel_stage.filter_order,
        "filter_cutoff_hz": cfg.sensors.imu.accel_stage.filter_cutoff_hz,
        "mechanical_bandwidth_hz": cfg.sensors.imu.accel_stage.mechanical_bandwidth_hz,
        "rate_hz": rate,
        "mean_g": summary.mean_m_s2 / g,
        "closed_form_mean_g": summary.expected_mean_m_s2 / g,
        "rest_g": summary.rest_m_s2 / g,
        "shift_g": summary.shift_m_s2() / g,
        "output_min_g": summary.output_min_m_s2 / g,
        "output_max_g": summary.output_max_m_s2 / g,
        "clipped_fraction": summary.clipped_fraction,
        "clipping_visible": summary.clipping_visible(),
        "samples_averaged": summary.samples,
    });
    let text = serde_json::to_string_pretty(&json)?;
    std::fs::write(args.out.join("summary.json"), text + "\n")
        .with_context(|| format!("cannot write {}/summary.json", args.out.display()))?;
    println!(
        "shaker {:?} axis, {} Hz, {} g on a ±{} g part: mean {:.4} g (closed form {:.4} g, rest {:.0} g), \
         output {:.3}..{:.3} g, mechanical stage clipped {:.1} % of the time{}",
        args.axis,
        args.freq_hz,
        args.amplitude_g,
        args.range_g,
        summary.mean_m_s2 / g,
        summary.expected_mean_m_s2 / g,
        summary.rest_m_s2 / g,
        summary.output_min_m_s2 / g,
        summary.output_max_m_s2 / g,
        100.0 * summary.clipped_fraction,
        if summary.clipped_fraction > 0.0 && !summary.clipping_visible() {
            ": HIDDEN saturation"
        } else {
            ""
        }
    );
    if !args.no_sweep {
        shaker_sweep(args, &cfg, g)?;
    }
    println!("wrote {}", args.out.display());
    Ok(())
}

fn shaker_figure(
    args: &ShakerArgs,
    cfg: &ShakerConfig,
    samples: &[ShakerSample],
    ys: &[f64],
    avg: &[f64],
    window: usize,
) -> Result<()> {
    let first = samples
        .iter()
        .position(|s| s.t_s > SHAKER_SETTLE_S)
        .unwrap_or(0);
    let last = (first + args.plot_samples.max(2)).min(samples.len());
    let pts = |v: &[f64]| -> Vec<(f64, f64)> {
        (first..last).map(|k| ((k - first) as f64, v[k])).collect()
    };
    let (out_pts, avg_pts) = (pts(ys), pts(avg));
    let avg_name = format!("mean of {window}");
    let mut panel = Panel::new("acceleration [g]")
        .series(Series::new("acc. output", &out_pts).color([31, 119, 180]))
        .series(Series::new(&avg_name, &avg_pts).color([214, 39, 40]));
    panel.hlines = vec![
        HLine {
            y: args.range_g,
            label: format!("+{} g", args.range_g),
            color: [90, 90, 90],
        },
        HLine {
            y: -args.range_g,
            label: format!("-{} g", args.range_g),
            color: [90, 90, 90],
        },
    ];
    panel.y_include = vec![-args.range_g, args.range_g];
    let st = &cfg.sensors.imu.accel_stage;
    let title = format!(
        "Shaker: {} Hz, {} g on {:?}; ±{} g part, order-{} {} Hz internal filter, {} Hz",
        args.freq_hz,
        args.amplitude_g,
        args.axis,
        args.range_g,
        st.filter_order,
        st.filter_cutoff_hz,
        cfg.sensors.imu.rate_hz
    );
    let fig = Figure::new(&title, "sample number [-]").panel(panel);
    for ext in ["png", "svg"] {
        fig.write(&args.out.join(format!("shaker.{ext}")))?;
    }
    Ok(())
}

/// The hidden-saturation map: the mean shift over frequency and amplitude
/// (ideal part, so only the clipping moves the mean).
fn shaker_sweep(args: &ShakerArgs, cfg: &ShakerConfig, g: f64) -> Result<()> {
    let path = args.out.join("map.csv");
    let mut w = csv::Writer::from_path(&path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    w.write_record([
        "freq_hz",
        "amplitude_g",
        "mean_g",
        "closed_form_mean_g",
        "shift_g",
        "output_min_g",
        "output_max_g",
        "clipped_fraction",
        "hidden",
    ])?;
    let range = cfg.sensors.imu.accel.range;
    let mut curves: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for &f in &args.sweep_freq_hz {
        let mut pts = Vec::new();
        for k in 0..=16 {
            let a_g = args.sweep_max_g * f64::from(k) / 16.0;
            let run = ShakerConfig {
                sensors: ideal_part(cfg.sensors, range),
                freq_hz: f,
                amplitude_m_s2: a_g * g,
                duration_s: SHAKER_SETTLE_S + (20.0 / f).max(2.0),
                ..*cfg
            };
            let s = shake(&run, |_| {}).with_context(|| format!("sweep at {f} Hz"))?;
            let hidden = s.clipped_fraction > 0.0 && !s.clipping_visible();
            w.write_record([
                f.to_string(),
                a_g.to_string(),
                (s.mean_m_s2 / g).to_string(),
                (s.expected_mean_m_s2 / g).to_string(),
                (s.shift_m_s2() / g).to_string(),
                (s.output_min_m_s2 / g).to_string(),
                (s.output_max_m_s2 / g).to_string(),
                s.clipped_fraction.to_string(),
                u8::from(hidden).to_string(),
            ])?;
            pts.push((a_g, s.shift_m_s2() / g));
        }
        curves.push((format!("{f} Hz"), pts));
    }
    w.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    let mut plot = LinePlot::new(
        &format!(
            "Mean shift of a ±{} g accelerometer on the {:?} axis (hidden saturation map)",
            args.range_g, args.axis
        ),
        "vibration amplitude [g]",
        "mean shift [g]",
    );
    for (name, pts) in &curves {
        plot = plot.series(Series::new(name, pts));
    }
    for ext in ["png", "svg"] {
        plot.write(&args.out.join(format!("map.{ext}")))?;
    }
    Ok(())
}
