//! `helicon mc CAMPAIGN --slurm` (a job array of shards and a merge job
//! after it, submitted with `sbatch`) and `helicon mc status DIR`.
//!
//! The folder `OUT` of a Slurm campaign:
//!
//! ```text
//! OUT/                      the merged campaign (as a local run's folder)
//! OUT/shards/shard-K-of-M/  one shard folder per array task
//! OUT/slurm/array.sbatch    the array job (one task per shard)
//! OUT/slurm/merge.sbatch    the merge job
//! OUT/slurm/jobs.json       the plan and every submission's job ids
//! OUT/slurm/logs/           the jobs' output
//! ```
//!
//! Submitting again with the same command submits only what is missing: the
//! shards neither done nor queued (a task resumes its shard from the runs
//! already in its store), and a new merge job after them and after the
//! tasks still queued; a merge job of an earlier submission still pending
//! is cancelled.

use anyhow::{Context, Result, bail};
use helicon_sim::mc::{Campaign, folder_progress};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// What `--slurm` was given.
#[derive(Debug, Clone)]
pub struct SlurmRequest {
    /// Runs of the campaign.
    pub runs: usize,
    /// Array tasks (shards).
    pub array: usize,
    /// Partition.
    pub partition: Option<String>,
    /// Time limit of each task and of the merge.
    pub time: Option<String>,
    /// CPUs (threads) per task.
    pub cpus_per_task: usize,
    /// Write the scripts, submit nothing.
    pub dry_run: bool,
    /// The `helicon mc` options that make the campaign (`--seed 7`, …).
    pub campaign_args: Vec<String>,
}

/// One `sbatch` of the array and its merge job.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Submission {
    /// Array job id.
    array_job: Option<String>,
    /// Its tasks (shard numbers).
    tasks: Vec<usize>,
    /// Merge job id.
    merge_job: String,
}

/// `OUT/slurm/jobs.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Plan {
    name: String,
    hash: String,
    runs: usize,
    array: usize,
    submissions: Vec<Submission>,
}

const PLAN: &str = "slurm/jobs.json";

fn shard_dir(out: &Path, k: usize, m: usize) -> PathBuf {
    out.join("shards").join(format!("shard-{k}-of-{m}"))
}

/// `'text'` for a POSIX shell.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// A Slurm `--time`: `M`, `M:S`, `H:M:S`, `D-H`, `D-H:M` or `D-H:M:S`.
fn check_time(t: &str) -> Result<()> {
    let (days, rest) = match t.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, t),
    };
    let parts: Vec<&str> = rest.split(':').collect();
    let num = |s: &str| !s.is_empty() && s.len() <= 6 && s.bytes().all(|b| b.is_ascii_digit());
    let ok = days.is_none_or(num) && parts.len() <= 3 && parts.iter().all(|p| num(p));
    if !ok || (days.is_none() && t == "0") {
        bail!("--time `{t}`: expected minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS");
    }
    Ok(())
}

/// A partition name: letters, digits, `_`, `-`, `.`, `,`.
fn check_partition(p: &str) -> Result<()> {
    if p.is_empty()
        || !p
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"_-.,".contains(&b))
    {
        bail!("--partition `{p}`: letters, digits and _ - . , only");
    }
    Ok(())
}

fn directives(req: &SlurmRequest, out: &Path) -> String {
    let mut s = String::new();
    if let Some(p) = &req.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(t) = &req.time {
        s.push_str(&format!("#SBATCH --time={t}\n"));
    }
    s.push_str(&format!("#SBATCH --chdir={}\n", out.display()));
    s
}

