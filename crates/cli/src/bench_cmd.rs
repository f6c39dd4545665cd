//! `helicon bench`: the cost of each stage of a flight on this machine —
//! the model's derivative and RK4 step, the closed loop, the log row (on
//! the flight's thread and in its formatter), `helicon sim` streaming its
//! log, the ESKF step and the SITL round trip through the pseudo-terminals.

use anyhow::{Context, Result};
use clap::Args;
use helicon_model::integrate::rk4;
use helicon_model::state::expand;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{Input, Model, Preset, State};
use helicon_sim::closed_loop::{fly, fly_to, prepare};
use helicon_sim::log_csv::{LogWriter, RowText};
use helicon_sim::scenario::Scenario;
use nalgebra::Vector3;
use std::time::Instant;

/// `helicon bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Print the figures as JSON: `derivative_ns`, `rk4_step_ns`,
    /// `closed_loop_step_ns`, `closed_loop_rtf`, `log_row_ns` (on the
    /// flight's thread), `log_row_format_ns` (the row's text),
    /// `sim_with_log_step_ns`, `sim_with_log_rtf`, `eskf_step_imu_ns`,
    /// `eskf_step_mag_ns`, `eskf_step_gps_ns`, `sitl_step_us`, `sitl_rtf`,
    /// `sitl_compute_p50_us`, `sitl_sensor_to_servo_p50_us`; the stages of
    /// one closed-loop step (mean ns): `stage_sensors_ns`,
    /// `stage_navigation_ns`, `stage_predictor_ns`, `stage_law_ns`,
    /// `stage_plant_ns` (RK4 and the truth row), and of a SITL sample (mean
    /// µs): `sitl_onboard_compute_us`, `sitl_hardware_compute_us`,
    /// `sitl_transport_us`.
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
#[allow(clippy::too_many_lines)] // one report: each stage measured, then its figures as JSON or text
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
    // 2b. the stages of one step, timed one by one
    let stages = bench_stages(&scenario, &prepared)?;
    // 3. the log row, and `helicon sim` streaming its log
    let (log_row_ns, log_format_ns, sim_step_ns, log_rows) = bench_log(&scenario, &prepared)?;
    let sim_rtf = ts * 1e9 / sim_step_ns;
    // 4. the ESKF step at 400 Hz: IMU only, with the magnetometer, with a
    // delayed GPS fix (position, velocity) and the magnetometer
    let (eskf_imu_ns, eskf_mag_ns, eskf_gps_ns) = bench_eskf()?;
    // 5. SITL in lock-step: the on-board program's threads on
    // pseudo-terminals against the simulated hardware
    let sitl = bench_sitl()?;
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
                "log_row_format_ns": log_format_ns,
                "sim_with_log_step_ns": sim_step_ns,
                "sim_with_log_rtf": sim_rtf,
                "eskf_step_imu_ns": eskf_imu_ns,
                "eskf_step_mag_ns": eskf_mag_ns,
                "eskf_step_gps_ns": eskf_gps_ns,
                "sitl_step_us": sitl.step_us,
                "sitl_rtf": sitl.rtf,
                "sitl_compute_p50_us": sitl.compute_p50_us,
                "sitl_sensor_to_servo_p50_us": sitl.sensor_to_servo_p50_us,
                "sitl_onboard_compute_us": sitl.onboard_us,
                "sitl_hardware_compute_us": sitl.hardware_us,
                "sitl_transport_us": sitl.transport_us,
                "stage_sensors_ns": stages.sensors_ns,
                "stage_navigation_ns": stages.navigation_ns,
                "stage_predictor_ns": stages.predictor_ns,
                "stage_law_ns": stages.law_ns,
                "stage_plant_ns": stages.plant_ns,
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
            "  its stages (mean of {STAGE_FLIGHTS} flights, each timed): sensors {:.0} ns, navigation (q-method, fusion) {:.0} ns, Kalman predictor {:.0} ns, control law {:.0} ns, plant (RK4, truth row, checks) {:.0} ns",
            stages.sensors_ns,
            stages.navigation_ns,
            stages.predictor_ns,
            stages.law_ns,
            stages.plant_ns
        );
        writeln!(
            con,
            "log.csv row on the flight's thread (checks, hand-off) {log_row_ns:10.0} ns (median of 15 logs of {log_rows} rows)"
        );
        writeln!(
            con,
            "log.csv row text (83 numbers, the writer's thread) {log_format_ns:10.0} ns"
        );
        writeln!(
            con,
            "closed-loop step streaming log.csv (helicon sim) {sim_step_ns:10.0} ns: {sim_rtf:.0} × real time"
        );
        writeln!(
            con,
            "ESKF step (15 states, 400 Hz)    {eskf_imu_ns:10.0} ns IMU only, {eskf_mag_ns:.0} ns with magnetometer, {eskf_gps_ns:.0} ns with GPS and magnetometer"
        );
        writeln!(
            con,
            "SITL lock-step sample (ptys, both sides) {:10.1} µs: {:.0} × real time; on board: compute p50 {:.1} µs, sensor frame to servo frame p50 {:.1} µs (median of {SITL_RUNS} flights of {SITL_S} s)",
            sitl.step_us, sitl.rtf, sitl.compute_p50_us, sitl.sensor_to_servo_p50_us
        );
        writeln!(
            con,
            "  its parts (mean µs a sample): on-board compute {:.1}, simulated hardware compute {:.1}, transport (ptys, wake-ups) {:.1}",
            sitl.onboard_us, sitl.hardware_us, sitl.transport_us
        );
    }
    con.finish().context("writing to stdout")
}

