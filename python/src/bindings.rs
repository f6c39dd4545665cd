//! The extension module `helicon._helicon`: PyO3 wrappers over the core.
//!
//! Conventions: every array argument goes through
//! `numpy.ascontiguousarray(value, dtype=float64)` (no copy when it is one
//! already), its shape is checked before any library call, long work runs
//! with the GIL released, and every failure is raised as
//! `helicon.HeliconError` (a `ValueError`) with the core's message. The
//! public Python API (docstrings, result classes) is the `helicon` package
//! around this module; see docs/python.md.

use crate::batch::{Rows, derivative_rows};
use crate::conditions::{Condition, linearize_at, trim_at, trim_json};
use crate::error::Error;
use crate::frf::{FrfOptions, frf as frf_core};
use crate::logs::{self, ParamsSource, SimOptions};
use crate::mc::{INTERRUPTED, load_campaign, run_campaign};
use crate::params as pk;
use crate::ulog::{Column, read as read_ulog};
use helicon_model::state::{INPUT_NAMES, REDUCED_STATE_NAMES, STATE_NAMES, STATE_UNITS};
use helicon_model::{Model, NX, Params, Preset};
use helicon_sim::mc::METRIC_NAMES;
use helicon_sim::scenario::Scenario;
use nalgebra::DMatrix;
use numpy::{
    Complex64, PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::{PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

create_exception!(
    helicon,
    HeliconError,
    PyValueError,
    "An error of helicon: bad input (a shape, a non-finite value, a parameter or scenario \
     field out of its range) or a failed computation (a trim that does not converge, a \
     Riccati equation without a stabilizing solution). The message is the library's: it \
     names the file, the field and the allowed range."
);

fn err(e: Error) -> PyErr {
    HeliconError::new_err(e.0)
}

fn herr(msg: impl Into<String>) -> PyErr {
    HeliconError::new_err(msg.into())
}

type Res<T> = PyResult<T>;

// ---------------------------------------------------------------- arrays

/// `value` as a C-contiguous float64 array (numpy.ascontiguousarray).
fn f64_array<'py>(
    py: Python<'py>,
    what: &str,
    value: &Bound<'py, PyAny>,
) -> Res<PyReadonlyArrayDyn<'py, f64>> {
    let np = py.import("numpy")?;
    let arr = np
        .getattr("ascontiguousarray")?
        .call1((value, np.getattr("float64")?))
        .map_err(|e| herr(format!("{what}: not an array of numbers: {e}")))?;
    let arr = arr
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|e| herr(format!("{what}: not a float64 array: {e}")))?;
    Ok(arr.readonly())
}

/// The data of a C-contiguous array.
fn slice<'a>(what: &str, a: &'a PyReadonlyArrayDyn<'_, f64>) -> Res<&'a [f64]> {
    a.as_slice()
        .map_err(|e| herr(format!("{what}: not contiguous: {e}")))
}

/// A matrix argument: 2-D, or a scalar as 1 × 1 (`ascontiguousarray` makes
/// a scalar 1-D of one element); every entry finite.
fn matrix(py: Python<'_>, what: &str, value: &Bound<'_, PyAny>) -> Res<DMatrix<f64>> {
    let a = f64_array(py, what, value)?;
    let shape = a.shape().to_vec();
    let (r, c) = match shape.as_slice() {
        [] | [1] => (1, 1),
        [r, c] => (*r, *c),
        s => {
            return Err(herr(format!(
                "{what}: shape {s:?}; a matrix must be 2-D (or a scalar)"
            )));
        }
    };
    let data = slice(what, &a)?;
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(herr(format!(
            "{what}[{}, {}] = {} is not finite",
            i / c.max(1),
            i % c.max(1),
            data[i]
        )));
    }
    Ok(DMatrix::from_row_slice(r, c, data))
}

/// A row-major float64 array of `shape` from a matrix.
fn to_array<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Res<Bound<'py, PyAny>> {
    let data: Vec<f64> = m.transpose().as_slice().to_vec();
    Ok(PyArray1::from_vec(py, data)
        .reshape([m.nrows(), m.ncols()])?
        .into_any())
}

fn complex_array<'py>(py: Python<'py>, z: &[nalgebra::Complex<f64>]) -> Bound<'py, PyAny> {
    let v: Vec<Complex64> = z.iter().map(|c| Complex64::new(c.re, c.im)).collect();
    PyArray1::from_vec(py, v).into_any()
}

/// A vector argument of exactly `n` finite numbers.
fn vector<const N: usize>(py: Python<'_>, what: &str, value: &Bound<'_, PyAny>) -> Res<[f64; N]> {
    let a = f64_array(py, what, value)?;
    let data = slice(what, &a)?;
    if a.ndim() != 1 || data.len() != N {
        return Err(herr(format!(
            "{what}: shape {:?}; expected ({N},)",
            a.shape()
        )));
    }
    let mut out = [0.0; N];
    out.copy_from_slice(data);
    Ok(out)
}

