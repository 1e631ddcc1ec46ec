//! `icub-board-emulator`: emulated iCub boards on CAN buses.
//!
//! ```text
//! icub-board-emulator --bus udp-hub://127.0.0.1:20001 --board 1:mc --board 2:mc --board 13:strain
//! icub-board-emulator --preset icub --bus udp-hub://127.0.0.1:20000+n --robot-dir ../shared/robots-configuration/iCubGenova01
//! icub-board-emulator --preset icub --bus udp-hub://127.0.0.1:20000+n   # launch-configs/icub-sim/robot
//! icub-board-emulator --config boards.txt
//! icub-board-emulator --xsens /tmp/ttyXSENS      # the head's Xsens MTx on a pseudo-terminal
//! icub-board-emulator --bno055 /tmp/ttyBNO       # the head's Bosch BNO055 on a pseudo-terminal
//! ```
//!
//! With `--preset icub` the boards are those of the robot directory's CAN devices, read
//! with the robot interface's XML reader (see `icub_emulators::can_robot`); without
//! `--robot-dir` it is the simulated iCub shipped in `launch-configs/icub-sim/robot`.
//!
//! On start it prints one `bus <name> <local address>` line per bus, then `ready`.
//! SIGINT or SIGTERM stops it cleanly (exit 0; its `--xsens` and `--bno055` links are removed).

use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use clap::Parser;
use icub_can::bus::config::BusSpec;
use icub_can::bus::udp::UdpBus;
use icub_can::emulator::network::{self, parse_file};
use icub_can::emulator::{board_from_spec, Board, BusEmulator, EmulatorHandle};
use icub_can::CanBus;
use icub_emulators::can_robot;

#[derive(Parser, Debug)]
#[command(
    version,
    about = "Emulates iCub CAN boards (motor control, strain, MAIS, skin, MTB) on CAN buses"
)]
struct Args {
    /// Bus URL (inproc://, udp://, udp-hub://, socketcan://). With --preset, `+n` or `{n}`
    /// in the URL is replaced per network (e.g. udp-hub://127.0.0.1:20000+n).
    #[arg(long)]
    bus: Option<String>,
    /// A board on --bus, as ADDRESS:KIND with KIND one of mc, strain, mais, skin, mtb.
    #[arg(long = "board", value_name = "ADDRESS:KIND")]
    boards: Vec<String>,
    /// Description file with `bus URL` and `board ADDRESS KIND` lines.
    #[arg(long)]
    config: Option<String>,
    /// A whole robot: `icub`, every CAN board of the robot in --robot-dir, one bus per
    /// network (`CanDeviceNum`).
    #[arg(long)]
    preset: Option<String>,
    /// The robots-configuration directory of --preset (default: the simulated iCub of
    /// launch-configs/icub-sim/robot).
    #[arg(long)]
    robot_dir: Option<String>,
    /// The robot file in --robot-dir (default: icub_all.xml, else the `config` of its
    /// yarprobotinterface.ini).
    #[arg(long)]
    robot_file: Option<String>,
    /// Simulation step in milliseconds.
    #[arg(long, default_value_t = 1.0)]
    tick_ms: f64,
    /// Broadcasts of a bus go out together once every this many milliseconds (one
    /// datagram for many frames, as cannelloni's send timeout does); frame rates are
    /// unchanged, replies go out at once. 0: after every simulation step.
    #[arg(long, default_value_t = 10.0)]
    batch_ms: f64,
    /// Exit after this many seconds (default: run until killed).
    #[arg(long)]
    duration_s: Option<f64>,
    /// Start sensor boards (strain, MAIS, MTB inertial) streaming without a host.
    #[arg(long)]
    stream: bool,
    /// Also emulate the head's Xsens MTx (xsensmtx) on a pseudo-terminal reachable at this
    /// path (a symbolic link; name it as `serial`, or in YARP_ICUB_XSENS_SERIAL).
    #[arg(long, value_name = "PATH")]
    xsens: Option<std::path::PathBuf>,
    /// Also emulate the head's Bosch BNO055 (imuBosch_BNO055) on a pseudo-terminal reachable
    /// at this path (a symbolic link; name it as `comport`, or in YARP_BNO055_COMPORT).
    #[arg(long, value_name = "PATH")]
    bno055: Option<std::path::PathBuf>,
    /// Print frame counters to stderr every this many seconds (0 = never).
    #[arg(long, default_value_t = 0.0)]
    stats_every_s: f64,
}

fn open(url: &str, num: Option<u32>) -> Result<(Arc<dyn CanBus>, String), String> {
    let spec = BusSpec::parse(url, num).map_err(|e| e.to_string())?;
    // A hub bound to port 0 is only useful if we tell where it landed.
    if let BusSpec::UdpHub(bind) = &spec {
        let hub = UdpBus::hub(bind).map_err(|e| e.to_string())?;
        let local = hub.local_addr().map_err(|e| e.to_string())?.to_string();
        return Ok((Arc::new(hub), local));
    }
    let bus = spec.open().map_err(|e| e.to_string())?;
    let name = bus.name().to_string();
    Ok((bus, name))
}

