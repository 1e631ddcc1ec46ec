//! What the whole-robot tests share: the drivers yarprobotinterface registers, an
//! in-process name server, the emulated boards, our `yarp` program as a child process.

#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use icub_emulators::eth::{robot_boards, serve};
use icub_emulators::eth::{AddressMap, ADDRESS_MAP_ENV};
use yarp_devices::robotinterface::{read_robot_file, ActionPhase, RobotRunner};
use yarp_proto::Property;

pub const T: Duration = Duration::from_secs(30);

pub fn robot_dir(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration")
        .join(name)
}

/// The workspace's `yarp` program (same target directory), or `None` after a loud
/// notice; under CI its absence fails.
pub fn our_yarp() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let p = exe.parent()?.parent()?.join("yarp");
    if p.is_file() {
        return Some(p);
    }
    assert!(
        std::env::var("CI").is_err(),
        "{} not built (cargo build -p yarp-cli)",
        p.display()
    );
    eprintln!(
        "\n*** SKIPPED: {} not built; run `cargo build -p yarp-cli` ***\n",
        p.display()
    );
    None
}

/// C++ `yarp` of the C++ peer for `test`, or `None` after the shared missing-peer rule
/// (fails under CI).
pub fn cpp_yarp(test: &str) -> Option<PathBuf> {
    yarp_interop_tests::cpp_program(test, "yarp")
}

/// Reads `joint` (a reader of its angle, bounded by its timeout) until it is within
/// 0.5° of `target`, starting from `at`; panics naming `what` after [`T`]. The angle.
pub fn until_at(
    what: &str,
    mut joint: impl FnMut(Duration) -> Option<f64>,
    mut at: f64,
    target: f64,
) -> f64 {
    let end = Instant::now() + T;
    while (at - target).abs() > 0.5 {
        assert!(Instant::now() < end, "{what} at {at}, not {target}");
        at = joint(T).unwrap_or(at);
    }
    at
}

/// A child process whose stdout lines arrive on a channel; killed and reaped on drop.
pub struct Peer {
    pub child: Child,
    pub lines: mpsc::Receiver<String>,
}

impl Peer {
    pub fn spawn(mut cmd: Command) -> Peer {
        let mut child = cmd
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn");
        let out = child.stdout.take().unwrap();
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines().map_while(Result::ok) {
                if tx.send(l).is_err() {
                    break;
                }
            }
        });
        Peer { child, lines }
    }
    pub fn line(&self, timeout: Duration) -> Option<String> {
        self.lines.recv_timeout(timeout).ok()
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub fn start_name_server() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    std::env::set_var("YARP_CONFIG_HOME", dir.path());
    let addr = yarp_devices::runtime::block_on(async {
        let ns = yarp_interop_tests::bind_name_server().await;
        let addr = ns.local_addr();
        tokio::spawn(ns.serve());
        addr
    })
    .expect("the device runtime");
    yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("write yarp.conf");
    dir
}

/// A robot of robots-configuration, unmodified, brought up by the robot-interface runner
/// (keep-going: what does not open is named) against its emulated boards, served at the
/// robot's addresses through `map`; returns the runner and the guards to keep.
pub fn bring_up(dir: &Path, top: &Path, map: &str) -> (RobotRunner, tempfile::TempDir) {
    bring_up_with(dir, top, map, &Property::default())
}

/// [`bring_up`] with yarprobotinterface's command-line options `config` (e.g.
/// `enable_tags`).
pub fn bring_up_with(
    dir: &Path,
    top: &Path,
    map: &str,
    config: &Property,
) -> (RobotRunner, tempfile::TempDir) {
    std::env::set_var(ADDRESS_MAP_ENV, map);
    let specs = robot_boards(dir, Some(top)).expect("robot boards");
    let (_served, _threads) = serve(
        specs,
        &AddressMap::parse(map).unwrap(),
        Arc::new(AtomicBool::new(false)),
    )
    .expect("the emulator binds its addresses");
    let conf = start_name_server();
    let robot = read_robot_file(top, config)
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    // What yarprobotinterface registers: the framework's drivers, icubmod's and the
    // Cartesian controller (the robots' files open one per arm).
    yarp_devices::Registry::install(icubmod::register);
    yarp_devices::Registry::install(icub_cartesian::register);
    let mut runner = RobotRunner::new(robot);
    runner.set_keep_going(true);
    eprintln!(
        "device types this build lacks: {:?}",
        runner.unavailable_devices()
    );
    let start = Instant::now();
    runner
        .enter_phase(ActionPhase::Startup)
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("startup (open, attach, calibrate): {:?}", start.elapsed());
    eprintln!("given up at start-up: {:?}", runner.failures());
    runner.enter_phase(ActionPhase::Run).unwrap();
    (runner, conf)
}
