//! The simulated iCub as separate processes, as launch-configs/icub-sim/robot/README.md
//! runs it: `icub-board-emulator` (the whole 53-joint robot, every board broadcasting at
//! its configured rate) on cannelloni-over-UDP ports 20000..20009, and
//! `yarprobotinterface --config icub_all.xml` with every device of that file.
//!
//! Measures, once the robot is up:
//! 1. CPU % of each process over `ICUB_BENCH_SECONDS` (default 10) from /proc (100 % =
//!    one core), nobody reading any port;
//! 2. the same while a client reads the left arm's `state:o` and cartesian `state:o`;
//! 3. command-to-encoder latency through the whole stack: a `remote_controlboard`
//!    `positionMove` of the left elbow -> `/icub/left_arm/rpc:i` (controlBoard_nws_yarp)
//!    -> controlboardremapper -> canmotioncontrol -> CAN over UDP -> emulator -> encoder
//!    broadcast -> canmotioncontrol -> `state:o` -> the client's `getEncoder`, until the
//!    value first changes; `ICUB_BENCH_MOVES` (default 20) moves.
//!
//! Run (sockets: inside the private network namespace; the emulator must be built with
//! the same profile):
//! ```sh
//! cargo build --release -p icub-emulators --bin icub-board-emulator
//! /work/shared/netns-run cargo bench -p yarp-device-programs --bench icub
//! ```

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_net::nameserver::NameServer;
use yarp_proto::Property;

const T: Duration = Duration::from_secs(60);

/// A child process killed and reaped when dropped.
struct Reaped(Child);

impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn env_num(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// utime + stime of `pid`, in clock ticks (100 per second on Linux).
fn cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // fields after the `(comm)`, which may contain spaces
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    Some(f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?)
}

/// CPU % (of one core) of each pid over `window`.
fn cpu_percent(pids: &[u32], window: Duration) -> Vec<f64> {
    let before: Vec<u64> = pids.iter().map(|&p| cpu_ticks(p).unwrap_or(0)).collect();
    let start = Instant::now();
    std::thread::sleep(window);
    let secs = start.elapsed().as_secs_f64();
    pids.iter()
        .zip(before)
        .map(|(&p, b)| (cpu_ticks(p).unwrap_or(b) - b) as f64 / 100.0 / secs * 100.0)
        .collect()
}

