//! `helicon`: model, trim, linearize, estimate and control miniature helicopters.

use clap::{CommandFactory, Parser, Subcommand};

mod bench_cmd;
mod console;
mod control;
mod demo;
mod design_cmd;
mod files;
mod gcs_cmd;
mod ident_cmd;
mod ident_fit;
mod ident_ground;
mod ident_servo;
mod ident_ss;
mod log_cmd;
mod mc_cmd;
mod model_cmd;
mod onboard_cmd;
mod sensors;
mod shaker_cmd;
mod signals;
mod sim_cmd;
mod sitl_cmd;
mod trim_cmd;

/// helicon: model, trim, linearize, estimate and control miniature helicopters.
#[derive(Parser)]
#[command(name = "helicon", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The main job on the embedded Bergen Twin: trim, linearize, design, fly closed loop (writes out/demo).
    Demo(demo::DemoArgs),
    /// Evaluate the nonlinear model ẋ = f(x, u, wind) for JSON lines (stdin or --input).
    Eval(model_cmd::EvalArgs),
    /// Print the effective model parameters as TOML (a starting point for your helicopter).
    Params(model_cmd::ParamsArgs),
    /// Trim at a steady flight condition (or sweep the envelope with --sweep).
    Trim(trim_cmd::TrimArgs),
    /// Trim and linearize: A.csv, B.csv, poles.csv, summary.json (and Phi/Gamma with --discrete).
    Linearize(trim_cmd::LinearizeArgs),
    /// Gain schedule over the flight envelope: design at a grid of operating points, frozen-point check, envelope map.
    Design(design_cmd::DesignArgs),
    /// Linear control design: DARE, dlqr (pincer), Kalman gain, c2d (JSON out).
    Control(control::ControlArgs),
    /// Batch Wahba solver (q-method, thesis §13.2) over a CSV of vector observations.
    Attitude(sensors::AttitudeArgs),
    /// Sensor simulation (IMU, magnetometer, GPS).
    Sensors(sensors::SensorsArgs),
    /// Replay a sensor log through attitude determination and the fusion filter (§13.3).
    Fuse(sensors::FuseArgs),
    /// Flight logs (ULog): export to CSV, summarise.
    Log(log_cmd::LogArgs),
    /// Monte Carlo campaign: dispersed parameters, wind and sensor seeds (rayon, shards, resume).
    Mc(mc_cmd::McArgs),
    /// Time the hot path on this machine: derivative, closed-loop step, real-time factor.
    Bench(bench_cmd::BenchArgs),
    /// Fly a closed-loop scenario (TOML): log.csv, summary.json, gains, plots, report.
    Sim(sim_cmd::SimArgs),
    /// Software in the loop: the simulator as the hardware on pseudo-terminals, the on-board runtime flying it.
    Sitl(sitl_cmd::SitlArgs),
    /// The on-board program: device drivers, 400 Hz control task, avionics, ULog logger.
    Onboard(onboard_cmd::OnboardArgs),
    /// Frequency-domain system identification: frequency responses from logs, transfer-function fits.
    Ident(ident_cmd::IdentArgs),
    /// A terminal ground station: vehicles' MAVLink state once a second, and commands from stdin (arm, takeoff, missions, parameters, waits).
    Gcs(gcs_cmd::GcsArgs),
    /// Print a shell completion script for SHELL (bash, zsh, fish, elvish, powershell), made from this command line's definition.
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff) of helicon, made from this command line's definition: `helicon man > helicon.1; man ./helicon.1`.
    Man {
        /// Write helicon.1 and a page per subcommand (helicon-sim.1, …) into DIR instead.
        #[arg(long, value_name = "DIR")]
        out: Option<std::path::PathBuf>,
    },
}

/// Exit status 130 or 143 for a run stopped by SIGINT or SIGTERM (its files
/// written, see [`signals`]).
///
/// Exit status 0 on a closed stdout pipe (`helicon sim … | head -1`): the
/// reader asked for no more, and the command's files are complete (see
/// [`console::Console`]). A shell pipeline therefore succeeds, as with
/// `set -o pipefail` users expect of a producer they cut short on purpose.
fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // A run ended by SIGINT/SIGTERM: its files are complete; the exit
        // status is the shell's for a death by that signal (128 + number).
        Err(e) if e.downcast_ref::<signals::Stopped>().is_some() => {
            use std::io::Write;
            let code = e
                .downcast_ref::<signals::Stopped>()
                .map_or(1, signals::Stopped::exit_code);
            let _ = writeln!(std::io::stderr(), "helicon: {}", error_text(&e));
            std::process::ExitCode::from(code)
        }
        // A closed pipe (`helicon ... | head`) is not an error.
        Err(e)
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            // One line, each cause once, no backtrace: errors here are the
            // user's input. (A closed stderr is ignored: nowhere to say it.)
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "error: {}", error_text(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by `: `, each said once: a cause whose
/// text the message so far already ends with (a `#[error("…: {0}")]` layer
/// that also exposes the cause as its `source`) is not repeated.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if text.is_empty() {
            text = c;
        } else if !text.ends_with(c.as_str()) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}

