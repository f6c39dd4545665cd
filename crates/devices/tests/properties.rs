//! Property tests of every decoder: random bytes never panic and never give
//! a non-finite value; every valid message round-trips through its encoder
//! and decoder, pushed in random chunks; a single flipped bit is always
//! rejected; garbage between frames never loses a frame.

use helicon_devices::framing::Protocol;
use helicon_devices::*;
use proptest::prelude::*;

/// Decodes `bytes` pushed in chunks of the given sizes (cycled).
fn decode_chunked<P: Protocol>(bytes: &[u8], chunks: &[usize]) -> (Vec<P::Message>, DecoderStats) {
    let mut d = StreamDecoder::<P>::new();
    let mut out = Vec::new();
    let mut rest = bytes;
    for &c in chunks.iter().cycle() {
        if rest.is_empty() {
            break;
        }
        let (head, tail) = rest.split_at(c.clamp(1, rest.len()));
        out.extend(d.push(head));
        rest = tail;
    }
    (out, d.stats())
}

fn f32_finite() -> impl Strategy<Value = f32> {
    prop::num::f32::NORMAL | prop::num::f32::ZERO | prop::num::f32::SUBNORMAL
}

fn arr3() -> impl Strategy<Value = [f32; 3]> {
    [f32_finite(), f32_finite(), f32_finite()]
}

fn vn_common() -> impl Strategy<Value = VnCommon> {
    (
        prop::option::of(any::<u64>()),
        prop::option::of(arr3()),
        prop::option::of([f32_finite(), f32_finite(), f32_finite(), f32_finite()]),
        prop::option::of(arr3()),
        prop::option::of(arr3()),
        prop::option::of((arr3(), f32_finite(), f32_finite())),
        prop::option::of(any::<u32>()),
    )
        .prop_filter("at least one field", |t| {
            t.0.is_some()
                || t.1.is_some()
                || t.2.is_some()
                || t.3.is_some()
                || t.4.is_some()
                || t.5.is_some()
                || t.6.is_some()
        })
        .prop_map(|(t, ypr, q, w, a, mp, s)| VnCommon {
            time_startup_ns: t,
            yaw_pitch_roll_deg: ypr,
            quaternion: q,
            angular_rate_rad_s: w,
            accel_m_s2: a,
            mag_pres: mp.map(|(m, t, p)| VnMagPres {
                mag_gauss: m,
                temperature_c: t,
                pressure_kpa: p,
            }),
            sync_in_count: s,
        })
}

/// Values on the printed grid of each `$VNYMR` field.
fn vn_ymr() -> impl Strategy<Value = VnYmr> {
    let grid = |scale: f64, max: i64| {
        prop::array::uniform3(-max..=max).prop_map(move |a| a.map(|k| k as f64 / scale))
    };
    (
        grid(1e3, 999_999),
        grid(1e4, 99_999),
        grid(1e3, 99_999),
        grid(1e6, 99_999_999),
    )
        .prop_map(|(y, m, a, g)| VnYmr {
            yaw_pitch_roll_deg: y,
            mag_gauss: m,
            accel_m_s2: a,
            angular_rate_rad_s: g,
        })
}

fn nav_pvt() -> impl Strategy<Value = NavPvt> {
    (
        (
            any::<u32>(),
            any::<u16>(),
            any::<[u8; 5]>(),
            any::<u8>(),
            0u8..=5,
            any::<u8>(),
            any::<u8>(),
        ),
        (
            any::<[i32; 4]>(),
            any::<[u32; 2]>(),
            any::<[i32; 3]>(),
            any::<[i32; 2]>(),
            any::<[u32; 2]>(),
            any::<u16>(),
        ),
    )
        .prop_map(
            |((itow, year, t, valid, fix_type, flags, num_sv), (pos, acc, vel, gh, sh, pdop))| {
                NavPvt {
                    itow_ms: itow,
                    year,
                    month: t[0],
                    day: t[1],
                    hour: t[2],
                    min: t[3],
                    sec: t[4],
                    valid,
                    fix_type,
                    flags,
                    num_sv,
                    lon_e7: pos[0],
                    lat_e7: pos[1],
                    height_mm: pos[2],
                    height_msl_mm: pos[3],
                    h_acc_mm: acc[0],
                    v_acc_mm: acc[1],
                    vel_ned_mm_s: vel,
                    g_speed_mm_s: gh[0],
                    head_mot_e5: gh[1],
                    s_acc_mm_s: sh[0],
                    head_acc_e5: sh[1],
                    pdop_e2: pdop,
                }
            },
        )
}

