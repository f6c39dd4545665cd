//! The `[gcs]` section of the on-board configuration: where the server
//! speaks, the vehicle's system id, the signing key, the start-up stream
//! rates and the navigator's tuning. Checked field by field; every error
//! names the file and the field (the toolkit's one `ConfigError` shape).
//!
//! ```toml
//! [gcs]
//! address = "udpout:127.0.0.1:14550"
//! system_id = 1
//! signing_key_hex = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff"
//!
//! [gcs.navigator]
//! cruise_speed_m_s = 2.0
//! link_loss_action = "return"
//!
//! [gcs.navigator.fence]
//! max_hor_dist_m = 150.0
//! max_ver_dist_m = 60.0
//! action = "return"
//! ```

use crate::navigator::NavigatorConfig;
use crate::server::{STREAMS, ServerConfig, default_rates_hz, parse_address};
use helicon_config::ConfigError;
use helicon_devices::Geodetic;
use serde::Deserialize;

/// The `[gcs]` section as written.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GcsSection {
    /// `udpout:HOST:PORT`, `udpin:HOST:PORT`, `tcpin:HOST:PORT`, or a
    /// comma-separated list of them.
    pub address: String,
    /// The vehicle's MAVLink system id (1..=254).
    pub system_id: u8,
    /// The MAVLink 2 signing key, 64 hexadecimal digits (32 bytes); absent:
    /// commands are not signed.
    pub signing_key_hex: Option<String>,
    /// Start-up stream rates by message name (Hz; 0: off; at most 100).
    pub rates_hz: std::collections::BTreeMap<String, f64>,
    /// The navigator's tuning (the parameter table's start-up values).
    pub navigator: NavigatorConfig,
}

impl Default for GcsSection {
    fn default() -> Self {
        GcsSection {
            address: crate::server::DEFAULT_ADDRESS.to_string(),
            system_id: 1,
            signing_key_hex: None,
            rates_hz: std::collections::BTreeMap::new(),
            navigator: NavigatorConfig::default(),
        }
    }
}

fn key_from_hex(hex: &str) -> Option<[u8; 32]> {
    if hex.len() != 64 || !hex.is_ascii() {
        return None;
    }
    let mut key = [0u8; 32];
    for (i, k) in key.iter_mut().enumerate() {
        *k = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).ok()?;
    }
    Some(key)
}

impl GcsSection {
    /// Parse a section on its own (`file` names it in errors; fields are
    /// reported as `gcs.…`).
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ConfigError> {
        toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.to_string(),
            message: format!("[gcs]: {e}"),
        })
    }

    /// The server's settings, every field checked; `home` is the GPS
    /// receiver's origin of the local NED frame.
    pub fn server_config(&self, home: Geodetic, file: &str) -> Result<ServerConfig, ConfigError> {
        let invalid = |field: &str, value: String, rule: &str| ConfigError::Invalid {
            file: file.to_string(),
            field: format!("gcs.{field}"),
            value,
            rule: rule.to_string(),
        };
        parse_address(&self.address).map_err(|_| {
            invalid(
                "address",
                self.address.clone(),
                "udpin:, udpout: or tcpin:HOST:PORT, or a comma-separated list",
            )
        })?;
        if self.system_id == 0 || self.system_id == 255 {
            return Err(invalid(
                "system_id",
                self.system_id.to_string(),
                "1..=254 (0 is broadcast, 255 the ground station)",
            ));
        }
        let signing_key = match &self.signing_key_hex {
            None => None,
            Some(h) => Some(key_from_hex(h).ok_or_else(|| {
                invalid(
                    "signing_key_hex",
                    "(hidden)".into(),
                    "64 hexadecimal digits",
                )
            })?),
        };
        let mut rates_hz = default_rates_hz();
        for (name, rate) in &self.rates_hz {
            let i = STREAMS
                .iter()
                .position(|(_, n, _)| n == name)
                .ok_or_else(|| {
                    invalid(
                        &format!("rates_hz.{name}"),
                        rate.to_string(),
                        "not a streamed message (HEARTBEAT, SYS_STATUS, ATTITUDE, GLOBAL_POSITION_INT, LOCAL_POSITION_NED, GPS_RAW_INT, VFR_HUD, SERVO_OUTPUT_RAW, RC_CHANNELS)",
                    )
                })?;
            if !(rate.is_finite() && (0.0..=100.0).contains(rate)) {
                return Err(ConfigError::invalid(
                    file,
                    format!("gcs.rates_hz.{name}"),
                    *rate,
                    "0 (off) to 100 Hz",
                ));
            }
            rates_hz[i] = *rate;
        }
        self.navigator.validate().map_err(|e| {
            ConfigError::invalid(file, format!("gcs.navigator.{}", e.field), e.value, e.rule)
        })?;
        Ok(ServerConfig {
            address: self.address.clone(),
            system_id: self.system_id,
            home,
            navigator: self.navigator,
            signing_key,
            rates_hz,
        })
    }
}
