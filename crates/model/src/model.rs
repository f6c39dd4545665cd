//! The assembled model: the five blocks of thesis Figure 4.4 (actuators,
//! flapping, force and torque generation, summation, rigid body) evaluated in
//! the order of Appendix D, giving ẋ = f(x, u, wind).
//!
//! Order (exact, not iterated): actuators → aerodynamic velocities → main-rotor
//! blade integrals → main-rotor inflow (7.33) → main-rotor forces → tail rotor
//! and its inflow (7.56) → drag (needs both induced velocities) → summation
//! (8.3)/(8.5) → rigid body (9.21)/(9.22) → flapping (6.47)/(6.53), which
//! needs the body accelerations only with `flap_accel` and then follows the
//! rigid body because the forces do not depend on flapping accelerations
//! (MODEL.md §10).

use crate::actuators::servo_derivative;
use crate::drag::{DragWrench, drag};
use crate::drivetrain::{DriveCommand, RotorState};
use crate::flapping::StabilizerBarCoefficients;
use crate::flapping::{FlapBody, main_rotor_accel};
use crate::frames::EulerTrig;
use crate::inflow::{InflowError, InflowProblem};
use crate::landing_gear::{Anchors, ContactWrench, GroundPlane, N_CONTACT};
use crate::options::{InflowMode, ModelOptions, Preset, SbVelocityScale, WindSign};
use crate::params::Params;
use crate::rigid_body::{angular_accel, linear_accel};
use crate::rotor::{BladeInputs, Grid, blade_integrals};
use crate::state::{INPUT_NAMES, Input, NX, STATE_NAMES, State, iu, ix};
use crate::tail_rotor::{self, TailRotorConsts};
use nalgebra::{Vector2, Vector3};

/// Errors of a derivative evaluation.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A state, input or wind component is NaN or infinite.
    #[error("non-finite {what} `{name}` = {value}")]
    NonFinite {
        /// "state", "input", "wind" or "inflow" (a carried λ).
        what: &'static str,
        /// Component name.
        name: &'static str,
        /// The value.
        value: f64,
    },
    /// |θ| reached π/2, where the 3-2-1 Euler kinematics (9.14) are singular.
    #[error(
        "pitch angle theta = {theta_rad} rad is at the 3-2-1 Euler singularity (|theta| -> pi/2)"
    )]
    GimbalLock {
        /// θ (rad).
        theta_rad: f64,
    },
    /// An output of the evaluation (a derivative or an [`Aux`] quantity) is
    /// NaN or infinite although the inputs were finite: the state or the
    /// parameters are beyond the range where the model's arithmetic holds.
    #[error("non-finite {what} `{name}` = {value} (state or parameters out of range)")]
    NonFiniteOutput {
        /// "derivative of", "aux", or the matrix ("A", "B") it belongs to.
        what: &'static str,
        /// The state, input or [`Aux`] quantity.
        name: &'static str,
        /// The value.
        value: f64,
    },
    /// [`InflowMode::ThesisIteration`] with `iterations = 0`: the forces would
    /// use the carried λ unchanged, which is not the thesis scheme (7 steps).
    #[error("thesis inflow iteration needs at least 1 Newton-Raphson step (iterations = 0)")]
    ZeroInflowIterations,
    /// The inflow solver failed (non-finite intermediate values).
    #[error("{rotor} inflow: {source}")]
    Inflow {
        /// "main rotor" or "tail rotor".
        rotor: &'static str,
        /// Cause.
        source: InflowError,
    },
}

