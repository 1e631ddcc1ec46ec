//! The Cartesian controller of an iCub's left arm, live: two fake boards served as
//! `/icub/torso` and `/icub/left_arm` (joint bounds as iKin's left_v2 arm), our
//! `iKinCartesianSolver` on iCubGenova02's own `cartesianSolver.ini`, our
//! `cartesiancontrollerserver` with the settings of its `cartesian/left_arm-cartesian.xml`,
//! and icub-main's C++ `cartesiancontrollerclient` (built from ../shared/peers) reaching
//! three poses, storing and restoring a context.

use icub_ikin::{Limb, RAD2DEG};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use yarp_devices::driver::{shared, SharedDevice};
use yarp_devices::PolyDriver;
use yarp_interop_tests as peer;
use yarp_proto::{Bottle, Property, Value};

const CTRL: &str = "/icub/cartesianController/left_arm";

fn robots() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration")
}

/// A fake board of `joints` with `limits` (deg), served by controlBoard_nws_yarp as `name`.
fn board(name: &str, limits: &[(f64, f64)], joints: usize) -> (SharedDevice, PolyDriver) {
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
type Bounds = Vec<(f64, f64)>;

/// The left_v2 arm's bounds (deg) in the robot's order: torso (yaw, roll, pitch) and arm.
fn arm_limits() -> (Bounds, Bounds) {
    let limb = Limb::arm("left_v2").unwrap();
    let links = limb.chain().links();
    let deg = |i: usize| (links[i].min * RAD2DEG, links[i].max * RAD2DEG);
    let torso = vec![deg(2), deg(1), deg(0)];
    let mut arm: Vec<(f64, f64)> = (3..10).map(deg).collect();
    arm.extend(std::iter::repeat_n((0.0, 90.0), 9));
    (torso, arm)
}

/// Three poses of the hand the arm reaches (iKin's forward kinematics of three postures).
fn reachable_poses() -> Vec<[f64; 7]> {
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

/// The robot's solver group, with the period of its file.
fn solver(test: &str) -> yarp_interop_tests::Reaped {
    let ini = robots().join("iCubGenova02/cartesianSolver.ini");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_iKinCartesianSolver"));
    cmd.arg("--from").arg(&ini).args(["--part", "left_arm"]);
    let child = cmd
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("{test}: iKinCartesianSolver: {e}"));
    yarp_interop_tests::Reaped(child)
}

fn server(torso: &SharedDevice, arm: &SharedDevice) -> PolyDriver {
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
fn client() -> std::sync::Arc<yarp_net::port::Port> {
    let ns = yarp_interop_tests::name_client();
    yarp_devices::runtime::block_on_result(async move {
        let p = yarp_net::port::Port::open("/test/cartesian/rpc", ns)
            .await
            .map_err(|e| e.to_string())?;
        p.connect(&format!("{CTRL}/rpc:i"), None)
            .await
            .map_err(|e| e.to_string())?;
        Ok::<_, String>(std::sync::Arc::new(p))
    })
    .expect("client port")
}

fn rpc(port: &std::sync::Arc<yarp_net::port::Port>, text: &str) -> Bottle {
    let (port, cmd) = (port.clone(), Bottle::from_text(text));
    yarp_devices::runtime::block_on_within(Duration::from_secs(20), async move {
        port.rpc(&cmd).await.ok()
    })
    .ok()
    .flatten()
    .unwrap_or_else(|| panic!("{text}: no reply"))
}

struct Robot {
    _boards: Vec<PolyDriver>,
    _server: PolyDriver,
    _solver: yarp_interop_tests::Reaped,
}

fn up(test: &str) -> Robot {
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
    let child = solver(test);
    let server = server(&torso, &arm);
    Robot {
        _boards: vec![torso_nws, arm_nws],
        _server: server,
        _solver: child,
    }
}

fn yarp_devices_register() {
    yarp_devices::Registry::install(icub_cartesian::register);
}

fn axis_angle_error(a: &[f64], b: &[f64]) -> f64 {
    let ra = icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(a[0], a[1], a[2], a[3]));
    let rb = icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(b[0], b[1], b[2], b[3]));
    icub_ikin::pose::dcm2axis(&(ra * rb.transpose()))[3].abs()
}

