//! The simulated iCub of `launch-configs/icub-sim/robot/icub_all.xml`, brought up in
//! process by the robotinterface runner against the board emulator (every network on an
//! in-process bus instead of the file's UDP ports), with an in-process name server
//! (run under netns-run). A remote client moves a left-arm joint through
//! controlBoard_nws_yarp -> controlboardremapper -> canmotioncontrol -> CAN -> emulator,
//! reads the F/T sensor from /icub/left_arm/analog:o, sets and reads a joint's impedance
//! and asks the part's calibrator (through the remapper) to home the arm. Every wait is
//! bounded.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_can::bus::inproc::VirtualBus;
use icub_can::emulator::network;
use icub_can::emulator::{BusEmulator, EmulatorHandle};
use icub_can::CanBus;
use icub_emulators::can_robot;
use icub_ikin::Limb;
use yarp_devices::robotinterface::{read_robot_file, ActionPhase, Robot, RobotRunner};
use yarp_devices::sensors::AnalogStatus;
use yarp_devices::vocabs::CM_POSITION;
use yarp_devices::PolyDriver;
use yarp_net::blocking::{BufferedPort, Network};
use yarp_proto::Property;

const T: Duration = Duration::from_secs(30);

fn robot_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-configs/icub-sim/robot")
}

fn genova_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/iCubGenova01")
}

/// The left arm's Cartesian solver on the robot's `cartesianSolver.ini` in `dir` (its
/// cartesiancontrollerserver streams `state:o` once connected to it, as C++'s); killed
/// and reaped on drop.
fn left_arm_solver(dir: &Path) -> Reaped {
    arm_solver(dir, "left_arm")
}

/// The Cartesian solver of `part` (`left_arm`, `right_arm`), as [`left_arm_solver`].
fn arm_solver(dir: &Path, part: &str) -> Reaped {
    let program = yarp_interop_tests::workspace_program("iKinCartesianSolver", "icub-cartesian");
    let child = std::process::Command::new(program)
        .arg("--from")
        .arg(dir.join("cartesianSolver.ini"))
        .args(["--part", part])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("iKinCartesianSolver");
    Reaped(child)
}

