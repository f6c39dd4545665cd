//! `helicon mc CAMPAIGN.toml` (Monte Carlo campaigns, shards, merge) and
//! `helicon bench` (timings of the hot path on this machine).

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use helicon_sim::mc::{Campaign, CampaignOverrides, RunOptions, Shard, merge, run};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::time::Instant;

mod slurm;

/// `helicon mc`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct McArgs {
    /// Merge shard folders instead of running.
    #[command(subcommand)]
    pub command: Option<McCommand>,
    /// Campaign file (TOML; see docs/monte-carlo.md and campaigns/).
    #[arg(required = true)]
    pub campaign: Option<PathBuf>,
    /// Number of runs (overrides the campaign's `runs`; ≥ 1). Memory does not
    /// grow with it (each run goes to the run store on disk); bounded by the
    /// output folder's free disk space (use --shard beyond that).
    #[arg(long, value_parser = at_least_one, allow_negative_numbers = true)]
    pub runs: Option<usize>,
    /// Campaign seed (overrides the campaign's `seed`; a new campaign hash).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Flight duration in seconds (overrides the scenario's `duration_s`;
    /// finite, > 0 and <= 86400).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Nominal plant parameters: a TOML file of `helicon params` keys over the
    /// Bergen Twin (overrides the scenario's `params`); dispersions apply around it.
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Keep traces only for the runs with an index below N (overrides the
    /// campaign's `trace_runs`; a new campaign hash).
    #[arg(long, value_name = "N")]
    pub trace_runs: Option<usize>,
    /// Worker threads (default: one per core; ≥ 1).
    #[arg(long, value_parser = at_least_one)]
    pub threads: Option<usize>,
    /// Output folder (default `out/mc/<name>-seed<seed>[-shard<K>of<M>]`);
    /// runs already recorded there are skipped (resume).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run only indices ≡ K (mod M); K is 0-based (0 ≤ K < M), e.g. a Slurm
    /// array index `--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Run on a Slurm cluster: write a job array of --array shard tasks and
    /// a merge job after them (`afterok`) into OUT/slurm/, submit both with
    /// `sbatch` and print their ids. Submitting again submits only what is
    /// missing (see `helicon mc status OUT`).
    #[arg(long, conflicts_with = "shard")]
    pub slurm: bool,
    /// With --slurm: array tasks, one shard each (1 <= K <= runs; default
    /// 10, or the runs if fewer).
    #[arg(long, value_name = "K", requires = "slurm", value_parser = at_least_one)]
    pub array: Option<usize>,
    /// With --slurm: the partition (`#SBATCH --partition`).
    #[arg(long, value_name = "P", requires = "slurm")]
    pub partition: Option<String>,
    /// With --slurm: the time limit of each task and of the merge
    /// (`#SBATCH --time`: minutes, HH:MM:SS, D-HH:MM, …).
    #[arg(long, value_name = "T", requires = "slurm")]
    pub time: Option<String>,
    /// With --slurm: CPUs per task (`#SBATCH --cpus-per-task`, the task's
    /// --threads; default 1).
    #[arg(long, value_name = "C", requires = "slurm", value_parser = at_least_one)]
    pub cpus_per_task: Option<usize>,
    /// With --slurm: write the batch scripts and print the `sbatch` commands,
    /// submit nothing.
    #[arg(long, requires = "slurm")]
    pub dry_run: bool,
}

/// A whole number ≥ 1.
fn at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("must be >= 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("`{s}`: {e}")),
    }
}

/// `helicon mc` subcommands.
#[derive(Subcommand, Debug)]
pub enum McCommand {
    /// Combine shard folders of one campaign (checked by hash) into one.
    Merge(MergeArgs),
    /// How far a campaign folder is: runs done; for a `--slurm` folder, each
    /// shard done/running/pending/failed (its folder, `squeue`/`sacct`) and
    /// the merge.
    Status(StatusArgs),
}

/// `helicon mc status`.
#[derive(Args, Debug)]
pub struct StatusArgs {
    /// The campaign folder (the `--out` of `helicon mc`, with or without --slurm).
    pub dir: PathBuf,
}

