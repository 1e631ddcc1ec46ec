//! iCubGenova02 as a whole, unmodified from robots-configuration, brought up by the
//! robot-interface runner (`icub_all.xml`: wrappers, remappers, the embObj devices,
//! calibrators) against the emulated Ethernet boards, with an in-process name server
//! (run under netns-run; the boards are reached through the address map
//! 10.0.1.0/24 -> 127.0.3.0/24). Every device opens except the types this build lacks,
//! which are named. Then our `yarp rpc` sends `set pos` to `/icub/left_arm/rpc:i` and the
//! joint is seen moving on `/icub/left_arm/state:o`; our `yarp read` receives the left
//! arm's F/T stream; Ctrl-C's phases park the arm and close everything.

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use icub_eth_devices::emulator::{robot_boards, serve};
use icub_eth_devices::eth::params::{AddressMap, ADDRESS_MAP_ENV};
use yarp_devices::robotinterface::{
    read_robot_file, ActionPhase, DeviceFactory, RegistryFactory, RobotRunner,
};
use yarp_devices::{DevResult, PolyDriver};
use yarp_net::blocking::{BufferedPort, Network};
use yarp_proto::Property;

const MAP: &str = "10.0.1.0/24=127.0.3.0/24";
const T: Duration = Duration::from_secs(30);

/// The framework's drivers plus the embObj ones.
struct WithEth;

impl DeviceFactory for WithEth {
    fn knows(&self, kind: &str) -> bool {
        icub_eth_devices::eth::DRIVERS
            .iter()
            .any(|(n, _)| *n == kind)
            || RegistryFactory.knows(kind)
    }
    fn open(&self, config: &Property) -> DevResult<PolyDriver> {
        let kind = config
            .find("device")
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        match icub_eth_devices::eth::DRIVERS
            .iter()
            .find(|(n, _)| *n == kind)
        {
            Some((name, make)) => {
                let mut d = make();
                d.open(config)?;
                Ok(PolyDriver::from_driver(name, d))
            }
            None => RegistryFactory.open(config),
        }
    }
}

/// The workspace's `yarp` program (same target directory), or `None` after a loud
/// notice; under CI its absence fails.
fn our_yarp() -> Option<PathBuf> {
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

/// A child process whose stdout lines arrive on a channel; killed and reaped on drop.
struct Peer {
    child: Child,
    lines: mpsc::Receiver<String>,
}

impl Peer {
    fn spawn(mut cmd: Command) -> Peer {
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
    fn line(&self, timeout: Duration) -> Option<String> {
        self.lines.recv_timeout(timeout).ok()
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start_name_server() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    std::env::set_var("YARP_CONFIG_HOME", dir.path());
    let addr = yarp_devices::runtime::block_on(async {
        let ns = yarp_interop_tests::bind_name_server().await;
        let addr = ns.local_addr();
        tokio::spawn(ns.serve());
        addr
    });
    yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("write yarp.conf");
    dir
}

#[test]
fn icub_genova02_comes_up_and_moves_its_left_arm_by_yarp_rpc() {
    std::env::set_var(ADDRESS_MAP_ENV, MAP);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova02");
    let top = dir.join("icub_all.xml");
    let specs = robot_boards(&dir, None).expect("robot boards");
    let (_served, _threads) = serve(
        specs,
        &AddressMap::parse(MAP).unwrap(),
        Arc::new(AtomicBool::new(false)),
    )
    .expect("the emulator binds 127.0.3.x");
    let _conf = start_name_server();

    let robot = read_robot_file(&top, &Property::default())
        .expect("icub_all.xml")
        .robot;
    let mut runner = RobotRunner::with_factory(robot, Box::new(WithEth));
    runner.set_keep_going(true);
    let missing = runner.unavailable_devices();
    eprintln!("device types this build lacks: {missing:?}");
    assert!(
        missing.iter().all(|(_, kind)| *kind == "embObjSkin"),
        "{missing:?}"
    );
    let start = Instant::now();
    runner
        .enter_phase(ActionPhase::Startup)
        .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("startup (open, attach, calibrate): {:?}", start.elapsed());
    let failed = runner.failures().to_vec();
    eprintln!("given up at start-up: {failed:?}");
    assert!(failed.is_empty(), "{failed:?}");
    for must in [
        "left_arm-eb1-j0_3-mc",
        "left_arm-eb2-j4_15-mc",
        "left_arm-mc_remapper",
        "left_arm-mc_nws_yarp",
        "left_arm-eb1-j0_3-strain",
        "left_arm-FT_wrapper",
        "left_arm-calibrator",
    ] {
        assert!(
            !failed.iter().any(|f| f.contains(must)),
            "{must} failed: {failed:?}"
        );
    }
    runner.enter_phase(ActionPhase::Run).unwrap();

    let net = Network::from_conf().expect("network");
    let state = BufferedPort::open(&net, "/test/left_arm/state:i").unwrap();
    net.connect("/icub/left_arm/state:o", "/test/left_arm/state:i", None)
        .expect("connect state:o");
    let joint0 = |timeout: Duration| -> Option<f64> {
        state
            .read_timeout(timeout)
            .and_then(|m| m.bottle.get(0).and_then(|v| v.as_f64()))
    };
    let q0 = joint0(T).expect("a state:o bottle");
    // Calibrated: l_shoulder_pitch at its startupPosition (-35.97).
    assert!((q0 + 35.97).abs() < 2.0, "joint 0 at {q0}");

    if let Some(yarp) = our_yarp() {
        let mut cmd = Command::new(&yarp);
        cmd.args(["rpc", "/icub/left_arm/rpc:i"]);
        let mut rpc = Peer::spawn(cmd);
        let sent = Instant::now();
        rpc.child
            .stdin
            .as_mut()
            .unwrap()
            .write_all(b"set pos 0 -20\n")
            .unwrap();
        let reply = rpc.line(T).expect("a reply from yarp rpc");
        assert!(reply.contains("[ok]"), "{reply}");
        let end = Instant::now() + T;
        let mut at = q0;
        while (at + 20.0).abs() > 0.5 {
            assert!(Instant::now() < end, "joint 0 at {at}, not -20");
            at = joint0(T).unwrap_or(at);
        }
        eprintln!("set pos 0 -20 seen on state:o after {:?}", sent.elapsed());
        drop(rpc);

        let mut cmd = Command::new(&yarp);
        cmd.args(["read", "/test/ft:i", "/icub/left_arm/FT/measures:o"]);
        let reader = Peer::spawn(cmd);
        let line = reader.line(T).expect("a line from yarp read");
        eprintln!("yarp read /icub/left_arm/FT/measures:o: {line}");
        assert!(line.contains('('), "{line}");
    }

    state.close();
    runner.enter_phase(ActionPhase::Interrupt1).unwrap();
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}
