//! `icub-robot-emulator ROBOT_DIR [--config FILE.xml] [--address-map MAP] [--can-port PORT]
//! [--serial-dir DIR] [--urdf PATH [--stance STANCE]]`: everything a robots-configuration robot's files call for, from one
//! command: its Ethernet boards (`icub-eth-emulator`), its CAN buses (`icub-board-emulator`,
//! one UDP hub per network from `--can-port`, default 20000), and its serial devices on
//! pseudo-terminals in `--serial-dir` (default: a directory of its own): the head's Xsens
//! MTx (`xsensmtx`), an Xsens MTi (`xsensmt`), a Bosch BNO055 (`imuBosch_BNO055`, on
//! a serial line even where the robot has it on I2C) and R1's RPLidars (`rpLidar2`: an A2,
//! `rpLidar3`: an A3, served by this program).
//!
//! It prints, for `yarprobotinterface` to be run with, one `env NAME=VALUE` line per
//! environment variable that points the robot's devices at the emulators
//! (`YARP_ICUB_ETH_ADDRESS_MAP`, `YARP_ICUB_CAN_BACKEND`, `YARP_ICUB_XSENS_SERIAL`,
//! `YARP_BNO055_COMPORT`, `YARP_RPLIDAR_PORTS`), then `ready` once every emulator serves. With `--urdf` the
//! Ethernet robot gets a body (`icub-eth-emulator --urdf`): its F/T sensors and its MTi
//! (the body's accelerometer its device's `sensor_name` names) read the body's statics,
//! and `push LINK FX FY FZ` lines on standard input push it. SIGINT or SIGTERM
//! stops them all (exit 0); one that stops on its own stops the rest (exit 1).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitCode, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_emulators::can_robot;
use icub_emulators::eth::{robot_boards, ADDRESS_MAP_ENV};
use yarp_devices::robotinterface::read_robot_file;
use yarp_proto::Property;

const HELP: &str = "usage: icub-robot-emulator ROBOT_DIR [--config FILE.xml] [--address-map MAP] [--can-port PORT] [--serial-dir DIR]

Emulates what the robot's files call for: Ethernet boards, CAN buses (a UDP hub per network
from PORT, default 20000) and serial IMUs on pseudo-terminals in DIR. Prints `env NAME=VALUE`
lines to run yarprobotinterface with, then `ready`.

  --config FILE.xml     the robot's top-level file (default: yarprobotinterface.ini's config)
  --address-map MAP     serve the robot's addresses elsewhere, e.g. 10.0.1.0/24=127.0.1.0/24
                        (default: $YARP_ICUB_ETH_ADDRESS_MAP; empty: the robot's own)
  --can-port PORT       first UDP port of the CAN hubs (default 20000)
  --serial-dir DIR      where the pseudo-terminals' links go (default: a new temporary one)
  --urdf PATH           the robot's body (Ethernet robots): F/T sensors and the MTi read it
  --stance STANCE       fixed-root (default) or standing:FRAME,FRAME,...";

/// How long an emulator may take to say it serves.
const START: Duration = Duration::from_secs(60);

struct Options {
    dir: PathBuf,
    config: Option<PathBuf>,
    map: String,
    can_port: u16,
    serial_dir: Option<PathBuf>,
    urdf: Option<PathBuf>,
    stance: Option<String>,
}

fn parse() -> Result<Options, String> {
    let mut args = std::env::args().skip(1);
    let mut o = Options {
        dir: PathBuf::new(),
        config: None,
        map: std::env::var(ADDRESS_MAP_ENV).unwrap_or_default(),
        can_port: 20000,
        serial_dir: None,
        urdf: None,
        stance: None,
    };
    let mut dir = None;
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--config" => o.config = Some(value()?.into()),
            "--address-map" => o.map = value()?,
            "--can-port" => {
                o.can_port = value()?.parse().map_err(|e| format!("--can-port: {e}"))?
            }
            "--serial-dir" => o.serial_dir = Some(value()?.into()),
            "--urdf" => o.urdf = Some(value()?.into()),
            "--stance" => o.stance = Some(value()?),
            "-h" | "--help" => {
                println!("{HELP}");
                std::process::exit(0)
            }
            _ if dir.is_none() && !a.starts_with('-') => dir = Some(PathBuf::from(a)),
            _ => return Err(format!("unexpected argument {a}")),
        }
    }
    o.dir = dir.ok_or("no ROBOT_DIR")?;
    Ok(o)
}

/// What the robot's top-level file calls for.
#[derive(Debug, Default)]
struct Needs {
    eth_boards: usize,
    can_networks: usize,
    mtx: bool,
    mti: bool,
    /// The MTi's `sensor_name`: the body's accelerometer it is.
    mti_sensor: Option<String>,
    bno055: bool,
    /// The RPLidars: their files' serial ports and models.
    lidars: Vec<(String, icub_emulators::rplidar::Model)>,
}

