//! Statistics over the runs: percentiles, failures by typed class, Markdown.
//!
//! Computed in memory independent of the number of runs: counts, extremes,
//! compensated sums and failure classes in one pass over the runs in index
//! order, and the percentiles exact (not estimated), by radix selection in
//! a few more passes over the run store (see `select.rs`).
//!
//! Every number written is finite: percentiles and means are taken over the
//! finite values only (a record never holds a non-finite metric), in forms
//! that cannot overflow, and [`Stats::check_finite`] refuses to write one
//! that is not. A statistic without data (`n = 0`) is `null` in
//! `stats.json` and `–` in `stats.md`.

use super::landing::{LandingCriteria, LandingFailure, Z_95, wilson_interval};
use super::select::{interpolate, percentiles};
use super::{
    FORMAT_VERSION, GROUND_METRIC_NAMES, METRIC_NAMES, McError, RunOutcome, RunRecord,
    RunTermination, metric_count,
};
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

/// One ground metric over the flown runs that have it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroundMetricStats {
    /// Runs with a value (e.g. touchdown metrics: runs that touched down).
    pub n: usize,
    /// 5th percentile (`None` when n = 0).
    pub p5: Option<f64>,
    /// Median.
    pub p50: Option<f64>,
    /// 95th percentile.
    pub p95: Option<f64>,
    /// Largest value.
    pub max: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
}

/// The runs that failed one take-off or landing criterion.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CriterionCount {
    /// The criterion.
    pub criterion: LandingFailure,
    /// Runs that failed it (a run may fail several).
    pub runs: usize,
    /// The lowest run index that failed it (`None`: none did).
    pub first_run: Option<usize>,
}

/// The take-offs and landings of a campaign with `[ground]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroundStats {
    /// The limits the runs were judged by.
    pub criteria: LandingCriteria,
    /// Runs recorded.
    pub runs: usize,
    /// Runs that failed at least one criterion (not flown and diverged
    /// runs included).
    pub failed: usize,
    /// failed / runs.
    pub failure_rate: f64,
    /// Confidence level of the interval (0.95).
    pub confidence: f64,
    /// Wilson score interval of the failure rate: lower bound.
    pub failure_rate_low: f64,
    /// Upper bound.
    pub failure_rate_high: f64,
    /// Runs per criterion, in [`LandingFailure::ALL`] order (every
    /// criterion, zeros included).
    pub criteria_failed: Vec<CriterionCount>,
    /// Per ground metric ([`GROUND_METRIC_NAMES`]), over every flown run
    /// that has the value (completed or diverged).
    pub metrics: BTreeMap<String, GroundMetricStats>,
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
    /// Take-offs and landings (campaigns with `[ground]` only; absent from
    /// `stats.json` otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground: Option<GroundStats>,
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
    Some(interpolate(sorted[lo], sorted[hi], h - lo as f64))
}

/// The percentiles of `stats.json`.
pub(super) const PERCENTILES: [f64; 3] = [0.05, 0.5, 0.95];

/// Bits per pass of the exact percentile selection over the runs
/// (6 passes; 20 metrics × 6 ranks × 2048 counters: 2 MB).
pub(super) const SELECT_BITS: u32 = 11;

/// Neumaier-compensated sum, plus the same sum scaled by 2⁻⁶⁴ for when the
/// plain one overflows (finite data near ±f64::MAX).
#[derive(Debug, Clone, Copy, Default)]
struct Sum {
    s: f64,
    c: f64,
    scaled: f64,
    scaled_c: f64,
}

fn neumaier(s: &mut f64, c: &mut f64, x: f64) {
    let t = *s + x;
    if s.abs() >= x.abs() {
        *c += (*s - t) + x;
    } else {
        *c += (x - t) + *s;
    }
    *s = t;
}

impl Sum {
    fn add(&mut self, x: f64) {
        neumaier(&mut self.s, &mut self.c, x);
        neumaier(&mut self.scaled, &mut self.scaled_c, x * 2f64.powi(-64));
    }

