//! R1SN001's odometry and double lidar from the robot's own files (robots-configuration,
//! unmodified): `cerOdometry` on a two-wheel board that drives straight then turns, and
//! `cerDoubleLidar` over two lidars seeing a round room of known radius.

use std::path::PathBuf;
use std::time::Duration;
use yarp_devices::driver::{shared, SharedDevice};
use yarp_devices::robotinterface::read_robot_file;
use yarp_devices::{PolyDriver, Registry};
use yarp_interop_tests::{name_client, wait_for};
use yarp_proto::Property;

/// The configuration of device `name` in R1SN001's CER.xml.
fn r1_device(name: &str) -> Property {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/R1SN001");
    let robot = read_robot_file(&dir.join("CER.xml"), &Property::default())
        .expect("CER.xml")
        .robot;
    robot.device(name).expect(name).to_property().unwrap()
}

fn open(cfg: &Property) -> PolyDriver {
    Registry::install(cermod::register);
    PolyDriver::open(cfg).unwrap_or_else(|e| panic!("open {cfg}: {e}"))
}

fn text(cfg: &str) -> Property {
    Property::from_config_text(cfg).unwrap()
}

#[test]
fn odometry_follows_the_wheels() {
    name_client();
    // the two wheels (degrees), as R1's mobile base remapper serves them
    let wheels: SharedDevice = shared(open(&text(
        "device fakeMotionControl\n[GENERAL]\nJoints 2\n",
    )));
    let mut odom = open(&r1_device("cer_odometry"));
    odom.device()
        .as_wrapper()
        .unwrap()
        .attach(wheels.clone())
        .expect("attach");
    let o = |pd: &mut PolyDriver| {
        pd.device()
            .as_odometry_2d()
            .unwrap()
            .get_odometry()
            .unwrap()
            .0
    };
    // both wheels forward at 90 deg/s: straight ahead
    {
        let mut w = wheels.lock();
        let m = w.device().as_control_mode().unwrap();
        m.set_control_mode(0, yarp_devices::vocabs::CM_VELOCITY)
            .unwrap();
        m.set_control_mode(1, yarp_devices::vocabs::CM_VELOCITY)
            .unwrap();
        let v = w.device().as_velocity_control().unwrap();
        v.velocity_move(0, 90.0).unwrap();
        v.velocity_move(1, 90.0).unwrap();
    }
    std::thread::sleep(Duration::from_millis(500));
    let straight = o(&mut odom);
    assert!(straight.odom_x > 0.05, "{straight:?}");
    // the two wheels start a command apart: straight within a hundredth of a degree
    assert!(
        straight.odom_y.abs() < 1e-4 && straight.odom_theta.abs() < 0.01,
        "{straight:?}"
    );
    let v = 0.16416 * 90f64.to_radians();
    assert!(
        (straight.base_vel_x - v).abs() < 0.05,
        "{straight:?} vs {v}"
    );
    // the right wheel faster: turning left
    wheels
        .lock()
        .device()
        .as_velocity_control()
        .unwrap()
        .velocity_move(1, 120.0)
        .unwrap();
    let turned = wait_for("a left turn", || {
        let d = o(&mut odom);
        (d.odom_theta > 5.0).then_some(d)
    });
    assert!(
        turned.base_vel_theta > 0.0 && turned.odom_y > 0.0,
        "{turned:?}"
    );
    // reset: back at the origin with the current wheels as zero
    odom.device()
        .as_odometry_2d()
        .unwrap()
        .reset_odometry()
        .unwrap();
    // (the heading follows at the next cycle, from the new zero)
    let reset = wait_for("the heading from the new zero", || {
        let d = o(&mut odom);
        (d.odom_theta.abs() < 1.0).then_some(d)
    });
    assert!(reset.odom_x.abs() < 0.05, "{reset:?}");
    odom.close().unwrap();
}

