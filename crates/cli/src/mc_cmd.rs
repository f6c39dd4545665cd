//! `helicon mc CAMPAIGN.toml` (Monte Carlo campaigns, shards, merge) and
//! `helicon bench` (timings of the hot path on this machine).

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use helicon_model::integrate::rk4;
use helicon_model::state::expand;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{Input, Model, Preset, State};
use helicon_sim::closed_loop::{fly, fly_to, prepare};
use helicon_sim::log_csv::LogWriter;
use helicon_sim::mc::{Campaign, CampaignOverrides, RunOptions, Shard, merge, run};
use helicon_sim::scenario::Scenario;
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::Vector3;
use std::path::PathBuf;
use std::time::Instant;

mod slurm;

/// `helicon mc`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct McArgs {
    /// Merge shard folders instead of running.
    #[command(subcommand)]
    pub command: Option<McCommand>,
    /// Campaign file (TOML; see docs/monte-carlo.md and campaigns/).
    #[arg(required = true)]
    pub campaign: Option<PathBuf>,
    /// Number of runs (overrides the campaign's `runs`; ≥ 1). Memory does not
    /// grow with it (each run goes to the run store on disk); bounded by the
    /// output folder's free disk space (use --shard beyond that).
    #[arg(long, value_parser = at_least_one, allow_negative_numbers = true)]
    pub runs: Option<usize>,
    /// Campaign seed (overrides the campaign's `seed`; a new campaign hash).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Flight duration in seconds (overrides the scenario's `duration_s`;
    /// finite, > 0 and <= 86400).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Nominal plant parameters: a TOML file of `helicon params` keys over the
    /// Bergen Twin (overrides the scenario's `params`); dispersions apply around it.
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Keep traces only for the runs with an index below N (overrides the
    /// campaign's `trace_runs`; a new campaign hash).
    #[arg(long, value_name = "N")]
    pub trace_runs: Option<usize>,
    /// Worker threads (default: one per core; ≥ 1).
    #[arg(long, value_parser = at_least_one)]
    pub threads: Option<usize>,
    /// Output folder (default `out/mc/<name>-seed<seed>[-shard<K>of<M>]`);
    /// runs already recorded there are skipped (resume).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run only indices ≡ K (mod M); K is 0-based (0 ≤ K < M), e.g. a Slurm
    /// array index `--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Run on a Slurm cluster: write a job array of --array shard tasks and
    /// a merge job after them (`afterok`) into OUT/slurm/, submit both with
    /// `sbatch` and print their ids. Submitting again submits only what is
    /// missing (see `helicon mc status OUT`).
    #[arg(long, conflicts_with = "shard")]
    pub slurm: bool,
    /// With --slurm: array tasks, one shard each (1 <= K <= runs; default
    /// 10, or the runs if fewer).
    #[arg(long, value_name = "K", requires = "slurm", value_parser = at_least_one)]
    pub array: Option<usize>,
    /// With --slurm: the partition (`#SBATCH --partition`).
    #[arg(long, value_name = "P", requires = "slurm")]
    pub partition: Option<String>,
    /// With --slurm: the time limit of each task and of the merge
    /// (`#SBATCH --time`: minutes, HH:MM:SS, D-HH:MM, …).
    #[arg(long, value_name = "T", requires = "slurm")]
    pub time: Option<String>,
    /// With --slurm: CPUs per task (`#SBATCH --cpus-per-task`, the task's
    /// --threads; default 1).
    #[arg(long, value_name = "C", requires = "slurm", value_parser = at_least_one)]
    pub cpus_per_task: Option<usize>,
    /// With --slurm: write the batch scripts and print the `sbatch` commands,
    /// submit nothing.
    #[arg(long, requires = "slurm")]
    pub dry_run: bool,
}

/// A whole number ≥ 1.
fn at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("must be >= 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("`{s}`: {e}")),
    }
}

/// `helicon mc` subcommands.
#[derive(Subcommand, Debug)]
pub enum McCommand {
    /// Combine shard folders of one campaign (checked by hash) into one.
    Merge(MergeArgs),
    /// How far a campaign folder is: runs done; for a `--slurm` folder, each
    /// shard done/running/pending/failed (its folder, `squeue`/`sacct`) and
    /// the merge.
    Status(StatusArgs),
}

/// `helicon mc status`.
#[derive(Args, Debug)]
pub struct StatusArgs {
    /// The campaign folder (the `--out` of `helicon mc`, with or without --slurm).
    pub dir: PathBuf,
}