    /// The mean of `n` values in `[lo, hi]`, finite whenever they are.
    fn mean(&self, n: u64, lo: f64, hi: f64) -> Option<f64> {
        if n == 0 {
            return None;
        }
        let nf = n as f64;
        let total = self.s + self.c;
        let m = if total.is_finite() {
            total / nf
        } else {
            (self.scaled + self.scaled_c) / nf * 2f64.powi(64)
        };
        // the mean lies between the extremes; the clamp undoes rounding past them
        Some(m.max(lo).min(hi))
    }
}

/// One metric over the completed runs, accumulated in one pass.
#[derive(Debug, Clone, Copy)]
pub(super) struct MetricAcc {
    /// Finite values seen.
    pub(super) n: u64,
    /// Smallest.
    pub(super) lo: f64,
    /// Largest.
    pub(super) hi: f64,
    sum: Sum,
}

impl Default for MetricAcc {
    fn default() -> Self {
        MetricAcc {
            n: 0,
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            sum: Sum::default(),
        }
    }
}

/// Everything of [`Stats`] but the percentiles, accumulated run by run in
/// index order, in memory independent of the number of runs (the failure
/// classes are bounded by the kinds of termination and parameter keys).
#[derive(Debug, Clone, Default)]
pub(super) struct StatsAcc {
    /// Runs counted.
    pub(super) runs: usize,
    /// Runs completed (their flight metrics enter the statistics).
    pub(super) completed: usize,
    classes: BTreeMap<RunTermination, FailureCount>,
    /// Per metric, in [`metric_names`](super::metric_names) order.
    pub(super) metrics: Vec<MetricAcc>,
    /// The landing criteria (campaigns with `[ground]`).
    landing: Option<LandingCriteria>,
    /// Runs failing a landing criterion.
    landing_failed: usize,
    /// Per criterion ([`LandingFailure::ALL`] order): runs and the first one.
    criteria: [(usize, Option<usize>); LandingFailure::ALL.len()],
}

/// Does metric `j` of run `r` enter the statistics? The flight metrics of
/// completed runs; the ground metrics of every run that has them.
pub(super) fn counted(j: usize, r: &RunRecord) -> bool {
    j >= METRIC_NAMES.len() || r.completed()
}

impl StatsAcc {
    /// The accumulator of a campaign; `landing`: its criteria, when it has `[ground]`.
    pub(super) fn new(landing: Option<LandingCriteria>) -> StatsAcc {
        StatsAcc {
            metrics: vec![MetricAcc::default(); metric_count(landing.is_some())],
            landing,
            ..StatsAcc::default()
        }
    }

    /// Count one run.
    pub(super) fn add(&mut self, r: &RunRecord) {
        self.runs += 1;
        if let Some(l) = &self.landing {
            let verdict = l.classify(r);
            if !verdict.ok() {
                self.landing_failed += 1;
            }
            for f in verdict.failures() {
                let c = &mut self.criteria[f as usize];
                c.0 += 1;
                c.1 = Some(c.1.map_or(r.index, |i| i.min(r.index)));
            }
        }
        for (j, (acc, v)) in self.metrics.iter_mut().zip(&r.metrics).enumerate() {
            if let Some(x) = *v
                && x.is_finite()
                && counted(j, r)
            {
                acc.n += 1;
                acc.lo = acc.lo.min(x);
                acc.hi = acc.hi.max(x);
                acc.sum.add(x);
            }
        }
        if r.completed() {
            self.completed += 1;
            return;
        }
        match self.classes.get_mut(&r.termination) {
            Some(c) => {
                c.runs += 1;
                if r.index < c.first_run {
                    c.first_run = r.index;
                    c.example.clone_from(&r.reason);
                }
            }
            None => {
                self.classes.insert(
                    r.termination.clone(),
                    FailureCount {
                        outcome: r.outcome(),
                        termination: r.termination.clone(),
                        runs: 1,
                        first_run: r.index,
                        example: r.reason.clone(),
                    },
                );
            }
        }
    }

