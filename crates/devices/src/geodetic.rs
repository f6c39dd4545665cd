//! WGS-84 geodetic coordinates and the local NED frame about a home position.
//!
//! Closed forms (as in the *NIMA TR8350.2* WGS-84 definition and any geodesy
//! text): geodetic → ECEF with the prime-vertical radius
//! `N = a / √(1 − e² sin²φ)`; ECEF → NED by the rotation of the home
//! position's latitude and longitude; ECEF → geodetic by Heikkinen's exact
//! closed form (no iteration). Checked against pymap3d's `geodetic2ned` /
//! `ned2geodetic` (fixture in `tests/fixtures/geodetic_pymap3d.json`).

use crate::error::{EncodeError, check_range};
use nalgebra::{Matrix3, Vector3};

/// WGS-84 semi-major axis (m).
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// A WGS-84 position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geodetic {
    /// Latitude (degrees, north positive).
    pub latitude_deg: f64,
    /// Longitude (degrees, east positive).
    pub longitude_deg: f64,
    /// Height above the ellipsoid (m).
    pub height_m: f64,
}

impl Geodetic {
    /// A checked position: finite, latitude in [−90, 90], longitude in
    /// [−180, 180], height in [−11 km, 100 km].
    pub fn new(latitude_deg: f64, longitude_deg: f64, height_m: f64) -> Result<Self, EncodeError> {
        Ok(Self {
            latitude_deg: check_range("latitude_deg", latitude_deg, -90.0, 90.0)?,
            longitude_deg: check_range("longitude_deg", longitude_deg, -180.0, 180.0)?,
            height_m: check_range("height_m", height_m, -11_000.0, 100_000.0)?,
        })
    }

    /// Earth-centred earth-fixed position (m).
    pub fn to_ecef_m(&self) -> Vector3<f64> {
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let (sl, cl) = self.latitude_deg.to_radians().sin_cos();
        let (so, co) = self.longitude_deg.to_radians().sin_cos();
        let n = WGS84_A_M / (1.0 - e2 * sl * sl).sqrt();
        Vector3::new(
            (n + self.height_m) * cl * co,
            (n + self.height_m) * cl * so,
            (n * (1.0 - e2) + self.height_m) * sl,
        )
    }

    /// The position of an ECEF point (Heikkinen's closed form).
    pub fn from_ecef_m(p: &Vector3<f64>) -> Geodetic {
        let a = WGS84_A_M;
        let b = a * (1.0 - WGS84_F);
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let ep2 = (a * a - b * b) / (b * b);
        let r = p.x.hypot(p.y);
        let ff = 54.0 * b * b * p.z * p.z;
        let g = r * r + (1.0 - e2) * p.z * p.z - e2 * (a * a - b * b);
        let c = e2 * e2 * ff * r * r / (g * g * g);
        let s = (1.0 + c + (c * c + 2.0 * c).sqrt()).cbrt();
        let pp = ff / (3.0 * (s + 1.0 / s + 1.0).powi(2) * g * g);
        let q = (1.0 + 2.0 * e2 * e2 * pp).sqrt();
        let r0 = -(pp * e2 * r) / (1.0 + q)
            + (0.5 * a * a * (1.0 + 1.0 / q)
                - pp * (1.0 - e2) * p.z * p.z / (q * (1.0 + q))
                - 0.5 * pp * r * r)
                .max(0.0)
                .sqrt();
        let u = ((r - e2 * r0).powi(2) + p.z * p.z).sqrt();
        let v = ((r - e2 * r0).powi(2) + (1.0 - e2) * p.z * p.z).sqrt();
        let z0 = b * b * p.z / (a * v);
        Geodetic {
            latitude_deg: (p.z + ep2 * z0).atan2(r).to_degrees(),
            longitude_deg: p.y.atan2(p.x).to_degrees(),
            height_m: u * (1.0 - b * b / (a * v)),
        }
    }
}

/// The local NED frame at a home position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalNed {
    home: Geodetic,
    home_ecef_m: Vector3<f64>,
    /// Rotation ECEF → NED.
    ned_from_ecef: Matrix3<f64>,
}

impl LocalNed {
    /// The frame at `home` (its origin; axes north, east, down). Build
    /// `home` with [`Geodetic::new`], which checks it: the fields are
    /// public, and a non-finite home would give a non-finite frame.
    pub fn new(home: Geodetic) -> Self {
        let (sl, cl) = home.latitude_deg.to_radians().sin_cos();
        let (so, co) = home.longitude_deg.to_radians().sin_cos();
        #[rustfmt::skip]
        let ned_from_ecef = Matrix3::new(
            -sl * co, -sl * so,  cl,
            -so,       co,       0.0,
            -cl * co, -cl * so, -sl,
        );
        Self {
            home,
            home_ecef_m: home.to_ecef_m(),
            ned_from_ecef,
        }
    }

    /// The home position.
    pub fn home(&self) -> Geodetic {
        self.home
    }

    /// NED position (m) of a geodetic point.
    pub fn to_ned_m(&self, p: &Geodetic) -> Vector3<f64> {
        self.ned_from_ecef * (p.to_ecef_m() - self.home_ecef_m)
    }

    /// Geodetic point of an NED position (m).
    pub fn to_geodetic(&self, ned_m: &Vector3<f64>) -> Geodetic {
        Geodetic::from_ecef_m(&(self.home_ecef_m + self.ned_from_ecef.transpose() * ned_m))
    }
}
