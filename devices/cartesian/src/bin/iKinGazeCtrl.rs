//! `iKinGazeCtrl [--from iKinGazeCtrl.ini] [--context iKinGazeCtrl] [--name ...]`: icub-main's
//! gaze controller module. The configuration file (found as C++'s ResourceFinder finds
//! it) and the command line (`--key value`, `--group::key value`) give its options; it
//! serves `/<name>/rpc`, `xd:i`, `angles:i`, `x:o`, `q:o`, `angles:o`, `events:o` and stops
//! at `[quit]` or Ctrl-C.
#![forbid(unsafe_code)]
// the program keeps C++'s name
#![allow(non_snake_case)]

use icub_cartesian::gaze::core::GazeConfig;
use icub_cartesian::gaze::service::GazeService;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use yarp_proto::Property;

/// The options: the file's, then the command line's over them (`--a::b v` sets `b` of
/// group `a`).
fn options(args: &[String]) -> Result<Property, String> {
    let cli = Property::from_command(args.iter().map(String::as_str), false);
    let text = |k: &str, d: &str| {
        cli.find(k)
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| d.to_string())
    };
    let (from, context) = (text("from", "config.ini"), text("context", "iKinGazeCtrl"));
    let mut p = match yarp_devices::robotinterface::resource::find_file(&from, Some(&context)) {
        Some(file) => {
            let t =
                std::fs::read_to_string(&file).map_err(|e| format!("{}: {e}", file.display()))?;
            Property::from_config_text(t).map_err(|e| format!("{}: {e}", file.display()))?
        }
        None if cli.check("from") => {
            return Err(format!("{from}: no such file (context {context})"))
        }
        None => Property::new(),
    };
    // the command line over the file, as C++'s ResourceFinder (`--a::b v` in group a)
    p.merge_args(args);
    Ok(p)
}

fn main() -> ExitCode {
    let _ = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .try_init();
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--help" || a == "-h") {
        println!("iKinGazeCtrl [--from FILE] [--context CTX] [--name NAME] [--robot R] [--head_version vX.Y] [--torso off] [--trajectory_time::neck S] [--trajectory_time::eyes S] [--imu::mode off] [--ping_robot_tmo S]");
        return ExitCode::SUCCESS;
    }
    let p = match options(&args) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("[ERROR] {e}");
            return ExitCode::FAILURE;
        }
    };
    let cfg = GazeConfig::from_property(&p);
    let stop = Arc::new(AtomicBool::new(false));
    if let Err(e) = icub_cartesian::stop_on_signals(stop.clone()) {
        eprintln!("[ERROR] cannot install signal handlers: {e}");
        return ExitCode::FAILURE;
    }
    let mut svc = match GazeService::open(cfg) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("[ERROR] {e}");
            return ExitCode::FAILURE;
        }
    };
    svc.run(&stop);
    ExitCode::SUCCESS
}
