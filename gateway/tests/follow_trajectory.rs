//! FollowJointTrajectory, MoveIt's controller interface, served by the gateway's trajectory
//! controller (`[[action]]` with a `controller`) on a real `controlBoard_nws_yarp` serving a
//! `fakeMotionControl` arm (run under netns-run). The action client is our ROS layer: a
//! second gateway whose `yarp_to_ros` entry turns YARP calls into goals (control_msgs has no
//! wheel for rclpy; rclpy checks the action's endpoints, types and hashes). Three points
//! within tolerance with feedback and SUCCESSFUL; a point outside a joint's limits gets
//! INVALID_GOAL, an unknown joint INVALID_JOINTS; a cancel stops the arm where it is; a new
//! goal preempts the running one. Kilted's control_msgs (6.8, feedback with `index`) and
//! Jazzy's (5.8), each from its venv as a sourced ROS gives it. Domain index: 4.

mod common;

use common::{blocking, Peer, T};
use serde_json::Value as Json;
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_net::buffered::BufferedPort;
use yarp_net::network;
use yarp_proto::{Bottle, Value};
use yarp_ros2_gateway::dynmsg::Value as Ros;

const FJT: &str = "control_msgs/action/FollowJointTrajectory";
const ACTION: &str = "/arm_controller/follow_joint_trajectory";

/// A 3-axis arm `/<name>`: two revolute joints (limits -90..90 degrees) and a prismatic
/// one (0..0.5 m).
fn board(name: &str) -> PolyDriver {
    common::open_device(&format!(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname {name}\nperiod 0.01\n\
         [GENERAL]\njoints 3\nAxisName \"shoulder\" \"elbow\" \"slide\"\n\
         AxisType \"revolute\" \"revolute\" \"prismatic\"\n\
         [LIMITS]\nMin -90 -90 0\nMax 90 90 0.5\n"
    ))
}

fn encoders(d: &mut PolyDriver) -> Option<Vec<f64>> {
    d.device().as_encoders()?.get_encoders().ok()
}

fn time(s: f64) -> Ros {
    let d = Duration::from_secs_f64(s);
    Ros::Struct(vec![
        Ros::I32(d.as_secs() as i32),
        Ros::U32(d.subsec_nanos()),
    ])
}

/// A goal in the generic Bottle layout the `yarp_to_ros` entry takes: `points` are
/// (positions, seconds from start).
fn goal(names: &[&str], points: &[(&[f64], f64)], goal_time: f64) -> String {
    let ty = yarp_ros2_gateway::types::lookup(&format!("{FJT}_Goal")).expect("goal type");
    let mut g = Ros::zero(ty.name).unwrap();
    let Ros::Struct(f) = &mut g else { panic!() };
    let Ros::Struct(t) = &mut f[0] else { panic!() };
    t[1] = Ros::List(names.iter().map(|n| Ros::Str(n.to_string())).collect());
    t[2] = Ros::List(
        points
            .iter()
            .map(|(p, at)| {
                let f64s = |v: &[f64]| Ros::List(v.iter().map(|x| Ros::F64(*x)).collect());
                Ros::Struct(vec![f64s(p), f64s(&[]), f64s(&[]), f64s(&[]), time(*at)])
            })
            .collect(),
    );
    f[6] = time(goal_time);
    yarp_ros2_gateway::generic::to_yarp(ty, &g)
        .unwrap()
        .to_string()
}

/// Calls the caller gateway's port until the action server answers.
async fn call(ns: &yarp_net::nameserver::NameClient, me: &str, cmd: &str) -> Bottle {
    let unanswered = "no action server answered";
    common::rpc_until_answered(ns, "/gw/t4/fjt:rpc", me, cmd, unanswered, 3 * T).await
}

