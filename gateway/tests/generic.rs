//! The generic conversion against rclpy, with types that are not in the gateway's
//! built-in catalog and that it reads from their definitions in the rclpy venv
//! (`<venv>/share/<pkg>/msg`, named by the mapping's `interfaces`): nav_msgs/Odometry
//! from rclpy to `yarp read` (ours and C++'s), a Bottle to rclpy as
//! visualization_msgs/Marker with rosidl's type hash, and a ROS-topic pattern without
//! `ros_type` mirroring topics of two types at once, YARP ports matching a pattern
//! published as such a type. Domain indices: 26, 27, 28, 29.

mod common;

use common::{Peer, T};
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};
use yarp_net::port::Port;
use yarp_proto::{Bottle, Value};

/// The workspace's `yarp` program (same target directory), or `None` after a notice.
fn our_yarp() -> Option<PathBuf> {
    let p = std::env::current_exe()
        .ok()?
        .parent()?
        .parent()?
        .join("yarp");
    if p.is_file() {
        return Some(p);
    }
    yarp_interop_tests::peer_missing(
        "rclpy_odometry_reaches_yarp_read",
        "our yarp program",
        &format!("{} not built", p.display()),
        "cargo build -p yarp-cli (same target directory)",
    );
    None
}

fn yarp_read(program: &PathBuf, port: &str) -> Peer {
    let mut cmd = Command::new(program);
    cmd.args(["read", port]);
    Peer::spawn(cmd, &format!("{} read {port}", program.display()))
}

/// The first line a `yarp read` prints that parses as an Odometry Bottle (4 items, the
/// third a pose list).
async fn odometry_line(reader: &Peer, who: &str) -> Bottle {
    let end = Instant::now() + T;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        let line = reader.expect_async("", left).await;
        let b = Bottle::from_text(&line);
        if b.len() == 4 && b.get(2).is_some_and(Value::is_list) {
            return b;
        }
        assert!(
            Instant::now() < end,
            "{who}: no Odometry line, last {line:?}"
        );
    }
}

fn numbers(v: Option<&Value>) -> Vec<f64> {
    v.and_then(Value::as_list)
        .map(|l| l.items().iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default()
}

const ODOMETRY: &str = r#"{"header": {"stamp": {"sec": 1700000000, "nanosec": 250000000}, "frame_id": "odom"},
 "child_frame_id": "base_link",
 "pose": {"pose": {"position": {"x": 1.5, "y": -2.0, "z": 0.25},
                   "orientation": {"x": 0.0, "y": 0.0, "z": 0.6, "w": 0.8}},
          "covariance": [0.1, 0, 0, 0, 0, 0, 0, 0.1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                         0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.2]},
 "twist": {"twist": {"linear": {"x": 0.3, "y": 0.0, "z": 0.0},
                     "angular": {"x": 0.0, "y": 0.0, "z": -0.1}}}}"#;

