//! `yarp-launch`: runs a launch config until Ctrl-C or SIGTERM.
//!
//! ```text
//! yarp-launch launch-configs/fake-devices.toml [--dashboard 127.0.0.1:8080] [--set key=value]...
//! yarp-launch app.xml --check          # load, resolve programs, print the plan, exit
//! ```
//!
//! Exit status: 0 after a clean stop; 1 when the config cannot be loaded or started;
//! 2 with `--exit-when-ready` if something did not come up within `--ready-timeout`.

use anyhow::Context as _;
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};
use yarp_launch::config::LaunchConfig;
use yarp_launch::dashboard::Dashboard;
use yarp_launch::say;
use yarp_launch::supervisor::Launcher;

#[derive(Parser, Debug)]
#[command(name = "yarp-launch", version, about)]
struct Args {
    /// Launch config: TOML (see launch-configs/README.md) or yarpmanager application XML.
    config: PathBuf,
    /// Serve the live dashboard here (host:port; port 0 picks one). Default: the
    /// config's `dashboard.address`, else none.
    #[arg(long)]
    dashboard: Option<String>,
    /// Override a config value: `name=value` sets a variable, `a.b=value` a key,
    /// `module.NAME.key=value` a module's key (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Load the config, find every program, print the plan, and exit.
    #[arg(long)]
    check: bool,
    /// Seconds to wait for every module to be ready before reporting what is missing.
    #[arg(long, default_value_t = 60.0)]
    ready_timeout: f64,
    /// Stop everything and exit once all modules are ready (status 2 if they are not):
    /// a smoke test of a config.
    #[arg(long)]
    exit_when_ready: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let rt = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("yarp-launch: cannot start tokio: {e}");
            return ExitCode::FAILURE;
        }
    };
    match rt.block_on(run(args)) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("yarp-launch: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn print_plan(l: &Launcher) {
    let c = l.config();
    println!("launch config {:?}: {}", c.name, c.description);
    println!(
        "name server: {} (embedded: {})",
        c.name_server.address, c.name_server.embedded
    );
    for m in c.enabled_modules() {
        let after = if m.after.is_empty() {
            String::new()
        } else {
            format!("  (after {})", m.after.join(", "))
        };
        println!(
            "module {}: {} {}{after}",
            m.name,
            m.program,
            m.args.join(" ")
        );
    }
    for m in c.modules.iter().filter(|m| !m.enabled) {
        println!("module {}: disabled", m.name);
    }
    for k in &c.connections {
        println!(
            "connect {} -> {} ({})",
            k.from,
            k.to,
            k.carrier.as_deref().unwrap_or("default")
        );
    }
}

/// The "what next" block printed once everything is up.
fn print_hints(l: &Launcher, dashboard: Option<&str>, took: Duration) {
    let c = l.config();
    say(&format!(
        "{} is up in {:.1} s. Try, in another terminal:",
        if c.name.is_empty() { "launch" } else { &c.name },
        took.as_secs_f64()
    ));
    let read = c
        .dashboard
        .plot
        .clone()
        .or_else(|| c.connections.first().map(|k| k.from.clone()));
    println!("    yarp name list                      # every registered port");
    if let Some(p) = read {
        println!("    yarp read /me {p}   # print what {p} sends");
    }
    for h in &c.hints {
        println!("    {h}");
    }
    if let Some(url) = dashboard {
        println!("    open {url}   # live dashboard: port graph, plots, camera, bridge health");
    }
    println!("    Ctrl-C here stops everything.");
}

/// Serves the dashboard if `--dashboard` or the config asks for one.
async fn start_dashboard(args: &Args, launcher: &Launcher) -> anyhow::Result<Option<Dashboard>> {
    let Some(a) = args
        .dashboard
        .clone()
        .or_else(|| launcher.config().dashboard.address.clone())
    else {
        return Ok(None);
    };
    let addr =
        yarp_launch::plan::parse_address(&a).map_err(|e| anyhow::anyhow!("--dashboard: {e}"))?;
    let d = Dashboard::start(
        addr,
        launcher.status_source(),
        launcher.name_client().clone(),
        launcher.config().dashboard.clone(),
    )
    .await
    .with_context(|| format!("cannot serve the dashboard on {addr}"))?;
    say(&format!("dashboard at {}", d.url()));
    Ok(Some(d))
}

async fn run(args: Args) -> anyhow::Result<ExitCode> {
    let cfg = LaunchConfig::load(&args.config, &args.sets)?;
    let mut launcher = Launcher::new(cfg)?;
    if args.check {
        print_plan(&launcher);
        return Ok(ExitCode::SUCCESS);
    }
    let t0 = Instant::now();
    let mut sigint = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::interrupt())
        .context("installing the SIGINT handler")?;
    let mut sigterm = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
        .context("installing the SIGTERM handler")?;
    // Whatever fails from here on, modules already started are stopped first.
    if let Err(e) = launcher.start().await {
        launcher.shutdown().await;
        return Err(e.into());
    }
    let dashboard = match start_dashboard(&args, &launcher).await {
        Ok(d) => d,
        Err(e) => {
            launcher.shutdown().await;
            return Err(e);
        }
    };
    let url = dashboard.as_ref().map(Dashboard::url);
    let limit = Duration::from_secs_f64(args.ready_timeout.clamp(0.0, 3600.0));
    let mut code = ExitCode::SUCCESS;
    let stop_reason = tokio::select! {
        missing = launcher.wait_ready(limit) => {
            if missing.is_empty() {
                launcher.wait_connected(Duration::from_secs(10)).await;
                print_hints(&launcher, url.as_deref(), t0.elapsed());
            } else {
                say(&format!("not ready after {limit:?}: {} (see their log lines above)", missing.join(", ")));
                if args.exit_when_ready {
                    code = ExitCode::from(2);
                }
            }
            if args.exit_when_ready {
                "--exit-when-ready"
            } else {
                tokio::select! {
                    _ = sigint.recv() => "SIGINT",
                    _ = sigterm.recv() => "SIGTERM",
                }
            }
        }
        _ = sigint.recv() => "SIGINT",
        _ = sigterm.recv() => "SIGTERM",
    };
    say(&format!("{stop_reason}: stopping everything"));
    if let Some(d) = dashboard {
        d.shutdown().await;
    }
    launcher.shutdown().await;
    say("all modules stopped");
    Ok(code)
}
