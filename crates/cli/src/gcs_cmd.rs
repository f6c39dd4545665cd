//! `helicon gcs`: a terminal ground station. It listens for vehicles'
//! MAVLink, sends a ground-station heartbeat once a second, prints each
//! vehicle's state once a second (a line per system id) and every
//! STATUSTEXT as it arrives — and flies: commands read line by line from
//! stdin (typed, or piped from a script), one at a time, each answered by
//! one line. The protocol logic is `helicon_gcs::client`'s.

use anyhow::{Context, Result, bail};
use helicon_gcs::client::{
    self, Fleet, GCS_COMPONENT_ID, GCS_SYSTEM_ID, Operation, Outcome, Request, WaitFor,
};
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::error::MessageReadError;
use helicon_gcs::mavlink::{MavHeader, MavlinkReader};
use helicon_gcs::{modes, wpl};
use std::collections::{BTreeMap, VecDeque};
use std::io::{BufRead, ErrorKind, IsTerminal, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs, UdpSocket};
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// `helicon gcs` arguments.
#[derive(clap::Args, Debug)]
pub struct GcsArgs {
    /// Where to listen or connect: `udpin:HOST:PORT` (listen, as ground
    /// stations do), `udpout:HOST:PORT` (send there first) or
    /// `tcp:HOST:PORT` (connect to a vehicle's TCP server).
    #[arg(default_value = "udpin:127.0.0.1:14550")]
    pub address: String,
    /// Stop after this many seconds (default: until interrupted, or with
    /// commands on stdin until they are done).
    #[arg(long, visible_alias = "duration-s", value_name = "S")]
    pub duration: Option<f64>,
    /// How long each command may take (s): its answer, or the state waited
    /// for.
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub timeout: f64,
}

/// The link to the vehicles.
enum Link {
    /// UDP: the socket, the `udpout:` destination, and where each system
    /// was heard from (commands go to their vehicle's address).
    Udp {
        socket: UdpSocket,
        dest: Option<SocketAddr>,
        peers: BTreeMap<u8, SocketAddr>,
        buffer: Vec<u8>,
    },
    /// A TCP connection, read through the mavlink crate's incremental
    /// reader (it keeps a partial frame between reads).
    Tcp(Box<MavlinkReader<TcpStream>>),
}

impl Link {
    fn open(address: &str, timeout_s: f64) -> Result<Link> {
        let named = |m: &str| format!("address `{address}`: {m}");
        let (scheme, host) = address
            .split_once(':')
            .filter(|(s, _)| matches!(*s, "udpin" | "udpout" | "tcp"))
            .ok_or_else(|| {
                anyhow::anyhow!(named(
                    "expected udpin:HOST:PORT, udpout:HOST:PORT or tcp:HOST:PORT"
                ))
            })?;
        let addr = host
            .to_socket_addrs()
            .map_err(|e| anyhow::anyhow!(named(&e.to_string())))?
            .next()
            .ok_or_else(|| anyhow::anyhow!(named("resolves to no address")))?;
        match scheme {
            "tcp" => {
                let stream = TcpStream::connect_timeout(&addr, Duration::from_secs_f64(timeout_s))
                    .with_context(|| named("connecting"))?;
                stream
                    .set_read_timeout(Some(Duration::from_millis(20)))
                    .with_context(|| named("socket"))?;
                Ok(Link::Tcp(Box::new(MavlinkReader::new(stream))))
            }
            _ => {
                let listen = scheme == "udpin";
                let bind: SocketAddr = if listen {
                    addr
                } else if addr.is_ipv4() {
                    ([0, 0, 0, 0], 0).into()
                } else {
                    ([0u16; 8], 0).into()
                };
                let socket = UdpSocket::bind(bind).with_context(|| named("binding"))?;
                socket
                    .set_read_timeout(Some(Duration::from_millis(20)))
                    .with_context(|| named("socket"))?;
                Ok(Link::Udp {
                    socket,
                    dest: (!listen).then_some(addr),
                    peers: BTreeMap::new(),
                    buffer: vec![0; 65_536],
                })
            }
        }
    }

