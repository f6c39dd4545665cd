//! Writing the campaign outputs: runs.csv, traces.csv, statistics, plots.

use super::store::{
    Manifest, RUNS, TRACES, write_file, write_json, write_runs_csv, write_traces_csv,
};
use super::{METRIC_NAMES, McError, RunRecord, Stats, TracePoint, percentile};
use crate::plot::{LinePlot, Series};
use crate::scenario::OUTPUTS;
use std::collections::BTreeMap;
use std::path::Path;

/// Write `runs.csv`, `traces.csv`, statistics and plots from all records.
pub(super) fn finish(
    manifest: &Manifest,
    records: &BTreeMap<usize, RunRecord>,
    traces: &BTreeMap<usize, Vec<TracePoint>>,
    out: &Path,
) -> Result<Stats, McError> {
    write_runs_csv(&out.join(RUNS), &manifest.dispersed, records.values())?;
    write_traces_csv(&out.join(TRACES), traces)?;
    let recs: Vec<&RunRecord> = records.values().collect();
    let stats = Stats::from_records(&manifest.name, &manifest.hash, &recs);
    let json = out.join("stats.json");
    stats.check_finite(&json.display().to_string())?;
    write_json(&json, &stats)?;
    write_file(&out.join("stats.md"), &stats.to_markdown())?;
    plots(&recs, traces, out)?;
    Ok(stats)
}

fn plots(
    records: &[&RunRecord],
    traces: &BTreeMap<usize, Vec<TracePoint>>,
    out: &Path,
) -> Result<(), McError> {
    // histograms (as step outlines) of the rms and max errors and settling times
    for (j, m) in METRIC_NAMES.iter().enumerate() {
        if !(m.ends_with("_rms") || m.ends_with("_settling_s") || m.ends_with("_max_abs")) {
            continue;
        }
        let v: Vec<f64> = records
            .iter()
            .filter(|r| r.completed())
            .filter_map(|r| r.metrics.get(j).copied().flatten())
            .filter(|v| v.is_finite())
            .collect();
        if v.len() < 2 {
            continue;
        }
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let bins = ((v.len() as f64).sqrt().ceil() as usize).clamp(5, 50);
        let w = if hi > lo {
            (hi - lo) / bins as f64
        } else {
            1.0
        };
        let mut counts = vec![0usize; bins];
        for x in &v {
            let b = (((x - lo) / w) as usize).min(bins - 1);
            counts[b] += 1;
        }
        let mut pts = vec![(lo, 0.0)];
        for (b, c) in counts.iter().enumerate() {
            let x0 = lo + b as f64 * w;
            pts.push((x0, *c as f64));
            pts.push((x0 + w, *c as f64));
        }
        pts.push((lo + bins as f64 * w, 0.0));
        LinePlot::new(&format!("{m} (completed runs)"), m, "runs")
            .series(Series::new(m, &pts))
            .write(&out.join(format!("hist_{m}.png")))?;
    }
    // envelopes: p5 / p50 / p95 over the runs at each trace time
    let Some(len) = traces.values().map(Vec::len).max() else {
        return Ok(());
    };
    if len < 2 {
        return Ok(());
    }
    let units = ["m/s", "m/s", "m/s", "rad"];
    for (o, name) in OUTPUTS.iter().enumerate() {
        let mut bands = [Vec::new(), Vec::new(), Vec::new()];
        for k in 0..len {
            let mut v: Vec<f64> = traces
                .values()
                .filter_map(|t| t.get(k).map(|p| p.output[o]))
                .filter(|v| v.is_finite())
                .collect();
            let t = traces
                .values()
                .find_map(|t| t.get(k).map(|p| p.t_s))
                .unwrap_or(0.0);
            v.sort_by(f64::total_cmp);
            for (b, p) in [0.05, 0.5, 0.95].iter().enumerate() {
                if let Some(x) = percentile(&v, *p) {
                    bands[b].push((t, x));
                }
            }
        }
        LinePlot::new(
            &format!("{name}: envelope over runs (runs still flying)"),
            "time [s]",
            &format!("{name} [{}]", units[o]),
        )
        .series(Series::new("p5", &bands[0]))
        .series(Series::new("p50", &bands[1]))
        .series(Series::new("p95", &bands[2]))
        .write(&out.join(format!("envelope_{name}.png")))?;
    }
    Ok(())
}
