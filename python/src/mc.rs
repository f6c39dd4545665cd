//! Monte Carlo campaigns in memory: the runs of `helicon mc`, each flown by
//! [`Campaign::run_one`] (so a run's record depends only on the campaign
//! and its index, whatever the threads), collected by index, with the
//! statistics of `stats.json`. Nothing is written to disk.
//!
//! A campaign can be stopped between runs: workers test a flag before
//! starting each run (the bindings set it on Ctrl-C), and a stopped
//! campaign returns [`Error`] `interrupted`.

use crate::error::{Error, Result};
use helicon_sim::mc::{Campaign, CampaignOverrides, RunOutput, Stats};
use helicon_sim::resources::memory_budget;
use rayon::prelude::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The message of a campaign stopped by its flag.
pub const INTERRUPTED: &str = "interrupted";

/// Load a campaign file with the CLI's overrides (`--seed`, `--duration`,
/// `--params`).
pub fn load_campaign(
    path: &Path,
    seed: Option<u64>,
    duration_s: Option<f64>,
    params: Option<PathBuf>,
) -> Result<Campaign> {
    let c = Campaign::from_file(path)?;
    if seed.is_none() && duration_s.is_none() && params.is_none() {
        return Ok(c);
    }
    let params = match params {
        Some(p) => Some(std::path::absolute(&p).map_err(|e| {
            Error::new(format!(
                "params {}: cannot resolve the path: {e}",
                p.display()
            ))
        })?),
        None => None,
    };
    Ok(c.with_overrides(&CampaignOverrides {
        seed,
        duration_s,
        params,
        trace_runs: None,
    })?)
}

/// A finished campaign.
#[derive(Debug, Clone)]
pub struct McRun {
    /// The dispersed parameter keys, in file order (the columns of
    /// [`RunOutput::record`]`.values`).
    pub dispersed: Vec<String>,
    /// Every run, by index.
    pub runs: Vec<RunOutput>,
    /// `stats.json`.
    pub stats: Value,
}

/// Fly runs `0..runs` (default: the campaign's) on `threads` workers
/// (default: one per core). `stop` is tested before each run; `done`
/// counts finished runs. Refused before anything is flown: zero runs, more
/// runs than the memory budget holds, a nominal design that fails, a
/// scenario beyond the work bound.
pub fn run_campaign(
    c: &Campaign,
    runs: Option<usize>,
    threads: Option<usize>,
    stop: &AtomicBool,
    done: &AtomicUsize,
) -> Result<McRun> {
    let runs = runs.unwrap_or(c.runs);
    if runs == 0 {
        return Err(Error::new("runs = 0: must be >= 1"));
    }
    if threads == Some(0) {
        return Err(Error::new(
            "threads = 0: must be >= 1 (or None for one per core)",
        ));
    }
    // every run is kept in memory here: its record and trace cost about what
    // the run store gives a traced run on disk
    let fp = c.footprint();
    let bytes_per_run = fp.disk_bytes_per_traced_run.max(1);
    let (budget, why) = memory_budget();
    let workers = threads.unwrap_or_else(rayon::current_num_threads).max(1) as u64;
    let working = fp.bytes_per_flight.saturating_mul(workers);
    let max_runs = budget.saturating_sub(working) / bytes_per_run;
    if runs as u64 > max_runs {
        return Err(Error::new(format!(
            "{runs} runs need {} MiB (at {} bytes a run, plus {} MiB of flights in progress), beyond the {} MiB budget ({why}): fly fewer runs, or lower trace_rate_hz",
            (bytes_per_run.saturating_mul(runs as u64) + working) >> 20,
            bytes_per_run,
            working >> 20,
            budget >> 20
        )));
    }
    let nominal = c.prepare_nominal()?;
    c.scenario.check_work(
        &format!("campaign `{}` scenario", c.name),
        nominal.gains.set.sample_time_s,
    )?;
    let work = || -> Vec<Option<RunOutput>> {
        (0..runs)
            .into_par_iter()
            .map(|i| {
                if stop.load(Ordering::Relaxed) {
                    return None;
                }
                let o = c.run_one(&nominal, i);
                done.fetch_add(1, Ordering::Relaxed);
                Some(o)
            })
            .collect()
    };
    let outputs = match threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map_err(|e| Error::new(format!("threads = {t}: {e}")))?
            .install(work),
        None => work(),
    };
    if stop.load(Ordering::Relaxed) {
        return Err(Error::new(INTERRUPTED));
    }
    let runs: Vec<RunOutput> = outputs.into_iter().flatten().collect();
    let records: Vec<_> = runs.iter().map(|o| &o.record).collect();
    let stats = serde_json::to_value(Stats::from_records(&c.name, &c.hash, &records))
        .map_err(|e| Error::new(format!("campaign `{}`: the statistics: {e}", c.name)))?;
    Ok(McRun {
        dispersed: c.dispersions.iter().map(|d| d.param.clone()).collect(),
        runs,
        stats,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAMPAIGN: &str = r#"
name = "t"
runs = 3
seed = 11
trace_rate_hz = 20.0
[scenario]
name = "s"
duration_s = 0.1
[[dispersion]]
param = "body.mass_kg"
distribution = "uniform"
kind = "relative"
half_width = 0.05
"#;

    #[test]
    fn runs_are_by_index_and_independent_of_threads() {
        let c = Campaign::from_toml_str(CAMPAIGN, "t.toml", None).unwrap();
        let (stop, done) = (AtomicBool::new(false), AtomicUsize::new(0));
        let a = run_campaign(&c, None, Some(1), &stop, &done).unwrap();
        let b = run_campaign(&c, Some(3), Some(2), &stop, &done).unwrap();
        assert_eq!(a.runs.len(), 3);
        assert_eq!(done.load(Ordering::Relaxed), 6);
        for (x, y) in a.runs.iter().zip(&b.runs) {
            assert_eq!(x.record, y.record);
        }
        assert_eq!(a.dispersed, vec!["body.mass_kg".to_string()]);
        assert_eq!(a.stats["runs"], serde_json::json!(3));
    }

    #[test]
    fn a_stopped_campaign_and_bad_counts_are_errors() {
        let c = Campaign::from_toml_str(CAMPAIGN, "t.toml", None).unwrap();
        let (stop, done) = (AtomicBool::new(true), AtomicUsize::new(0));
        let e = run_campaign(&c, None, None, &stop, &done).unwrap_err();
        assert_eq!(e.message(), INTERRUPTED);
        stop.store(false, Ordering::Relaxed);
        assert!(run_campaign(&c, Some(0), None, &stop, &done).is_err());
        assert!(run_campaign(&c, None, Some(0), &stop, &done).is_err());
    }
}
