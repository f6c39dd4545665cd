//! helicon's ULog reader and writer against pyulog, the PX4 project's
//! Python reader (fixtures made by `tools/gen_ulog_fixtures.py`):
//! - the committed sample written by helicon's writer is byte for byte what
//!   the writer produces today, and helicon's reader returns exactly what
//!   pyulog returned for it (every value bit for bit, info, parameters and
//!   their change, text messages with levels, the dropout);
//! - a log written by pyulog's own writer with real PX4 formats (nested
//!   types, padding inside records, several instances, `char` strings) is
//!   read by helicon's reader, and exported to CSV, with exactly pyulog's
//!   values.
//!
//! pyulog lists the `_padding` fields inside records as columns; the ULog
//! specification says readers do not display them, so they are left out
//! of the comparison (and of helicon's columns).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "../examples/ulog_sample.rs"]
mod sample;

use helicon_ulog::ReadError;
use helicon_ulog::reader::{UlogReader, Value};
use helicon_ulog::visit::{End, Event, visit};
use serde_json::Value as Json;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[derive(Default, Debug)]
struct Collected {
    info: BTreeMap<String, Value>,
    info_multiple: BTreeMap<String, Vec<String>>,
    initial: BTreeMap<String, Value>,
    changed: Vec<(u64, String, Value)>,
    logged: Vec<(u64, u8, String)>,
    dropouts: Vec<(u64, u16)>,
    // "topic_multiid" -> (columns, rows)
    data: BTreeMap<String, (Vec<String>, Vec<Vec<Value>>)>,
}

fn collect(path: &Path) -> Collected {
    let bytes = std::fs::read(path).unwrap();
    let reader = UlogReader::new(&bytes[..], &path.display().to_string()).unwrap();
    let mut c = Collected::default();
    let pass = visit(reader, |ev| -> Result<(), ReadError> {
        match ev {
            Event::Info(kv) => {
                c.info.insert(kv.name.clone(), kv.value.clone());
            }
            Event::InfoMultiple(kv) => {
                let Value::Str(text) = &kv.value() else {
                    panic!("{}: not text", kv.name)
                };
                c.info_multiple
                    .entry(kv.name.clone())
                    .or_default()
                    .push(text.clone());
            }
            Event::Parameter {
                kv,
                in_data,
                timestamp_us,
            } => {
                if in_data {
                    c.changed
                        .push((timestamp_us, kv.name.clone(), kv.value.clone()));
                } else {
                    c.initial.insert(kv.name.clone(), kv.value.clone());
                }
            }
            Event::Subscribed { topic, .. } => {
                let cols = topic
                    .format
                    .columns
                    .iter()
                    .map(|c| c.name.clone())
                    .collect();
                c.data
                    .entry(format!("{}_{}", topic.name, topic.multi_id))
                    .or_insert((cols, Vec::new()));
            }
            Event::Data { topic, payload, .. } => {
                let row = (0..topic.format.columns.len())
                    .map(|i| topic.format.value(payload, i).unwrap())
                    .collect();
                let key = format!("{}_{}", topic.name, topic.multi_id);
                c.data.get_mut(&key).unwrap().1.push(row);
            }
            Event::Logging {
                level,
                timestamp_us,
                text,
                ..
            } => c
                .logged
                .push((timestamp_us, level.unwrap().byte(), text.to_string())),
            Event::Dropout {
                duration_ms,
                timestamp_us,
            } => c.dropouts.push((timestamp_us, duration_ms)),
        }
        Ok(())
    })
    .unwrap();
    assert_eq!(pass.end, End::Complete);
    assert_eq!(pass.non_monotonic, 0);
    assert_eq!(pass.unknown_records, 0);
    c
}

/// A non-finite value equals pyulog's string for it (`NaN`, `inf`, `-inf`).
fn non_finite(a: f64, s: &str) -> bool {
    match s {
        "NaN" => a.is_nan(),
        "inf" => a == f64::INFINITY,
        "-inf" => a == f64::NEG_INFINITY,
        _ => false,
    }
}

