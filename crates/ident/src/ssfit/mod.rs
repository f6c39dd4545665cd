//! Linear state-space fits to one or several frequency responses at once,
//! with the coherence-weighted cost of [`crate::cost`]:
//!
//! ẋ = A x + B u, y = C x + D u, input i delayed by τ_i,
//!
//! T_{o,i}(jω) = [C (jωI − A)⁻¹ B + D]_{o,i} · e^{−jωτ_i}.
//!
//! Every entry of A, B, C, D and every delay is either fixed (a number) or a
//! named free parameter ([`Cell`]); a name may appear in several entries (a
//! stability derivative shared by two equations). Parameters may carry
//! bounds. Levenberg–Marquardt minimises the mean of the responses' costs
//! J_r (CIFER reports the average over the responses), with the analytic
//! Jacobian: for a cell (i, k) of A, ∂T/∂A_ik = [C(jωI − A)⁻¹]_{o,i}
//! [(jωI − A)⁻¹B]_{k,u}, the same two solves that give T, so it costs one
//! extra linear solve per point and carries no step-size error. Bounds are
//! kept by the transformations of MINUIT (θ = lo + (hi − lo)(sin φ + 1)/2
//! for two bounds, θ = lo − 1 + √(φ² + 1) for one), the accuracy being
//! computed in the parameters themselves.
//!
//! The model and its responses can be read from TOML ([`SsSpec`]; see
//! docs/ident.md for the format); errors name the file and the field.

use crate::cost::{CostOptions, Points, percent, select, separable_accuracy};
use crate::error::{IdentError, Result};
use crate::frf::Frf;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rustfft::num_complex::Complex64;

/// CIFER's guideline for the Cramér–Rao bound, % of the parameter.
pub const CRAMER_RAO_GUIDELINE_PCT: f64 = 20.0;
/// CIFER's guideline for the insensitivity, % of the parameter.
pub const INSENSITIVITY_GUIDELINE_PCT: f64 = 10.0;

/// One entry of a model matrix or one input delay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cell {
    /// A fixed number.
    Fixed(f64),
    /// The free parameter of this index in [`SsModel::parameters`].
    Free(usize),
}

/// A free parameter: its name, start value and optional bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeParameter {
    /// Name (unique in the model).
    pub name: String,
    /// Start value (finite; strictly inside the bounds).
    pub start: f64,
    /// Lower bound.
    pub min: Option<f64>,
    /// Upper bound.
    pub max: Option<f64>,
}

/// A linear model with chosen free entries.
#[derive(Debug, Clone, PartialEq)]
pub struct SsModel {
    /// State names (n).
    pub states: Vec<String>,
    /// Input names (m).
    pub inputs: Vec<String>,
    /// Output names (p).
    pub outputs: Vec<String>,
    /// A, n rows of n cells.
    pub a: Vec<Vec<Cell>>,
    /// B, n rows of m cells.
    pub b: Vec<Vec<Cell>>,
    /// C, p rows of n cells.
    pub c: Vec<Vec<Cell>>,
    /// D, p rows of m cells.
    pub d: Vec<Vec<Cell>>,
    /// Input delays, s, one per input.
    pub delay_s: Vec<Cell>,
    /// The free parameters.
    pub parameters: Vec<FreeParameter>,
}

/// The numeric matrices of a model for given parameter values.
#[derive(Debug, Clone, PartialEq)]
pub struct Matrices {
    /// A (n × n).
    pub a: DMatrix<f64>,
    /// B (n × m).
    pub b: DMatrix<f64>,
    /// C (p × n).
    pub c: DMatrix<f64>,
    /// D (p × m).
    pub d: DMatrix<f64>,
    /// Input delays, s.
    pub delay_s: Vec<f64>,
}

/// The factors of one frequency: X = (jωI − A)⁻¹B (n × m), Y = C(jωI − A)⁻¹
/// (p × n) and the delay-free response G = C X + D.
struct Factors {
    x: DMatrix<Complex64>,
    y: DMatrix<Complex64>,
    g: DMatrix<Complex64>,
}

