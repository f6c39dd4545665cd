//! ArduPilot JSON's per-frame path allocates nothing but the flight
//! summary's amortized growth (`helicon sim`'s own metric trace, doubling
//! its vectors: O(log n) allocations over n frames): the server run on this
//! thread, counted per thread with a wrapping allocator, for 400 and for
//! 4000 frames from the same stand-in (on its own thread); the difference
//! (3600 frames) is at most 30 allocations — five trace vectors doubling
//! from ~400 to ~4000 rows take 4 reallocations each, 20 in all.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

use helicon_sim::closed_loop::prepare;
use helicon_sim::scenario::Scenario;
use helicon_sitl::ardupilot::{
    ArduPilotMap, ArduPilotOptions, ArduPilotSection, ArduPilotServer, BERGEN_TWIN_TOML,
    ServoPacket,
};
use std::net::UdpSocket;
use std::time::Duration;

fn allocations_for(frames: u32) -> usize {
    let s = Scenario::from_toml_str(
        "name = \"ardupilot-alloc\"\npreset = \"physical\"\nduration_s = 600.0\n",
        "test",
    )
    .unwrap();
    let p = prepare(&s).unwrap();
    let section = ArduPilotSection::from_toml_str(BERGEN_TWIN_TOML, "b.toml").unwrap();
    let map = ArduPilotMap::new(section, p.model.params(), "b.toml").unwrap();
    let server = ArduPilotServer::bind("127.0.0.1:0").unwrap();
    let to = server.local_addr();
    let pwm = {
        let mut all = [0u16; 32];
        all[..4].copy_from_slice(&[1607, 1607, 1607, 1500]);
        all[7] = 1700;
        all
    };
    let client = std::thread::spawn(move || {
        let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
        sock.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let mut buf = [0u8; 2048];
        for k in 0..frames {
            let pkt = ServoPacket {
                frame_rate_hz: 400,
                frame_count: k,
                pwm,
                channels: 16,
            };
            sock.send_to(&pkt.encode(), to).unwrap();
            sock.recv_from(&mut buf).unwrap();
        }
    });
    let options = ArduPilotOptions {
        max_frames: Some(u64::from(frames)),
        silence_timeout: Some(Duration::from_secs(20)),
        ..ArduPilotOptions::default()
    };
    let before = allocations();
    let r = server.run(&s, &p, &map, &options).unwrap();
    let n = allocations() - before;
    client.join().unwrap();
    assert_eq!(r.counts.frames, u64::from(frames));
    n
}

#[test]
fn a_frame_allocates_nothing_in_steady_state() {
    let short = allocations_for(400);
    let long = allocations_for(4000);
    eprintln!("allocations: 400 frames {short}, 4000 frames {long}");
    assert!(
        long.saturating_sub(short) <= 30,
        "{short} for 400 frames, {long} for 4000"
    );
}
