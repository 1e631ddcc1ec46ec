//! Topic bridges against real rclpy peers over real YARP ports (run under netns-run).
//! Domain indices used here: 2, 3, 16.

mod common;

use common::{Peer, T};
use serde_json::{json, Value as Json};
use std::time::Duration;
use yarp_net::buffered::BufferedPort;
use yarp_net::port::Port;
use yarp_proto::Bottle;

async fn read(p: &BufferedPort) -> Bottle {
    tokio::time::timeout(T, p.read())
        .await
        .expect("a Bottle from the gateway in time")
        .expect("port open")
        .bottle
}

fn json_line(s: &str) -> Json {
    serde_json::from_str(s).unwrap_or_else(|e| panic!("bad JSON from peer `{s}`: {e}"))
}

/// Writes `b` on `w` until the peer prints a MSG line; returns it as JSON.
async fn write_until_received(w: &Port, b: &Bottle, peer: &Peer) -> Json {
    let line = common::repeat_until(
        "rclpy to receive",
        Duration::from_millis(50),
        async || {
            w.write(b).await;
        },
        || peer.try_line("MSG"),
    )
    .await;
    json_line(&line)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn yarp_bottles_reach_rclpy_subscribers() {
    for d in common::distros("yarp_bottles_reach_rclpy_subscribers") {
        yarp_bottles_reach_rclpy_subscribers_on(&d).await;
    }
}

async fn yarp_bottles_reach_rclpy_subscribers_on(venv: &common::Distro) {
    let domain = venv.domain(2);
    let (ns, stop) = common::name_server().await;
    let w_text = Port::open("/test/text:o", ns.clone()).await.unwrap();
    let w_int = Port::open("/test/int:o", ns.clone()).await.unwrap();
    let w_arr = Port::open("/test/array:o", ns.clone()).await.unwrap();
    let w_twist = Port::open("/test/twist:o", ns.clone()).await.unwrap();
    let gw = common::gateway(
        r#"
[[topic]]
name = "text"
direction = "yarp_to_ros"
yarp_port = "/gw/text:i"
yarp_source = "/test/text:o"
ros_topic = "/yarp/text"
ros_type = "std_msgs/msg/String"

[[topic]]
name = "int"
direction = "yarp_to_ros"
yarp_port = "/gw/int:i"
yarp_source = "/test/int:o"
ros_topic = "/yarp/int"
ros_type = "std_msgs/msg/Int64"

[[topic]]
name = "array"
direction = "yarp_to_ros"
yarp_port = "/gw/array:i"
yarp_source = "/test/array:o"
ros_topic = "/yarp/array"
ros_type = "std_msgs/msg/Float64MultiArray"

[[topic]]
name = "twist"
direction = "yarp_to_ros"
yarp_port = "/gw/twist:i"
yarp_source = "/test/twist:o"
ros_topic = "/yarp/twist"
ros_type = "geometry_msgs/msg/Twist"
"#,
        &ns,
        domain,
    )
    .await;
    eprintln!("{}", gw.table());
    let subs = [
        ("std_msgs/msg/String", "/yarp/text"),
        ("std_msgs/msg/Int64", "/yarp/int"),
        ("std_msgs/msg/Float64MultiArray", "/yarp/array"),
        ("geometry_msgs/msg/Twist", "/yarp/twist"),
    ]
    .map(|(ty, topic)| Peer::start(venv, domain, &["sub", ty, topic]));
    for p in &subs {
        p.expect_async("READY", T).await;
    }

    let got = write_until_received(
        &w_text,
        &Bottle::from_text("[set] [pos] 0 1.5 \"a b\""),
        &subs[0],
    )
    .await;
    assert_eq!(got, json!({"data": "[set] [pos] 0 1.5 \"a b\""}));

    let got = write_until_received(&w_int, &Bottle::from_text("-7000000000"), &subs[1]).await;
    assert_eq!(got, json!({"data": -7000000000i64}));

    let got = write_until_received(&w_arr, &Bottle::from_text("(1 2 3) (4 5 6)"), &subs[2]).await;
    assert_eq!(got["data"], json!([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
    assert_eq!(
        got["layout"]["dim"],
        json!([{"label": "rows", "size": 2, "stride": 6}, {"label": "cols", "size": 3, "stride": 3}])
    );

    let got =
        write_until_received(&w_twist, &Bottle::from_text("0.5 0 0 0 0 -0.25"), &subs[3]).await;
    assert_eq!(
        got,
        json!({"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": -0.25}})
    );

    for p in subs {
        assert!(p.finish(T), "peer exits cleanly");
    }
    let counts: Vec<u64> = gw
        .bridges()
        .iter()
        .map(|b| b.counters.snapshot().messages)
        .collect();
    assert!(counts.iter().all(|&n| n >= 1), "{counts:?}");
    gw.shutdown().await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rclpy_messages_reach_yarp_readers() {
    for d in common::distros("rclpy_messages_reach_yarp_readers") {
        rclpy_messages_reach_yarp_readers_on(&d).await;
    }
}

async fn rclpy_messages_reach_yarp_readers_on(venv: &common::Distro) {
    let domain = venv.domain(3);
    let (ns, stop) = common::name_server().await;
    let r_twist = BufferedPort::open("/test/cmd_vel:i", ns.clone())
        .await
        .unwrap();
    let r_bool = BufferedPort::open("/test/flag:i", ns.clone())
        .await
        .unwrap();
    let r_text = BufferedPort::open("/test/chatter:i", ns.clone())
        .await
        .unwrap();
    let gw = common::gateway(
        r#"
[[topic]]
name = "cmd_vel"
direction = "ros_to_yarp"
yarp_port = "/gw/cmd_vel:o"
yarp_sink = "/test/cmd_vel:i"
ros_topic = "/cmd_vel"
ros_type = "geometry_msgs/msg/Twist"

[[topic]]
name = "flag"
direction = "ros_to_yarp"
yarp_port = "/gw/flag:o"
yarp_sink = "/test/flag:i"
ros_topic = "/flag"
ros_type = "std_msgs/msg/Bool"

[[topic]]
name = "chatter"
direction = "ros_to_yarp"
yarp_port = "/gw/chatter:o"
yarp_sink = "/test/chatter:i"
ros_topic = "/chatter"
ros_type = "std_msgs/msg/String"
qos = { reliability = "best_effort", depth = 1 }
"#,
        &ns,
        domain,
    )
    .await;
    let args = |ty: &'static str, topic: &'static str, msg: &'static str| {
        ["pub", ty, topic, msg, "--count", "400", "--rate", "20"]
    };
    let pubs = [
        args(
            "geometry_msgs/msg/Twist",
            "/cmd_vel",
            r#"{"linear": {"x": 0.5}, "angular": {"z": -0.25}}"#,
        ),
        args("std_msgs/msg/Bool", "/flag", r#"{"data": true}"#),
        args(
            "std_msgs/msg/String",
            "/chatter",
            r#"{"data": "[hello] (1 2) \"x y\""}"#,
        ),
    ]
    .map(|a| Peer::start(venv, domain, &a));
    assert_eq!(
        read(&r_twist).await,
        Bottle::from_text("0.5 0.0 0.0 0.0 0.0 -0.25")
    );
    assert_eq!(
        read(&r_bool).await.get(0).and_then(|v| v.as_bool()),
        Some(true)
    );
    assert_eq!(
        read(&r_text).await,
        Bottle::from_text("[hello] (1 2) \"x y\"")
    );
    drop(pubs); // killed and reaped
    gw.shutdown().await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_start_that_cannot_complete_is_an_error_and_leaves_nothing_behind() {
    let (ns, stop) = common::name_server().await;
    let mut m = yarp_ros2_gateway::mapping::Mappings::parse(
        r#"
[[topic]]
name = "ok"
direction = "yarp_to_ros"
yarp_port = "/gw/ok:i"
ros_topic = "/ok"
ros_type = "std_msgs/msg/Int32"

[[topic]]
name = "broken"
direction = "yarp_to_ros"
yarp_port = "/gw/broken:i"
ros_topic = "/broken"
ros_type = "std_msgs/msg/String"
"#,
        std::path::Path::new("t.toml"),
    )
    .unwrap();
    // A name the loader would refuse, so that the second entry fails inside ROS.
    m.topics[1].ros_topic = "/bro__ken".into();
    let opt = yarp_ros2_gateway::gateway::Options {
        domain_id: common::domain_id(16),
        networks: vec!["127.0.0.1".parse().unwrap()],
        ..Default::default()
    };
    let err = match yarp_ros2_gateway::gateway::Gateway::start(&m, ns.clone(), opt).await {
        Err(e) => e,
        Ok(_) => panic!("an invalid ROS name must fail the start"),
    };
    assert!(err.to_string().contains("bro__ken"), "{err}");
    // The first entry's port was opened; after the failed start nothing listens on it
    // any more (its tasks are aborted and the port dropped).
    tokio::time::sleep(Duration::from_millis(100)).await;
    let w = Port::open("/test/probe:o", ns.clone()).await.unwrap();
    assert!(
        w.connect("/gw/ok:i", None).await.is_err(),
        "no listener left behind"
    );
    stop.shutdown();
}
