//! Flight logs are never overwritten: `create` refuses an existing file,
//! numbered logs get distinct names whatever the clock says (two in one
//! second, a folder of earlier logs, a board without a real-time clock at
//! 1970), and each numbered log is a complete file of its own.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_ulog::reader::{Message, UlogReader};
use helicon_ulog::writer::{EXISTS_ACTION, log_number, utc_stamp};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, UlogWriter};
use std::path::{Path, PathBuf};

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A numbered flight log holding one LOGGING text `tag`, finished.
fn flight(dir: &Path, unix_s: u64, tag: &str) -> PathBuf {
    let (mut log, path) =
        FlightLog::create_numbered(dir, unix_s, &LogInfo::default(), FlushPolicy::default())
            .unwrap();
    log.writer_mut()
        .log(helicon_ulog::spec::LogLevel::Info, 1, tag)
        .unwrap();
    log.finish().unwrap();
    path
}

/// The LOGGING texts of a log, read to its end by the crate's reader.
fn texts(path: &Path) -> Vec<String> {
    let bytes = std::fs::read(path).unwrap();
    let mut r = UlogReader::new(&bytes[..], &path.display().to_string()).unwrap();
    let mut out = Vec::new();
    while let Some(m) = r.next_message().unwrap() {
        if let Message::Logging { text, .. } = m {
            out.push(text);
        }
    }
    // read to the file's end: every byte is a whole message
    assert_eq!(r.offset(), bytes.len() as u64, "{}", path.display());
    out
}

#[test]
fn create_refuses_an_existing_file_and_leaves_it() {
    let dir = helicon_test_support::tmpdir("ulog-exists");
    let path = dir.join("x.ulg");
    std::fs::write(&path, b"an earlier flight").unwrap();
    let e = UlogWriter::create(&path, 0, FlushPolicy::default()).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("x.ulg") && text.contains("already there"),
        "{text}"
    );
    assert!(matches!(e, helicon_ulog::WriteError::Io { action, .. } if action == EXISTS_ACTION));
    assert_eq!(std::fs::read(&path).unwrap(), b"an earlier flight");
    let e = FlightLog::create(&path, &LogInfo::default(), FlushPolicy::default()).unwrap_err();
    assert!(e.to_string().contains("already there"), "{e}");
    assert_eq!(std::fs::read(&path).unwrap(), b"an earlier flight");
    // replacing is asked for by name
    UlogWriter::create_replacing(&path, 0, FlushPolicy::default())
        .unwrap()
        .finish()
        .unwrap();
    assert_ne!(std::fs::read(&path).unwrap(), b"an earlier flight");
}

#[test]
fn two_logs_in_one_second_are_distinct_and_complete() {
    let dir = helicon_test_support::tmpdir("ulog-same-second");
    let t = 1_764_640_000; // 2025-12-02T01:46:40Z
    let a = flight(&dir, t, "first");
    let b = flight(&dir, t, "second");
    assert_ne!(a, b);
    assert_eq!(
        names(&dir),
        [
            "flight-0001-20251202T014640Z.ulg",
            "flight-0002-20251202T014640Z.ulg"
        ]
    );
    assert_eq!(texts(&a), ["first"]);
    assert_eq!(texts(&b), ["second"]);
}

#[test]
fn a_folder_of_earlier_logs_is_numbered_after_and_kept() {
    let dir = helicon_test_support::tmpdir("ulog-earlier");
    // earlier logs (one from the old naming, other files, a gap in the numbers)
    std::fs::write(dir.join("flight-0007-20240101T000000Z.ulg"), b"seven").unwrap();
    std::fs::write(dir.join("flight-0003-20230101T000000Z.ulg"), b"three").unwrap();
    std::fs::write(dir.join("flight-1764640000.ulg"), b"old name").unwrap();
    std::fs::write(dir.join("timing.json"), b"{}").unwrap();
    let p = flight(&dir, 1_704_067_200, "next");
    assert_eq!(
        p.file_name().unwrap().to_str().unwrap(),
        "flight-0008-20240101T000000Z.ulg"
    );
    assert_eq!(
        std::fs::read(dir.join("flight-0007-20240101T000000Z.ulg")).unwrap(),
        b"seven"
    );
    assert_eq!(
        std::fs::read(dir.join("flight-1764640000.ulg")).unwrap(),
        b"old name"
    );
    assert_eq!(names(&dir).len(), 5);
}

