//! Gain scheduling over the flight envelope: a grid of [`GainSet`]s designed
//! at operating points (velocity in heading axes: forward, lateral, down),
//! interpolated multilinearly on board.
//!
//! Two scheduled parts, each with its own scheduling variable:
//!
//! - [`ScheduledLqi`], the law, is scheduled on the **commanded** velocity
//!   in heading axes: the reference NED velocity rotated by the estimated
//!   heading ψ̂. Scheduling the law's trim on the measured velocity instead
//!   would move the trim velocity with the helicopter, x̂ − x_trim(x̂), and
//!   cancel the law's own proportional velocity feedback; the jerk-limited
//!   reference moves the operating point smoothly and free of sensor noise.
//! - [`ScheduledPredictor`], the Kalman predictor, is scheduled on its own
//!   **estimated** ground velocity in heading axes (the navigation's GPS/IMU
//!   velocity through the predictor; the helicopter carries no air-data
//!   sensor, so in a mean wind the operating point is the ground speed, not
//!   the airspeed). Along the trim manifold x_trim(σ), u_trim(σ) the
//!   scheduled affine model x⁺ = x_trim + Φ(x − x_trim) + Γ(u − u_trim)
//!   agrees with the nonlinear model to first order (the trim's own
//!   derivative cancels), so the predictor needs no reference.
//!
//! Both interpolations are continuous in the scheduling variable (bumpless:
//! the commands and the estimate move continuously as the operating point
//! moves), clamp at the grid's edges, and allocate nothing: the grid is
//! built once ([`GainSchedule::new`]) with at most [`MAX_SCHEDULE_POINTS`]
//! points and [`MAX_AXIS_POINTS`] per axis.

use crate::error::CoreError;
use crate::estimator::{KalmanPredictor, Predictor};
use crate::frames::{EulerTrig, wrap_pi};
use crate::gains::{GainSet, ServoLimits};
use crate::lqi::{Command, Lqi, Reference, StateFeedback};
use crate::state::{Input, MeasuredStates, ReducedState};
use nalgebra::{SMatrix, Vector3};
use std::sync::Arc;

/// Largest number of points on one scheduling axis.
pub const MAX_AXIS_POINTS: usize = 32;
/// Largest number of design points in one schedule (≈10 kB each).
pub const MAX_SCHEDULE_POINTS: usize = 1024;

/// The scheduling axes: operating-point velocities in heading axes (m/s),
/// each strictly increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduleAxes {
    /// Forward ground speed along the heading (m/s).
    pub forward_m_s: Vec<f64>,
    /// Lateral ground speed, right of the heading (m/s).
    pub lateral_m_s: Vec<f64>,
    /// Down velocity (m/s; negative climbs).
    pub down_m_s: Vec<f64>,
}