fn avionics_msg() -> impl Strategy<Value = AvionicsMessage> {
    prop_oneof![
        (any::<u8>(), any::<bool>(), any::<bool>(), any::<[i16; 4]>()).prop_map(
            |(seq, armed, throttle_hold, c)| {
                AvionicsMessage::Servo(ServoCommand {
                    seq,
                    armed,
                    throttle_hold,
                    servo_counts: c,
                })
            }
        ),
        (
            any::<u8>(),
            any::<bool>(),
            any::<bool>(),
            any::<[u16; 8]>(),
            any::<[i16; 4]>(),
            any::<u8>()
        )
            .prop_map(
                |(seq, autonomous, failsafe, ch, applied, last)| AvionicsMessage::Rc(RcInput {
                    seq,
                    autonomous,
                    failsafe,
                    channels_us: ch,
                    applied_counts: applied,
                    last_command_seq: last,
                })
            ),
    ]
}

/// GGA on the encoder's grid: 1e-5 arc-minute, 0.1 m, 0.01 s, 0.01 HDOP;
/// latitude and longitude together (the `nmea` crate refuses one alone).
fn gga() -> impl Strategy<Value = Gga> {
    (
        prop::option::of(0u64..8_640_000),
        prop::option::of((
            -540_000_000i64..=540_000_000,
            -1_080_000_000i64..=1_080_000_000,
        )),
        0u8..=8,
        prop::option::of(0u8..=99),
        prop::option::of(0u32..=9999),
        prop::option::of(-1000i32..=90_000),
        prop::option::of(-1200i32..=1200),
    )
        .prop_map(|(t, pos, quality, sats, hdop, alt, sep)| Gga {
            utc_time_s: t.map(|c| c as f64 / 100.0),
            latitude_deg: pos.map(|(m, _)| m as f64 / 6e6),
            longitude_deg: pos.map(|(_, m)| m as f64 / 6e6),
            quality,
            satellites: sats,
            hdop: hdop.map(|h| f64::from(h) / 100.0),
            altitude_msl_m: alt.map(|a| f64::from(a) / 10.0),
            geoid_separation_m: sep.map(|s| f64::from(s) / 10.0),
        })
}

/// RMC and VTG on the encoder's grid: 0.001 kn, 0.01°, 0.01 s.
fn rmc_vtg() -> impl Strategy<Value = (Rmc, Vtg)> {
    (
        prop::option::of(0u64..8_640_000),
        prop::option::of((1983i32..=2082, 1u8..=12, 1u8..=28)),
        any::<bool>(),
        prop::option::of((
            -540_000_000i64..=540_000_000,
            -1_080_000_000i64..=1_080_000_000,
        )),
        prop::option::of((0u32..999_999, 0u32..36_000)),
    )
        .prop_map(|(t, date, valid, pos, vel)| {
            let speed = vel.map(|(k, _)| f64::from(k) / 1000.0);
            let course = vel.map(|(_, c)| f64::from(c) / 100.0);
            (
                Rmc {
                    utc_time_s: t.map(|c| c as f64 / 100.0),
                    date,
                    valid,
                    latitude_deg: pos.map(|(m, _)| m as f64 / 6e6),
                    longitude_deg: pos.map(|(_, m)| m as f64 / 6e6),
                    speed_knots: speed,
                    course_true_deg: course,
                },
                Vtg {
                    course_true_deg: course,
                    speed_knots: speed,
                },
            )
        })
}

fn chunks() -> impl Strategy<Value = Vec<usize>> {
    prop::collection::vec(1usize..40, 1..6)
}

/// Every message from arbitrary bytes; none may panic.
fn decode_random(bytes: &[u8], chunks: &[usize]) {
    let (vn, s) = decode_chunked::<vectornav::VnBinary>(bytes, chunks);
    assert_eq!(s.bytes, bytes.len() as u64);
    for m in vn {
        if let Some(i) = m.imu_sample() {
            assert!(
                i.gyro_body_rad_s
                    .iter()
                    .chain(i.specific_force_body_m_s2.iter())
                    .all(|x| x.is_finite())
            );
        }
    }
    for m in decode_chunked::<vectornav::VnAscii>(bytes, chunks).0 {
        assert!(m.mag_gauss.iter().all(|x| x.is_finite()));
    }
    for m in decode_chunked::<nmea0183::Nmea>(bytes, chunks).0 {
        if let NmeaMessage::Gga(g) = m {
            assert!(g.latitude_deg.is_none_or(f64::is_finite));
        }
    }
    decode_chunked::<ubx::Ubx>(bytes, chunks);
    decode_chunked::<avionics::Avionics>(bytes, chunks);
}

