//! Shared test helpers.
#![allow(dead_code)]

use nalgebra::DMatrix;

/// Reads a reference CSV with header row `row,<names>` and a first column of row names.
pub fn read_named_csv(path: &str) -> DMatrix<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .skip(1)
                .map(|c| c.trim().parse::<f64>().unwrap())
                .collect()
        })
        .collect();
    let (r, c) = (rows.len(), rows[0].len());
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

/// Fixture directory (copies of ../shared/reference/thesis_*.csv, verbatim).
pub const REF: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures");

/// Thesis hover model A (27×27) and B (27×4), Appendix E (E.1).
pub fn thesis_ab() -> (DMatrix<f64>, DMatrix<f64>) {
    (
        read_named_csv(&format!("{REF}/thesis_A.csv")),
        read_named_csv(&format!("{REF}/thesis_B.csv")),
    )
}

/// max |a − b| / max(|b|_max, tiny): relative error in the max-norm of the reference.
pub fn rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    let scale = b.amax().max(1e-300);
    (a - b).amax() / scale
}

/// Row-major matrix literal helper: `mat(2, 2, &[a, b, c, d])`.
pub fn mat(r: usize, c: usize, v: &[f64]) -> DMatrix<f64> {
    assert_eq!(v.len(), r * c);
    DMatrix::from_row_slice(r, c, v)
}