impl ScheduleAxes {
    /// The three axes in order [forward, lateral, down].
    pub fn as_array(&self) -> [&[f64]; 3] {
        [&self.forward_m_s, &self.lateral_m_s, &self.down_m_s]
    }

    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.as_array().iter().map(|a| a.len()).product()
    }

    /// Whether the grid has no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The operating point of grid index `(i, j, k)` as [forward, lateral, down].
    pub fn point(&self, i: usize, j: usize, k: usize) -> Vector3<f64> {
        Vector3::new(self.forward_m_s[i], self.lateral_m_s[j], self.down_m_s[k])
    }

    /// Flat index of `(i, j, k)` (down fastest, forward slowest).
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (i * self.lateral_m_s.len() + j) * self.down_m_s.len() + k
    }

    /// Check: every axis has 1..=[`MAX_AXIS_POINTS`] finite, strictly
    /// increasing values and the grid at most [`MAX_SCHEDULE_POINTS`] points.
    pub fn check(&self) -> Result<(), CoreError> {
        for (what, axis) in [
            ("forward_m_s", &self.forward_m_s),
            ("lateral_m_s", &self.lateral_m_s),
            ("down_m_s", &self.down_m_s),
        ] {
            let bad = |rule| Err(CoreError::InvalidSchedule { what, rule });
            if axis.is_empty() || axis.len() > MAX_AXIS_POINTS {
                return bad("must hold 1 to MAX_AXIS_POINTS (32) values");
            }
            if !axis.iter().all(|v| v.is_finite()) {
                return bad("values must be finite");
            }
            if axis.windows(2).any(|w| w[1] <= w[0]) {
                return bad("values must be strictly increasing");
            }
        }
        if self.len() > MAX_SCHEDULE_POINTS {
            return Err(CoreError::InvalidSchedule {
                what: "grid",
                rule: "has more than MAX_SCHEDULE_POINTS (1024) points",
            });
        }
        Ok(())
    }

    /// The bracketing cell of `sigma` (clamped to the grid): per axis the
    /// lower index and the weight of the upper one.
    fn locate(&self, sigma: &Vector3<f64>) -> [(usize, f64); 3] {
        let axes = self.as_array();
        std::array::from_fn(|d| {
            let a = axes[d];
            let n = a.len();
            let s = sigma[d];
            // NaN clamps to the first point (never reached: inputs are finite)
            if n == 1 || s.is_nan() || s <= a[0] {
                return (0, 0.0);
            }
            if s >= a[n - 1] {
                return (n - 2, 1.0);
            }
            let i = a.partition_point(|&v| v <= s).saturating_sub(1).min(n - 2);
            (i, (s - a[i]) / (a[i + 1] - a[i]))
        })
    }

    /// The up to eight grid corners around `sigma` with their multilinear
    /// weights (zero-weight corners dropped), as (flat index, weight).
    fn corners(&self, sigma: &Vector3<f64>) -> ([(usize, f64); 8], usize) {
        let cell = self.locate(sigma);
        let mut out = [(0usize, 0.0f64); 8];
        let mut n = 0;
        for c in 0..8usize {
            let mut w = 1.0;
            let mut idx = [0usize; 3];
            for d in 0..3 {
                let upper = (c >> d) & 1 == 1;
                let (i, t) = cell[d];
                w *= if upper { t } else { 1.0 - t };
                idx[d] = i + usize::from(upper);
            }
            if w > 0.0 {
                out[n] = (self.index(idx[0], idx[1], idx[2]), w);
                n += 1;
            }
        }
        (out, n)
    }
}

/// A grid of designs over the envelope (built once; read on board).
#[derive(Debug, Clone, PartialEq)]
pub struct GainSchedule {
    axes: ScheduleAxes,
    points: Vec<GainSet>,
}

fn blend<const R: usize, const C: usize>(
    out: &mut SMatrix<f64, R, C>,
    corners: &[(usize, f64)],
    points: &[GainSet],
    pick: impl Fn(&GainSet) -> &SMatrix<f64, R, C>,
) {
    out.fill(0.0);
    for &(i, w) in corners {
        for (o, x) in out
            .as_mut_slice()
            .iter_mut()
            .zip(pick(&points[i]).as_slice())
        {
            *o += w * x;
        }
    }
}

impl GainSchedule {
    /// A schedule from its axes and one gain set per grid point, in the order
    /// of [`ScheduleAxes::index`]. Every set must be flyable
    /// ([`GainSet::check`]) and share the sample time, α and wiring options.
    pub fn new(axes: ScheduleAxes, points: Vec<GainSet>) -> Result<Self, CoreError> {
        axes.check()?;
        if points.len() != axes.len() {
            return Err(CoreError::InvalidSchedule {
                what: "points",
                rule: "must hold one gain set per grid point",
            });
        }
        let first = points.first().ok_or(CoreError::InvalidSchedule {
            what: "points",
            rule: "must not be empty",
        })?;
        for p in &points {
            p.check()?;
            if p.sample_time_s != first.sample_time_s
                || p.alpha != first.alpha
                || p.options != first.options
            {
                return Err(CoreError::InvalidSchedule {
                    what: "points",
                    rule: "must share the sample time, alpha and wiring options",
                });
            }
        }
        Ok(GainSchedule { axes, points })
    }

    /// The axes.
    pub fn axes(&self) -> &ScheduleAxes {
        &self.axes
    }

    /// The design points, in the order of [`ScheduleAxes::index`].
    pub fn points(&self) -> &[GainSet] {
        &self.points
    }

    /// The whole gain set interpolated at `sigma` [forward, lateral, down]
    /// (m/s, heading axes; clamped to the grid), written into `out`
    /// (no allocation).
    pub fn interpolate_into(&self, sigma: &Vector3<f64>, out: &mut GainSet) {
        let (c, n) = self.axes.corners(sigma);
        let c = &c[..n];
        let p = &self.points;
        blend(&mut out.x_trim, c, p, |g| &g.x_trim);
        blend(&mut out.u_trim, c, p, |g| &g.u_trim);
        blend(&mut out.phi, c, p, |g| &g.phi);
        blend(&mut out.gamma, c, p, |g| &g.gamma);
        blend(&mut out.ls, c, p, |g| &g.ls);
        blend(&mut out.li, c, p, |g| &g.li);
        blend(&mut out.k, c, p, |g| &g.k);
        out.sample_time_s = p[0].sample_time_s;
        out.alpha = p[0].alpha;
        out.options = p[0].options;
    }

