//! ROS -> robot: rclpy publishes Float64MultiArray, JointTrajectory and JointState
//! commands; the gateway drives a real `controlBoard_nws_yarp` serving a `fakeMotionControl`
//! through `remote_controlboard`, and the joints are checked through the encoders of a
//! second `remote_controlboard` in the test. Domain indices: 19, 20, 21 (19 also hosts
//! the position-direct entry, on its own topic).

mod common;

use common::{blocking, Peer, T};
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;

/// A 3-axis board `/<name>`: two revolute joints and a prismatic one.
fn board(name: &str) -> PolyDriver {
    common::open_device(&format!(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname {name}\nperiod 0.01\n\
         [GENERAL]\njoints 3\nAxisName \"shoulder\" \"elbow\" \"slide\"\n\
         AxisType \"revolute\" \"revolute\" \"prismatic\"\n"
    ))
}

/// A client of the board, for reading its encoders.
fn checker(remote: &str, local: &str) -> PolyDriver {
    common::open_device(&format!(
        "device remote_controlboard\nremote {remote}\nlocal {local}\ncarrier tcp\n"
    ))
}

fn encoders(d: &mut PolyDriver) -> Option<Vec<f64>> {
    d.device().as_encoders()?.get_encoders().ok()
}

/// Polls the encoders (every 10 ms, bounded by `T`) until `done` accepts them; returns
/// the checker, the accepted reading and when it was seen.
async fn wait_encoders(
    mut d: PolyDriver,
    what: &'static str,
    done: impl Fn(&[f64]) -> bool + Send + 'static,
) -> (PolyDriver, Vec<f64>, Instant) {
    blocking(move || {
        let end = Instant::now() + T;
        let mut last = None;
        while Instant::now() < end {
            if let Some(q) = encoders(&mut d) {
                if done(&q) {
                    return (d, q, Instant::now());
                }
                last = Some(q);
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        panic!("timed out waiting for {what}; last encoders {last:?}");
    })
    .await
}

fn near(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-6
}

/// Starts board, checker and gateway for one test; waits until the gateway's
/// remote_controlboard has registered its ports.
async fn setup(
    venv: &common::Distro,
    prefix: &str,
    index: u16,
    mapping: &str,
) -> (
    PolyDriver,
    PolyDriver,
    yarp_ros2_gateway::gateway::Gateway,
    u16,
) {
    let ns = common::device_name_server();
    let domain = venv.domain(index);
    let (server_name, check_name) = (format!("{prefix}/arm"), format!("{prefix}/check"));
    let server = blocking(move || board(&server_name)).await;
    let remote = format!("{prefix}/arm");
    let check = blocking(move || checker(&remote, &check_name)).await;
    let gw = common::gateway(mapping, &ns, domain).await;
    let state = format!("/gw{prefix}/stateExt:i");
    let end = Instant::now() + T;
    while ns.query(&state).await.ok().flatten().is_none() {
        assert!(Instant::now() < end, "the gateway never opened {state}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    (server, check, gw, domain)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn multi_array_positions_then_position_direct_setpoints_move_the_joints() {
    for d in common::distros("multi_array_positions_then_position_direct_setpoints_move_the_joints")
    {
        multi_array_positions_then_position_direct_setpoints_move_the_joints_on(&d).await;
    }
}

async fn multi_array_positions_then_position_direct_setpoints_move_the_joints_on(
    venv: &common::Distro,
) {
    let (_server, check, gw, domain) = setup(
        venv,
        "/t19",
        19,
        r#"
[[topic]]
name = "arm_position"
direction = "ros_to_yarp"
yarp_port = "/gw/t19"
ros_topic = "/arm/position_command"
ros_type = "std_msgs/msg/Float64MultiArray"
control_board = { remote = "/t19/arm", mode = "position" }

[[topic]]
name = "arm_direct"
direction = "ros_to_yarp"
yarp_port = "/gw/t19d"
ros_topic = "/arm/direct_command"
ros_type = "sensor_msgs/msg/JointState"
control_board = { remote = "/t19/arm", mode = "position_direct" }
"#,
    )
    .await;
    let publisher = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "std_msgs/msg/Float64MultiArray",
            "/arm/position_command",
            r#"{"data": [0.5, -0.25, 0.1]}"#,
            "--count",
            "200",
            "--rate",
            "10",
            "--wait-sub",
        ],
    );
    let want = [0.5f64.to_degrees(), -0.25f64.to_degrees(), 0.1];
    let (check, q, _) = wait_encoders(check, "the commanded positions", move |q| {
        q.iter().zip(want).all(|(a, b)| near(*a, b))
    })
    .await;
    eprintln!("encoders after Float64MultiArray: {q:?}");
    let snap = gw.bridges()[0].counters.snapshot();
    assert!(snap.messages >= 1, "{snap:?}");
    drop(publisher);
    // Position-direct setpoints by name on the same board (the elbow only).
    let _direct = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "sensor_msgs/msg/JointState",
            "/arm/direct_command",
            r#"{"name": ["elbow"], "position": [0.75]}"#,
            "--count",
            "200",
            "--rate",
            "10",
            "--wait-sub",
        ],
    );
    let (_check, q, _) = wait_encoders(check, "the position-direct setpoint", move |q| {
        near(q[1], 0.75f64.to_degrees())
    })
    .await;
    eprintln!("encoders after position-direct JointState: {q:?}");
    assert!(near(q[0], want[0]), "the shoulder kept its position: {q:?}");
    gw.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn joint_trajectory_is_followed_point_by_point() {
    for d in common::distros("joint_trajectory_is_followed_point_by_point") {
        joint_trajectory_is_followed_point_by_point_on(&d).await;
    }
}

async fn joint_trajectory_is_followed_point_by_point_on(venv: &common::Distro) {
    let (_server, check, gw, domain) = setup(
        venv,
        "/t20",
        20,
        r#"
[[topic]]
name = "arm_trajectory"
direction = "ros_to_yarp"
yarp_port = "/gw/t20"
ros_topic = "/arm/joint_trajectory"
ros_type = "trajectory_msgs/msg/JointTrajectory"
control_board = { remote = "/t20/arm", mode = "position" }
qos = { durability = "transient_local", depth = 1 }
"#,
    )
    .await;
    // Named joints in another order than the board's, a subset of the axes.
    let traj = r#"{"joint_names": ["elbow", "shoulder"], "points": [
        {"positions": [0.2, 0.4], "time_from_start": {"sec": 0, "nanosec": 600000000}},
        {"positions": [-0.2, 0.8], "time_from_start": {"sec": 1, "nanosec": 600000000}}]}"#;
    let publisher = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "trajectory_msgs/msg/JointTrajectory",
            "/arm/joint_trajectory",
            traj,
            "--transient",
            "--depth",
            "1",
            "--wait-sub",
            "--linger",
            "8",
            "--timeout",
            "10",
        ],
    );
    publisher.expect_async("SENT", T).await;
    // The publisher stays (transient_local) until the gateway's reader has matched it.
    // The shoulder moves at 0.4 rad / 0.6 s to the first point, then 0.4 rad / 1 s.
    let (check, _, t_first) = wait_encoders(check, "the first point", |q| {
        (q[0] - 0.4f64.to_degrees()).abs() < 0.5
    })
    .await;
    let (_check, q, t_last) = wait_encoders(check, "the last point", |q| {
        near(q[0], 0.8f64.to_degrees()) && near(q[1], -0.2f64.to_degrees())
    })
    .await;
    let segment = t_last - t_first;
    eprintln!("trajectory: second segment took {segment:?}; final encoders {q:?}");
    assert_eq!(q[2], 0.0, "the prismatic axis was not commanded");
    assert!(
        segment > Duration::from_millis(700) && segment < Duration::from_millis(1600),
        "the second segment lasts 1 s, measured {segment:?}"
    );
    assert_eq!(gw.bridges()[0].counters.snapshot().messages, 1);
    gw.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn joint_state_velocities_by_name_in_velocity_mode() {
    for d in common::distros("joint_state_velocities_by_name_in_velocity_mode") {
        joint_state_velocities_by_name_in_velocity_mode_on(&d).await;
    }
}

