//! # helicon-gcs
//!
//! The thesis's Ground Station Server and Navigator (Figure 3.5) for today's
//! ground stations:
//!
//! - [`navigator`]: missions and modes → the references the LQI tracks
//!   (earth velocities and heading): takeoff, waypoint legs with speed and
//!   acceleration limits, hold, return, landing, guided targets, the
//!   link-loss failsafe. Allocation-free.
//! - [`fence`]: the geofence (radius and height about home, PX4's
//!   `GF_*` parameters): targets outside it refused, a breach acted on.
//! - [`geo`]: mission items (MAVLink `MISSION_ITEM_INT`) ↔ the navigator's
//!   local NED frame about home, through `helicon-devices`' WGS-84 geodesy.
//! - [`link`]: what crosses between the control task and the server thread
//!   (lock-free `rtrb` rings), and the vehicle-side half ([`link::Vehicle`]).
//! - [`modes`]: the navigator's modes as PX4's custom modes (what ground
//!   stations name, set and fly).
//! - [`params`]: the parameter table (typed, validated).
//! - [`rally`]: rally points, the safe landing places a return picks from
//!   (the nearest of home and them).
//! - [`server`]: the MAVLink 2 server (common dialect, UDP and TCP) on its own thread.
//! - [`config`]: the `[gcs]` section of the on-board configuration.
//! - [`client`]: the ground-station side (`helicon gcs`): the vehicles
//!   heard, and the command, mission and parameter microservices as state
//!   machines fed messages and time.
//! - [`wpl`]: mission files in the QGC WPL 110 format.

pub mod client;
pub mod config;
pub mod fence;
pub mod geo;
pub mod link;
pub mod mission_item;
pub mod modes;
pub mod navigator;
pub mod params;
pub mod rally;
pub mod server;
pub mod wpl;

pub use mavlink;
pub use navigator::{NavMode, Navigator, NavigatorConfig};