    /// The interpolated gain set at `sigma` (allocates the result; for
    /// analyses off board).
    pub fn at(&self, sigma: &Vector3<f64>) -> GainSet {
        let mut g = self.points[0].clone();
        self.interpolate_into(sigma, &mut g);
        g
    }

    fn interpolate_law(&self, sigma: &Vector3<f64>, law: &mut Lqi) {
        let (c, n) = self.axes.corners(sigma);
        let c = &c[..n];
        let p = &self.points;
        blend(&mut law.x_trim, c, p, |g| &g.x_trim);
        blend(&mut law.u_trim, c, p, |g| &g.u_trim);
        blend(&mut law.ls, c, p, |g| &g.ls);
        blend(&mut law.li, c, p, |g| &g.li);
    }

    /// Re-aim the predictor at `sigma`: its model and gain interpolated, its
    /// deviation re-expressed about the new trim (the absolute estimate is
    /// unchanged).
    fn interpolate_predictor(&self, sigma: &Vector3<f64>, kp: &mut KalmanPredictor) {
        let (c, n) = self.axes.corners(sigma);
        let c = &c[..n];
        let p = &self.points;
        let x_abs = kp.x_hat + kp.x_trim;
        blend(&mut kp.x_trim, c, p, |g| &g.x_trim);
        blend(&mut kp.u_trim, c, p, |g| &g.u_trim);
        blend(&mut kp.phi, c, p, |g| &g.phi);
        blend(&mut kp.gamma, c, p, |g| &g.gamma);
        blend(&mut kp.k, c, p, |g| &g.k);
        kp.x_hat = x_abs - kp.x_trim;
    }
}

/// The velocity `v_ned` in heading axes [forward, right, down] for heading ψ.
pub fn heading_axes(psi_rad: f64, v_ned: &Vector3<f64>) -> Vector3<f64> {
    let (s, c) = psi_rad.sin_cos();
    Vector3::new(
        c * v_ned.x + s * v_ned.y,
        -s * v_ned.x + c * v_ned.y,
        v_ned.z,
    )
}

/// The estimated ground velocity of an absolute reduced state, in heading
/// axes (the predictor's scheduling variable).
pub fn estimated_operating_point(x: &ReducedState) -> Vector3<f64> {
    let v_ned = EulerTrig::new(x[0], x[1], x[2]).ned_from_body() * Vector3::new(x[3], x[4], x[5]);
    heading_axes(x[2], &v_ned)
}

/// The commanded operating point: the reference velocity in the axes of
/// the reference heading (the law's scheduling variable). It depends on the
/// reference only: a heading error does not move the operating point (with
/// the estimated heading, a yaw error δψ at speed V would move the lateral
/// operating point by V·δψ and feed back through the trims).
pub fn commanded_operating_point(reference: &Reference) -> Vector3<f64> {
    heading_axes(reference.yaw_rad, &reference.velocity_ned_m_s)
}

/// The LQI law with its gains and trim interpolated on the commanded
/// operating point each sample (see the module documentation).
#[derive(Debug, Clone)]
pub struct ScheduledLqi {
    schedule: Arc<GainSchedule>,
    law: Lqi,
    sigma: Vector3<f64>,
}

impl ScheduledLqi {
    /// The scheduled law, saturating to `limits`; `enabled = false` holds the
    /// interpolated trim commands.
    pub fn new(
        schedule: Arc<GainSchedule>,
        limits: ServoLimits,
        enabled: bool,
    ) -> Result<Self, CoreError> {
        let law = Lqi::new(&schedule.points[0], limits, enabled)?;
        Ok(ScheduledLqi {
            schedule,
            law,
            sigma: Vector3::zeros(),
        })
    }

    /// The operating point of the last sample [forward, lateral, down] (m/s).
    pub fn operating_point(&self) -> Vector3<f64> {
        self.sigma
    }

    /// The integral states [ψ, vn, ve, vd].
    pub fn integral_states(&self) -> &nalgebra::SVector<f64, 4> {
        self.law.integral_states()
    }
}

impl StateFeedback for ScheduledLqi {
    fn command(&mut self, estimate: &ReducedState, reference: &Reference) -> Command {
        self.command_with_offset(estimate, reference, &Input::zeros())
    }

