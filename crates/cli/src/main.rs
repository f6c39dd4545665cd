//! `helicon`: model, trim, linearize, estimate and control miniature helicopters.

use clap::{Parser, Subcommand};

/// helicon: model, trim, linearize, estimate and control miniature helicopters.
#[derive(Parser)]
#[command(name = "helicon", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {}
}