fn cplx(m: &DMatrix<f64>) -> DMatrix<Complex64> {
    m.map(|v| Complex64::new(v, 0.0))
}

impl Matrices {
    /// (jωI − A), or `None` when ω is (numerically) an eigenvalue.
    fn resolvent_lu(&self, omega_rad_s: f64) -> Option<nalgebra::LU<Complex64, Dyn, Dyn>> {
        let n = self.a.nrows();
        let s = Complex64::new(0.0, omega_rad_s);
        let m = DMatrix::from_fn(n, n, |i, j| {
            (if i == j { s } else { Complex64::new(0.0, 0.0) }) - self.a[(i, j)]
        });
        let lu = m.lu();
        lu.is_invertible().then_some(lu)
    }

    fn factors(&self, omega_rad_s: f64) -> Option<Factors> {
        let lu = self.resolvent_lu(omega_rad_s)?;
        let x = lu.solve(&cplx(&self.b))?;
        // Yᵀ = (jωI − A)⁻ᵀ Cᵀ: solve with the transposed matrix.
        let n = self.a.nrows();
        let s = Complex64::new(0.0, omega_rad_s);
        let mt = DMatrix::from_fn(n, n, |i, j| {
            (if i == j { s } else { Complex64::new(0.0, 0.0) }) - self.a[(j, i)]
        });
        let y = mt.lu().solve(&cplx(&self.c).transpose())?.transpose();
        let g = cplx(&self.c) * &x + cplx(&self.d);
        Some(Factors { x, y, g })
    }

    /// The response matrix (p × m) at ω: [C (jωI − A)⁻¹ B + D] with column i
    /// times e^{−jωτ_i} (a linear solve, no inverse). `None` when jω is an
    /// eigenvalue of A or the result is not finite.
    pub fn response(&self, omega_rad_s: f64) -> Option<DMatrix<Complex64>> {
        let lu = self.resolvent_lu(omega_rad_s)?;
        let x = lu.solve(&cplx(&self.b))?;
        let mut g = cplx(&self.c) * x + cplx(&self.d);
        for (i, tau) in self.delay_s.iter().enumerate() {
            let e = Complex64::new(0.0, -omega_rad_s * tau).exp();
            g.column_mut(i).iter_mut().for_each(|v| *v *= e);
        }
        g.iter()
            .all(|v| v.re.is_finite() && v.im.is_finite())
            .then_some(g)
    }
}

/// Where a free parameter appears.
#[derive(Debug, Clone, Copy)]
enum Place {
    A(usize, usize),
    B(usize, usize),
    C(usize, usize),
    D(usize, usize),
    Delay(usize),
}

impl SsModel {
    /// Check the dimensions, the parameter references, the finiteness of
    /// the fixed cells and of the starts, the bounds (min < max, the start
    /// strictly inside) and that every parameter is used and named once.
    /// The error names the field (`A[1][2]`, `parameter[0].start`, …).
    pub fn check(&self) -> Result<()> {
        self.check_fields()
            .map_err(|(field, rule)| IdentError::Invalid {
                field,
                value: String::new(),
                rule,
            })
    }