/// A board without a real-time clock boots at 1970 every time: the same
/// stamp each boot, the numbers keep the names apart.
#[test]
fn a_board_without_a_clock_repeats_no_name_across_boots() {
    let dir = helicon_test_support::tmpdir("ulog-no-rtc");
    let mut seen = Vec::new();
    for boot in 0..5u64 {
        // each "boot" a few seconds after 1970-01-01T00:00:00Z
        let p = flight(&dir, 3 + boot % 2, &format!("boot {boot}"));
        assert!(!seen.contains(&p), "{p:?} repeated");
        seen.push(p);
    }
    assert_eq!(names(&dir).len(), 5);
    assert_eq!(
        seen[4].file_name().unwrap().to_str().unwrap(),
        "flight-0005-19700101T000003Z.ulg"
    );
    for (boot, p) in seen.iter().enumerate() {
        assert_eq!(texts(p), [format!("boot {boot}")]);
    }
}

/// Names taken between a scan and its create (loggers racing in one
/// folder) move on to the next number: every log gets its own file.
#[test]
fn racing_loggers_in_one_folder_get_distinct_files() {
    let dir = helicon_test_support::tmpdir("ulog-race");
    let threads: Vec<_> = (0..6)
        .map(|i| {
            let dir = dir.to_path_buf();
            std::thread::spawn(move || {
                (0..15)
                    .map(|j| flight(&dir, 0, &format!("{i}.{j}")))
                    .collect::<Vec<_>>()
            })
        })
        .collect();
    let mut all: Vec<PathBuf> = threads
        .into_iter()
        .flat_map(|t| t.join().unwrap())
        .collect();
    all.sort();
    all.dedup();
    assert_eq!(all.len(), 90);
    assert_eq!(names(&dir).len(), 90);
    let mut tags: Vec<String> = all.iter().flat_map(|p| texts(p)).collect();
    tags.sort();
    tags.dedup();
    assert_eq!(tags.len(), 90, "each log holds its own flight");
}

#[test]
fn numbers_and_stamps_of_names() {
    assert_eq!(
        log_number("flight-0042-19700101T000000Z.ulg", "flight"),
        Some(42)
    );
    assert_eq!(log_number("flight-12345-x.ulg", "flight"), Some(12345));
    assert_eq!(log_number("flight-1764640000.ulg", "flight"), None);
    assert_eq!(log_number("flight--x.ulg", "flight"), None);
    assert_eq!(log_number("flight-00a1-x.ulg", "flight"), None);
    assert_eq!(log_number("flight-0001-x.csv", "flight"), None);
    assert_eq!(log_number("other-0001-x.ulg", "flight"), None);
    assert_eq!(log_number("flight-99999999999-x.ulg", "flight"), None);
    assert_eq!(utc_stamp(0), "19700101T000000Z");
    // 2000-02-29 (a leap day) 23:59:59 UTC
    assert_eq!(utc_stamp(951_868_799), "20000229T235959Z");
    assert_eq!(utc_stamp(u64::MAX), "19700101T000000Z");
}

#[test]
fn a_missing_folder_is_an_error_naming_it() {
    let dir = helicon_test_support::tmpdir("ulog-missing").join("not-there");
    let e = FlightLog::create_numbered(&dir, 0, &LogInfo::default(), FlushPolicy::default())
        .unwrap_err();
    assert!(e.to_string().contains("not-there"), "{e}");
}
