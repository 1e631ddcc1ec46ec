//! ROS nodes that come and go leave nothing behind in the gateway's DDS participant (run
//! under netns-run). The 30-minute soak run found the gateway growing by ~50 KB per
//! rclpy node that had come and gone: RustDDS kept every discovery announcement (and its
//! disposal) in the SEDP topic caches up to 4096 samples each, and the disposed
//! instances' metadata for ever. Domain index used here: 20.

mod common;

use common::{Peer, T};
use std::time::Duration;

const NODES: usize = 6;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn discovery_forgets_rclpy_nodes_that_left() {
    for d in common::first_distro("discovery_forgets_rclpy_nodes_that_left") {
        discovery_forgets_rclpy_nodes_that_left_on(&d).await;
    }
}

/// Samples held by the caches of the built-in discovery topics of endpoints.
fn sedp_samples(gw: &yarp_ros2_gateway::gateway::Gateway) -> usize {
    gw.dds_topic_cache_samples()
        .iter()
        .filter(|(topic, _)| topic == "DCPSPublication" || topic == "DCPSSubscription")
        .map(|(_, n)| n)
        .sum()
}

async fn discovery_forgets_rclpy_nodes_that_left_on(venv: &common::Distro) {
    let domain = venv.domain(20);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "departed"
direction = "ros_to_yarp"
yarp_port = "/gw/departed:o"
ros_topic = "/departed/text"
ros_type = "std_msgs/msg/String"
"#,
        &ns,
        domain,
    )
    .await;

    // Each rclpy node has some 15 endpoints (its topic, rosout, parameter events and
    // services): ~30 announcements to discover and ~30 disposals when it leaves.
    for i in 0..NODES {
        let venv = venv.clone();
        let ok = common::blocking(move || {
            let peer = Peer::start(
                &venv,
                domain,
                &[
                    "pub",
                    "std_msgs/msg/String",
                    "/departed/text",
                    r#"{"data": "hello"}"#,
                    "--wait-sub",
                    "--count",
                    "5",
                    "--rate",
                    "20",
                    // Long enough for the gateway to match the writer and have the
                    // samples repaired on a loaded machine (0.5 s was not, under CI).
                    "--linger",
                    "2",
                ],
            );
            peer.finish(T)
        })
        .await;
        assert!(ok, "rclpy node {i} published to the gateway and exited");
    }
    // Each node was matched: its messages reached the gateway (a reliable writer may
    // leave before the very first is repaired, so not all are counted on).
    let messages = gw.bridges()[0].counters.snapshot().messages;
    assert!(
        messages >= NODES as u64,
        "{messages} messages from {NODES} nodes of 5"
    );

    // Every announcement has been processed once the nodes were matched and gone; what
    // is left in the caches is what discovery has not taken yet.
    let left = common::repeat_until(
        "the discovery caches to forget the nodes that left",
        Duration::from_millis(200),
        async || {},
        || {
            let n = sedp_samples(&gw);
            (n <= 4).then_some(n)
        },
    )
    .await;
    assert!(
        left <= 4,
        "{left} SEDP samples kept after {NODES} nodes left"
    );

    gw.shutdown().await;
    stop.shutdown();
}