    #[allow(clippy::too_many_lines, reason = "one linear list of checks")]
    fn check_fields(&self) -> std::result::Result<(), (String, String)> {
        let (n, m, p) = (self.states.len(), self.inputs.len(), self.outputs.len());
        for (what, names) in [
            ("states", &self.states),
            ("inputs", &self.inputs),
            ("outputs", &self.outputs),
        ] {
            if names.is_empty() {
                return Err((what.into(), "at least one name is needed".into()));
            }
            for (i, s) in names.iter().enumerate() {
                if names[..i].contains(s) {
                    return Err((format!("{what}[{i}]"), format!("`{s}` named twice")));
                }
            }
        }
        let np = self.parameters.len();
        for (name, mat, rows, cols) in [
            ("A", &self.a, n, n),
            ("B", &self.b, n, m),
            ("C", &self.c, p, n),
            ("D", &self.d, p, m),
        ] {
            if mat.len() != rows {
                return Err((name.into(), format!("{} rows, {rows} expected", mat.len())));
            }
            for (i, row) in mat.iter().enumerate() {
                if row.len() != cols {
                    return Err((
                        format!("{name}[{i}]"),
                        format!("{} cells, {cols} expected", row.len()),
                    ));
                }
                for (j, c) in row.iter().enumerate() {
                    check_cell(c, np).map_err(|r| (format!("{name}[{i}][{j}]"), r))?;
                }
            }
        }
        if self.delay_s.len() != m {
            return Err((
                "delay_s".into(),
                format!("{} delays for {m} inputs", self.delay_s.len()),
            ));
        }
        for (i, c) in self.delay_s.iter().enumerate() {
            check_cell(c, np).map_err(|r| (format!("delay_s[{i}]"), r))?;
            if let Cell::Fixed(v) = c
                && *v < 0.0
            {
                return Err((format!("delay_s[{i}]"), format!("{v}: must be ≥ 0")));
            }
        }
        let places = self.places();
        for (k, q) in self.parameters.iter().enumerate() {
            let f = |s: &str| format!("parameter[{k}].{s}");
            if self.parameters[..k].iter().any(|o| o.name == q.name) {
                return Err((f("name"), format!("`{}` declared twice", q.name)));
            }
            if places[k].is_empty() {
                return Err((
                    f("name"),
                    format!("`{}` appears in no matrix cell or delay", q.name),
                ));
            }
            if !q.start.is_finite() {
                return Err((f("start"), format!("{}: must be finite", q.start)));
            }
            for (s, b) in [("min", q.min), ("max", q.max)] {
                if b.is_some_and(|v| !v.is_finite()) {
                    return Err((f(s), "must be finite (leave it out for no bound)".into()));
                }
            }
            if let (Some(lo), Some(hi)) = (q.min, q.max)
                && lo >= hi
            {
                return Err((f("min"), format!("{lo} must be below max {hi}")));
            }
            if q.min.is_some_and(|lo| q.start <= lo) || q.max.is_some_and(|hi| q.start >= hi) {
                return Err((
                    f("start"),
                    format!(
                        "{} must be strictly inside the bounds [{}, {}]",
                        q.start,
                        q.min.map_or("-inf".into(), |v| v.to_string()),
                        q.max.map_or("inf".into(), |v| v.to_string())
                    ),
                ));
            }
        }
        Ok(())
    }

    /// For each parameter, the cells where it appears.
    fn places(&self) -> Vec<Vec<Place>> {
        let mut out = vec![Vec::new(); self.parameters.len()];
        let mut put = |c: &Cell, pl: Place| {
            if let Cell::Free(k) = c
                && let Some(v) = out.get_mut(*k)
            {
                v.push(pl);
            }
        };
        for (mat, mk) in [
            (&self.a, Place::A as fn(usize, usize) -> Place),
            (&self.b, Place::B),
            (&self.c, Place::C),
            (&self.d, Place::D),
        ] {
            for (i, row) in mat.iter().enumerate() {
                for (j, c) in row.iter().enumerate() {
                    put(c, mk(i, j));
                }
            }
        }
        for (i, c) in self.delay_s.iter().enumerate() {
            put(c, Place::Delay(i));
        }
        out
    }

    /// The start values of the parameters.
    pub fn start(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.start).collect()
    }

    /// The numeric matrices for the parameter values `theta` (in
    /// [`SsModel::parameters`] order). Errors on a wrong count or a
    /// non-finite value.
    pub fn matrices(&self, theta: &[f64]) -> Result<Matrices> {
        if theta.len() != self.parameters.len() || theta.iter().any(|v| !v.is_finite()) {
            return Err(IdentError::data(
                "parameters",
                format!(
                    "{} values for {} parameters (all must be finite)",
                    theta.len(),
                    self.parameters.len()
                ),
            ));
        }
        Ok(self.matrices_unchecked(theta))
    }

    fn matrices_unchecked(&self, theta: &[f64]) -> Matrices {
        let v = |c: &Cell| match c {
            Cell::Fixed(x) => *x,
            Cell::Free(k) => theta.get(*k).copied().unwrap_or(f64::NAN),
        };
        let mat = |m: &Vec<Vec<Cell>>, cols: usize| {
            DMatrix::from_fn(m.len(), cols, |i, j| m[i].get(j).map_or(f64::NAN, &v))
        };
        let (n, mi) = (self.states.len(), self.inputs.len());
        Matrices {
            a: mat(&self.a, n),
            b: mat(&self.b, mi),
            c: mat(&self.c, n),
            d: mat(&self.d, mi),
            delay_s: self.delay_s.iter().map(v).collect(),
        }
    }
}

