//! A SITL flight to watch and fly from a ground station (QGroundControl,
//! Mission Planner, MAVProxy, a pymavlink script): the simulated helicopter
//! hovers disarmed at home, the MAVLink server sends to the ground station,
//! and the ground station arms it, takes off, uploads and flies missions.
//!
//! ```text
//! cargo run --release -p helicon-gcs --example gcs_sitl -- [ADDRESS] [SECONDS] [--max-speed] [--full-rate | --no-streams]
//! ```
//!
//! `--full-rate` starts every stream at 100 Hz and the status at every
//! sample; `--no-streams` starts them all off: the real-time run prints the
//! control steps that ended after their deadline either way.
//!
//! `ADDRESS` defaults to `udpout:127.0.0.1:14550` (where ground stations
//! listen); `SECONDS` to 600; the flight runs on the wall clock unless
//! `--max-speed` (lock-step, as fast as the machine allows).

#[path = "../tests/common/harness.rs"]
mod harness;

use harness::{Harness, scenario};
use helicon_devices::Geodetic;
use helicon_gcs::navigator::NavigatorConfig;
use helicon_gcs::server::{DEFAULT_ADDRESS, STREAMS, ServerConfig, parse_address};
use helicon_sim::closed_loop::prepare;
use std::time::{Duration, Instant};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let max_speed = args.iter().any(|a| a == "--max-speed");
    let full_rate = args.iter().any(|a| a == "--full-rate");
    let no_streams = args.iter().any(|a| a == "--no-streams");
    let free: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let address = free
        .first()
        .map_or(DEFAULT_ADDRESS.to_string(), |a| (*a).clone());
    parse_address(&address)?;
    let seconds: f64 = match free.get(1) {
        Some(s) => s.parse().map_err(|e| format!("SECONDS `{s}`: {e}"))?,
        None => 600.0,
    };
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!("SECONDS must be positive, not {seconds}").into());
    }
    let s = scenario(seconds);
    let prepared = prepare(&s)?;
    let config = ServerConfig {
        address: address.clone(),
        system_id: 1,
        home: Geodetic::new(57.0146, 9.9869, 20.0).map_err(|e| e.to_string())?,
        navigator: NavigatorConfig::default(),
        signing_key: None,
        rates_hz: if full_rate {
            [100.0; STREAMS.len()]
        } else if no_streams {
            [0.0; STREAMS.len()]
        } else {
            helicon_gcs::server::default_rates_hz()
        },
    };
    let status_every = if full_rate { 1 } else { 4 };
    let mut h = Harness::new(
        &s,
        &prepared,
        config,
        NavigatorConfig::default(),
        status_every,
    );
    println!(
        "SITL: helicopter at home (57.0146 N, 9.9869 E), MAVLink on {address}, {seconds} s{}",
        if max_speed {
            ", lock-step"
        } else {
            ", real time"
        }
    );
    let period = Duration::from_secs_f64(0.0025);
    let start = Instant::now();
    let mut k: u32 = 0;
    let mut misses = 0u64;
    let mut worst_late = Duration::ZERO;
    while h.step() {
        k += 1;
        if max_speed {
            h.sync();
        } else {
            // a step that ends after the next sample's deadline missed it
            let now = start.elapsed();
            let due = period * k;
            if now > due {
                misses += 1;
                worst_late = worst_late.max(now - due);
            } else {
                std::thread::sleep(due - now);
            }
        }
        if k % 4000 == 0 {
            let p = h.truth_ned_m;
            println!(
                "t = {:6.1} s  {:<8} nav {:<8} N {:7.2} E {:7.2} D {:7.2} m",
                h.t_s,
                h.mode().as_str(),
                h.vehicle().navigator().mode().as_str(),
                p.x,
                p.y,
                p.z
            );
        }
    }
    let report = h.stop();
    println!("ended: {:?}; server {report:?}", h.ended);
    if !max_speed {
        println!(
            "deadline misses: {misses} of {k} steps (worst {:.0} µs late); control step max {:.0} µs",
            worst_late.as_secs_f64() * 1e6,
            h.max_step_s * 1e6
        );
    }
    Ok(())
}