/// `helicon mc merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Shard folders.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Run `helicon mc`.
pub fn run_mc(args: &McArgs) -> Result<()> {
    if let Some(McCommand::Merge(m)) = &args.command {
        let report = merge(&m.dirs, &m.out).context("merging shard folders")?;
        let s = &report.stats;
        crate::console::note!(
            "merged {} runs into {}: {} completed, {} failed ({:.1} %)",
            s.runs,
            m.out.display(),
            s.completed,
            s.failed,
            100.0 * s.failure_fraction
        );
        if let Some(g) = &s.ground {
            crate::console::note!("take-offs and landings: {}", g.headline());
        }
        return Ok(());
    }
    if let Some(McCommand::Status(st)) = &args.command {
        return slurm::status(&st.dir);
    }
    let Some(path) = &args.campaign else {
        anyhow::bail!("give a campaign file (or `helicon mc merge DIR... --out DIR`)");
    };
    let campaign = Campaign::from_file(path)?
        .with_overrides(&CampaignOverrides {
            seed: args.seed,
            duration_s: args.duration,
            params: args.params.clone(),
            trace_runs: args.trace_runs,
        })
        .with_context(|| format!("campaign {}", path.display()))?;
    let out = args.out.clone().unwrap_or_else(|| {
        let mut n = format!("{}-seed{}", campaign.name, campaign.seed);
        if let Some(s) = args.shard {
            n.push_str(&format!("-shard{}of{}", s.k, s.m));
        }
        PathBuf::from("out").join("mc").join(n)
    });
    if args.slurm {
        let runs = args.runs.unwrap_or(campaign.runs);
        let mut campaign_args = Vec::new();
        if let Some(s) = args.seed {
            campaign_args.extend(["--seed".to_string(), s.to_string()]);
        }
        if let Some(d) = args.duration {
            campaign_args.extend(["--duration".to_string(), d.to_string()]);
        }
        if let Some(p) = &args.params {
            let abs =
                std::fs::canonicalize(p).with_context(|| format!("--params {}", p.display()))?;
            campaign_args.extend(["--params".to_string(), abs.display().to_string()]);
        }
        if let Some(n) = args.trace_runs {
            campaign_args.extend(["--trace-runs".to_string(), n.to_string()]);
        }
        let req = slurm::SlurmRequest {
            runs,
            array: args.array.unwrap_or_else(|| runs.min(10)),
            partition: args.partition.clone(),
            time: args.time.clone(),
            cpus_per_task: args.cpus_per_task.unwrap_or(1),
            dry_run: args.dry_run,
            campaign_args,
        };
        return slurm::submit(&campaign, path, &out, &req);
    }
    let options = RunOptions {
        runs: args.runs,
        threads: args.threads,
        shard: args.shard,
        disk_budget_bytes: None,
    };
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs ({per_sec}, ETA {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let progress = |done: usize, total: usize| {
        if bar.length() != Some(total as u64) {
            bar.set_length(total as u64);
        }
        bar.set_position(done as u64);
    };
    let t0 = Instant::now();
    let report = run(&campaign, &options, &out, Some(&progress))
        .with_context(|| format!("campaign {}", path.display()))?;
    bar.finish_and_clear();
    let s = &report.stats;
    crate::console::note!(
        "{}: {} runs flown in {:.1} s ({} already done), {} recorded: {} completed, {} failed ({:.1} %)",
        campaign.name,
        report.flown,
        t0.elapsed().as_secs_f64(),
        report.skipped,
        s.runs,
        s.completed,
        s.failed,
        100.0 * s.failure_fraction
    );
    for f in &s.failures {
        crate::console::note!(
            "  {:6} × {}: {} (first: run {}: {})",
            f.runs,
            f.outcome,
            f.termination.as_str(),
            f.first_run,
            f.example
        );
    }
    if let Some(g) = &s.ground {
        crate::console::note!("take-offs and landings: {}", g.headline());
    }
    crate::console::note!("outputs in {}", out.display());
    Ok(())
}

/// `helicon bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Print the figures as JSON: `derivative_ns`, `rk4_step_ns`,
    /// `closed_loop_step_ns`, `closed_loop_rtf`, `log_row_ns`,
    /// `sim_with_log_step_ns`, `sim_with_log_rtf`, `eskf_step_imu_ns`,
    /// `eskf_step_mag_ns`, `eskf_step_gps_ns`.
    #[arg(long)]
    pub json: bool,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The closed loop measured by `helicon bench`: thesis controller with
/// sensors, q-method + fusion and the state estimator, hovering in calm air.
pub const BENCH_SCENARIO: &str = r#"
name = "bench"
preset = "thesis"
duration_s = 2.0
[controller]
input_max = [0.1, 0.7, 0.7, 0.04]
estimator = true
fusion = true
"#;

/// Run `helicon bench`.
pub fn run_bench(args: &BenchArgs) -> Result<()> {
    // 1. derivative: hover trim of the Bergen Twin, batches of evaluations
    let model = Model::bergen_twin(Preset::Thesis);
    let t = trim(
        &model,
        &TrimTarget {
            velocity_ned_m_s: Vector3::zeros(),
            yaw_rad: 0.0,
            wind_ned_m_s: Vector3::zeros(),
        },
        &TrimOptions::default(),
    )
    .context("hover trim")?;
    let x: State = expand(&t.x, [0.0; 3]);
    let u: Input = t.u;
    let w = Vector3::zeros();
    let batch = 20_000;
    let mut per = Vec::new();
    let mut sink = 0.0;
    for _ in 0..15 {
        let t0 = Instant::now();
        for _ in 0..batch {
            let (d, _) = model.derivative(std::hint::black_box(&x), &u, &w)?;
            sink += d[5];
        }
        per.push(t0.elapsed().as_secs_f64() * 1e9 / f64::from(batch));
    }
    let derivative_ns = median(per);
    // RK4 step for reference (4 derivatives)
    let mut per = Vec::new();
    for _ in 0..15 {
        let t0 = Instant::now();
        for _ in 0..batch / 4 {
            let n = rk4(std::hint::black_box(&x), 0.0025, |s| {
                model.derivative(s, &u, &w).map(|r| r.0)
            })?;
            sink += n[5];
        }
        per.push(t0.elapsed().as_secs_f64() * 1e9 / f64::from(batch / 4));
    }
    let rk4_ns = median(per);
    std::hint::black_box(sink);
    // 2. closed loop: whole flights (sensors, fusion, estimator, controller,
    // RK4, logging and metrics) divided by their steps; median of flights
    let scenario = Scenario::from_toml_str(BENCH_SCENARIO, "<bench scenario>")?;
    let prepared = prepare(&scenario)?;
    let mut per = Vec::new();
    for _ in 0..15 {
        let t0 = Instant::now();
        let f = fly(&scenario, &prepared, None)?;
        let steps = f.log.len().max(1) as f64;
        per.push(t0.elapsed().as_secs_f64() * 1e9 / steps);
    }
    let step_ns = median(per);
    let ts = prepared.gains.set.sample_time_s;
    let rtf = ts * 1e9 / step_ns;
    // 3. the log row: the flight's rows written to a log.csv (formatting
    // and buffered writes), and the flight as `helicon sim` flies it,
    // streaming its log.csv
    let flight = fly(&scenario, &prepared, None)?;
    let dir = std::env::temp_dir().join(format!("helicon-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let log_path = dir.join("log.csv");
    let mut per = Vec::new();
    for _ in 0..15 {
        let mut w = LogWriter::create(&log_path)?;
        let t0 = Instant::now();
        for r in &flight.log {
            w.write(r)?;
        }
        w.finish()?;
        per.push(t0.elapsed().as_secs_f64() * 1e9 / flight.log.len().max(1) as f64);
    }
    let log_row_ns = median(per);
    let mut per = Vec::new();
    for _ in 0..15 {
        let mut w = LogWriter::create(&log_path)?;
        let t0 = Instant::now();
        fly_to(&scenario, &prepared, &mut w, None)?;
        w.finish()?;
        let steps = (scenario.duration_s / ts).round().max(1.0);
        per.push(t0.elapsed().as_secs_f64() * 1e9 / steps);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let sim_step_ns = median(per);
    let sim_rtf = ts * 1e9 / sim_step_ns;
    // 4. the ESKF step at 400 Hz: IMU only, with the magnetometer, with a
    // delayed GPS fix (position, velocity) and the magnetometer
    let (eskf_imu_ns, eskf_mag_ns, eskf_gps_ns) = bench_eskf()?;
    let mut con = crate::console::Console::stdout();
    if args.json {
        writeln!(
            con,
            "{}",
            serde_json::json!({
                "derivative_ns": derivative_ns,
                "rk4_step_ns": rk4_ns,
                "closed_loop_step_ns": step_ns,
                "closed_loop_rtf": rtf,
                "log_row_ns": log_row_ns,
                "sim_with_log_step_ns": sim_step_ns,
                "sim_with_log_rtf": sim_rtf,
                "eskf_step_imu_ns": eskf_imu_ns,
                "eskf_step_mag_ns": eskf_mag_ns,
                "eskf_step_gps_ns": eskf_gps_ns,
            })
        );
    } else {
        writeln!(
            con,
            "derivative f(x, u, wind)        {derivative_ns:10.0} ns (median of 15 batches of {batch})"
        );
        writeln!(con, "RK4 step (4 derivatives)         {rk4_ns:10.0} ns");
        writeln!(
            con,
            "closed-loop step (sensors, fusion, estimator, controller, RK4, log) {step_ns:10.0} ns (median of 15 flights of {} s)",
            scenario.duration_s
        );
        writeln!(
            con,
            "closed-loop real-time factor     {rtf:10.0} × (one thread, Ts = {} ms)",
            ts * 1e3
        );
        writeln!(
            con,
            "log.csv row (83 numbers, buffered write) {log_row_ns:10.0} ns (median of 15 logs of {} rows)",
            flight.log.len()
        );
        writeln!(
            con,
            "closed-loop step streaming log.csv (helicon sim) {sim_step_ns:10.0} ns: {sim_rtf:.0} × real time"
        );
        writeln!(
            con,
            "ESKF step (15 states, 400 Hz)    {eskf_imu_ns:10.0} ns IMU only, {eskf_mag_ns:.0} ns with magnetometer, {eskf_gps_ns:.0} ns with GPS and magnetometer"
        );
    }
    con.finish().context("writing to stdout")
}

/// Median step costs (ns) of the ESKF at 400 Hz on a hovering IMU: IMU
/// only, with the magnetometer, with a delayed GPS fix and the magnetometer.
fn bench_eskf() -> Result<(f64, f64, f64)> {
    use helicon_core::eskf::{Eskf, EskfConfig, ImuNoise};
    use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame, SensorNoise};
    let imu = ImuNoise {
        accel_noise_density: 0.004,
        accel_bias_walk: 3e-4,
        accel_bias_sigma: 0.2,
        gyro_noise_density: 1e-4,
        gyro_bias_walk: 2e-5,
        gyro_bias_sigma: 0.01,
        mag_sigma: 0.002,
    };
    let noise = SensorNoise {
        gps_sigma_m: Vector3::new(1.5, 1.5, 3.0),
        gps_vel_sigma_m_s: Vector3::new(0.05, 0.05, 0.1),
        mag_field_ned: Vector3::new(0.153, 0.008, -0.438),
        gravity_m_s2: 9.81,
    };
    let dt = 0.0025;
    let mut f = Eskf::new(
        &EskfConfig::default(),
        &imu,
        &noise,
        dt,
        &nalgebra::SVector::<f64, 9>::zeros(),
    )?;
    let mut k = 0.0;
    let mut step = |f: &mut Eskf, mag: bool, gps: bool| {
        k += 1.0;
        let t: f64 = k * dt;
        let frame = SensorFrame {
            mag_body: mag.then_some(noise.mag_field_ned),
            gps: gps.then_some(GpsFix {
                epoch_s: t - 0.1,
                fix: GpsFixType::Fix3d,
                position_ned_m: Vector3::zeros(),
                velocity_ned_m_s: Some(Vector3::zeros()),
            }),
            ..SensorFrame::imu_only(
                t,
                ImuSample {
                    specific_force_body_m_s2: Vector3::new(0.01, -0.02, -9.81),
                    gyro_body_rad_s: Vector3::new(0.001, -0.002, 0.003),
                },
            )
        };
        f.step(std::hint::black_box(&frame)).map(|m| m[0])
    };
    // a filled history and a settled covariance
    for _ in 0..400 {
        step(&mut f, false, false)?;
    }
    let mut sink = 0.0;
    let mut time = |mag: bool, gps: bool, f: &mut Eskf| -> Result<f64> {
        let mut per = Vec::new();
        for _ in 0..15 {
            let t0 = Instant::now();
            for _ in 0..400 {
                sink += step(f, mag, gps)?;
            }
            per.push(t0.elapsed().as_secs_f64() * 1e9 / 400.0);
        }
        Ok(median(per))
    };
    let imu_ns = time(false, false, &mut f)?;
    let mag_ns = time(true, false, &mut f)?;
    let gps_ns = time(true, true, &mut f)?;
    std::hint::black_box(sink);
    Ok((imu_ns, mag_ns, gps_ns))
}
