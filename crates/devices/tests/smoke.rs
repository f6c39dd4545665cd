//! First round trips of every protocol (the property tests go further).

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::*;
use nalgebra::{Vector3, Vector4};

#[test]
fn every_protocol_round_trips_once() {
    let imu = ImuSample {
        specific_force_body_m_s2: Vector3::new(0.1, -0.2, -9.82),
        gyro_body_rad_s: Vector3::new(0.01, 0.02, -0.03),
    };
    let vn = VnCommon::from_samples(1.25, &imu, Some(&Vector3::new(0.153, 0.008, -0.438))).unwrap();
    let f = vn.encode().unwrap();
    let got: Vec<_> = VnBinaryDecoder::new().push(f.as_bytes()).collect();
    assert_eq!(got, vec![vn]);

    let home = LocalNed::new(Geodetic::new(57.0, 9.9, 30.0).unwrap());
    let fix = GpsFix {
        epoch_s: 3.0,
        fix: GpsFixType::Fix3d,
        position_ned_m: Vector3::new(10.0, -5.0, -20.0),
        velocity_ned_m_s: Some(Vector3::new(1.0, 2.0, -0.5)),
    };
    let pvt = NavPvt::from_gps_fix(&fix, &home, 1000, 40.0).unwrap();
    let got: Vec<_> = UbxDecoder::new().push(pvt.encode().as_bytes()).collect();
    assert_eq!(got, vec![pvt]);
    let back = got[0].to_gps_fix(&home, 3.0);
    assert!((back.position_ned_m - fix.position_ned_m).norm() < 0.02);

    let mut dec = NmeaDecoder::new();
    for m in nmea0183::sentences_from_fix(&fix, &home, 43_200.5, 40.0).unwrap() {
        let f = m.encode().unwrap();
        let got: Vec<_> = dec.push(f.as_bytes()).collect();
        assert_eq!(got.len(), 1, "{:?}", std::str::from_utf8(f.as_bytes()));
        if let NmeaMessage::Gga(g) = got[0] {
            let p = g.to_gps_fix(&home, 3.0).position_ned_m;
            assert!((p - fix.position_ned_m).norm() < 0.1, "{p}");
        }
    }

    let cmd = ServoCommand::from_inputs(3, true, &Vector4::new(0.185, -0.1, 0.2, 0.3)).unwrap();
    let got: Vec<_> = AvionicsDecoder::new()
        .push(cmd.encode().as_bytes())
        .collect();
    assert_eq!(got, vec![AvionicsMessage::Servo(cmd)]);
}