/// Everything a derivative evaluation computes besides ẋ: inflow and the
/// forces and torques of each block, for logging and plotting.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Aux {
    /// Main-rotor inflow ratio used by the forces.
    pub lambda_mr: f64,
    /// Tail-rotor inflow ratio used by the forces.
    pub lambda_tr: f64,
    /// Main-rotor inflow ratio used by the flapping (equal to `lambda_mr`
    /// with converged inflow).
    pub lambda_mr_flap: f64,
    /// Main-rotor induced velocity vi = hż − λΩR (m/s, positive down).
    pub vi_mr_m_s: f64,
    /// Tail-rotor induced velocity vi,tr = tẏ − λtr Ωtr Rtr (m/s, positive +y).
    pub vi_tr_m_s: f64,
    /// Main-rotor thrust coefficient C_T (7.30).
    pub ct_mr: f64,
    /// Tail-rotor thrust coefficient C_T,tr (7.53).
    pub ct_tr: f64,
    /// Main-rotor advance ratios [μx, μy, μz] (D.7)–(D.9).
    pub mu_mr: Vector3<f64>,
    /// Tail-rotor advance ratios [μx,tr, μy,tr, μz,tr] (D.13)–(D.15).
    pub mu_tr: Vector3<f64>,
    /// Main-rotor force in the hub frame [hFx, hFy, hFz] (N), (7.7)–(7.9).
    pub force_mr_hub_n: Vector3<f64>,
    /// Main-rotor torque at the hub [hτx, hτy, hτz] (N·m), (7.21), (7.22), (7.25).
    pub torque_mr_hub_nm: Vector3<f64>,
    /// Main-rotor torque about the CM (N·m), (7.26).
    pub torque_mr_body_nm: Vector3<f64>,
    /// Tail-rotor thrust tFy (N), (7.47)/(D.39).
    pub force_tr_y_n: f64,
    /// Tail-rotor torque about the CM (N·m), (7.52).
    pub torque_tr_body_nm: Vector3<f64>,
    /// Drag forces and torques, (7.57)–(7.64).
    pub drag: DragWrench,
    /// Gravity in body axes (N), (8.3).
    pub force_gravity_body_n: Vector3<f64>,
    /// Total force in body axes (N), (8.3).
    pub force_total_body_n: Vector3<f64>,
    /// Total torque about the CM in body axes (N·m), (8.5).
    pub torque_total_body_nm: Vector3<f64>,
    /// Inflow solver iterations (main, tail).
    pub inflow_iterations: [u32; 2],
    /// |g(λ)| of (7.33)/(7.56) at the λ used by the forces (main, tail): the
    /// solver's residual with converged inflow, the iteration's with the
    /// thesis emulation.
    pub inflow_residual: [f64; 2],
    /// The landing gear's forces (zero with the block off or in the air).
    pub contact: ContactWrench,
    /// The ground-effect factor k_G on the main rotor's induced velocity
    /// (1 − (R/4z)²; 0 when the block is off, i.e. not evaluated).
    pub ground_effect_factor: f64,
    /// The rotor speed Ω the evaluation used (rad/s).
    pub omega_rad_s: f64,
    /// The rotors' aerodynamic load at the main shaft, Q_mr + G·Q_tr (N·m),
    /// the torque the engine must give at constant speed.
    pub rotor_load_n_m: f64,
    /// The drivetrain's throttle (0 … 1; 0 when the block is off).
    pub throttle: f64,
}

/// The plant's state beyond the model's 30: the drivetrain's (used when
/// `drivetrain.enabled`) and the landing gear's friction anchors (used when
/// `landing_gear.enabled`). The 30-state model, its trim and its
/// linearization do not see them: with both blocks off
/// [`Model::plant_derivative`] is [`Model::derivative_with`] bit for bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantState {
    /// The model's 30 states.
    pub x: State,
    /// Rotor speed and governor integrator.
    pub rotor: RotorState,
    /// The friction anchors (held over an integration step).
    pub anchors: Anchors,
}

/// Number of integrated plant states: the model's 30, then Ω and the
/// governor's integrator.
pub const NX_PLANT: usize = NX + 2;

/// The integrated plant vector `[x (30), Ω, I]`.
pub type PlantVector = nalgebra::SVector<f64, NX_PLANT>;

impl PlantState {
    /// The integrated part as one vector.
    pub fn vector(&self) -> PlantVector {
        let mut v = PlantVector::zeros();
        v.fixed_rows_mut::<NX>(0).copy_from(&self.x);
        v[NX] = self.rotor.omega_rad_s;
        v[NX + 1] = self.rotor.governor_integral;
        v
    }

    /// Split an integrated vector back into the states (the anchors kept).
    pub fn set_vector(&mut self, v: &PlantVector) {
        self.x = v.fixed_rows::<NX>(0).into_owned();
        self.rotor = RotorState {
            omega_rad_s: v[NX],
            governor_integral: v[NX + 1],
        };
    }
}

/// Precomputed constants.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Consts {
    omega_rad_s: f64,
    mr_grid: Grid,
    tr: TailRotorConsts,
    lift_k: f64,
    drag_k: f64,
    a_cal_sb: f64,
    ct_den: f64,
    tip_speed: f64,
    inertia: Vector3<f64>,
    sb_scale: f64,
    wind_sign: f64,
}

impl Consts {
    /// The constants at rotor speed `omega_rad_s` (the tail rotor at G·Ω).
    fn new(params: &Params, options: &ModelOptions, omega_rad_s: f64) -> Consts {
        let mut at = *params;
        at.main_rotor.omega_rad_s = omega_rad_s;
        let params = &at;
        let mr = &params.main_rotor;
        let sb = &params.stabilizer_bar;
        let rho = params.environment.rho_kg_m3;
        let tip = mr.omega_rad_s * mr.radius_m;
        let sb_scale = match options.sb_velocity {
            SbVelocityScale::Physical => 1.0,
            SbVelocityScale::OuterRadius => sb.outer_radius_m / mr.radius_m,
        };
        Consts {
            omega_rad_s: mr.omega_rad_s,
            mr_grid: Grid::new(0.0, mr.radius_m - mr.hinge_offset_m),
            tr: TailRotorConsts::new(params),
            lift_k: 0.5 * rho * mr.chord_m * mr.lift_slope_per_rad,
            drag_k: 0.5 * rho * mr.chord_m * mr.drag_coefficient,
            a_cal_sb: rho * sb.lift_slope_per_rad * sb.chord_m / (2.0 * sb.paddle_inertia_kg_m2),
            ct_den: rho * std::f64::consts::PI * mr.radius_m * mr.radius_m * tip * tip,
            tip_speed: tip,
            inertia: Vector3::new(
                params.body.ixx_kg_m2,
                params.body.iyy_kg_m2,
                params.body.izz_kg_m2,
            ),
            sb_scale,
            wind_sign: match options.wind {
                WindSign::Physical => -1.0,
                WindSign::Thesis => 1.0,
            },
        }
    }
}