#[test]
fn double_lidar_merges_front_and_back() {
    // two lidars of R1SN001's geometry, each seeing a wall at 2 m all around
    let lidar = |d: f64| {
        shared(open(&text(&format!(
            "device fakeLaser\ntest use_constant\n[CONSTANT_MODE]\nconst_distance {d}\n\
             [SENSOR]\nmin_angle 0\nmax_angle 360\nresolution 0.225\n"
        ))))
    };
    let mut double = open(&r1_device("cer_double_laser_device"));
    let attach = |pd: &mut PolyDriver, list: Vec<(String, SharedDevice)>| {
        pd.device().as_multiple_wrapper().unwrap().attach_all(&list)
    };
    // keys must be the sensor names
    let e = attach(
        &mut double,
        vec![("x".into(), lidar(2.0)), ("L_Back".into(), lidar(2.0))],
    )
    .unwrap_err();
    assert!(e.to_string().contains("neither the front"), "{e}");
    attach(
        &mut double,
        vec![
            ("L_Front".into(), lidar(2.0)),
            ("L_Back".into(), lidar(2.0)),
        ],
    )
    .expect("attach");
    let l = double.device().as_rangefinder_2d().unwrap();
    assert_eq!(l.get_horizontal_resolution().unwrap(), 0.225);
    let (scan, t) = l.get_raw_data().unwrap();
    assert_eq!(scan.len(), 1600);
    assert!(t > 1.6e9);
    // every point is 2 m from a lidar 7 cm off the centre: 1.93..2.07 m from the centre
    let seen: Vec<f64> = scan.iter().copied().filter(|d| d.is_finite()).collect();
    assert!(seen.len() > 1400, "{} steps seen", seen.len());
    assert!(seen.iter().all(|d| (1.92..=2.08).contains(d)), "{seen:?}");
    // straight ahead only the front lidar's wall: 2 m + 7 cm
    assert!((scan[0] - 2.07).abs() < 0.01, "{}", scan[0]);
    double.close().unwrap();
    // a lidar of another resolution is refused
    let mut other = open(&r1_device("cer_double_laser_device"));
    let coarse = shared(open(&text(
        "device fakeLaser\ntest use_constant\n[SENSOR]\nmin_angle 0\nmax_angle 360\nresolution 1\n",
    )));
    let e = attach(
        &mut other,
        vec![("L_Front".into(), coarse), ("L_Back".into(), lidar(2.0))],
    )
    .unwrap_err();
    assert!(e.to_string().contains("resolution"), "{e}");
}

#[test]
fn torso_tripod_reaches_heave_pitch_and_roll() {
    // the torso board: three legs (m) and the yaw, in position control
    let board: SharedDevice = shared(open(&text(
        "device fakeMotionControl\n[GENERAL]\nJoints 4\n",
    )));
    {
        let mut b = board.lock();
        let p = b.device().as_position_control().unwrap();
        p.set_ref_speeds(&[0.5, 0.5, 0.5, 10.0]).unwrap();
    }
    let mut tripod = open(&r1_device("cer_torso_equivalent_mc"));
    // not attached: no axes yet, as C++
    assert!(tripod.device().as_encoders().unwrap().get_axes().is_err());
    tripod
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("FirstSetOfJoints".into(), board.clone())])
        .expect("attach");
    let d = tripod.device();
    assert_eq!(
        d.as_axis_info().unwrap().get_axis_name(1).unwrap(),
        "torso_pitch_eq_joint"
    );
    // pitch's Encoder is -1: its limits and values change sign, the range stays
    assert_eq!(
        d.as_control_limits().unwrap().get_limits(0).unwrap(),
        (-0.04, 0.15)
    );
    assert_eq!(
        d.as_control_limits().unwrap().get_limits(1).unwrap(),
        (-25.0, 25.0)
    );
    let p = d.as_position_control().unwrap();
    p.set_ref_speed(0, 0.05).unwrap();
    p.position_moves(&[0.05, 5.0, 3.0]).unwrap();
    assert_eq!(p.get_target_positions().unwrap(), vec![0.05, 5.0, 3.0]);
    let q = wait_for("the tripod at its target", || {
        let q = tripod.device().as_encoders()?.get_encoders().ok()?;
        let done =
            (q[0] - 0.05).abs() < 1e-4 && (q[1] - 5.0).abs() < 0.05 && (q[2] - 3.0).abs() < 0.05;
        done.then_some(q)
    });
    // the legs: C++'s inverse kinematics of heave 0.05, pitch -5 (Encoder -1), roll 3, once
    // they too have stopped (the joints' test above passes while they still settle)
    let want = cermod::tripod::Tripod {
        radius: 0.09,
        base: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ],
    }
    .inverse([0.05, -5.0, 3.0]);
    let legs = wait_for("the legs at the target's lengths", || {
        let legs = board.lock().device().as_encoders()?.get_encoders().ok()?;
        (0..3)
            .all(|k| (legs[k] - want[k]).abs() < 1e-4)
            .then_some(legs)
    });
    assert!(
        legs.len() >= 3,
        "legs {legs:?} want {want:?} (joints {q:?})"
    );
    // velocity control is refused, as C++'s
    assert!(tripod
        .device()
        .as_velocity_control()
        .unwrap()
        .velocity_move(0, 0.01)
        .is_err());
}