/// The pose of an Odometry Bottle: position, orientation, covariance[0].
fn pose_of(b: &Bottle) -> (Vec<f64>, Vec<f64>, f64) {
    let pwc = b.get(2).and_then(Value::as_list).expect("pose");
    let pose = pwc.get(0).and_then(Value::as_list).expect("pose.pose");
    let cov = numbers(pwc.get(1));
    assert_eq!(cov.len(), 36, "{b}");
    (numbers(pose.get(0)), numbers(pose.get(1)), cov[0])
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rclpy_odometry_reaches_yarp_read() {
    for d in common::distros("rclpy_odometry_reaches_yarp_read") {
        rclpy_odometry_reaches_yarp_read_on(&d).await;
    }
}

async fn rclpy_odometry_reaches_yarp_read_on(venv: &common::Distro) {
    let Some(ours) = our_yarp() else {
        return;
    };
    let domain = venv.domain(26);
    let ns = common::device_name_server();
    let our_reader = yarp_read(&ours, "/t26/ours");
    let cpp_reader = yarp_interop_tests::cpp_program("rclpy_odometry_reaches_yarp_read", "yarp")
        .map(|p| yarp_read(&p, "/t26/cpp"));
    let gw = common::gateway(
        &format!(
            r#"{}
[[topic]]
name = "odom"
direction = "ros_to_yarp"
yarp_port = "/gw/odom:o"
yarp_sink = "/t26/ours"
ros_topic = "/odom"
ros_type = "nav_msgs/msg/Odometry"
"#,
            venv.interfaces_line()
        ),
        &ns,
        domain,
    )
    .await;
    assert!(gw.table().contains("Generic"), "{}", gw.table());
    if cpp_reader.is_some() {
        let end = Instant::now() + T;
        while !matches!(
            yarp_net::network::connect(&ns, "/gw/odom:o", "/t26/cpp", None).await,
            Ok((true, _))
        ) {
            assert!(Instant::now() < end, "cannot connect to the C++ reader");
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    }
    let _pub = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "nav_msgs/msg/Odometry",
            "/odom",
            ODOMETRY,
            "--count",
            "400",
            "--rate",
            "20",
            "--wait-sub",
        ],
    );
    let want = (vec![1.5, -2.0, 0.25], vec![0.0, 0.0, 0.6, 0.8], 0.1);
    let b = odometry_line(&our_reader, "our yarp read").await;
    assert_eq!(pose_of(&b), want, "{b}");
    let header = b.get(0).and_then(Value::as_list).expect("header");
    assert_eq!(numbers(header.get(0)), [1_700_000_000.0, 250_000_000.0]);
    assert_eq!(header.get(1).and_then(Value::as_str), Some("odom"));
    assert_eq!(b.get(1).and_then(Value::as_str), Some("base_link"));
    if let Some(cpp) = &cpp_reader {
        let b = odometry_line(cpp, "C++ yarp read").await;
        assert_eq!(pose_of(&b), want, "{b}");
        eprintln!(
            "[{}] Odometry read by our `yarp read` and C++'s: {b}",
            venv.name
        );
    }
    gw.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bottle_reaches_rclpy_as_a_marker() {
    for d in common::distros("a_bottle_reaches_rclpy_as_a_marker") {
        a_bottle_reaches_rclpy_as_a_marker_on(&d).await;
    }
}

/// rosidl's hash of `type_name` from the venv's `share/<pkg>/<kind>/<Name>.json`.
fn rosidl_hash(venv: &common::Distro, type_name: &str) -> String {
    let (pkg, kind, name) = yarp_ros2_gateway::types::split_name(type_name).unwrap();
    let path = venv.join(format!("share/{pkg}/{kind}/{name}.json"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    json["type_hashes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|h| h["type_name"] == type_name)
        .unwrap()["hash_string"]
        .as_str()
        .unwrap()
        .to_string()
}

async fn a_bottle_reaches_rclpy_as_a_marker_on(venv: &common::Distro) {
    let domain = venv.domain(27);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        &format!(
            r#"{}
[[topic]]
name = "marker"
direction = "yarp_to_ros"
yarp_port = "/gw/marker:i"
ros_topic = "/marker"
ros_type = "visualization_msgs/msg/Marker"
frame_id = "map"
"#,
            venv.interfaces_line()
        ),
        &ns,
        domain,
    )
    .await;
    let sub = Peer::start(
        venv,
        domain,
        &["sub", "visualization_msgs/msg/Marker", "/marker"],
    );
    sub.expect_async("READY", T).await;
    let info = Peer::start(
        venv,
        domain,
        &[
            "info",
            "/marker",
            "--pubs",
            "1",
            "--named",
            "--timeout",
            "15",
        ],
    );
    // As `yarp write` would send it: header left unset (stamp from the envelope or now,
    // frame_id from the mapping), then ns id type action pose scale color lifetime
    // frame_locked points; the rest (colors, texture, text, mesh...) left out.
    let text = "((0 0) \"\") shapes 7 2 0 ((1.0 2.0 3.0) (0 0 0 1)) (0.5 0.5 0.5) \
                (1 0 0 1) (0 0) 0 ((0 0 0) (1 1 1))";
    let writer = Port::open("/t27/writer:o", ns.clone()).await.unwrap();
    writer.connect("/gw/marker:i", None).await.unwrap();
    let end = Instant::now() + T;
    let msg = loop {
        // One that does not fit (a string for the id) is dropped and counted.
        writer.write_nowait(&Bottle::from_text("() shapes seven"), None);
        writer.write_nowait(&Bottle::from_text(text), None);
        if let Some(line) = sub.try_line("MSG") {
            break line;
        }
        assert!(Instant::now() < end, "no Marker reached rclpy");
        tokio::time::sleep(Duration::from_millis(100)).await;
    };
    let m: serde_json::Value = serde_json::from_str(&msg).unwrap();
    assert_eq!(m["ns"], "shapes", "{m}");
    assert_eq!(m["id"], 7);
    assert_eq!(m["type"], 2, "SPHERE");
    assert_eq!(m["pose"]["position"]["z"], 3.0);
    assert_eq!(m["pose"]["orientation"]["w"], 1.0);
    assert_eq!(m["scale"]["x"], 0.5);
    assert_eq!(m["color"]["r"], 1.0);
    assert_eq!(m["color"]["a"], 1.0);
    assert_eq!(m["points"][1]["y"], 1.0);
    assert_eq!(m["points"].as_array().map(Vec::len), Some(2));
    assert_eq!(m["text"], "");
    assert_eq!(m["mesh_use_embedded_materials"], false);
    assert_eq!(m["header"]["frame_id"], "map");
    assert!(
        m["header"]["stamp"]["sec"].as_i64().unwrap() > 1_600_000_000,
        "{m}"
    );
    let info: serde_json::Value =
        serde_json::from_str(&info.expect_async("INFO", T).await).unwrap();
    let e = &info["pubs"][0];
    assert_eq!(e["type"], "visualization_msgs/msg/Marker", "{info}");
    let want = rosidl_hash(venv, "visualization_msgs/msg/Marker");
    let got = e["hash"].as_str().unwrap_or_default();
    assert!(
        got.contains(&want[7..]),
        "rclpy sees {got}, rosidl's is {want}"
    );
    eprintln!("[{}] Marker from a Bottle, hash {want}", venv.name);
    let counters = gw.bridges()[0].counters.snapshot();
    assert!(counters.drops > 0, "{counters:?}");
    assert!(counters.messages > 0, "{counters:?}");
    writer.close().await;
    gw.shutdown().await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_pattern_without_type_mirrors_topics_of_two_types() {
    for d in common::distros("a_pattern_without_type_mirrors_topics_of_two_types") {
        a_pattern_without_type_mirrors_topics_of_two_types_on(&d).await;
    }
}

async fn a_pattern_without_type_mirrors_topics_of_two_types_on(venv: &common::Distro) {
    let domain = venv.domain(28);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        &format!(
            r#"{}
[[topic]]
name = "mixed"
direction = "ros_to_yarp"
yarp_port = "/mirror"
ros_topic = "/mixed/*"
"#,
            venv.interfaces_line()
        ),
        &ns,
        domain,
    )
    .await;
    let publish = |ty: &str, topic: &str, json: &str| {
        Peer::start(
            venv,
            domain,
            &["pub", ty, topic, json, "--count", "400", "--rate", "20"],
        )
    };
    let _odom = publish("nav_msgs/msg/Odometry", "/mixed/odom", ODOMETRY);
    let _pose = publish(
        "geometry_msgs/msg/PoseStamped",
        "/mixed/goal",
        r#"{"header": {"stamp": {"sec": 12, "nanosec": 500000000}, "frame_id": "map"},
            "pose": {"position": {"x": 4.0, "y": 5.0, "z": 0.0},
                     "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}}"#,
    );
    let registered = |n: &'static str| {
        let ns = ns.clone();
        async move { ns.query(n).await.ok().flatten().is_some() }
    };
    let mut got = Vec::new();
    for (k, port) in ["/mirror/mixed/odom", "/mirror/mixed/goal"]
        .into_iter()
        .enumerate()
    {
        let end = Instant::now() + T;
        while !registered(port).await {
            assert!(Instant::now() < end, "{port} was never mirrored");
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        let reader = Port::open(&format!("/t28/reader{k}:i"), ns.clone())
            .await
            .unwrap();
        yarp_net::network::connect(&ns, port, reader.name(), None)
            .await
            .unwrap();
        let inc = tokio::time::timeout(T, reader.read())
            .await
            .expect("a mirrored message")
            .unwrap();
        got.push((inc.bottle().unwrap(), inc.stamp));
        reader.close().await;
    }
    let (odom, odom_stamp) = &got[0];
    assert_eq!(
        pose_of(odom),
        (vec![1.5, -2.0, 0.25], vec![0.0, 0.0, 0.6, 0.8], 0.1)
    );
    assert_eq!(odom_stamp.map(|s| s.time), Some(1_700_000_000.25));
    let (goal, goal_stamp) = &got[1];
    assert_eq!(goal.len(), 2, "{goal}");
    let pose = goal.get(1).and_then(Value::as_list).unwrap();
    assert_eq!(numbers(pose.get(0)), [4.0, 5.0, 0.0]);
    assert_eq!(goal_stamp.map(|s| s.time), Some(12.5));
    gw.shutdown().await;
    stop.shutdown();
}

/// `show-type` prints the layout of a type read from its definition (named with
/// `--interfaces`) and an example Bottle that the generic conversion takes back.
#[test]
fn show_type_prints_layout_and_example() {
    for venv in common::distros("show_type_prints_layout_and_example") {
        let out = Command::new(env!("CARGO_BIN_EXE_yarp-ros2-gateway"))
            .args(["show-type", "nav_msgs/Odometry", "--interfaces"])
            .arg(&venv.venv)
            .env_remove("AMENT_PREFIX_PATH")
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{text}");
        assert!(
            text.contains("nav_msgs/msg/Odometry (from its definition"),
            "{text}"
        );
        assert!(text.contains("covariance"), "{text}");
        let example = text.lines().last().unwrap();
        yarp_ros2_gateway::interfaces::add_dir(&venv.venv);
        let t = yarp_ros2_gateway::types::lookup("nav_msgs/msg/Odometry").unwrap();
        let m = yarp_ros2_gateway::generic::to_ros(t, &Bottle::from_text(example), 1).unwrap();
        assert!(m.conforms_to(t.name));
        let bad = Command::new(env!("CARGO_BIN_EXE_yarp-ros2-gateway"))
            .args(["show-type", "nope_msgs/msg/Nope"])
            .env_remove("AMENT_PREFIX_PATH")
            .output()
            .unwrap();
        assert!(!bad.status.success());
        assert!(String::from_utf8_lossy(&bad.stderr).contains("unknown type"));
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn yarp_ports_matching_a_pattern_publish_a_type_from_its_definition() {
    for d in common::distros("yarp_ports_matching_a_pattern_publish_a_type_from_its_definition") {
        yarp_ports_matching_a_pattern_publish_a_type_from_its_definition_on(&d).await;
    }
}

/// YARP-port pattern mode with the generic conversion: each `/goals/*:o` port becomes a
/// geometry_msgs/PoseStamped topic (not a built-in type). Domain index: 29.
async fn yarp_ports_matching_a_pattern_publish_a_type_from_its_definition_on(
    venv: &common::Distro,
) {
    let domain = venv.domain(29);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        &format!(
            r#"{}
[[topic]]
name = "goals"
direction = "yarp_to_ros"
yarp_pattern = "/goals/*:o"
ros_topic = "/yarp"
ros_type = "geometry_msgs/msg/PoseStamped"
frame_id = "map"
"#,
            venv.interfaces_line()
        ),
        &ns,
        domain,
    )
    .await;
    let a = Port::open("/goals/left:o", ns.clone()).await.unwrap();
    let sub = Peer::start(
        venv,
        domain,
        &["sub", "geometry_msgs/msg/PoseStamped", "/yarp/goals/left_o"],
    );
    sub.expect_async("READY", T).await;
    let got = common::repeat_until(
        "the port to be bridged",
        Duration::from_millis(100),
        async || {
            a.write(&Bottle::from_text("() ((0.5 -1 0) (0 0 1 0))"))
                .await;
        },
        || sub.try_line("MSG"),
    )
    .await;
    let m: serde_json::Value = serde_json::from_str(&got).unwrap();
    assert_eq!(m["pose"]["position"]["x"], 0.5, "{m}");
    assert_eq!(m["pose"]["position"]["y"], -1.0, "{m}");
    assert_eq!(m["pose"]["orientation"]["z"], 1.0, "{m}");
    assert_eq!(m["header"]["frame_id"], "map", "{m}");
    a.close().await;
    gw.shutdown().await;
    stop.shutdown();
}