/// The two batch scripts.
fn scripts(
    campaign: &Campaign,
    campaign_path: &Path,
    out: &Path,
    req: &SlurmRequest,
    helicon: &Path,
) -> (String, String) {
    let m = req.array;
    let logs = out.join("slurm").join("logs");
    let mut extra = String::new();
    for a in &req.campaign_args {
        extra.push(' ');
        extra.push_str(&quote(a));
    }
    let array = format!(
        "#!/bin/bash\n\
         # helicon mc --slurm: campaign `{name}` ({hash}), {runs} runs in {m} shards.\n\
         # Task K flies shard K/{m} into shards/shard-K-of-{m}/, resuming from the\n\
         # runs already stored there. Submitted by `helicon mc ... --slurm`\n\
         # (which picks the tasks with --array); by hand: sbatch array.sbatch\n\
         #SBATCH --job-name=helicon-{name}\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --output={logs}/task-%A_%a.out\n\
         {dir}\
         set -u\n\
         K=${{SLURM_ARRAY_TASK_ID:?not a Slurm array task}}\n\
         SHARD={shards}/shard-$K-of-{m}\n\
         mkdir -p \"$SHARD\" && rm -f \"$SHARD/slurm-exit\"\n\
         {helicon} mc {campaign} --runs {runs} --shard \"$K/{m}\" --threads {cpus} --out \"$SHARD\"{extra}\n\
         rc=$?\n\
         echo \"$rc\" > \"$SHARD/slurm-exit\"\n\
         exit \"$rc\"\n",
        name = campaign.name,
        hash = campaign.hash,
        runs = req.runs,
        last = m - 1,
        cpus = req.cpus_per_task,
        logs = logs.display(),
        dir = directives(req, out),
        shards = quote(&out.join("shards").display().to_string()),
        helicon = quote(&helicon.display().to_string()),
        campaign = quote(&campaign_path.display().to_string()),
    );
    let folders: Vec<String> = (0..m)
        .map(|k| quote(&shard_dir(out, k, m).display().to_string()))
        .collect();
    let merge = format!(
        "#!/bin/bash\n\
         # helicon mc --slurm: merge the {m} shards of campaign `{name}` into {out}\n\
         # (submitted with --dependency=afterok on the array's tasks).\n\
         #SBATCH --job-name=helicon-{name}-merge\n\
         #SBATCH --cpus-per-task=1\n\
         #SBATCH --output={logs}/merge-%j.out\n\
         {dir}\
         set -u\n\
         rm -f {exit}\n\
         {helicon} mc merge {folders} --out {outq}\n\
         rc=$?\n\
         echo \"$rc\" > {exit}\n\
         exit \"$rc\"\n",
        name = campaign.name,
        out = out.display(),
        logs = logs.display(),
        dir = directives(req, out),
        exit = quote(&out.join("slurm").join("merge-exit").display().to_string()),
        helicon = quote(&helicon.display().to_string()),
        folders = folders.join(" "),
        outq = quote(&out.display().to_string()),
    );
    (array, merge)
}

/// The state of Slurm jobs by id (`123`, `123_4`) as `squeue` and, when it
/// works, `sacct` tell it; empty when neither is there.
fn job_states(ids: &[String]) -> BTreeMap<String, (String, String)> {
    let mut states = BTreeMap::new();
    if ids.is_empty() {
        return states;
    }
    let list = ids.join(",");
    // sacct first (finished jobs), squeue over it (the live view)
    if let Ok(o) = Command::new("sacct")
        .args(["-n", "-P", "-X", "-j", &list, "-o", "JobID,State"])
        .output()
        && o.status.success()
    {
        for l in String::from_utf8_lossy(&o.stdout).lines() {
            if let Some((id, st)) = l.split_once('|') {
                let st = st.split_whitespace().next().unwrap_or("").to_string();
                states.insert(id.to_string(), (st, String::new()));
            }
        }
    }
    if let Ok(o) = Command::new("squeue")
        .args(["-h", "-r", "-t", "all", "-j", &list, "-o", "%i|%T|%r"])
        .output()
        && o.status.success()
    {
        for l in String::from_utf8_lossy(&o.stdout).lines() {
            let f: Vec<&str> = l.split('|').collect();
            if f.len() == 3 {
                states.insert(
                    f[0].trim().to_string(),
                    (f[1].to_string(), f[2].to_string()),
                );
            }
        }
    }
    states
}

