//! The random draws of one run (its own ChaCha8 stream).

use super::campaign::{WindKey, param_field};
use super::{Campaign, DispersionKind, DistributionKind};
use helicon_model::Params;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The draws of one run.
#[derive(Debug, Clone)]
pub struct Draw {
    /// Run index.
    pub index: usize,
    /// Wind seed flown.
    pub wind_seed: u64,
    /// Sensor seed flown.
    pub sensor_seed: u64,
    /// Dispersed values, one per `[[dispersion]]`.
    pub values: Vec<f64>,
    /// The dispersed parameters (not yet validated).
    pub params: Params,
    /// The scenario's wind with its dispersed values (`wind.…` keys; not
    /// yet validated; the seed is the scenario's, `wind_seed` is flown).
    pub wind: crate::wind::WindConfig,
}

impl Campaign {
    /// The draws of run `index`: seeds and dispersed values (pure; no flight).
    pub fn draw(&self, index: usize) -> Draw {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(index as u64);
        let wind_seed = rng.next_u64();
        let sensor_seed = rng.next_u64();
        let mut params = self.nominal;
        let mut wind = self.scenario.wind.clone();
        let mut values = Vec::with_capacity(self.dispersions.len());
        for d in &self.dispersions {
            let delta = match d.distribution {
                DistributionKind::Normal => {
                    let s = d.sigma.unwrap_or(0.0);
                    let mut z: f64 = StandardNormal.sample(&mut rng);
                    // bounded: P(|z| > 0.5) ≈ 0.62, so 64 tries fail with p < 1e-13
                    let mut tries = 0;
                    while d.truncate_sigma > 0.0 && z.abs() > d.truncate_sigma && tries < 64 {
                        z = StandardNormal.sample(&mut rng);
                        tries += 1;
                    }
                    if d.truncate_sigma > 0.0 {
                        z = z.clamp(-d.truncate_sigma, d.truncate_sigma);
                    }
                    s * z
                }
                DistributionKind::Uniform => {
                    let w = d.half_width.unwrap_or(0.0);
                    // 53 random bits → [0, 1)
                    let u = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
                    w * (2.0 * u - 1.0)
                }
            };
            let slot = match param_field(&d.param) {
                Some(f) => Some(f(&mut params)),
                None => WindKey::parse(&d.param).and_then(|w| w.slot(&mut wind)),
            };
            let v = match slot {
                Some(slot) => {
                    *slot = match d.kind {
                        DispersionKind::Relative => *slot * (1.0 + delta),
                        DispersionKind::Absolute => *slot + delta,
                    };
                    *slot
                }
                None => f64::NAN,
            };
            values.push(v);
        }
        Draw {
            index,
            wind_seed: if self.disperse_wind_seed {
                wind_seed
            } else {
                self.scenario.wind.seed
            },
            sensor_seed: if self.disperse_sensor_seed {
                sensor_seed
            } else {
                self.scenario.sensors.seed
            },
            values,
            params,
            wind,
        }
    }
}
