//! Statistics over the runs: percentiles, failure classes, Markdown.

use super::{METRIC_NAMES, RunRecord};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Percentiles of one metric over the completed runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MetricStats {
    /// Completed runs with a value (settling time: runs that settled).
    pub n: usize,
    /// 5th percentile.
    pub p5: Option<f64>,
    /// Median.
    pub p50: Option<f64>,
    /// 95th percentile.
    pub p95: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
}

/// Campaign statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stats {
    /// Campaign name.
    pub campaign: String,
    /// Campaign hash.
    pub hash: String,
    /// Runs recorded.
    pub runs: usize,
    /// Runs that flew the whole duration.
    pub completed: usize,
    /// Runs that did not (diverged, invalid draw, trim/design error).
    pub failed: usize,
    /// failed / runs.
    pub failure_fraction: f64,
    /// Failures by reason class (the reason without times and values).
    pub reasons: BTreeMap<String, usize>,
    /// Per metric, over completed runs.
    pub metrics: BTreeMap<String, MetricStats>,
}

/// Percentile (linear interpolation between order statistics, "type 7") of sorted data.
pub fn percentile(sorted: &[f64], p: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    Some(sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo]))
}

/// The class of a failure reason: the text before times and details, with
/// numbers replaced by `#` (so "body rate 10.02 rad/s beyond 10 rad/s" and
/// "body rate 10.04 …" count together).
pub fn reason_class(outcome: &str, reason: &str) -> String {
    let cut = [" at t = ", ": ", " ("]
        .iter()
        .filter_map(|p| reason.find(p))
        .min()
        .unwrap_or(reason.len());
    let mut head = String::with_capacity(cut);
    let mut in_number = false;
    for c in reason[..cut].trim().chars() {
        let numeric = c.is_ascii_digit() || (in_number && matches!(c, '.' | 'e' | '-' | '+'));
        if numeric {
            if !in_number {
                head.push('#');
            }
            in_number = true;
        } else {
            in_number = false;
            head.push(c);
        }
    }
    let head = head.replace("-#", "#").replace("+#", "#");
    let head = head.trim();
    if head.is_empty() {
        outcome.to_string()
    } else {
        format!("{outcome}: {head}")
    }
}

impl Stats {
    /// Statistics of records.
    pub fn from_records(name: &str, hash: &str, records: &[&RunRecord]) -> Stats {
        let runs = records.len();
        let completed: Vec<&&RunRecord> = records
            .iter()
            .filter(|r| r.outcome == "completed")
            .collect();
        let mut reasons = BTreeMap::new();
        for r in records.iter().filter(|r| r.outcome != "completed") {
            *reasons
                .entry(reason_class(&r.outcome, &r.reason))
                .or_insert(0) += 1;
        }
        let mut metrics = BTreeMap::new();
        for (j, m) in METRIC_NAMES.iter().enumerate() {
            let mut v: Vec<f64> = completed
                .iter()
                .filter_map(|r| r.metrics.get(j).copied().flatten())
                .filter(|v| v.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            let mean = if v.is_empty() {
                None
            } else {
                Some(v.iter().sum::<f64>() / v.len() as f64)
            };
            metrics.insert(
                (*m).to_string(),
                MetricStats {
                    n: v.len(),
                    p5: percentile(&v, 0.05),
                    p50: percentile(&v, 0.5),
                    p95: percentile(&v, 0.95),
                    mean,
                },
            );
        }
        let failed = runs - completed.len();
        Stats {
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
            reasons,
            metrics,
        }
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
        if !self.reasons.is_empty() {
            let _ = writeln!(s, "| failure | runs |\n|---|---:|");
            for (k, v) in &self.reasons {
                let _ = writeln!(s, "| {k} | {v} |");
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