fn run() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Demo(a) => demo::run(&a),
        Command::Eval(a) => model_cmd::run_eval(&a),
        Command::Params(a) => model_cmd::run_params(&a),
        Command::Trim(a) => trim_cmd::run_trim(&a),
        Command::Linearize(a) => trim_cmd::run_linearize(&a),
        Command::Control(args) => control::run(args),
        Command::Design(a) => design_cmd::run(&a),
        Command::Attitude(a) => sensors::run_attitude(&a),
        Command::Sensors(a) => match a.command {
            sensors::SensorsCommand::Simulate(s) => sensors::run_simulate(&s),
            sensors::SensorsCommand::Config => sensors::run_sensors_config(),
            sensors::SensorsCommand::Shaker(s) => shaker_cmd::run_shaker(&s),
        },
        Command::Fuse(a) => sensors::run_fuse(&a),
        Command::Log(a) => log_cmd::run(&a),
        Command::Mc(a) => mc_cmd::run_mc(&a),
        Command::Bench(a) => bench_cmd::run_bench(&a),
        Command::Sim(a) => sim_cmd::run(&a),
        Command::Sitl(a) => sitl_cmd::run(&a),
        Command::Onboard(a) => onboard_cmd::run(&a),
        Command::Ident(a) => ident_cmd::run(&a),
        Command::Gcs(a) => gcs_cmd::run(&a),
        Command::Completions { shell } => {
            let mut cmd = Cli::command();
            let mut out = std::io::stdout().lock();
            clap_complete::generate(shell, &mut cmd, "helicon", &mut out);
            std::io::Write::flush(&mut out)?;
            Ok(())
        }
        Command::Man { out: None } => {
            let mut out = std::io::stdout().lock();
            clap_mangen::Man::new(Cli::command()).render(&mut out)?;
            std::io::Write::flush(&mut out)?;
            Ok(())
        }
        Command::Man { out: Some(dir) } => write_man_pages(&dir),
    }
}

/// `helicon man --out DIR`: `helicon.1` and one page per subcommand, its
/// own subcommands included (`helicon-ident-frf.1`), and a one-line summary.
fn write_man_pages(dir: &std::path::Path) -> anyhow::Result<()> {
    use anyhow::Context as _;
    fn pages(
        cmd: clap::Command,
        name: String,
        dir: &std::path::Path,
        n: &mut usize,
    ) -> anyhow::Result<()> {
        let path = dir.join(format!("{name}.1"));
        let mut text = Vec::new();
        clap_mangen::Man::new(cmd.clone())
            .title(name.clone())
            .render(&mut text)?;
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
        *n += 1;
        for sub in cmd.get_subcommands().filter(|s| s.get_name() != "help") {
            pages(sub.clone(), format!("{name}-{}", sub.get_name()), dir, n)?;
        }
        Ok(())
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut cmd = Cli::command();
    cmd.build();
    let mut n = 0;
    pages(cmd, "helicon".to_string(), dir, &mut n)?;
    console::note!(
        "wrote {n} manual pages to {} (man {}/helicon.1)",
        dir.display(),
        dir.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::error_text;
    use std::fmt;

    #[derive(Debug)]
    struct Inner;
    impl fmt::Display for Inner {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("trim is not physical: S_col = 8.6")
        }
    }
    impl std::error::Error for Inner {}

    /// A `#[error("design point: {0}")]` layer with `#[from]`: its Display
    /// already holds the cause, which is also its `source`.
    #[derive(Debug)]
    struct Outer(Inner);
    impl fmt::Display for Outer {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "design point: {}", self.0)
        }
    }
    impl std::error::Error for Outer {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn each_cause_is_said_once() {
        let e = anyhow::Error::new(Outer(Inner)).context("scenario `x`: preparing");
        assert_eq!(
            error_text(&e),
            "scenario `x`: preparing: design point: trim is not physical: S_col = 8.6"
        );
        // a cause not already said is appended
        let e = anyhow::Error::new(Inner).context("scenario `x`");
        assert_eq!(
            error_text(&e),
            "scenario `x`: trim is not physical: S_col = 8.6"
        );
    }
}