    /// Send `msg` to system `to` (`None`: every vehicle heard, and the
    /// `udpout:` destination). Nothing to send to yet is not an error.
    fn send(&mut self, header: MavHeader, msg: &MavMessage, to: Option<u8>) {
        match self {
            Link::Tcp(reader) => {
                let mut frame = Vec::new();
                if helicon_gcs::mavlink::write_v2_msg(&mut frame, header, msg).is_ok() {
                    let _ = reader.get_mut().write_all(&frame);
                }
            }
            Link::Udp {
                socket,
                dest,
                peers,
                ..
            } => {
                let mut frame = Vec::new();
                if helicon_gcs::mavlink::write_v2_msg(&mut frame, header, msg).is_err() {
                    return;
                }
                let mut targets: Vec<SocketAddr> = match to.and_then(|s| peers.get(&s)) {
                    Some(a) => vec![*a],
                    None => peers.values().copied().collect(),
                };
                if let Some(d) = dest
                    && (targets.is_empty() || to.is_none())
                    && !targets.contains(d)
                {
                    targets.push(*d);
                }
                for a in targets {
                    let _ = socket.send_to(&frame, a);
                }
            }
        }
    }

    /// The messages that arrive within the read timeout.
    fn recv(&mut self) -> Vec<(MavHeader, MavMessage)> {
        match self {
            Link::Tcp(reader) => {
                // the frames already whole, then one wait of the read
                // timeout; a frame failing its CRC is skipped by the reader
                let mut out = Vec::new();
                for _ in 0..256 {
                    match reader.read_any_message::<MavMessage>() {
                        Ok(m) => out.push(m),
                        Err(MessageReadError::Io(e))
                            if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) =>
                        {
                            break;
                        }
                        Err(MessageReadError::Io(_)) => {
                            // closed: nothing more will come
                            std::thread::sleep(Duration::from_millis(5));
                            break;
                        }
                        // a frame of no known message: skipped
                        Err(_) => {}
                    }
                }
                out
            }
            Link::Udp {
                socket,
                peers,
                buffer,
                ..
            } => {
                let Ok((n, from)) = socket.recv_from(buffer) else {
                    return Vec::new();
                };
                let mut r = MavlinkReader::new(&buffer[..n]);
                let mut out = Vec::new();
                for _ in 0..=n / 8 {
                    match r.read_any_message::<MavMessage>() {
                        Ok((h, m)) => {
                            if h.system_id != GCS_SYSTEM_ID {
                                peers.insert(h.system_id, from);
                            }
                            out.push((h, m));
                        }
                        Err(_) => break,
                    }
                }
                out
            }
        }
    }
}

/// A line read, parsed.
enum Line {
    /// Run this on the current vehicle.
    Op(Request),
    /// Commands go to this system from now on.
    Vehicle(u8),
    /// End the session.
    Quit,
}