async fn joint_state_velocities_by_name_in_velocity_mode_on(venv: &common::Distro) {
    let (_server, check, gw, domain) = setup(
        venv,
        "/t21",
        21,
        r#"
[[topic]]
name = "arm_velocity"
direction = "ros_to_yarp"
yarp_port = "/gw/t21"
ros_topic = "/arm/velocity_command"
ros_type = "sensor_msgs/msg/JointState"
control_board = { remote = "/t21/arm", mode = "velocity" }
"#,
    )
    .await;
    let _pub = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "sensor_msgs/msg/JointState",
            "/arm/velocity_command",
            r#"{"name": ["slide", "elbow"], "velocity": [0.05, 0.5]}"#,
            "--count",
            "200",
            "--rate",
            "10",
            "--wait-sub",
        ],
    );
    let (check, q0, t0) = wait_encoders(check, "the joints to move", |q| q[2] > 0.0).await;
    let start = q0[2];
    let (_check, q1, t1) = wait_encoders(check, "one more second of motion", move |q| {
        q[2] > start + 0.05
    })
    .await;
    let dt = (t1 - t0).as_secs_f64();
    let (slide, elbow) = ((q1[2] - q0[2]) / dt, (q1[1] - q0[1]) / dt);
    eprintln!("velocity mode: slide {slide:.4} m/s, elbow {elbow:.2} deg/s");
    assert!((slide - 0.05).abs() < 0.01, "slide {slide} m/s");
    assert!(
        (elbow - 0.5f64.to_degrees()).abs() < 0.2 * 0.5f64.to_degrees(),
        "elbow {elbow} deg/s"
    );
    assert_eq!(q1[0], 0.0, "the shoulder was not commanded");
    gw.shutdown().await;
}
