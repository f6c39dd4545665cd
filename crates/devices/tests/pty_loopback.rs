//! The transports over a real pseudo-terminal: the SITL side writes device
//! frames on the master, the on-board side reads them through `serialport`
//! on the slave path, and back.
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_devices::*;
use std::time::{Duration, Instant};

fn read_until<P: helicon_devices::framing::Protocol>(
    link: &mut SerialLink,
    decoder: &mut StreamDecoder<P>,
    want: usize,
) -> Vec<P::Message> {
    let mut out = Vec::new();
    let mut buf = [0u8; 64];
    let deadline = Instant::now() + Duration::from_secs(5);
    while out.len() < want && Instant::now() < deadline {
        let n = link.read_chunk(&mut buf).unwrap();
        out.extend(decoder.push(&buf[..n]));
    }
    out
}

#[test]
fn frames_cross_a_pty_both_ways() {
    let mut pty = PtyPair::open().unwrap();
    let mut link = SerialLink::open(pty.slave_path(), 115_200, Duration::from_millis(20)).unwrap();

    // SITL → on-board: RC input reports with garbage in between
    let mut sent = Vec::new();
    for seq in 0..50u8 {
        let rc = RcInput {
            seq,
            autonomous: seq % 2 == 0,
            failsafe: seq == 13,
            channels_us: [1500 + u16::from(seq); 8],
            applied_counts: [i16::from(seq), -1, 2, -3],
            last_command_seq: seq.wrapping_sub(1),
        };
        pty.write_all(b"\x00\xA5\xA5garbage").unwrap();
        pty.write_all(rc.encode().as_bytes()).unwrap();
        sent.push(AvionicsMessage::Rc(rc));
    }
    let mut decoder = AvionicsDecoder::new();
    let got = read_until(&mut link, &mut decoder, sent.len());
    assert_eq!(got, sent);
    assert_eq!(decoder.stats().checksum_failures, 0);

    // on-board → SITL: servo commands
    let cmd = ServoCommand {
        seq: 9,
        armed: true,
        throttle_hold: false,
        servo_counts: [1850, -7500, 7500, 3000],
    };
    link.write_all(cmd.encode().as_bytes()).unwrap();
    let mut decoder = AvionicsDecoder::new();
    let mut buf = [0u8; 64];
    let mut got = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(5);
    while got.is_empty() && Instant::now() < deadline {
        let n = pty
            .read_timeout(&mut buf, Duration::from_millis(20))
            .unwrap();
        got.extend(decoder.push(&buf[..n]));
    }
    assert_eq!(got, vec![AvionicsMessage::Servo(cmd)]);

    // nothing more: the read times out with 0 bytes instead of blocking
    let t0 = Instant::now();
    assert_eq!(
        pty.read_timeout(&mut buf, Duration::from_millis(50))
            .unwrap(),
        0
    );
    assert!(t0.elapsed() < Duration::from_secs(2));
    assert_eq!(link.read_chunk(&mut buf).unwrap(), 0);
}

/// The on-board side may close and reopen its port (a restart): the master
/// neither fails nor reads end-of-file meanwhile, and bytes written while
/// the port was closed are read after it reopens.
#[test]
fn the_on_board_side_may_reopen_the_port() {
    let mut pty = PtyPair::open().unwrap();
    let link = SerialLink::open(pty.slave_path(), 115_200, Duration::from_millis(20)).unwrap();
    drop(link);
    let mut buf = [0u8; 64];
    assert_eq!(
        pty.read_timeout(&mut buf, Duration::from_millis(30))
            .unwrap(),
        0
    );
    let frame = ServoCommand {
        seq: 3,
        armed: false,
        throttle_hold: false,
        servo_counts: [0, 1, 2, 3],
    }
    .encode();
    pty.write_all(frame.as_bytes()).unwrap();
    let mut link = SerialLink::open(pty.slave_path(), 115_200, Duration::from_millis(20)).unwrap();
    let mut decoder = AvionicsDecoder::new();
    let got = read_until(&mut link, &mut decoder, 1);
    assert_eq!(
        got,
        vec![AvionicsMessage::Servo(ServoCommand {
            seq: 3,
            armed: false,
            throttle_hold: false,
            servo_counts: [0, 1, 2, 3]
        })]
    );
}

/// `read_timeout`: a read with its own timeout (zero: what is there now)
/// on a link and on its clone, each keeping its own.
#[test]
fn a_read_waits_at_most_its_own_timeout() {
    let mut pty = PtyPair::open().unwrap();
    let mut link = SerialLink::open(pty.slave_path(), 115_200, Duration::from_secs(5)).unwrap();
    let mut writer = link.try_clone().unwrap();
    let mut buf = [0u8; 64];
    // nothing there: zero and a short timeout return at once with nothing
    let t0 = std::time::Instant::now();
    assert_eq!(link.read_timeout(&mut buf, Duration::ZERO).unwrap(), 0);
    assert_eq!(
        link.read_timeout(&mut buf, Duration::from_millis(10))
            .unwrap(),
        0
    );
    assert!(
        t0.elapsed() < Duration::from_secs(4),
        "waited the link's 5 s"
    );
    pty.write_all(b"abc").unwrap();
    let n = link
        .read_timeout(&mut buf, Duration::from_millis(500))
        .unwrap();
    assert_eq!(&buf[..n], b"abc");
    // the clone writes to the master side
    writer.write_all(b"xy").unwrap();
    let n = pty
        .read_timeout(&mut buf, Duration::from_millis(500))
        .unwrap();
    assert_eq!(&buf[..n], b"xy");
}