fn parse_line(line: &str, timeout_s: f64) -> Result<Line> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let number = |w: Option<&&str>, what: &str| -> Result<f64> {
        let w = w.with_context(|| format!("expected {what}"))?;
        let v: f64 = w
            .parse()
            .with_context(|| format!("{what} `{w}`: not a number"))?;
        if !v.is_finite() {
            bail!("{what} `{w}`: not finite");
        }
        Ok(v)
    };
    let cmd = |command: MavCmd, p1: f32| {
        let mut params = [0.0; 7];
        params[0] = p1;
        Line::Op(Request::Command { command, params })
    };
    let set_mode = |name: &str| -> Result<Line> {
        let (main, sub) = modes::parse_name(name).with_context(|| {
            format!("mode `{name}`: not one of IDLE TAKEOFF HOLD MISSION RETURN LAND GUIDED (or QGroundControl's names)")
        })?;
        let mut params = [0.0; 7];
        params[0] = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits() as f32;
        params[1] = f32::from(main);
        params[2] = f32::from(sub);
        Ok(Line::Op(Request::Command {
            command: MavCmd::MAV_CMD_DO_SET_MODE,
            params,
        }))
    };
    let extra = |n: usize| -> Result<()> {
        if words.len() > n {
            bail!("unexpected `{}`", words[n..].join(" "));
        }
        Ok(())
    };
    let line = match words.as_slice() {
        ["arm"] => cmd(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0),
        ["disarm"] => cmd(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0.0),
        ["takeoff"] => Line::Op(Request::Takeoff(None)),
        ["takeoff", ..] => {
            extra(2)?;
            let h = number(words.get(1), "height (m)")?;
            if h <= 0.0 {
                bail!("height {h} m: must be above home");
            }
            Line::Op(Request::Takeoff(Some(h)))
        }
        ["land"] => cmd(MavCmd::MAV_CMD_NAV_LAND, 0.0),
        ["rtl"] => cmd(MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH, 0.0),
        ["hold"] => set_mode("HOLD")?,
        ["mode", name] => set_mode(name)?,
        ["mission", "upload", file] => {
            let items = wpl::read(&PathBuf::from(file))?;
            Line::Op(Request::Upload(items))
        }
        ["mission", "download", _] => Line::Op(Request::Download),
        ["mission", "start"] => cmd(MavCmd::MAV_CMD_MISSION_START, 0.0),
        ["param", "get", name] => Line::Op(Request::ParamGet((*name).to_string())),
        ["param", "set", name, _] => {
            let v = number(words.get(3), "value")?;
            Line::Op(Request::ParamSet((*name).to_string(), v as f32))
        }
        ["vehicle", id] => Line::Vehicle(
            id.parse()
                .ok()
                .filter(|i| *i > 0)
                .with_context(|| format!("system id `{id}`: expected 1…255"))?,
        ),
        ["wait", "armed"] => Line::Op(Request::Wait(WaitFor::Armed)),
        ["wait", "disarmed"] => Line::Op(Request::Wait(WaitFor::Disarmed)),
        ["wait", "landed"] => Line::Op(Request::Wait(WaitFor::Landed)),
        ["wait", "mission", "done"] => Line::Op(Request::Wait(WaitFor::MissionDone)),
        ["wait", "mode", name] => {
            let (main, sub) =
                modes::parse_name(name).with_context(|| format!("mode `{name}`: unknown"))?;
            Line::Op(Request::Wait(WaitFor::Mode(main, sub, (*name).to_string())))
        }
        ["wait", "seconds", _] => {
            let s = number(words.get(2), "seconds")?;
            if s < 0.0 {
                bail!("seconds {s}: must be ≥ 0");
            }
            Line::Op(Request::Wait(WaitFor::Seconds(s)))
        }
        ["quit"] => Line::Quit,
        _ => bail!(
            "unknown command (arm, disarm, takeoff [HEIGHT_M], land, rtl, hold, mode NAME, mission upload|download FILE, mission start, param get NAME, param set NAME VALUE, vehicle SYSID, wait armed|disarmed|landed|mode NAME|seconds N|mission done, quit; timeout {timeout_s} s)"
        ),
    };
    Ok(line)
}

/// The answer line of a finished operation (`line` the command as read).
fn answer(line: &str, outcome: Outcome) -> Result<String> {
    Ok(match outcome {
        Outcome::Command(r) => format!("{line}: {r:?}"),
        Outcome::Uploaded(r, n) => format!("{line}: {r:?} ({n} items)"),
        Outcome::Downloaded(items) => {
            let file = line
                .split_whitespace()
                .nth(2)
                .unwrap_or("mission.waypoints");
            wpl::write(&PathBuf::from(file), &items)?;
            format!("{line}: {} items", items.len())
        }
        Outcome::Param(name, v) => format!("{line}: {name} = {v}"),
        Outcome::Reached => format!("{line}: done"),
    })
}

