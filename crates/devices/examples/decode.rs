//! Decodes a capture of a device's serial line and prints one line per
//! message, then the decoder's statistics:
//!
//! ```sh
//! cargo run -p helicon-devices --example decode -- ubx capture.bin
//! ```
//! Protocols: `vn` (VN-100 binary), `vnymr` (VN-100 ASCII), `nmea`, `ubx`,
//! `avionics`.

use anyhow::{Context, bail};
use helicon_devices::framing::{DecoderStats, Protocol, StreamDecoder};
use helicon_devices::{avionics, nmea0183, ubx, vectornav};
use std::fmt::Debug;
use std::io::Read;
use std::path::Path;

fn run<P: Protocol>(path: &Path) -> anyhow::Result<DecoderStats>
where
    P::Message: Debug,
{
    let mut file =
        std::fs::File::open(path).with_context(|| format!("{}: cannot open", path.display()))?;
    let mut decoder = StreamDecoder::<P>::new();
    let mut buf = [0u8; 4096];
    loop {
        let n = file
            .read(&mut buf)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        if n == 0 {
            return Ok(decoder.stats());
        }
        for m in decoder.push(&buf[..n]) {
            println!("{m:?}");
        }
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [protocol, file] = args.as_slice() else {
        bail!("usage: decode <vn|vnymr|nmea|ubx|avionics> FILE");
    };
    let path = Path::new(file);
    let stats = match protocol.as_str() {
        "vn" => run::<vectornav::VnBinary>(path)?,
        "vnymr" => run::<vectornav::VnAscii>(path)?,
        "nmea" => run::<nmea0183::Nmea>(path)?,
        "ubx" => run::<ubx::Ubx>(path)?,
        "avionics" => run::<avionics::Avionics>(path)?,
        other => bail!("unknown protocol `{other}`: one of vn, vnymr, nmea, ubx, avionics"),
    };
    eprintln!("{stats:?}");
    Ok(())
}