/// A name server for this test process, announced through a private yarp.conf.
fn start_name_server() -> tempfile::TempDir {
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

/// The whole emulated robot, one in-process bus per network: `inproc://<tag>-<n>`.
/// The head's Xsens MTx on a pseudo-terminal, named to every `xsensmtx` of this process
/// through YARP_ICUB_XSENS_SERIAL; stops when dropped.
fn emulate_head_imu() -> icub_can::emulator::mtx::MtxHandle {
    let (port, path) = icub_can::emulator::mtx::pty().unwrap();
    let mtx = icub_can::emulator::mtx::serve(
        port,
        icub_can::xsens::EmulatedMtx::default(),
        icub_can::xsens::emulated_motion,
    )
    .unwrap();
    std::env::set_var(icubmod::xsens::SERIAL_ENV, &path);
    mtx
}

fn emulate_icub(tag: &str) -> Vec<EmulatorHandle> {
    // The boards of the robot files this test runs (the same layout as iCubGenova01).
    let file = can_robot::robot_file(&robot_dir()).expect("robot file");
    can_robot::networks(&file)
        .expect("CAN layout of the robot files")
        .iter()
        .map(|net| {
            let bus: Arc<dyn CanBus> =
                Arc::new(VirtualBus::named(&format!("{tag}-{}", net.num)).endpoint());
            BusEmulator::new(bus, network::build(net))
                .spawn()
                .expect("emulator")
        })
        .collect()
}

/// Points every `canBackend` of `robot` (top-level params and inside the motor-control
/// `CAN` groups) at the in-process buses; returns how many were changed.
fn use_inproc(robot: &mut Robot, tag: &str) -> usize {
    const FILE_BACKEND: &str = "udp://127.0.0.1:20000+n";
    let mut n = 0;
    for d in &mut robot.devices {
        for p in d
            .params
            .iter_mut()
            .filter(|p| p.value.contains(FILE_BACKEND))
        {
            p.value = p
                .value
                .replace(FILE_BACKEND, &format!("inproc://{tag}-{{n}}"));
            n += 1;
        }
    }
    n
}

/// C++ `yarp` of the C++ peer, or `None` after the shared missing-peer rule (fails in CI).
fn cpp_yarp() -> Option<PathBuf> {
    yarp_interop_tests::cpp_program("simulated_icub (C++ yarp rpc step)", "yarp")
}

/// The encoders (degrees) of the opened device `name` of `runner`.
fn encoders_of(runner: &RobotRunner, name: &str) -> Vec<f64> {
    let dev = runner.device(name).unwrap_or_else(|| panic!("{name}"));
    let mut pd = dev.lock();
    pd.device().as_encoders().unwrap().get_encoders().unwrap()
}

/// A fresh pose from `/icub/cartesianController/left_arm/state:o` (read by `reader`),
/// checked against icub-ikin's `left_v2` arm at the torso and left-arm encoders read
/// from the robot right after; the pose.
fn left_arm_pose_matches_ikin(runner: &RobotRunner, reader: &BufferedPort) -> Vec<f64> {
    while reader.try_read().is_some() {}
    let msg = reader
        .read_timeout(T)
        .expect("a pose on the cartesian state:o");
    let msg = reader.read_timeout(T).unwrap_or(msg);
    assert!(msg.stamp.is_some(), "state:o has an envelope");
    let pose: Vec<f64> = msg.bottle.iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(pose.len(), 7, "{pose:?}");
    let torso = encoders_of(runner, "torso_mc_remapper");
    let arm = encoders_of(runner, "left_arm_mc_remapper");
    let want = Limb::arm("left_v2")
        .unwrap()
        .pose_from_encoders(&torso, &arm)
        .unwrap();
    for i in 0..7 {
        assert!(
            (pose[i] - want[i]).abs() < 2e-3,
            "pose {pose:?} vs iKin {want:?} (torso {torso:?}, arm {arm:?})"
        );
    }
    pose
}

fn eventually(limit: Duration, mut f: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < limit {
        if f() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

#[test]
fn simulated_icub_comes_up_moves_and_shuts_down() {
    yarp_device_programs::register_all();
    let file = robot_dir().join("icub_all.xml");
    if !genova_dir().exists() {
        eprintln!("SKIPPED: {} not found", genova_dir().display());
        return;
    }
    let mut robot = read_robot_file(&file, &Property::new())
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    let tag = format!("sim{}", std::process::id());
    // 8 motor-control parts, 6 strains, 2 MAIS, 3 skins, 2 hand MTBs
    assert_eq!(use_inproc(&mut robot, &tag), 21);
    let _emulators = emulate_icub(&tag);
    let _mtx = emulate_head_imu();
    let _conf = start_name_server();

    let mut runner = RobotRunner::new(robot);
    assert!(
        runner.unavailable_devices().is_empty(),
        "{:?}",
        runner.unavailable_devices()
    );
    let start = Instant::now();
    runner
        .enter_phase(ActionPhase::Startup)
        .unwrap_or_else(|e| panic!("{e}"));
    println!(
        "startup (open, attach, calibrate 8 parts): {:?}",
        start.elapsed()
    );
    runner.enter_phase(ActionPhase::Run).unwrap();

    // a remote client, as `yarp rpc` / iCub modules would use
    let cfg =
        "device remote_controlboard\nremote /icub/left_arm\nlocal /test/left_arm\ncarrier tcp\n";
    let mut arm = PolyDriver::open(&Property::from_config_text(cfg).unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let dev = arm.device();
    assert_eq!(dev.as_encoders().unwrap().get_axes().unwrap(), 16);
    // calibrated: the elbow at its startupPosition
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 45.0).abs() < 2.0)));
    assert_eq!(
        dev.as_control_mode().unwrap().get_control_mode(3).unwrap(),
        CM_POSITION
    );
    // the cartesian state of the left arm, from the same encoders
    let _solver = left_arm_solver(&robot_dir());
    let net = Network::from_conf().expect("network");
    let cart = BufferedPort::open(&net, "/test/left_arm_cartesian:i").unwrap();
    net.connect(
        "/icub/cartesianController/left_arm/state:o",
        "/test/left_arm_cartesian:i",
        None,
    )
    .expect("connect to the cartesian state:o");
    let pose_before = left_arm_pose_matches_ikin(&runner, &cart);
    // the head IMU streams through its multiple-analog-sensors wrapper
    let imu = BufferedPort::open(&net, "/test/head_imu:i").unwrap();
    net.connect("/icub/head/inertials/measures:o", "/test/head_imu:i", None)
        .expect("connect to the head IMU");
    assert!(imu.read_timeout(T).is_some(), "a head IMU measurement");
    imu.close();

    let dev = arm.device();
    let pos = dev.as_position_control().unwrap();
    pos.set_ref_speed(3, 60.0).unwrap();
    let before = dev.as_encoders().unwrap().get_encoder(3).unwrap();
    let t = Instant::now();
    dev.as_position_control()
        .unwrap()
        .position_move(3, 60.0)
        .unwrap();
    // command -> rpc:i -> CAN -> emulator -> broadcast -> state:o -> client
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - before).abs() > 0.05)));
    println!(
        "command-to-encoder latency (first change on state:o): {:?}",
        t.elapsed()
    );
    let reached = eventually(T, || {
        dev.as_encoders()
            .unwrap()
            .get_encoder(3)
            .is_ok_and(|q| (q - 60.0).abs() < 1.0)
    });
    assert!(reached, "elbow did not reach 60");
    println!("elbow 45 -> 60 deg seen on state:o after {:?}", t.elapsed());
    std::thread::sleep(Duration::from_millis(300));
    let pose_after = left_arm_pose_matches_ikin(&runner, &cart);
    let moved: f64 = (0..3)
        .map(|i| (pose_after[i] - pose_before[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    println!("left hand moved {moved:.3} m: {pose_before:?} -> {pose_after:?}");
    assert!(moved > 0.01, "the elbow motion moves the hand");
    cart.close();

    let cfg = "device analogsensorclient\nremote /icub/left_arm/analog:o\nlocal /test/left_arm_ft\ncarrier tcp\n";
    let mut ft = PolyDriver::open(&Property::from_config_text(cfg).unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let sensor = ft.device().as_analog_sensor().unwrap();
    let mut v = Vec::new();
    assert!(eventually(T, || sensor.read(&mut v) == AnalogStatus::Ok
        && v.len() == 6));
    assert!((4.0..=16.0).contains(&v[2]), "fz {v:?}");
    drop(ft);

    // C++ `yarp rpc` drives the same joint
    if let Some(yarp) = cpp_yarp() {
        let out =
            yarp_interop_tests::cpp_rpc_output(&yarp, "/icub/left_arm/rpc:i", "set pos 3 50\n");
        assert!(out.contains("[ok]"), "{out}");
        let dev = arm.device();
        assert!(eventually(T, || dev
            .as_encoders()
            .unwrap()
            .get_encoder(3)
            .is_ok_and(|q| (q - 50.0).abs() < 1.0)));
        let out = yarp_interop_tests::cpp_rpc_output(&yarp, "/icub/left_arm/rpc:i", "get enc 3\n");
        assert!(
            out.contains("[is] enc 49.") || out.contains("[is] enc 50."),
            "{out}"
        );
    }

    // Impedance through the network: `set iimp ipr 3 (stiff damp)` / `get iimp ipr 3` ->
    // remapper -> canmotioncontrol -> SET/GET_IMPEDANCE_PARAMS -> the emulated board (the
    // values come back quantized to the board's sensor-units-per-tick integers).
    let dev = arm.device();
    let imp = dev.as_impedance_control().unwrap();
    imp.set_impedance(3, 0.2, 0.002).unwrap();
    let (k, d) = imp.get_impedance(3).unwrap();
    assert!(
        (k - 0.2).abs() < 2e-3 && (d - 0.002).abs() < 2e-5,
        "{k} {d}"
    );
    imp.set_impedance_offset(3, 0.5).unwrap();
    let off = imp.get_impedance_offset(3).unwrap();
    assert!((off - 0.5).abs() < 1e-2, "{off}");
    let lim = imp.get_current_impedance_limit(3).unwrap();
    assert_eq!((lim.min_stiffness, lim.max_stiffness), (0.002, 9.889));

    // Remote homing: `[set] [reca] [hom] 3` / `[homs]` -> controlBoard_nws_yarp -> the
    // remapper's calibrator device (left_arm_calib, attached by yarprobotinterface's
    // calibrate) -> the boards, served with the part unlocked (C++ getCalibratorDevice),
    // so state:o goes on meanwhile. HOME::positionHome of left_arm_calib.xml.
    const HOME: [f64; 8] = [-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 40.0, 30.0];
    let dev = arm.device();
    dev.as_position_control()
        .unwrap()
        .position_move(3, 55.0)
        .unwrap();
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 55.0).abs() < 1.0)));
    let rc = dev.as_remote_calibrator().unwrap();
    assert!(rc.is_calibrator_device_present().unwrap());
    let t = Instant::now();
    rc.homing_single_joint(3).unwrap();
    println!("homing the elbow 55 -> 45 deg: {:?}", t.elapsed());
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 45.0).abs() < 1.0)));
    dev.as_position_control()
        .unwrap()
        .position_move(3, 60.0)
        .unwrap();
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 60.0).abs() < 1.0)));
    // Whole-part homing from a second client; this one keeps reading the streamed
    // encoders (stale after 0.5 s) and sees the elbow travel while the call runs.
    let t = Instant::now();
    let homing = std::thread::spawn(|| {
        let cfg = "device remote_controlboard\nremote /icub/left_arm\nlocal /test/left_arm_homing\ncarrier tcp\n";
        let mut other = PolyDriver::open(&Property::from_config_text(cfg).unwrap())
            .unwrap_or_else(|e| panic!("{e}"));
        let r = other
            .device()
            .as_remote_calibrator()
            .unwrap()
            .homing_whole_part();
        let _ = other.close();
        r
    });
    let mut seen = Vec::new();
    while !homing.is_finished() {
        let q = dev.as_encoders().unwrap().get_encoder(3);
        assert!(q.is_ok(), "state:o stalled during homing: {q:?}");
        seen.push(q.unwrap());
        std::thread::sleep(Duration::from_millis(20));
    }
    homing.join().unwrap().unwrap();
    println!("homing the left arm: {:?}", t.elapsed());
    assert!(
        seen.iter().any(|q| *q < 59.0 && *q > 46.0),
        "the elbow's travel 60 -> 45 is seen on state:o during the call: {seen:?}"
    );
    // (wrist yaw's positionHome 40 lies beyond its joint limit 25: the board stops there)
    let home: Vec<f64> = (0..8)
        .map(|j| {
            let (lo, hi) = dev.as_control_limits().unwrap().get_limits(j).unwrap();
            HOME[j].clamp(lo, hi)
        })
        .collect();
    assert_eq!(home[6], 25.0);
    assert!(eventually(T, || {
        dev.as_encoders()
            .unwrap()
            .get_encoders()
            .is_ok_and(|q| (0..8).all(|j| (q[j] - home[j]).abs() < 1.0))
    }));
    drop(arm);

    runner
        .enter_phase(ActionPhase::Interrupt1)
        .unwrap_or_else(|e| panic!("{e}"));
    runner
        .enter_phase(ActionPhase::Shutdown)
        .unwrap_or_else(|e| panic!("{e}"));
}

