//! Lock-step SITL of the control task with the ground-station server: the
//! simulator's hardware (plant, wind, sensor models) is stepped one control
//! period at a time; the on-board control task (`helicon_flight::ControlTask`:
//! the safety supervisor over the very flight computer `helicon sim` flies)
//! takes the navigator's reference; the MAVLink server runs on its own
//! thread over real UDP. Shared by the tests and the `gcs_sitl` example.
#![allow(dead_code)]
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::Telemetry;
use helicon_core::state::Input;
use helicon_flight::config::{FailsafeConfig, StaleLimits};
use helicon_flight::control::{ControlTask, Tick};
use helicon_flight::runtime::flight_mode;
use helicon_flight::safety::{Mode, Supervisor};
use helicon_gcs::link::{Vehicle, channel};
use helicon_gcs::navigator::{Navigator, NavigatorConfig};
use helicon_gcs::server::{self, ServerConfig, ServerHandle, ServerReport};
use helicon_sim::closed_loop::{Hardware, Prepared, flight_computer};
use helicon_sim::scenario::Scenario;
use nalgebra::Vector3;
use std::time::Instant;

/// The SITL scenario: the physical Bergen Twin in hover, a light steady wind,
/// the whole estimation chain; the navigator owns the heading.
pub fn scenario(duration_s: f64) -> Scenario {
    let text = format!(
        r#"
name = "gcs"
preset = "physical"
duration_s = {duration_s}

[plant]
max_yaw_error_rad = 1000.0

[wind]
seed = 1

[wind.steady]
wind_ned_m_s = [1.0, 0.0, 0.0]

[sensors]
seed = 1

[controller]
input_max = [0.1, 0.7, 0.7, 0.4]
estimator = true
fusion = true

[log]
decimation = 4
"#
    );
    Scenario::from_toml_str(&text, "gcs.toml").unwrap()
}

/// One SITL flight in progress.
pub struct Harness<'a> {
    hw: Hardware<'a>,
    task: ControlTask,
    vehicle: Vehicle,
    server: Option<ServerHandle>,
    last_tel: Option<Telemetry>,
    servo: Input,
    mode: Mode,
    /// Samples flown.
    pub k: u64,
    /// Time of the next sample (s).
    pub t_s: f64,
    /// The true position NED (m).
    pub truth_ned_m: Vector3<f64>,
    /// Longest control-task step (vehicle + navigator + flight computer), s.
    pub max_step_s: f64,
    /// Sum of the control-task steps (s).
    pub sum_step_s: f64,
    /// The last control-task step (s).
    pub last_step_s: f64,
    /// The flight ended (the plant's envelope or the scenario's duration).
    pub ended: Option<String>,
}

impl<'a> Harness<'a> {
    /// A flight at the scenario's initial state, disarmed, the server at
    /// `server_config` sending statuses every `status_every` samples.
    pub fn new(
        scenario: &'a Scenario,
        prepared: &'a Prepared,
        server_config: ServerConfig,
        nav: NavigatorConfig,
        status_every: u64,
    ) -> Self {
        let hw = Hardware::new(scenario, prepared).unwrap();
        let x0 = *hw.state();
        let computer = flight_computer(&prepared.onboard_setup(scenario, &x0)).unwrap();
        let u_trim = prepared.gains.set.u_trim;
        let supervisor = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0);
        let task = ControlTask::new(computer, supervisor, u_trim);
        let (vehicle_end, server_end) = channel(8192);
        let vehicle = Vehicle::new(Navigator::new(nav).unwrap(), vehicle_end, status_every);
        let server = server::spawn(server_config, server_end).unwrap();
        Harness {
            hw,
            task,
            vehicle,
            server: Some(server),
            last_tel: None,
            servo: u_trim,
            mode: Mode::Disarmed,
            k: 0,
            t_s: 0.0,
            truth_ned_m: Vector3::new(x0[0], x0[1], x0[2]),
            max_step_s: 0.0,
            sum_step_s: 0.0,
            last_step_s: 0.0,
            ended: None,
        }
    }

    /// The vehicle side (navigator, arming).
    pub fn vehicle(&self) -> &Vehicle {
        &self.vehicle
    }

    /// The supervisor's mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// One control period; `false` once the flight has ended.
    pub fn step(&mut self) -> bool {
        if self.ended.is_some() {
            return false;
        }
        let Some(s) = self.hw.sense() else {
            self.ended = Some("duration".into());
            return false;
        };
        let start = Instant::now();
        let out = self.vehicle.step(
            s.t_s,
            self.last_tel.as_ref(),
            flight_mode(self.mode),
            &self.servo,
            self.last_step_s / self.hw.sample_time_s(),
        );
        if let Some(a) = out.arm {
            self.task.set_armed(a);
        }
        let c = self.task.step(&Tick {
            now_s: s.t_s,
            frame: Some(s.frame),
            deadline_missed: false,
            rc: None,
            reference: out.reference,
            gps_quality: None,
        });
        let dt = start.elapsed().as_secs_f64();
        self.max_step_s = self.max_step_s.max(dt);
        self.sum_step_s += dt;
        self.last_step_s = dt;
        self.servo = c.servo;
        self.mode = c.mode;
        if c.telemetry.is_some() {
            self.last_tel = c.telemetry;
        }
        let Some(step) = self.hw.actuate(&c.servo, self.last_tel.as_ref()) else {
            self.ended = Some("no sample".into());
            return false;
        };
        let x = self.hw.state();
        self.truth_ned_m = Vector3::new(x[0], x[1], x[2]);
        self.k += 1;
        self.t_s = s.t_s + self.hw.sample_time_s();
        if let Some((term, why)) = step.end {
            self.ended = Some(format!("{term:?}: {why:?}"));
            return false;
        }
        true
    }

    /// Fly `seconds` (or until the flight ends); `false` when it ended.
    pub fn run(&mut self, seconds: f64) -> bool {
        let n = (seconds / self.hw.sample_time_s()).round() as u64;
        for _ in 0..n {
            if !self.step() {
                return false;
            }
        }
        self.sync();
        true
    }

    /// Wait (wall clock) until the server has sent on everything the
    /// vehicle handed it: the lock-step between the simulation and the
    /// ground-station thread.
    pub fn sync(&self) {
        let Some(server) = &self.server else { return };
        let start = Instant::now();
        while server.processed() < self.vehicle.sent() {
            assert!(
                start.elapsed().as_secs_f64() < 5.0,
                "the server does not keep up"
            );
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
    }

    /// Stop the server.
    pub fn stop(&mut self) -> ServerReport {
        self.server
            .take()
            .map(ServerHandle::stop)
            .unwrap_or_default()
    }
}

impl Drop for Harness<'_> {
    fn drop(&mut self) {
        self.stop();
    }
}