    /// The statistics, given the percentiles ([`PERCENTILES`]) of each metric.
    pub(super) fn finish(self, name: &str, hash: &str, pct: &[Vec<Option<f64>>]) -> Stats {
        let mut metrics = BTreeMap::new();
        for (j, m) in METRIC_NAMES.iter().enumerate() {
            let a = self.metrics[j];
            let p = |i: usize| pct.get(j).and_then(|v| v.get(i)).copied().flatten();
            metrics.insert(
                (*m).to_string(),
                MetricStats {
                    n: usize::try_from(a.n).unwrap_or(usize::MAX),
                    p5: p(0),
                    p50: p(1),
                    p95: p(2),
                    mean: a.sum.mean(a.n, a.lo, a.hi),
                },
            );
        }
        let failed = self.runs - self.completed;
        let ground = self.landing.map(|criteria| {
            let mut gm = BTreeMap::new();
            for (g, name) in GROUND_METRIC_NAMES.iter().enumerate() {
                let j = METRIC_NAMES.len() + g;
                let a = self.metrics[j];
                let p = |i: usize| pct.get(j).and_then(|v| v.get(i)).copied().flatten();
                gm.insert(
                    (*name).to_string(),
                    GroundMetricStats {
                        n: usize::try_from(a.n).unwrap_or(usize::MAX),
                        p5: p(0),
                        p50: p(1),
                        p95: p(2),
                        max: (a.n > 0).then_some(a.hi),
                        mean: a.sum.mean(a.n, a.lo, a.hi),
                    },
                );
            }
            let (lo, hi) = wilson_interval(self.landing_failed, self.runs, Z_95);
            GroundStats {
                criteria,
                runs: self.runs,
                failed: self.landing_failed,
                failure_rate: if self.runs == 0 {
                    0.0
                } else {
                    self.landing_failed as f64 / self.runs as f64
                },
                confidence: 0.95,
                failure_rate_low: lo,
                failure_rate_high: hi,
                criteria_failed: LandingFailure::ALL
                    .iter()
                    .zip(self.criteria)
                    .map(|(c, (runs, first_run))| CriterionCount {
                        criterion: *c,
                        runs,
                        first_run,
                    })
                    .collect(),
                metrics: gm,
            }
        });
        Stats {
            format_version: FORMAT_VERSION,
            campaign: name.to_string(),
            hash: hash.to_string(),
            runs: self.runs,
            completed: self.completed,
            failed,
            failure_fraction: if self.runs == 0 {
                0.0
            } else {
                failed as f64 / self.runs as f64
            },
            failures: self.classes.into_values().collect(),
            metrics,
            ground,
        }
    }
}

/// Feed the finite metrics of completed runs to a percentile selection
/// (stream = metric index).
pub(super) fn feed_metrics(r: &RunRecord, feed: &mut dyn FnMut(usize, f64)) {
    for (j, v) in r.metrics.iter().enumerate() {
        if let Some(x) = *v
            && counted(j, r)
        {
            feed(j, x);
        }
    }
}

impl Stats {
    /// Statistics of records (in memory; a campaign streams its store
    /// through the same accumulator and selection, with the same result).
    /// Means are compensated sums in the order given.
    pub fn from_records(name: &str, hash: &str, records: &[&RunRecord]) -> Stats {
        Self::from_records_with(name, hash, None, records)
    }

