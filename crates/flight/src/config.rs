//! The on-board program's configuration (`onboard.toml`): device ports,
//! the parameter and gains files, the navigation's sensor figures, sensor
//! stale limits, failsafe settings, the log folder and the real-time
//! options. Every field is checked where it is read; an error names the file,
//! the field and the rule (the toolkit's one [`ConfigError`] shape).
//!
//! ```toml
//! params = "../params/bergen-twin.toml"   # optional: the Bergen Twin when absent
//! gains = "gains.json"                    # designed at params' control.sample_time_s
//! [devices.imu]                           # VectorNav binary (IMU + magnetometer)
//! path = "/dev/ttyS1"
//! baud = 921600
//! [devices.gps]                           # UBX or NMEA receiver
//! path = "/dev/ttyS2"
//! baud = 115200
//! [devices.avionics]                      # servo out, RC receiver in
//! path = "/dev/ttyS3"
//! baud = 115200
//! [stale]                                 # a sensor older than this is lost
//! imu_s = 0.02
//! gps_s = 1.0
//! mag_s = 0.5
//! rc_s = 0.5
//! [failsafe]
//! hold_s = 5.0                            # hover hold before the descent
//! descent_m_s = 0.5                       # then descend at this rate (down +)
//! overrun_limit = 8                       # consecutive deadline misses → hold
//! [log]
//! dir = "flight-logs"
//! [home]                                  # origin of the local NED frame (WGS-84)
//! latitude_deg = 57.0146
//! longitude_deg = 9.9869
//! height_m = 20.0
//! [realtime]
//! sched_fifo = true
//! priority = 80                           # 1..=99
//! mlockall = true
//! ```

use helicon_config::ConfigError;
use helicon_setup::estimator::EstimatorSection;
use helicon_setup::sensors::SensorConfig;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One serial device.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DevicePort {
    /// Device path (`/dev/ttyS1`, a pty slave in SITL).
    pub path: PathBuf,
    /// Baud rate (bit/s).
    pub baud: u32,
}

/// The three serial devices of thesis Figure 3.5.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Devices {
    /// IMU with magnetometer (VectorNav binary protocol).
    pub imu: DevicePort,
    /// GPS receiver.
    pub gps: DevicePort,
    /// Avionics board: servo frames out, RC receiver frames in.
    pub avionics: DevicePort,
}

/// Sensor stale limits: a sensor whose last fresh sample is older than its
/// limit is lost and triggers its failsafe.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StaleLimits {
    /// IMU (s): a few samples at 400 Hz.
    pub imu_s: f64,
    /// GPS (s): a few fixes at 4–5 Hz.
    pub gps_s: f64,
    /// Magnetometer (s).
    pub mag_s: f64,
    /// The avionics board's RC receiver frames (s; they come at about
    /// 50 Hz): a receiver silent this long after its last frame is the
    /// pilot's link lost, handled as the receiver's own failsafe flag
    /// (not before its first frame: a flight without a receiver is flown
    /// from the ground station).
    pub rc_s: f64,
}

/// The least stale limits accepted: one sample period of the fastest
/// device of each kind the runtime reads (an IMU at the 400 Hz control rate,
/// a 10 Hz GPS fix, a 100 Hz magnetometer, a 50 Hz receiver frame). A limit
/// below its device's period would call the sensor lost between any two
/// samples; the limits should hold several periods of the device flown.
pub const STALE_FLOOR_S: StaleLimits = StaleLimits {
    imu_s: 0.0025,
    gps_s: 0.1,
    mag_s: 0.01,
    rc_s: 0.02,
};

impl Default for StaleLimits {
    fn default() -> Self {
        StaleLimits {
            imu_s: 0.02,
            gps_s: 1.0,
            mag_s: 0.5,
            rc_s: 0.5,
        }
    }
}

/// What the failsafes do.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FailsafeConfig {
    /// Hover hold (zero velocity references, heading held) before the
    /// descent (s).
    pub hold_s: f64,
    /// The descent's vertical velocity reference (m/s, down positive).
    pub descent_m_s: f64,
    /// Consecutive control deadline misses that trigger the hold.
    pub overrun_limit: u32,
}

impl Default for FailsafeConfig {
    fn default() -> Self {
        FailsafeConfig {
            hold_s: 5.0,
            descent_m_s: 0.5,
            overrun_limit: 8,
        }
    }
}

