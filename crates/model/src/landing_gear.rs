//! The optional landing gear: the skids as four contact points on a flat
//! (possibly sloped) ground, in the ground-reaction form of JSBSim's
//! `FGLGear` (penetration spring and damper, friction bounded by μ·N).
//!
//! For each contact point at body position `r_b` (the skid ends, from
//! `[landing_gear]`), with the CM at `p` (NED) and the rotation R = R_nb:
//!
//! ```text
//! p_i = p + R r_b,   v_i = R (v_b + ω × r_b)          (point position, inertial velocity)
//! δ   = −n·(p_i − p0)                                  (penetration; n the ground's up normal)
//! N   = max(0, k δ + c δ̇),   δ̇ = −n·v_i               (normal force, never pulling)
//! d   = tangential part of (p_i − a_i)                 (offset from the point's anchor a_i)
//! F_t = −k d − c v_t,   |F_t| ≤ μ(|v_t|) N             (friction: spring-damper to the anchor, bounded)
//! μ(v) = μd + (μs − μd) exp(−v / v_s)                  (smooth static-to-dynamic transition)
//! ```
//!
//! The anchors are the friction's memory (an elasto-plastic, "bristle"
//! model): where each point stuck. While |k d| ≤ μN the anchor stays and a
//! point under a load below μs·N holds still apart from the spring's fixed
//! elastic offset — it cannot creep, as a velocity-only friction law
//! (F = −μN·v/v_s near v = 0) does at any load. When the spring force
//! exceeds the bound the anchor is dragged along ([`Anchors::update`],
//! after each integration step: the anchors are held, like the inputs,
//! within a step). A point off the ground has no anchor; it takes the
//! place where it touches down.
//!
//! The forces act at the contact points; their sum and their torque about
//! the CM enter the rigid body (8.3)/(8.5). The ground plane passes through
//! `(0, 0, ground_down_m)` NED and rises toward north by `ground_slope_rad`.

use crate::params::LandingGear;
use crate::state::{State, ix};
use helicon_core::frames::EulerTrig;
use nalgebra::{Matrix3, Vector3};

/// Number of contact points: the two ends of each skid.
pub const N_CONTACT: usize = 4;

/// Names of the contact points, in order.
pub const CONTACT_NAMES: [&str; N_CONTACT] =
    ["front_left", "front_right", "rear_left", "rear_right"];

/// The ground plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundPlane {
    /// Unit normal pointing out of the ground (up), NED.
    pub up_ned: Vector3<f64>,
    /// A point of the plane, NED (m).
    pub point_ned_m: Vector3<f64>,
}

impl GroundPlane {
    /// The plane of `[landing_gear]`.
    pub fn new(gear: &LandingGear) -> GroundPlane {
        let (s, c) = gear.ground_slope_rad.sin_cos();
        GroundPlane {
            up_ned: Vector3::new(-s, 0.0, -c),
            point_ned_m: Vector3::new(0.0, 0.0, gear.ground_down_m),
        }
    }

    /// Height of `p_ned_m` above the plane, along its normal (m).
    #[inline]
    pub fn height_m(&self, p_ned_m: &Vector3<f64>) -> f64 {
        self.up_ned.dot(&(p_ned_m - self.point_ned_m))
    }

    /// The foot of `p_ned_m` on the plane.
    #[inline]
    pub fn project(&self, p_ned_m: &Vector3<f64>) -> Vector3<f64> {
        p_ned_m - self.up_ned * self.height_m(p_ned_m)
    }
}

/// The contact points in body axes (m), in [`CONTACT_NAMES`] order.
pub fn contact_points_body_m(gear: &LandingGear) -> [Vector3<f64>; N_CONTACT] {
    let (xf, xr, y, z) = (
        gear.contact_x_front_m,
        gear.contact_x_rear_m,
        gear.contact_y_half_m,
        gear.contact_z_m,
    );
    [
        Vector3::new(xf, -y, z),
        Vector3::new(xf, y, z),
        Vector3::new(xr, -y, z),
        Vector3::new(xr, y, z),
    ]
}

/// The friction anchors: where each contact point stuck (NED, on the
/// plane), `None` for a point off the ground.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Anchors {
    /// One anchor per contact point.
    pub points_ned_m: [Option<Vector3<f64>>; N_CONTACT],
}

/// The gear's forces and torques and what each point sees.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactWrench {
    /// Total contact force in body axes (N).
    pub force_body_n: Vector3<f64>,
    /// Total contact torque about the CM in body axes (N·m).
    pub torque_body_nm: Vector3<f64>,
    /// Normal force of each point (N, ≥ 0).
    pub normal_n: [f64; N_CONTACT],
    /// Friction force magnitude of each point (N, ≤ μs·N).
    pub friction_n: [f64; N_CONTACT],
    /// Penetration of each point (m; negative: above the ground).
    pub penetration_m: [f64; N_CONTACT],
}