fn needs(dir: &Path, top: &Path) -> Result<Needs, String> {
    let robot = read_robot_file(top, &Property::default())
        .map_err(|e| format!("{}: {e}", top.display()))?
        .robot;
    let mut n = Needs::default();
    for d in &robot.devices {
        match d.kind.as_str() {
            "xsensmtx" => n.mtx = true,
            "xsensmt" => {
                n.mti = true;
                n.mti_sensor = d.to_property().ok().and_then(|p| {
                    p.find("sensor_name")
                        .and_then(|v| v.as_str().map(str::to_string))
                });
            }
            // on a serial line or an I2C bus: the emulated chip speaks UART for both
            // (`YARP_BNO055_COMPORT` moves the device to it)
            "imuBosch_BNO055" => n.bno055 = true,
            kind @ ("rpLidar2" | "rpLidar3") => {
                let port = d.to_property().ok().and_then(|p| {
                    p.find_group("GENERAL")
                        .and_then(|g| g.find("serial_port"))
                        .and_then(|v| v.as_str().map(str::to_string))
                });
                if let Some(port) = port {
                    // rpLidar2 drives A1/A2 lidars, rpLidar3 the A3s of R1SN001
                    let model = if kind == "rpLidar2" {
                        icub_emulators::rplidar::Model::A2
                    } else {
                        icub_emulators::rplidar::Model::A3
                    };
                    n.lidars.push((port, model));
                }
            }
            _ => {}
        }
    }
    n.can_networks = match can_robot::networks(top) {
        Ok(v) => v.len(),
        Err(can_robot::LayoutError::NoCanDevice(_)) => 0,
        Err(e) => return Err(format!("the CAN buses: {e}")),
    };
    // a robot without Ethernet boards has no electronics files
    n.eth_boards = if dir.join("hardware/electronics").is_dir() {
        robot_boards(dir, Some(top))
            .map_err(|e| format!("the Ethernet boards: {e}"))?
            .len()
    } else {
        0
    };
    Ok(n)
}

/// The robot's top-level file as `yarprobotinterface` finds it: the `config` of its
/// `yarprobotinterface.ini` (a name starting with `/` is absolute), else `icub_all.xml`.
fn top_file(dir: &Path) -> Result<PathBuf, String> {
    let file = icub_emulators::eth::robot_file(dir)
        .or_else(|_| can_robot::robot_file(dir).map_err(|e| e.to_string()))?;
    if file.is_file() {
        Ok(file)
    } else {
        Err(format!("no robot file {}", file.display()))
    }
}

/// An emulator program, reaped when dropped.
struct Running {
    name: &'static str,
    child: Child,
}

impl Drop for Running {
    fn drop(&mut self) {
        // SIGTERM first: the emulators remove their links and sockets
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(5) {
            if matches!(self.child.try_wait(), Ok(Some(_))) {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts the sibling program `name` with `args` and waits for its line containing
/// `ready`; its output goes on to our stderr.
fn start(
    name: &'static str,
    args: &[String],
    ready: &'static str,
    stdin: bool,
) -> Result<Running, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let program = exe.with_file_name(name);
    let mut child = Command::new(&program)
        .args(args)
        .stdin(if stdin { Stdio::piped() } else { Stdio::null() })
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("{}: {e}", program.display()))?;
    let out = child.stdout.take().ok_or("no stdout")?;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut told = false;
        for line in BufReader::new(out).lines().map_while(Result::ok) {
            eprintln!("[{name}] {line}");
            if !told && line.contains(ready) {
                told = tx.send(()).is_ok();
            }
        }
    });
    let running = Running { name, child };
    match rx.recv_timeout(START) {
        Ok(()) => Ok(running),
        Err(_) => Err(format!("{name} did not say `{ready}` within {START:?}")),
    }
}