fn check_cell(c: &Cell, np: usize) -> std::result::Result<(), String> {
    match c {
        Cell::Fixed(v) if !v.is_finite() => Err(format!("{v}: must be finite")),
        Cell::Free(k) if *k >= np => Err(format!("parameter {k} of {np}")),
        _ => Ok(()),
    }
}

/// One measured response to fit: the input and output indices in the
/// model, the estimate and the band used.
#[derive(Debug, Clone, PartialEq)]
pub struct Response {
    /// Input index in [`SsModel::inputs`].
    pub input: usize,
    /// Output index in [`SsModel::outputs`].
    pub output: usize,
    /// The estimate (with coherence).
    pub frf: Frf,
    /// Lowest frequency used, rad/s.
    pub omega_min_rad_s: f64,
    /// Highest frequency used, rad/s.
    pub omega_max_rad_s: f64,
}

/// A fitted parameter with its accuracy.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterEstimate {
    /// Name.
    pub name: String,
    /// Fitted value.
    pub value: f64,
    /// Cramér–Rao bound (one standard deviation); infinite when the responses
    /// do not determine the parameter (alone or in a combination with others).
    pub cramer_rao: f64,
    /// Cramér–Rao bound, % of the value.
    pub cramer_rao_pct: f64,
    /// Insensitivity, % of the value.
    pub insensitivity_pct: f64,
    /// Ways the parameter misses CIFER's guidelines (CR ≤ 20 %,
    /// insensitivity ≤ 10 %), or rests on a bound; empty when it meets them.
    pub flags: Vec<String>,
}

impl ParameterEstimate {
    /// Whether the responses determine the parameter
    /// ([`crate::cost::identifiable`]).
    pub fn identifiable(&self) -> bool {
        crate::cost::identifiable(self.cramer_rao_pct, self.insensitivity_pct)
    }
}

/// The cost of one response at the optimum.
#[derive(Debug, Clone, PartialEq)]
pub struct ResponseCost {
    /// Input name.
    pub input: String,
    /// Output name.
    pub output: String,
    /// J of this response.
    pub cost: f64,
    /// Points used (γ² above the threshold, inside the band).
    pub n_points: usize,
}

/// A fitted state-space model.
#[derive(Debug, Clone, PartialEq)]
pub struct SsFit {
    /// The parameters, in [`SsModel::parameters`] order.
    pub parameters: Vec<ParameterEstimate>,
    /// Parameter correlations (unit diagonal; NaN for a parameter the
    /// responses do not see).
    pub correlation: DMatrix<f64>,
    /// Cost per response.
    pub responses: Vec<ResponseCost>,
    /// The total cost: the mean of the responses' J.
    pub cost: f64,
    /// The identified matrices and delays.
    pub matrices: Matrices,
    /// Residual evaluations used by Levenberg–Marquardt.
    pub evaluations: usize,
}

impl SsFit {
    /// The fitted values.
    pub fn values(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.value).collect()
    }
}

/// The bound transformation of one parameter (MINUIT): internal φ ↔ θ.
#[derive(Debug, Clone, Copy)]
enum Bound {
    Free,
    Both(f64, f64),
    Lower(f64),
    Upper(f64),
}

