//! Ten thousand random datagrams and a flood of addresses at the real
//! server on 127.0.0.1: no panic, nothing commanded, the peer table and the
//! process's memory bounded. Alone in its test binary, so that the resident
//! set measured is the server's and this test's only.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::client::Client;
use common::vehicle::*;
use helicon_gcs::mavlink::dialects::common::*;
use helicon_gcs::mavlink::{SigningConfig, SigningData};
use helicon_gcs::server::MAX_PEERS;
use rand::{RngExt, SeedableRng};
use std::net::UdpSocket;
use std::time::Duration;

/// The resident set of this process (bytes), from /proc.
fn rss_bytes() -> u64 {
    let s = std::fs::read_to_string("/proc/self/statm").unwrap();
    let pages: u64 = s.split_whitespace().nth(1).unwrap().parse().unwrap();
    pages * 4096
}

#[test]
fn ten_thousand_random_datagrams_and_a_flood_of_addresses() {
    let mut veh = Vehicle::start(None);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let attacker = UdpSocket::bind("127.0.0.1:0").unwrap();
    // a valid frame to mutate
    let mut signer = Signer::new([0u8; 32], 0);
    signer.data = SigningData::from_config(SigningConfig::new([0u8; 32], 0, false, false));
    let template = signer.frame(&long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1, 1, ARM));
    let mut rss0 = 0;
    for i in 0..10_000 {
        // the first thousand warm up the allocator and the socket's buffers
        if i == 1_000 {
            rss0 = rss_bytes();
        }
        let d: Vec<u8> = match i % 3 {
            // noise of any length
            0 => {
                let n = rng.random_range(0..600);
                (0..n).map(|_| rng.random()).collect()
            }
            // a MAVLink 2 start and a plausible header, random rest
            1 => {
                let n = rng.random_range(10..300);
                let mut d: Vec<u8> = (0..n).map(|_| rng.random()).collect();
                d[0] = 0xFD;
                d[1] = (n as u8).wrapping_sub(12);
                d
            }
            // a real frame with bytes flipped (its CRC then fails)
            _ => {
                let mut d = template.clone();
                let k = rng.random_range(1..d.len());
                d[k] ^= rng.random_range(1..=255u8);
                d
            }
        };
        let _ = attacker.send_to(&d, ("127.0.0.1", veh.port));
        // paced so that the socket's buffer rarely overflows
        if i % 50 == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
        if i % 500 == 0 {
            veh.status(0.01);
        }
    }
    veh.status(0.5);
    assert_eq!(veh.commands(), vec![], "random bytes commanded the vehicle");
    // a flood of valid heartbeats from 40 addresses: the table stays bounded
    let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    });
    let flood: Vec<UdpSocket> = (0..40)
        .map(|_| UdpSocket::bind("127.0.0.1:0").unwrap())
        .collect();
    for s in &flood {
        s.send_to(&signer.frame(&hb), ("127.0.0.1", veh.port))
            .unwrap();
        veh.status(0.01);
    }
    // the server still answers a ground station
    let mut c = Client::to_port(veh.port, None);
    c.heartbeat();
    veh.status(0.1);
    let from = c.log.len();
    c.send(&long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1, 1, ARM));
    assert_eq!(
        ack_within(&mut c, from, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, T),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let grown = rss_bytes().saturating_sub(rss0);
    let r = veh.stop();
    println!("{r:?}; resident set grown by {} kB", grown / 1024);
    assert_eq!(r.peers_max, MAX_PEERS, "{r:?}");
    assert_eq!(r.peers_evicted, 41 - MAX_PEERS as u64, "{r:?}");
    // no random datagram held a valid frame (a flipped byte breaks the
    // CRC): the frames heard are the 40 heartbeats and the station's two;
    // most datagrams were read (the kernel drops some of a burst)
    assert_eq!(r.received, 42, "{r:?}");
    assert_eq!(r.garbage_datagrams, r.datagrams - 42, "{r:?}");
    assert!(r.datagrams > 5_000, "{r:?}");
    assert!(grown < 2 << 20, "resident set grew by {grown} bytes");
}
