//! The Cartesian controller of an iCub's left arm, live: two fake boards served as
//! `/icub/torso` and `/icub/left_arm` (joint bounds as iKin's left_v2 arm), our
//! `iKinCartesianSolver` on iCubGenova02's own `cartesianSolver.ini`, our
//! `cartesiancontrollerserver` with the settings of its `cartesian/left_arm-cartesian.xml`,
//! and icub-main's C++ `cartesiancontrollerclient` (built from ../shared/peers) reaching
//! three poses, storing and restoring a context.

mod common;

use common::*;
use icub_ikin::RAD2DEG;
use std::time::Duration;
use yarp_devices::PolyDriver;
use yarp_proto::Property;

#[test]
fn cpp_client_reaches_three_poses_on_our_server_and_on_cpps_beside_it() {
    let test = "cpp_client_reaches_three_poses_on_our_server_and_on_cpps_beside_it";
    let Some(program) = cpp_client(test) else {
        return;
    };
    let traj_time = 1.5;
    yarp_interop_tests::name_server();
    // icub-main's own server with our solver first: the reference
    let Some(_cpp) = cpp_stack(test) else {
        return;
    };
    wait_solver(test, "/cpp/cartesianController/left_arm");
    let theirs = run_cpp_client(
        test,
        &program,
        "/cpp/cartesianController/left_arm",
        traj_time,
    );
    let _robot = up(test);
    wait_solver(test, CTRL);
    let ours = run_cpp_client(test, &program, CTRL, traj_time);
    for (i, (o, t)) in ours.iter().zip(&theirs).enumerate() {
        eprintln!("{test}: pose {i}: ours {o:.3} s, C++'s {t:.3} s");
        assert!(
            (o - t).abs() <= 0.1 * t,
            "{test}: pose {i} took {o:.3} s on ours, {t:.3} s on C++'s server"
        );
    }
}

#[test]
fn rust_client_reaches_three_poses_reads_events_and_stops_at_the_closest_reachable() {
    let test = "rust_client_reaches_three_poses_reads_events_and_stops_at_the_closest_reachable";
    let _robot = up(test);
    wait_solver(test, CTRL);
    let mut pd = PolyDriver::open(&Property::from_text(format!(
        // tcp: the events are all checked (over C++'s default udp a loaded machine may
        // drop a datagram, as it may for C++'s client)
        "(device cartesiancontrollerclient) (remote {CTRL}) (local /rust_cartesian_client) \
         (carrier tcp)"
    )))
    .expect("cartesiancontrollerclient");
    let cart = pd
        .device()
        .as_cartesian_control()
        .expect("ICartesianControl");
    let info = cart.get_info().unwrap();
    assert!(
        info.to_string().contains("(server_version \"2.0\")"),
        "{info}"
    );
    assert!(info.to_string().contains("(arm_type left_v2)"), "{info}");
    let ctx = cart.store_context().unwrap();
    let traj_time = 1.0;
    cart.set_traj_time(traj_time).unwrap();
    cart.set_in_target_tol(1e-3).unwrap();
    cart.register_ongoing_checkpoint(0.5).unwrap();
    for want in reachable_poses() {
        let (x, o) = (
            [want[0], want[1], want[2]],
            [want[3], want[4], want[5], want[6]],
        );
        // the solver's answer for it, without moving
        let asked = cart.ask_for_pose(&x, &o, None).unwrap();
        assert_eq!(asked.q.len(), 10, "{asked:?}");
        cart.take_events();
        cart.go_to_pose_sync(&x, &o, 0.0).unwrap();
        assert!(
            cart.wait_motion_done(0.01, 10.0).unwrap(),
            "{test}: not done"
        );
        std::thread::sleep(Duration::from_millis(100));
        let ((px, po), _) = cart.get_pose().unwrap();
        let dist = (0..3).map(|k| (px[k] - x[k]).powi(2)).sum::<f64>().sqrt();
        let ang = axis_angle_error(&po, &o) * RAD2DEG;
        assert!(
            dist < 1e-3 && ang < 2.0,
            "{test}: {:.2} mm, {ang:.2} deg",
            dist * 1e3
        );
        let kinds: Vec<String> = cart
            .take_events()
            .iter()
            .map(|e| match e.checkpoint {
                Some(c) => format!("{} {c}", e.kind),
                None => e.kind.clone(),
            })
            .collect();
        assert_eq!(
            kinds.first().map(String::as_str),
            Some("motion-onset"),
            "{kinds:?}"
        );
        assert!(kinds.iter().any(|k| k == "motion-ongoing 0.5"), "{kinds:?}");
        assert_eq!(
            kinds.last().map(String::as_str),
            Some("motion-done"),
            "{kinds:?}"
        );
    }
    // out of reach: the hand ends where the solver's closest answer is, and says done
    let far = [-1.5, -0.2, 0.4];
    cart.go_to_position_sync(&far, 0.0).unwrap();
    assert!(
        cart.wait_motion_done(0.01, 10.0).unwrap(),
        "{test}: not done"
    );
    std::thread::sleep(Duration::from_millis(100));
    let des = cart.get_desired().unwrap();
    let ((px, _), _) = cart.get_pose().unwrap();
    let gap = (0..3)
        .map(|k| (px[k] - des.x[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(gap < 2e-3, "{test}: {gap} m from the solver's closest pose");
    let reach = (0..3).map(|k| (px[k] - far[k]).powi(2)).sum::<f64>().sqrt();
    assert!(reach > 0.5, "{test}: an out-of-reach target reached?");
    // a stop mid-way: done at once, and said
    let back = reachable_poses()[0];
    cart.take_events();
    cart.go_to_pose(
        &[back[0], back[1], back[2]],
        &[back[3], back[4], back[5], back[6]],
        2.0,
    )
    .unwrap();
    // events, as they come, until `kind` (at most 5 s)
    let mut kinds: Vec<String> = Vec::new();
    let mut wait_event = |cart: &mut dyn yarp_devices::cartesian_control::ICartesianControl,
                          kind: &str| {
        let until = std::time::Instant::now() + Duration::from_secs(5);
        while !kinds.iter().any(|k| k == kind) && std::time::Instant::now() < until {
            std::thread::sleep(Duration::from_millis(10));
            kinds.extend(cart.take_events().into_iter().map(|e| e.kind));
        }
        assert!(
            kinds.iter().any(|k| k == kind),
            "{test}: no {kind}: {kinds:?}"
        );
    };
    // the solver answered and the arm moves
    wait_event(&mut *cart, "motion-onset");
    std::thread::sleep(Duration::from_millis(300));
    cart.stop_control().unwrap();
    assert!(
        cart.check_motion_done().unwrap(),
        "{test}: still moving after stop"
    );
    wait_event(&mut *cart, "motion-done");
    cart.restore_context(ctx).unwrap();
    assert_eq!(cart.get_traj_time().unwrap(), 2.0);
    assert_eq!(cart.get_dof().unwrap(), vec![0, 0, 0, 1, 1, 1, 1, 1, 1, 1]);
    pd.close().unwrap();
}
