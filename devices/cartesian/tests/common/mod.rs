//! The set-up of the Cartesian controller's live tests and benches: fake boards served
//! as an iCub's torso and left arm, our solver and server, icub-main's C++ server and
//! client (built from ../shared/peers).
#![allow(dead_code)]

use icub_ikin::{Limb, RAD2DEG};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use yarp_devices::driver::{shared, SharedDevice};
use yarp_devices::PolyDriver;
use yarp_interop_tests as peer;
use yarp_proto::{Bottle, Property, Value};

pub const CTRL: &str = "/icub/cartesianController/left_arm";
static CLIENTS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

pub fn robots() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration")
}

/// A fake board of `joints` with `limits` (deg), served by controlBoard_nws_yarp as `name`.
pub fn board(name: &str, limits: &[(f64, f64)], joints: usize) -> (SharedDevice, PolyDriver) {
    // C++'s fake takes its bounds from LIMITS (setLimits does nothing)
    let list = |f: fn(&(f64, f64)) -> f64| {
        limits
            .iter()
            .map(f)
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let fake = PolyDriver::open(
        &Property::from_config_text(format!(
            "device fakeMotionControl\n[GENERAL]\nJoints {joints}\n[LIMITS]\nMin ({})\nMax ({})\n",
            list(|l| l.0),
            list(|l| l.1)
        ))
        .unwrap(),
    )
    .expect("fakeMotionControl");
    let fake = shared(fake);
    let mut nws = PolyDriver::open(&Property::from_text(format!(
        "(device controlBoard_nws_yarp) (name {name}) (period 0.01)"
    )))
    .expect("controlBoard_nws_yarp");
    nws.device()
        .as_wrapper()
        .unwrap()
        .attach(fake.clone())
        .expect("attach");
    (fake, nws)
}

/// Joint bounds \[deg\].
pub type Bounds = Vec<(f64, f64)>;

/// The left_v2 arm's bounds (deg) in the robot's order: torso (yaw, roll, pitch) and arm.
pub fn arm_limits() -> (Bounds, Bounds) {
    let limb = Limb::arm("left_v2").unwrap();
    let links = limb.chain().links();
    let deg = |i: usize| (links[i].min * RAD2DEG, links[i].max * RAD2DEG);
    let torso = vec![deg(2), deg(1), deg(0)];
    let mut arm: Vec<(f64, f64)> = (3..10).map(deg).collect();
    arm.extend(std::iter::repeat_n((0.0, 90.0), 9));
    (torso, arm)
}

/// Three poses of the hand the arm reaches (iKin's forward kinematics of three postures).
pub fn reachable_poses() -> Vec<[f64; 7]> {
    let postures = [
        [-30.0, 30.0, 10.0, 50.0, 0.0, 0.0, 0.0],
        [-50.0, 40.0, 20.0, 70.0, -20.0, -10.0, 10.0],
        [-40.0, 20.0, 30.0, 60.0, 30.0, 10.0, -10.0],
    ];
    postures
        .iter()
        .map(|q| {
            let mut limb = Limb::arm("left_v2").unwrap();
            let x = limb.pose_from_encoders(&[0.0; 3], q).unwrap();
            let mut p = [0.0; 7];
            p.copy_from_slice(x.as_slice());
            p
        })
        .collect()
}

/// Our solver on the robot's `cartesianSolver.ini` (unmodified for `robot` `icub`;
/// for another robot prefix, a copy naming it and solver `name`).
pub fn solver(test: &str, robot: &str, name: &str) -> yarp_interop_tests::Reaped {
    let mut ini = robots().join("iCubGenova02/cartesianSolver.ini");
    if robot != "icub" {
        let text = std::fs::read_to_string(&ini).unwrap();
        let text: String = text
            .lines()
            .map(|l| match l.split_whitespace().next() {
                Some("robot") => format!("robot {robot}"),
                Some("name") => format!("name {name}/{}", l.rsplit('/').next().unwrap_or("")),
                _ => l.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n");
        ini = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cartesianSolver-{robot}.ini"));
        std::fs::write(&ini, text).unwrap();
    }
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_iKinCartesianSolver"));
    cmd.arg("--from").arg(&ini).args(["--part", "left_arm"]);
    let log = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("solver-{robot}.log"));
    let child = cmd
        .stderr(std::fs::File::create(log).unwrap())
        .spawn()
        .unwrap_or_else(|e| panic!("{test}: iKinCartesianSolver: {e}"));
    yarp_interop_tests::Reaped(child)
}

pub fn server(torso: &SharedDevice, arm: &SharedDevice) -> PolyDriver {
    let text = format!(
        "device cartesiancontrollerserver\n[GENERAL]\nControllerName {}\nControllerPeriod 10\n\
         TaskRefVelPeriodFactor 4\nSolverNameToConnect cartesianSolver/left_arm\n\
         KinematicPart arm\nKinematicType left_v2\nPositionControl on\nNumberOfDrivers 2\n\
         [DRIVER_0]\nKey torso\nJointsOrder reversed\nMinAbsVels (0.35 0.35 0.35)\n\
         [DRIVER_1]\nKey left_arm\nJointsOrder direct\n",
        &CTRL[1..]
    );
    let mut pd = PolyDriver::open(&Property::from_config_text(text).unwrap()).expect("server");
    pd.device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[
            ("torso".to_string(), torso.clone()),
            ("left_arm".to_string(), arm.clone()),
        ])
        .expect("attach_all");
    pd
}

/// A port of the test's own, connected to the server's `rpc:i`.
pub fn client(ctrl: &str) -> std::sync::Arc<yarp_net::port::Port> {
    let ns = yarp_interop_tests::name_client();
    let target = format!("{ctrl}/rpc:i");
    let local = format!(
        "/test{ctrl}/rpc{}",
        CLIENTS.fetch_add(1, std::sync::atomic::Ordering::SeqCst)
    );
    yarp_devices::runtime::block_on_result(async move {
        let p = yarp_net::port::Port::open(&local, ns)
            .await
            .map_err(|e| e.to_string())?;
        p.connect(&target, None).await.map_err(|e| e.to_string())?;
        Ok::<_, String>(std::sync::Arc::new(p))
    })
    .expect("client port")
}

pub fn rpc(port: &std::sync::Arc<yarp_net::port::Port>, text: &str) -> Bottle {
    let (port, cmd) = (port.clone(), Bottle::from_text(text));
    yarp_devices::runtime::block_on_within(Duration::from_secs(20), async move {
        port.rpc(&cmd).await.ok()
    })
    .ok()
    .flatten()
    .unwrap_or_else(|| panic!("{text}: no reply"))
}

pub struct Robot {
    _boards: Vec<PolyDriver>,
    _server: PolyDriver,
    _solver: yarp_interop_tests::Reaped,
}

pub fn up(test: &str) -> Robot {
    yarp_interop_tests::name_server();
    yarp_devices_register();
    let (torso_lim, arm_lim) = arm_limits();
    let (torso, torso_nws) = board("/icub/torso", &torso_lim, 3);
    let (arm, arm_nws) = board("/icub/left_arm", &arm_lim, 16);
    {
        // a posture away from the bounds, as a calibrated arm's
        let mut pd = arm.lock();
        let enc = pd.device().as_position_direct().unwrap();
        for (j, q) in [-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 0.0].iter().enumerate() {
            enc.set_position(j, *q).unwrap();
        }
    }
    let child = solver(test, "icub", "cartesianSolver");
    let server = server(&torso, &arm);
    Robot {
        _boards: vec![torso_nws, arm_nws],
        _server: server,
        _solver: child,
    }
}

pub fn yarp_devices_register() {
    yarp_devices::Registry::install(icub_cartesian::register);
}

pub fn axis_angle_error(a: &[f64], b: &[f64]) -> f64 {
    let ra = icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(a[0], a[1], a[2], a[3]));
    let rb = icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(b[0], b[1], b[2], b[3]));
    icub_ikin::pose::dcm2axis(&(ra * rb.transpose()))[3].abs()
}

