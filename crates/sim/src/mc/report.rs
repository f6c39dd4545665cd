//! Writing the campaign outputs from the run store: runs.csv, traces.csv,
//! statistics, plots. Streamed in index order: memory independent of the
//! number of runs (a few slots, the statistics' counters, one histogram and
//! one envelope grid).

use super::select::percentiles;
use super::slots::{Slot, Store};
use super::stats::{PERCENTILES, SELECT_BITS, StatsAcc, counted, feed_metrics};
use super::store::{
    Manifest, RUNS, TRACE_HEADER, TRACES, create, csv_line, finish_file, io_err, record_fields,
    trace_lines, write_file, write_json,
};
use super::{McError, Stats, TracePoint, csv_header, metric_count, metric_names};
use crate::plot::{self, Figure, Panel, Series};
use crate::scenario::OUTPUTS;
use std::io::Write as _;
use std::path::Path;

/// Bits per pass of the envelopes' exact percentile selection (8 passes;
/// 4 outputs × trace points × 6 ranks × 256 counters).
const ENVELOPE_BITS: u32 = 8;

/// Every valid run of `store`, in index order, with its slot and trace length.
fn each_run(
    store: &Store,
    mut f: impl FnMut(usize, &super::RunRecord, usize) -> Result<(), McError>,
) -> Result<(), McError> {
    let mut buf = Vec::new();
    for j in 0..store.slots()? {
        if let Slot::Run(r, tlen) = store.get(j, &mut buf)? {
            f(j, &r, tlen)?;
        }
    }
    Ok(())
}

/// Write `runs.csv`, `traces.csv`, statistics and plots from the store.
pub(super) fn finish(manifest: &Manifest, store: &Store, out: &Path) -> Result<Stats, McError> {
    let runs_path = out.join(RUNS);
    let traces_path = out.join(TRACES);
    let mut wr = create(&runs_path)?;
    let mut wt = create(&traces_path)?;
    let landing = manifest.landing;
    let ground = landing.is_some();
    wr.write_all(csv_line(&csv_header(&manifest.dispersed, ground))?.as_bytes())
        .map_err(|e| io_err(&runs_path, "write", e))?;
    writeln!(wt, "{TRACE_HEADER}").map_err(|e| io_err(&traces_path, "write", e))?;
    let mut acc = StatsAcc::new(landing);
    // envelope grid: the time of sample k (from the lowest run having it)
    let mut env_t: Vec<Option<f64>> = vec![None; store.layout().trace_points];
    let mut env_len = 0usize;
    let mut tr: Vec<TracePoint> = Vec::new();
    each_run(store, |j, r, tlen| {
        wr.write_all(csv_line(&record_fields(r, landing.as_ref()))?.as_bytes())
            .map_err(|e| io_err(&runs_path, "write", e))?;
        acc.add(r);
        if tlen > 0 {
            store.trace(j, tlen, &mut tr)?;
            wt.write_all(trace_lines(r.index, &tr).as_bytes())
                .map_err(|e| io_err(&traces_path, "write", e))?;
            env_len = env_len.max(tlen);
            for (k, p) in tr.iter().enumerate() {
                env_t[k].get_or_insert(p.t_s);
            }
        }
        Ok(())
    })?;
    finish_file(&runs_path, wr)?;
    finish_file(&traces_path, wt)?;
    let (pct, _) = percentiles(
        metric_count(ground),
        &PERCENTILES,
        SELECT_BITS,
        &mut |feed| {
            each_run(store, |_, r, _| {
                feed_metrics(r, feed);
                Ok(())
            })
        },
    )?;
    let hist = histograms(store, &acc, ground)?;
    let (runs, completed) = (acc.runs, acc.completed);
    let stats = acc.finish(&manifest.name, &manifest.hash, &pct);
    let json = out.join("stats.json");
    stats.check_finite(&json.display().to_string())?;
    write_json(&json, &stats)?;
    write_file(&out.join("stats.md"), &stats.to_markdown())?;
    for h in &hist {
        plot_histogram(h, runs, completed, out)?;
    }
    envelopes(store, &env_t[..env_len], runs, out)?;
    Ok(stats)
}

/// The ground metrics plotted as histograms (campaigns with `[ground]`).
const GROUND_HISTOGRAMS: [&str; 7] = [
    "liftoff_time_s",
    "liftoff_drift_m",
    "touchdown_vertical_speed_m_s",
    "touchdown_horizontal_speed_m_s",
    "touchdown_offset_m",
    "touchdown_drift_m",
    "max_tilt_on_ground_rad",
];

/// A histogram of one metric over the runs counted in its statistics.
struct Histogram {
    metric: &'static str,
    /// The bins ([`plot::bin_layout`]).
    layout: (f64, f64, usize),
    counts: Vec<usize>,
    /// The runs whose value is counted.
    n: u64,
}