    fn command_with_offset(
        &mut self,
        estimate: &ReducedState,
        reference: &Reference,
        offset: &Input,
    ) -> Command {
        let sigma = commanded_operating_point(reference);
        // non-finite: keep the last operating point (the law reports the error)
        if sigma.iter().all(|v| v.is_finite()) {
            self.sigma = sigma;
        }
        self.schedule.interpolate_law(&self.sigma, &mut self.law);
        // The trim is the same at every heading: fly it at the commanded one
        // (the reference heading nearest the estimate, so x̂ − x_trim holds
        // the wrapped heading error), else the proportional path would pull
        // the heading back to the design's ψ = 0 through a turn.
        self.law.x_trim[2] = estimate[2] - wrap_pi(estimate[2] - reference.yaw_rad);
        self.law.command_with_offset(estimate, reference, offset)
    }

    fn reset(&mut self) {
        self.law.reset();
    }
}

/// The steady-state Kalman predictor with its model, gain and trim
/// interpolated on the estimated operating point before each prediction.
#[derive(Debug, Clone)]
pub struct ScheduledPredictor {
    schedule: Arc<GainSchedule>,
    inner: KalmanPredictor,
    sigma: Vector3<f64>,
}

impl ScheduledPredictor {
    /// The predictor starting at the absolute state `x0`.
    pub fn new(schedule: Arc<GainSchedule>, x0: &ReducedState) -> Result<Self, CoreError> {
        let mut inner = KalmanPredictor::new(&schedule.points[0], x0)?;
        let sigma = estimated_operating_point(x0);
        schedule.interpolate_predictor(&sigma, &mut inner);
        Ok(ScheduledPredictor {
            schedule,
            inner,
            sigma,
        })
    }

    /// The operating point of the last prediction [forward, lateral, down] (m/s).
    pub fn operating_point(&self) -> Vector3<f64> {
        self.sigma
    }
}

impl Predictor for ScheduledPredictor {
    fn absorb(&mut self, measured: &MeasuredStates) -> Result<ReducedState, CoreError> {
        self.inner.absorb(measured)
    }

    fn advance(&mut self, applied: &Input) -> Result<(), CoreError> {
        let sigma = estimated_operating_point(&(self.inner.x_hat + self.inner.x_trim));
        if sigma.iter().all(|v| v.is_finite()) {
            self.sigma = sigma;
        }
        self.schedule
            .interpolate_predictor(&self.sigma, &mut self.inner);
        self.inner.advance(applied)
    }
}

/// A law that is either one fixed design or a schedule: what a flight
/// computer built from either a `gains.json` or a gain-schedule file flies.
#[derive(Debug, Clone)]
pub enum Law {
    /// One design ([`Lqi`]).
    Fixed(Lqi),
    /// A gain schedule ([`ScheduledLqi`]).
    Scheduled(ScheduledLqi),
}

impl StateFeedback for Law {
    #[inline]
    fn command(&mut self, estimate: &ReducedState, reference: &Reference) -> Command {
        match self {
            Law::Fixed(l) => l.command(estimate, reference),
            Law::Scheduled(l) => l.command(estimate, reference),
        }
    }

    #[inline]
    fn command_with_offset(
        &mut self,
        estimate: &ReducedState,
        reference: &Reference,
        offset: &Input,
    ) -> Command {
        match self {
            Law::Fixed(l) => l.command_with_offset(estimate, reference, offset),
            Law::Scheduled(l) => l.command_with_offset(estimate, reference, offset),
        }
    }

    fn reset(&mut self) {
        match self {
            Law::Fixed(l) => l.reset(),
            Law::Scheduled(l) => l.reset(),
        }
    }
}

/// A predictor that is either one fixed design or a schedule.
#[derive(Debug, Clone)]
pub enum AnyPredictor {
    /// One design ([`KalmanPredictor`]).
    Fixed(KalmanPredictor),
    /// A gain schedule ([`ScheduledPredictor`]).
    Scheduled(ScheduledPredictor),
}

impl Predictor for AnyPredictor {
    #[inline]
    fn absorb(&mut self, measured: &MeasuredStates) -> Result<ReducedState, CoreError> {
        match self {
            AnyPredictor::Fixed(p) => p.absorb(measured),
            AnyPredictor::Scheduled(p) => p.absorb(measured),
        }
    }

    #[inline]
    fn advance(&mut self, applied: &Input) -> Result<(), CoreError> {
        match self {
            AnyPredictor::Fixed(p) => p.advance(applied),
            AnyPredictor::Scheduled(p) => Predictor::advance(p, applied),
        }
    }
}