// ---------------------------------------------------------------- JSON

/// A JSON value as Python objects (dict, list, str, int, float, bool, None).
fn json_to_py<'py>(py: Python<'py>, v: &Value) -> Res<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<Res<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(m) => {
            let d = PyDict::new(py);
            for (k, x) in m {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

// ---------------------------------------------------------------- Params

/// The model parameters: every constant of the thesis Nomenclature plus
/// the main-rotor speed, in SI units (see docs/python.md).
///
/// ``Params()`` is the Bergen Industrial Twin. Keys are ``section.key`` as
/// in the TOML files (``"body.mass_kg"``, ``"servo.tail.s_min"``); reading
/// and writing them by key (``p["body.mass_kg"] = 12.0``) checks each value
/// against its rule and the set against the cross-key rules, as loading a
/// file does, and leaves the parameters unchanged on an error.
#[pyclass(name = "Params", module = "helicon", eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct PyParams {
    inner: Params,
}

/// Flatten a mapping of edits: dotted keys, or nested tables as in TOML.
fn collect_edits(prefix: &str, m: &Bound<'_, PyDict>, out: &mut Vec<(String, f64)>) -> Res<()> {
    for (k, v) in m.iter() {
        let k: String = k
            .extract()
            .map_err(|_| herr("parameter keys must be strings"))?;
        let key = if prefix.is_empty() {
            k
        } else {
            format!("{prefix}.{k}")
        };
        if let Ok(sub) = v.cast::<PyDict>() {
            collect_edits(&key, sub, out)?;
            continue;
        }
        out.push((key.clone(), edit_value(&key, &v)?));
    }
    Ok(())
}

/// A value for `key`: a number, or a bool for a switch (as in TOML).
fn edit_value(key: &str, v: &Bound<'_, PyAny>) -> Res<f64> {
    let d = pk::descriptor(key).map_err(err)?;
    let wrong = |found: &str| {
        err(Error::from(helicon_model::params::ParamError::WrongType {
            file: pk::ORIGIN.to_string(),
            line: None,
            key: key.to_string(),
            found: found.to_string(),
        }))
    };
    if v.is_instance_of::<PyBool>() {
        if d.rule == helicon_model::params::Rule::Flag {
            return Ok(if v.extract::<bool>()? { 1.0 } else { 0.0 });
        }
        return Err(wrong("boolean"));
    }
    if v.is_instance_of::<PyInt>() || v.is_instance_of::<PyFloat>() {
        return v
            .extract::<f64>()
            .map_err(|_| wrong("an integer beyond f64"));
    }
    // NumPy scalars and other numbers
    if let Ok(x) = v.call_method0("__float__").and_then(|f| f.extract::<f64>()) {
        return Ok(x);
    }
    Err(wrong(
        &v.get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string()),
    ))
}

#[pymethods]
impl PyParams {
    #[new]
    fn new() -> Self {
        PyParams {
            inner: Params::bergen_twin(),
        }
    }

    /// Parameters from a TOML file: the Bergen Twin with the file's keys
    /// overriding it (any subset), validated; errors name file:line and key.
    #[staticmethod]
    fn from_file(path: PathBuf) -> Res<Self> {
        Ok(PyParams {
            inner: Params::from_file(&path).map_err(|e| err(e.into()))?,
        })
    }

    /// Parameters from TOML text (as a file's); ``name`` labels it in errors.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<string>"))]
    fn from_toml(text: &str, name: &str) -> Res<Self> {
        Ok(PyParams {
            inner: Params::from_toml_str(text, name).map_err(|e| err(e.into()))?,
        })
    }

