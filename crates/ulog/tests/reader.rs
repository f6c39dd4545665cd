//! The reader: a file cut at any byte gives every complete message before
//! the cut and then "truncated" (checked against px4-ulog too); a process
//! killed mid-flight leaves a readable log missing at most 0.1 s; corrupt
//! sizes, cyclic or exploding formats and random bytes give typed errors,
//! never a panic or a hang.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use helicon_ulog::ReadError;
use helicon_ulog::messages::{Control, RcInput, Timing};
use helicon_ulog::reader::{Message, UlogReader};
use helicon_ulog::spec::{MAGIC, msg};
use helicon_ulog::visit::{End, Event, PassSummary, visit};
use helicon_ulog::{FlushPolicy, Record, UlogWriter};
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

fn sample() -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/helicon_sample.ulg"))
        .unwrap()
}

use helicon_test_support::tmpdir;

/// Message end offsets of a complete file.
fn message_ends(bytes: &[u8]) -> Vec<u64> {
    let mut r = UlogReader::new(bytes, "full").unwrap();
    let mut ends = Vec::new();
    while r.next_message().unwrap().is_some() {
        ends.push(r.offset());
    }
    ends
}

/// Read until the end: (messages, final result).
fn read_prefix(bytes: &[u8]) -> (usize, Result<(), ReadError>) {
    let mut r = match UlogReader::new(bytes, "cut") {
        Ok(r) => r,
        Err(e) => return (0, Err(e)),
    };
    let mut n = 0;
    loop {
        match r.next_message() {
            Ok(Some(_)) => n += 1,
            Ok(None) => return (n, Ok(())),
            Err(e) => return (n, Err(e)),
        }
    }
}

fn pass(bytes: &[u8]) -> Result<(PassSummary, u64), ReadError> {
    let r = UlogReader::new(bytes, "t")?;
    let mut controls = 0;
    let s = visit(r, |ev| -> Result<(), ReadError> {
        if let Event::Data { topic, .. } = ev {
            controls += u64::from(topic.name == "control");
        }
        Ok(())
    })?;
    Ok((s, controls))
}

#[test]
fn a_cut_file_gives_every_complete_message_then_truncated() {
    let bytes = sample();
    let ends = message_ends(&bytes);
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let cuts: Vec<usize> = (0..300)
        .map(|_| rng.random_range(0..bytes.len()))
        .chain(0..64)
        .chain(ends.iter().take(40).map(|e| *e as usize))
        .collect();
    for cut in cuts {
        let (n, end) = read_prefix(&bytes[..cut]);
        let complete = ends.iter().filter(|e| **e as usize <= cut).count();
        assert_eq!(n, complete, "cut at {cut}");
        let on_boundary = cut == 16 || ends.contains(&(cut as u64));
        match end {
            Ok(()) => assert!(on_boundary, "cut at {cut}: clean end"),
            Err(ReadError::Truncated { offset, .. }) => {
                assert!(!on_boundary, "cut at {cut}");
                assert!(offset as usize <= cut);
            }
            Err(e) => panic!("cut at {cut}: {e}"),
        }
    }
}