fn run(o: Options, stop: &AtomicBool) -> Result<(), String> {
    let top = match &o.config {
        Some(c) if c.is_absolute() => c.clone(),
        Some(c) => o.dir.join(c),
        None => top_file(&o.dir)?,
    };
    let n = needs(&o.dir, &top)?;
    let serial_dir = match &o.serial_dir {
        Some(d) => d.clone(),
        None => std::env::temp_dir().join(format!("icub-robot-emulator-{}", std::process::id())),
    };
    std::fs::create_dir_all(&serial_dir).map_err(|e| format!("{}: {e}", serial_dir.display()))?;
    let (mtx, mti, bno) = (
        serial_dir.join("xsens-mtx"),
        serial_dir.join("xsens-mti"),
        serial_dir.join("bno055"),
    );
    let text = |p: &Path| p.display().to_string();
    let mut env = Vec::new();
    let mut running = Vec::new();
    // the CAN buses and the MTx/BNO055 (icub-board-emulator)
    if n.can_networks > 0 || n.mtx || n.bno055 {
        let mut args = Vec::new();
        if n.can_networks > 0 {
            args.extend([
                "--preset".into(),
                "icub".into(),
                "--bus".into(),
                format!("udp-hub://127.0.0.1:{}+n", o.can_port),
                "--robot-dir".into(),
                text(&o.dir),
                "--robot-file".into(),
                text(&top),
            ]);
            env.push(format!(
                "YARP_ICUB_CAN_BACKEND=udp://127.0.0.1:{}+n",
                o.can_port
            ));
        }
        if n.mtx {
            args.extend(["--xsens".into(), text(&mtx)]);
            env.push(format!("YARP_ICUB_XSENS_SERIAL={}", text(&mtx)));
        }
        if n.bno055 {
            args.extend(["--bno055".into(), text(&bno)]);
            env.push(format!("YARP_BNO055_COMPORT={}", text(&bno)));
        }
        running.push(start("icub-board-emulator", &args, "ready", false)?);
    }
    // the Ethernet boards and the MTi (icub-eth-emulator)
    if n.eth_boards > 0 || n.mti {
        let mut args = vec![text(&o.dir), "--config".into(), text(&top)];
        args.extend(["--address-map".into(), o.map.clone()]);
        if !o.map.is_empty() {
            env.push(format!("{ADDRESS_MAP_ENV}={}", o.map));
        }
        if n.mti {
            args.extend(["--xsens".into(), text(&mti)]);
            env.push(format!("YARP_ICUB_XSENS_SERIAL={}", text(&mti)));
        }
        if let Some(urdf) = &o.urdf {
            args.extend(["--urdf".into(), text(urdf)]);
            if let Some(s) = &o.stance {
                args.extend(["--stance".into(), s.clone()]);
            }
            if let Some(s) = &n.mti_sensor {
                args.extend(["--xsens-sensor".into(), s.clone()]);
            }
        }
        let mut eth = start("icub-eth-emulator", &args, "serving", o.urdf.is_some())?;
        // our standard input (`push …` lines) goes on to the body's emulator
        if let Some(mut to) = eth.child.stdin.take() {
            std::thread::spawn(move || {
                use std::io::Write;
                for line in std::io::stdin().lock().lines().map_while(Result::ok) {
                    if writeln!(to, "{line}").is_err() {
                        break;
                    }
                }
            });
        }
        running.push(eth);
    }
    // the RPLidars, on pseudo-terminals served here
    let mut lidars = Vec::new();
    let mut moved = Vec::new();
    for (k, (port, model)) in n.lidars.iter().enumerate() {
        let link = serial_dir.join(format!("rplidar-{k}"));
        let (handle, _) = icub_emulators::rplidar::pty_link(&link, *model)
            .map_err(|e| format!("RPLidar on {}: {e}", link.display()))?;
        lidars.push(handle);
        moved.push(format!("{port}={}", text(&link)));
    }
    if !moved.is_empty() {
        env.push(format!("YARP_RPLIDAR_PORTS={}", moved.join(",")));
    }
    for e in &env {
        println!("env {e}");
    }
    println!(
        "ready: {} Ethernet boards, {} CAN networks{}{}{}{}",
        n.eth_boards,
        n.can_networks,
        if n.mtx { ", Xsens MTx" } else { "" },
        if n.mti { ", Xsens MTi" } else { "" },
        if n.bno055 { ", BNO055" } else { "" },
        if n.lidars.is_empty() {
            String::new()
        } else {
            format!(", {} RPLidars", n.lidars.len())
        },
    );

    loop {
        if stop.load(Ordering::SeqCst) {
            return Ok(());
        }
        for r in &mut running {
            if let Ok(Some(status)) = r.child.try_wait() {
                return Err(format!("{} stopped: {status}", r.name));
            }
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn main() -> ExitCode {
    let o = match parse() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("icub-robot-emulator: {e}\n{HELP}");
            return ExitCode::from(2);
        }
    };
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        if let Err(e) = signal_hook::flag::register(sig, stop.clone()) {
            eprintln!("icub-robot-emulator: {e}");
            return ExitCode::FAILURE;
        }
    }
    let own_dir = o.serial_dir.is_none();
    let result = run(o, &stop);
    if own_dir {
        let dir = std::env::temp_dir().join(format!("icub-robot-emulator-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(dir);
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("icub-robot-emulator: {e}");
            ExitCode::FAILURE
        }
    }
}