    /// The complete parameter set as a TOML file (units and thesis symbols
    /// in comments), as ``helicon params`` prints it.
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    /// The parameters as nested dicts, as the TOML file's tables
    /// (``d["servo"]["tail"]["s_min"]``); counts are ints, switches bools.
    fn to_dict<'py>(&self, py: Python<'py>) -> Res<Bound<'py, PyAny>> {
        json_to_py(py, &pk::to_json(&self.inner))
    }

    /// Every key, ``section.key``, in file order.
    #[staticmethod]
    fn keys() -> Vec<String> {
        pk::keys()
    }

    /// What ``key`` is: ``{"unit", "symbol", "rule"}``.
    #[staticmethod]
    fn describe<'py>(py: Python<'py>, key: &str) -> Res<Bound<'py, PyAny>> {
        json_to_py(py, &pk::describe(key).map_err(err)?)
    }

    /// A copy with ``edits`` applied (dotted keys or nested dicts), validated.
    fn replace(&self, edits: &Bound<'_, PyDict>) -> Res<Self> {
        let mut list = Vec::new();
        collect_edits("", edits, &mut list)?;
        Ok(PyParams {
            inner: pk::with_edits(&self.inner, &list).map_err(err)?,
        })
    }

    /// Apply ``edits`` in place, all or none (validated as a file is).
    fn update(&mut self, edits: &Bound<'_, PyDict>) -> Res<()> {
        let mut list = Vec::new();
        collect_edits("", edits, &mut list)?;
        self.inner = pk::with_edits(&self.inner, &list).map_err(err)?;
        Ok(())
    }

    /// A copy.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __copy__(&self) -> Self {
        self.clone()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.clone()
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> Res<Bound<'py, PyAny>> {
        let v = pk::get(&self.inner, key).map_err(|e| PyKeyError::new_err(e.0))?;
        json_to_py(py, &v)
    }

    fn __setitem__(&mut self, key: &str, value: &Bound<'_, PyAny>) -> Res<()> {
        let v = edit_value(key, value)?;
        self.inner = pk::with_edits(&self.inner, &[(key.to_string(), v)]).map_err(err)?;
        Ok(())
    }

    fn __contains__(&self, key: &str) -> bool {
        pk::descriptor(key).is_ok()
    }

    fn __len__(&self) -> usize {
        pk::keys().len()
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> Res<Bound<'py, PyAny>> {
        Ok(PyList::new(py, pk::keys())?.try_iter()?.into_any())
    }

    fn __repr__(&self) -> String {
        if self.inner == Params::bergen_twin() {
            "helicon.Params()  # the Bergen Twin".to_string()
        } else {
            let base = Params::bergen_twin();
            let changed: Vec<String> = pk::keys()
                .into_iter()
                .filter(|k| pk::get(&self.inner, k).ok() != pk::get(&base, k).ok())
                .map(|k| {
                    let v = pk::get(&self.inner, &k)
                        .map(|v| v.to_string())
                        .unwrap_or_default();
                    format!("{k:?}: {v}")
                })
                .collect();
            format!("helicon.Params().replace({{{}}})", changed.join(", "))
        }
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> Res<Bound<'py, PyTuple>> {
        let py = slf.py();
        let text = slf.borrow().inner.to_toml();
        let ctor = slf.get_type().getattr("from_toml")?;
        PyTuple::new(py, [ctor, PyTuple::new(py, [text])?.into_any()])
    }
}

/// Parameters from ``None`` (the Bergen Twin), a ``Params`` or a TOML path.
fn params_arg(value: Option<&Bound<'_, PyAny>>) -> Res<Params> {
    match value {
        None => Ok(Params::bergen_twin()),
        Some(v) if v.is_none() => Ok(Params::bergen_twin()),
        Some(v) => {
            if let Ok(p) = v.cast::<PyParams>() {
                return Ok(p.borrow().inner);
            }
            let path: PathBuf = v
                .extract()
                .map_err(|_| herr("params: expected a helicon.Params, a TOML file path or None"))?;
            Params::from_file(&path).map_err(|e| err(e.into()))
        }
    }
}

fn preset_arg(name: &str) -> Res<Preset> {
    Preset::from_str(name).map_err(|e| herr(e.to_string()))
}

// ---------------------------------------------------------------- Model

/// The nonlinear model ẋ = f(x, u, wind) of a preset and parameters.
#[pyclass(name = "Model", module = "helicon", frozen)]
pub struct PyModel {
    model: Model,
    preset: Preset,
}

#[pymethods]
impl PyModel {
    #[new]
    #[pyo3(signature = (preset = "physical", params = None))]
    fn new(preset: &str, params: Option<&Bound<'_, PyAny>>) -> Res<Self> {
        let preset = preset_arg(preset)?;
        Ok(PyModel {
            model: Model::new(params_arg(params)?, preset.options()),
            preset,
        })
    }

