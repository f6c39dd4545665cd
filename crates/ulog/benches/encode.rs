//! Encoder throughput: one `control` record encoded into a caller buffer,
//! and one whole control step (IMU, control, navigation, timing) written
//! through the `FlightLog` into a sink (buffering and flushing included);
//! and the reader: one pass (formats resolved, every record's timestamp)
//! over the committed sample log, in bytes per second.
#![allow(clippy::unwrap_used, missing_docs)] // bench: criterion macros generate undocumented items

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use helicon_ulog::messages::{Control, Navigation, SensorImu, Timing};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, LogRecord, Record};
use std::hint::black_box;

fn control(k: u64) -> Control {
    Control {
        timestamp: 2500 * k,
        sample: k,
        t_s: k as f64 * 0.0025,
        command: [0.1, 0.2, 0.3, 0.4],
        estimate: [1.0; 9],
        measured: [2.0; 9],
        ..Default::default()
    }
}

fn bench_encode(c: &mut Criterion) {
    let mut g = c.benchmark_group("ulog");
    g.throughput(Throughput::Elements(1));
    let rec = control(7);
    let mut buf = [0u8; Control::SIZE];
    g.bench_function("encode_control_record", |b| {
        b.iter(|| black_box(&rec).encode(black_box(&mut buf)))
    });
    let mut log =
        FlightLog::new(std::io::sink(), &LogInfo::default(), FlushPolicy::default()).unwrap();
    let mut k = 0u64;
    g.throughput(Throughput::Elements(4));
    g.bench_function("write_control_step_4_records", |b| {
        b.iter(|| {
            k += 1;
            let ts = 2500 * k;
            log.write(&LogRecord::Imu(SensorImu {
                timestamp: ts,
                ..Default::default()
            }))
            .unwrap();
            log.write(&LogRecord::Control(control(k))).unwrap();
            log.write(&LogRecord::Navigation(Navigation {
                timestamp: ts,
                ..Default::default()
            }))
            .unwrap();
            log.write(&LogRecord::Timing(Timing {
                timestamp: ts,
                sample: k,
                ..Default::default()
            }))
            .unwrap();
        })
    });
    g.finish();
}

fn bench_read(c: &mut Criterion) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/helicon_sample.ulg");
    let bytes = std::fs::read(path).unwrap();
    let mut g = c.benchmark_group("ulog");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("read_pass_sample", |b| {
        b.iter(|| {
            let r = helicon_ulog::reader::UlogReader::new(black_box(&bytes[..]), "s").unwrap();
            let mut n = 0u64;
            helicon_ulog::visit::visit(r, |ev| -> Result<(), helicon_ulog::ReadError> {
                if let helicon_ulog::visit::Event::Data { timestamp_us, .. } = ev {
                    n = n.wrapping_add(timestamp_us);
                }
                Ok(())
            })
            .unwrap();
            n
        })
    });
    g.finish();
}

criterion_group!(benches, bench_encode, bench_read);
criterion_main!(benches);