/// The ground blocks' precomputed geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
struct GroundConsts {
    plane: GroundPlane,
    points_body_m: [Vector3<f64>; N_CONTACT],
}

/// The helicopter model: parameters, preset options and precomputed constants.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    params: Params,
    options: ModelOptions,
    c: Consts,
    ground: GroundConsts,
}

/// The extra inputs of a plant evaluation.
#[derive(Debug, Clone, Copy)]
struct PlantInputs<'a> {
    rotor: &'a RotorState,
    drive: &'a DriveCommand,
    anchors: &'a Anchors,
}

impl Model {
    /// A model from validated parameters and options.
    pub fn new(params: Params, options: ModelOptions) -> Model {
        let c = Consts::new(&params, &options, params.main_rotor.omega_rad_s);
        let ground = GroundConsts {
            plane: GroundPlane::new(&params.landing_gear),
            points_body_m: crate::landing_gear::contact_points_body_m(&params.landing_gear),
        };
        Model {
            params,
            options,
            c,
            ground,
        }
    }

    /// The ground plane of `[landing_gear]`.
    pub fn ground_plane(&self) -> &GroundPlane {
        &self.ground.plane
    }

    /// The contact points in body axes (m).
    pub fn contact_points_body_m(&self) -> &[Vector3<f64>; N_CONTACT] {
        &self.ground.points_body_m
    }

    /// The plant derivative: the 30 states with the landing gear's forces
    /// (when on, with the friction `anchors` held) and, when the drivetrain
    /// is on, the rotor speed and governor states under `drive`
    /// ([`crate::drivetrain`]). With both blocks off the 30 states are
    /// [`Model::derivative_with`]'s bit for bit and the rotor rates are 0.
    /// Returns (ẋ, the rotor states' rates as a [`RotorState`], aux).
    pub fn plant_derivative(
        &self,
        plant: &PlantState,
        u: &Input,
        wind_ned: &Vector3<f64>,
        inflow: InflowMode,
        drive: &DriveCommand,
    ) -> Result<(State, RotorState, Aux), ModelError> {
        if !plant.rotor.omega_rad_s.is_finite() || !plant.rotor.governor_integral.is_finite() {
            return Err(ModelError::NonFinite {
                what: "state",
                name: "omega_rad_s",
                value: plant.rotor.omega_rad_s + plant.rotor.governor_integral,
            });
        }
        let ext = PlantInputs {
            rotor: &plant.rotor,
            drive,
            anchors: &plant.anchors,
        };
        let mut aux = Aux::default();
        let (xdot, rates) = self.eval(&plant.x, u, wind_ned, inflow, Some(ext), &mut aux)?;
        Ok((xdot, rates, aux))
    }

    /// After an integration step of the plant: the friction anchors follow
    /// ([`Anchors::update`]); nothing with the landing gear off.
    pub fn update_anchors(&self, plant: &mut PlantState) {
        if self.params.landing_gear.is_enabled() {
            plant.anchors.update(
                &self.params.landing_gear,
                &self.ground.plane,
                &self.ground.points_body_m,
                &plant.x,
            );
        }
    }

    /// The Bergen Industrial Twin with a preset.
    pub fn bergen_twin(preset: Preset) -> Model {
        Model::new(Params::bergen_twin(), preset.options())
    }

    /// The parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The options.
    pub fn options(&self) -> &ModelOptions {
        &self.options
    }

    /// ẋ = f(x, u, wind_ned) with converged inflow. `wind_ned` is the
    /// air-mass velocity in NED (m/s, where the air moves to).
    pub fn derivative(
        &self,
        x: &State,
        u: &Input,
        wind_ned: &Vector3<f64>,
    ) -> Result<(State, Aux), ModelError> {
        self.derivative_with(x, u, wind_ned, InflowMode::Converged)
    }

    /// ẋ = f(x, u, wind_ned) with a chosen inflow mode. With the ground
    /// effect on, its factor at the hub's height enters the inflow; the
    /// landing gear and the drivetrain need the plant's extra states and
    /// enter only [`Model::plant_derivative`] (Ω is the constant
    /// `main_rotor.omega_rad_s` here).
    pub fn derivative_with(
        &self,
        x: &State,
        u: &Input,
        wind_ned: &Vector3<f64>,
        inflow: InflowMode,
    ) -> Result<(State, Aux), ModelError> {
        let mut aux = Aux::default();
        let xdot = self.derivative_into(x, u, wind_ned, inflow, &mut aux)?;
        Ok((xdot, aux))
    }

