//! Writing the campaign outputs: runs.csv, traces.csv, statistics, plots.

use super::store::{
    Manifest, RUNS, TRACES, write_file, write_json, write_runs_csv, write_traces_csv,
};
use super::{METRIC_NAMES, McError, RunRecord, Stats, TracePoint, percentile};
use crate::plot::{Histogram, LinePlot, Series};
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
    // histograms of the rms and max errors and settling times, each saying
    // how many of the runs it holds and why the others are not in it
    let completed = records.iter().filter(|r| r.completed()).count();
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
        let (label, what) = metric_axis(m);
        let mut h = Histogram::new(
            &format!("{what}: {} of {} runs", v.len(), records.len()),
            &label,
            &v,
        );
        h.notes.push(format!("{} runs flown", records.len()));
        h.notes.push(format!("{completed} completed"));
        let missing = completed - v.len();
        if missing > 0 {
            h.notes
                .push(format!("{missing} completed without a value:"));
            h.notes.push(if m.ends_with("_settling_s") {
                "  not settled before the end".to_string()
            } else {
                "  no step on this output".to_string()
            });
        }
        h.write(&out.join(format!("hist_{m}.png")))?;
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

/// The x label (with unit) and the title of a metric's histogram.
fn metric_axis(metric: &str) -> (String, String) {
    let (output, kind) = metric.split_once('_').unwrap_or((metric, ""));
    let unit = if output == "psi" { "rad" } else { "m/s" };
    let symbol = if output == "psi" { "ψ" } else { output };
    match kind {
        "settling_s" => (
            format!("{symbol} settling time [s]"),
            format!("{symbol} settling time"),
        ),
        "rms" => (
            format!("{symbol} RMS error [{unit}]"),
            format!("{symbol} RMS tracking error"),
        ),
        "max_abs" => (
            format!("{symbol} largest |error| [{unit}]"),
            format!("{symbol} largest tracking error"),
        ),
        _ => (metric.to_string(), metric.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::metric_axis;

    #[test]
    fn histogram_axes_carry_units() {
        assert_eq!(metric_axis("vd_settling_s").0, "vd settling time [s]");
        assert_eq!(metric_axis("psi_rms").0, "ψ RMS error [rad]");
        assert_eq!(metric_axis("vn_max_abs").0, "vn largest |error| [m/s]");
    }
}