/// An opened bus, its printable local address, and the boards to run on it.
type Planned = (Arc<dyn CanBus>, String, Vec<Box<dyn Board>>);

/// Prints a line; a closed stdout (e.g. piped into `head`) must not stop the emulator.
fn say(line: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}").and_then(|()| out.flush());
}

fn run(args: Args) -> Result<(), String> {
    let mut plan: Vec<Planned> = Vec::new();
    if let Some(p) = &args.preset {
        if p != "icub" {
            return Err(format!("unknown preset {p:?} (known: icub)"));
        }
        let url = args
            .bus
            .as_deref()
            .ok_or("--preset needs --bus with `+n` or `{n}`")?;
        if !url.contains("+n") && !url.contains("{n}") {
            return Err("--preset needs one bus per network: put `+n` or `{n}` in --bus".into());
        }
        let dir = match &args.robot_dir {
            Some(d) => std::path::PathBuf::from(d),
            None => std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../launch-configs/icub-sim/robot"),
        };
        let file = match &args.robot_file {
            Some(f) => dir.join(f),
            None => can_robot::robot_file(&dir).map_err(|e| e.to_string())?,
        };
        for net in can_robot::networks(&file).map_err(|e| e.to_string())? {
            let (bus, local) = open(url, Some(net.num))?;
            plan.push((bus, local, network::build(&net)));
        }
    } else if !args.boards.is_empty() {
        let url = args.bus.as_deref().ok_or("--board needs --bus")?;
        let boards = args
            .boards
            .iter()
            .map(|s| board_from_spec(s))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| e.to_string())?;
        let (bus, local) = open(url, None)?;
        plan.push((bus, local, boards));
    }
    if let Some(path) = &args.config {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
        for (url, boards) in parse_file(path, &text).map_err(|e| e.to_string())? {
            let (bus, local) = open(&url, None)?;
            plan.push((bus, local, boards));
        }
    }
    if plan.is_empty() && args.xsens.is_none() && args.bno055.is_none() {
        return Err(
            "nothing to emulate: give --board, --preset, --config, --xsens or --bno055 (see --help)"
                .into(),
        );
    }
    if !(0.1..=100.0).contains(&args.tick_ms) {
        return Err("--tick-ms must be within 0.1..=100".into());
    }
    if !(0.0..=100.0).contains(&args.batch_ms) {
        return Err("--batch-ms must be within 0..=100".into());
    }
    let tick = Duration::from_secs_f64(args.tick_ms / 1000.0);
    let batch = Duration::from_secs_f64(args.batch_ms / 1000.0);
    let mut running: Vec<EmulatorHandle> = Vec::new();
    for (bus, local, boards) in plan {
        let kinds: Vec<String> = boards
            .iter()
            .map(|b| format!("{}:{}", b.address(), b.kind()))
            .collect();
        say(&format!(
            "bus {} {} boards {}",
            bus.name(),
            local,
            kinds.join(",")
        ));
        let mut emu = BusEmulator::new(bus, boards)
            .with_tick(tick)
            .with_batch(batch);
        if args.stream {
            emu = emu.start_streaming();
        }
        running.push(emu.spawn().map_err(|e| e.to_string())?);
    }
    let _mtx = match &args.xsens {
        Some(link) => {
            let (mtx, pts) = icub_can::emulator::mtx::pty_link(link)
                .map_err(|e| format!("--xsens {}: {e}", link.display()))?;
            say(&format!("xsens {} {}", link.display(), pts.display()));
            Some(mtx)
        }
        None => None,
    };
    let _bno055 = match &args.bno055 {
        Some(link) => {
            let (chip, pts) = icub_emulators::bno055::pty_link(link)
                .map_err(|e| format!("--bno055 {}: {e}", link.display()))?;
            say(&format!("bno055 {} {}", link.display(), pts.display()));
            Some(chip)
        }
        None => None,
    };
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(sig, stop.clone()).map_err(|e| e.to_string())?;
    }
    say("ready");
    let start = Instant::now();
    let mut last_stats = Instant::now();
    loop {
        std::thread::sleep(Duration::from_millis(50));
        if stop.load(Ordering::SeqCst) {
            break;
        }
        if args
            .duration_s
            .is_some_and(|d| start.elapsed().as_secs_f64() >= d)
        {
            break;
        }
        if args.stats_every_s > 0.0 && last_stats.elapsed().as_secs_f64() >= args.stats_every_s {
            last_stats = Instant::now();
            for h in &running {
                let s = h.stats();
                eprintln!(
                    "{}: in {} out {} malformed {} ticks {} send-errors {}",
                    h.name(),
                    s.frames_in.load(Ordering::Relaxed),
                    s.frames_out.load(Ordering::Relaxed),
                    s.malformed.load(Ordering::Relaxed),
                    s.ticks.load(Ordering::Relaxed),
                    s.send_errors.load(Ordering::Relaxed)
                );
            }
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("icub-board-emulator: {e}");
            ExitCode::from(2)
        }
    }
}