/// The C++ client program, built once per source against the C++ peer.
fn cpp_client(test: &str) -> Option<(PathBuf, PathBuf)> {
    let bin = peer::cpp_bin_dir();
    if bin.is_none() {
        peer::peer_missing(
            test,
            "C++ YARP with icub-main",
            "no YARP_CPP_BIN",
            peer::CPP_YARP_INSTALL,
        );
        return None;
    }
    let prefix = std::fs::canonicalize(bin.unwrap())
        .ok()?
        .parent()?
        .to_path_buf();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peers/cartesian_client.cpp");
    let text = std::fs::read(&src).unwrap();
    let stamp = text.iter().fold(0xcbf29ce484222325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x100000001b3)
    }) ^ prefix.to_string_lossy().len() as u64;
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cartesian_client-{stamp:x}"));
    if !out.is_file() {
        let st = Command::new("g++")
            .args(["-std=c++17", "-O1", "-o"])
            .arg(&out)
            .arg(&src)
            .arg(format!("-I{}", prefix.join("include").display()))
            .arg(format!("-L{}", prefix.join("lib").display()))
            .args(["-lYARP_dev", "-lYARP_sig", "-lYARP_os", "-lYARP_init"])
            .status()
            .expect("g++");
        assert!(st.success(), "{test}: building {} failed", src.display());
    }
    Some((out, prefix))
}

#[test]
fn cpp_client_reaches_three_poses_and_restores_a_context() {
    let test = "cpp_client_reaches_three_poses_and_restores_a_context";
    let Some((program, prefix)) = cpp_client(test) else {
        return;
    };
    let _robot = up(test);
    let port = client();
    let until = Instant::now() + Duration::from_secs(30);
    loop {
        let r = rpc(&port, "[get] [ison]");
        if r.get(1)
            .and_then(Value::as_vocab)
            .map(|v| v.as_string())
            .as_deref()
            == Some("true")
        {
            break;
        }
        assert!(
            Instant::now() < until,
            "{test}: the server never reached the solver: {r:?}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let poses = reachable_poses();
    let traj_time = 1.5;
    let mut cmd = Command::new(&program);
    cmd.env("LD_LIBRARY_PATH", prefix.join("lib")).env(
        "YARP_DATA_DIRS",
        format!(
            "{}:{}",
            prefix.join("share/yarp").display(),
            prefix.join("share/iCub").display()
        ),
    );
    cmd.arg(CTRL).arg(traj_time.to_string());
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
    eprintln!(
        "{test}: the server's last target: {}",
        rpc(&port, "[get] [des]")
    );
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines.iter().any(|l| l.starts_with("STORED 1 ")), "{stdout}");
    let reached: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with("POSE"))
        .collect();
    assert_eq!(reached.len(), 3, "{stdout}");
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
            "{test}: reached in {t:.3} s (trajectory {traj_time} s): {:.2} mm, {ang:.2} deg",
            dist * 1e3
        );
        assert!(
            dist < 1e-3,
            "{test}: {:.2} mm from the target: {line}",
            dist * 1e3
        );
        assert!(ang < 2.0, "{test}: {ang:.2} deg from the target: {line}");
        // a minimum-jerk step is 90 % done at T and over by 1.5 T; a millimetre's
        // tolerance ends it past that (measured here: about 2 T; C++'s figure is still to
        // be taken side by side)
        assert!(
            t >= 0.9 * traj_time && t <= 2.5 * traj_time,
            "{test}: {t:.3} s for a trajectory time of {traj_time} s"
        );
    }
    let restored = lines
        .iter()
        .find(|l| l.starts_with("RESTORED"))
        .expect("RESTORED");
    // context 1 was stored before the trajectory time was set: the server's 2 s again
    assert_eq!(*restored, "RESTORED 1 2.000", "{stdout}");
}