    /// The preset's name.
    #[getter]
    fn preset(&self) -> &'static str {
        self.preset.name()
    }

    /// A copy of the parameters.
    #[getter]
    fn params(&self) -> PyParams {
        PyParams {
            inner: *self.model.params(),
        }
    }

    /// ẋ for one state ``(30,)`` or a batch ``(N, 30)``.
    #[pyo3(signature = (x, u, wind = None))]
    fn derivative<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
        wind: Option<&Bound<'py, PyAny>>,
    ) -> Res<Bound<'py, PyAny>> {
        let xa = f64_array(py, "x", x)?;
        let ua = f64_array(py, "u", u)?;
        let wa = match wind {
            Some(w) if !w.is_none() => Some(f64_array(py, "wind", w)?),
            _ => None,
        };
        let (n, batch) = match xa.shape() {
            [k] if *k == NX => (1, false),
            [n, k] if *k == NX => (*n, true),
            s => {
                return Err(herr(format!(
                    "x: shape {s:?}; expected (30,) or (N, 30) (the state order of helicon.state_names())"
                )));
            }
        };
        let rows = |what: &str, a: &PyReadonlyArrayDyn<'py, f64>, width: usize| -> Res<bool> {
            match a.shape() {
                [k] if *k == width => Ok(false),
                [m, k] if batch && *m == n && *k == width => Ok(true),
                s => Err(herr(format!(
                    "{what}: shape {s:?}; expected ({width},){}",
                    if batch {
                        format!(" or ({n}, {width}) for x of shape ({n}, 30)")
                    } else {
                        " for x of shape (30,)".to_string()
                    }
                ))),
            }
        };
        let u_each = rows("u", &ua, 4)?;
        let w_each = match &wa {
            Some(w) => Some(rows("wind", w, 3)?),
            None => None,
        };
        let xs = slice("x", &xa)?;
        let us = slice("u", &ua)?;
        let ws = match &wa {
            Some(w) => Some(slice("wind", w)?),
            None => None,
        };
        let u_rows = if u_each {
            Rows::Each(us)
        } else {
            Rows::One(us)
        };
        let w_rows = match (ws, w_each) {
            (Some(w), Some(true)) => Some(Rows::Each(w)),
            (Some(w), _) => Some(Rows::One(w)),
            (None, _) => None,
        };
        let model = &self.model;
        let out = py
            .detach(|| {
                let mut out = vec![0.0; n * NX];
                derivative_rows(model, n, xs, u_rows, w_rows, &mut out).map(|()| out)
            })
            .map_err(err)?;
        let arr = PyArray1::from_vec(py, out);
        if batch {
            Ok(arr.reshape([n, NX])?.into_any())
        } else {
            Ok(arr.into_any())
        }
    }

    fn __repr__(&self) -> String {
        if *self.model.params() == Params::bergen_twin() {
            format!("helicon.Model(preset={:?})", self.preset.name())
        } else {
            format!(
                "helicon.Model(preset={:?}, params=<edited Params>)",
                self.preset.name()
            )
        }
    }
}

// ---------------------------------------------------------------- trim, linearize

fn condition(
    py: Python<'_>,
    velocity_ned: &Bound<'_, PyAny>,
    yaw: f64,
    wind_ned: Option<&Bound<'_, PyAny>>,
) -> Res<Condition> {
    Ok(Condition {
        velocity_ned_m_s: vector::<3>(py, "velocity_ned", velocity_ned)?,
        yaw_rad: yaw,
        wind_ned_m_s: match wind_ned {
            Some(w) if !w.is_none() => vector::<3>(py, "wind_ned", w)?,
            _ => [0.0; 3],
        },
    })
}

/// `helicon trim --json` as a dict.
#[pyfunction]
#[pyo3(signature = (preset, velocity_ned, params, yaw, wind_ned))]
fn trim<'py>(
    py: Python<'py>,
    preset: &str,
    velocity_ned: &Bound<'py, PyAny>,
    params: Option<&Bound<'py, PyAny>>,
    yaw: f64,
    wind_ned: Option<&Bound<'py, PyAny>>,
) -> Res<Bound<'py, PyAny>> {
    let model = Model::new(params_arg(params)?, preset_arg(preset)?.options());
    let cond = condition(py, velocity_ned, yaw, wind_ned)?;
    let value = py
        .detach(|| trim_at(&model, &cond).map(|t| trim_json(&t, &model)))
        .map_err(err)?;
    json_to_py(py, &value)
}

/// `helicon linearize`: (A, B) or (A, B, Phi, Gamma).
#[pyfunction]
#[pyo3(signature = (preset, velocity_ned, params, yaw, wind_ned, thesis_inflow, dt, allow_unphysical))]
fn linearize<'py>(
    py: Python<'py>,
    preset: &str,
    velocity_ned: &Bound<'py, PyAny>,
    params: Option<&Bound<'py, PyAny>>,
    yaw: f64,
    wind_ned: Option<&Bound<'py, PyAny>>,
    thesis_inflow: bool,
    dt: Option<f64>,
    allow_unphysical: bool,
) -> Res<Bound<'py, PyTuple>> {
    let model = Model::new(params_arg(params)?, preset_arg(preset)?.options());
    let cond = condition(py, velocity_ned, yaw, wind_ned)?;
    let l = py
        .detach(|| linearize_at(&model, &cond, thesis_inflow, dt, allow_unphysical))
        .map_err(err)?;
    let mut items = vec![to_array(py, &l.a)?, to_array(py, &l.b)?];
    if let Some((phi, gamma)) = &l.discrete {
        items.push(to_array(py, phi)?);
        items.push(to_array(py, gamma)?);
    }
    PyTuple::new(py, items)
}

// ---------------------------------------------------------------- control

fn lti(e: helicon_lti::LtiError) -> PyErr {
    err(e.into())
}

fn opt_matrix(
    py: Python<'_>,
    what: &str,
    v: Option<&Bound<'_, PyAny>>,
) -> Res<Option<DMatrix<f64>>> {
    match v {
        Some(x) if !x.is_none() => Ok(Some(matrix(py, what, x)?)),
        _ => Ok(None),
    }
}

