//! Hostile flight logs for `helicon_ulog::columns`: a small valid log cut at
//! every byte offset, every byte flipped, duplicated and backward control
//! timestamps, absurd control periods. Every case must give columns or an
//! error naming the file; never a panic, and no non-finite value in the
//! columns given.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_ulog::LogRecord;
use helicon_ulog::columns::read_ulog_columns;
use helicon_ulog::messages::Excitation;
use helicon_ulog::synthetic::{synthetic_value, write_control_log};
use std::path::{Path, PathBuf};

const T_S: f64 = 0.0025;
const NAMES: [&str; 5] = ["S_lat", "meas_p", "est_q", "exc_lat", "exc_col"];

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("helicon_ulog_hostile_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A log of `n` control steps stamped by `stamp(k)` (µs), each followed by
/// an excitation record.
fn write_log(name: &str, n: u64, stamp: impl Fn(u64) -> u64) -> PathBuf {
    let path = dir().join(format!("{name}.ulg"));
    write_control_log(
        &path,
        n,
        |k| Some(stamp(k)),
        |_, _| {},
        |k, c| {
            Some(LogRecord::Excitation(Excitation {
                timestamp: c.timestamp,
                offset: std::array::from_fn(|i| synthetic_value(k, i + 30)),
                active: true,
            }))
        },
    )
    .unwrap();
    path
}

/// Read `path`; a panic fails with `what`; an error must name the file;
/// columns given must be finite.
fn read_checked(path: &Path, period_s: Option<f64>, what: &str) {
    let r = std::panic::catch_unwind(|| read_ulog_columns(path, &NAMES, period_s));
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    match r {
        Err(_) => panic!("{what}: the reader panicked"),
        Ok(Err(e)) => {
            let e = e.to_string();
            assert!(e.contains(&name), "{what}: error without the file: {e}");
        }
        Ok(Ok(c)) => {
            for (n, col) in c.names.iter().zip(&c.columns) {
                assert!(
                    col.iter().all(|x| x.is_finite()),
                    "{what}: column {n} has a non-finite value"
                );
                assert_eq!(col.len(), c.columns[0].len(), "{what}: column {n} length");
            }
        }
    }
}

#[test]
fn a_log_cut_at_every_offset_reads_or_is_refused_naming_the_file() {
    let p = write_log("whole", 40, |k| 1_000_000 + k * 2500);
    let bytes = std::fs::read(&p).unwrap();
    let cut = dir().join("cut.ulg");
    for at in 0..bytes.len() {
        std::fs::write(&cut, &bytes[..at]).unwrap();
        read_checked(&cut, Some(T_S), &format!("cut at {at}"));
    }
}

#[test]
fn a_log_with_any_byte_flipped_reads_or_is_refused_naming_the_file() {
    let p = write_log("flip_src", 40, |k| 1_000_000 + k * 2500);
    let bytes = std::fs::read(&p).unwrap();
    let flipped = dir().join("flipped.ulg");
    for at in 0..bytes.len() {
        // all bits of the even bytes, the lowest bit of the odd ones
        let mask = if at % 2 == 0 { 0xFFu8 } else { 0x01 };
        let mut b = bytes.clone();
        b[at] ^= mask;
        std::fs::write(&flipped, &b).unwrap();
        read_checked(&flipped, None, &format!("byte {at} ^ {mask:#x}"));
    }
}

#[test]
fn duplicated_or_backward_control_stamps_are_refused_naming_the_time() {
    // step 21 stamped as step 20
    let dup = write_log("dup", 40, |k| 1_000_000 + (k - u64::from(k > 20)) * 2500);
    let e = read_ulog_columns(&dup, &NAMES, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("dup.ulg") && e.contains("1.05") && e.contains("twice"),
        "{e}"
    );
    assert!(!e.contains("back in time"), "{e}");
    let back = write_log("back", 40, |k| {
        if k == 25 {
            1_000_000
        } else {
            1_000_000 + k * 2500
        }
    });
    let e = read_ulog_columns(&back, &NAMES, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("back.ulg") && e.contains("back in time"), "{e}");
    // the largest stamps the format can hold
    let huge = write_log("huge", 40, |k| u64::MAX - 40 * 2500 + k * 2500);
    read_checked(&huge, None, "stamps near u64::MAX");
    read_checked(&huge, Some(T_S), "stamps near u64::MAX, period given");
}

#[test]
fn absurd_control_periods_are_refused_naming_the_period() {
    let p = write_log("period", 40, |k| 1_000_000 + k * 2500);
    for ts in [
        0.0,
        -T_S,
        f64::NAN,
        f64::INFINITY,
        1e-300,
        1e300,
        f64::MIN_POSITIVE,
    ] {
        let e = read_ulog_columns(&p, &NAMES, Some(ts))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("period.ulg") && e.contains("period"),
            "{ts}: {e}"
        );
    }
}

