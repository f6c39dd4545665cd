//! ẋ = f(x, u, wind) for one state or a batch of rows, on flat slices
//! (row-major, as NumPy's C order).
//!
//! One row is exactly `helicon eval`'s evaluation ([`Model::derivative`]
//! then [`check_output`]), so a batch and a loop of single calls give the
//! same bits: rows are independent and each is computed by the same code,
//! whatever the thread that runs it. Rows are spread over the rayon pool
//! in blocks; the first failing row (lowest index) is the one reported.

use crate::error::{Error, Result};
use helicon_model::model::check_output;
use helicon_model::{Input, Model, NU, NX, State};
use nalgebra::Vector3;
use rayon::prelude::*;

/// Rows per parallel block (large enough that scheduling costs nothing).
const BLOCK_ROWS: usize = 512;

/// A per-row operand: one row broadcast to every row, or one per row.
#[derive(Debug, Clone, Copy)]
pub enum Rows<'a> {
    /// The same values for every row.
    One(&'a [f64]),
    /// `n` rows, row-major.
    Each(&'a [f64]),
}

impl<'a> Rows<'a> {
    fn row(&self, i: usize, width: usize) -> &'a [f64] {
        match *self {
            Rows::One(v) => v,
            Rows::Each(v) => &v[i * width..(i + 1) * width],
        }
    }

    fn check(&self, what: &str, width: usize, n: usize) -> Result<()> {
        let (len, want) = match self {
            Rows::One(v) => (v.len(), width),
            Rows::Each(v) => (v.len(), n * width),
        };
        if len != want {
            return Err(Error::new(format!(
                "{what}: {len} values where {want} were expected ({} row(s) of {width})",
                if matches!(self, Rows::One(_)) { 1 } else { n }
            )));
        }
        Ok(())
    }
}

/// One row: `helicon eval`'s evaluation.
fn one(model: &Model, x: &[f64], u: &[f64], w: &[f64], out: &mut [f64]) -> Result<()> {
    let xs = State::from_column_slice(x);
    let us = Input::from_column_slice(u);
    let ws = Vector3::new(w[0], w[1], w[2]);
    let (xd, aux) = model.derivative(&xs, &us, &ws)?;
    check_output(&xd, &aux)?;
    out.copy_from_slice(xd.as_slice());
    Ok(())
}

/// ẋ of `n` rows into `out` (`n`·30 values). `x` holds `n` rows of 30;
/// `u` one or `n` rows of 4; `wind` (NED air-mass velocity, m/s) one or `n`
/// rows of 3, or none for still air. An error names the row (when `n` > 1)
/// and the library's reason (a non-finite component, the Euler singularity,
/// an output beyond the model's range).
pub fn derivative_rows(
    model: &Model,
    n: usize,
    x: &[f64],
    u: Rows<'_>,
    wind: Option<Rows<'_>>,
    out: &mut [f64],
) -> Result<()> {
    Rows::Each(x).check("x", NX, n)?;
    u.check("u", NU, n)?;
    const STILL: [f64; 3] = [0.0; 3];
    let wind = wind.unwrap_or(Rows::One(&STILL));
    wind.check("wind", 3, n)?;
    if out.len() != n * NX {
        return Err(Error::new(format!(
            "output buffer of {} values for {n} rows of {NX}",
            out.len()
        )));
    }
    let results: Vec<Result<()>> = out
        .par_chunks_mut(BLOCK_ROWS * NX)
        .enumerate()
        .map(|(b, block)| {
            for (k, o) in block.chunks_mut(NX).enumerate() {
                let i = b * BLOCK_ROWS + k;
                one(
                    model,
                    &x[i * NX..(i + 1) * NX],
                    u.row(i, NU),
                    wind.row(i, 3),
                    o,
                )
                .map_err(|e| {
                    if n > 1 {
                        e.context(&format!("row {i}"))
                    } else {
                        e
                    }
                })?;
            }
            Ok(())
        })
        .collect();
    results.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use helicon_model::Preset;

    fn hoverish(n: usize) -> Vec<f64> {
        let mut x = vec![0.0; n * NX];
        for i in 0..n {
            x[i * NX + 6] = 0.01 * i as f64; // u (m/s)
            x[i * NX + 22] = 0.1; // theta0 (rad)
        }
        x
    }

    #[test]
    fn a_batch_equals_single_rows_bit_for_bit() {
        let m = Model::bergen_twin(Preset::Physical);
        let n = 1100; // three blocks, the last one partial
        let x = hoverish(n);
        let u = [0.1, 0.0, 0.0, 0.05];
        let mut batch = vec![0.0; n * NX];
        derivative_rows(&m, n, &x, Rows::One(&u), None, &mut batch).unwrap();
        for i in [0, 1, 511, 512, 1099] {
            let mut single = vec![0.0; NX];
            derivative_rows(
                &m,
                1,
                &x[i * NX..(i + 1) * NX],
                Rows::One(&u),
                None,
                &mut single,
            )
            .unwrap();
            let a: Vec<u64> = batch[i * NX..(i + 1) * NX]
                .iter()
                .map(|v| v.to_bits())
                .collect();
            let b: Vec<u64> = single.iter().map(|v| v.to_bits()).collect();
            assert_eq!(a, b, "row {i}");
        }
    }

    #[test]
    fn the_first_bad_row_is_named() {
        let m = Model::bergen_twin(Preset::Physical);
        let n = 1500;
        let mut x = hoverish(n);
        x[700 * NX + 4] = f64::NAN;
        x[1400 * NX + 4] = f64::NAN;
        let mut out = vec![0.0; n * NX];
        let e = derivative_rows(&m, n, &x, Rows::One(&[0.0; 4]), None, &mut out).unwrap_err();
        assert!(e.message().starts_with("row 700: "), "{e}");
        assert!(e.message().contains("theta"), "{e}");
        let e = derivative_rows(&m, 2, &x[..NX], Rows::One(&[0.0; 4]), None, &mut out[..60])
            .unwrap_err();
        assert!(e.message().contains("x: 30 values where 60"), "{e}");
    }

    #[test]
    fn the_euler_singularity_is_an_error() {
        let m = Model::bergen_twin(Preset::Thesis);
        let mut x = vec![0.0; NX];
        x[4] = std::f64::consts::FRAC_PI_2;
        let mut out = vec![0.0; NX];
        let e = derivative_rows(&m, 1, &x, Rows::One(&[0.0; 4]), None, &mut out).unwrap_err();
        assert!(e.message().contains("singularity"), "{e}");
    }
}