/// The stabilizing solution X of the DARE.
#[pyfunction]
#[pyo3(signature = (a, b, q, r, n = None))]
fn dare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    r: &Bound<'py, PyAny>,
    n: Option<&Bound<'py, PyAny>>,
) -> Res<Bound<'py, PyAny>> {
    let (a, b, q, r) = (
        matrix(py, "A", a)?,
        matrix(py, "B", b)?,
        matrix(py, "Q", q)?,
        matrix(py, "R", r)?,
    );
    let n = opt_matrix(py, "N", n)?;
    let s = py
        .detach(|| helicon_lti::dare(&a, &b, &q, &r, n.as_ref()))
        .map_err(lti)?;
    to_array(py, &s.x)
}

/// (K, X, E) of the discrete LQR.
#[pyfunction]
#[pyo3(signature = (a, b, q, r, n = None))]
fn dlqr<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    r: &Bound<'py, PyAny>,
    n: Option<&Bound<'py, PyAny>>,
) -> Res<Bound<'py, PyTuple>> {
    let (a, b, q, r) = (
        matrix(py, "A", a)?,
        matrix(py, "B", b)?,
        matrix(py, "Q", q)?,
        matrix(py, "R", r)?,
    );
    let n = opt_matrix(py, "N", n)?;
    let l = py
        .detach(|| helicon_lti::dlqr(&a, &b, &q, &r, n.as_ref()))
        .map_err(lti)?;
    PyTuple::new(
        py,
        [
            to_array(py, &l.k)?,
            to_array(py, &l.s)?,
            complex_array(py, &l.poles),
        ],
    )
}

/// (L, P, E) of the steady-state Kalman predictor.
#[pyfunction]
#[pyo3(signature = (a, g, c, qn, rn))]
fn dlqe<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    g: Option<&Bound<'py, PyAny>>,
    c: &Bound<'py, PyAny>,
    qn: &Bound<'py, PyAny>,
    rn: &Bound<'py, PyAny>,
) -> Res<Bound<'py, PyTuple>> {
    let a = matrix(py, "A", a)?;
    let g = opt_matrix(py, "G", g)?;
    let (c, qn, rn) = (
        matrix(py, "C", c)?,
        matrix(py, "Qn", qn)?,
        matrix(py, "Rn", rn)?,
    );
    let k = py
        .detach(|| helicon_lti::dlqe(&a, g.as_ref(), &c, &qn, &rn))
        .map_err(lti)?;
    PyTuple::new(
        py,
        [
            to_array(py, &k.l)?,
            to_array(py, &k.p)?,
            complex_array(py, &k.poles),
        ],
    )
}

/// The filter gain M and posterior covariance Z of the steady-state Kalman filter.
#[pyfunction]
#[pyo3(signature = (a, g, c, qn, rn))]
fn kalman_filter<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    g: Option<&Bound<'py, PyAny>>,
    c: &Bound<'py, PyAny>,
    qn: &Bound<'py, PyAny>,
    rn: &Bound<'py, PyAny>,
) -> Res<Bound<'py, PyTuple>> {
    let a = matrix(py, "A", a)?;
    let g = opt_matrix(py, "G", g)?;
    let (c, qn, rn) = (
        matrix(py, "C", c)?,
        matrix(py, "Qn", qn)?,
        matrix(py, "Rn", rn)?,
    );
    let k = py
        .detach(|| helicon_lti::dlqe(&a, g.as_ref(), &c, &qn, &rn))
        .map_err(lti)?;
    PyTuple::new(py, [to_array(py, &k.m)?, to_array(py, &k.z)?])
}

/// ZOH discretization (Phi, Gamma).
#[pyfunction]
fn c2d<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    dt: f64,
) -> Res<Bound<'py, PyTuple>> {
    let (a, b) = (matrix(py, "A", a)?, matrix(py, "B", b)?);
    let (phi, gamma) = py.detach(|| helicon_lti::c2d(&a, &b, dt)).map_err(lti)?;
    PyTuple::new(py, [to_array(py, &phi)?, to_array(py, &gamma)?])
}

// ---------------------------------------------------------------- Scenario, sim

/// A closed-loop scenario (TOML), validated; see docs/closed-loop.md.
#[pyclass(name = "Scenario", module = "helicon", frozen)]
pub struct PyScenario {
    inner: Scenario,
    source: String,
}

#[pymethods]
impl PyScenario {
    /// Load a scenario file (relative paths inside resolve against its folder).
    #[staticmethod]
    fn from_file(path: PathBuf) -> Res<Self> {
        Ok(PyScenario {
            inner: logs::load_scenario(&path).map_err(err)?,
            source: path.display().to_string(),
        })
    }

    /// A scenario from TOML text; ``base_dir`` resolves its relative paths
    /// (default: the working directory); ``name`` labels it in errors.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir = None, name = "<string>"))]
    fn from_toml(text: &str, base_dir: Option<PathBuf>, name: &str) -> Res<Self> {
        let mut s = Scenario::from_toml_str(text, name).map_err(|e| err(e.into()))?;
        s.base_dir = base_dir.clone();
        for v in &mut s.variants {
            v.base_dir = base_dir.clone();
        }
        Ok(PyScenario {
            inner: s,
            source: name.to_string(),
        })
    }