/// The pilot's receiver: arming, the kill channel, the channels' range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RcConfig {
    /// The arm switch (channel 5) acts once held in its new position this
    /// long (s): one glitching frame, or a toggling channel, does nothing.
    pub arm_hold_s: f64,
    /// A kill channel (1-based, 6..=8), high above 1500 µs: held for
    /// `kill_hold_s` it disarms at any time: the receiver's only disarm in
    /// flight. The arm switch (held `arm_hold_s`) disarms only on the
    /// ground, which the ground logic (`landing.enabled`) tells; without
    /// it, the arm switch never disarms an armed helicopter.
    pub kill_channel: Option<u8>,
    /// The kill channel acts once held this long (s; 0.1 s is five frames).
    pub kill_hold_s: f64,
    /// Least pulse width of the receiver's range (µs): a frame with a
    /// channel below it is refused (counted, logged).
    pub min_us: u16,
    /// Largest pulse width of the receiver's range (µs).
    pub max_us: u16,
}

impl Default for RcConfig {
    fn default() -> Self {
        RcConfig {
            arm_hold_s: 0.5,
            kill_channel: None,
            kill_hold_s: 0.1,
            min_us: 800,
            max_us: 2200,
        }
    }
}

impl RcConfig {
    /// Check every field (`file` names the configuration in errors).
    pub fn validate(&self, file: &str) -> Result<(), ConfigError> {
        for (field, v) in [
            ("rc.arm_hold_s", self.arm_hold_s),
            ("rc.kill_hold_s", self.kill_hold_s),
        ] {
            if !(v.is_finite() && (0.0..=5.0).contains(&v)) {
                return Err(ConfigError::invalid(
                    file,
                    field,
                    v,
                    "must be within 0..=5 s",
                ));
            }
        }
        if let Some(k) = self.kill_channel
            && !(6..=8).contains(&k)
        {
            return Err(ConfigError::invalid(
                file,
                "rc.kill_channel",
                f64::from(k),
                "must be 6..=8 (1-4 are the sticks, 5 the arm switch)",
            ));
        }
        if !(500..1500).contains(&self.min_us) || !(1501..=2500).contains(&self.max_us) {
            return Err(ConfigError::invalid(
                file,
                "rc.min_us",
                f64::from(self.min_us),
                format!(
                    "rc.min_us must be 500..1500 and rc.max_us 1501..=2500 µs (got {}..{})",
                    self.min_us, self.max_us
                ),
            ));
        }
        Ok(())
    }
}

/// Where the flight log goes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogConfig {
    /// Folder of the flight logs (created when missing).
    pub dir: PathBuf,
}

impl Default for LogConfig {
    fn default() -> Self {
        LogConfig {
            dir: PathBuf::from("flight-logs"),
        }
    }
}

/// The origin of the local NED frame the GPS positions are given in.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HomeConfig {
    /// WGS-84 latitude (degrees, −90..=90).
    pub latitude_deg: f64,
    /// WGS-84 longitude (degrees, −180..=180).
    pub longitude_deg: f64,
    /// Height above the ellipsoid (m).
    pub height_m: f64,
}

impl Default for HomeConfig {
    /// A field near Aalborg (the thesis's flights).
    fn default() -> Self {
        HomeConfig {
            latitude_deg: 57.0146,
            longitude_deg: 9.9869,
            height_m: 20.0,
        }
    }
}

/// Real-time options: each is tried and, when the system does not permit
/// it, the program warns and runs without.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RealtimeConfig {
    /// Run the control task under SCHED_FIFO.
    pub sched_fifo: bool,
    /// Its priority (1..=99).
    pub priority: u8,
    /// Lock the program's memory (`mlockall`).
    pub mlockall: bool,
}

impl Default for RealtimeConfig {
    fn default() -> Self {
        RealtimeConfig {
            sched_fifo: true,
            priority: 80,
            mlockall: true,
        }
    }
}