/// `(error_code error_string)`, or `[fail] how error_code error_string`.
fn result(b: &Bottle) -> (Option<String>, i64, String) {
    let items: Vec<&Value> = b.iter().collect();
    let (how, rest) = match items.first() {
        Some(Value::Vocab32(v)) if v.as_string() == "fail" => (
            items.get(1).and_then(|v| v.as_str()).map(String::from),
            &items[2..],
        ),
        _ => (None, &items[..]),
    };
    let code = rest.first().and_then(|v| v.as_i64()).unwrap_or(i64::MIN);
    let text = rest
        .get(1)
        .and_then(|v| v.as_str())
        .unwrap_or("")
        .to_string();
    (how, code, text)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn follow_joint_trajectory_moves_the_arm_within_tolerance() {
    for d in common::distros("follow_joint_trajectory_moves_the_arm_within_tolerance") {
        follow_joint_trajectory_moves_the_arm_within_tolerance_on(&d).await;
    }
}

async fn follow_joint_trajectory_moves_the_arm_within_tolerance_on(venv: &common::Distro) {
    let ns = common::device_name_server();
    let domain = venv.domain(4);
    let _server = blocking(|| board("/t4/arm")).await;
    let check = blocking(|| {
        common::open_device(
            "device remote_controlboard\nremote /t4/arm\nlocal /t4/check\ncarrier tcp\n",
        )
    })
    .await;
    let controller = common::gateway(
        &(venv.interfaces_line()
            + r#"
[[action]]
name = "arm_controller"
direction = "ros_to_yarp"
yarp_port = "/gw/t4/controller"
ros_action = "/arm_controller/follow_joint_trajectory"
ros_type = "control_msgs/action/FollowJointTrajectory"
controller = { boards = ["/t4/arm"], goal_tolerance = 0.01, goal_time = 2.0, rate_hz = 20 }
"#),
        &ns,
        domain,
    )
    .await;
    let caller = common::gateway(
        &(venv.interfaces_line()
            + r#"
[[action]]
name = "fjt_caller"
direction = "yarp_to_ros"
yarp_port = "/gw/t4/fjt:rpc"
ros_action = "/arm_controller/follow_joint_trajectory"
ros_type = "control_msgs/action/FollowJointTrajectory"
yarp_feedback = "/gw/t4/fjt/feedback:o"
"#),
        &ns,
        domain,
    )
    .await;
    let feedback = BufferedPort::open("/t4/feedback:i", ns.clone())
        .await
        .unwrap();
    feedback.set_strict(true);
    network::connect(&ns, "/gw/t4/fjt/feedback:o", "/t4/feedback:i", None)
        .await
        .unwrap();

    // rclpy sees the action's endpoints with control_msgs' types and hashes (the
    // release of its distro: the venv's control_msgs is the one the gateway reads).
    let info = Peer::start(
        venv,
        domain,
        &[
            "info_many",
            &format!("{ACTION}/_action/feedback"),
            &format!("{ACTION}/_action/status"),
            "--timeout",
            "20",
        ],
    );
    let found: Json = serde_json::from_str(&info.expect_async("INFO", T).await).unwrap();
    let fb = &found[format!("{ACTION}/_action/feedback")];
    let want_hash = rosidl_hash(venv, "FollowJointTrajectory_FeedbackMessage");
    assert!(
        fb.as_array().unwrap().iter().any(|e| e["kind"] == "pub"
            && e["type"] == format!("{FJT}_FeedbackMessage")
            && e["hash"] == want_hash),
        "{found}"
    );
    let status = &found[format!("{ACTION}/_action/status")][0];
    assert_eq!(status["durability"], "TRANSIENT_LOCAL", "{found}");

    // Three points, joints named in another order than the board's, the prismatic one left
    // out: SUCCESSFUL, the arm at the last point, feedback on the way.
    let t0 = Instant::now();
    let r = call(
        &ns,
        "/t4/a",
        &goal(
            &["elbow", "shoulder"],
            &[(&[0.2, 0.1], 0.5), (&[0.4, -0.2], 1.0), (&[0.6, 0.3], 1.5)],
            0.0,
        ),
    )
    .await;
    let took = t0.elapsed();
    assert_eq!(
        result(&r),
        (None, 0, "Goal successfully reached!".into()),
        "{r}"
    );
    assert!(took >= Duration::from_millis(1400), "done after {took:?}");
    let (check, q) = blocking(move || {
        let mut check = check;
        let q = encoders(&mut check).unwrap();
        (check, q)
    })
    .await;
    assert!(
        (q[0] - 0.3f64.to_degrees()).abs() < 0.01f64.to_degrees(),
        "{q:?}"
    );
    assert!(
        (q[1] - 0.6f64.to_degrees()).abs() < 0.01f64.to_degrees(),
        "{q:?}"
    );
    assert_eq!(q[2], 0.0, "the slide was not commanded");
    // (header joint_names desired actual error [index] ...): a feedback of this goal
    let mut seen = 0;
    while let Ok(Some(m)) = tokio::time::timeout(Duration::from_millis(200), feedback.read()).await
    {
        let b = &m.bottle;
        let names = b.get(1).and_then(Value::as_list).unwrap();
        let names: Vec<&str> = names.iter().filter_map(Value::as_str).collect();
        assert_eq!(names, ["elbow", "shoulder"], "{b}");
        let desired = b.get(2).and_then(Value::as_list).unwrap();
        assert_eq!(
            desired.get(0).and_then(Value::as_list).unwrap().len(),
            2,
            "{b}"
        );
        seen += 1;
    }
    assert!(
        seen >= 10,
        "{seen} feedback messages for a 1.5 s goal at 20 Hz"
    );

    // A point outside the elbow's limits (-90..90 degrees): INVALID_GOAL, nothing moves.
    let r = call(&ns, "/t4/b", &goal(&["elbow"], &[(&[2.0], 1.0)], 0.0)).await;
    let (how, code, text) = result(&r);
    assert_eq!((how.as_deref(), code), (Some("aborted"), -1), "{r}");
    assert!(text.contains("outside its limits"), "{r}");
    // A joint the controller does not have: INVALID_JOINTS.
    let r = call(&ns, "/t4/c", &goal(&["wrist"], &[(&[0.0], 1.0)], 0.0)).await;
    assert_eq!(result(&r).1, -2, "{r}");

    // A long goal, canceled by `[stop]` 0.6 s in: CANCELED, and the arm stops short.
    let long = tokio::spawn({
        let ns = ns.clone();
        let g = goal(&["shoulder"], &[(&[-1.2], 6.0)], 0.0);
        async move { call(&ns, "/t4/d", &g).await }
    });
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let stop = common::rpc_until_answered(&ns, "/gw/t4/fjt:rpc", "/t4/e", "[stop]", "-", T).await;
    assert_eq!(stop.to_string(), "[ok] 1");
    let r = tokio::time::timeout(T, long).await.unwrap().unwrap();
    assert_eq!(result(&r).0.as_deref(), Some("canceled"), "{r}");
    let (mut check, q1) = blocking(move || {
        let mut check = check;
        std::thread::sleep(Duration::from_millis(300));
        let q = encoders(&mut check).unwrap();
        (check, q)
    })
    .await;
    assert!(
        q1[0] > -1.2f64.to_degrees() + 20.0 && q1[0] < 0.3f64.to_degrees(),
        "stopped on the way: {q1:?}"
    );
    let q2 = blocking(move || {
        std::thread::sleep(Duration::from_millis(500));
        encoders(&mut check).unwrap()
    })
    .await;
    assert!((q2[0] - q1[0]).abs() < 0.5, "still: {q1:?} then {q2:?}");

    // A new goal preempts a running one: the first ends CANCELED (INVALID_GOAL, as
    // joint_trajectory_controller says), the second succeeds.
    let first = tokio::spawn({
        let ns = ns.clone();
        let g = goal(&["shoulder"], &[(&[0.5], 4.0)], 0.0);
        async move { call(&ns, "/t4/f", &g).await }
    });
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let r = call(&ns, "/t4/g", &goal(&["shoulder"], &[(&[0.0], 1.0)], 0.0)).await;
    assert_eq!(result(&r).1, 0, "{r}");
    let r = tokio::time::timeout(T, first).await.unwrap().unwrap();
    assert_eq!(
        result(&r),
        (
            Some("canceled".into()),
            -1,
            "Current goal cancelled due to new incoming action.".into()
        ),
        "{r}"
    );
    caller.shutdown().await;
    controller.shutdown().await;
}

/// The hash rosidl gave `control_msgs/action/<name>` in the venv (its installed JSON).
fn rosidl_hash(venv: &common::Distro, name: &str) -> String {
    let file = venv.join("share/control_msgs/action/FollowJointTrajectory.json");
    let json: Json = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    json["type_hashes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|h| h["type_name"] == format!("control_msgs/action/{name}"))
        .unwrap()["hash_string"]
        .as_str()
        .unwrap()
        .to_string()
}
