//! `iKinCartesianSolver --part left_arm`: icub-main's Cartesian solver module, for the
//! `cartesiancontrollerserver` that names it in `SolverNameToConnect`. Reads the group
//! `--part` of `cartesianSolver.ini` (found as C++'s ResourceFinder finds it: `--from`,
//! context `cartesianSolver`, then the robot's directory), serves `/<name>/rpc`, `/in`
//! and `/out`, and stops at `[quit]` or Ctrl-C.
#![forbid(unsafe_code)]
// the program keeps C++'s name
#![allow(non_snake_case)]

use clap::Parser;
use icub_cartesian::solver::SolverConfig;
use icub_cartesian::solver_service::SolverService;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "iKinCartesianSolver",
    about = "icub-main's Cartesian solver module"
)]
struct Args {
    /// The group of the configuration file to run (left_arm, right_arm, left_leg, right_leg)
    #[arg(long)]
    part: Option<String>,
    /// The configuration file
    #[arg(long, default_value = "cartesianSolver.ini")]
    from: String,
    /// The ResourceFinder context
    #[arg(long, default_value = "cartesianSolver")]
    context: String,
}

fn main() -> ExitCode {
    let _ = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .try_init();
    let args = Args::parse();
    let Some(part) = args.part else {
        eprintln!("[ERROR] part option is not specified");
        return ExitCode::FAILURE;
    };
    let Some(file) =
        yarp_devices::robotinterface::resource::find_file(&args.from, Some(&args.context))
    else {
        eprintln!(
            "[ERROR] {}: no such file (context {})",
            args.from, args.context
        );
        return ExitCode::FAILURE;
    };
    let ini = match std::fs::read_to_string(&file)
        .map_err(|e| e.to_string())
        .and_then(|t| yarp_proto::Property::from_config_text(t).map_err(|e| e.to_string()))
    {
        Ok(p) => p,
        Err(e) => {
            eprintln!("[ERROR] {}: {e}", file.display());
            return ExitCode::FAILURE;
        }
    };
    let cfg = match SolverConfig::from_ini(&part, &ini) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("[ERROR] {e}");
            return ExitCode::FAILURE;
        }
    };
    let stop = Arc::new(AtomicBool::new(false));
    if let Err(e) = icub_cartesian::stop_on_signals(stop.clone()) {
        eprintln!("[ERROR] cannot install signal handlers: {e}");
        return ExitCode::FAILURE;
    }
    let mut svc = match SolverService::open(cfg) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("[ERROR] {e}");
            return ExitCode::FAILURE;
        }
    };
    svc.run(&stop);
    ExitCode::SUCCESS
}