impl Bound {
    fn of(p: &FreeParameter) -> Self {
        match (p.min, p.max) {
            (Some(lo), Some(hi)) => Bound::Both(lo, hi),
            (Some(lo), None) => Bound::Lower(lo),
            (None, Some(hi)) => Bound::Upper(hi),
            (None, None) => Bound::Free,
        }
    }

    /// θ(φ) and dθ/dφ.
    fn external(self, phi: f64) -> (f64, f64) {
        match self {
            Bound::Free => (phi, 1.0),
            Bound::Both(lo, hi) => (
                lo + (hi - lo) * (phi.sin() + 1.0) / 2.0,
                (hi - lo) / 2.0 * phi.cos(),
            ),
            Bound::Lower(lo) => {
                let r = (phi * phi + 1.0).sqrt();
                (lo - 1.0 + r, phi / r)
            }
            Bound::Upper(hi) => {
                let r = (phi * phi + 1.0).sqrt();
                (hi + 1.0 - r, -phi / r)
            }
        }
    }

    /// φ(θ) (θ strictly inside the bounds).
    fn internal(self, theta: f64) -> f64 {
        match self {
            Bound::Free => theta,
            Bound::Both(lo, hi) => (2.0 * (theta - lo) / (hi - lo) - 1.0)
                .clamp(-1.0, 1.0)
                .asin(),
            Bound::Lower(lo) => ((theta - lo + 1.0).powi(2) - 1.0).max(0.0).sqrt(),
            Bound::Upper(hi) => ((hi - theta + 1.0).powi(2) - 1.0).max(0.0).sqrt(),
        }
    }

    /// θ within 1e-6 of the bound's span (or of 1 for one bound) of a bound.
    fn at_bound(self, theta: f64) -> bool {
        match self {
            Bound::Free => false,
            Bound::Both(lo, hi) => {
                let tol = 1e-6 * (hi - lo);
                theta - lo < tol || hi - theta < tol
            }
            Bound::Lower(lo) => theta - lo < 1e-6,
            Bound::Upper(hi) => hi - theta < 1e-6,
        }
    }
}

/// The least-squares problem: residuals [mag, phase] per point, response by
/// response, each response's residuals scaled by 1/√(number of responses)
/// so that the sum of squares is the mean J.
struct Problem<'a> {
    model: &'a SsModel,
    places: &'a [Vec<Place>],
    bounds: &'a [Bound],
    data: &'a [(usize, usize, Points)],
    scale: f64,
    rows: usize,
    phi: DVector<f64>,
}

impl Problem<'_> {
    fn theta(&self) -> (Vec<f64>, Vec<f64>) {
        self.bounds
            .iter()
            .zip(self.phi.iter())
            .map(|(b, p)| b.external(*p))
            .unzip()
    }

    /// The residuals and, when asked, the Jacobian with respect to θ.
    fn evaluate(&self, with_jac: bool) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let (theta, _) = self.theta();
        let mats = self.model.matrices_unchecked(&theta);
        let np = theta.len();
        let mut r = DVector::zeros(self.rows);
        let mut jac = DMatrix::zeros(if with_jac { self.rows } else { 0 }, np);
        let mut row = 0;
        for (u, o, pts) in self.data {
            let (u, o) = (*u, *o);
            let tau = mats.delay_s[u];
            for (k, &w) in pts.omega.iter().enumerate() {
                let s = Complex64::new(0.0, w);
                let f = mats.factors(w)?;
                let g = f.g[(o, u)];
                let t = g * (-s * tau).exp();
                let (rm, rp) = pts.residuals(k, t);
                r[row] = self.scale * rm;
                r[row + 1] = self.scale * rp;
                if with_jac {
                    for (j, pl) in self.places.iter().enumerate() {
                        let mut dg = Complex64::new(0.0, 0.0);
                        let mut dlog = Complex64::new(0.0, 0.0);
                        for p in pl {
                            match *p {
                                Place::A(i, c) => dg += f.y[(o, i)] * f.x[(c, u)],
                                Place::B(i, c) if c == u => dg += f.y[(o, i)],
                                Place::C(i, c) if i == o => dg += f.x[(c, u)],
                                Place::D(i, c) if i == o && c == u => dg += 1.0,
                                Place::Delay(i) if i == u => dlog -= s,
                                _ => {}
                            }
                        }
                        let (jm, jp) = pts.jacobian(k, dlog + dg / g);
                        jac[(row, j)] = self.scale * jm;
                        jac[(row + 1, j)] = self.scale * jp;
                    }
                }
                row += 2;
            }
        }
        (r.iter().chain(jac.iter()).all(|v| v.is_finite())).then_some((r, jac))
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.phi.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.phi.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.evaluate(false).map(|(r, _)| r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let (_, dtheta) = self.theta();
        let (_, mut jac) = self.evaluate(true)?;
        for (j, d) in dtheta.iter().enumerate() {
            jac.column_mut(j).iter_mut().for_each(|v| *v *= d);
        }
        Some(jac)
    }
}