/// Run the ground station.
#[allow(clippy::too_many_lines)] // one loop: link in, operation, stdin, display
pub fn run(args: &GcsArgs) -> Result<()> {
    if let Some(d) = args.duration
        && !(d.is_finite() && d > 0.0)
    {
        bail!("--duration {d}: must be a positive number of seconds");
    }
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!(
            "--timeout {}: must be a positive number of seconds",
            args.timeout
        );
    }
    let mut link = Link::open(&args.address, args.timeout)?;
    let (tx, rx) = mpsc::channel::<Option<String>>();
    let interactive = std::io::stdin().is_terminal();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { break };
            if tx.send(Some(line)).is_err() {
                return;
            }
        }
        let _ = tx.send(None);
    });
    let mut sequence = 0u8;
    let mut header = || {
        sequence = sequence.wrapping_add(1);
        MavHeader {
            system_id: GCS_SYSTEM_ID,
            component_id: GCS_COMPONENT_ID,
            sequence,
        }
    };
    let start = Instant::now();
    let mut fleet = Fleet::default();
    let mut next_print = 1.0;
    let mut last_beat: Option<f64> = None;
    // each vehicle's clock (ATTITUDE's time_boot_ms) at the last heartbeat
    // on its account: a lock-step SITL runs faster than the wall clock, and
    // its link-loss failsafe counts its own seconds
    let mut beat_boot_ms: BTreeMap<u8, u32> = BTreeMap::new();
    let mut queue: VecDeque<String> = VecDeque::new();
    let mut eof = false;
    let mut read_any = false;
    let mut target: u8 = 1;
    let mut op: Option<(String, Operation)> = None;
    let mut failed = 0usize;
    let mut quit = false;
    loop {
        let now = start.elapsed().as_secs_f64();
        if args.duration.is_some_and(|d| now >= d) {
            break;
        }
        if last_beat.is_none_or(|t| now - t >= 1.0) {
            link.send(header(), &client::gcs_heartbeat(), None);
            last_beat = Some(now);
        }
        let mut finished = None;
        for (h, m) in link.recv() {
            let now = start.elapsed().as_secs_f64();
            fleet.on_message(&h, &m, now);
            match &m {
                MavMessage::STATUSTEXT(x) => {
                    let text = x.text.to_str().unwrap_or("?").trim_end_matches('\0');
                    println!(
                        "[{now:8.1} s] vehicle {}: {:?}: {text}",
                        h.system_id, x.severity
                    );
                }
                MavMessage::MISSION_ITEM_REACHED(x) => {
                    println!(
                        "[{now:8.1} s] vehicle {}: reached mission item {}",
                        h.system_id, x.seq
                    );
                }
                MavMessage::ATTITUDE(a) if h.system_id != GCS_SYSTEM_ID => {
                    let b = beat_boot_ms.entry(h.system_id).or_insert(a.time_boot_ms);
                    if a.time_boot_ms < *b {
                        *b = a.time_boot_ms; // rebooted
                    } else if a.time_boot_ms - *b >= 1000 {
                        *b = a.time_boot_ms;
                        link.send(header(), &client::gcs_heartbeat(), Some(h.system_id));
                    }
                }
                _ => {}
            }
            if let Some((_, o)) = &mut op {
                let step = o.on_message(h.system_id, &m, now);
                for s in &step.send {
                    link.send(header(), s, Some(target));
                }
                if step.done.is_some() {
                    finished = step.done;
                }
            }
        }
        if finished.is_none()
            && let Some((_, o)) = &mut op
        {
            let step = o.poll(&fleet, start.elapsed().as_secs_f64());
            for s in &step.send {
                link.send(header(), s, Some(target));
            }
            finished = step.done;
        }
        if let Some(done) = finished
            && let Some((line, o)) = op.take()
        {
            // an upload or a mission start begins the mission waited for
            fleet.on_finished(&o, &done);
            match done
                .map_err(anyhow::Error::from)
                .and_then(|o| answer(&line, o))
            {
                Ok(text) => println!("{text}"),
                Err(e) => {
                    failed += 1;
                    eprintln!("error: {line}: {e:#}");
                }
            }
        }
        while let Ok(l) = rx.try_recv() {
            match l {
                Some(l) => queue.push_back(l),
                None => eof = true,
            }
        }
        while op.is_none() && !quit {
            let Some(raw) = queue.pop_front() else { break };
            let line = raw.trim().to_string();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            read_any = true;
            let now = start.elapsed().as_secs_f64();
            match parse_line(&line, args.timeout) {
                Ok(Line::Quit) => quit = true,
                Ok(Line::Vehicle(id)) => {
                    target = id;
                    println!("{line}: commands go to vehicle {id}");
                }
                Ok(Line::Op(r)) => match Operation::new(r, target, now, args.timeout) {
                    Ok(o) => op = Some((line, o)),
                    Err(e) => {
                        failed += 1;
                        eprintln!("error: {line}: {e}");
                    }
                },
                Err(e) => {
                    failed += 1;
                    eprintln!("error: {line}: {e:#}");
                }
            }
        }
        if quit && op.is_none() {
            break;
        }
        if eof && read_any && queue.is_empty() && op.is_none() {
            break;
        }
        let now = start.elapsed().as_secs_f64();
        if now >= next_print {
            let lines = fleet.lines(now);
            if lines.is_empty() {
                println!("waiting for a vehicle…");
            }
            for l in lines {
                println!("{l}");
            }
            next_print += 1.0;
        }
    }
    if failed > 0 && !interactive {
        bail!("{failed} command(s) failed");
    }
    Ok(())
}