impl ContactWrench {
    /// The sum of the normal forces (N).
    pub fn total_normal_n(&self) -> f64 {
        self.normal_n.iter().sum()
    }

    /// Whether any point carries load.
    pub fn on_ground(&self) -> bool {
        self.normal_n.iter().any(|n| *n > 0.0)
    }
}

/// One point's kinematics: NED position and inertial velocity.
#[inline]
fn point_motion(
    r_b: &Vector3<f64>,
    pos: &Vector3<f64>,
    ned_from_body: &Matrix3<f64>,
    v_b: &Vector3<f64>,
    omega: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    (
        pos + ned_from_body * r_b,
        ned_from_body * (v_b + omega.cross(r_b)),
    )
}

/// μ at sliding speed `v_m_s`: μd + (μs − μd)·exp(−v / v_s).
#[inline]
pub fn friction_coefficient(gear: &LandingGear, v_m_s: f64) -> f64 {
    gear.friction_dynamic
        + (gear.friction_static - gear.friction_dynamic) * (-v_m_s / gear.stribeck_speed_m_s).exp()
}

/// The state's body kinematics: position, rotation, body velocity, rates.
fn kinematics(x: &State) -> (Vector3<f64>, Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
    let pos = Vector3::new(x[ix::X], x[ix::Y], x[ix::Z]);
    let r = EulerTrig::new(x[ix::PHI], x[ix::THETA], x[ix::PSI]).ned_from_body();
    let v = Vector3::new(x[ix::U], x[ix::V], x[ix::W]);
    let w = Vector3::new(x[ix::P], x[ix::Q], x[ix::R]);
    (pos, r, v, w)
}

/// The contact wrench at state `x` with the friction `anchors` held.
/// Allocation-free.
pub fn contact_wrench(
    gear: &LandingGear,
    plane: &GroundPlane,
    points_body_m: &[Vector3<f64>; N_CONTACT],
    x: &State,
    anchors: &Anchors,
) -> ContactWrench {
    let (pos, ned_from_body, v_b, omega) = kinematics(x);
    let n = plane.up_ned;
    let mut w = ContactWrench::default();
    let mut force_ned_total = Vector3::zeros();
    let mut torque_body = Vector3::zeros();
    for (i, r_b) in points_body_m.iter().enumerate() {
        let (p, v) = point_motion(r_b, &pos, &ned_from_body, &v_b, &omega);
        let depth = -plane.height_m(&p);
        w.penetration_m[i] = depth;
        if depth <= 0.0 {
            continue;
        }
        let depth_rate = -n.dot(&v);
        let normal = (gear.stiffness_n_m * depth + gear.damping_n_s_m * depth_rate).max(0.0);
        if normal == 0.0 {
            continue;
        }
        let v_t = v - n * n.dot(&v);
        let offset = match anchors.points_ned_m[i] {
            Some(a) => {
                let d = p - a;
                d - n * n.dot(&d)
            }
            None => Vector3::zeros(),
        };
        let mut f_t = -offset * gear.stiffness_n_m - v_t * gear.damping_n_s_m;
        let limit = friction_coefficient(gear, v_t.norm()) * normal;
        let f_t_norm = f_t.norm();
        if f_t_norm > limit {
            f_t *= limit / f_t_norm;
        }
        w.normal_n[i] = normal;
        w.friction_n[i] = f_t.norm();
        let f_ned = n * normal + f_t;
        force_ned_total += f_ned;
        let f_body = ned_from_body.transpose() * f_ned;
        torque_body += r_b.cross(&f_body);
    }
    w.force_body_n = ned_from_body.transpose() * force_ned_total;
    w.torque_body_nm = torque_body;
    w
}

