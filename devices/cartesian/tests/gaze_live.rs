//! The gaze controller live: two fake boards served as an iCub's `/icub/torso` and
//! `/icub/head` (an iCub 2.5 head's joint bounds), our `iKinGazeCtrl` on them and our
//! `gazecontrollerclient` looking at three points in front of the robot; the fixation
//! point, as the head's kinematics computes it from the boards' encoders, reaches each
//! within 1 cm.

use icub_cartesian::gaze::kinematics::Head;
use icub_ikin::DEG2RAD;
use std::process::Command;
use std::time::Duration;
use yarp_devices::driver::{shared, SharedDevice};
use yarp_devices::PolyDriver;
use yarp_proto::Property;

fn board(name: &str, limits: &[(f64, f64)]) -> (SharedDevice, PolyDriver) {
    let list = |f: fn(&(f64, f64)) -> f64| {
        limits
            .iter()
            .map(f)
            .map(|v| format!("{v}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let fake = PolyDriver::open(
        &Property::from_config_text(format!(
            "device fakeMotionControl\n[GENERAL]\nJoints {}\n[LIMITS]\nMin ({})\nMax ({})\n",
            limits.len(),
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

fn encoders(dev: &SharedDevice) -> Vec<f64> {
    let mut pd = dev.lock();
    pd.device().as_encoders().unwrap().get_encoders().unwrap()
}

#[test]
fn our_client_looks_at_three_points_through_our_ikingazectrl() {
    let test = "our_client_looks_at_three_points_through_our_ikingazectrl";
    yarp_interop_tests::name_server();
    yarp_devices::Registry::install(icub_cartesian::register);
    let (torso, _torso_nws) = board(
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
    let (head, _head_nws) = board("/icub/head", &head_limits);
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
    let child = Command::new(env!("CARGO_BIN_EXE_iKinGazeCtrl"))
        .args([
            "--head_version",
            "v2.5",
            "--saccades",
            "off",
            "--imu::mode",
            "off",
            "--ping_robot_tmo",
            "20",
        ])
        .stderr(log)
        .spawn()
        .expect("iKinGazeCtrl");
    let _gaze = yarp_interop_tests::Reaped(child);
    yarp_interop_tests::wait_for("/iKinGazeCtrl/rpc", || {
        yarp_interop_tests::registered("/iKinGazeCtrl/rpc").then_some(())
    });
    let mut pd = PolyDriver::open(&Property::from_text(
        "(device gazecontrollerclient) (remote /iKinGazeCtrl) (local /gaze_test)",
    ))
    .expect("gazecontrollerclient");
    let gaze = pd.device().as_gaze_control().expect("IGazeControl");
    let info = gaze.get_info().unwrap().to_string();
    assert!(info.contains("(server_version \"2.0\")"), "{info}");
    assert!(info.contains("(head_version \"2.5\")"), "{info}");
    let kin = Head::new("v2.5").unwrap();
    // in front of the robot (its root frame: x backwards, y right... z up)
    let points = [[-0.5, 0.0, 0.35], [-0.45, 0.12, 0.3], [-0.6, -0.1, 0.45]];
    for p in points {
        gaze.take_events();
        gaze.look_at_fixation_point_sync(&p).unwrap();
        assert!(
            gaze.wait_motion_done(0.02, 10.0).unwrap(),
            "{test}: not done"
        );
        std::thread::sleep(Duration::from_millis(100));
        let t = encoders(&torso);
        let h = encoders(&head);
        let mut tq = [t[2] * DEG2RAD, t[1] * DEG2RAD, t[0] * DEG2RAD];
        if kin.version >= 3.0 {
            tq.reverse();
        }
        let hq: [f64; 6] = std::array::from_fn(|k| h[k] * DEG2RAD);
        let fp = kin.fixation_point(&tq, &hq).expect("the eyes converge");
        let d = ((fp[0] - p[0]).powi(2) + (fp[1] - p[1]).powi(2) + (fp[2] - p[2]).powi(2)).sqrt();
        eprintln!("{test}: {p:?}: fixation {fp:?} ({:.1} mm off)", d * 1e3);
        assert!(
            d < 0.01,
            "{test}: {:.1} mm from {p:?} (head {h:?})",
            d * 1e3
        );
        let (streamed, _) = gaze.get_fixation_point().unwrap();
        let ds = ((streamed[0] - p[0]).powi(2)
            + (streamed[1] - p[1]).powi(2)
            + (streamed[2] - p[2]).powi(2))
        .sqrt();
        assert!(ds < 0.01, "{test}: x:o says {streamed:?}");
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
    let ctx = gaze.store_context().unwrap();
    gaze.set_neck_traj_time(2.0).unwrap();
    gaze.restore_context(ctx).unwrap();
    assert_eq!(gaze.get_neck_traj_time().unwrap(), 0.75);
    pd.close().unwrap();
}