/// The on-board program's configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OnboardConfig {
    /// Parameter file (relative to the configuration); the Bergen Twin when absent.
    #[serde(default)]
    pub params: Option<PathBuf>,
    /// Gains file (relative to the configuration).
    pub gains: PathBuf,
    /// The devices.
    pub devices: Devices,
    /// The navigation's sensor noise figures and local magnetic field (the
    /// simulator's sensor-configuration format; its defaults when absent).
    #[serde(default)]
    pub sensors: SensorConfig,
    /// Navigation tuning.
    #[serde(default)]
    pub navigation: helicon_core::NavigationConfig,
    /// Which navigation flies (`kind = "thesis" | "eskf"`) and the ESKF's
    /// tuning, as in scenarios.
    #[serde(default, skip_serializing_if = "EstimatorSection::is_default")]
    pub estimator: EstimatorSection,
    /// Sensor stale limits.
    #[serde(default)]
    pub stale: StaleLimits,
    /// Failsafe settings.
    #[serde(default)]
    pub failsafe: FailsafeConfig,
    /// The pilot's receiver (arm hold time, kill channel, range).
    #[serde(default)]
    pub rc: RcConfig,
    /// The sensors' plausibility limits.
    #[serde(default)]
    pub plausibility: crate::plausibility::PlausibilityConfig,
    /// From the ground to the ground: the rotor's run-up, the land
    /// detector, take-off and landing ([`crate::landing`]).
    #[serde(default)]
    pub landing: crate::landing::LandingConfig,
    /// Log folder.
    #[serde(default)]
    pub log: LogConfig,
    /// The local NED frame's origin.
    #[serde(default)]
    pub home: HomeConfig,
    /// A mission: a scenario file whose `[trim]` and `[[reference]]` give
    /// the references against time since arming (relative to this file);
    /// without it the helicopter holds a hover at the heading of alignment.
    #[serde(default)]
    pub mission: Option<PathBuf>,
    /// Real-time options.
    #[serde(default)]
    pub realtime: RealtimeConfig,
    /// The ground station (`[gcs]`, optional; see `helicon_gcs::config`):
    /// when present the program starts the MAVLink server and flies the
    /// navigator's references (not with `mission`).
    #[serde(default, skip_serializing)]
    pub gcs: Option<helicon_gcs::config::GcsSection>,
    /// Flight-test inputs (`[[excitation]]`, the scenarios' form): added to
    /// the law's command in auto from the first entry into auto, ended for
    /// good when auto is left (the pilot's switch stops them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub excitation: Vec<helicon_setup::excitation::ExcitationEntry>,
    /// The folder relative paths are resolved against (the file's folder).
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// The file it was read from (named in errors found later).
    #[serde(skip)]
    pub file: String,
}

fn positive(file: &str, field: &str, v: f64, max: f64) -> Result<(), ConfigError> {
    if v.is_finite() && v > 0.0 && v <= max {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            file,
            field,
            v,
            format!("must be finite, > 0 and <= {max}"),
        ))
    }
}

impl OnboardConfig {
    /// Parse and check a configuration's text (`file` names it in errors).
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ConfigError> {
        let mut cfg: OnboardConfig = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        cfg.validate(file)?;
        cfg.file = file.to_string();
        Ok(cfg)
    }