    /// [`Model::derivative_with`] writing the auxiliary outputs into `aux`
    /// (every field; unspecified after an error) instead of returning them:
    /// for integration loops, which keep one [`Aux`] of a step and would
    /// otherwise copy the large struct out of each evaluation.
    pub fn derivative_into(
        &self,
        x: &State,
        u: &Input,
        wind_ned: &Vector3<f64>,
        inflow: InflowMode,
        aux: &mut Aux,
    ) -> Result<State, ModelError> {
        self.eval(x, u, wind_ned, inflow, None, aux)
            .map(|(xdot, _)| xdot)
    }

    #[allow(clippy::too_many_lines)] // the blocks of Figure 4.4 in data-flow order in one hot function (no call overhead, no allocation)
    fn eval(
        &self,
        x: &State,
        u: &Input,
        wind_ned: &Vector3<f64>,
        inflow: InflowMode,
        ext: Option<PlantInputs<'_>>,
        aux: &mut Aux,
    ) -> Result<(State, RotorState), ModelError> {
        check_finite(x, u, wind_ned)?;
        let p = &self.params;
        let geo = &p.geometry;
        // Rotor speed: the constant Ω, or the drivetrain's state (evaluated
        // at no less than the aerodynamic floor, the rotors' forces scaled by
        // (Ω/Ω_eval)² below it).
        let drive_on = p.drivetrain.is_enabled() && ext.is_some();
        let (c_var, omega_now, aero_scale);
        let c = if let (true, Some(e)) = (drive_on, ext.as_ref()) {
            let w = e.rotor.omega_rad_s.max(0.0);
            let w_eval = w.max(p.drivetrain.aero_floor_rad_s);
            omega_now = w;
            aero_scale = (w / w_eval) * (w / w_eval);
            if w_eval == p.main_rotor.omega_rad_s {
                &self.c
            } else {
                c_var = Consts::new(p, &self.options, w_eval);
                &c_var
            }
        } else {
            omega_now = p.main_rotor.omega_rad_s;
            aero_scale = 1.0;
            &self.c
        };
        let mr_at;
        let mr = if c.omega_rad_s == p.main_rotor.omega_rad_s {
            &p.main_rotor
        } else {
            mr_at = crate::params::MainRotor {
                omega_rad_s: c.omega_rad_s,
                ..p.main_rotor
            };
            &mr_at
        };
        let (phi, theta, psi) = (x[ix::PHI], x[ix::THETA], x[ix::PSI]);
        let trig = EulerTrig::new(phi, theta, psi);
        if trig.ct.abs() < 1e-9 {
            return Err(ModelError::GimbalLock { theta_rad: theta });
        }
        let v_body = Vector3::new(x[ix::U], x[ix::V], x[ix::W]);
        let omega = Vector3::new(x[ix::P], x[ix::Q], x[ix::R]);
        let (pr, qr, rr) = (omega.x, omega.y, omega.z);
        let mut xdot = State::zeros();
        *aux = Aux::default();

        // Actuators (5.1)–(5.4), (D.16)–(D.23).
        for (ch, (&pos, &rate)) in [ix::THETA0, ix::A1_SWASH, ix::B1_SWASH, ix::THETA_TR]
            .iter()
            .zip(
                [
                    ix::THETA0_DOT,
                    ix::A1_SWASH_DOT,
                    ix::B1_SWASH_DOT,
                    ix::THETA_TR_DOT,
                ]
                .iter(),
            )
            .enumerate()
        {
            let (d_pos, d_rate) = servo_derivative(&p.servos[ch], u[ch], x[pos], x[rate]);
            xdot[pos] = d_pos;
            xdot[rate] = d_rate;
        }
        debug_assert_eq!(iu::S_COL, 0);

        // Aerodynamic velocity (DESIGN.md wind convention; thesis (14.46) adds it).
        let ned_from_body = trig.ned_from_body();
        let v_air = v_body + c.wind_sign * (ned_from_body.transpose() * wind_ned);
        // Hub velocities (D.4)–(D.6) and advance ratios (D.7)–(D.9).
        let hub = Vector3::new(
            v_air.x - qr * geo.kappa_v_m,
            v_air.y + pr * geo.kappa_v_m - rr * geo.kappa_h_m,
            v_air.z + qr * geo.kappa_h_m,
        );
        let mu = hub / c.tip_speed;
        aux.mu_mr = mu;

        // Main-rotor pitch inputs: Bell-Hiller mixing (4.3), (D.26)/(D.27).
        let (a1sb, b1sb) = (x[ix::A1SB], x[ix::B1SB]);
        let a1_swash = x[ix::A1_SWASH];
        let b1_swash = x[ix::B1_SWASH];
        let a1_mr = mr.bell_factor * a1_swash - mr.hiller_factor * b1sb;
        let b1_mr = mr.bell_factor * b1_swash - mr.hiller_factor * a1sb;
        let flap = Vector3::new(x[ix::A0], x[ix::A1], x[ix::B1]);
        let flap_rate = Vector3::new(x[ix::A0_DOT], x[ix::A1_DOT], x[ix::B1_DOT]);
        let bi = blade_integrals(
            &c.mr_grid,
            &BladeInputs {
                omega_rad_s: mr.omega_rad_s,
                hinge_offset_m: mr.hinge_offset_m,
                hub_u_m_s: hub.x,
                hub_v_m_s: hub.y,
                lambda_speed_m_s: c.tip_speed,
                p_rad_s: pr,
                q_rad_s: qr,
                flap_rad: flap,
                flap_rate_rad_s: flap_rate,
                theta0_rad: x[ix::THETA0],
                cyclic_a_rad: a1_mr,
                cyclic_b_rad: b1_mr,
                twist_rad_per_m: mr.twist_rad / mr.radius_m,
                k1: mr.pitch_flap_coupling,
                lift_k: c.lift_k,
                drag_k: c.drag_k,
            },
        );
        let b = mr.blades;
        // Inflow (7.29)–(7.33): C_T = b⟨∫dL⟩/(ρπR²(ΩR)²) is affine in λ.
        let mr_problem = InflowProblem {
            mu_inplane2: mu.x * mu.x + mu.y * mu.y,
            mu_axial: mu.z,
            ct0: b * bi.lift.0 / c.ct_den,
            ct1: b * bi.lift.1 / c.ct_den,
        };
        // Tail rotor frame velocities (D.10)–(D.12) and advance ratios (D.13)–(D.15).
        let v_tr = Vector3::new(
            v_air.x - qr * geo.kappa_v_tr_m,
            v_air.y + pr * geo.kappa_v_tr_m - rr * geo.kappa_h_tr_m,
            v_air.z + qr * geo.kappa_h_tr_m,
        );
        let mu_tr = tail_rotor::advance_ratios(&c.tr, &v_tr);
        aux.mu_tr = mu_tr;
        let theta_tr = x[ix::THETA_TR];
        let tr_problem = tail_rotor::inflow_problem(&c.tr, &mu_tr, theta_tr, pr, rr);

        // Ground effect (Cheeseman–Bennett): the induced velocity is k_G
        // times momentum theory's at the same thrust (crate::ground_effect).
        // With λ' = μz − λi the out-of-ground-effect ratio and λ = μz − k_G·λi,
        // (7.33) in λ' is the same affine problem with C_T0' = C_T0 + C_T1(1−k)μz
        // and C_T1' = k·C_T1; λ = (1−k)μz + k·λ'.
        let ge = if p.ground_effect.is_enabled() {
            let hub_b = Vector3::new(-geo.kappa_h_m, 0.0, -geo.kappa_v_m);
            let hub_ned = Vector3::new(x[ix::X], x[ix::Y], x[ix::Z]) + ned_from_body * hub_b;
            let (k, _) = crate::ground_effect::inflow_factor(
                self.ground.plane.height_m(&hub_ned),
                mr.radius_m,
                p.ground_effect.min_height_ratio,
            );
            aux.ground_effect_factor = k;
            Some((k, (1.0 - k) * mr_problem.mu_axial))
        } else {
            None
        };
        let mr_solve = match ge {
            Some((k, shift)) => InflowProblem {
                ct0: mr_problem.ct0 + mr_problem.ct1 * shift,
                ct1: k * mr_problem.ct1,
                ..mr_problem
            },
            None => mr_problem,
        };
        let to_prime = |l: f64| match ge {
            Some((k, shift)) => (l - shift) / k,
            None => l,
        };
        let from_prime = |l: f64| match ge {
            Some((k, shift)) => shift + k * l,
            None => l,
        };
        let (lam_flap, lam, lam_tr) = match inflow {
            InflowMode::Converged | InflowMode::ConvergedFrom { .. } => {
                let (h_mr, h_tr) = match inflow {
                    InflowMode::ConvergedFrom {
                        lambda_mr_hint,
                        lambda_tr_hint,
                    } => (Some(to_prime(lambda_mr_hint)), Some(lambda_tr_hint)),
                    _ => (None, None),
                };
                let s = mr_solve
                    .solve_from(h_mr)
                    .map_err(|source| ModelError::Inflow {
                        rotor: "main rotor",
                        source,
                    })?;
                let st = tr_problem
                    .solve_from(h_tr)
                    .map_err(|source| ModelError::Inflow {
                        rotor: "tail rotor",
                        source,
                    })?;
                aux.inflow_iterations = [s.iterations, st.iterations];
                aux.inflow_residual = [s.residual, st.residual];
                let l = from_prime(s.lambda);
                (l, l, st.lambda)
            }
            InflowMode::ThesisIteration {
                lambda_mr_in,
                lambda_tr_in,
                iterations,
            } => {
                if iterations == 0 {
                    return Err(ModelError::ZeroInflowIterations);
                }
                let l_prime = mr_solve.thesis_iterate(to_prime(lambda_mr_in), iterations);
                let l = from_prime(l_prime);
                let lt = tr_problem.thesis_iterate(lambda_tr_in, iterations);
                aux.inflow_iterations = [iterations, iterations];
                aux.inflow_residual = [mr_solve.residual(l_prime), tr_problem.residual(lt)];
                if !(l.is_finite() && lt.is_finite()) {
                    let source = InflowError::NoConvergence {
                        iterations,
                        residual: f64::NAN,
                    };
                    let rotor = if l.is_finite() {
                        "tail rotor"
                    } else {
                        "main rotor"
                    };
                    return Err(ModelError::Inflow { rotor, source });
                }
                (lambda_mr_in, l, lt)
            }
        };
        aux.lambda_mr = lam;
        aux.lambda_mr_flap = lam_flap;
        aux.lambda_tr = lam_tr;
        aux.ct_mr = mr_problem.ct(lam);
        aux.ct_tr = tr_problem.ct(lam_tr);

        // Main-rotor forces and torques (7.7)–(7.9), (7.21), (7.22), (7.25).
        let ks_half = 0.5 * b * mr.spring_n_m_per_rad;
        let mut f_hub = Vector3::new(b * bi.fx.at(lam), b * bi.fy.at(lam), -b * bi.lift.at(lam));
        let mut t_hub = Vector3::new(b * bi.tx.at(lam), b * bi.ty.at(lam), b * bi.tz.at(lam));
        if aero_scale != 1.0 {
            f_hub *= aero_scale;
            t_hub *= aero_scale;
        }
        // the hinge springs' torque is not aerodynamic
        t_hub.x += ks_half * flap.z;
        t_hub.y += ks_half * flap.y;
        // (7.26): hub offset from the CM.
        let t_mr = Vector3::new(
            t_hub.x + f_hub.y * geo.kappa_v_m,
            t_hub.y - f_hub.x * geo.kappa_v_m + f_hub.z * geo.kappa_h_m,
            t_hub.z - f_hub.y * geo.kappa_h_m,
        );
        aux.force_mr_hub_n = f_hub;
        aux.torque_mr_hub_nm = t_hub;
        aux.torque_mr_body_nm = t_mr;
        let mut vi = hub.z - lam * c.tip_speed;
        // Tail rotor (D.39)–(D.43).
        let mut f_tr = tail_rotor::thrust_y(&c.tr, &mu_tr, theta_tr, pr, rr, lam_tr);
        let mut tq_tr = tail_rotor::torque_y(&c.tr, &mu_tr, theta_tr, pr, rr, lam_tr);
        let mut vi_tr = v_tr.y - lam_tr * c.tr.tip_speed;
        if aero_scale != 1.0 {
            let s = aero_scale.sqrt();
            vi = hub.z + (vi - hub.z) * s;
            vi_tr = v_tr.y + (vi_tr - v_tr.y) * s;
            f_tr *= aero_scale;
            tq_tr *= aero_scale;
        }
        aux.vi_mr_m_s = vi;
        let t_tr = tail_rotor::body_torque(f_tr, tq_tr, geo.kappa_v_tr_m, geo.kappa_h_tr_m);
        aux.force_tr_y_n = f_tr;
        aux.torque_tr_body_nm = t_tr;
        aux.vi_tr_m_s = vi_tr;

        // Drag (7.57)–(7.64).
        let d = drag(
            &p.fuselage,
            geo,
            p.environment.rho_kg_m3,
            &v_air,
            qr,
            vi,
            v_tr.y,
            vi_tr,
            p.tail_rotor.fin_area_ratio,
            self.options.front_plane_q.sign(),
        );
        aux.drag = d;

        // The rotors' load at the main shaft: the drag torques opposing
        // the rotation, Q_mr = −hτz and G·Q_tr with Q_tr = tτy·(sign of the
        // tail rotor's spin, −1: tτy < 0 is drag in hover).
        let load = -t_hub.z - p.tail_rotor.gear_ratio * tq_tr;
        aux.rotor_load_n_m = load;
        aux.omega_rad_s = omega_now;
        let mut rotor_rates = RotorState {
            omega_rad_s: 0.0,
            governor_integral: 0.0,
        };

        // Summation (8.3), (8.5).
        let m = p.body.mass_kg;
        let grav = m * trig.gravity_body(p.environment.g_m_s2);
        let mut force = f_hub + Vector3::new(0.0, f_tr, 0.0) + d.force_body_n + grav;
        let mut torque = t_mr + t_tr + d.torque_body_nm;
        if let (true, Some(e)) = (drive_on, ext.as_ref()) {
            let (w_dot, i_dot, thr) =
                crate::drivetrain::derivative(&p.drivetrain, e.drive, e.rotor, load);
            rotor_rates = RotorState {
                omega_rad_s: w_dot,
                governor_integral: i_dot,
            };
            aux.throttle = thr;
            // the engine's reaction: hτz − J Ω̇ about the shaft (body z)
            torque.z -= p.drivetrain.inertia_kg_m2 * w_dot;
        }
        if let (true, Some(e)) = (p.landing_gear.is_enabled(), ext.as_ref()) {
            let cw = crate::landing_gear::contact_wrench(
                &p.landing_gear,
                &self.ground.plane,
                &self.ground.points_body_m,
                x,
                e.anchors,
            );
            force += cw.force_body_n;
            torque += cw.torque_body_nm;
            aux.contact = cw;
        }
        aux.force_gravity_body_n = grav;
        aux.force_total_body_n = force;
        aux.torque_total_body_nm = torque;

        // Rigid body (9.8), (9.14), (9.21), (9.22).
        let v_dot = linear_accel(&force, m, &v_body, &omega);
        let w_dot = angular_accel(&torque, &c.inertia, &omega);
        let e_dot = trig.euler_rates(&omega);
        let pos_dot = ned_from_body * v_body;
        for i in 0..3 {
            xdot[ix::X + i] = pos_dot[i];
            xdot[ix::PHI + i] = e_dot[i];
            xdot[ix::U + i] = v_dot[i];
            xdot[ix::P + i] = w_dot[i];
        }

        // Flapping (6.47)/(6.53) by harmonic balance (flapping module).
        // The body normal torque (6.37)–(6.40), τbn = mb·(hz̈ − hẋ·q + hẏ·p), with
        // the inertial hub velocities (D.4)–(D.5) without wind (MODEL.md §4). Its
        // velocity-product part −hẋ·q + hẏ·p needs no acceleration and is in
        // both presets; the hub normal acceleration hz̈ = ẇ + q̇·κh and the
        // body angular-acceleration torques (6.36) only with `flap_accel`
        // (the thesis implementation dropped exactly these: MODEL.md §11 item 3).
        let hx_in = v_body.x - qr * geo.kappa_v_m;
        let hy_in = v_body.y + pr * geo.kappa_v_m - rr * geo.kappa_h_m;
        let velocity_product = -hx_in * qr + hy_in * pr;
        let body = if self.options.flap_accel {
            let hz_ddot = v_dot.z + w_dot.y * geo.kappa_h_m;
            FlapBody {
                p_rad_s: pr,
                q_rad_s: qr,
                p_dot_rad_s2: w_dot.x,
                q_dot_rad_s2: w_dot.y,
                normal_accel_m_s2: hz_ddot + velocity_product,
            }
        } else {
            FlapBody {
                p_rad_s: pr,
                q_rad_s: qr,
                p_dot_rad_s2: 0.0,
                q_dot_rad_s2: 0.0,
                normal_accel_m_s2: velocity_product,
            }
        };
        let aero = [
            bi.flap_torque[0].at(lam_flap),
            bi.flap_torque[1].at(lam_flap),
            bi.flap_torque[2].at(lam_flap),
        ];
        let a_ddot = main_rotor_accel(
            mr.omega_rad_s,
            mr.hinge_offset_m,
            mr.blade_inertia_kg_m2,
            mr.blade_mass_moment_kg_m,
            mr.spring_n_m_per_rad,
            &flap,
            &flap_rate,
            aero,
            &body,
        );
        let sb = &p.stabilizer_bar;
        let sb_flap = Vector2::new(a1sb, b1sb);
        let sb_rate = Vector2::new(x[ix::A1SB_DOT], x[ix::B1SB_DOT]);
        // Stabilizer bar (6.53): the closed form of MODEL.md §6.4 is exact for
        // the paddles (no twist, no δ3, no hinge); `tests::stabilizer_bar_closed_form_is_the_quadrature`
        // checks it against the blade-element quadrature used for the main rotor.
        let sbc = StabilizerBarCoefficients::new(
            mr.omega_rad_s,
            c.a_cal_sb,
            sb.inner_radius_m,
            sb.outer_radius_m,
            c.sb_scale * mr.radius_m,
            mu.x,
            mu.y,
            &body,
        );
        let sb_ddot = sbc.accel(
            &sb_flap,
            &sb_rate,
            &Vector2::new(a1_swash, b1_swash),
            lam_flap,
        );
        for i in 0..3 {
            xdot[ix::A0 + i] = flap_rate[i];
            xdot[ix::A0_DOT + i] = a_ddot[i];
        }
        xdot[ix::A1SB] = sb_rate.x;
        xdot[ix::B1SB] = sb_rate.y;
        xdot[ix::A1SB_DOT] = sb_ddot.x;
        xdot[ix::B1SB_DOT] = sb_ddot.y;
        Ok((xdot, rotor_rates))
    }
}

