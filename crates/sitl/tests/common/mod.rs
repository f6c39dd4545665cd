//! Shared helpers of the SITL tests: scenarios, options, and the on-board
//! ULog read back by the PX4 organisation's independent reader (`px4-ulog`).
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use helicon_flight::config::{FailsafeConfig, RealtimeConfig, StaleLimits};
use helicon_sim::scenario::Scenario;
use helicon_sitl::{Faults, Pilot, SitlOptions, Speed};
use px4_ulog::full_parser::{Completeness, MultiId, SomeVec, read_file};
use px4_ulog::stream_parser::{Message, SimpleCallbackResult, read_file_with_simple_callback};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub fn scenario(name: &str, duration_s: f64) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    let mut s = Scenario::from_file(&path).unwrap();
    s.duration_s = duration_s;
    s.log.decimation = 1;
    s
}

pub fn options(tag: &str) -> SitlOptions {
    let out_dir: PathBuf = helicon_test_support::process_scratch().join(tag);
    let _ = std::fs::remove_dir_all(&out_dir);
    SitlOptions {
        speed: Speed::Max,
        out_dir,
        faults: Faults::default(),
        pilot: Pilot::default(),
        stale: StaleLimits::default(),
        failsafe: FailsafeConfig::default(),
        realtime: RealtimeConfig::default(),
        keep_frames: true,
        gcs: None,
        log_stride: 1,
        log_part_bytes: None,
        stop: None,
        clock: None,
    }
}

/// The topics of a ULog file: topic → field → values.
pub struct Ulog {
    pub topics: HashMap<String, HashMap<String, SomeVec>>,
    pub texts: Vec<(u64, String)>,
}

impl Ulog {
    pub fn read(path: &Path) -> Ulog {
        let parsed = read_file(path.to_str().unwrap()).unwrap();
        assert_eq!(parsed.completeness, Completeness::Complete);
        let topics = parsed
            .messages
            .into_iter()
            .filter_map(|(name, mut m)| m.remove(&MultiId::new(0)).map(|f| (name, f)))
            .collect();
        let mut texts = Vec::new();
        read_file_with_simple_callback(path.to_str().unwrap(), &mut |m: &Message| {
            if let Message::LoggedMessage(l) = m {
                texts.push((l.timestamp, l.logged_message.to_string()));
            }
            SimpleCallbackResult::KeepReading
        })
        .unwrap();
        Ulog { topics, texts }
    }

    pub fn f64s(&self, topic: &str, field: &str) -> Vec<f64> {
        match self.topics.get(topic).and_then(|t| t.get(field)) {
            Some(SomeVec::Double(v)) => v.clone(),
            None => Vec::new(),
            _ => panic!("{topic}.{field} is not a double"),
        }
    }

    pub fn u64s(&self, topic: &str, field: &str) -> Vec<u64> {
        match self.topics.get(topic).and_then(|t| t.get(field)) {
            Some(SomeVec::UInt64(v)) => v.clone(),
            None => Vec::new(),
            _ => panic!("{topic}.{field} is not a u64"),
        }
    }

    pub fn u8s(&self, topic: &str, field: &str) -> Vec<u8> {
        match self.topics.get(topic).and_then(|t| t.get(field)) {
            Some(SomeVec::UInt8(v)) => v.clone(),
            None => Vec::new(),
            _ => panic!("{topic}.{field} is not a u8"),
        }
    }

    pub fn bools(&self, topic: &str, field: &str) -> Vec<bool> {
        match self.topics.get(topic).and_then(|t| t.get(field)) {
            Some(SomeVec::Bool(v)) => v.clone(),
            None => Vec::new(),
            _ => panic!("{topic}.{field} is not a bool"),
        }
    }

    /// The text messages containing `needle`, with their times (s).
    pub fn texts_with(&self, needle: &str) -> Vec<(f64, String)> {
        self.texts
            .iter()
            .filter(|(_, t)| t.contains(needle))
            .map(|(ts, t)| (*ts as f64 * 1e-6, t.clone()))
            .collect()
    }

    /// The time (s) of the first text containing `needle`, which must have
    /// been logged.
    pub fn first_text(&self, needle: &str) -> f64 {
        let t = self.texts_with(needle);
        assert!(!t.is_empty(), "no text with {needle:?} in {:?}", self.texts);
        t[0].0
    }
}
