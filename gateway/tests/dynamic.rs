//! Dynamic mode: YARP ports matching a pattern are bridged as they appear and unbridged
//! as they disappear, and ROS topics matching a pattern are mirrored into YARP ports
//! while rclpy publishes them. Domain indices: 17, 25.

mod common;

use common::{Peer, T};
use std::time::{Duration, Instant};
use yarp_net::port::Port;
use yarp_proto::Bottle;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ports_matching_a_pattern_come_and_go() {
    for d in common::distros("ports_matching_a_pattern_come_and_go") {
        ports_matching_a_pattern_come_and_go_on(&d).await;
    }
}

async fn ports_matching_a_pattern_come_and_go_on(venv: &common::Distro) {
    let domain = venv.domain(17);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "sensors"
direction = "yarp_to_ros"
yarp_pattern = "/sensors/*:o"
ros_topic = "/yarp"
ros_type = "std_msgs/msg/String"
"#,
        &ns,
        domain,
    )
    .await;
    let table = gw.table();
    assert!(
        table.contains("/sensors/*:o") && table.contains("/yarp/<port>"),
        "{table}"
    );
    // Not matched: wrong suffix.
    let _other = Port::open("/sensors/cmd:i", ns.clone()).await.unwrap();
    let a = Port::open("/sensors/temp:o", ns.clone()).await.unwrap();
    let sub = Peer::start(
        venv,
        domain,
        &["sub", "std_msgs/msg/String", "/yarp/sensors/temp_o"],
    );
    sub.expect_async("READY", T).await;
    let got = common::repeat_until(
        "the new port to be bridged",
        Duration::from_millis(100),
        async || {
            a.write(&Bottle::from_text("21.5 [C]")).await;
        },
        || sub.try_line("MSG"),
    )
    .await;
    assert_eq!(got, r#"{"data": "21.5 [C]"}"#);
    let bridged = "/yarp_ros2_gateway/sensors/sensors/temp:o";
    assert!(ns.query(bridged).await.unwrap().is_some());
    assert!(ns
        .query("/yarp_ros2_gateway/sensors/sensors/cmd:i")
        .await
        .unwrap()
        .is_none());
    // The source goes away: so does its bridge.
    a.close().await;
    let end = Instant::now() + T;
    while ns.query(bridged).await.unwrap().is_some() {
        assert!(
            Instant::now() < end,
            "bridge for a vanished port still registered"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    gw.shutdown().await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ros_topics_matching_a_pattern_are_mirrored_while_published() {
    for d in common::distros("ros_topics_matching_a_pattern_are_mirrored_while_published") {
        ros_topics_matching_a_pattern_are_mirrored_while_published_on(&d).await;
    }
}

async fn ros_topics_matching_a_pattern_are_mirrored_while_published_on(venv: &common::Distro) {
    let domain = venv.domain(25);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "sensors"
direction = "ros_to_yarp"
yarp_port = "/ros"
ros_topic = "/sensors/*"
ros_type = "std_msgs/msg/Float64"
"#,
        &ns,
        domain,
    )
    .await;
    // Three seconds of a matching topic, plus one of another type and one elsewhere.
    let float = |topic: &str, data: &str| {
        Peer::start(
            venv,
            domain,
            &[
                "pub",
                "std_msgs/msg/Float64",
                topic,
                data,
                "--count",
                "60",
                "--rate",
                "20",
            ],
        )
    };
    let temp = float("/sensors/temp_a", r#"{"data": 21.5}"#);
    let _elsewhere = float("/other/temp", r#"{"data": 1.0}"#);
    let _other_type = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "std_msgs/msg/String",
            "/sensors/label",
            r#"{"data": "x"}"#,
            "--count",
            "60",
            "--rate",
            "20",
        ],
    );
    let registered = |n: &'static str| {
        let ns = ns.clone();
        async move { ns.query(n).await.ok().flatten().is_some() }
    };
    let end = Instant::now() + T;
    while !registered("/ros/sensors/temp_a").await {
        assert!(Instant::now() < end, "/sensors/temp_a was never mirrored");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let reader = Port::open("/t25/reader:i", ns.clone()).await.unwrap();
    yarp_net::network::connect(&ns, "/ros/sensors/temp_a", "/t25/reader:i", None)
        .await
        .unwrap();
    let got = tokio::time::timeout(T, reader.read())
        .await
        .expect("a mirrored message")
        .unwrap();
    assert_eq!(got.bottle().unwrap(), Bottle::from_text("21.5"));
    assert!(!registered("/ros/other/temp").await);
    assert!(!registered("/ros/sensors/label").await);
    // The publisher ends (cleanly): the mirror goes away.
    assert!(temp.finish(T));
    let end = Instant::now() + T;
    while registered("/ros/sensors/temp_a").await {
        assert!(Instant::now() < end, "the mirror outlived its topic");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    reader.close().await;
    gw.shutdown().await;
    stop.shutdown();
}
