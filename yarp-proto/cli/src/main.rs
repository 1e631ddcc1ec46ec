//! `yarp`: the YARP command-line tool, with C++ YARP's subcommand names and flags.

mod cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "yarp", version, about = "YARP command-line tool (Rust implementation)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Bottle debugging aid: convert between YARP text and the binary wire encoding.
    #[command(subcommand)]
    Bottle(cmd::bottle::BottleCommand),
    /// Print the version of this YARP implementation.
    Version,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Bottle(c) => cmd::bottle::run(c),
        Command::Version => {
            println!("YARP version {} (Rust)", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("yarp: {e:#}");
            ExitCode::FAILURE
        }
    }
}
