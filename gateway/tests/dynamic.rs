//! Dynamic mode: YARP ports matching a pattern are bridged as they appear and unbridged
//! as they disappear, against rclpy. Domain index: 17.

mod common;

use common::{Peer, T};
use std::time::{Duration, Instant};
use yarp_net::port::Port;
use yarp_proto::Bottle;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ports_matching_a_pattern_come_and_go() {
    let Some(venv) = common::venv_or_skip("ports_matching_a_pattern_come_and_go") else {
        return;
    };
    let domain = common::domain_id(17);
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
        &venv,
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