/// Flips bit `bit` of `frame` and checks the decoder gives nothing.
fn flipped_is_rejected<P: Protocol>(frame: &[u8], bit: usize) -> Result<(), TestCaseError>
where
    P::Message: std::fmt::Debug,
{
    let mut bad = frame.to_vec();
    let i = bit % (8 * bad.len());
    bad[i / 8] ^= 1 << (i % 8);
    let (got, _) = decode_chunked::<P>(&bad, &[usize::MAX]);
    prop_assert!(got.is_empty(), "bit {} flipped still decoded: {:?}", i, got);
    Ok(())
}

/// `garbage frame garbage frame` decodes to exactly the two messages.
fn survives_garbage<P: Protocol>(
    frame: &[u8],
    g1: &[u8],
    g2: &[u8],
    want: &P::Message,
    ch: &[usize],
) -> Result<(), TestCaseError>
where
    P::Message: std::fmt::Debug + PartialEq,
{
    let mut bytes = g1.to_vec();
    bytes.extend_from_slice(frame);
    bytes.extend_from_slice(g2);
    bytes.extend_from_slice(frame);
    let (got, stats) = decode_chunked::<P>(&bytes, ch);
    prop_assert_eq!(got.len(), 2, "stats {:?}", stats);
    prop_assert_eq!(&got[0], want);
    prop_assert_eq!(&got[1], want);
    Ok(())
}