fn active(state: &str) -> bool {
    matches!(
        state,
        "PENDING"
            | "RUNNING"
            | "CONFIGURING"
            | "COMPLETING"
            | "REQUEUED"
            | "RESIZING"
            | "SUSPENDED"
    )
}

/// The state of shard `k`: from its folder, its exit marker and the queue.
#[derive(Debug, Clone, PartialEq, Eq)]
enum ShardState {
    Done,
    Queued(String),
    Failed(String),
    Partial,
    Missing,
}

struct ShardView {
    state: ShardState,
    done: usize,
    runs: usize,
}

fn shard_view(
    out: &Path,
    plan: &Plan,
    k: usize,
    states: &BTreeMap<String, (String, String)>,
) -> Result<ShardView> {
    let dir = shard_dir(out, k, plan.array);
    let runs = helicon_sim::mc::Shard { k, m: plan.array }.count(plan.runs);
    let p = folder_progress(&dir).with_context(|| format!("shard folder {}", dir.display()))?;
    let done = p.as_ref().map_or(0, |p| p.done);
    if let Some(p) = &p
        && p.hash != plan.hash
    {
        bail!(
            "{}: campaign hash {} differs from the plan's {}",
            dir.display(),
            p.hash,
            plan.hash
        );
    }
    // the latest submission of this task
    let task = plan
        .submissions
        .iter()
        .rev()
        .find(|s| s.tasks.contains(&k))
        .and_then(|s| s.array_job.as_ref().map(|a| format!("{a}_{k}")));
    let queue = task
        .as_ref()
        .and_then(|t| states.get(t))
        .map(|s| s.0.clone());
    let exit = crate::files::read_text_if_present(&dir.join("slurm-exit"))
        .ok()
        .flatten()
        .map(|s| s.trim().to_string());
    let state = if p.as_ref().is_some_and(|p| p.finished) && done == runs {
        ShardState::Done
    } else if let Some(q) = queue.as_ref().filter(|q| active(q)) {
        ShardState::Queued(q.clone())
    } else if let Some(e) = exit.filter(|e| e != "0") {
        ShardState::Failed(format!("exit status {e}"))
    } else if let Some(q) = queue.filter(|q| q != "COMPLETED") {
        ShardState::Failed(q.to_lowercase())
    } else if task.is_some() && done < runs {
        ShardState::Failed("stopped (cancelled or killed)".into())
    } else if p.is_some() {
        ShardState::Partial
    } else {
        ShardState::Missing
    };
    Ok(ShardView { state, done, runs })
}

fn read_plan(out: &Path) -> Result<Option<Plan>> {
    let p = out.join(PLAN);
    match crate::files::read_text_if_present(&p)? {
        Some(t) => Ok(Some(
            serde_json::from_str(&t).with_context(|| format!("reading {}", p.display()))?,
        )),
        None => Ok(None),
    }
}

fn write_plan(out: &Path, plan: &Plan) -> Result<()> {
    let p = out.join(PLAN);
    std::fs::write(&p, serde_json::to_string_pretty(plan)?)
        .with_context(|| format!("writing {}", p.display()))
}

/// Run `sbatch --parsable ARGS`; the job id.
fn sbatch(args: &[String]) -> Result<String> {
    let o = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .context("running sbatch (is Slurm installed here? --dry-run writes the scripts only)")?;
    if !o.status.success() {
        bail!(
            "sbatch {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr).trim()
        );
    }
    let id = String::from_utf8_lossy(&o.stdout)
        .trim()
        .split(';')
        .next()
        .unwrap_or("")
        .to_string();
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        bail!(
            "sbatch printed no job id: `{}`",
            String::from_utf8_lossy(&o.stdout).trim()
        );
    }
    Ok(id)
}