/// Check the outputs of a derivative evaluation for NaN and infinity: every
/// component of ẋ and every [`Aux`] quantity. The derivative itself does not
/// (it stays allocation- and branch-light for simulation loops); callers that
/// hand results on (`helicon eval`, trim, linearization) call this and get a
/// typed error naming the first non-finite quantity.
pub fn check_output(xdot: &State, aux: &Aux) -> Result<(), ModelError> {
    for i in 0..NX {
        if !xdot[i].is_finite() {
            return Err(ModelError::NonFiniteOutput {
                what: "derivative of",
                name: STATE_NAMES[i],
                value: xdot[i],
            });
        }
    }
    let d = &aux.drag;
    let scalars = [
        ("lambda_mr", aux.lambda_mr),
        ("lambda_tr", aux.lambda_tr),
        ("lambda_mr_flap", aux.lambda_mr_flap),
        ("vi_mr_m_s", aux.vi_mr_m_s),
        ("vi_tr_m_s", aux.vi_tr_m_s),
        ("ct_mr", aux.ct_mr),
        ("ct_tr", aux.ct_tr),
        ("force_tr_y_n", aux.force_tr_y_n),
    ];
    let vectors = [
        ("mu_mr", aux.mu_mr),
        ("mu_tr", aux.mu_tr),
        ("force_mr_hub_n", aux.force_mr_hub_n),
        ("torque_mr_hub_nm", aux.torque_mr_hub_nm),
        ("torque_mr_body_nm", aux.torque_mr_body_nm),
        ("torque_tr_body_nm", aux.torque_tr_body_nm),
        ("force_drag_body_n", d.force_body_n),
        ("torque_drag_body_nm", d.torque_body_nm),
        ("force_gravity_body_n", aux.force_gravity_body_n),
        ("force_total_body_n", aux.force_total_body_n),
        ("torque_total_body_nm", aux.torque_total_body_nm),
    ];
    let bad = |name, value| ModelError::NonFiniteOutput {
        what: "aux",
        name,
        value,
    };
    for (name, value) in scalars {
        if !value.is_finite() {
            return Err(bad(name, value));
        }
    }
    for (name, v) in vectors {
        if let Some(value) = v.iter().copied().find(|c| !c.is_finite()) {
            return Err(bad(name, value));
        }
    }
    Ok(())
}

