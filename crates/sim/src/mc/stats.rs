//! Statistics over the runs: percentiles, failures by typed class, Markdown.
//!
//! Every number written is finite: percentiles and means are taken over the
//! finite values only (a record never holds a non-finite metric), in forms
//! that cannot overflow, and [`Stats::check_finite`] refuses to write one
//! that is not. A statistic without data (`n = 0`) is `null` in
//! `stats.json` and `–` in `stats.md`.

use super::{FORMAT_VERSION, METRIC_NAMES, McError, RunOutcome, RunRecord, RunTermination};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Percentiles of one metric over the completed runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MetricStats {
    /// Completed runs with a value (settling time: runs that settled).
    pub n: usize,
    /// 5th percentile (`None` when n = 0).
    pub p5: Option<f64>,
    /// Median.
    pub p50: Option<f64>,
    /// 95th percentile.
    pub p95: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
}

/// The failed runs of one class.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FailureCount {
    /// `diverged`, `invalid` or `error`.
    pub outcome: RunOutcome,
    /// The class: the flight's termination (`rate_limit`, …), the invalid
    /// parameter key or the failing stage.
    pub termination: RunTermination,
    /// Number of runs.
    pub runs: usize,
    /// The lowest run index of the class.
    pub first_run: usize,
    /// That run's reason (an example with times and values).
    pub example: String,
}

/// Campaign statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stats {
    /// [`FORMAT_VERSION`] of the folder.
    pub format_version: u32,
    /// Campaign name.
    pub campaign: String,
    /// Campaign hash.
    pub hash: String,
    /// Runs recorded.
    pub runs: usize,
    /// Runs that flew the whole duration.
    pub completed: usize,
    /// Runs that did not (diverged, invalid draw, error).
    pub failed: usize,
    /// failed / runs.
    pub failure_fraction: f64,
    /// Failures by typed class, ordered by outcome then class.
    pub failures: Vec<FailureCount>,
    /// Per metric, over completed runs.
    pub metrics: BTreeMap<String, MetricStats>,
}

/// Percentile (linear interpolation between order statistics, "type 7") of
/// sorted finite data; finite whenever the data are.
pub fn percentile(sorted: &[f64], p: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    let (a, b, f) = (sorted[lo], sorted[hi], h - lo as f64);
    let v = a + f * (b - a);
    // b − a overflows for values near ±f64::MAX: the convex form cannot; the
    // clamp undoes rounding past the two order statistics
    let v = if v.is_finite() {
        v
    } else {
        (1.0 - f) * a + f * b
    };
    Some(v.max(a.min(b)).min(a.max(b)))
}

/// Mean of finite data; finite whenever the data are (`None` when empty).
fn mean(v: &[f64]) -> Option<f64> {
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if v.is_empty() {
        return None;
    }
    let n = v.len() as f64;
    let mut m = v.iter().sum::<f64>() / n;
    if !m.is_finite() {
        // the sum overflowed: scale by the largest magnitude first
        let s = lo.abs().max(hi.abs());
        m = s * (v.iter().map(|x| x / s).sum::<f64>() / n);
    }
    // the mean lies between the extremes; the clamp undoes rounding past them
    Some(m.max(lo).min(hi))
}

impl Stats {
    /// Statistics of records.
    pub fn from_records(name: &str, hash: &str, records: &[&RunRecord]) -> Stats {
        let runs = records.len();
        let completed: Vec<&&RunRecord> = records.iter().filter(|r| r.completed()).collect();
        let mut classes: BTreeMap<&RunTermination, FailureCount> = BTreeMap::new();
        for r in records.iter().filter(|r| !r.completed()) {
            classes
                .entry(&r.termination)
                .and_modify(|c| {
                    c.runs += 1;
                    if r.index < c.first_run {
                        c.first_run = r.index;
                        c.example.clone_from(&r.reason);
                    }
                })
                .or_insert_with(|| FailureCount {
                    outcome: r.outcome(),
                    termination: r.termination.clone(),
                    runs: 1,
                    first_run: r.index,
                    example: r.reason.clone(),
                });
        }
        let mut metrics = BTreeMap::new();
        for (j, m) in METRIC_NAMES.iter().enumerate() {
            let mut v: Vec<f64> = completed
                .iter()
                .filter_map(|r| r.metrics.get(j).copied().flatten())
                .filter(|v| v.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            metrics.insert(
                (*m).to_string(),
                MetricStats {
                    n: v.len(),
                    p5: percentile(&v, 0.05),
                    p50: percentile(&v, 0.5),
                    p95: percentile(&v, 0.95),
                    mean: mean(&v),
                },
            );
        }
        let failed = runs - completed.len();
        Stats {
            format_version: FORMAT_VERSION,
            campaign: name.to_string(),
            hash: hash.to_string(),
            runs,
            completed: completed.len(),
            failed,
            failure_fraction: if runs == 0 {
                0.0
            } else {
                failed as f64 / runs as f64
            },
            failures: classes.into_values().collect(),
            metrics,
        }
    }

    /// Refuse a statistic that is not finite (JSON would write it as `null`,
    /// indistinguishable from "no data"); `file` names the file in the error.
    pub fn check_finite(&self, file: &str) -> Result<(), McError> {
        let bad = |field: String, value: f64| McError::NonFinite {
            file: file.to_string(),
            field,
            value,
        };
        if !self.failure_fraction.is_finite() {
            return Err(bad("failure_fraction".into(), self.failure_fraction));
        }
        for (k, m) in &self.metrics {
            for (f, v) in [
                ("p5", m.p5),
                ("p50", m.p50),
                ("p95", m.p95),
                ("mean", m.mean),
            ] {
                if let Some(x) = v
                    && !x.is_finite()
                {
                    return Err(bad(format!("metrics.{k}.{f}"), x));
                }
            }
        }
        Ok(())
    }

    /// The statistics as a Markdown report.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Campaign `{}` ({})\n", self.campaign, self.hash);
        let _ = writeln!(
            s,
            "{} runs: {} completed, {} failed (failure fraction {:.3}).\n",
            self.runs, self.completed, self.failed, self.failure_fraction
        );
        if !self.failures.is_empty() {
            let _ = writeln!(
                s,
                "| outcome | termination | runs | first run | its reason |\n|---|---|---:|---:|---|"
            );
            for c in &self.failures {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} |",
                    c.outcome,
                    c.termination.as_str(),
                    c.runs,
                    c.first_run,
                    c.example.replace('|', "\\|")
                );
            }
            s.push('\n');
        }
        let _ = writeln!(
            s,
            "Over completed runs (settling: runs that settled, n):\n\n| metric | n | p5 | p50 | p95 |\n|---|---:|---:|---:|---:|"
        );
        let f = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{x:.4}"));
        for (k, m) in &self.metrics {
            let _ = writeln!(
                s,
                "| {k} | {} | {} | {} | {} |",
                m.n,
                f(m.p5),
                f(m.p50),
                f(m.p95)
            );
        }
        s
    }
}