    /// The scenario's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// Flight time (s).
    #[getter]
    fn duration_s(&self) -> f64 {
        self.inner.duration_s
    }

    /// The model preset.
    #[getter]
    fn preset(&self) -> &'static str {
        self.inner.preset.name()
    }

    /// The case labels (``[[case]]`` names; the scenario's name when none).
    #[getter]
    fn cases(&self) -> Vec<String> {
        logs::cases(&self.inner)
            .into_iter()
            .map(|(l, _)| l)
            .collect()
    }

    /// The effective scenario as TOML (without its ``[[case]]`` entries).
    fn to_toml(&self) -> Res<String> {
        toml_string(&self.inner)
    }

    fn __repr__(&self) -> String {
        format!(
            "helicon.Scenario({:?} from {})",
            self.inner.name, self.source
        )
    }
}

fn toml_string(s: &Scenario) -> Res<String> {
    toml::to_string(s).map_err(|e| herr(format!("the scenario as TOML: {e}")))
}

/// The scenario argument: a ``Scenario`` or a path.
fn scenario_arg(v: &Bound<'_, PyAny>) -> Res<(Scenario, String)> {
    if let Ok(s) = v.cast::<PyScenario>() {
        let s = s.get();
        return Ok((s.inner.clone(), s.source.clone()));
    }
    let path: PathBuf = v
        .extract()
        .map_err(|_| herr("scenario: expected a helicon.Scenario or a scenario file path"))?;
    Ok((
        logs::load_scenario(&path).map_err(err)?,
        path.display().to_string(),
    ))
}

/// Fly every case of a scenario; a list of dicts (name, label, log, summary, outcome).
#[pyfunction]
#[pyo3(signature = (scenario, duration, seed, params))]
fn sim<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    duration: Option<f64>,
    seed: Option<u64>,
    params: Option<&Bound<'py, PyAny>>,
) -> Res<Bound<'py, PyList>> {
    let (s, source) = scenario_arg(scenario)?;
    let params = match params {
        None => ParamsSource::Scenario,
        Some(p) if p.is_none() => ParamsSource::Scenario,
        Some(p) => match p.cast::<PyParams>() {
            Ok(pp) => ParamsSource::Value(Box::new(pp.borrow().inner)),
            Err(_) => ParamsSource::File(p.extract().map_err(|_| {
                herr("params: expected a helicon.Params, a TOML file path or None")
            })?),
        },
    };
    let opts = SimOptions {
        duration_s: duration,
        seed,
        params,
    };
    let (s, label) = logs::with_options(s, &source, &opts).map_err(err)?;
    let names = logs::column_names();
    let out = PyList::empty(py);
    for (case_label, case) in logs::cases(&s) {
        let src = if s.variants.is_empty() {
            label.clone()
        } else {
            format!("{label}, case `{case_label}`")
        };
        // Ctrl-C stops the flight at its next controller sample
        let stop = AtomicBool::new(false);
        let r = interruptible(py, &stop, "the flight", || {
            logs::fly_case(&case_label, &case, &opts.params, &src, &stop)
        })?
        .map_err(err)?;
        let log = PyDict::new(py);
        for (name, col) in names.iter().zip(r.columns) {
            log.set_item(*name, PyArray1::from_vec(py, col))?;
        }
        let d = PyDict::new(py);
        d.set_item("name", r.name)?;
        d.set_item("label", r.label)?;
        d.set_item("log", log)?;
        d.set_item("summary", json_to_py(py, &r.summary)?)?;
        d.set_item("outcome", r.outcome)?;
        out.append(d)?;
        // Ctrl-C between cases
        py.check_signals()?;
    }
    Ok(out)
}

/// Run `work` on a worker thread with the GIL released while this thread
/// checks for Python signals every 50 ms: on one (Ctrl-C) it sets `stop`,
/// which `work` polls, waits for `work` to end and raises the signal's
/// exception. `what` names the work in the message of a worker panic.
fn interruptible<T: Send>(
    py: Python<'_>,
    stop: &AtomicBool,
    what: &str,
    work: impl FnOnce() -> T + Send,
) -> Res<T> {
    let (result, interrupt) = py.detach(|| {
        std::thread::scope(|s| {
            let h = s.spawn(work);
            let mut interrupt: Option<PyErr> = None;
            while !h.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                if interrupt.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    stop.store(true, Ordering::Relaxed);
                    interrupt = Some(e);
                }
            }
            (h.join(), interrupt)
        })
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    result.map_err(|_| {
        herr(format!(
            "internal error: the worker thread of {what} panicked"
        ))
    })
}

// ---------------------------------------------------------------- mc