    /// [`Stats::from_records`] of a campaign with `[ground]` when `landing`
    /// is given (its records carry the ground metrics): with the take-off
    /// and landing statistics.
    pub fn from_records_with(
        name: &str,
        hash: &str,
        landing: Option<LandingCriteria>,
        records: &[&RunRecord],
    ) -> Stats {
        let mut acc = StatsAcc::new(landing);
        for r in records {
            acc.add(r);
        }
        let count = metric_count(landing.is_some());
        let pct = percentiles(count, &PERCENTILES, SELECT_BITS, &mut |feed| {
            for r in records {
                feed_metrics(r, feed);
            }
            Ok(())
        })
        .map(|(p, _)| p)
        .unwrap_or_default();
        acc.finish(name, hash, &pct)
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
        if let Some(g) = &self.ground {
            for (f, x) in [
                ("failure_rate", g.failure_rate),
                ("failure_rate_low", g.failure_rate_low),
                ("failure_rate_high", g.failure_rate_high),
            ] {
                if !x.is_finite() {
                    return Err(bad(format!("ground.{f}"), x));
                }
            }
            for (k, m) in &g.metrics {
                for (f, v) in [
                    ("p5", m.p5),
                    ("p50", m.p50),
                    ("p95", m.p95),
                    ("max", m.max),
                    ("mean", m.mean),
                ] {
                    if let Some(x) = v
                        && !x.is_finite()
                    {
                        return Err(bad(format!("ground.metrics.{k}.{f}"), x));
                    }
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
        if let Some(g) = &self.ground {
            g.markdown(&mut s);
        }
        s
    }
}

impl GroundStats {
    /// One line: the failures, the rate and its interval, the criteria
    /// failed (`4 of 200 runs failed (failure rate 2.0 %, 95 % Wilson
    /// interval 0.8 % – 5.0 %): 1 diverged, 3 tip_over`).
    pub fn headline(&self) -> String {
        let pc = |x: f64| format!("{:.1} %", 100.0 * x);
        let mut s = format!(
            "{} of {} runs failed (failure rate {}, {:.0} % Wilson interval {} – {})",
            self.failed,
            self.runs,
            pc(self.failure_rate),
            100.0 * self.confidence,
            pc(self.failure_rate_low),
            pc(self.failure_rate_high)
        );
        let failed: Vec<String> = self
            .criteria_failed
            .iter()
            .filter(|c| c.runs > 0)
            .map(|c| format!("{} {}", c.runs, c.criterion.as_str()))
            .collect();
        if !failed.is_empty() {
            s.push_str(": ");
            s.push_str(&failed.join(", "));
        }
        s
    }

    /// The take-off and landing section of `stats.md`.
    fn markdown(&self, s: &mut String) {
        let _ = writeln!(s, "\n## Take-offs and landings\n\n{}.\n", self.headline());
        let c = &self.criteria;
        let limit = |x: f64| {
            if x.is_finite() {
                format!("{x}")
            } else {
                "off".into()
            }
        };
        let limits = [
            "–".to_string(),
            "–".to_string(),
            format!("{} s after take-off", limit(c.max_liftoff_delay_s)),
            format!("{} m", limit(c.max_liftoff_drift_m)),
            format!("{} rad", limit(c.max_tilt_on_ground_rad)),
            "–".to_string(),
            format!("{} m/s", limit(c.max_touchdown_vertical_speed_m_s)),
            format!("{} m/s", limit(c.max_touchdown_horizontal_speed_m_s)),
            format!("{} m", limit(c.max_touchdown_offset_m)),
            format!("{} m", limit(c.max_touchdown_drift_m)),
        ];
        let _ = writeln!(
            s,
            "| criterion | limit | runs | first run |\n|---|---|---:|---:|"
        );
        for (cc, l) in self.criteria_failed.iter().zip(limits) {
            let _ = writeln!(
                s,
                "| {} | {l} | {} | {} |",
                cc.criterion.as_str(),
                cc.runs,
                cc.first_run.map_or("–".to_string(), |i| i.to_string())
            );
        }
        let f = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{x:.4}"));
        let _ = writeln!(
            s,
            "\nOver the flown runs that have the value:\n\n| metric | n | p50 | p95 | max |\n|---|---:|---:|---:|---:|"
        );
        for name in GROUND_METRIC_NAMES {
            if let Some(m) = self.metrics.get(name) {
                let _ = writeln!(
                    s,
                    "| {name} | {} | {} | {} | {} |",
                    m.n,
                    f(m.p50),
                    f(m.p95),
                    f(m.max)
                );
            }
        }
    }
}