/// The histograms (one pass over the store) of the rms, max and settling
/// metrics and, with `ground`, of the take-off and landing metrics, with at
/// least two values, binned as every histogram is ([`plot::bin_layout`]).
fn histograms(store: &Store, acc: &StatsAcc, ground: bool) -> Result<Vec<Histogram>, McError> {
    let mut hs: Vec<(usize, Histogram)> = Vec::new();
    for (j, m) in metric_names(ground).enumerate() {
        if !(m.ends_with("_rms")
            || m.ends_with("_settling_s")
            || m.ends_with("_max_abs")
            || GROUND_HISTOGRAMS.contains(&m))
        {
            continue;
        }
        let a = &acc.metrics[j];
        if a.n < 2 {
            continue;
        }
        let layout = plot::bin_layout(a.n, a.lo, a.hi);
        hs.push((
            j,
            Histogram {
                metric: m,
                layout,
                counts: vec![0; layout.2],
                n: a.n,
            },
        ));
    }
    if hs.is_empty() {
        return Ok(Vec::new());
    }
    each_run(store, |_, r, _| {
        for (j, h) in &mut hs {
            if let Some(x) = r.metrics.get(*j).copied().flatten()
                && x.is_finite()
                && counted(*j, r)
            {
                h.counts[plot::bin_of(x, h.layout)] += 1;
            }
        }
        Ok(())
    })?;
    Ok(hs.into_iter().map(|(_, h)| h).collect())
}

/// The x label of metric `m`: an output's rms or peak in the output's unit
/// (`vn_rms [m/s]`, `psi_max_abs [rad]`), else its unit from its name
/// ([`plot::column_label`]).
fn metric_label(m: &str) -> String {
    if m.ends_with("_rms") || m.ends_with("_max_abs") {
        let unit = if m.starts_with("psi") { "rad" } else { "m/s" };
        format!("{m} [{unit}]")
    } else {
        plot::column_label(m)
    }
}

/// `hist_<metric>.png`: outlined bars, the metric with its unit on x, how
/// many of the campaign's `runs` (`completed` of them) are counted and why
/// the others are not.
fn plot_histogram(h: &Histogram, runs: usize, completed: usize, out: &Path) -> Result<(), McError> {
    let m = h.metric;
    let (lo, w, _) = h.layout;
    let bins = h
        .counts
        .iter()
        .enumerate()
        .map(|(b, c)| (lo + b as f64 * w, w, *c))
        .collect();
    let ground = GROUND_HISTOGRAMS.contains(&m);
    let over = if ground {
        "flown runs"
    } else {
        "completed runs"
    };
    let mut hist = plot::Histogram::of_bins(&format!("{m} ({over})"), &metric_label(m), bins)
        .note(format!("{} runs flown", runs));
    hist.y_label = "runs".into();
    let pool = if ground {
        runs
    } else {
        hist = hist.note(format!("{} completed", completed));
        completed
    };
    let missing = pool.saturating_sub(usize::try_from(h.n).unwrap_or(usize::MAX));
    if missing > 0 {
        hist = hist.note(if m.ends_with("_settling_s") {
            format!("{missing} not settled")
        } else {
            format!("{missing} without a value")
        });
        if m.ends_with("_settling_s") {
            hist = hist.note("before the end");
        }
    }
    hist.write(&out.join(format!("hist_{m}.png")))?;
    Ok(())
}

/// `envelope_<output>.png`: p5 / p50 / p95 over the runs still flying at
/// each trace sample `k` (times `grid`), exact; the note names the
/// campaign's `runs`.
fn envelopes(store: &Store, grid: &[Option<f64>], runs: usize, out: &Path) -> Result<(), McError> {
    let len = grid.len();
    if len < 2 {
        return Ok(());
    }
    let mut tr: Vec<TracePoint> = Vec::new();
    let (pct, _) = percentiles(len * 4, &PERCENTILES, ENVELOPE_BITS, &mut |feed| {
        each_run(store, |j, _, tlen| {
            if tlen > 0 {
                store.trace(j, tlen, &mut tr)?;
                for (k, p) in tr.iter().enumerate().take(len) {
                    for (o, v) in p.output.iter().enumerate() {
                        feed(k * 4 + o, *v);
                    }
                }
            }
            Ok(())
        })
    })?;
    let units = ["m/s", "m/s", "m/s", "rad"];
    for (o, name) in OUTPUTS.iter().enumerate() {
        let mut bands = [Vec::new(), Vec::new(), Vec::new()];
        for (k, t) in grid.iter().enumerate() {
            let t = t.unwrap_or(0.0);
            for (b, band) in bands.iter_mut().enumerate() {
                if let Some(x) = pct[k * 4 + o][b] {
                    band.push((t, x));
                }
            }
        }
        let mut panel = Panel::new(&format!("{name} [{}]", units[o]))
            .series(Series::new("p5", &bands[0]))
            .series(Series::new("p50", &bands[1]))
            .series(Series::new("p95", &bands[2]));
        panel.notes = vec![format!("over {runs} runs,"), "those still flying".into()];
        let mut fig = Figure::new(
            &format!("{name}: envelope over runs (runs still flying)"),
            "time [s]",
        )
        .panel(panel);
        (fig.width_px, fig.panel_height_px) = (1000, 508);
        fig.write(&out.join(format!("envelope_{name}.png")))?;
    }
    Ok(())
}