/// One of our values equals pyulog's JSON value exactly.
fn same(v: &Value, j: &Json) -> bool {
    match (v, j) {
        (Value::Int(a), Json::Number(n)) => n.as_i64() == Some(*a),
        (Value::UInt(a), Json::Number(n)) => n.as_u64() == Some(*a),
        // pyulog gives `char` fields as one-byte strings
        (Value::UInt(a), Json::String(s)) => s.as_bytes() == [u8::try_from(*a).unwrap()],
        (Value::Float(a), Json::Number(n)) => n.as_f64().unwrap().to_bits() == a.to_bits(),
        (Value::Float32(a), Json::Number(n)) => {
            n.as_f64().unwrap().to_bits() == f64::from(*a).to_bits()
        }
        // pyulog's JSON writes non-finite values as strings
        (Value::Float(a), Json::String(s)) => non_finite(*a, s),
        (Value::Float32(a), Json::String(s)) => non_finite(f64::from(*a), s),
        (Value::Bool(a), Json::Bool(b)) => a == b,
        // pyulog gives `bool` fields as int8 0/1
        (Value::Bool(a), Json::Number(n)) => n.as_u64() == Some(u64::from(*a)),
        (Value::Str(a), Json::String(b)) => a == b,
        _ => false,
    }
}

fn check_against_pyulog(ulg: &str, json: &str) -> usize {
    let ours = collect(&fixture(ulg));
    let py: Json = serde_json::from_str(&std::fs::read_to_string(fixture(json)).unwrap()).unwrap();
    assert_eq!(py["file_corruption"], Json::Bool(false));

    let info = py["info"].as_object().unwrap();
    assert_eq!(info.len(), ours.info.len(), "info keys");
    for (k, v) in info {
        assert!(
            same(&ours.info[k], v),
            "info {k}: {:?} vs {v}",
            ours.info[k]
        );
    }
    let multiple: BTreeMap<String, Vec<String>> =
        serde_json::from_value(py["info_multiple"].clone()).unwrap();
    assert_eq!(multiple, ours.info_multiple, "multi-part information");
    let params = py["initial_parameters"].as_object().unwrap();
    assert_eq!(params.len(), ours.initial.len());
    for (k, v) in params {
        assert!(same(&ours.initial[k], v), "parameter {k}");
    }
    let changed = py["changed_parameters"].as_array().unwrap();
    assert_eq!(changed.len(), ours.changed.len());
    for (p, (t, n, v)) in changed.iter().zip(&ours.changed) {
        assert_eq!(p[0].as_u64(), Some(*t));
        assert_eq!(p[1].as_str(), Some(n.as_str()));
        assert!(same(v, &p[2]));
    }
    let logged = py["logged_messages"].as_array().unwrap();
    assert_eq!(logged.len(), ours.logged.len());
    for (p, (t, level, text)) in logged.iter().zip(&ours.logged) {
        assert_eq!(p[0].as_u64(), Some(*t));
        assert_eq!(p[1].as_u64(), Some(u64::from(*level)));
        assert_eq!(p[3].as_str(), Some(text.as_str()));
    }
    let dropouts = py["dropouts"].as_array().unwrap();
    assert_eq!(dropouts.len(), ours.dropouts.len());
    for (p, (t, d)) in dropouts.iter().zip(&ours.dropouts) {
        assert_eq!(p[0].as_u64(), Some(*t), "dropout time");
        assert_eq!(p[1].as_u64(), Some(u64::from(*d)));
    }

    let data = py["data"].as_object().unwrap();
    // pyulog leaves out the topics subscribed that logged no record
    assert_eq!(
        data.keys().collect::<Vec<_>>(),
        ours.data
            .iter()
            .filter(|(_, (_, rows))| !rows.is_empty())
            .map(|(k, _)| k)
            .collect::<Vec<_>>()
    );
    let mut values = 0;
    for (key, topic) in data {
        let (cols, rows) = &ours.data[key];
        let py_cols: Vec<&str> = topic["columns"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap())
            .filter(|c| !c.split('.').any(|part| part.starts_with("_padding")))
            .collect();
        assert_eq!(cols, &py_cols, "{key}: columns");
        for (i, col) in cols.iter().enumerate() {
            let py_vals = topic["values"][col.as_str()].as_array().unwrap();
            assert_eq!(py_vals.len(), rows.len(), "{key}.{col}: rows");
            for (r, (ours_row, p)) in rows.iter().zip(py_vals).enumerate() {
                assert!(
                    same(&ours_row[i], p),
                    "{key}.{col} row {r}: {:?} vs {p}",
                    ours_row[i]
                );
                values += 1;
            }
        }
    }
    values
}