/// Compact task list for `--array`: `0-3,5`.
fn ranges(tasks: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < tasks.len() {
        let mut j = i;
        while j + 1 < tasks.len() && tasks[j + 1] == tasks[j] + 1 {
            j += 1;
        }
        out.push(if i == j {
            tasks[i].to_string()
        } else {
            format!("{}-{}", tasks[i], tasks[j])
        });
        i = j + 1;
    }
    out.join(",")
}

/// `helicon mc CAMPAIGN --slurm`.
pub fn submit(
    campaign: &Campaign,
    campaign_path: &Path,
    out: &Path,
    req: &SlurmRequest,
) -> Result<()> {
    let mut con = crate::console::Console::stdout();
    submit_to(&mut con, campaign, campaign_path, out, req)?;
    con.finish().context("writing to stdout")
}

#[allow(clippy::too_many_lines)] // one submission in order: scripts, sbatch of the array, of the merge job, the record
fn submit_to(
    con: &mut crate::console::Console,
    campaign: &Campaign,
    campaign_path: &Path,
    out: &Path,
    req: &SlurmRequest,
) -> Result<()> {
    if req.array == 0 || req.array > req.runs {
        bail!("--array {}: need 1 <= K <= runs ({})", req.array, req.runs);
    }
    if req.array > 100_000 {
        bail!("--array {}: at most 100000 tasks", req.array);
    }
    if let Some(t) = &req.time {
        check_time(t)?;
    }
    if let Some(p) = &req.partition {
        check_partition(p)?;
    }
    std::fs::create_dir_all(out.join("slurm").join("logs"))
        .and_then(|()| std::fs::create_dir_all(out.join("shards")))
        .with_context(|| format!("creating {}", out.display()))?;
    let out = std::fs::canonicalize(out).with_context(|| format!("{}", out.display()))?;
    let campaign_path = std::fs::canonicalize(campaign_path)
        .with_context(|| format!("{}", campaign_path.display()))?;
    let helicon = std::env::current_exe().context("the path of this helicon")?;
    let mut plan = match read_plan(&out)? {
        Some(p) => {
            if p.hash != campaign.hash || p.runs != req.runs || p.array != req.array {
                bail!(
                    "{}: holds campaign {} ({} runs in {} shards); this is {} ({} runs in {}): use another --out",
                    out.display(),
                    p.hash,
                    p.runs,
                    p.array,
                    campaign.hash,
                    req.runs,
                    req.array
                );
            }
            p
        }
        None => Plan {
            name: campaign.name.clone(),
            hash: campaign.hash.clone(),
            runs: req.runs,
            array: req.array,
            submissions: Vec::new(),
        },
    };
    let (array_sh, merge_sh) = scripts(campaign, &campaign_path, &out, req, &helicon);
    let array_path = out.join("slurm").join("array.sbatch");
    let merge_path = out.join("slurm").join("merge.sbatch");
    for (p, text) in [(&array_path, &array_sh), (&merge_path, &merge_sh)] {
        std::fs::write(p, text).with_context(|| format!("writing {}", p.display()))?;
    }
    // what is there already
    let ids = job_ids(&plan);
    let states = if req.dry_run {
        BTreeMap::new()
    } else {
        job_states(&ids)
    };
    let mut todo = Vec::new();
    let mut queued = Vec::new();
    for k in 0..plan.array {
        match shard_view(&out, &plan, k, &states)?.state {
            ShardState::Done => {}
            ShardState::Queued(_) => queued.push(k),
            _ => todo.push(k),
        }
    }
    let merged = folder_progress(&out)?.is_some_and(|p| p.finished && p.shard.is_none());
    if todo.is_empty() && queued.is_empty() && merged {
        writeln!(
            con,
            "{}: all {} shards done and merged; nothing to submit",
            out.display(),
            plan.array
        );
        return Ok(());
    }
    let array_args = |tasks: &[usize]| {
        vec![
            format!("--array={}", ranges(tasks)),
            array_path.display().to_string(),
        ]
    };
    if req.dry_run {
        write_plan(&out, &plan)?;
        writeln!(
            con,
            "wrote {} and {}",
            array_path.display(),
            merge_path.display()
        );
        if !todo.is_empty() {
            writeln!(
                con,
                "would run: sbatch --parsable {}",
                array_args(&todo).join(" ")
            );
        }
        writeln!(
            con,
            "would run: sbatch --parsable --dependency=afterok:<array job> {}",
            merge_path.display()
        );
        return Ok(());
    }
    // a merge job of an earlier submission still waiting: replaced below
    for s in &plan.submissions {
        if states.get(&s.merge_job).is_some_and(|st| active(&st.0)) {
            let _ = Command::new("scancel").arg(&s.merge_job).status();
        }
    }
    let mut after: Vec<String> = Vec::new();
    let array_job = if todo.is_empty() {
        None
    } else {
        let id = sbatch(&array_args(&todo))?;
        writeln!(
            con,
            "tasks {} of {}: array job {id}",
            ranges(&todo),
            plan.array
        );
        after.push(id.clone());
        Some(id)
    };
    for k in &queued {
        if let Some(s) = plan.submissions.iter().rev().find(|s| s.tasks.contains(k))
            && let Some(a) = &s.array_job
        {
            after.push(format!("{a}_{k}"));
        }
    }
    if !queued.is_empty() {
        writeln!(
            con,
            "still queued, not resubmitted: tasks {}",
            ranges(&queued)
        );
    }
    let mut margs = Vec::new();
    if !after.is_empty() {
        margs.push(format!("--dependency=afterok:{}", after.join(":")));
    }
    margs.push(merge_path.display().to_string());
    let merge_job = sbatch(&margs)?;
    writeln!(
        con,
        "merge: job {merge_job}{} into {}",
        if after.is_empty() {
            String::new()
        } else {
            format!(" (afterok:{})", after.join(":"))
        },
        out.display()
    );
    plan.submissions.push(Submission {
        array_job,
        tasks: todo,
        merge_job,
    });
    write_plan(&out, &plan)?;
    writeln!(con, "follow it with: helicon mc status {}", out.display());
    Ok(())
}

