//! `yarprobotinterface`: brings up a robot from a robots-configuration XML file
//! (C++ YARP 3.12 `yarprobotinterface`), keeps it running, and on Ctrl-C / SIGTERM runs
//! the `interrupt1` phase (parking), then `shutdown` (detach, close in reverse order).
//!
//! ```text
//! yarprobotinterface --config icub_all.xml [--portprefix /icub] [--verbose] [--dryrun]
//!                    [--keep-going] [--enable_tags "(enable_ros2 ...)"]
//!                    [--disable_tags "(disable_left_hand ...)"]
//! yarprobotinterface                # reads ./yarprobotinterface.ini (`config icub_all.xml`)
//! yarprobotinterface --from robot.ini
//! ```
//!
//! `--enable_tags` / `--disable_tags` decide which `xi:include`s with `enabled_by` /
//! `disabled_by` attributes are read, as in C++ (`enable_all` enables every one).
//!
//! A device that cannot be opened stops the startup, as in C++: its type is not in this
//! build, or its driver fails. With `--keep-going` (not in C++), devices whose type this
//! build does not provide are named and skipped with the actions on them, and devices that
//! fail to open and actions that fail at startup (say, a remapper naming a network no board
//! provides) are reported by name too and skipped with whatever depends on them; the rest
//! of the robot comes up. `/<portprefix>/yarprobotinterface`
//! answers `get_phase`, `get_level`, `get_robot`, `is_ready` and `quit`, as in C++.
//! A second signal during the interrupt phase adds `interrupt2`, a third `interrupt3`;
//! a fourth aborts at once.
//! Exit status 0 after a clean shutdown, 1 when the robot fails to load or run.
#![forbid(unsafe_code)]

use parking_lot::Mutex;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;
use yarp_devices::robotinterface::resource;
use yarp_devices::robotinterface::rpc::{self, RpcStatus};
use yarp_devices::robotinterface::{read_robot_file, ActionPhase, RobotRunner};
use yarp_devices::runtime;
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;
use yarp_proto::{Property, Value};

/// How the program learns it must stop: signals and the RPC `quit` raise `interrupted`,
/// bump `count` and wake the main thread.
#[derive(Clone)]
struct Interrupts {
    tx: mpsc::Sender<()>,
    interrupted: Arc<AtomicBool>,
    count: Arc<AtomicUsize>,
}

impl Interrupts {
    /// Records one interrupt; the fourth one exits at once.
    fn raise(&self, why: &str) {
        self.interrupted.store(true, Ordering::SeqCst);
        let n = self.count.fetch_add(1, Ordering::SeqCst) + 1;
        tracing::warn!("Interrupt #{n}# received ({why}).");
        if n > 3 {
            tracing::error!("Aborting...");
            std::process::exit(1);
        }
        let _ = self.tx.send(());
    }
}

/// Installs SIGINT/SIGTERM handlers now, so that an early signal is not lost.
fn watch_signals(interrupts: Interrupts) -> std::io::Result<()> {
    yarp_net::signals::on_signals(move |why| interrupts.raise(why))
}