/// iCubGenova01's own icub_all.xml, unmodified: the backend comes from the environment.
/// Every CAN device it names opens against the emulator; the devices this build lacks are
/// reported by name; with keep-going (`yarprobotinterface --keep-going`) the two
/// inconsistencies of the files themselves (see launch-configs/icub-sim/robot/README.md)
/// are reported by name and skipped, and the rest comes up: the left arm moves and its
/// joint and cartesian `state:o` stream.
#[test]
fn genova01_icub_all_runs_its_can_devices_against_the_emulator() {
    yarp_device_programs::register_all();
    let file = genova_dir().join("icub_all.xml");
    if !file.exists() {
        eprintln!("SKIPPED: {} not found", file.display());
        return;
    }
    let tag = format!("real{}", std::process::id());
    std::env::set_var(
        icubmod::common::BACKEND_ENV,
        format!("inproc://{tag}-{{n}}"),
    );
    let _emulators = emulate_icub(&tag);
    let _mtx = emulate_head_imu(); // serial /dev/ttyS0 in the file
    let _conf = start_name_server();
    let robot = read_robot_file(&file, &Property::new())
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    let mut runner = RobotRunner::new(robot);
    let missing: Vec<&str> = runner
        .unavailable_devices()
        .iter()
        .map(|(_, k)| *k)
        .collect();
    assert!(
        missing.is_empty(),
        "every device type is provided: {missing:?}"
    );
    runner.set_keep_going(true);
    runner
        .enter_phase(ActionPhase::Startup)
        .unwrap_or_else(|e| panic!("keep-going startup failed: {e}"));
    let failures = runner.failures().to_vec();
    for f in &failures {
        println!("kept going past: {f}");
    }
    assert_eq!(failures.len(), 2, "{failures:?}");
    assert!(
        failures.iter().any(|f| f.contains("right_leg_oints")),
        "{failures:?}"
    );
    assert!(
        failures.iter().any(|f| f.contains("left_leg-FT_remapper")
            || f.contains("left_leg_FT_remapper")
            || f.contains("l_foot")),
        "{failures:?}"
    );
    runner.enter_phase(ActionPhase::Run).unwrap();
    // the head IMU is read through its wrapper and filtered by the imuFilter
    let head_imu = runner
        .device("head-inertial")
        .expect("head-inertial opened");
    assert!(eventually(T, || {
        let mut pd = head_imu.lock();
        let mut v = Vec::new();
        pd.device().as_analog_sensor().unwrap().read(&mut v)
            == yarp_devices::sensors::AnalogStatus::Ok
    }));
    for wrapper in [
        "head-inertials_wrapper",
        "head-imuFilter",
        "head-imuFilter_wrapper",
    ] {
        assert!(runner.device(wrapper).is_some(), "{wrapper} is up");
    }
    for part in ["left_arm", "right_arm", "head", "torso", "left_leg"] {
        let dev = runner
            .device(&format!("{part}_mc_remapper"))
            .unwrap_or_else(|| panic!("{part} remapper"));
        let mut pd = dev.lock();
        let enc = pd.device().as_encoders().unwrap();
        assert!(enc.get_encoders().is_ok(), "{part}");
    }

    // the left arm moves through its wrapper, and its cartesian state follows
    let _solver = left_arm_solver(&genova_dir());
    let net = Network::from_conf().expect("network");
    let cart = BufferedPort::open(&net, "/real/left_arm_cartesian:i").unwrap();
    net.connect(
        "/icub/cartesianController/left_arm/state:o",
        "/real/left_arm_cartesian:i",
        None,
    )
    .expect("connect to the cartesian state:o");
    let cfg =
        "device remote_controlboard\nremote /icub/left_arm\nlocal /real/left_arm\ncarrier tcp\n";
    let mut arm = PolyDriver::open(&Property::from_config_text(cfg).unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let dev = arm.device();
    let mut start = 0.0;
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .map(|q| start = q)
        .is_ok()));
    let pose_before = left_arm_pose_matches_ikin(&runner, &cart);
    let target = if start < 50.0 {
        start + 15.0
    } else {
        start - 15.0
    };
    let pos = dev.as_position_control().unwrap();
    pos.set_ref_speed(3, 60.0).unwrap();
    pos.position_move(3, target).unwrap();
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - target).abs() < 1.0)));
    std::thread::sleep(Duration::from_millis(300));
    let pose_after = left_arm_pose_matches_ikin(&runner, &cart);
    assert!(
        (0..3)
            .map(|i| (pose_after[i] - pose_before[i]).powi(2))
            .sum::<f64>()
            .sqrt()
            > 0.01,
        "{pose_before:?} -> {pose_after:?}"
    );
    drop(arm);
    cart.close();
    runner
        .enter_phase(ActionPhase::Interrupt1)
        .unwrap_or_else(|e| panic!("{e}"));
    runner
        .enter_phase(ActionPhase::Shutdown)
        .unwrap_or_else(|e| panic!("{e}"));
}

