//! The checksums of the protocols, each as its manual defines it.

use crc::{CRC_16_IBM_3740, CRC_16_XMODEM, Crc};

/// VectorNav's "16-bit CRC" (VN-100 User Manual, section "Checksum / CRC"):
/// CRC-16-CCITT, polynomial 0x1021, initial value 0, no reflection, no final
/// XOR — the catalogue's CRC-16/XMODEM. Running it over a whole packet after
/// the sync byte, CRC included (big-endian), gives 0.
pub const VECTORNAV_CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_XMODEM);

/// The avionics link's CRC: CRC-16/CCITT-FALSE (catalogue name
/// CRC-16/IBM-3740: polynomial 0x1021, initial value 0xFFFF, no reflection),
/// chosen over XMODEM so that leading zero bytes change it.
pub const AVIONICS_CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_3740);

/// The 8-bit XOR checksum of NMEA 0183 and VectorNav ASCII sentences: XOR of
/// every byte between `$` and `*` (exclusive).
pub fn xor8(body: &[u8]) -> u8 {
    body.iter().fold(0, |acc, b| acc ^ b)
}

/// The UBX checksum (u-blox M8 Receiver Description, "UBX Checksum"): the
/// 8-bit Fletcher algorithm over class, id, length and payload; returns
/// `(CK_A, CK_B)`.
pub fn ubx_fletcher(data: &[u8]) -> (u8, u8) {
    data.iter().fold((0u8, 0u8), |(a, b), &x| {
        let a = a.wrapping_add(x);
        (a, b.wrapping_add(a))
    })
}

/// Value of an upper-case ASCII hexadecimal digit, the form NMEA 0183 and
/// VectorNav write checksums in. Lower case is refused: accepting it would
/// let a flipped bit 5 (`B` ↔ `b`) pass unnoticed.
pub(crate) fn hex_value(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_check_values() {
        // The catalogue's check value: the CRC of ASCII "123456789".
        assert_eq!(VECTORNAV_CRC.checksum(b"123456789"), 0x31C3);
        assert_eq!(AVIONICS_CRC.checksum(b"123456789"), 0x29B1);
    }

    #[test]
    fn vectornav_reference_algorithm() {
        // The byte-wise C routine printed in the VN-100 manual, transcribed.
        fn manual(data: &[u8]) -> u16 {
            let mut crc: u16 = 0;
            for &d in data {
                crc = crc.rotate_left(8); // the manual: (crc >> 8) | (crc << 8)
                crc ^= u16::from(d);
                crc ^= (crc & 0xff) >> 4;
                crc ^= crc << 12;
                crc ^= (crc & 0x00ff) << 5;
            }
            crc
        }
        for data in [&b""[..], b"\x01", b"\x01\x08\x01\xff\x00\x10", b"123456789"] {
            assert_eq!(manual(data), VECTORNAV_CRC.checksum(data));
        }
    }
}