fn job_ids(plan: &Plan) -> Vec<String> {
    let mut ids = Vec::new();
    for s in &plan.submissions {
        if let Some(a) = &s.array_job {
            ids.push(a.clone());
        }
        ids.push(s.merge_job.clone());
    }
    ids
}

/// `helicon mc status DIR`.
pub fn status(dir: &Path) -> Result<()> {
    let mut con = crate::console::Console::stdout();
    status_to(&mut con, dir)?;
    con.finish().context("writing to stdout")
}

fn status_to(con: &mut crate::console::Console, dir: &Path) -> Result<()> {
    let Some(plan) = read_plan(dir)? else {
        // a campaign folder run here
        let p = folder_progress(dir)?.with_context(|| {
            format!(
                "{}: not a campaign folder (no manifest.json)",
                dir.display()
            )
        })?;
        writeln!(
            con,
            "{} ({}{}): {}/{} runs done{}",
            p.name,
            p.hash,
            p.shard.map(|s| format!(", shard {s}")).unwrap_or_default(),
            p.done,
            p.runs,
            if p.finished { ", outputs written" } else { "" }
        );
        return Ok(());
    };
    let states = job_states(&job_ids(&plan));
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    let (mut done_runs, mut failed) = (0, Vec::new());
    writeln!(
        con,
        "campaign {} ({}): {} runs in {} shards, {} submission(s)",
        plan.name,
        plan.hash,
        plan.runs,
        plan.array,
        plan.submissions.len()
    );
    for k in 0..plan.array {
        let v = shard_view(dir, &plan, k, &states)?;
        done_runs += v.done;
        let (word, note) = match &v.state {
            ShardState::Done => ("done", String::new()),
            ShardState::Queued(q) if q == "PENDING" => ("pending", String::new()),
            ShardState::Queued(q) => ("running", q.to_lowercase()),
            ShardState::Failed(why) => {
                failed.push(k);
                ("failed", why.clone())
            }
            ShardState::Partial => ("partial", String::new()),
            ShardState::Missing => ("missing", String::new()),
        };
        *counts.entry(word).or_default() += 1;
        writeln!(
            con,
            "  shard {k:>4}/{}  {word:<8} {:>8}/{} runs  {note}",
            plan.array, v.done, v.runs
        );
    }
    let c = |w: &str| counts.get(w).copied().unwrap_or(0);
    writeln!(
        con,
        "shards: {} done, {} running, {} pending, {} failed, {} partial, {} missing (of {})",
        c("done"),
        c("running"),
        c("pending"),
        c("failed"),
        c("partial"),
        c("missing"),
        plan.array
    );
    writeln!(con, "runs: {done_runs}/{} done", plan.runs);
    let merged = folder_progress(dir)?.is_some_and(|p| p.finished && p.shard.is_none());
    let merge_exit = crate::files::read_text_if_present(&dir.join("slurm").join("merge-exit"))
        .ok()
        .flatten()
        .map(|s| s.trim().to_string());
    let last = plan.submissions.last().map(|s| s.merge_job.clone());
    let mstate = last.as_ref().and_then(|j| states.get(j)).cloned();
    let line = if merged {
        "done".to_string()
    } else if let Some((st, reason)) = &mstate
        && reason.contains("DependencyNeverSatisfied")
    {
        format!(
            "never (merge job {} {st}: {reason})",
            last.unwrap_or_default()
        )
    } else if !failed.is_empty() {
        let job = match (&last, &mstate) {
            (Some(j), Some((st, _))) => format!("; merge job {j} {}", st.to_lowercase()),
            _ => String::new(),
        };
        format!("never (a task failed{job})")
    } else if let Some((st, _)) = mstate.as_ref().filter(|s| active(&s.0)) {
        format!(
            "waiting (merge job {} {})",
            last.unwrap_or_default(),
            st.to_lowercase()
        )
    } else if let Some(e) = merge_exit.filter(|e| e != "0") {
        format!("failed (merge exit status {e})")
    } else {
        "not yet".to_string()
    };
    writeln!(con, "merged: {line}");
    if !failed.is_empty() || line.starts_with("never") || line.starts_with("failed") {
        writeln!(
            con,
            "resubmit what is missing with the same `helicon mc CAMPAIGN --runs {} --slurm --array {} --out {}` command",
            plan.runs,
            plan.array,
            dir.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_lists_are_compact_ranges() {
        assert_eq!(ranges(&[0, 1, 2, 3]), "0-3");
        assert_eq!(ranges(&[1]), "1");
        assert_eq!(ranges(&[0, 2, 3, 7]), "0,2-3,7");
    }

    #[test]
    fn times_and_partitions_are_checked() {
        for t in ["10", "10:00", "1:00:00", "2-0", "2-12:30", "2-12:30:00"] {
            assert!(check_time(t).is_ok(), "{t}");
        }
        for t in ["", "0", "ten", "1:2:3:4", "1-", "-5", "10 ;rm"] {
            assert!(check_time(t).is_err(), "{t}");
        }
        assert!(check_partition("gpu_a100,cpu").is_ok());
        assert!(check_partition("a b").is_err());
        assert!(check_partition("x\n#SBATCH --mem=1").is_err());
    }

    #[test]
    fn shell_quoting_survives_quotes() {
        assert_eq!(quote("it's"), "'it'\\''s'");
    }
}