/// The cost of `model` at the parameter values `theta` on `responses`:
/// the total (the mean of the responses' J) and each response's J, over the
/// same points a fit uses. Errors as [`fit_ss`], and on a non-finite response.
pub fn cost_at(
    model: &SsModel,
    responses: &[Response],
    opts: &CostOptions,
    theta: &[f64],
) -> Result<(f64, Vec<f64>)> {
    model.check()?;
    model.matrices(theta)?;
    let data = prepare(model, responses, opts)?;
    let bounds = vec![Bound::Free; theta.len()];
    let problem = problem(
        model,
        &[],
        &bounds,
        &data,
        DVector::from_column_slice(theta),
    );
    let (r, _) = problem
        .evaluate(false)
        .ok_or_else(|| IdentError::Fit("non-finite model response".into()))?;
    let per = per_response(&r, &data);
    Ok((r.norm_squared(), per))
}

/// Each response's J from the stacked residuals.
fn per_response(r: &DVector<f64>, data: &[(usize, usize, Points)]) -> Vec<f64> {
    let mut row = 0;
    data.iter()
        .map(|(_, _, pts)| {
            let len = 2 * pts.omega.len();
            let j = r.rows(row, len).norm_squared() * data.len() as f64;
            row += len;
            j
        })
        .collect()
}

fn problem<'a>(
    model: &'a SsModel,
    places: &'a [Vec<Place>],
    bounds: &'a [Bound],
    data: &'a [(usize, usize, Points)],
    phi: DVector<f64>,
) -> Problem<'a> {
    Problem {
        model,
        places,
        bounds,
        data,
        scale: 1.0 / (data.len() as f64).sqrt(),
        rows: data.iter().map(|d| 2 * d.2.omega.len()).sum(),
        phi,
    }
}

/// Check the responses against the model and select their points.
fn prepare(
    model: &SsModel,
    responses: &[Response],
    opts: &CostOptions,
) -> Result<Vec<(usize, usize, Points)>> {
    if responses.is_empty() {
        return Err(IdentError::Fit("no response to fit".into()));
    }
    let mut data = Vec::with_capacity(responses.len());
    for (i, r) in responses.iter().enumerate() {
        if r.input >= model.inputs.len() || r.output >= model.outputs.len() {
            return Err(IdentError::Fit(format!(
                "response {i}: input {} and output {} of a model with {} inputs and {} outputs",
                r.input,
                r.output,
                model.inputs.len(),
                model.outputs.len()
            )));
        }
        let pts = select(&r.frf, opts, r.omega_min_rad_s, r.omega_max_rad_s);
        if pts.omega.is_empty() {
            return Err(IdentError::Fit(format!(
                "response {i} ({} → {}): no point with γ² > {} between {} and {} rad/s",
                model.inputs[r.input],
                model.outputs[r.output],
                opts.min_coherence,
                r.omega_min_rad_s,
                r.omega_max_rad_s
            )));
        }
        data.push((r.input, r.output, pts));
    }
    Ok(data)
}

