//! `helicon gcs`: a small terminal ground station — listens for a vehicle's
//! MAVLink, sends a ground-station heartbeat once a second, and prints the
//! vehicle's state once a second (armed, navigator mode, attitude, position,
//! link quality) and every STATUSTEXT as it arrives.

use anyhow::{Context, Result, bail};
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{Connectable, ConnectionAddress, MavConnection, MavHeader};
use helicon_gcs::navigator::NavMode;
use std::time::{Duration, Instant};

/// `helicon gcs` arguments.
#[derive(clap::Args, Debug)]
pub struct GcsArgs {
    /// Where to listen or send: `udpin:HOST:PORT` (as ground stations do) or
    /// `udpout:HOST:PORT`.
    #[arg(default_value = "udpin:127.0.0.1:14550")]
    pub address: String,
    /// Stop after this many seconds (default: run until interrupted).
    #[arg(long)]
    pub duration_s: Option<f64>,
}

#[derive(Default)]
struct Seen {
    heartbeat: Option<HEARTBEAT_DATA>,
    attitude: Option<ATTITUDE_DATA>,
    position: Option<GLOBAL_POSITION_INT_DATA>,
    local: Option<LOCAL_POSITION_NED_DATA>,
    received: u64,
    lost: u64,
    last_seq: Option<u8>,
}

impl Seen {
    fn count(&mut self, h: &MavHeader) {
        if let Some(last) = self.last_seq {
            self.lost += u64::from(h.sequence.wrapping_sub(last).wrapping_sub(1));
        }
        self.last_seq = Some(h.sequence);
        self.received += 1;
    }

    fn line(&self) -> String {
        let Some(hb) = &self.heartbeat else {
            return "waiting for a vehicle…".to_string();
        };
        let armed = hb
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        let (main, sub) = helicon_gcs::modes::main_sub(hb.custom_mode);
        let mode = helicon_gcs::modes::nav_of_custom(hb.custom_mode)
            .map_or_else(|| helicon_gcs::modes::qgc_name(main, sub), NavMode::as_str);
        let mut s = format!(
            "{:?} {} {:<8}",
            hb.mavtype,
            if armed { "ARMED   " } else { "disarmed" },
            mode
        );
        if let Some(a) = &self.attitude {
            s += &format!(
                " | φ {:6.1}° θ {:6.1}° ψ {:6.1}°",
                a.roll.to_degrees(),
                a.pitch.to_degrees(),
                a.yaw.to_degrees()
            );
        }
        if let Some(l) = &self.local {
            s += &format!(" | N {:7.2} E {:7.2} D {:7.2} m", l.x, l.y, l.z);
        }
        if let Some(p) = &self.position {
            s += &format!(
                " | {:.7} {:.7} rel {:.2} m",
                f64::from(p.lat) * 1e-7,
                f64::from(p.lon) * 1e-7,
                f64::from(p.relative_alt) * 1e-3
            );
        }
        let total = self.received + self.lost;
        let quality = if total > 0 {
            100.0 * self.received as f64 / total as f64
        } else {
            0.0
        };
        s + &format!(" | link {quality:.0} % ({} msgs)", self.received)
    }
}

/// Run the monitor.
pub fn run(args: &GcsArgs) -> Result<()> {
    if !(args.address.starts_with("udpin:") || args.address.starts_with("udpout:")) {
        bail!(
            "address `{}`: expected udpin:HOST:PORT or udpout:HOST:PORT",
            args.address
        );
    }
    if let Some(d) = args.duration_s
        && !(d.is_finite() && d > 0.0)
    {
        bail!("--duration-s {d}: must be a positive number of seconds");
    }
    let ConnectionAddress::Udp(udp) = ConnectionAddress::parse_address(&args.address)
        .with_context(|| format!("address `{}`", args.address))?
    else {
        bail!("address `{}`: only UDP is offered", args.address);
    };
    let conn = udp
        .read_timeout(Duration::from_millis(50))
        .connect::<MavMessage>()
        .with_context(|| format!("address `{}`", args.address))?;
    let me = MavHeader {
        system_id: 255,
        component_id: MavComponent::MAV_COMP_ID_MISSIONPLANNER as u8,
        sequence: 0,
    };
    let heartbeat = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    });
    let start = Instant::now();
    let mut seen = Seen::default();
    let mut next_print = Duration::from_secs(1);
    let mut next_beat = Duration::ZERO;
    loop {
        let now = start.elapsed();
        if args.duration_s.is_some_and(|d| now.as_secs_f64() >= d) {
            break;
        }
        if now >= next_beat {
            // nothing to send to before a udpin peer has spoken: not an error
            let _ = conn.send(&me, &heartbeat);
            next_beat += Duration::from_secs(1);
        }
        if let Ok((h, m)) = conn.recv() {
            seen.count(&h);
            match m {
                MavMessage::HEARTBEAT(x) if x.mavtype != MavType::MAV_TYPE_GCS => {
                    seen.heartbeat = Some(x);
                }
                MavMessage::ATTITUDE(x) => seen.attitude = Some(x),
                MavMessage::GLOBAL_POSITION_INT(x) => seen.position = Some(x),
                MavMessage::LOCAL_POSITION_NED(x) => seen.local = Some(x),
                MavMessage::STATUSTEXT(x) => {
                    let text = x.text.to_str().unwrap_or("?").trim_end_matches('\0');
                    println!("[{:8.1} s] {:?}: {text}", now.as_secs_f64(), x.severity);
                }
                MavMessage::MISSION_ITEM_REACHED(x) => {
                    println!(
                        "[{:8.1} s] reached mission item {}",
                        now.as_secs_f64(),
                        x.seq
                    );
                }
                _ => {}
            }
        }
        if start.elapsed() >= next_print {
            println!("{}", seen.line());
            next_print += Duration::from_secs(1);
        }
    }
    Ok(())
}