/// A child process killed and reaped when dropped.
struct Reaped(std::process::Child);

impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Waits for `child` to exit within `T`; its status.
fn wait_exit(child: &mut Reaped) -> Option<std::process::ExitStatus> {
    let start = Instant::now();
    while start.elapsed() < T {
        if let Some(s) = child.0.try_wait().unwrap() {
            return Some(s);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    None
}

/// The `icub-board-emulator` binary built beside this test, with iCubGenova01's files, or
/// `None` after a SKIPPED notice.
fn emulator_program() -> Option<PathBuf> {
    let emulator = std::env::current_exe()
        .ok()
        .and_then(|exe| Some(exe.parent()?.parent()?.join("icub-board-emulator")))
        .filter(|p| p.is_file());
    let Some(emulator) = emulator else {
        eprintln!("SKIPPED: icub-board-emulator not built (cargo build -p icub-emulators)");
        return None;
    };
    if !genova_dir().exists() {
        eprintln!("SKIPPED: {} not found", genova_dir().display());
        return None;
    }
    Some(emulator)
}

/// The whole emulated iCub (iCubGenova01's boards) on UDP ports `base_port`.., once it
/// says it is ready; killed and reaped on drop.
/// The emulator program with the whole iCub on UDP ports from `base_port`, and the head's
/// Xsens MTx at `xsens` when given.
fn spawn_emulator(program: &Path, base_port: u16, xsens: Option<&Path>) -> Reaped {
    // no other test's name server may hand out the hubs' ports meanwhile
    if !yarp_interop_tests::hold_port_block(base_port) {
        eprintln!("ports {base_port}.. are held by another test process: going on");
    }
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let mut cmd = Command::new(program);
    cmd.args(["--preset", "icub", "--bus"])
        .arg(format!("udp-hub://127.0.0.1:{base_port}+n"))
        .arg("--robot-dir")
        .arg(genova_dir());
    if let Some(link) = xsens {
        cmd.arg("--xsens").arg(link);
    }
    let mut emu = Reaped(
        cmd.stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn emulator"),
    );
    let stdout = emu.0.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if line == "ready" {
                let _ = tx.send(());
            }
        }
    });
    rx.recv_timeout(T).expect("emulator ready");
    emu
}