/// Fit the free parameters of `model` to `responses` with the cost of
/// `opts` (the mean of the responses' J), from the model's start values.
/// Errors: an invalid model, a response naming an input or output the
/// model lacks, a response without points above the coherence threshold,
/// fewer residuals than parameters, a start where jω is an eigenvalue, a
/// non-finite or singular result.
pub fn fit_ss(model: &SsModel, responses: &[Response], opts: &CostOptions) -> Result<SsFit> {
    model.check()?;
    let data = prepare(model, responses, opts)?;
    let rows: usize = data.iter().map(|d| 2 * d.2.omega.len()).sum();
    let np = model.parameters.len();
    if rows <= np {
        return Err(IdentError::Fit(format!(
            "{rows} residuals for {np} parameters"
        )));
    }
    let places = model.places();
    let bounds: Vec<Bound> = model.parameters.iter().map(Bound::of).collect();
    let phi = DVector::from_iterator(
        np,
        bounds
            .iter()
            .zip(&model.parameters)
            .map(|(b, p)| b.internal(p.start)),
    );
    let problem = problem(model, &places, &bounds, &data, phi);
    if problem.evaluate(false).is_none() {
        return Err(IdentError::Fit(
            "the start gives a non-finite response (jω an eigenvalue of A?)".into(),
        ));
    }
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(400)
        .minimize(problem);
    if report.termination.was_usage_issue() {
        return Err(IdentError::Fit(format!("{:?}", report.termination)));
    }
    let (r, jac) = problem
        .evaluate(true)
        .ok_or_else(|| IdentError::Fit("non-finite residuals at the optimum".into()))?;
    let (theta, _) = problem.theta();
    let cost = r.norm_squared();
    let acc = separable_accuracy(&jac, cost)?;
    let costs = data
        .iter()
        .zip(per_response(&r, &data))
        .map(|((u, o, pts), j)| ResponseCost {
            input: model.inputs[*u].clone(),
            output: model.outputs[*o].clone(),
            cost: j,
            n_points: pts.omega.len(),
        })
        .collect();
    let cr_pct = percent(&acc.cramer_rao, &theta);
    let ins_pct = percent(&acc.insensitivity, &theta);
    let parameters = (0..np)
        .map(|j| {
            let mut flags = Vec::new();
            if !acc.cramer_rao[j].is_finite() {
                flags.push(
                    "not identifiable: the responses do not determine it (alone or with others)"
                        .to_string(),
                );
            } else if !crate::cost::identifiable(cr_pct[j], ins_pct[j]) {
                flags.push(format!(
                    "not identifiable: Cramér–Rao bound {:.3} %, insensitivity {:.3} % (≥ {} %: not even its sign is determined)",
                    cr_pct[j],
                    ins_pct[j],
                    crate::cost::NOT_IDENTIFIABLE_PCT
                ));
            } else {
                if cr_pct[j].is_nan() || cr_pct[j] > CRAMER_RAO_GUIDELINE_PCT {
                    flags.push(format!(
                        "Cramér–Rao bound {:.3} % > {CRAMER_RAO_GUIDELINE_PCT} %",
                        cr_pct[j]
                    ));
                }
                if ins_pct[j].is_nan() || ins_pct[j] > INSENSITIVITY_GUIDELINE_PCT {
                    flags.push(format!(
                        "insensitivity {:.3} % > {INSENSITIVITY_GUIDELINE_PCT} %",
                        ins_pct[j]
                    ));
                }
            }
            if bounds[j].at_bound(theta[j]) {
                flags.push("at a bound".to_string());
            }
            ParameterEstimate {
                name: model.parameters[j].name.clone(),
                value: theta[j],
                cramer_rao: acc.cramer_rao[j],
                cramer_rao_pct: cr_pct[j],
                insensitivity_pct: ins_pct[j],
                flags,
            }
        })
        .collect();
    Ok(SsFit {
        parameters,
        correlation: acc.correlation,
        responses: costs,
        cost,
        matrices: model.matrices(&theta)?,
        evaluations: report.number_of_evaluations,
    })
}