/// Fly a Monte Carlo campaign in memory; a dict of columns, traces and stats.
#[pyfunction]
#[pyo3(signature = (campaign, runs, threads, seed, duration, params))]
fn mc<'py>(
    py: Python<'py>,
    campaign: &Bound<'py, PyAny>,
    runs: Option<usize>,
    threads: Option<usize>,
    seed: Option<u64>,
    duration: Option<f64>,
    params: Option<&Bound<'py, PyAny>>,
) -> Res<Bound<'py, PyDict>> {
    let campaign: PathBuf = campaign
        .extract()
        .map_err(|_| herr("campaign: expected a campaign file path"))?;
    let params: Option<PathBuf> = match params {
        Some(p) if !p.is_none() => Some(
            p.extract()
                .map_err(|_| herr("params: expected a parameter TOML file path or None"))?,
        ),
        _ => None,
    };
    let c = load_campaign(&campaign, seed, duration, params).map_err(err)?;
    let stop = AtomicBool::new(false);
    let done = AtomicUsize::new(0);
    // stopped between runs on Ctrl-C
    let run = interruptible(py, &stop, "the campaign", || {
        run_campaign(&c, runs, threads, &stop, &done)
    })?
    .map_err(|e| {
        if e.message() == INTERRUPTED {
            herr("the campaign was interrupted")
        } else {
            err(e)
        }
    })?;
    let cols = PyDict::new(py);
    let rec = |f: &dyn Fn(&helicon_sim::mc::RunRecord) -> f64| -> Vec<f64> {
        run.runs.iter().map(|o| f(&o.record)).collect()
    };
    cols.set_item(
        "index",
        PyArray1::from_vec(
            py,
            run.runs
                .iter()
                .map(|o| i64::try_from(o.record.index).unwrap_or(i64::MAX))
                .collect::<Vec<_>>(),
        ),
    )?;
    cols.set_item(
        "wind_seed",
        PyArray1::from_vec(
            py,
            run.runs
                .iter()
                .map(|o| o.record.wind_seed)
                .collect::<Vec<_>>(),
        ),
    )?;
    cols.set_item(
        "sensor_seed",
        PyArray1::from_vec(
            py,
            run.runs
                .iter()
                .map(|o| o.record.sensor_seed)
                .collect::<Vec<_>>(),
        ),
    )?;
    for (k, name) in run.dispersed.iter().enumerate() {
        cols.set_item(
            name,
            PyArray1::from_vec(py, rec(&|r| r.values.get(k).copied().unwrap_or(f64::NAN))),
        )?;
    }
    let strings = |f: &dyn Fn(&helicon_sim::mc::RunRecord) -> String| -> Vec<String> {
        run.runs.iter().map(|o| f(&o.record)).collect()
    };
    cols.set_item("outcome", strings(&|r| r.outcome().as_str().to_string()))?;
    cols.set_item(
        "termination",
        strings(&|r| r.termination.as_str().to_string()),
    )?;
    cols.set_item("reason", strings(&|r| r.reason.clone()))?;
    cols.set_item("t_end_s", PyArray1::from_vec(py, rec(&|r| r.t_end_s)))?;
    for (k, name) in METRIC_NAMES.iter().enumerate() {
        cols.set_item(
            *name,
            PyArray1::from_vec(
                py,
                rec(&|r| r.metrics.get(k).copied().flatten().unwrap_or(f64::NAN)),
            ),
        )?;
    }
    let traces = PyList::empty(py);
    for o in &run.runs {
        let mut v = Vec::with_capacity(o.trace.len() * 5);
        for p in &o.trace {
            v.push(p.t_s);
            v.extend_from_slice(&p.output);
        }
        traces.append(PyArray1::from_vec(py, v).reshape([o.trace.len(), 5])?)?;
    }
    let d = PyDict::new(py);
    d.set_item("name", c.name.clone())?;
    d.set_item("dispersed", run.dispersed.clone())?;
    d.set_item("columns", cols)?;
    d.set_item("traces", traces)?;
    d.set_item("stats", json_to_py(py, &run.stats)?)?;
    Ok(d)
}

// ---------------------------------------------------------------- ident, ulog

fn column<'py>(py: Python<'py>, what: &str, v: &Bound<'py, PyAny>) -> Res<Vec<f64>> {
    let a = f64_array(py, what, v)?;
    if a.ndim() != 1 {
        return Err(herr(format!("{what}: shape {:?}; expected 1-D", a.shape())));
    }
    Ok(slice(what, &a)?.to_vec())
}

/// Columns of a 1-D array (one channel) or a 2-D (N, k) array (k channels).
fn channels<'py>(py: Python<'py>, what: &str, v: &Bound<'py, PyAny>) -> Res<(Vec<Vec<f64>>, bool)> {
    let a = f64_array(py, what, v)?;
    let data = slice(what, &a)?;
    match a.shape() {
        [_] => Ok((vec![data.to_vec()], false)),
        [n, k] => Ok((
            (0..*k)
                .map(|j| (0..*n).map(|i| data[i * k + j]).collect())
                .collect(),
            true,
        )),
        s => Err(herr(format!(
            "{what}: shape {s:?}; expected (N,) or (N, k)"
        ))),
    }
}

