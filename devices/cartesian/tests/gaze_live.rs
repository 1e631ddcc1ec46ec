//! The gaze controller live: two fake boards served as an iCub's `/icub/torso` and
//! `/icub/head` (an iCub 2.5 head's joint bounds), our `iKinGazeCtrl` on them and our
//! `gazecontrollerclient` looking at three points in front of the robot; the fixation
//! point, as the head's kinematics computes it from the boards' encoders, reaches each
//! within 1 cm.

mod common;

use icub_cartesian::gaze::kinematics::Head;
use icub_ikin::DEG2RAD;
use std::process::Command;
use std::time::Duration;
use yarp_devices::driver::SharedDevice;
use yarp_devices::PolyDriver;
use yarp_proto::Property;

/// A fake board of `limits`' joints served as `name` (the Cartesian tests' own).
fn board(name: &str, limits: &[(f64, f64)]) -> (SharedDevice, PolyDriver) {
    common::board(name, limits, limits.len())
}

fn encoders(dev: &SharedDevice) -> Vec<f64> {
    let mut pd = dev.lock();
    pd.device().as_encoders().unwrap().get_encoders().unwrap()
}

/// The robot's torso and head boards and our iKinGazeCtrl on them.
struct Robot {
    torso: SharedDevice,
    head: SharedDevice,
    _nws: Vec<PolyDriver>,
    _gaze: yarp_interop_tests::Reaped,
}

/// `name`: the module's port prefix (each test its own: a killed module's ports stay
/// registered in this process's name server).
fn up(test: &str, name: &str) -> Robot {
    up_with(test, name, None)
}

/// [`up`] with the head IMU `imu` (a `multipleanalogsensorsserver` as
/// `/icub/head/inertials`): iKinGazeCtrl then runs with `imu::mode on`, its default.
fn up_with(test: &str, name: &str, imu: Option<PolyDriver>) -> Robot {
    yarp_interop_tests::name_server();
    yarp_devices::Registry::install(icub_cartesian::register);
    let (torso, torso_nws) = board(
        "/icub/torso",
        &[(-59.0, 59.0), (-39.0, 39.0), (-22.0, 84.0)],
    );
    let head_limits = [
        (-40.0, 30.0),
        (-70.0, 60.0),
        (-55.0, 55.0),
        (-35.0, 15.0),
        (-50.0, 50.0),
        (0.0, 90.0),
    ];
    let (head, head_nws) = board("/icub/head", &head_limits);
    {
        // eyes slightly converged, as a calibrated head parks them
        let mut pd = head.lock();
        pd.device()
            .as_position_direct()
            .unwrap()
            .set_position(5, 10.0)
            .unwrap();
        pd.device()
            .as_control_mode()
            .unwrap()
            .set_control_mode(5, yarp_devices::vocabs::CM_POSITION_DIRECT)
            .unwrap();
    }
    let log = std::fs::File::create(
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("iKinGazeCtrl.log"),
    )
    .unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_iKinGazeCtrl"));
    if imu.is_none() {
        cmd.args(["--imu::mode", "off"]);
    }
    let child = cmd
        .args([
            "--head_version",
            "v2.5",
            "--saccades",
            "off",
            "--ping_robot_tmo",
            "20",
            "--name",
            name,
            // the eyes' calibration of a robot, read unmodified
            "--cameras::file",
        ])
        .arg(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../../shared/robots-configuration/iCubGenova01/icubEyes.ini"),
        )
        .stderr(log)
        .spawn()
        .expect("iKinGazeCtrl");
    let gaze = yarp_interop_tests::Reaped(child);
    let rpc = format!("/{name}/rpc");
    yarp_interop_tests::wait_for(&rpc, || yarp_interop_tests::registered(&rpc).then_some(()));
    let _ = test;
    Robot {
        torso,
        head,
        _nws: [torso_nws, head_nws].into_iter().chain(imu).collect(),
        _gaze: gaze,
    }
}