    /// Read and check a configuration file.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let (file, text) = ConfigError::read_file(path)?;
        let mut cfg = Self::from_toml_str(&text, &file)?;
        cfg.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(cfg)
    }

    /// A path of the configuration, resolved against its folder.
    pub fn resolve(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base_dir.join(p)
        }
    }

    /// Check every field (`file` names the configuration in errors).
    pub fn validate(&self, file: &str) -> Result<(), ConfigError> {
        for (name, d) in [
            ("imu", &self.devices.imu),
            ("gps", &self.devices.gps),
            ("avionics", &self.devices.avionics),
        ] {
            if d.path.as_os_str().is_empty() {
                return Err(ConfigError::Invalid {
                    file: file.to_string(),
                    field: format!("devices.{name}.path"),
                    value: "\"\"".into(),
                    rule: "a device path is required".into(),
                });
            }
            if !crate::ports::BAUDS.contains(&d.baud) {
                return Err(ConfigError::invalid(
                    file,
                    format!("devices.{name}.baud"),
                    f64::from(d.baud),
                    format!("must be one of {:?} bit/s", crate::ports::BAUDS),
                ));
            }
        }
        helicon_setup::excitation::Excitations::new(&self.excitation, file)?;
        let s = &self.stale;
        for (field, v, floor, max) in [
            ("stale.imu_s", s.imu_s, STALE_FLOOR_S.imu_s, 1.0),
            ("stale.gps_s", s.gps_s, STALE_FLOOR_S.gps_s, 60.0),
            ("stale.mag_s", s.mag_s, STALE_FLOOR_S.mag_s, 60.0),
            ("stale.rc_s", s.rc_s, STALE_FLOOR_S.rc_s, 10.0),
        ] {
            positive(file, field, v, max)?;
            // below one period of the device it is stale between any two
            // samples: its failsafe would latch with nothing wrong
            if v < floor {
                return Err(ConfigError::invalid(
                    file,
                    field,
                    v,
                    format!(
                        "must be at least {floor} s, one sample period of the fastest such device (below it the sensor is stale between any two samples); use several of your device's periods"
                    ),
                ));
            }
        }
        let f = &self.failsafe;
        positive(file, "failsafe.hold_s", f.hold_s, 3600.0)?;
        positive(file, "failsafe.descent_m_s", f.descent_m_s, 5.0)?;
        if !(1..=10_000).contains(&f.overrun_limit) {
            return Err(ConfigError::invalid(
                file,
                "failsafe.overrun_limit",
                f64::from(f.overrun_limit),
                "must be 1..=10000 samples",
            ));
        }
        self.rc.validate(file)?;
        self.plausibility.validate(file)?;
        self.landing.validate(file)?;
        if !(1..=99).contains(&self.realtime.priority) {
            return Err(ConfigError::invalid(
                file,
                "realtime.priority",
                f64::from(self.realtime.priority),
                "must be 1..=99 (SCHED_FIFO)",
            ));
        }
        let h = &self.home;
        let range = |field: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(ConfigError::invalid(
                    file,
                    field,
                    v,
                    format!("must be finite and within {lo}..={hi}"),
                ))
            }
        };
        range("home.latitude_deg", h.latitude_deg, -90.0, 90.0)?;
        range("home.longitude_deg", h.longitude_deg, -180.0, 180.0)?;
        range("home.height_m", h.height_m, -1000.0, 10_000.0)?;
        self.sensors
            .validate(file)
            .map_err(|e| e.within(file, "sensors"))?;
        self.navigation.validate().map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: format!("[navigation]: {e}"),
        })?;
        self.estimator
            .eskf
            .validate()
            .map_err(|e| ConfigError::Parse {
                file: file.to_string(),
                message: format!("[estimator.eskf]: {e}"),
            })?;
        if let Some(g) = &self.gcs {
            if self.mission.is_some() {
                return Err(ConfigError::Invalid {
                    file: file.to_string(),
                    field: "gcs".into(),
                    value: "[gcs]".into(),
                    rule: "the ground station's navigator and `mission` both give the \
                           references: keep one"
                        .into(),
                });
            }
            g.server_config(self.home_geodetic(file)?, file)?;
        }
        Ok(())
    }

    /// The home as a WGS-84 position (checked).
    pub fn home_geodetic(&self, file: &str) -> Result<helicon_devices::Geodetic, ConfigError> {
        let h = &self.home;
        helicon_devices::Geodetic::new(h.latitude_deg, h.longitude_deg, h.height_m).map_err(|e| {
            ConfigError::Invalid {
                file: file.to_string(),
                field: "home".into(),
                value: format!("{}, {}, {}", h.latitude_deg, h.longitude_deg, h.height_m),
                rule: e.to_string(),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: &str = "gains = \"g.json\"\n[devices.imu]\npath = \"/dev/ttyS1\"\nbaud = 921600\n\
        [devices.gps]\npath = \"/dev/ttyS2\"\nbaud = 115200\n\
        [devices.avionics]\npath = \"/dev/ttyS3\"\nbaud = 115200\n";

    fn err(extra: &str) -> String {
        match OnboardConfig::from_toml_str(&format!("{MIN}{extra}"), "o.toml") {
            Ok(_) => String::new(),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn minimal_configuration_takes_the_defaults() {
        let c = OnboardConfig::from_toml_str(MIN, "o.toml").unwrap();
        assert_eq!(c.stale, StaleLimits::default());
        assert_eq!(c.failsafe.overrun_limit, 8);
        assert!(c.realtime.sched_fifo);
        assert!(c.gcs.is_none());
    }

    #[test]
    fn excitation_entries_are_read_and_checked() {
        let sweep = "[[excitation]]\nservo = \"S_lon\"\nt_s = 1.0\ninput = { kind = \"sweep\", \
            amplitude = 0.02, omega_min_rad_s = 1.2, omega_max_rad_s = 30.0, duration_s = 27.0 }\n";
        let c = OnboardConfig::from_toml_str(&format!("{MIN}{sweep}"), "o.toml").unwrap();
        assert_eq!(c.excitation.len(), 1);
        assert_eq!(c.excitation[0].servo, "S_lon");
        let e = err(&sweep.replace("S_lon", "S_pitch"));
        assert!(
            e.contains("o.toml") && e.contains("excitation[0].servo"),
            "{e}"
        );
        let e = err(&sweep.replace("t_s = 1.0", "t_s = -1.0"));
        assert!(e.contains("excitation[0].t_s"), "{e}");
        let e = err(&sweep.replace("duration_s = 27.0", "duration_s = -27.0"));
        assert!(e.contains("excitation[0].input.duration_s"), "{e}");
    }

    #[test]
    fn the_gcs_section_is_read_and_checked() {
        let c = OnboardConfig::from_toml_str(
            &format!("{MIN}[gcs]\naddress = \"udpin:0.0.0.0:14550\"\n[gcs.navigator]\ncruise_speed_m_s = 3.0\n"),
            "o.toml",
        )
        .unwrap();
        let g = c.gcs.unwrap();
        assert_eq!(g.address, "udpin:0.0.0.0:14550");
        assert_eq!(g.navigator.cruise_speed_m_s, 3.0);
        let e = err("[gcs]\nsystem_id = 255\n");
        assert!(e.contains("o.toml") && e.contains("gcs.system_id"), "{e}");
        let e = err("[gcs]\naddress = \"tcp:1.2.3.4:5\"\n");
        assert!(e.contains("o.toml") && e.contains("gcs.address"), "{e}");
        let e = err("[gcs.navigator]\ncruise_speed_m_s = -1.0\n");
        assert!(e.contains("gcs.navigator.cruise_speed_m_s"), "{e}");
        let both = format!("mission = \"m.toml\"\n{MIN}[gcs]\n");
        let e = OnboardConfig::from_toml_str(&both, "o.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("o.toml") && e.contains("`gcs`"), "{e}");
    }

    #[test]
    fn bad_fields_are_named_with_file_and_rule() {
        assert_eq!(
            err("[stale]\ngps_s = -1.0\n"),
            "o.toml: `stale.gps_s` = -1: must be finite, > 0 and <= 60"
        );
        assert_eq!(
            err("[stale]\nimu_s = nan\n"),
            "o.toml: `stale.imu_s` = NaN: must be finite, > 0 and <= 1"
        );
        // a receiver limit below its 50 Hz frame period (20 ms): lost
        // between every two frames
        let e = err("[stale]\nrc_s = 0.005\n");
        assert!(
            e.starts_with("o.toml: `stale.rc_s` = 0.005: must be at least 0.02 s"),
            "{e}"
        );
        let e = err("[stale]\ngps_s = 0.05\n");
        assert!(
            e.contains("`stale.gps_s`") && e.contains("at least 0.1 s"),
            "{e}"
        );
        assert_eq!(
            err("[realtime]\npriority = 0\n"),
            "o.toml: `realtime.priority` = 0: must be 1..=99 (SCHED_FIFO)"
        );
        assert_eq!(
            err("[failsafe]\noverrun_limit = 0\n"),
            "o.toml: `failsafe.overrun_limit` = 0: must be 1..=10000 samples"
        );
        assert!(
            err("[sensors.gps]\nrate_hz = -5.0\n").starts_with("o.toml: `sensors.gps.rate_hz`")
        );
        assert!(err("[stale]\nbogus = 1\n").contains("bogus"));
        assert_eq!(
            err("[stale]\nrc_s = 0.0\n"),
            "o.toml: `stale.rc_s` = 0: must be finite, > 0 and <= 10"
        );
        for v in ["-0.5", "nan", "inf", "-inf", "1e300", "10.000001"] {
            let e = err(&format!("[stale]\nrc_s = {v}\n"));
            assert!(
                e.starts_with("o.toml: `stale.rc_s` = ")
                    && e.ends_with("must be finite, > 0 and <= 10"),
                "{v}: {e}"
            );
        }
        let e = err("[stale]\nrc_s = \"0.5\"\n");
        assert!(e.contains("o.toml") && e.contains("rc_s"), "{e}");
        assert_eq!(
            err("[home]\nlatitude_deg = 91.0\n"),
            "o.toml: `home.latitude_deg` = 91: must be finite and within -90..=90"
        );
        let bad_baud = MIN.replace("baud = 921600", "baud = 7");
        let e = OnboardConfig::from_toml_str(&bad_baud, "o.toml").unwrap_err();
        assert_eq!(
            e.to_string(),
            "o.toml: `devices.imu.baud` = 7: must be one of [9600, 19200, 38400, 57600, \
             115200, 230400, 460800, 921600, 1000000] bit/s"
        );
    }
}

#[cfg(test)]
mod example_tests {
    use super::*;

    #[test]
    fn the_shipped_example_reads() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/onboard.toml");
        let c = OnboardConfig::from_file(&path).unwrap();
        assert_eq!(c.devices.imu.baud, 921_600);
        assert_eq!(c.failsafe.hold_s, 5.0);
        assert!(c.resolve(&c.gains).ends_with("out/demo/gains.json"));
    }
}