/// Frequency responses; a list of dicts of arrays (one per output column).
#[pyfunction]
#[pyo3(signature = (t, u, y, omega_min, omega_max, points, windows, conditioned_on, max_window_s))]
fn frf<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    u: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
    omega_min: Option<f64>,
    omega_max: Option<f64>,
    points: usize,
    windows: usize,
    conditioned_on: Option<&Bound<'py, PyAny>>,
    max_window_s: Option<f64>,
) -> Res<Bound<'py, PyList>> {
    let t = column(py, "t", t)?;
    let u = column(py, "u", u)?;
    let (ys, _) = channels(py, "y", y)?;
    let cond = match conditioned_on {
        Some(c) if !c.is_none() => channels(py, "conditioned_on", c)?.0,
        _ => Vec::new(),
    };
    let o = FrfOptions {
        omega_min,
        omega_max,
        points,
        windows,
        max_window_s,
    };
    let rs = py
        .detach(|| {
            let yr: Vec<&[f64]> = ys.iter().map(Vec::as_slice).collect();
            let cr: Vec<&[f64]> = cond.iter().map(Vec::as_slice).collect();
            frf_core(&t, &u, &cr, &yr, &o)
        })
        .map_err(err)?;
    let out = PyList::empty(py);
    for r in rs {
        let d = PyDict::new(py);
        d.set_item("omega_rad_s", PyArray1::from_vec(py, r.omega_rad_s))?;
        d.set_item("mag_db", PyArray1::from_vec(py, r.mag_db))?;
        d.set_item("phase_deg", PyArray1::from_vec(py, r.phase_deg))?;
        d.set_item("coherence", PyArray1::from_vec(py, r.coherence))?;
        d.set_item("random_error", PyArray1::from_vec(py, r.random_error))?;
        out.append(d)?;
    }
    Ok(out)
}

/// A ULog file: (topics, info, parameters, start_timestamp_us, truncated).
#[pyfunction]
fn ulog_read<'py>(py: Python<'py>, path: PathBuf) -> Res<Bound<'py, PyDict>> {
    let log = py.detach(|| read_ulog(&path)).map_err(err)?;
    let topics = PyDict::new(py);
    for (name, t) in log.topics {
        let fields = PyDict::new(py);
        for (field, c) in t.columns {
            let arr = match c {
                Column::F64(v) => PyArray1::from_vec(py, v).into_any(),
                Column::U64(v) => PyArray1::from_vec(py, v).into_any(),
                Column::I64(v) => PyArray1::from_vec(py, v).into_any(),
                Column::Bool(v) => PyArray1::from_vec(py, v).into_any(),
            };
            fields.set_item(field, arr)?;
        }
        topics.set_item(name, fields)?;
    }
    let d = PyDict::new(py);
    d.set_item("topics", topics)?;
    d.set_item("info", log.info.into_pyobject(py)?)?;
    d.set_item("parameters", log.parameters.into_pyobject(py)?)?;
    d.set_item("start_timestamp_us", log.start_timestamp_us)?;
    d.set_item("truncated", log.truncated)?;
    Ok(d)
}

// ---------------------------------------------------------------- module

#[pymodule]
fn _helicon(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("HeliconError", py.get_type::<HeliconError>())?;
    m.add("STATE_NAMES", PyTuple::new(py, STATE_NAMES)?)?;
    m.add("STATE_UNITS", PyTuple::new(py, STATE_UNITS)?)?;
    m.add(
        "REDUCED_STATE_NAMES",
        PyTuple::new(py, REDUCED_STATE_NAMES)?,
    )?;
    m.add("INPUT_NAMES", PyTuple::new(py, INPUT_NAMES)?)?;
    m.add("LOG_COLUMNS", PyTuple::new(py, logs::column_names())?)?;
    m.add("LOG_UNITS", PyTuple::new(py, logs::column_units())?)?;
    m.add("METRIC_NAMES", PyTuple::new(py, METRIC_NAMES)?)?;
    m.add_class::<PyParams>()?;
    m.add_class::<PyModel>()?;
    m.add_class::<PyScenario>()?;
    for f in [
        wrap_pyfunction!(trim, m)?,
        wrap_pyfunction!(linearize, m)?,
        wrap_pyfunction!(dare, m)?,
        wrap_pyfunction!(dlqr, m)?,
        wrap_pyfunction!(dlqe, m)?,
        wrap_pyfunction!(kalman_filter, m)?,
        wrap_pyfunction!(c2d, m)?,
        wrap_pyfunction!(sim, m)?,
        wrap_pyfunction!(mc, m)?,
        wrap_pyfunction!(frf, m)?,
        wrap_pyfunction!(ulog_read, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