// ---------------------------------------------------------------------------
// ULog bombs: small files whose reading could cost far more than their size.
// Memory is measured with the counting allocator (this thread's peak heap),
// never with a timer.

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

mod bombs {
    use helicon_ulog::ReadError;
    use helicon_ulog::reader::UlogReader;
    use helicon_ulog::spec::{MAGIC, msg};
    use helicon_ulog::visit::{Event, Limits, visit, visit_with};

    /// A ULog message: size, type, payload.
    fn message(out: &mut Vec<u8>, kind: u8, payload: &[u8]) {
        let n = u16::try_from(payload.len()).unwrap();
        out.extend_from_slice(&n.to_le_bytes());
        out.push(kind);
        out.extend_from_slice(payload);
    }

    fn header() -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.push(1);
        b.extend_from_slice(&0u64.to_le_bytes());
        b
    }

    fn format(out: &mut Vec<u8>, text: &str) {
        message(out, msg::FORMAT, text.as_bytes());
    }

    fn subscribe(out: &mut Vec<u8>, msg_id: u16, name: &str) {
        let mut p = vec![0u8];
        p.extend_from_slice(&msg_id.to_le_bytes());
        p.extend_from_slice(name.as_bytes());
        message(out, msg::ADD_LOGGED, &p);
    }

    /// One format of 65,500 `uint8_t` columns (and its timestamp)
    /// subscribed `n` times, then one record of each of the first
    /// `records` subscriptions.
    fn wide(n: usize, records: usize, topic: &str) -> Vec<u8> {
        wide_as(n, records, topic, "uint8_t[65500] x;")
    }

    /// [`wide`] with the fields `fields` after the timestamp.
    fn wide_as(n: usize, records: usize, topic: &str, fields: &str) -> Vec<u8> {
        let mut b = header();
        format(&mut b, &format!("{topic}:uint64_t timestamp;{fields}"));
        for i in 0..n {
            subscribe(&mut b, u16::try_from(i % 65_535).unwrap(), topic);
        }
        for i in 0..records {
            let mut p = u16::try_from(i).unwrap().to_le_bytes().to_vec();
            p.extend_from_slice(&(1000 + i as u64).to_le_bytes());
            p.extend(std::iter::repeat_n(7u8, 65_500));
            message(&mut b, msg::DATA, &p);
        }
        b
    }

    /// Peak heap (bytes) of this thread while `f` runs, above its start.
    fn peak_of<T>(f: impl FnOnce() -> T) -> (T, isize) {
        helicon_test_support::reset_peak();
        let before = helicon_test_support::live_bytes();
        let out = f();
        let peak = helicon_test_support::peak_bytes() - before;
        eprintln!("peak heap: {peak} bytes");
        (out, peak)
    }

    const MIB: isize = 1 << 20;

    #[test]
    fn a_65500_column_format_subscribed_50000_times_is_refused_in_bounded_memory() {
        let bytes = wide(50_000, 0, "t");
        assert!(bytes.len() < 400_000, "{}", bytes.len());
        let (r, peak) = peak_of(|| {
            let reader = UlogReader::new(&bytes[..], "bomb.ulg").unwrap();
            let mut subscribed = 0usize;
            let r = visit(reader, |e| -> Result<(), ReadError> {
                if let Event::Subscribed { .. } = e {
                    subscribed += 1;
                }
                Ok(())
            });
            (r, subscribed)
        });
        let (r, subscribed) = r;
        match r {
            Err(ReadError::Limit {
                file, what, limit, ..
            }) => {
                assert_eq!(file, "bomb.ulg");
                assert_eq!(what, "subscriptions");
                assert_eq!(limit, Limits::DEFAULT.subscriptions as u64);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(subscribed, Limits::DEFAULT.subscriptions);
        // one flattening (65,500 columns, a few MB) shared by every
        // subscription; flattened per subscription it was 3.7 MB each
        assert!(peak < 16 * MIB, "peak {peak} bytes");
    }

    #[test]
    fn a_65500_column_format_subscribed_4096_times_is_read_in_bounded_memory() {
        let n = Limits::DEFAULT.subscriptions;
        let bytes = wide(n, 3, "t");
        let (r, peak) = peak_of(|| {
            let reader = UlogReader::new(&bytes[..], "wide.ulg").unwrap();
            let mut first: Option<std::sync::Arc<helicon_ulog::flat::FlatFormat>> = None;
            let (mut shared, mut records) = (0usize, 0usize);
            let r = visit(reader, |e| -> Result<(), ReadError> {
                match e {
                    Event::Subscribed { topic, .. } => {
                        let f = first.get_or_insert_with(|| topic.format.clone());
                        shared += usize::from(std::sync::Arc::ptr_eq(f, &topic.format));
                    }
                    Event::Data {
                        topic,
                        payload,
                        timestamp_us,
                        ..
                    } => {
                        assert_eq!(timestamp_us, 1000 + records as u64);
                        assert_eq!(topic.format.columns.len(), 65_501);
                        assert_eq!(
                            topic.format.value(payload, 65_500),
                            Some(helicon_ulog::reader::Value::UInt(7))
                        );
                        records += 1;
                    }
                    _ => {}
                }
                Ok(())
            });
            (r, shared, records)
        });
        let (r, shared, records) = r;
        r.unwrap();
        assert_eq!((shared, records), (n, 3));
        assert!(peak < 16 * MIB, "peak {peak} bytes");
    }

    #[test]
    fn the_bombs_on_disk_are_refused_by_the_columns_reader_in_bounded_memory() {
        let d = super::dir();
        // the time base topic, the field asked for after 65,000 others: each
        // subscription would search them all
        let fields = "uint8_t[65000] x;float[4] command;";
        let wide_control = d.join("wide_control.ulg");
        std::fs::write(&wide_control, wide_as(4000, 0, "control", fields)).unwrap();
        let bomb = d.join("bomb_control.ulg");
        std::fs::write(&bomb, wide_as(50_000, 0, "control", fields)).unwrap();
        for (p, want) in [
            (&wide_control, "control"),
            (&bomb, "more than 4096 subscriptions"),
        ] {
            let (r, peak) =
                peak_of(|| helicon_ulog::columns::read_ulog_columns(p, &["S_lat"], None));
            let e = r.unwrap_err().to_string();
            assert!(e.contains(&p.display().to_string()), "{e}");
            assert!(e.contains(want), "{e}");
            assert!(peak < 16 * MIB, "{}: peak {peak} bytes", p.display());
        }
    }

    #[cfg(feature = "export")]
    #[test]
    fn the_bomb_is_refused_by_log_info_and_export_in_bounded_memory() {
        let d = super::dir();
        let bomb = d.join("bomb_info.ulg");
        std::fs::write(&bomb, wide(50_000, 0, "t")).unwrap();
        let (r, peak) = peak_of(|| helicon_ulog::export::summarize(&bomb));
        let e = r.unwrap_err().to_string();
        assert!(
            e.contains("bomb_info.ulg") && e.contains("subscriptions"),
            "{e}"
        );
        assert!(peak < 16 * MIB, "peak {peak} bytes");
        let out = d.join("bomb_export");
        let (r, peak) = peak_of(|| helicon_ulog::export::export_csv(&bomb, &out));
        let e = r.unwrap_err().to_string();
        assert!(
            e.contains("bomb_info.ulg") && e.contains("subscriptions"),
            "{e}"
        );
        assert!(peak < 16 * MIB, "peak {peak} bytes");
    }

    /// `parts` INFO_MULTIPLE parts of key `key`, each `part(i)` bytes.
    fn multi(key: &str, parts: usize, part: impl Fn(usize) -> Vec<u8>) -> Vec<u8> {
        let mut b = header();
        for i in 0..parts {
            let mut p = vec![u8::from(i > 0), u8::try_from(key.len()).unwrap()];
            p.extend_from_slice(key.as_bytes());
            p.extend(part(i));
            message(&mut b, msg::INFO_MULTIPLE, &p);
        }
        b
    }

    fn joined(bytes: &[u8], limits: &Limits) -> Result<Vec<(String, Vec<u8>, String)>, ReadError> {
        let reader = UlogReader::new(bytes, "multi.ulg").unwrap();
        let mut out = Vec::new();
        visit_with(reader, limits, |e| -> Result<(), ReadError> {
            if let Event::InfoMultiple(m) = e {
                out.push((m.name.clone(), m.bytes.clone(), m.type_name()));
            }
            Ok(())
        })?;
        Ok(out)
    }

    #[test]
    fn info_multiple_parts_are_joined_as_bytes_in_memory_of_their_size() {
        let byte = |i: usize, k: usize| ((i * 31 + k * 7) % 251) as u8;
        let bytes = multi("uint8_t[65000] blob", 100, |i| {
            (0..65_000).map(|k| byte(i, k)).collect()
        });
        let (r, peak) = peak_of(|| joined(&bytes, &Limits::DEFAULT));
        let r = r.unwrap();
        assert_eq!(r.len(), 1);
        let (name, value, ty) = &r[0];
        assert_eq!((name.as_str(), ty.as_str()), ("blob", "uint8_t[6500000]"));
        assert_eq!(value.len(), 6_500_000);
        assert!(
            value
                .iter()
                .enumerate()
                .all(|(j, b)| *b == byte(j / 65_000, j % 65_000))
        );
        // the joined bytes, the copy collected above and the reader's
        // message; one value per byte was 35 times the file
        assert!(peak < 2 * 6_500_000 + 4 * MIB, "peak {peak} bytes");
        // the limit: one byte less than the whole
        let small = Limits {
            info_multiple_bytes: 6_499_999,
            ..Limits::DEFAULT
        };
        match joined(&bytes, &small) {
            Err(ReadError::Limit { what, limit, .. }) => {
                assert!(what.contains("`blob`"), "{what}");
                assert_eq!(limit, 6_499_999);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn text_split_inside_a_character_is_joined_whole() {
        // "é" (0xC3 0xA9) split across two parts; a third part of another
        // type is left out
        let mut bytes = multi("char[2] t", 2, |i| {
            if i == 0 {
                vec![b'a', 0xC3]
            } else {
                vec![0xA9, b'b']
            }
        });
        let mut p = vec![1u8, 9];
        p.extend_from_slice(b"uint8_t t");
        p.push(5);
        message(&mut bytes, msg::INFO_MULTIPLE, &p);
        let reader = UlogReader::new(&bytes[..], "t.ulg").unwrap();
        let mut texts = Vec::new();
        visit(reader, |e| -> Result<(), ReadError> {
            if let Event::InfoMultiple(m) = e {
                texts.push((m.value(), m.to_string()));
            }
            Ok(())
        })
        .unwrap();
        assert_eq!(
            texts,
            [(
                helicon_ulog::reader::Value::Str("aéb".into()),
                "aéb".to_string()
            )]
        );
    }

    #[test]
    fn a_format_of_too_many_fields_is_refused() {
        let mut b = header();
        let fields = "bool a;".repeat(5000);
        format(&mut b, &format!("t:uint64_t timestamp;{fields}"));
        let reader = UlogReader::new(&b[..], "fields.ulg").unwrap();
        match visit(reader, |_| -> Result<(), ReadError> { Ok(()) }) {
            Err(ReadError::Limit {
                what,
                limit,
                offset,
                ..
            }) => {
                assert_eq!(what, "fields in format `t`");
                assert_eq!(limit, 4096);
                assert_eq!(offset, 16);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn formats_declared_anew_between_subscriptions_stop_at_the_column_budget() {
        // each declaration differs from the last, so each subscription
        // flattens 65,000 columns again
        let mut b = header();
        for i in 0..2000u16 {
            format(
                &mut b,
                &format!("t:uint64_t timestamp;uint8_t[{}] x;", 65_000 + i % 2),
            );
            subscribe(&mut b, i, "t");
        }
        let (r, peak) = peak_of(|| {
            let reader = UlogReader::new(&b[..], "anew.ulg").unwrap();
            visit(reader, |_| -> Result<(), ReadError> { Ok(()) })
        });
        match r {
            Err(ReadError::Limit { what, limit, .. }) => {
                assert!(what.starts_with("columns flattened in all"), "{what}");
                assert_eq!(limit, 1 << 20);
            }
            other => panic!("{other:?}"),
        }
        // at most the budget's columns held (about 70 bytes each)
        assert!(peak < 96 * MIB, "peak {peak} bytes");
    }

    #[test]
    fn the_same_format_declared_again_is_flattened_once() {
        let mut b = header();
        for i in 0..3000u16 {
            format(&mut b, "t:uint64_t timestamp;uint8_t[65000] x;");
            subscribe(&mut b, i % 2000, "t");
        }
        let reader = UlogReader::new(&b[..], "again.ulg").unwrap();
        let mut subs = 0;
        visit(reader, |e| -> Result<(), ReadError> {
            subs += usize::from(matches!(e, Event::Subscribed { .. }));
            Ok(())
        })
        .unwrap();
        assert_eq!(subs, 3000);
    }
}