/// Options: `--from FILE` (else `yarprobotinterface.ini`, C++'s default config file, when
/// found), overridden by the command line. Returns them with the directory of the file
/// they came from.
fn options(args: &[String]) -> Result<(Property, Option<PathBuf>), String> {
    let cli = Property::from_args(args);
    let context = cli.find("context").map(Value::to_string_bare);
    let from = match cli.find("from").map(Value::to_string_bare) {
        Some(name) => {
            let found = resource::find_file(&name, context.as_deref());
            Some(found.ok_or_else(|| format!("cannot find --from {name}"))?)
        }
        None => resource::find_file("yarprobotinterface.ini", context.as_deref()),
    };
    let mut options = Property::new();
    let mut base = None;
    if let Some(path) = from {
        let file = Property::from_config_file(&path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        options.merge_bottle(&file.to_bottle());
        base = path.parent().map(Path::to_path_buf);
    }
    options.merge_args(args);
    Ok((options, base))
}

/// The robot file: searched as C++ `findFile` would, else relative to the `.ini` that
/// named it.
fn config_path(options: &Property, base: Option<&Path>) -> Result<PathBuf, String> {
    let name = options
        .find("config")
        .map(Value::to_string_bare)
        .ok_or("Missing \"config\" argument")?;
    let context = options.find("context").map(Value::to_string_bare);
    if let Some(p) = resource::find_file(&name, context.as_deref()) {
        return Ok(p);
    }
    match base.map(|b| b.join(&name)) {
        Some(p) if p.is_file() => Ok(p),
        _ => Err(format!("robot file {name} not found")),
    }
}

fn check_network() -> Result<NameClient, String> {
    let client = yarp_net::network::name_client()
        .map_err(|e| e.to_string())?
        .with_timeout(Duration::from_secs(5));
    let probe = client.clone();
    runtime::block_on_result(async move {
        probe
            .query("/yarprobotinterface")
            .await
            .map_err(|e| e.to_string())
    })?;
    Ok(client)
}

/// A port served by a task until `stop` is called, then closed (and unregistered).
struct ServedPort {
    stop: tokio::sync::oneshot::Sender<()>,
    task: tokio::task::JoinHandle<()>,
}

impl ServedPort {
    fn stop(self) {
        let _ = self.stop.send(());
        let task = self.task;
        runtime::block_on_logged("yarprobotinterface: closing its port", async move {
            let _ = tokio::time::timeout(Duration::from_secs(2), task).await;
        });
    }
}

/// Serves `/<prefix>/yarprobotinterface` from `status`; `quit` raises an interrupt.
fn open_rpc_port(
    prefix: &str,
    ns: NameClient,
    status: Arc<Mutex<RpcStatus>>,
    interrupts: Interrupts,
) -> Option<ServedPort> {
    let name = format!("/{}/yarprobotinterface", prefix.trim_start_matches('/'));
    let port = match runtime::block_on_result({
        let name = name.clone();
        async move { Port::open(&name, ns).await.map_err(|e| e.to_string()) }
    }) {
        Ok(p) => p,
        Err(e) => {
            tracing::warn!("cannot open {name}: {e}");
            return None;
        }
    };
    let (stop, mut stopped) = tokio::sync::oneshot::channel();
    let task = runtime::handle().spawn(async move {
        loop {
            let mut msg = tokio::select! {
                _ = &mut stopped => break,
                msg = port.read() => match msg {
                    Some(m) => m,
                    None => break,
                },
            };
            let Ok(cmd) = msg.bottle() else { continue };
            let answer = rpc::handle(&cmd, &status.lock());
            msg.reply(answer.reply);
            if answer.quit {
                interrupts.raise("quit requested on the RPC port");
            }
        }
        port.close().await;
    });
    Some(ServedPort { stop, task })
}

fn run() -> i32 {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let verbose = Property::from_args(&args).check("verbose");
    let filter = if verbose { "debug" } else { "info" };
    let _ = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(filter)),
        )
        .with_target(false)
        .with_ansi(std::io::stderr().is_terminal())
        .without_time()
        .try_init();
    let (options, base) = match options(&args) {
        Ok(o) => o,
        Err(e) => {
            tracing::error!("{e}");
            return 1;
        }
    };
    let verbose = verbose || options.check("verbose");

    let (tx, rx) = mpsc::channel();
    let interrupts = Interrupts {
        tx,
        interrupted: Arc::new(AtomicBool::new(false)),
        count: Arc::new(AtomicUsize::new(0)),
    };
    let count = interrupts.count.clone();
    if let Err(e) = watch_signals(interrupts.clone()) {
        tracing::error!("cannot install signal handlers: {e}");
        return 1;
    }

    let path = match config_path(&options, base.as_deref()) {
        Ok(p) => p,
        Err(e) => {
            tracing::error!("{e}");
            return 1;
        }
    };
    let dryrun = options.check("dryrun");
    let ns = if dryrun {
        None
    } else {
        match check_network() {
            Ok(ns) => Some(ns),
            Err(e) => {
                tracing::error!(
                    "Sorry YARP network does not seem to be available, is the yarp server available? ({e})"
                );
                return 1;
            }
        }
    };

    // Everything but `config` is visible to the reader (`portprefix`, `extern-name`s).
    let mut reader_config = options.clone();
    reader_config.unput("config");
    tracing::info!("Reading robot config file {}", path.display());
    let loaded = match read_robot_file(&path, &reader_config) {
        Ok(l) => l,
        Err(e) => {
            tracing::error!("Config file {} not parsed correctly: {e}", path.display());
            return 1;
        }
    };
    let mut robot = loaded.robot;
    if verbose {
        robot.set_verbose();
    }
    if options.check("allow-deprecated-devices") {
        robot.add_default_param("allow-deprecated-devices", "1");
    }

    let mut runner = RobotRunner::new(robot);
    runner.set_dryrun(dryrun);
    let keep_going = options.check("keep-going");
    runner.set_keep_going(keep_going);
    let unavailable: Vec<String> = runner
        .unavailable_devices()
        .iter()
        .map(|(name, kind)| format!("{name} ({kind})"))
        .collect();
    if !unavailable.is_empty() && (keep_going || dryrun) {
        tracing::info!(
            "{} of {} devices are not available in this build and are skipped with their actions: {}",
            unavailable.len(),
            runner.robot().devices.len(),
            unavailable.join(", ")
        );
    }
    // A signal before or during startup stops it between actions.
    runner.set_interrupt_flag(interrupts.interrupted.clone());
    let status = Arc::new(Mutex::new(RpcStatus {
        robot: runner.robot().name.clone(),
        ..RpcStatus::default()
    }));
    let rpc_task = ns.and_then(|ns| {
        let prefix = runner.robot().portprefix.clone();
        open_rpc_port(&prefix, ns, status.clone(), interrupts.clone())
    });
    let progress_status = status.clone();
    runner.set_progress(Box::new(move |phase, level| {
        let mut s = progress_status.lock();
        s.phase = Some(phase);
        s.level = level;
    }));

    let mut ok = true;
    let started = runner
        .enter_phase(ActionPhase::Startup)
        .and_then(|()| runner.enter_phase(ActionPhase::Run));
    match started {
        Ok(()) => {
            if !runner.failures().is_empty() {
                tracing::warn!(
                    "--keep-going: the robot runs without {} failed device(s)/action(s): {}",
                    runner.failures().len(),
                    runner.failures().join("; ")
                );
            }
            tracing::info!(
                "yarprobotinterface running happily: robot {} ({} devices)",
                runner.robot().name,
                runner.robot().devices.len()
            );
            let _ = rx.recv();
        }
        Err(e) => {
            tracing::error!("Error in {} phase: {e}", e.phase);
            ok = false;
        }
    }

    // C++ enters interrupt1 after the first signal; further signals add interrupt2/3.
    for (phase, needed) in [
        (ActionPhase::Interrupt1, 0),
        (ActionPhase::Interrupt2, 2),
        (ActionPhase::Interrupt3, 3),
        (ActionPhase::Shutdown, 0),
    ] {
        if count.load(Ordering::SeqCst) < needed {
            continue;
        }
        if let Err(e) = runner.enter_phase(phase) {
            tracing::error!("Error in {phase} phase: {e}");
            ok = false;
        }
    }
    if let Some(port) = rpc_task {
        port.stop();
    }
    if ok {
        0
    } else {
        1
    }
}

fn main() {
    yarp_device_programs::register_all();
    // Runs for hours: keep glibc's freed pages from piling up in the RSS.
    yarp_net::heap::for_long_runs();
    let code = run();
    // Serving tasks of closed devices may still be winding down on the device runtime;
    // they must not keep the process alive.
    std::process::exit(code);
}
