//! `helicon log`: flight logs in ULog format (`.ulg`) — a summary, and the
//! export to CSV and text for the tools that want CSV.

use anyhow::Result;
use clap::{Args, Subcommand};
// keys, values and topic names come from the file: printed escaped
use helicon_model::config_error::escape_control as esc;
use helicon_ulog::export::{export_csv, summarize};
use helicon_ulog::visit::End;
use std::path::PathBuf;

/// `helicon log` arguments.
#[derive(Args, Debug)]
pub struct LogArgs {
    /// Subcommand.
    #[command(subcommand)]
    pub command: LogCommand,
}

/// `helicon log` subcommands.
#[derive(Subcommand, Debug)]
pub enum LogCommand {
    /// Export a ULog file: one CSV per topic instance (`<file>_<topic>_<multi_id>.csv`,
    /// timestamp in µs first) and the info, parameters and messages as text.
    Export(ExportArgs),
    /// Summarise a ULog file: information, topics with record counts, span and rate.
    Info(InfoArgs),
}

/// `helicon log export` arguments.
#[derive(Args, Debug)]
pub struct ExportArgs {
    /// The ULog file (`.ulg`).
    pub file: PathBuf,
    /// Output folder for the CSV and text files (created if needed).
    #[arg(long = "csv", value_name = "DIR")]
    pub csv: PathBuf,
}

/// `helicon log info` arguments.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The ULog file (`.ulg`).
    pub file: PathBuf,
}

/// Run a `helicon log` subcommand.
pub fn run(args: &LogArgs) -> Result<()> {
    match &args.command {
        LogCommand::Export(a) => run_export(a),
        LogCommand::Info(a) => run_info(a),
    }
}

fn truncation_note(file: &std::path::Path, end: End) {
    if let End::Truncated { offset } = end {
        crate::console::note!(
            "note: {}: truncated at byte {offset} (a writer stopped mid-message); everything before was read",
            file.display()
        );
    }
}

fn run_export(a: &ExportArgs) -> Result<()> {
    // the errors name the file, the byte offset and the rule
    let report = export_csv(&a.file, &a.csv)?;
    let mut con = crate::console::Console::stdout();
    let (mut nan, mut inf) = (0u64, 0u64);
    for ((topic, multi_id), t) in &report.topics {
        let mut marks = String::new();
        if t.nan_values > 0 {
            marks.push_str(&format!(", {} NaN", t.nan_values));
        }
        if t.infinite_values > 0 {
            marks.push_str(&format!(", {} inf", t.infinite_values));
        }
        writeln!(
            con,
            "{} {multi_id}: {} rows{marks} -> {}",
            esc(topic),
            t.stats.rows,
            t.file.display()
        );
        nan += t.nan_values;
        inf += t.infinite_values;
    }
    for f in &report.text_files {
        writeln!(con, "{}", f.display());
    }
    if nan + inf > 0 {
        // PX4's topics mark a field the vehicle does not have with NaN,
        // and a limit that does not apply (vehicle_local_position's
        // vxy_max, vz_max, hagl_*) with INFINITY
        crate::console::note!(
            "note: {nan} values NaN and {inf} infinite, per topic above (in PX4's topics NaN is \"not available\", INFINITY \"no limit\")"
        );
    }
    truncation_note(&a.file, report.pass.end);
    con.finish()?;
    Ok(())
}

fn run_info(a: &InfoArgs) -> Result<()> {
    let s = summarize(&a.file)?;
    let mut con = crate::console::Console::stdout();
    writeln!(con, "start: {} us", s.pass.start_us);
    for (k, v) in &s.info {
        writeln!(con, "info {}: {}", esc(k), esc(v));
    }
    writeln!(con, "parameters: {}", s.parameters);
    writeln!(con, "text messages: {}", s.log_messages);
    writeln!(con, "dropouts: {} ms", s.dropout_ms);
    writeln!(con, "topic multi_id records first_us last_us rate_hz");
    for ((topic, multi_id), t) in &s.topics {
        let (first, last) = t
            .first_last_us
            .map_or((String::new(), String::new()), |(f, l)| {
                (f.to_string(), l.to_string())
            });
        let rate = t.rate_hz().map_or(String::new(), |r| format!("{r:.3}"));
        writeln!(
            con,
            "{} {multi_id} {} {first} {last} {rate}",
            esc(topic),
            t.rows
        );
    }
    if s.pass.non_monotonic > 0 {
        crate::console::note!(
            "warning: {} records go back in time within their topic",
            s.pass.non_monotonic
        );
    }
    if s.pass.unknown_records > 0 {
        crate::console::note!(
            "warning: {} records of unsubscribed message ids skipped",
            s.pass.unknown_records
        );
    }
    truncation_note(&a.file, s.pass.end);
    con.finish()?;
    Ok(())
}