/// Nobody reads the pseudo-terminal (an avionics board that stopped
/// reading, a line slower than the frames): the servo frames fill the
/// kernel's buffer, then each is refused at once with
/// `TransportError::Full` naming the device, never blocking; the frames the
/// link accepted are whole on the line, and once the other side reads again
/// the writes go through.
#[test]
fn a_full_output_buffer_drops_frames_without_blocking() {
    let mut pty = PtyPair::open().unwrap();
    let slave = pty.slave_path().to_path_buf();
    let mut link = SerialLink::open(&slave, 115_200, Duration::from_millis(20)).unwrap();
    let frame = ServoCommand {
        seq: 3,
        armed: true,
        throttle_hold: false,
        servo_counts: [1850, -7500, 7500, 3000],
    }
    .encode();
    let len = frame.as_bytes().len();
    // on a thread: a write that blocked would fail the test, not hang it
    let (tx, rx) = std::sync::mpsc::channel();
    let writer = std::thread::spawn(move || {
        let (mut accepted, mut refused, mut partial) = (0u64, 0u64, 0u64);
        let mut worst = Duration::ZERO;
        let mut message = String::new();
        while refused < 200 && accepted < 1_000_000 {
            let t = Instant::now();
            match link.write_all(frame.as_bytes()) {
                Ok(()) => accepted += 1,
                Err(TransportError::Full {
                    path,
                    queued,
                    len: l,
                }) => {
                    assert_eq!((path.as_path(), l), (slave.as_path(), len));
                    assert!(queued < len);
                    partial += u64::from(queued > 0);
                    refused += 1;
                    message = TransportError::Full {
                        path,
                        queued,
                        len: l,
                    }
                    .to_string();
                }
                Err(e) => panic!("{e}"),
            }
            worst = worst.max(t.elapsed());
        }
        tx.send((accepted, refused, partial, worst, message))
            .unwrap();
        link
    });
    let (accepted, refused, partial, worst, message) = rx
        .recv_timeout(Duration::from_secs(30))
        .expect("a write blocked on the full buffer");
    let mut link = writer.join().unwrap();
    eprintln!(
        "{accepted} frames queued, then {refused} refused ({partial} in part); \
         slowest write {worst:?}: {message}"
    );
    assert_eq!(refused, 200);
    assert!(accepted > 100, "the buffer took {accepted} frames");
    assert!(message.contains("output buffer full") && message.contains("/dev/pts"));
    // a refused write returns at once (a partial one waits at most
    // PARTIAL_WRITE_WAIT); the bound is loose for a loaded machine
    assert!(
        worst < PARTIAL_WRITE_WAIT + Duration::from_millis(500),
        "{worst:?}"
    );
    // the line holds the accepted frames whole (a frame taken in part and
    // dropped is skipped by its checksum, costing at most the next one)
    let mut decoder = AvionicsDecoder::new();
    let mut buf = [0u8; 4096];
    let mut decoded = 0u64;
    loop {
        let n = pty
            .read_timeout(&mut buf, Duration::from_millis(50))
            .unwrap();
        if n == 0 {
            break;
        }
        decoded += decoder.push(&buf[..n]).count() as u64;
    }
    assert!(decoded <= accepted && decoded + partial >= accepted);
    assert!(decoder.stats().checksum_failures <= partial);
    // read again: the link writes again
    link.write_all(frame.as_bytes()).unwrap();
    let n = pty.read_timeout(&mut buf, Duration::from_secs(5)).unwrap();
    assert_eq!(&buf[..n], frame.as_bytes());
}

/// A read of nothing from a readable line is the line's end: an error (the
/// device lost, its port to be reopened), never "nothing yet". Nothing
/// within the timeout is `Ok(0)`. The end is made for real: the terminal
/// put in canonical mode (as a program that leaves a line cooked does)
/// reads 0 bytes at its end-of-file character, as a line whose driver
/// ended reads.
#[test]
fn a_zero_byte_read_of_a_readable_line_is_its_end() {
    use rustix::fs::{Mode, OFlags};
    use rustix::termios::{LocalModes, OptionalActions, SpecialCodeIndex};
    let mut pty = PtyPair::open().unwrap();
    let mut link = SerialLink::open(pty.slave_path(), 115_200, Duration::from_millis(100)).unwrap();
    let mut buf = [0u8; 64];
    assert_eq!(
        link.read_chunk(&mut buf).unwrap(),
        0,
        "a quiet line is not its end"
    );
    pty.write_all(b"abc").unwrap();
    assert_eq!(link.read_chunk(&mut buf).unwrap(), 3);
    // the same terminal opened again (not as a controlling terminal) and
    // cooked, its end-of-file character Ctrl-D
    let fd = rustix::fs::open(
        pty.slave_path(),
        OFlags::RDWR | OFlags::NOCTTY,
        Mode::empty(),
    )
    .unwrap();
    let mut t = rustix::termios::tcgetattr(&fd).unwrap();
    t.local_modes |= LocalModes::ICANON;
    t.special_codes[SpecialCodeIndex::VEOF] = 4;
    rustix::termios::tcsetattr(&fd, OptionalActions::Now, &t).unwrap();
    pty.write_all(&[4]).unwrap();
    let err = link.read_chunk(&mut buf).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("end of file") && text.contains(&pty.slave_path().display().to_string()),
        "{text}"
    );
}