/// iCubGenova01 as processes: its CAN boards emulated on UDP ports from `base_port` (and
/// the head's MTx on a pseudo-terminal), our `yarprobotinterface --keep-going` on its own
/// `icub_all.xml`, up to "running happily".
struct Genova01 {
    robot: Reaped,
    log: tempfile::NamedTempFile,
    _emu: Reaped,
    _dir: tempfile::TempDir,
}

impl Genova01 {
    fn up(emulator: &Path, base_port: u16) -> Genova01 {
        use std::process::{Command, Stdio};
        let dir = tempfile::tempdir().unwrap();
        let xsens = dir.path().join("ttyS0");
        let emu = spawn_emulator(emulator, base_port, Some(&xsens));
        let log = tempfile::NamedTempFile::new().unwrap();
        let robot = Reaped(
            Command::new(env!("CARGO_BIN_EXE_yarprobotinterface"))
                .args(["--config", "icub_all.xml", "--keep-going"])
                .env(
                    icubmod::common::BACKEND_ENV,
                    format!("udp://127.0.0.1:{base_port}+n"),
                )
                .env(icubmod::xsens::SERIAL_ENV, &xsens)
                .current_dir(genova_dir())
                .stdout(Stdio::null())
                .stderr(log.reopen().unwrap())
                .spawn()
                .expect("spawn yarprobotinterface"),
        );
        let g = Genova01 {
            robot,
            log,
            _emu: emu,
            _dir: dir,
        };
        assert!(
            eventually(Duration::from_secs(60), || g
                .log()
                .contains("running happily")),
            "{}",
            g.log()
        );
        g
    }