/// The fixation point, as the head's kinematics computes it from the boards' encoders.
fn fixation(robot: &Robot) -> [f64; 3] {
    let kin = Head::new("v2.5").unwrap();
    let t = encoders(&robot.torso);
    let h = encoders(&robot.head);
    let tq = [t[2] * DEG2RAD, t[1] * DEG2RAD, t[0] * DEG2RAD];
    let hq: [f64; 6] = std::array::from_fn(|k| h[k] * DEG2RAD);
    let fp = kin.fixation_point(&tq, &hq).expect("the eyes converge");
    [fp[0], fp[1], fp[2]]
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Three points in front of the robot (its root frame: x backwards, y right, z up).
const POINTS: [[f64; 3]; 3] = [[-0.5, 0.0, 0.35], [-0.45, 0.12, 0.3], [-0.6, -0.1, 0.45]];

#[test]
fn our_client_looks_at_three_points_through_our_ikingazectrl() {
    let test = "our_client_looks_at_three_points_through_our_ikingazectrl";
    let robot = up(test, "iKinGazeCtrlRust");
    let mut pd = PolyDriver::open(&Property::from_text(
        "(device gazecontrollerclient) (remote /iKinGazeCtrlRust) (local /gaze_test)",
    ))
    .expect("gazecontrollerclient");
    let gaze = pd.device().as_gaze_control().expect("IGazeControl");
    let info = gaze.get_info().unwrap().to_string();
    assert!(info.contains("(server_version \"2.0\")"), "{info}");
    assert!(info.contains("(head_version \"2.5\")"), "{info}");
    for p in POINTS {
        gaze.take_events();
        gaze.look_at_fixation_point_sync(&p).unwrap();
        assert!(
            gaze.wait_motion_done(0.02, 10.0).unwrap(),
            "{test}: not done"
        );
        std::thread::sleep(Duration::from_millis(100));
        let fp = fixation(&robot);
        let d = dist(&fp, &p);
        eprintln!("{test}: {p:?}: fixation {fp:?} ({:.1} mm off)", d * 1e3);
        assert!(d < 0.01, "{test}: {:.1} mm from {p:?}", d * 1e3);
        let (streamed, _) = gaze.get_fixation_point().unwrap();
        assert!(dist(&streamed, &p) < 0.01, "{test}: x:o says {streamed:?}");
        let kinds: Vec<String> = gaze.take_events().into_iter().map(|e| e.kind).collect();
        assert_eq!(
            kinds.first().map(String::as_str),
            Some("motion-onset"),
            "{kinds:?}"
        );
        assert_eq!(
            kinds.last().map(String::as_str),
            Some("motion-done"),
            "{kinds:?}"
        );
    }
    let ang = gaze.get_angles().unwrap();
    assert!(ang[2] > 0.0, "{ang:?}");
    // a point seen by both cameras: triangulated back, then looked at by its pixels
    let p = [-0.55, 0.05, 0.4];
    let (pl, pr) = (
        gaze.get_2d_pixel(0, &p).unwrap(),
        gaze.get_2d_pixel(1, &p).unwrap(),
    );
    let back = gaze.triangulate_3d_point(&pl, &pr).unwrap();
    assert!(dist(&back, &p) < 1e-6, "{test}: triangulated {back:?}");
    gaze.look_at_stereo_pixels_sync(&pl, &pr).unwrap();
    assert!(
        gaze.wait_motion_done(0.02, 10.0).unwrap(),
        "{test}: not done"
    );
    std::thread::sleep(Duration::from_millis(100));
    let fp = fixation(&robot);
    assert!(
        dist(&fp, &p) < 0.01,
        "{test}: looking at the pixels: {fp:?}"
    );
    // and the left camera's centre pixel at 0.5 m
    let x = gaze.get_3d_point(0, &[160.0, 120.0], 0.5).unwrap();
    assert!(dist(&x, &fp) > 0.0);
    let ctx = gaze.store_context().unwrap();
    gaze.set_neck_traj_time(2.0).unwrap();
    gaze.restore_context(ctx).unwrap();
    assert_eq!(gaze.get_neck_traj_time().unwrap(), 0.75);
    pd.close().unwrap();
}

/// icub-main's C++ client, built from ../shared/peers' sources against the C++ peer.
fn cpp_gaze_client(test: &str) -> Option<std::path::PathBuf> {
    let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let client =
        here.join("../../../shared/peers/src/icub-main/src/libraries/icubmod/gazeController");
    yarp_interop_tests::build_cpp_program(
        test,
        "gaze_client",
        &[
            here.join("tests/peers/gaze_client.cpp"),
            client.join("ClientGazeController.cpp"),
        ],
        &[client],
        &["YARP_dev", "YARP_sig", "YARP_math", "YARP_os", "YARP_init"],
    )
}

#[test]
fn cpp_client_looks_at_three_points_through_our_ikingazectrl() {
    let test = "cpp_client_looks_at_three_points_through_our_ikingazectrl";
    let Some(program) = cpp_gaze_client(test) else {
        return;
    };
    let robot = up(test, "iKinGazeCtrl");
    let mut cmd = yarp_interop_tests::cpp_program_command(&program);
    cmd.arg("/iKinGazeCtrl");
    for p in POINTS {
        for v in p {
            cmd.arg(v.to_string());
        }
    }
    let out = cmd.output().expect("C++ gaze client");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{test}: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("STORED 1 "), "{stdout}");
    let fixes: Vec<&str> = stdout.lines().filter(|l| l.starts_with("FIX")).collect();
    assert_eq!(fixes.len(), 3, "{stdout}");
    for (line, p) in fixes.iter().zip(POINTS) {
        let f: Vec<f64> = line
            .split_whitespace()
            .skip(1)
            .filter_map(|v| v.parse().ok())
            .collect();
        assert_eq!(&f[..3], &[1.0, 1.0, 1.0], "{test}: {line}");
        let fp = [f[3], f[4], f[5]];
        eprintln!(
            "{test}: {p:?}: the C++ client reads {fp:?} ({:.1} mm off)",
            dist(&fp, &p) * 1e3
        );
        assert!(dist(&fp, &p) < 0.01, "{test}: {line}");
    }
    // the last point, also as the head's kinematics has it
    assert!(dist(&fixation(&robot), &POINTS[2]) < 0.01);
    assert!(stdout.contains("RESTORED 1 0.750"), "{stdout}");
    // imu::mode off: VOR 0, OCR 1, stabilisation refused (C++'s client gets false)
    assert!(stdout.contains("REFLEXES 1 0.000 1.000 0 0"), "{stdout}");
}

