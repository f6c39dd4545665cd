//! Decoder throughput (bytes/s) on streams of valid frames, pushed in
//! 64-byte chunks as a serial read delivers them.
#![allow(clippy::unwrap_used, missing_docs)] // bench: criterion macros generate undocumented items

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::framing::Protocol;
use helicon_devices::*;
use nalgebra::{Vector3, Vector4};
use std::hint::black_box;

fn stream(frame: &[u8], n: usize) -> Vec<u8> {
    frame
        .iter()
        .copied()
        .cycle()
        .take(frame.len() * n)
        .collect()
}

fn bench_one<P: Protocol>(c: &mut Criterion, name: &str, bytes: &[u8]) {
    let mut g = c.benchmark_group("decode");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function(name, |b| {
        let mut d = StreamDecoder::<P>::new();
        b.iter(|| {
            let mut n = 0usize;
            for chunk in bytes.chunks(64) {
                n += d.push(black_box(chunk)).count();
            }
            n
        })
    });
    g.finish();
}

fn decoders(c: &mut Criterion) {
    let imu = ImuSample {
        specific_force_body_m_s2: Vector3::new(0.1, -0.2, -9.82),
        gyro_body_rad_s: Vector3::new(0.01, 0.02, -0.03),
    };
    let mag = Vector3::new(0.153, 0.008, -0.438);
    let vn = VnCommon::from_samples(1.0, &imu, Some(&mag))
        .unwrap()
        .encode()
        .unwrap();
    bench_one::<vectornav::VnBinary>(c, "vn100_binary", &stream(vn.as_bytes(), 100));

    let home = LocalNed::new(Geodetic::new(57.0, 9.9, 30.0).unwrap());
    let fix = GpsFix {
        epoch_s: 1.0,
        fix: GpsFixType::Fix3d,
        position_ned_m: Vector3::new(10.0, 20.0, -30.0),
        velocity_ned_m_s: Some(Vector3::new(1.0, 2.0, 0.1)),
    };
    let pvt = NavPvt::from_gps_fix(&fix, &home, 0, 40.0).unwrap().encode();
    bench_one::<ubx::Ubx>(c, "ubx_nav_pvt", &stream(pvt.as_bytes(), 100));

    let mut nmea = Vec::new();
    for m in nmea0183::sentences_from_fix(&fix, &home, 3600.0, 40.0).unwrap() {
        nmea.extend_from_slice(m.encode().unwrap().as_bytes());
    }
    bench_one::<nmea0183::Nmea>(c, "nmea_gga_rmc_vtg", &stream(&nmea, 100));

    let servo = ServoCommand::from_inputs(1, true, &Vector4::new(0.18, 0.0, 0.1, 0.3))
        .unwrap()
        .encode();
    bench_one::<avionics::Avionics>(c, "avionics_servo", &stream(servo.as_bytes(), 100));
}

criterion_group!(benches, decoders);
criterion_main!(benches);