/// Flights of the stage benchmark.
const STAGE_FLIGHTS: usize = 5;

/// The mean cost (ns) of each stage of a closed-loop step.
struct StageCosts {
    /// The sensor models (and the truth they sample, the wind, the reference).
    sensors_ns: f64,
    /// The navigation: q-method and the GPS/IMU fusion filter.
    navigation_ns: f64,
    /// The Kalman predictor: absorbing the measured states and advancing.
    predictor_ns: f64,
    /// The LQI control law.
    law_ns: f64,
    /// The plant: RK4 over the period, the truth row, the summary and the
    /// envelope checks.
    plant_ns: f64,
}

/// The closed loop of the bench scenario flown stage by stage, each stage
/// timed on its own ([`STAGE_FLIGHTS`] flights; the clock read between the
/// stages is not in any of them). The thesis chain only: the flight
/// computer's navigation, predictor and law are stepped as
/// `FlightComputer::step` steps them.
fn bench_stages(
    scenario: &Scenario,
    prepared: &helicon_sim::closed_loop::Prepared,
) -> Result<StageCosts> {
    use helicon_core::SensorComputer;
    use helicon_core::estimator::Predictor;
    use helicon_core::lqi::StateFeedback;
    use helicon_sim::closed_loop::{Hardware, flight_computer};
    let mut sum = [0u128; 5];
    let mut steps = 0u64;
    let zero = Input::zeros();
    for _ in 0..STAGE_FLIGHTS {
        let mut hw = Hardware::new(scenario, prepared)?;
        let computer = flight_computer(&prepared.onboard_setup(scenario, hw.state()))?;
        let SensorComputer::Thesis(mut fc) = computer else {
            anyhow::bail!("the bench scenario flies the thesis chain");
        };
        let mut t = Instant::now();
        let mut lap = |k: usize| {
            let now = Instant::now();
            sum[k] += now.duration_since(t).as_nanos();
            t = now;
        };
        while let Some(s) = hw.sense() {
            lap(0);
            let y = fc.estimator.navigation.step(&s.frame)?;
            lap(1);
            let x_hat = fc.estimator.predictor.absorb(&y)?;
            lap(2);
            let c = fc.feedback.command_with_offset(&x_hat, &s.reference, &zero);
            lap(3);
            fc.estimator.predictor.advance(&c.u)?;
            lap(2);
            let step = hw.actuate(&c.u, None);
            lap(4);
            steps += 1;
            if step.is_none_or(|st| st.end.is_some()) {
                break;
            }
        }
    }
    let per = |k: usize| sum[k] as f64 / steps.max(1) as f64;
    Ok(StageCosts {
        sensors_ns: per(0),
        navigation_ns: per(1),
        predictor_ns: per(2),
        law_ns: per(3),
        plant_ns: per(4),
    })
}

