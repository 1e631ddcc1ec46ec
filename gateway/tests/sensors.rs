//! Multiple-analog-sensors streams as sensor_msgs/Imu and geometry_msgs/WrenchStamped, and
//! a YARP source that vanishes and returns, against rclpy. Domain indices: 12, 13.

mod common;

use common::{Peer, T};
use serde_json::Value as Json;
use std::time::Duration;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Stamp};

const MAS: &str = "((((0 0 90) 100.25))) ((((0.0 0.0 9.81) 100.25))) (()) ((((0 0 90) 100.25))) \
                   (()) ((((1 2 3 0.1 0.2 0.3) 100.5)))";

async fn write_until(w: &Port, b: &Bottle, peer: &Peer) -> Json {
    let line = common::repeat_until(
        "rclpy to receive",
        Duration::from_millis(50),
        async || {
            w.write(b).await;
        },
        || peer.try_line("MSG"),
    )
    .await;
    serde_json::from_str(&line).unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn imu_and_wrench_from_multiple_analog_sensors() {
    let Some(venv) = common::venv_or_skip("imu_and_wrench_from_multiple_analog_sensors") else {
        return;
    };
    let domain = common::domain_id(12);
    let (ns, stop) = common::name_server().await;
    let w = Port::open("/test/inertials/measures:o", ns.clone())
        .await
        .unwrap();
    let gw = common::gateway(
        r#"
[[topic]]
name = "imu"
direction = "yarp_to_ros"
yarp_port = "/gw/imu:i"
yarp_source = "/test/inertials/measures:o"
ros_topic = "/imu"
ros_type = "sensor_msgs/msg/Imu"
frame_id = "imu_link"

[[topic]]
name = "ft"
direction = "yarp_to_ros"
yarp_port = "/gw/ft:i"
yarp_source = "/test/inertials/measures:o"
ros_topic = "/wrench"
ros_type = "geometry_msgs/msg/WrenchStamped"
frame_id = "ft_link"
qos = { reliability = "best_effort", depth = 5 }
"#,
        &ns,
        domain,
    )
    .await;
    let imu = Peer::start(&venv, domain, &["sub", "sensor_msgs/msg/Imu", "/imu"]);
    let ft = Peer::start(
        &venv,
        domain,
        &[
            "sub",
            "geometry_msgs/msg/WrenchStamped",
            "/wrench",
            "--best-effort",
        ],
    );
    imu.expect_async("READY", T).await;
    ft.expect_async("READY", T).await;
    let b = Bottle::from_text(MAS);
    let m = write_until(&w, &b, &imu).await;
    assert_eq!(m["header"]["frame_id"], "imu_link");
    assert_eq!(m["header"]["stamp"]["sec"], 100);
    assert_eq!(m["header"]["stamp"]["nanosec"], 250_000_000);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        (m["orientation"]["z"].as_f64().unwrap() - h).abs() < 1e-9,
        "{m}"
    );
    let wz = m["angular_velocity"]["z"].as_f64().unwrap();
    assert!((wz - std::f64::consts::FRAC_PI_2).abs() < 1e-9, "{m}");
    assert_eq!(m["linear_acceleration"]["z"], 9.81);
    let m = write_until(&w, &b, &ft).await;
    assert_eq!(m["header"]["frame_id"], "ft_link");
    assert_eq!(m["header"]["stamp"]["sec"], 100);
    assert_eq!(m["wrench"]["force"]["y"], 2.0);
    assert_eq!(m["wrench"]["torque"]["z"], 0.3);
    gw.shutdown().await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_yarp_source_that_vanishes_and_returns_is_reconnected() {
    let Some(venv) = common::venv_or_skip("a_yarp_source_that_vanishes_and_returns_is_reconnected")
    else {
        return;
    };
    let domain = common::domain_id(13);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "counter"
direction = "yarp_to_ros"
yarp_port = "/gw/counter:i"
yarp_source = "/test/counter:o"
ros_topic = "/counter"
ros_type = "std_msgs/msg/Int32"
"#,
        &ns,
        domain,
    )
    .await;
    let sub = Peer::start(
        &venv,
        domain,
        &["sub", "std_msgs/msg/Int32", "/counter", "--count", "1000"],
    );
    sub.expect_async("READY", T).await;
    // The source starts after the gateway, and the envelope travels along.
    let w = Port::open("/test/counter:o", ns.clone()).await.unwrap();
    let m = write_until(&w, &Bottle::from_text("1"), &sub).await;
    assert_eq!(m["data"], 1);
    w.close().await;
    // A new process with the same port name: the gateway connects again.
    let w = Port::open("/test/counter:o", ns.clone()).await.unwrap();
    while sub.try_line("MSG").is_some() {}
    let got = common::repeat_until(
        "the restarted source to reach ROS",
        Duration::from_millis(50),
        async || {
            w.write_stamped(&Bottle::from_text("2"), Stamp::new(1, 5.0))
                .await;
        },
        || sub.try_line("MSG").filter(|l| l.contains('2')),
    )
    .await;
    assert_eq!(got, r#"{"data": 2}"#);
    w.close().await;
    gw.shutdown().await;
    stop.shutdown();
}