impl Anchors {
    /// After an integration step ending at `x`: a point off the ground
    /// loses its anchor, a point touching down takes its foot on the plane
    /// as anchor, and a point whose spring pulls harder than μ·N (its
    /// friction bound) has its anchor dragged to where the spring force
    /// equals the bound (it slides).
    pub fn update(
        &mut self,
        gear: &LandingGear,
        plane: &GroundPlane,
        points_body_m: &[Vector3<f64>; N_CONTACT],
        x: &State,
    ) {
        let (pos, ned_from_body, v_b, omega) = kinematics(x);
        let n = plane.up_ned;
        for (i, r_b) in points_body_m.iter().enumerate() {
            let (p, v) = point_motion(r_b, &pos, &ned_from_body, &v_b, &omega);
            let depth = -plane.height_m(&p);
            let normal = if depth > 0.0 {
                (gear.stiffness_n_m * depth - gear.damping_n_s_m * n.dot(&v)).max(0.0)
            } else {
                0.0
            };
            if normal == 0.0 {
                self.points_ned_m[i] = None;
                continue;
            }
            let foot = plane.project(&p);
            let Some(a) = self.points_ned_m[i] else {
                self.points_ned_m[i] = Some(foot);
                continue;
            };
            let d = foot - plane.project(&a);
            let spring = gear.stiffness_n_m * d.norm();
            let v_t = v - n * n.dot(&v);
            let limit = friction_coefficient(gear, v_t.norm()) * normal;
            self.points_ned_m[i] = Some(if spring > limit {
                foot - d * (limit / spring)
            } else {
                a
            });
        }
    }
}

/// The CM height above the ground at which the helicopter, level on the
/// plane (attitude following the slope), rests with each point carrying
/// `m g cos(slope) / 4` (the static compression `δ = m g cos(slope) / (4 k)`):
/// `contact_z − δ` (m). Exact for contact points symmetric about the CM.
pub fn rest_height_m(gear: &LandingGear, mass_kg: f64, g_m_s2: f64) -> f64 {
    gear.contact_z_m - static_compression_m(gear, mass_kg, g_m_s2)
}

/// The static compression of each point at rest, `m g cos(slope) / (4 k)` (m).
pub fn static_compression_m(gear: &LandingGear, mass_kg: f64, g_m_s2: f64) -> f64 {
    mass_kg * g_m_s2 * gear.ground_slope_rad.cos() / (N_CONTACT as f64 * gear.stiffness_n_m)
}

/// The lowest point's height above the plane at state `x` (m): the gear's
/// clearance (negative: in contact).
pub fn clearance_m(gear: &LandingGear, x: &State) -> f64 {
    let plane = GroundPlane::new(gear);
    let (pos, ned_from_body, _, _) = kinematics(x);
    contact_points_body_m(gear)
        .iter()
        .map(|r_b| plane.height_m(&(pos + ned_from_body * r_b)))
        .fold(f64::INFINITY, f64::min)
}

/// The state resting on the ground: the CM above the point `(north, east)`
/// at the rest height, the attitude following the slope (pitch = slope,
/// heading 0 — nose up the slope — unless `yaw_rad`), at rest. The other
/// states (flapping, servos) are taken from `x`.
pub fn resting_state(gear: &LandingGear, mass_kg: f64, g_m_s2: f64, x: &State) -> State {
    let plane = GroundPlane::new(gear);
    let mut s = *x;
    for i in [ix::U, ix::V, ix::W, ix::P, ix::Q, ix::R, ix::PHI] {
        s[i] = 0.0;
    }
    s[ix::THETA] = gear.ground_slope_rad;
    s[ix::PSI] = 0.0;
    let foot = plane.project(&Vector3::new(x[ix::X], x[ix::Y], 0.0));
    let ned_from_body = EulerTrig::new(0.0, s[ix::THETA], 0.0).ned_from_body();
    // CM = foot + up·(rest height) shifted so the skids' centre is under it
    let centre_b = Vector3::new(
        0.5 * (gear.contact_x_front_m + gear.contact_x_rear_m),
        0.0,
        0.0,
    );
    let cm = foot + plane.up_ned * rest_height_m(gear, mass_kg, g_m_s2) - ned_from_body * centre_b;
    s[ix::X] = cm.x;
    s[ix::Y] = cm.y;
    s[ix::Z] = cm.z;
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    #[test]
    fn flat_plane_height_is_minus_down() {
        let mut p = Params::bergen_twin().landing_gear;
        p.ground_down_m = 2.0;
        let g = GroundPlane::new(&p);
        assert_eq!(g.height_m(&Vector3::new(5.0, -3.0, 0.5)), 1.5);
        p.ground_slope_rad = 0.3;
        let g = GroundPlane::new(&p);
        // a point 1 m north on the level of the origin's ground is under the rising plane
        let h = g.height_m(&Vector3::new(1.0, 0.0, 2.0));
        assert!((h + 0.3f64.sin()).abs() < 1e-15);
    }

    #[test]
    fn friction_coefficient_goes_from_static_to_dynamic() {
        let p = Params::bergen_twin().landing_gear;
        assert_eq!(friction_coefficient(&p, 0.0), p.friction_static);
        let far = friction_coefficient(&p, 100.0 * p.stribeck_speed_m_s);
        assert!((far - p.friction_dynamic).abs() < 1e-12);
    }
}