fn eventually(limit: Duration, mut f: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < limit {
        if f() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    false
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is accepted
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let robot_dir = root.join("launch-configs/icub-sim/robot");
    let genova = root.join("../shared/robots-configuration/iCubGenova01");
    let emulator = std::env::current_exe()
        .ok()
        .and_then(|exe| Some(exe.parent()?.parent()?.join("icub-board-emulator")))
        .filter(|p| p.is_file());
    let Some(emulator) = emulator else {
        eprintln!("SKIPPED: icub-board-emulator not built for this profile (cargo build --release -p icub-emulators)");
        return;
    };
    let seconds = env_num("ICUB_BENCH_SECONDS", 10);
    let moves = env_num("ICUB_BENCH_MOVES", 20) as usize;

    // a name server in this process, announced through a private yarp.conf
    let conf = tempfile::tempdir().expect("temp dir");
    std::env::set_var("YARP_CONFIG_HOME", conf.path());
    let addr = yarp_devices::runtime::block_on(async {
        let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
            .await
            .expect("bind name server");
        let addr = ns.local_addr();
        tokio::spawn(ns.serve());
        addr
    })
    .expect("the device runtime");
    yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("write yarp.conf");

    let mut emu = Reaped(
        Command::new(&emulator)
            .args(["--preset", "icub", "--bus", "udp-hub://127.0.0.1:20000+n"])
            .args(["--xsens", "/tmp/icub-sim-ttyXSENS"])
            .arg("--robot-dir")
            .arg(&genova)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn emulator"),
    );
    let stdout = emu.0.stdout.take().expect("emulator stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if line == "ready" {
                let _ = tx.send(());
            }
        }
    });
    rx.recv_timeout(T).expect("emulator ready");

    let log = tempfile::NamedTempFile::new().expect("log file");
    let started = Instant::now();
    let robot = Reaped(
        Command::new(env!("CARGO_BIN_EXE_yarprobotinterface"))
            .args(["--config", "icub_all.xml"])
            .current_dir(&robot_dir)
            .stdout(Stdio::null())
            .stderr(log.reopen().expect("log"))
            .spawn()
            .expect("spawn yarprobotinterface"),
    );
    assert!(
        eventually(T, || std::fs::read_to_string(log.path())
            .is_ok_and(|t| t.contains("running happily"))),
        "yarprobotinterface did not start: {}",
        std::fs::read_to_string(log.path()).unwrap_or_default()
    );
    println!(
        "icub-sim: startup (open, attach, calibrate 8 parts over UDP) {:.2} s",
        started.elapsed().as_secs_f64()
    );
    std::thread::sleep(Duration::from_secs(1));

    let pids = [emu.0.id(), robot.0.id()];
    let idle = cpu_percent(&pids, Duration::from_secs(seconds));
    println!(
        "icub-sim CPU, no readers, {seconds} s: icub-board-emulator {:.1} %, yarprobotinterface {:.1} % (100 % = one core)",
        idle[0], idle[1]
    );

    let cfg = Property::from_config_text(
        "device remote_controlboard\nremote /icub/left_arm\nlocal /bench/left_arm\ncarrier tcp\n",
    )
    .expect("config");
    let mut arm = PolyDriver::open(&cfg).expect("remote_controlboard to /icub/left_arm");
    // the left arm's Cartesian solver: its server streams the pose once connected to it
    let solver = std::env::current_exe()
        .ok()
        .and_then(|exe| Some(exe.parent()?.parent()?.join("iKinCartesianSolver")))
        .filter(|p| p.is_file())
        .map(|p| {
            Reaped(
                Command::new(p)
                    .arg("--from")
                    .arg(robot_dir.join("cartesianSolver.ini"))
                    .args(["--part", "left_arm"])
                    .stdout(Stdio::null())
                    .stderr(Stdio::null())
                    .spawn()
                    .expect("spawn iKinCartesianSolver"),
            )
        });
    if solver.is_none() {
        println!("(no iKinCartesianSolver beside this bench: the cartesian state:o stays silent; cargo build --release -p icub-cartesian)");
    }
    let net = yarp_net::blocking::Network::from_conf().expect("network");
    let cart = yarp_net::blocking::BufferedPort::open(&net, "/bench/cartesian:i").expect("port");
    net.connect(
        "/icub/cartesianController/left_arm/state:o",
        "/bench/cartesian:i",
        None,
    )
    .expect("connect cartesian state:o");
    let poses = Arc::new(AtomicUsize::new(0));
    let counter = poses.clone();
    cart.on_read(move |_| {
        counter.fetch_add(1, Ordering::Relaxed);
    });
    let read = cpu_percent(&pids, Duration::from_secs(seconds));
    let poses = poses.load(Ordering::Relaxed);
    println!(
        "icub-sim CPU, reading left_arm state:o + cartesian state:o, {seconds} s: icub-board-emulator {:.1} %, yarprobotinterface {:.1} % ({poses} poses received)",
        read[0], read[1]
    );

    let dev = arm.device();
    assert!(eventually(T, || dev
        .as_encoders()
        .expect("encoders")
        .get_encoder(3)
        .is_ok_and(|q| (q - 45.0).abs() < 1.0)));
    dev.as_position_control()
        .expect("position control")
        .set_ref_speed(3, 60.0)
        .expect("ref speed");
    let mut lat = Vec::with_capacity(moves);
    for k in 0..moves {
        let target = if k % 2 == 0 { 50.0 } else { 45.0 };
        let before = dev.as_encoders().unwrap().get_encoder(3).unwrap();
        let t = Instant::now();
        dev.as_position_control()
            .unwrap()
            .position_move(3, target)
            .expect("position move");
        assert!(eventually(T, || dev
            .as_encoders()
            .unwrap()
            .get_encoder(3)
            .is_ok_and(|q| (q - before).abs() > 0.05)));
        lat.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(eventually(T, || dev
            .as_encoders()
            .unwrap()
            .get_encoder(3)
            .is_ok_and(|q| (q - target).abs() < 0.5)));
        std::thread::sleep(Duration::from_millis(100));
    }
    lat.sort_by(f64::total_cmp);
    println!(
        "command-to-encoder latency (positionMove -> first change on state:o), {moves} moves: min {:.1} ms, median {:.1} ms, p95 {:.1} ms, max {:.1} ms",
        lat[0],
        percentile(&lat, 0.5),
        percentile(&lat, 0.95),
        lat[lat.len() - 1]
    );
    drop(arm);
    cart.close();
    let pid = robot.0.id().to_string();
    let _ = Command::new("kill").args(["-INT", &pid]).status();
    drop(robot);
    drop(emu);
}
