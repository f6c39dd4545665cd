#!/usr/bin/env python3
"""Reference frames and coordinates for crates/devices, from implementations
independent of the Rust code:

- UBX NAV-PVT frames written by pyubx2 from random field values;
- VN-100 binary Common-group packets assembled with struct from the manual's
  layout, CRC by binascii.crc_hqx (CRC-16-CCITT, initial value 0);
- avionics frames assembled from the layout documented in docs/devices.md,
  CRC by binascii.crc_hqx with initial value 0xFFFF (CRC-16/CCITT-FALSE);
- WGS-84 geodetic <-> local NED by pymap3d (geodetic2ned, ned2geodetic).

Usage: python3 -m venv /tmp/v && /tmp/v/bin/pip install pyubx2 pymap3d &&
       /tmp/v/bin/python tools/gen_devices_fixtures.py
Writes crates/devices/tests/fixtures/devices_reference.json.
"""
import binascii
import json
import random
import struct
from pathlib import Path

import pymap3d
from pyubx2 import GET, UBXMessage, UBXReader

rng = random.Random(20261130)
OUT = Path(__file__).resolve().parent.parent / "crates/devices/tests/fixtures/devices_reference.json"


def navpvt_cases(n=8):
    cases = []
    while len(cases) < n:
        raw = dict(
            itow_ms=rng.randrange(0, 604_800_000),
            year=rng.randrange(2000, 2100), month=rng.randrange(1, 13), day=rng.randrange(1, 29),
            hour=rng.randrange(0, 24), min=rng.randrange(0, 60), sec=rng.randrange(0, 60),
            fix_type=rng.choice([0, 2, 3, 4]), gnss_fix_ok=rng.randrange(0, 2),
            num_sv=rng.randrange(0, 40),
            lon_e7=rng.randrange(-1_800_000_000, 1_800_000_001),
            lat_e7=rng.randrange(-900_000_000, 900_000_001),
            height_mm=rng.randrange(-100_000, 9_000_000), height_msl_mm=rng.randrange(-100_000, 9_000_000),
            h_acc_mm=rng.randrange(0, 100_000), v_acc_mm=rng.randrange(0, 100_000),
            vel_ned_mm_s=[rng.randrange(-100_000, 100_001) for _ in range(3)],
            g_speed_mm_s=rng.randrange(0, 100_000), head_mot_e5=rng.randrange(0, 36_000_000),
            s_acc_mm_s=rng.randrange(0, 10_000), head_acc_e5=rng.randrange(0, 18_000_000),
            pdop_e2=rng.randrange(0, 9999),
        )
        msg = UBXMessage(
            "NAV", "NAV-PVT", GET, iTOW=raw["itow_ms"], year=raw["year"], month=raw["month"],
            day=raw["day"], hour=raw["hour"], min=raw["min"], second=raw["sec"],
            validDate=1, validTime=1, fullyResolved=1, fixType=raw["fix_type"],
            gnssFixOk=raw["gnss_fix_ok"], numSV=raw["num_sv"],
            lon=raw["lon_e7"] * 1e-7, lat=raw["lat_e7"] * 1e-7, height=raw["height_mm"],
            hMSL=raw["height_msl_mm"], hAcc=raw["h_acc_mm"], vAcc=raw["v_acc_mm"],
            velN=raw["vel_ned_mm_s"][0], velE=raw["vel_ned_mm_s"][1], velD=raw["vel_ned_mm_s"][2],
            gSpeed=raw["g_speed_mm_s"], headMot=raw["head_mot_e5"] * 1e-5, sAcc=raw["s_acc_mm_s"],
            headAcc=raw["head_acc_e5"] * 1e-5, pDOP=raw["pdop_e2"] * 1e-2,
        )
        frame = msg.serialize()
        p = frame[6:-2]
        # keep only cases pyubx2 wrote exactly (its scaled floats can round a count away)
        got = struct.unpack_from("<iiii", p, 24)
        if got != (raw["lon_e7"], raw["lat_e7"], raw["height_mm"], raw["height_msl_mm"]):
            continue
        head_mot, _, head_acc, pdop = struct.unpack_from("<iIIH", p, 64)
        if (head_mot, head_acc, pdop) != (raw["head_mot_e5"], raw["head_acc_e5"], raw["pdop_e2"]):
            continue
        parsed = UBXReader.parse(frame)
        assert parsed.numSV == raw["num_sv"]
        raw["valid"] = p[11]
        raw["flags"] = p[21]
        raw["hex"] = frame.hex()
        cases.append(raw)
    return cases