/// With the head's IMU (a fakeIMU turning at a steady 10 deg/s about each axis, served as
/// `/icub/head/inertials`), as iKinGazeCtrl runs by default: the reflexes' gains are
/// C++'s defaults (VOR 1, OCR 0); gaze stabilisation, asked through our client, turns the
/// idle neck against the rotation and says `stabilization-on`; turned off, the neck
/// stops and it says `stabilization-off`. Without the IMU it is refused.
#[test]
fn stabilization_turns_the_idle_neck_against_the_imus_rotation() {
    let test = "stabilization_turns_the_idle_neck_against_the_imus_rotation";
    yarp_interop_tests::name_server();
    let imu = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /icub/head/inertials\n\
             period 10\nconstantValue true\n",
        )
        .unwrap(),
    )
    .expect("fakeIMU behind multipleanalogsensorsserver");
    let robot = up_with(test, "iKinGazeCtrlImu", Some(imu));
    let mut pd = PolyDriver::open(&Property::from_text(
        "(device gazecontrollerclient) (remote /iKinGazeCtrlImu) (local /gaze_test_imu)",
    ))
    .expect("gazecontrollerclient");
    let gaze = pd.device().as_gaze_control().expect("IGazeControl");
    assert_eq!(gaze.get_vor_gain().unwrap(), 1.0);
    assert_eq!(gaze.get_ocr_gain().unwrap(), 0.0);
    gaze.set_ocr_gain(0.5).unwrap();
    assert_eq!(gaze.get_ocr_gain().unwrap(), 0.5);
    assert!(!gaze.get_stabilization_mode().unwrap());
    let neck = |r: &Robot| encoders(&r.head)[..3].to_vec();
    let before = neck(&robot);
    gaze.take_events();
    gaze.set_stabilization_mode(true).unwrap();
    assert!(gaze.get_stabilization_mode().unwrap());
    std::thread::sleep(Duration::from_millis(1000));
    let turned = neck(&robot);
    let moved = (0..3)
        .map(|k| (turned[k] - before[k]).abs())
        .fold(0.0, f64::max);
    eprintln!("{test}: the neck from {before:?} to {turned:?}");
    assert!(
        moved > 1.0,
        "{test}: the neck did not counter the rotation: {turned:?}"
    );
    gaze.set_stabilization_mode(false).unwrap();
    assert!(!gaze.get_stabilization_mode().unwrap());
    std::thread::sleep(Duration::from_millis(200));
    let stopped = neck(&robot);
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        neck(&robot),
        stopped,
        "{test}: the neck goes on after stabilization-off"
    );
    let kinds: Vec<String> = gaze.take_events().into_iter().map(|e| e.kind).collect();
    assert!(kinds.contains(&"stabilization-on".to_string()), "{kinds:?}");
    assert!(
        kinds.contains(&"stabilization-off".to_string()),
        "{kinds:?}"
    );
    pd.close().unwrap();
    // without the IMU (imu::mode off) the request is refused, as C++'s
    let _robot = up(test, "iKinGazeCtrlNoImu");
    let mut pd = PolyDriver::open(&Property::from_text(
        "(device gazecontrollerclient) (remote /iKinGazeCtrlNoImu) (local /gaze_test_noimu)",
    ))
    .expect("gazecontrollerclient");
    let gaze = pd.device().as_gaze_control().expect("IGazeControl");
    assert!(gaze.set_stabilization_mode(true).is_err());
    assert_eq!(gaze.get_vor_gain().unwrap(), 0.0);
    assert_eq!(gaze.get_ocr_gain().unwrap(), 1.0);
    pd.close().unwrap();
}