/// The log row's cost (ns) on the flight's thread and in its formatter,
/// `helicon sim`'s step streaming its log (ns), and the rows of the flight.
fn bench_log(
    scenario: &Scenario,
    prepared: &helicon_sim::closed_loop::Prepared,
) -> Result<(f64, f64, f64, usize)> {
    let ts = prepared.gains.set.sample_time_s;
    // the log row: on the flight's thread (the checks and the hand-off
    // to the writer's thread, LogWriter::write), in the formatter (the
    // text of a row, no I/O), and the flight as `helicon sim` flies it,
    // streaming its log.csv. A fresh file each time: rewriting a truncated
    // one makes ext4 write it back at close, which is not the log's cost.
    let flight = fly(scenario, prepared, None)?;
    let dir = std::env::temp_dir().join(format!("helicon-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let log_path = dir.join("log.csv");
    let fresh = |path: &std::path::Path| -> Result<LogWriter> {
        match std::fs::remove_file(path) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(e).with_context(|| format!("removing {}", path.display())),
        }
        Ok(LogWriter::create(path)?)
    };
    let rows = flight.log.len().max(1) as f64;
    let mut per = Vec::new();
    for _ in 0..15 {
        let mut w = fresh(&log_path)?;
        let t0 = Instant::now();
        for r in &flight.log {
            w.write(r)?;
        }
        per.push(t0.elapsed().as_secs_f64() * 1e9 / rows);
        w.finish()?;
    }
    let log_row_ns = median(per);
    let mut text = RowText::new();
    let mut per = Vec::new();
    let mut bytes = 0;
    for _ in 0..15 {
        let t0 = Instant::now();
        for r in &flight.log {
            bytes += std::hint::black_box(text.format(r)).len();
        }
        per.push(t0.elapsed().as_secs_f64() * 1e9 / rows);
    }
    std::hint::black_box(bytes);
    let log_format_ns = median(per);
    let mut per = Vec::new();
    for _ in 0..15 {
        let mut w = fresh(&log_path)?;
        let t0 = Instant::now();
        fly_to(scenario, prepared, &mut w, None)?;
        w.finish()?;
        let steps = (scenario.duration_s / ts).round().max(1.0);
        per.push(t0.elapsed().as_secs_f64() * 1e9 / steps);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let sim_step_ns = median(per);
    Ok((log_row_ns, log_format_ns, sim_step_ns, flight.log.len()))
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

/// Simulated seconds of each SITL flight of the benchmark.
const SITL_S: f64 = 5.0;
/// SITL flights of the benchmark.
const SITL_RUNS: usize = 3;

/// The SITL round trip measured by `helicon bench`.
struct SitlBench {
    /// Wall time per control sample, both sides (µs).
    step_us: f64,
    /// Simulated time per wall time.
    rtf: f64,
    /// The on-board control step's compute time, median (µs).
    compute_p50_us: f64,
    /// From a sensor frame's arrival to its servo frame, median (µs).
    sensor_to_servo_p50_us: f64,
    /// The on-board control step's compute time, mean (µs).
    onboard_us: f64,
    /// The simulated hardware's own work per sample (µs): all but its wait
    /// for the servo frame.
    hardware_us: f64,
    /// The rest of the wait for the servo frame (µs): the bytes through
    /// the pseudo-terminals both ways and the threads' wake-ups.
    transport_us: f64,
}

/// Lock-step SITL flights of the bench scenario ([`SITL_S`] s each): the
/// median flight by wall time per sample.
fn bench_sitl() -> Result<SitlBench> {
    use helicon_flight::config::{FailsafeConfig, RealtimeConfig, StaleLimits};
    use helicon_sitl::{Faults, Pilot, SitlOptions, Speed};
    let mut scenario = Scenario::from_toml_str(BENCH_SCENARIO, "<bench scenario>")?;
    scenario.duration_s = SITL_S;
    let prepared = prepare(&scenario)?;
    let dir = std::env::temp_dir().join(format!("helicon-bench-sitl-{}", std::process::id()));
    let mut flights = Vec::new();
    for k in 0..SITL_RUNS {
        let options = SitlOptions {
            speed: Speed::Max,
            out_dir: dir.join(k.to_string()),
            faults: Faults::default(),
            pilot: Pilot::default(),
            stale: StaleLimits::default(),
            failsafe: FailsafeConfig::default(),
            realtime: RealtimeConfig::default(),
            keep_frames: false,
            gcs: None,
            log_stride: 1,
            stop: None,
            clock: None,
            log_part_bytes: None,
        };
        std::fs::create_dir_all(&options.out_dir)
            .with_context(|| format!("creating {}", options.out_dir.display()))?;
        let r = helicon_sitl::run(&scenario, &prepared, &options)
            .context("the SITL benchmark flight")?;
        if let Some(e) = &r.onboard.error {
            anyhow::bail!("the SITL benchmark flight: the on-board program failed: {e}");
        }
        let samples = r.samples.max(1) as f64;
        flights.push(SitlBench {
            step_us: r.wall_s * 1e6 / samples,
            rtf: r.speed_x,
            compute_p50_us: r.onboard.compute.p50_us,
            sensor_to_servo_p50_us: r.onboard.sensor_to_servo.p50_us,
            onboard_us: r.onboard.compute.mean_us,
            hardware_us: (r.wall_s - r.servo_wait_s) * 1e6 / samples,
            transport_us: (r.servo_wait_s * 1e6 / samples - r.onboard.compute.mean_us).max(0.0),
        });
    }
    let _ = std::fs::remove_dir_all(&dir);
    flights.sort_by(|a, b| a.step_us.total_cmp(&b.step_us));
    flights
        .into_iter()
        .nth(SITL_RUNS / 2)
        .context("no SITL benchmark flight")
}