#[test]
fn writer_reproduces_the_committed_sample() {
    let committed = std::fs::read(fixture("helicon_sample.ulg")).unwrap();
    let now = sample::build().unwrap();
    assert!(
        committed == now,
        "the writer's output changed: regenerate the sample and the pyulog fixture \
         (cargo run -p helicon-ulog --example ulog_sample -- crates/ulog/tests/fixtures/helicon_sample.ulg; \
         python3 tools/gen_ulog_fixtures.py)"
    );
}

#[test]
fn reader_matches_pyulog_on_helicons_sample() {
    let n = check_against_pyulog("helicon_sample.ulg", "helicon_sample.pyulog.json");
    assert!(n > 4_000, "{n} values compared");
}

#[test]
fn reader_matches_pyulog_on_a_px4_log_written_by_pyulog() {
    let n = check_against_pyulog("px4_trimmed.ulg", "px4_trimmed.pyulog.json");
    assert!(n > 1_000, "{n} values compared");
}

/// The CSV export has pyulog's columns (padding left out) and values.
#[test]
fn csv_export_matches_pyulog() {
    for (ulg, json) in [
        ("helicon_sample.ulg", "helicon_sample.pyulog.json"),
        ("px4_trimmed.ulg", "px4_trimmed.pyulog.json"),
    ] {
        let dir = std::env::temp_dir().join(format!(
            "helicon_ulog_export_{}_{}",
            std::process::id(),
            ulg.replace('.', "_")
        ));
        let report = helicon_ulog::export::export_csv(&fixture(ulg), &dir).unwrap();
        let py: Json =
            serde_json::from_str(&std::fs::read_to_string(fixture(json)).unwrap()).unwrap();
        let stem = ulg.trim_end_matches(".ulg");
        let data = py["data"].as_object().unwrap();
        assert_eq!(report.topics.len(), data.len());
        for (key, topic) in data {
            let path = dir.join(format!("{stem}_{key}.csv"));
            let mut rdr = csv::Reader::from_path(&path).unwrap();
            let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
            assert_eq!(header[0], "timestamp", "{key}: timestamp first");
            for (i, col) in header.iter().enumerate() {
                let py_vals = topic["values"][col.as_str()].as_array().unwrap();
                let mut rows = 0;
                for (rec, p) in csv::Reader::from_path(&path)
                    .unwrap()
                    .records()
                    .zip(py_vals)
                {
                    let field = rec.unwrap()[i].to_string();
                    let ok = match p {
                        // `float` columns are written in f32's shortest form
                        Json::Number(n) if topic["types"][col.as_str()] == "float" => {
                            f64::from(field.parse::<f32>().unwrap()).to_bits()
                                == n.as_f64().unwrap().to_bits()
                        }
                        Json::Number(n) if n.is_f64() => {
                            field.parse::<f64>().unwrap().to_bits() == n.as_f64().unwrap().to_bits()
                        }
                        Json::Number(n) => field == n.to_string(),
                        Json::Bool(b) => field == if *b { "1" } else { "0" },
                        Json::String(s) if ["NaN", "inf", "-inf"].contains(&s.as_str()) => {
                            field == *s
                        }
                        Json::String(s) => field == s.as_bytes()[0].to_string(),
                        _ => false,
                    };
                    assert!(ok, "{key}.{col}: {field} vs {p}");
                    rows += 1;
                }
                assert_eq!(rows, py_vals.len(), "{key}.{col}: rows");
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