    /// What `yarprobotinterface` printed so far.
    fn log(&self) -> String {
        std::fs::read_to_string(self.log.path()).unwrap_or_default()
    }

    /// SIGINT: parks and exits 0.
    fn interrupt(mut self) {
        let pid = self.robot.0.id().to_string();
        let _ = std::process::Command::new("kill")
            .args(["-INT", &pid])
            .status();
        let status = wait_exit(&mut self.robot).expect("yarprobotinterface exits after SIGINT");
        assert!(status.success(), "{status:?}\n{}", self.log());
    }
}

/// The command lines of launch-configs/icub-sim/robot/README.md, as processes: the
/// emulator binary on UDP ports 20000..20009 and `yarprobotinterface --config
/// icub_all.xml` unchanged; a client moves the elbow; SIGINT parks and exits 0.
#[test]
fn readme_command_lines_bring_up_the_robot_over_udp() {
    yarp_device_programs::register_all();
    use std::process::{Command, Stdio};
    let Some(emulator) = emulator_program() else {
        return;
    };
    let _conf = start_name_server();
    let _emu = spawn_emulator(&emulator, 20000, Some(Path::new("/tmp/icub-sim-ttyXSENS")));

    let log = tempfile::NamedTempFile::new().unwrap();
    let mut robot = Reaped(
        Command::new(env!("CARGO_BIN_EXE_yarprobotinterface"))
            .args(["--config", "icub_all.xml"])
            .current_dir(robot_dir())
            .stdout(Stdio::null())
            .stderr(log.reopen().unwrap())
            .spawn()
            .expect("spawn yarprobotinterface"),
    );
    let cfg = Property::from_config_text(
        "device remote_controlboard\nremote /icub/left_arm\nlocal /readme/left_arm\ncarrier tcp\n",
    )
    .unwrap();
    let mut arm = None;
    assert!(eventually(T, || {
        arm = PolyDriver::open(&cfg).ok();
        arm.is_some()
    }));
    let mut arm = arm.unwrap();
    let dev = arm.device();
    // wait for the calibrator (startupPosition 45) before commanding
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 45.0).abs() < 1.0)));
    std::thread::sleep(Duration::from_millis(500));
    let pos = dev.as_position_control().unwrap();
    pos.set_ref_speed(3, 60.0).unwrap();
    pos.position_move(3, 70.0).unwrap();
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 70.0).abs() < 1.0)));
    drop(arm);

    // interrupting a startup that is still calibrating other parts is a failure
    assert!(eventually(T, || std::fs::read_to_string(log.path())
        .is_ok_and(|t| t.contains("running happily"))));
    let pid = robot.0.id().to_string();
    let _ = Command::new("kill").args(["-INT", &pid]).status();
    let status = wait_exit(&mut robot).expect("yarprobotinterface exits after SIGINT");
    let text = std::fs::read_to_string(log.path()).unwrap_or_default();
    assert!(status.success(), "{status:?}\n{text}");
    assert!(text.contains("shutdown phase finished"), "{text}");
}

/// `yarprobotinterface --keep-going` on iCubGenova01's own icub_all.xml, unmodified, as
/// processes over UDP (ports 21000..21009, the backend from `YARP_ICUB_CAN_BACKEND`):
/// the missing device types and the two failed attaches are named in the log, the rest
/// comes up; the left arm moves, its cartesian `state:o` streams; SIGINT exits 0.
#[test]
fn keep_going_runs_the_real_genova01_config_as_processes() {
    yarp_device_programs::register_all();
    let Some(emulator) = emulator_program() else {
        return;
    };
    let _conf = start_name_server();
    let robot = Genova01::up(&emulator, 21000);
    let text = robot.log();
    // every device type is provided: the head's MTx (emulated) measures
    assert!(
        text.contains("MTx on") && text.contains("measuring"),
        "{text}"
    );
    assert!(
        text.contains("the robot runs without 2 failed")
            && text.contains("right_leg_oints")
            && text.contains("l_foot_ft"),
        "{text}"
    );

    let _solver = left_arm_solver(&genova_dir());
    let net = Network::from_conf().expect("network");
    let cart = BufferedPort::open(&net, "/kg/left_arm_cartesian:i").unwrap();
    net.connect(
        "/icub/cartesianController/left_arm/state:o",
        "/kg/left_arm_cartesian:i",
        None,
    )
    .expect("connect to the cartesian state:o");
    let first = cart.read_timeout(T).expect("a pose");
    assert_eq!(first.bottle.len(), 7);

    let cfg = Property::from_config_text(
        "device remote_controlboard\nremote /icub/left_arm\nlocal /kg/left_arm\ncarrier tcp\n",
    )
    .unwrap();
    let mut arm = PolyDriver::open(&cfg).unwrap_or_else(|e| panic!("{e}"));
    let dev = arm.device();
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 45.0).abs() < 1.0)));
    let pos = dev.as_position_control().unwrap();
    pos.set_ref_speed(3, 60.0).unwrap();
    pos.position_move(3, 65.0).unwrap();
    assert!(eventually(T, || dev
        .as_encoders()
        .unwrap()
        .get_encoder(3)
        .is_ok_and(|q| (q - 65.0).abs() < 1.0)));
    std::thread::sleep(Duration::from_millis(300));
    while cart.try_read().is_some() {}
    let last = cart.read_timeout(T).expect("a pose");
    let moved: f64 = (0..3)
        .map(|i| {
            (last.bottle.get(i).unwrap().as_f64().unwrap()
                - first.bottle.get(i).unwrap().as_f64().unwrap())
            .powi(2)
        })
        .sum::<f64>()
        .sqrt();
    assert!(moved > 0.01, "{first:?} -> {last:?}");
    drop(arm);
    cart.close();
    robot.interrupt();
}