/// icub-main's C++ `cartesiancontrollerclient` driven by `tests/peers/cartesian_client.cpp`,
/// built once against the C++ peer.
pub fn cpp_client(test: &str) -> Option<PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peers/cartesian_client.cpp");
    yarp_interop_tests::build_cpp_program(
        test,
        "cartesian_client",
        &[src],
        &[],
        &["YARP_dev", "YARP_sig", "YARP_os", "YARP_init"],
    )
}

/// Waits until the server at `ctrl` says its solver is connected.
pub fn wait_solver(test: &str, ctrl: &str) -> std::sync::Arc<yarp_net::port::Port> {
    let rpc_i = format!("{ctrl}/rpc:i");
    yarp_interop_tests::wait_for(&rpc_i, || {
        yarp_interop_tests::registered(&rpc_i).then_some(())
    });
    let port = client(ctrl);
    let until = Instant::now() + Duration::from_secs(30);
    loop {
        let r = rpc(&port, "[get] [ison]");
        if r.get(1)
            .and_then(Value::as_vocab)
            .map(|v| v.as_string())
            .as_deref()
            == Some("true")
        {
            return port;
        }
        assert!(
            Instant::now() < until,
            "{test}: {ctrl} never reached its solver: {r:?}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// Runs the C++ client on `ctrl`: the time each pose took (checked reached within
/// 1 mm and 2 degrees) and the stdout.
pub fn run_cpp_client(test: &str, program: &Path, ctrl: &str, traj_time: f64) -> Vec<f64> {
    let poses = reachable_poses();
    let mut cmd = yarp_interop_tests::cpp_program_command(program);
    cmd.arg(ctrl).arg(traj_time.to_string());
    for p in &poses {
        for v in p {
            cmd.arg(format!("{v:.9}"));
        }
    }
    let out = cmd.output().expect("C++ client");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        out.status.success(),
        "{test}: C++ client: {stdout}\n{stderr}"
    );
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines.iter().any(|l| l.starts_with("STORED 1 ")), "{stdout}");
    let reached: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with("POSE"))
        .collect();
    assert_eq!(reached.len(), 3, "{stdout}");
    let mut times = Vec::new();
    for (line, want) in reached.iter().zip(&poses) {
        let f: Vec<f64> = line
            .split_whitespace()
            .skip(1)
            .filter_map(|v| v.parse().ok())
            .collect();
        assert_eq!(&f[..2], &[1.0, 1.0], "{test}: go/wait failed: {line}");
        let t = f[2];
        let x = &f[3..6];
        let o = &f[6..10];
        let dist = (0..3).map(|k| (x[k] - want[k]).powi(2)).sum::<f64>().sqrt();
        let ang = axis_angle_error(o, &want[3..7]) * RAD2DEG;
        eprintln!(
            "{test}: {ctrl}: reached in {t:.3} s (trajectory {traj_time} s): {:.2} mm, {ang:.2} deg",
            dist * 1e3
        );
        assert!(
            dist < 1e-3,
            "{test}: {:.2} mm from the target: {line}",
            dist * 1e3
        );
        assert!(ang < 2.0, "{test}: {ang:.2} deg from the target: {line}");
        times.push(t);
    }
    let restored = lines
        .iter()
        .find(|l| l.starts_with("RESTORED"))
        .expect("RESTORED");
    // context 1 was stored before the trajectory time was set: the server's 2 s again
    assert_eq!(*restored, "RESTORED 1 2.000", "{stdout}");
    times
}