mod spec;
pub use spec::{ResponseSpec, SsSpec};

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// The analytic Jacobian (with respect to the internal φ, through the
    /// bound transformations) against central differences, on a model
    /// with a parameter in each of A, B, C, D and a delay, one of them
    /// shared, one bounded on both sides and one on one side.
    #[test]
    fn analytic_jacobian_matches_central_differences() {
        let p = |name: &str, start: f64, min: Option<f64>, max: Option<f64>| FreeParameter {
            name: name.into(),
            start,
            min,
            max,
        };
        let f = Cell::Fixed;
        let model = SsModel {
            states: vec!["x1".into(), "x2".into()],
            inputs: vec!["u1".into(), "u2".into()],
            outputs: vec!["y1".into(), "y2".into()],
            a: vec![
                vec![Cell::Free(0), f(1.0)],
                vec![Cell::Free(1), Cell::Free(0)],
            ],
            b: vec![vec![Cell::Free(2), f(0.3)], vec![f(0.0), f(2.0)]],
            c: vec![vec![f(1.0), Cell::Free(3)], vec![f(0.0), f(1.0)]],
            d: vec![vec![f(0.0), Cell::Free(4)], vec![f(0.0), f(0.0)]],
            delay_s: vec![Cell::Free(5), f(0.01)],
            parameters: vec![
                p("a", -1.5, None, None),
                p("k", -9.0, Some(-20.0), Some(-1.0)),
                p("b", 3.0, Some(0.0), None),
                p("c", 0.4, None, Some(2.0)),
                p("d", 0.05, None, None),
                p("tau", 0.03, Some(0.0), Some(0.2)),
            ],
        };
        model.check().unwrap();
        let grid: Vec<f64> = (0..12).map(|k| 0.3 * 1.5_f64.powi(k)).collect();
        let frf = |i: usize, o: usize| Frf {
            omega_rad_s: grid.clone(),
            h: grid
                .iter()
                .map(|w| {
                    Complex64::from_polar(1.0 + 0.1 * w, -0.2 * w) * (1.0 + (i + 2 * o) as f64)
                })
                .collect(),
            coherence: grid.iter().map(|w| 0.7 + 0.02 * w.min(10.0)).collect(),
            random_error: vec![0.1; grid.len()],
        };
        let responses: Vec<Response> = [(0, 0), (1, 0), (0, 1), (1, 1)]
            .iter()
            .map(|&(i, o)| Response {
                input: i,
                output: o,
                frf: frf(i, o),
                omega_min_rad_s: 0.0,
                omega_max_rad_s: f64::INFINITY,
            })
            .collect();
        let data = prepare(&model, &responses, &CostOptions::default()).unwrap();
        let places = model.places();
        let bounds: Vec<Bound> = model.parameters.iter().map(Bound::of).collect();
        let phi = DVector::from_iterator(
            6,
            bounds
                .iter()
                .zip(&model.parameters)
                .map(|(b, p)| b.internal(p.start)),
        );
        let mut pr = problem(&model, &places, &bounds, &data, phi.clone());
        let jac = pr.jacobian().unwrap();
        let mut worst = 0.0_f64;
        for j in 0..6 {
            let h = 1e-6 * (1.0 + phi[j].abs());
            let mut plus = phi.clone();
            plus[j] += h;
            pr.set_params(&plus);
            let rp = pr.residuals().unwrap();
            let mut minus = phi.clone();
            minus[j] -= h;
            pr.set_params(&minus);
            let rm = pr.residuals().unwrap();
            let fd = (rp - rm) / (2.0 * h);
            let scale = fd.amax().max(1e-3);
            worst = worst.max((fd - jac.column(j)).amax() / scale);
        }
        // central differences carry an error of order h² and round-off
        // 1e-16/h: agreement to 1e-6 of each column's largest entry.
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn bound_transformations_round_trip() {
        for (b, t) in [
            (Bound::Both(-2.0, 3.0), 0.7),
            (Bound::Lower(1.0), 4.0),
            (Bound::Upper(-1.0), -3.5),
            (Bound::Free, 2.5),
        ] {
            let (back, _) = b.external(b.internal(t));
            assert!((back - t).abs() < 1e-12, "{b:?}");
        }
    }
}