fn check_finite(x: &State, u: &Input, wind: &Vector3<f64>) -> Result<(), ModelError> {
    for i in 0..NX {
        if !x[i].is_finite() {
            return Err(ModelError::NonFinite {
                what: "state",
                name: STATE_NAMES[i],
                value: x[i],
            });
        }
    }
    for i in 0..4 {
        if !u[i].is_finite() {
            return Err(ModelError::NonFinite {
                what: "input",
                name: INPUT_NAMES[i],
                value: u[i],
            });
        }
    }
    const W: [&str; 3] = ["wind_n", "wind_e", "wind_d"];
    for i in 0..3 {
        if !wind[i].is_finite() {
            return Err(ModelError::NonFinite {
                what: "wind",
                name: W[i],
                value: wind[i],
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flapping::stabilizer_bar_accel;

    #[test]
    fn stabilizer_bar_closed_form_is_the_quadrature() {
        // The model uses the §6.4 closed form for the paddles; the blade-element
        // quadrature of `rotor` (exact for these integrands) must agree to round-off.
        let p = Params::bergen_twin();
        let sb = p.stabilizer_bar;
        let om = p.main_rotor.omega_rad_s;
        let rho = p.environment.rho_kg_m3;
        let grid = Grid::new(sb.inner_radius_m, sb.outer_radius_m);
        for (scale, hu, hv, lam, pr, qr) in [
            (0.65, 7.0, -2.0, -0.03, 0.3, -0.2),
            (1.0, -4.0, 9.0, 0.01, -0.5, 0.7),
        ] {
            let flap = Vector2::new(0.01, -0.02);
            let rate = Vector2::new(0.4, -0.3);
            let (a1, b1) = (0.02, -0.015);
            let body = FlapBody {
                p_rad_s: pr,
                q_rad_s: qr,
                p_dot_rad_s2: 0.7,
                q_dot_rad_s2: -0.4,
                normal_accel_m_s2: 0.0,
            };
            let bi = blade_integrals(
                &grid,
                &BladeInputs {
                    omega_rad_s: om,
                    hinge_offset_m: 0.0,
                    hub_u_m_s: scale * hu,
                    hub_v_m_s: scale * hv,
                    lambda_speed_m_s: scale * om * p.main_rotor.radius_m,
                    p_rad_s: pr,
                    q_rad_s: qr,
                    flap_rad: Vector3::new(0.0, flap.x, flap.y),
                    flap_rate_rad_s: Vector3::new(0.0, rate.x, rate.y),
                    theta0_rad: 0.0,
                    cyclic_a_rad: a1,
                    cyclic_b_rad: b1,
                    twist_rad_per_m: 0.0,
                    k1: 0.0,
                    lift_k: 0.5 * rho * sb.chord_m * sb.lift_slope_per_rad,
                    drag_k: 0.0,
                },
            );
            let quad = stabilizer_bar_accel(
                om,
                sb.paddle_inertia_kg_m2,
                &flap,
                &rate,
                [bi.flap_torque[1].at(lam), bi.flap_torque[2].at(lam)],
                &body,
            );
            let a_cal = rho * sb.lift_slope_per_rad * sb.chord_m / (2.0 * sb.paddle_inertia_kg_m2);
            let mu = (
                hu / (om * p.main_rotor.radius_m),
                hv / (om * p.main_rotor.radius_m),
            );
            let cf = StabilizerBarCoefficients::new(
                om,
                a_cal,
                sb.inner_radius_m,
                sb.outer_radius_m,
                scale * p.main_rotor.radius_m,
                mu.0,
                mu.1,
                &body,
            )
            .accel(&flap, &rate, &Vector2::new(a1, b1), lam);
            // terms are ~Ω²𝒜·n3·(a) ≈ 1e4·0.02 = 200 rad/s²: 1e-12 relative → 1e-9
            assert!((quad - cf).norm() < 1e-9, "{quad:?} vs {cf:?}");
        }
    }
}