/// `helicon mc merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Shard folders.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Run `helicon mc`.
pub fn run_mc(args: &McArgs) -> Result<()> {
    if let Some(McCommand::Merge(m)) = &args.command {
        let report = merge(&m.dirs, &m.out).context("merging shard folders")?;
        let s = &report.stats;
        crate::console::note!(
            "merged {} runs into {}: {} completed, {} failed ({:.1} %)",
            s.runs,
            m.out.display(),
            s.completed,
            s.failed,
            100.0 * s.failure_fraction
        );
        if let Some(g) = &s.ground {
            crate::console::note!("take-offs and landings: {}", g.headline());
        }
        return Ok(());
    }
    if let Some(McCommand::Status(st)) = &args.command {
        return slurm::status(&st.dir);
    }
    let Some(path) = &args.campaign else {
        anyhow::bail!("give a campaign file (or `helicon mc merge DIR... --out DIR`)");
    };
    let campaign = Campaign::from_file(path)?
        .with_overrides(&CampaignOverrides {
            seed: args.seed,
            duration_s: args.duration,
            params: args.params.clone(),
            trace_runs: args.trace_runs,
        })
        .with_context(|| format!("campaign {}", path.display()))?;
    let out = args.out.clone().unwrap_or_else(|| {
        let mut n = format!("{}-seed{}", campaign.name, campaign.seed);
        if let Some(s) = args.shard {
            n.push_str(&format!("-shard{}of{}", s.k, s.m));
        }
        PathBuf::from("out").join("mc").join(n)
    });
    if args.slurm {
        let runs = args.runs.unwrap_or(campaign.runs);
        let mut campaign_args = Vec::new();
        if let Some(s) = args.seed {
            campaign_args.extend(["--seed".to_string(), s.to_string()]);
        }
        if let Some(d) = args.duration {
            campaign_args.extend(["--duration".to_string(), d.to_string()]);
        }
        if let Some(p) = &args.params {
            let abs =
                std::fs::canonicalize(p).with_context(|| format!("--params {}", p.display()))?;
            campaign_args.extend(["--params".to_string(), abs.display().to_string()]);
        }
        if let Some(n) = args.trace_runs {
            campaign_args.extend(["--trace-runs".to_string(), n.to_string()]);
        }
        let req = slurm::SlurmRequest {
            runs,
            array: args.array.unwrap_or_else(|| runs.min(10)),
            partition: args.partition.clone(),
            time: args.time.clone(),
            cpus_per_task: args.cpus_per_task.unwrap_or(1),
            dry_run: args.dry_run,
            campaign_args,
        };
        return slurm::submit(&campaign, path, &out, &req);
    }
    let options = RunOptions {
        runs: args.runs,
        threads: args.threads,
        shard: args.shard,
        disk_budget_bytes: None,
    };
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs ({per_sec}, ETA {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let progress = |done: usize, total: usize| {
        if bar.length() != Some(total as u64) {
            bar.set_length(total as u64);
        }
        bar.set_position(done as u64);
    };
    let t0 = Instant::now();
    let report = run(&campaign, &options, &out, Some(&progress))
        .with_context(|| format!("campaign {}", path.display()))?;
    bar.finish_and_clear();
    let s = &report.stats;
    crate::console::note!(
        "{}: {} runs flown in {:.1} s ({} already done), {} recorded: {} completed, {} failed ({:.1} %)",
        campaign.name,
        report.flown,
        t0.elapsed().as_secs_f64(),
        report.skipped,
        s.runs,
        s.completed,
        s.failed,
        100.0 * s.failure_fraction
    );
    for f in &s.failures {
        crate::console::note!(
            "  {:6} × {}: {} (first: run {}: {})",
            f.runs,
            f.outcome,
            f.termination.as_str(),
            f.first_run,
            f.example
        );
    }
    if let Some(g) = &s.ground {
        crate::console::note!("take-offs and landings: {}", g.headline());
    }
    crate::console::note!("outputs in {}", out.display());
    Ok(())
}