fn garbage() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(any::<u8>(), 0..300)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000), ch in chunks()) {
        decode_random(&bytes, &ch);
    }

    #[test]
    fn random_bytes_after_a_sync_never_panic(
        sync in prop::sample::select(vec![&b"\xFA\x01"[..], b"$", b"$VNYMR,", b"$GPGGA,", b"\xB5\x62\x01\x07", b"\xA5\x5A"]),
        bytes in prop::collection::vec(any::<u8>(), 0..400),
        ch in chunks(),
    ) {
        let mut all = sync.to_vec();
        all.extend(bytes);
        decode_random(&all, &ch);
    }

    /// Sentences with a valid checksum but hostile fields reach the `nmea`
    /// crate's parser and `$VNYMR`'s: no panic, no non-finite value.
    #[test]
    fn hostile_fields_with_valid_checksums_never_panic(
        head in prop::sample::select(vec!["GPGGA,", "GNRMC,", "GPVTG,", "VNYMR,", "GPGGA,123519,"]),
        body in "[-+,.0-9NSEWAVMTKDe]{0,70}",
    ) {
        let text = format!("{head}{body}");
        let cs = text.bytes().fold(0u8, |a, b| a ^ b);
        let line = format!("${text}*{cs:02X}\r\n");
        for m in decode_chunked::<nmea0183::Nmea>(line.as_bytes(), &[7]).0 {
            match m {
                NmeaMessage::Gga(g) => prop_assert!(g.altitude_msl_m.is_none_or(f64::is_finite)),
                NmeaMessage::Rmc(r) => prop_assert!(r.speed_knots.is_none_or(f64::is_finite)),
                NmeaMessage::Vtg(v) => prop_assert!(v.course_true_deg.is_none_or(f64::is_finite)),
            }
        }
        for m in decode_chunked::<vectornav::VnAscii>(line.as_bytes(), &[7]).0 {
            prop_assert!(m.angular_rate_rad_s.iter().all(|x| x.is_finite()));
        }
    }

    #[test]
    fn vn_binary_round_trips(m in vn_common(), ch in chunks(), bit in any::<usize>(), g1 in garbage(), g2 in garbage()) {
        let f = m.encode().unwrap();
        let (got, _) = decode_chunked::<vectornav::VnBinary>(f.as_bytes(), &ch);
        prop_assert_eq!(got, vec![m]);
        flipped_is_rejected::<vectornav::VnBinary>(f.as_bytes(), bit)?;
        survives_garbage::<vectornav::VnBinary>(f.as_bytes(), &g1, &g2, &m, &ch)?;
    }

    #[test]
    fn vn_ascii_round_trips(m in vn_ymr(), ch in chunks(), bit in any::<usize>(), g1 in garbage(), g2 in garbage()) {
        let f = m.encode().unwrap();
        let (got, _) = decode_chunked::<vectornav::VnAscii>(f.as_bytes(), &ch);
        prop_assert_eq!(got, vec![m]);
        flipped_is_rejected::<vectornav::VnAscii>(f.as_bytes(), bit)?;
        survives_garbage::<vectornav::VnAscii>(f.as_bytes(), &g1, &g2, &m, &ch)?;
    }

    #[test]
    fn nav_pvt_round_trips(m in nav_pvt(), ch in chunks(), bit in any::<usize>(), g1 in garbage(), g2 in garbage()) {
        let f = m.encode();
        let (got, _) = decode_chunked::<ubx::Ubx>(f.as_bytes(), &ch);
        prop_assert_eq!(got, vec![m]);
        flipped_is_rejected::<ubx::Ubx>(f.as_bytes(), bit)?;
        survives_garbage::<ubx::Ubx>(f.as_bytes(), &g1, &g2, &m, &ch)?;
    }

    #[test]
    fn avionics_round_trips(m in avionics_msg(), ch in chunks(), bit in any::<usize>(), g1 in garbage(), g2 in garbage()) {
        let f = m.encode();
        let (got, _) = decode_chunked::<avionics::Avionics>(f.as_bytes(), &ch);
        prop_assert_eq!(got, vec![m]);
        flipped_is_rejected::<avionics::Avionics>(f.as_bytes(), bit)?;
        survives_garbage::<avionics::Avionics>(f.as_bytes(), &g1, &g2, &m, &ch)?;
    }

    #[test]
    fn nmea_gga_round_trips(m in gga(), ch in chunks(), bit in any::<usize>(), g1 in garbage(), g2 in garbage()) {
        let f = NmeaMessage::Gga(m).encode().unwrap();
        let (got, stats) = decode_chunked::<nmea0183::Nmea>(f.as_bytes(), &ch);
        prop_assert_eq!(got.len(), 1, "{:?} {:?}", std::str::from_utf8(f.as_bytes()), stats);
        let NmeaMessage::Gga(g) = got[0] else { return Err(TestCaseError::fail("not GGA")) };
        // the nmea crate parses altitude, separation and HDOP as f32
        let close = |a: Option<f64>, b: Option<f64>, tol: f64| match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() <= tol,
            (a, b) => a.is_none() && b.is_none(),
        };
        prop_assert!(close(g.latitude_deg, m.latitude_deg, 1e-12) && close(g.longitude_deg, m.longitude_deg, 1e-12));
        prop_assert!(close(g.utc_time_s, m.utc_time_s, 1e-6));
        prop_assert!(close(g.altitude_msl_m, m.altitude_msl_m, 1e-3) && close(g.geoid_separation_m, m.geoid_separation_m, 1e-4));
        prop_assert!(close(g.hdop, m.hdop, 1e-5));
        prop_assert_eq!((g.quality, g.satellites), (m.quality, m.satellites));
        // re-encoding what was decoded gives the same bytes
        let again = NmeaMessage::Gga(g).encode().unwrap();
        prop_assert_eq!(again.as_bytes(), f.as_bytes());
        flipped_is_rejected::<nmea0183::Nmea>(f.as_bytes(), bit)?;
        survives_garbage::<nmea0183::Nmea>(f.as_bytes(), &g1, &g2, &got[0], &ch)?;
    }

    #[test]
    fn nmea_rmc_vtg_round_trip(m in rmc_vtg(), ch in chunks(), bit in any::<usize>()) {
        for msg in [NmeaMessage::Rmc(m.0), NmeaMessage::Vtg(m.1)] {
            let f = msg.encode().unwrap();
            let (got, stats) = decode_chunked::<nmea0183::Nmea>(f.as_bytes(), &ch);
            prop_assert_eq!(got.len(), 1, "{:?} {:?}", std::str::from_utf8(f.as_bytes()), stats);
            match (got[0], msg) {
                // speed and course pass through the nmea crate's f32; RMC
                // re-encodes to the same bytes
                (NmeaMessage::Rmc(_), _) => {
                    let again = got[0].encode().unwrap();
                    prop_assert_eq!(again.as_bytes(), f.as_bytes());
                }
                // VTG's km/h field is derived from the (f32) knots, so
                // compare the fields: within f32 rounding (2^-24 relative)
                (NmeaMessage::Vtg(g), NmeaMessage::Vtg(w)) => {
                    let close = |a: Option<f64>, b: Option<f64>| match (a, b) {
                        (Some(a), Some(b)) => (a - b).abs() <= 1e-7 * b.abs().max(1.0),
                        (a, b) => a.is_none() && b.is_none(),
                    };
                    prop_assert!(close(g.speed_knots, w.speed_knots) && close(g.course_true_deg, w.course_true_deg));
                }
                (g, w) => return Err(TestCaseError::fail(format!("{g:?} from {w:?}"))),
            }
            flipped_is_rejected::<nmea0183::Nmea>(f.as_bytes(), bit)?;
        }
    }
}