/// The Cartesian controllers of both arms of the simulated iCub (iCubGenova01's own
/// `icub_all.xml`, its CAN boards emulated as a process over UDP ports 22000..): each
/// arm's `iKinCartesianSolver` on the robot's `cartesianSolver.ini`, then our
/// `cartesiancontrollerclient` and icub-main's C++ one (built from ../shared/peers) each
/// reach three poses of each arm within 1 mm and 2 degrees, the measured pose in the
/// server's tolerance before it says done, as C++'s `isInTargetHelper` asks; an
/// out-of-reach position ends at the solver's closest pose.
#[test]
fn both_arms_reach_three_poses_with_our_and_cpps_clients() {
    let test = "both_arms_reach_three_poses_with_our_and_cpps_clients";
    yarp_device_programs::register_all();
    let Some(emulator) = emulator_program() else {
        return;
    };
    let Some(cpp_client) = yarp_interop_tests::build_cpp_program(
        test,
        "cartesian_client",
        &[Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../cartesian/tests/peers/cartesian_client.cpp")],
        &[],
        &["YARP_dev", "YARP_sig", "YARP_os", "YARP_init"],
    ) else {
        return;
    };
    let _conf = start_name_server();
    let robot = Genova01::up(&emulator, 22000);
    let _solvers = [
        arm_solver(&genova_dir(), "left_arm"),
        arm_solver(&genova_dir(), "right_arm"),
    ];
    let torso_cfg = Property::from_config_text(
        "device remote_controlboard\nremote /icub/torso\nlocal /cart_test/torso\n",
    )
    .unwrap();
    let mut torso = None;
    assert!(eventually(T, || {
        torso = PolyDriver::open(&torso_cfg).ok();
        torso.is_some()
    }));
    let mut torso = torso.unwrap();
    let mut torso_q = Vec::new();
    assert!(eventually(T, || {
        torso_q = torso
            .device()
            .as_encoders()
            .unwrap()
            .get_encoders()
            .unwrap_or_default();
        torso_q.len() == 3
    }));
    let postures = [
        [-30.0, 30.0, 10.0, 50.0, 0.0, 0.0, 0.0],
        [-50.0, 40.0, 20.0, 70.0, -20.0, -10.0, 10.0],
        [-40.0, 20.0, 30.0, 60.0, 30.0, 10.0, -10.0],
    ];
    for side in ["left", "right"] {
        let ctrl = format!("/icub/cartesianController/{side}_arm");
        let poses: Vec<[f64; 7]> = postures
            .iter()
            .map(|q| {
                let mut limb = Limb::arm(&format!("{side}_v2")).unwrap();
                let x = limb.pose_from_encoders(&torso_q, q).unwrap();
                std::array::from_fn(|k| x[k])
            })
            .collect();
        // ours, once the server has its solver
        let client_cfg = Property::from_text(format!(
            "(device cartesiancontrollerclient) (remote {ctrl}) (local /cart_test/{side})"
        ));
        let mut pd = None;
        assert!(
            eventually(T, || {
                pd = PolyDriver::open(&client_cfg).ok();
                pd.is_some()
            }),
            "{test}: {ctrl} never had its solver"
        );
        let mut pd = pd.unwrap();
        let cart = pd.device().as_cartesian_control().unwrap();
        cart.set_traj_time(1.5).unwrap();
        cart.set_in_target_tol(IN_TARGET_TOL).unwrap();
        // ctrlLib's trajectory time: 90 % of the way at T
        cart.register_ongoing_checkpoint(0.9).unwrap();
        for p in &poses {
            let (x, o) = ([p[0], p[1], p[2]], [p[3], p[4], p[5], p[6]]);
            let t0 = Instant::now();
            cart.go_to_pose_sync(&x, &o, 0.0).unwrap();
            let done = cart.wait_motion_done(0.02, 20.0).unwrap();
            let ((px, po), _) = cart.get_pose().unwrap();
            let d = (0..3).map(|k| (px[k] - x[k]).powi(2)).sum::<f64>().sqrt();
            let ang = axis_angle_deg(&po, &o);
            eprintln!(
                "{test}: {side}: ours: done {done} in {:.2} s, {:.2} mm, {ang:.2} deg",
                t0.elapsed().as_secs_f64(),
                d * 1e3
            );
            assert!(
                done,
                "{test}: {side}: not done: {:.2} mm, {ang:.2} deg",
                d * 1e3
            );
            assert!(
                d < 1e-3 && ang < 2.0,
                "{test}: {side}: {:.2} mm, {ang:.2} deg",
                d * 1e3
            );
            let events = cart.take_events();
            let at = |kind: &str, cp: Option<f64>| {
                events
                    .iter()
                    .find(|e| e.kind == kind && e.checkpoint == cp)
                    .map(|e| e.time)
            };
            let (Some(onset), Some(t90)) =
                (at("motion-onset", None), at("motion-ongoing", Some(0.9)))
            else {
                panic!("{test}: {side}: events {events:?}");
            };
            eprintln!(
                "{test}: {side}: ours: 90 % of the way at {:.3} s (T 1.5 s)",
                t90 - onset
            );
            assert!(
                ((t90 - onset) - 1.5).abs() <= 0.15,
                "{test}: {side}: 90 % of the way at {:.3} s, not within 10 % of T",
                t90 - onset
            );
        }
        // out of reach: the hand ends at the solver's closest pose and says done
        let far = [-1.5, if side == "left" { -0.2 } else { 0.2 }, 0.4];
        cart.go_to_position_sync(&far, 0.0).unwrap();
        assert!(
            cart.wait_motion_done(0.02, 20.0).unwrap(),
            "{test}: {side}: out of reach, not done"
        );
        std::thread::sleep(Duration::from_millis(200));
        let des = cart.get_desired().unwrap();
        let ((px, _), _) = cart.get_pose().unwrap();
        let gap = (0..3)
            .map(|k| (px[k] - des.x[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let reach = (0..3).map(|k| (px[k] - far[k]).powi(2)).sum::<f64>().sqrt();
        eprintln!(
            "{test}: {side}: out of reach: {:.2} mm from the solver's closest pose, {reach:.2} m short",
            gap * 1e3
        );
        assert!(
            gap < 2e-3 && reach > 0.5,
            "{test}: {side}: {gap} m from the closest, {reach} m short"
        );
        pd.close().unwrap();
        // icub-main's C++ client, the same poses
        let mut cmd = yarp_interop_tests::cpp_program_command(&cpp_client);
        cmd.arg(&ctrl)
            .arg("1.5")
            .env("IN_TARGET_TOL", IN_TARGET_TOL.to_string());
        for p in &poses {
            for v in p {
                cmd.arg(format!("{v:.9}"));
            }
        }
        let out = cmd.output().expect("C++ client");
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(out.status.success(), "{test}: {side}: C++ client: {stdout}");
        let reached: Vec<&str> = stdout.lines().filter(|l| l.starts_with("POSE")).collect();
        assert_eq!(reached.len(), 3, "{stdout}");
        for (line, p) in reached.iter().zip(&poses) {
            let f: Vec<f64> = line
                .split_whitespace()
                .skip(1)
                .filter_map(|v| v.parse().ok())
                .collect();
            assert_eq!(&f[..2], &[1.0, 1.0], "{test}: {side}: {line}");
            let d = (0..3)
                .map(|k| (f[3 + k] - p[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            let ang = axis_angle_deg(&f[6..10], &p[3..7]);
            eprintln!(
                "{test}: {side}: C++'s: done in {:.2} s, {:.2} mm, {ang:.2} deg",
                f[2],
                d * 1e3
            );
            assert!(
                d < 1e-3 && ang < 2.0,
                "{test}: {side}: C++'s client: {line}"
            );
        }
    }
    drop(torso);
    robot.interrupt();
}

/// The Cartesian controllers' in-target tolerance in the simulated-robot test: the
/// emulated boards hold each joint within an encoder tick or two (0.09° on an arm
/// joint), so the measured hand orientation stays up to about 0.1° (1.7e-3 rad) off
/// the planned one, more than the 1e-3 of the fake-board tests.
const IN_TARGET_TOL: f64 = 2.5e-3;

/// The angle between two axis-angle orientations, degrees.
fn axis_angle_deg(a: &[f64], b: &[f64]) -> f64 {
    use icub_ikin::nalgebra::Vector4;
    let ra = icub_ikin::pose::axis2dcm(&Vector4::new(a[0], a[1], a[2], a[3]));
    let rb = icub_ikin::pose::axis2dcm(&Vector4::new(b[0], b[1], b[2], b[3]));
    icub_ikin::pose::dcm2axis(&(ra * rb.transpose()))[3]
        .abs()
        .to_degrees()
}
