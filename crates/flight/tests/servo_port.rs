//! The servo side of the avionics port on a pseudo-terminal nobody reads
//! (an avionics board that stopped reading, a line slower than the
//! frames): `DeviceServos::send` never waits for the line; the frames the
//! port cannot take are dropped and counted, not errors; every frame it
//! took arrives whole (but the one after a frame taken in part).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test: a failed unwrap is a failed test

use helicon_core::state::Input;
use helicon_devices::{AvionicsDecoder, AvionicsMessage, PtyPair};
use helicon_flight::ports::{DeviceServos, open_port};
use helicon_flight::runtime::ServoPort;
use std::time::Duration;

#[test]
fn a_full_servo_port_drops_and_counts_frames_without_blocking() {
    let mut pty = PtyPair::open().unwrap();
    let port = open_port(pty.slave_path(), 115_200).unwrap();
    let mut servos = DeviceServos::new(port);
    let frames = 3000u64;
    // on a thread: a send that blocked fails the test instead of hanging it
    let (tx, rx) = std::sync::mpsc::channel();
    let sender = std::thread::spawn(move || {
        for k in 0..frames {
            let u = Input::repeat(0.01 * (k % 10) as f64);
            servos.send(&u, false).unwrap();
        }
        tx.send(servos.dropped()).unwrap();
    });
    let dropped = rx
        .recv_timeout(Duration::from_secs(30))
        .expect("a servo send blocked on the full port");
    sender.join().unwrap();
    assert!(dropped > 0 && dropped < frames, "{dropped} dropped");
    let mut decoder = AvionicsDecoder::new();
    let mut buf = [0u8; 4096];
    let mut got = 0u64;
    loop {
        let n = pty
            .read_timeout(&mut buf, Duration::from_millis(50))
            .unwrap();
        if n == 0 {
            break;
        }
        got += decoder
            .push(&buf[..n])
            .filter(|m| matches!(m, AvionicsMessage::Servo(_)))
            .count() as u64;
    }
    let bad = decoder.stats().checksum_failures;
    eprintln!("{frames} frames: {got} on the line, {dropped} dropped, {bad} bad checksums");
    // every frame is on the line or counted dropped; a frame the kernel
    // took in part (counted dropped) is a bad checksum on the line that can
    // cost the whole frame after it, so at most `bad` frames are neither
    // (a pseudo-terminal's buffer fills in whole frames here: bad = 0)
    assert!(got + dropped <= frames, "{got} + {dropped}");
    assert!(got + dropped + bad >= frames, "{got} + {dropped} + {bad}");
}