VN_SIZES = [8, 8, 8, 12, 16, 12, 24, 12, 12, 24, 20, 28, 2, 4, 8]


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def vn_cases(n=6):
    cases = []
    for k in range(n):
        c = dict(
            time_startup_ns=rng.randrange(0, 2**63),
            yaw_pitch_roll_deg=[f32(rng.uniform(-180, 180)) for _ in range(3)] if k % 2 else None,
            angular_rate_rad_s=[f32(rng.gauss(0, 1)) for _ in range(3)],
            accel_m_s2=[f32(rng.gauss(0, 5)) for _ in range(3)],
            mag_pres=[f32(rng.gauss(0, 0.4)) for _ in range(3)] + [f32(rng.uniform(-20, 60)), f32(rng.uniform(60, 110))]
            if k % 3 != 2 else None,
        )
        mask = 1 | (1 << 5) | (1 << 8)
        payload = struct.pack("<Q", c["time_startup_ns"])
        if c["yaw_pitch_roll_deg"] is not None:
            mask |= 1 << 3
            payload += struct.pack("<3f", *c["yaw_pitch_roll_deg"])
        payload += struct.pack("<3f", *c["angular_rate_rad_s"]) + struct.pack("<3f", *c["accel_m_s2"])
        if c["mag_pres"] is not None:
            mask |= 1 << 10
            payload += struct.pack("<5f", *c["mag_pres"])
        assert len(payload) == sum(s for b, s in enumerate(VN_SIZES) if mask >> b & 1)
        body = bytes([0x01]) + struct.pack("<H", mask) + payload
        crc = binascii.crc_hqx(body, 0)
        frame = bytes([0xFA]) + body + struct.pack(">H", crc)
        assert binascii.crc_hqx(frame[1:], 0) == 0
        c["hex"] = frame.hex()
        cases.append(c)
    return cases


def avionics_frame(kind, seq, payload):
    body = bytes([len(payload), kind, seq]) + payload
    return bytes([0xA5, 0x5A]) + body + struct.pack("<H", binascii.crc_hqx(body, 0xFFFF))


def avionics_cases():
    cases = []
    for seq in (0, 1, 200, 255):
        armed = seq % 2
        servo = [rng.randrange(-32768, 32768) for _ in range(4)]
        f = avionics_frame(0x01, seq, struct.pack("<B4h", armed, *servo))
        cases.append(dict(kind="servo", seq=seq, armed=bool(armed), servo_counts=servo, hex=f.hex()))
        auto, fs = seq % 2, (seq // 2) % 2
        ch = [rng.randrange(800, 2200) for _ in range(8)]
        applied = [rng.randrange(-32768, 32768) for _ in range(4)]
        last = rng.randrange(0, 256)
        f = avionics_frame(0x02, seq, struct.pack("<B8H4hB", auto | fs << 1, *ch, *applied, last))
        cases.append(dict(kind="rc", seq=seq, autonomous=bool(auto), failsafe=bool(fs), channels_us=ch,
                          applied_counts=applied, last_command_seq=last, hex=f.hex()))
    return cases


def geodetic_cases():
    homes = [(57.0147, 9.9859, 30.0), (0.0, 0.0, 0.0), (-33.9, 151.2, 50.0), (78.2, 15.6, 10.0),
             (47.2852, 8.5653, 499.6 + 48.0)]
    out = []
    for lat0, lon0, h0 in homes:
        for _ in range(5):
            lat = lat0 + rng.uniform(-0.05, 0.05)
            lon = lon0 + rng.uniform(-0.05, 0.05)
            h = h0 + rng.uniform(-100, 2000)
            n, e, d = pymap3d.geodetic2ned(lat, lon, h, lat0, lon0, h0)
            ned = [rng.uniform(-5000, 5000), rng.uniform(-5000, 5000), rng.uniform(-2000, 100)]
            lat2, lon2, h2 = pymap3d.ned2geodetic(*ned, lat0, lon0, h0)
            out.append(dict(home=[lat0, lon0, h0], point=[lat, lon, h], ned_m=[n, e, d],
                            ned_in_m=ned, geodetic_out=[lat2, lon2, h2]))
    return out


doc = dict(
    generator="tools/gen_devices_fixtures.py (pyubx2, pymap3d, binascii.crc_hqx)",
    navpvt=navpvt_cases(), vn_binary=vn_cases(), avionics=avionics_cases(), geodetic=geodetic_cases(),
)
OUT.write_text(json.dumps(doc, indent=1) + "\n")
print("wrote", OUT)
