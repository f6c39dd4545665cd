//! PX4's per-step path (receive HIL_ACTUATOR_CONTROLS, step, send
//! HIL_SENSOR, HIL_GPS, HIL_STATE_QUATERNION) allocates nothing but the
//! flight summary's amortized growth (O(log n) over n steps): the server
//! run on this thread, counted per thread with a wrapping allocator, for
//! 400 and for 4000 steps from the same stand-in (on its own thread); the
//! difference (3600 steps) is at most 30 allocations.
#![allow(clippy::unwrap_used, clippy::expect_used)] // a failed unwrap is a failed test

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

use helicon_gcs::mavlink::dialects::common::{
    HIL_ACTUATOR_CONTROLS_DATA, HilActuatorControlsFlags, MavMessage, MavModeFlag,
};
use helicon_gcs::mavlink::{MavHeader, MavlinkReader, write_v2_msg};
use helicon_sim::closed_loop::prepare;
use helicon_sim::scenario::Scenario;
use helicon_sitl::px4::{BERGEN_TWIN_TOML, Px4Map, Px4Options, Px4Section, Px4Server};
use std::net::TcpStream;
use std::time::Duration;

fn allocations_for(steps: u64) -> usize {
    let s = Scenario::from_toml_str(
        "name = \"px4-alloc\"\npreset = \"physical\"\nduration_s = 600.0\n",
        "test",
    )
    .unwrap();
    let p = prepare(&s).unwrap();
    let section = Px4Section::from_toml_str(BERGEN_TWIN_TOML, "b.toml").unwrap();
    let map = Px4Map::new(section, p.model.params(), "b.toml").unwrap();
    let controls = map.controls_for(&map.outputs_for(&p.trim.u, 1.0));
    let server = Px4Server::bind("127.0.0.1:0").unwrap();
    let to = server.local_addr();
    let client = std::thread::spawn(move || {
        let mut stream = TcpStream::connect(to).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(20)))
            .unwrap();
        let mut reader = MavlinkReader::new(stream.try_clone().unwrap());
        let mut header = MavHeader::default();
        let msg = MavMessage::HIL_ACTUATOR_CONTROLS(HIL_ACTUATOR_CONTROLS_DATA {
            time_usec: 0,
            flags: HilActuatorControlsFlags::HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP,
            controls,
            mode: MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
        });
        // first contact: the actuator message itself (the sensors at t = 0 come first)
        for _ in 0..=steps {
            write_v2_msg(&mut stream, header, &msg).unwrap();
            header.sequence = header.sequence.wrapping_add(1);
            loop {
                let (_, m) = reader.read_any_message::<MavMessage>().unwrap();
                if matches!(m, MavMessage::HIL_SENSOR(_)) {
                    break;
                }
            }
        }
    });
    let options = Px4Options {
        max_steps: Some(steps),
        silence_timeout: Some(Duration::from_secs(20)),
        ..Px4Options::default()
    };
    let before = allocations();
    let r = server.run(&s, &p, &map, &options).unwrap();
    let n = allocations() - before;
    client.join().unwrap();
    assert_eq!(r.counts.steps, steps);
    n
}

#[test]
fn a_step_allocates_nothing_in_steady_state() {
    let short = allocations_for(400);
    let long = allocations_for(4000);
    eprintln!("allocations: 400 steps {short}, 4000 steps {long}");
    assert!(
        long.saturating_sub(short) <= 30,
        "{short} for 400 steps, {long} for 4000"
    );
}