/// icub-main's C++ server (in C++ yarprobotinterface, on C++ fake boards) with our
/// solver: `/cpp/...` ports, so that it runs beside ours.
pub fn cpp_stack(test: &str) -> Option<(yarp_interop_tests::Reaped, yarp_interop_tests::Reaped)> {
    let yri = peer::cpp_program(test, "yarprobotinterface")?;
    let (torso, arm) = arm_limits();
    let list = |l: &[(f64, f64)], f: fn(&(f64, f64)) -> f64| {
        l.iter()
            .map(f)
            .map(|v| format!("{v:.4}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let board = |name: &str, lim: &[(f64, f64)]| {
        format!(
            r#"<device name="{name}_fake" type="fakeMotionControl">
  <group name="GENERAL"><param name="Joints">{n}</param></group>
  <group name="LIMITS"><param name="Min">({min})</param><param name="Max">({max})</param></group>
</device>
<device name="{name}_nws" type="controlBoard_nws_yarp">
  <param name="name">/cpp/{name}</param>
  <action phase="startup" level="5" type="attach"><paramlist name="networks"><elem name="subdevice">{name}_fake</elem></paramlist></action>
  <action phase="shutdown" level="5" type="detach"/>
</device>
"#,
            n = lim.len(),
            min = list(lim, |l| l.0),
            max = list(lim, |l| l.1)
        )
    };
    let xml = format!(
        r#"<?xml version="1.0" encoding="UTF-8" ?>
<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">
<robot name="cartesianCpp" build="1" portprefix="/cpp">
<devices>
{torso}{arm}<device name="left_arm_cartesian" type="cartesiancontrollerserver">
  <group name="GENERAL">
    <param name="ControllerName">cpp/cartesianController/left_arm</param>
    <param name="ControllerPeriod">10</param>
    <param name="TaskRefVelPeriodFactor">4</param>
    <param name="SolverNameToConnect">cartesianSolverCpp/left_arm</param>
    <param name="KinematicPart">arm</param>
    <param name="KinematicType">left_v2</param>
    <param name="PositionControl">on</param>
    <param name="NumberOfDrivers">2</param>
  </group>
  <group name="DRIVER_0"><param name="Key">torso</param><param name="JointsOrder">reversed</param></group>
  <group name="DRIVER_1"><param name="Key">left_arm</param><param name="JointsOrder">direct</param></group>
  <action phase="startup" level="15" type="attach"><paramlist name="networks"><elem name="torso">torso_fake</elem><elem name="left_arm">left_arm_fake</elem></paramlist></action>
  <action phase="shutdown" level="2" type="detach"/>
</device>
</devices>
</robot>
"#,
        torso = board("torso", &torso),
        arm = board("left_arm", &arm)
    );
    let file = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cartesian-cpp-robot.xml");
    std::fs::write(&file, xml).unwrap();
    let mut cmd = peer::cpp_command(&yri);
    cmd.arg("--config").arg(&file);
    let log = std::fs::File::create(
        Path::new(env!("CARGO_TARGET_TMPDIR")).join("cartesian-cpp-robot.log"),
    )
    .unwrap();
    let robot = cmd
        .stdout(log.try_clone().unwrap())
        .stderr(log)
        .spawn()
        .expect("C++ yarprobotinterface");
    let robot = yarp_interop_tests::Reaped(robot);
    // the boards' wrappers answer once attached (before, `get axes` fails): then the
    // solver can start, as after a robot's start-up
    for part in ["/cpp/torso", "/cpp/left_arm"] {
        let rpc_i = format!("{part}/rpc:i");
        yarp_interop_tests::wait_for(&rpc_i, || {
            yarp_interop_tests::registered(&rpc_i).then_some(())
        });
        let port = client(part);
        yarp_interop_tests::wait_for(&format!("{part} attached"), || {
            rpc(&port, "get axes")
                .to_string()
                .contains("axes")
                .then_some(())
        });
    }
    Some((robot, solver(test, "cpp", "cartesianSolverCpp")))
}