/// px4-ulog agrees on how many control records a cut file holds.
#[test]
fn px4_ulog_agrees_on_cut_files() {
    let bytes = sample();
    let dir = tmpdir("cut");
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for i in 0..20 {
        let cut = rng.random_range(2000..bytes.len());
        let path = dir.join(format!("cut{i}.ulg"));
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let (summary, ours) = pass(&bytes[..cut]).unwrap();
        let theirs = px4_ulog::full_parser::read_file(path.to_str().unwrap()).unwrap();
        let n = theirs.messages.get("control").map_or(0, |m| {
            match &m[&px4_ulog::full_parser::MultiId::new(0)]["timestamp"] {
                px4_ulog::full_parser::SomeVec::UInt64(v) => v.len() as u64,
                _ => panic!("timestamp type"),
            }
        });
        assert_eq!(ours, n, "cut at {cut}");
        let truncated = matches!(summary.end, End::Truncated { .. });
        assert_eq!(
            truncated,
            theirs.completeness == px4_ulog::full_parser::Completeness::Truncated,
            "cut at {cut}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

const CHILD_ENV: &str = "HELICON_ULOG_KILLED_CHILD";

/// Not a test on its own: the process `a_killed_writer_leaves_a_readable_log`
/// starts and kills. Logs 400 Hz control steps in real time and prints each
/// step number once written (bounded to 60 s if nobody kills it).
#[test]
fn killed_writer_child() {
    let Ok(path) = std::env::var(CHILD_ENV) else {
        return;
    };
    let mut w = UlogWriter::create(Path::new(&path), 0, FlushPolicy::default()).unwrap();
    w.add_format::<Control>().unwrap();
    let topic = w.add_logged::<Control>(0).unwrap();
    let start = std::time::Instant::now();
    for k in 0..24_000u64 {
        let c = Control {
            timestamp: 2500 * k,
            sample: k,
            ..Default::default()
        };
        w.write(topic, &c).unwrap();
        println!("step {k}");
        let next = std::time::Duration::from_micros(2500 * (k + 1));
        if let Some(d) = next.checked_sub(start.elapsed()) {
            std::thread::sleep(d);
        }
    }
}

#[test]
fn a_killed_writer_leaves_a_readable_log() {
    let dir = tmpdir("killed");
    let path = dir.join("killed.ulg");
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "killed_writer_child",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, &path)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let out = BufReader::new(child.stdout.take().unwrap());
    let mut last = None;
    for line in out.lines() {
        let line = line.unwrap();
        if let Some(k) = line.strip_prefix("step ") {
            let k: u64 = k.parse().unwrap();
            last = Some(k);
            if k >= 300 {
                break; // 0.75 s into the flight
            }
        }
    }
    child.kill().unwrap(); // SIGKILL: no destructor, no final flush
    child.wait().unwrap();
    let reported = last.expect("the child wrote steps");
    let bytes = std::fs::read(&path).unwrap();
    let (summary, controls) = pass(&bytes).unwrap();
    assert_eq!(summary.non_monotonic, 0);
    eprintln!(
        "killed after step {reported}: {controls} steps in the file, end {:?}",
        summary.end
    );
    // every step up to the last flush, at most 0.1 s (40 steps) lost
    assert!(
        controls + 40 > reported,
        "{controls} steps in the file, {reported} written"
    );
    let mut r = UlogReader::new(&bytes[..], "killed").unwrap();
    let mut k = 0;
    while let Ok(Some(m)) = r.next_message() {
        if let Message::Data { payload, .. } = m {
            assert_eq!(Control::decode(payload).unwrap().sample, k);
            k += 1;
        }
    }
    assert_eq!(k, controls);
    // and PX4's reader reads the same steps
    let theirs = px4_ulog::full_parser::read_file(path.to_str().unwrap()).unwrap();
    let px4_samples = match &theirs.messages["control"][&px4_ulog::full_parser::MultiId::new(0)]["sample"]
    {
        px4_ulog::full_parser::SomeVec::UInt64(v) => v.clone(),
        _ => panic!("sample type"),
    };
    assert_eq!(px4_samples, (0..controls).collect::<Vec<u64>>());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn message(kind: u8, payload: &[u8]) -> Vec<u8> {
    let mut v = (payload.len() as u16).to_le_bytes().to_vec();
    v.push(kind);
    v.extend_from_slice(payload);
    v
}

fn header() -> Vec<u8> {
    let mut v = MAGIC.to_vec();
    v.push(1);
    v.extend_from_slice(&0u64.to_le_bytes());
    v
}

fn add_logged(name: &str) -> Vec<u8> {
    let mut p = vec![0u8, 0, 0];
    p.extend_from_slice(name.as_bytes());
    message(msg::ADD_LOGGED, &p)
}

fn file(parts: &[Vec<u8>]) -> Vec<u8> {
    let mut v = header();
    for p in parts {
        v.extend_from_slice(p);
    }
    v
}

fn malformed_rule(bytes: &[u8]) -> String {
    match pass(bytes) {
        Err(ReadError::Malformed { rule, .. }) => rule,
        other => panic!("expected a malformed-message error, got {other:?}"),
    }
}

#[test]
fn corrupt_files_are_typed_errors() {
    // not ULog
    assert!(matches!(
        UlogReader::new(&b"PK\x03\x04 not a log"[..], "x.ulg"),
        Err(ReadError::BadMagic { .. })
    ));
    // a size beyond the end of the file: truncated
    let mut f = file(&[]);
    f.extend_from_slice(&[0xff, 0xff, b'D', 0, 0]);
    let (_, end) = read_prefix(&f);
    assert!(matches!(end, Err(ReadError::Truncated { .. })));
    // formats that refer to each other
    let f = file(&[
        message(msg::FORMAT, b"a:uint64_t timestamp;b x;"),
        message(msg::FORMAT, b"b:a y;"),
        add_logged("a"),
    ]);
    assert!(malformed_rule(&f).contains("nest deeper"));
    // a nested array that would be larger than any message
    let f = file(&[
        message(msg::FORMAT, b"a:uint64_t timestamp;b[65535] x;"),
        message(msg::FORMAT, b"b:c[65535] y;"),
        message(msg::FORMAT, b"c:uint8_t z;"),
        add_logged("a"),
    ]);
    assert!(malformed_rule(&f).contains("larger than"));
    // an empty nested type repeated
    let f = file(&[
        message(msg::FORMAT, b"a:uint64_t timestamp;e[65535] x;"),
        message(msg::FORMAT, b"e:"),
        add_logged("a"),
    ]);
    assert!(malformed_rule(&f).contains("empty"));
    // a nested type never defined
    let f = file(&[
        message(msg::FORMAT, b"a:uint64_t timestamp;nope x;"),
        add_logged("a"),
    ]);
    assert!(malformed_rule(&f).contains("no format"));
    // no timestamp
    let f = file(&[message(msg::FORMAT, b"a:float x;"), add_logged("a")]);
    assert!(malformed_rule(&f).contains("timestamp"));
    // a record shorter than its format
    let f = file(&[
        message(msg::FORMAT, b"a:uint64_t timestamp;double x;"),
        add_logged("a"),
        message(msg::DATA, &[0, 0, 1, 2, 3]),
    ]);
    assert!(malformed_rule(&f).contains("needs 16"));
    // a bad array length, a key longer than its message, a bad sync
    let f = file(&[message(msg::FORMAT, b"a:uint64_t timestamp;float[x] v;")]);
    assert!(malformed_rule(&f).contains("array length"));
    let f = file(&[message(msg::INFO, &[200, b'a'])]);
    assert!(malformed_rule(&f).contains("beyond the message"));
    let f = file(&[message(msg::SYNC, &[1; 8])]);
    assert!(malformed_rule(&f).contains("SYNC"));
    // an incompatible flag this reader does not know
    let mut flags = [0u8; 40];
    flags[8] = 0b10;
    let f = file(&[message(msg::FLAG_BITS, &flags)]);
    assert!(matches!(pass(&f), Err(ReadError::Incompatible { .. })));
    // data of an unknown message id is counted and skipped
    let f = file(&[message(msg::DATA, &[7, 0, 1, 2])]);
    assert_eq!(pass(&f).unwrap().0.unknown_records, 1);
    // the error names the file and the offset
    let e = UlogReader::new(&f[..10], "flight.ulg").unwrap_err();
    assert_eq!(
        e.to_string(),
        "flight.ulg: truncated at byte 0 (inside a header message)"
    );
}

fn arb_control() -> impl Strategy<Value = Control> {
    (
        any::<u64>(),
        any::<u64>(),
        any::<f64>(),
        prop::array::uniform4(any::<f64>()),
        prop::array::uniform9(any::<f64>()),
        prop::array::uniform4(any::<bool>()),
    )
        .prop_map(
            |(timestamp, sample, t_s, command, estimate, saturated)| Control {
                timestamp,
                sample,
                t_s,
                ref_yaw_rad: -t_s,
                command,
                estimate,
                measured: estimate,
                saturated,
                ..Default::default()
            },
        )
}

fn arb_rc() -> impl Strategy<Value = RcInput> {
    (
        any::<u64>(),
        prop::array::uniform16(any::<u16>()),
        any::<u8>(),
        any::<bool>(),
    )
        .prop_map(
            |(timestamp, channels_us, channel_count, manual_switch)| RcInput {
                timestamp,
                channels_us,
                channel_count,
                manual_switch,
                signal_lost: !manual_switch,
            },
        )
}

fn encoded<R: Record>(r: &R) -> Vec<u8> {
    let mut b = vec![0; R::SIZE];
    assert_eq!(r.encode(&mut b), Some(R::SIZE));
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Random records written and read back are the same bytes (NaN
    /// payloads included) and the same values.
    #[test]
    fn random_records_round_trip(
        controls in prop::collection::vec(arb_control(), 1..40),
        rcs in prop::collection::vec(arb_rc(), 0..10),
        jitter in any::<i32>(),
    ) {
        let mut w = UlogWriter::new(Vec::new(), 0, FlushPolicy::default()).unwrap();
        w.add_format::<Control>().unwrap();
        w.add_format::<RcInput>().unwrap();
        w.add_format::<Timing>().unwrap();
        let tc = w.add_logged::<Control>(0).unwrap();
        let tr = w.add_logged::<RcInput>(3).unwrap();
        let tt = w.add_logged::<Timing>(0).unwrap();
        let timing = Timing { wakeup_jitter_us: jitter, ..Default::default() };
        for c in &controls { w.write(tc, c).unwrap(); }
        for r in &rcs { w.write(tr, r).unwrap(); }
        w.write(tt, &timing).unwrap();
        let bytes = w.finish().unwrap();
        let mut r = UlogReader::new(&bytes[..], "p").unwrap();
        let (mut got_c, mut got_r, mut got_t) = (Vec::new(), Vec::new(), Vec::new());
        while let Some(m) = r.next_message().unwrap() {
            if let Message::Data { msg_id, payload } = m {
                match msg_id {
                    0 => got_c.push(encoded(&Control::decode(payload).unwrap())),
                    1 => got_r.push(RcInput::decode(payload).unwrap()),
                    _ => got_t.push(Timing::decode(payload).unwrap()),
                }
            }
        }
        prop_assert_eq!(got_c, controls.iter().map(encoded).collect::<Vec<_>>());
        prop_assert_eq!(got_r, rcs);
        prop_assert_eq!(got_t, vec![timing]);
    }

    /// Random bytes, with and without a valid header, never panic the
    /// reader or the pass, and the pass ends.
    #[test]
    fn random_bytes_never_panic(
        body in prop::collection::vec(any::<u8>(), 0..3000),
        with_header in any::<bool>(),
    ) {
        let mut f = if with_header { header() } else { Vec::new() };
        f.extend_from_slice(&body);
        let _ = read_prefix(&f);
        let _ = pass(&f);
    }

    /// A valid log with random bytes overwritten never panics the reader,
    /// the pass or the CSV export's decoding.
    #[test]
    fn corrupted_logs_never_panic(
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..20),
    ) {
        let mut f = sample();
        let n = f.len();
        for (i, b) in edits {
            f[i.index(n)] = b;
        }
        let _ = read_prefix(&f);
        if let Ok(r) = UlogReader::new(&f[..], "x") {
            let _ = visit(r, |ev| -> Result<(), ReadError> {
                if let Event::Data { topic, payload, .. } = ev {
                    for i in 0..topic.format.columns.len() {
                        let _ = topic.format.value(payload, i).map(|v| v.to_string());
                    }
                }
                Ok(())
            });
        }
    }
}

/// As pyulog's `ulog2csv`: no CSV for a topic that logged no record; the
/// text files always.
#[test]
fn export_skips_topics_without_records() {
    let dir = tmpdir("empty_topic");
    let mut w = UlogWriter::new(Vec::new(), 0, FlushPolicy::default()).unwrap();
    w.add_format::<Control>().unwrap();
    w.add_format::<Timing>().unwrap();
    let tc = w.add_logged::<Control>(0).unwrap();
    let _unused = w.add_logged::<Timing>(0).unwrap();
    w.write(tc, &Control::default()).unwrap();
    let path = dir.join("x.ulg");
    std::fs::write(&path, w.finish().unwrap()).unwrap();
    let out = dir.join("csv");
    let report = helicon_ulog::export::export_csv(&path, &out).unwrap();
    assert_eq!(report.topics.len(), 1);
    assert!(out.join("x_control_0.csv").exists());
    assert!(!out.join("x_timing_0.csv").exists());
    for t in ["info", "params", "messages"] {
        assert!(out.join(format!("x_{t}.txt")).exists(), "{t}");
    }
    // the summary still lists the subscription
    let s = helicon_ulog::export::summarize(&path).unwrap();
    assert_eq!(s.topics[&("timing".to_string(), 0)].rows, 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The export counts, per topic, the floats written as `NaN` and as
/// `inf`/`-inf` (PX4's "not available" and "no limit"), and no others.
#[test]
fn export_counts_non_finite_values_per_topic() {
    let dir = tmpdir("non_finite");
    let mut w = UlogWriter::new(Vec::new(), 0, FlushPolicy::default()).unwrap();
    w.add_format::<Control>().unwrap();
    let tc = w.add_logged::<Control>(0).unwrap();
    let mut c = Control {
        command: [f64::NAN, 0.0, f64::INFINITY, f64::NEG_INFINITY],
        ..Control::default()
    };
    w.write(tc, &c).unwrap();
    c.command = [0.5, f64::NAN, 0.0, 0.0];
    w.write(tc, &c).unwrap();
    let path = dir.join("x.ulg");
    std::fs::write(&path, w.finish().unwrap()).unwrap();
    let report = helicon_ulog::export::export_csv(&path, &dir.join("csv")).unwrap();
    let t = &report.topics[&("control".to_string(), 0)];
    assert_eq!((t.stats.rows, t.nan_values, t.infinite_values), (2, 2, 2));
    let text = std::fs::read_to_string(dir.join("csv/x_control_0.csv")).unwrap();
    assert_eq!(text.matches("NaN").count(), 2, "{text}");
    assert_eq!(text.matches("-inf").count(), 1, "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}
