//! ROS nodes that come and go leave nothing behind in the gateway's DDS participant (run
//! under netns-run). The 30-minute soak run found the gateway growing by ~50 KB per
//! rclpy node that had come and gone: RustDDS kept every discovery announcement (and its
//! disposal) in the SEDP topic caches up to 4096 samples each, and the disposed
//! instances' metadata for ever. Each node's messages must all arrive too: a reliable
//! publisher that matched the gateway first and left soon lost its first messages to it
//! (RustDDS asked for them only at the writer's next HEARTBEAT); and a hundred nodes that
//! each publish one message and leave 0.5 s later all get it through, on a loaded machine
//! too (RustDDS keeps DATA of writers it has not matched yet and delivers them at the
//! match). Domain index used here: 20.

mod common;

use common::{Peer, T};
use std::time::Duration;
use yarp_net::buffered::BufferedPort;

const NODES: usize = 6;
/// Messages each node publishes.
const COUNT: u64 = 5;
/// Short-lived publishers of one message each, one after the other.
const SHORT_LIVED: u64 = 100;

// One test per distro (each in its own domain): together they would near nextest's limit.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn discovery_forgets_rclpy_nodes_that_left_kilted() {
    on_distro("discovery_forgets_rclpy_nodes_that_left_kilted", "kilted").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn discovery_forgets_rclpy_nodes_that_left_jazzy() {
    on_distro("discovery_forgets_rclpy_nodes_that_left_jazzy", "jazzy").await;
}

async fn on_distro(test: &str, name: &str) {
    for d in common::distros(test).into_iter().filter(|d| d.name == name) {
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

/// Waits (bounded) until the gateway's bridge has counted `want` messages; the count then.
async fn messages_reach(gw: &yarp_ros2_gateway::gateway::Gateway, what: &str, want: u64) -> u64 {
    common::repeat_until(
        &format!("{what} to reach the gateway"),
        Duration::from_millis(100),
        async || {},
        || {
            let n = gw.bridges()[0].counters.snapshot().messages;
            (n >= want).then_some(n)
        },
    )
    .await
}

/// Announcements of our own participant kept by its SPDP writer.
fn spdp_writer_samples(gw: &yarp_ros2_gateway::gateway::Gateway) -> usize {
    let counts = gw.dds_writer_samples();
    counts
        .iter()
        .find(|(topic, _)| topic == "DCPSParticipant")
        .map(|(_, n)| *n)
        .unwrap_or_else(|| panic!("no SPDP writer among {counts:?}"))
}

async fn discovery_forgets_rclpy_nodes_that_left_on(venv: &common::Distro) {
    let domain = venv.domain(20);
    let started = std::time::Instant::now();
    let (ns, stop) = common::name_server().await;
    // What arrives, kept in order: a lost short-lived message is then named.
    let sink = BufferedPort::open("/test/departed:i", ns.clone())
        .await
        .unwrap();
    sink.set_strict(true);
    let gw = common::gateway(
        r#"
[[topic]]
name = "departed"
direction = "ros_to_yarp"
yarp_port = "/gw/departed:o"
yarp_sink = "/test/departed:i"
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
                    &COUNT.to_string(),
                    "--rate",
                    "20",
                    "--linger",
                    "2",
                ],
            );
            peer.finish(T)
        })
        .await;
        assert!(ok, "rclpy node {i} published to the gateway and exited");
        // Every message of every node arrives, though the node has matched the gateway's
        // reader before the gateway matched its writer, so its first messages were
        // dropped and are repaired: it leaves 2 s later, before Fast DDS's periodic
        // HEARTBEAT (3 s) would have offered them again.
        let want = (i as u64 + 1) * COUNT;
        let got = messages_reach(&gw, "the node's messages", want).await;
        assert_eq!(got, want, "messages from {} nodes of {COUNT}", i + 1);
    }

    // A hundred short-lived nodes, one after the other (each its own participant): each
    // publishes one message once its writer has matched the gateway's reader and leaves
    // 0.5 s later. Every message arrives, once.
    let before = gw.bridges()[0].counters.snapshot().messages;
    let shots = common::blocking({
        let venv = venv.clone();
        move || {
            let peer = Peer::start(
                &venv,
                domain,
                &[
                    "oneshot",
                    "std_msgs/msg/String",
                    "/departed/text",
                    r#"{"data": "shot {i}"}"#,
                    "--count",
                    &SHORT_LIVED.to_string(),
                    "--linger",
                    "0.5",
                    "--timeout",
                    "300",
                ],
            );
            peer.finish(Duration::from_secs(300))
        }
    })
    .await;
    assert!(shots, "the short-lived rclpy nodes published and left");
    let mut arrived = Vec::new();
    let end = std::time::Instant::now() + T;
    while arrived.len() < SHORT_LIVED as usize && std::time::Instant::now() < end {
        match tokio::time::timeout(Duration::from_millis(200), sink.read()).await {
            Ok(Some(m)) => {
                // A String's text reads as a Bottle: "shot 7" is (shot 7).
                let text = m.bottle.to_string();
                if let Some(i) = text
                    .strip_prefix("shot ")
                    .and_then(|n| n.parse::<u64>().ok())
                {
                    arrived.push(i);
                }
            }
            Ok(None) => panic!("the test's reader closed"),
            Err(_) => {}
        }
    }
    let missing: Vec<u64> = (0..SHORT_LIVED).filter(|i| !arrived.contains(i)).collect();
    assert!(
        missing.is_empty() && arrived.len() == SHORT_LIVED as usize,
        "messages from {SHORT_LIVED} short-lived publishers: {} arrived, missing {missing:?}",
        arrived.len()
    );
    let got = messages_reach(&gw, "the short-lived nodes' messages", before + SHORT_LIVED).await;
    assert_eq!(got - before, SHORT_LIVED, "messages counted by the bridge");

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

    // Our own participant announcement (SPDP) is written again for every node that
    // appears, to speed its discovery, and every 10 s. Its writer is best-effort with
    // History depth 8: RustDDS 0.15.1 kept every announcement, for hours, as no
    // best-effort reader ever acknowledges one. Writers are cleaned every 6 s. By 30 s
    // after the start there were at least 1 + NODES + 2 announcements (9, over the depth).
    tokio::time::sleep(Duration::from_secs(30).saturating_sub(started.elapsed())).await;
    let spdp = common::repeat_until(
        "the SPDP writer to keep its History depth (8) only",
        Duration::from_millis(500),
        async || {},
        || {
            let n = spdp_writer_samples(&gw);
            (n <= 8).then_some(n)
        },
    )
    .await;
    assert!(spdp <= 8, "the SPDP writer keeps {spdp} announcements");

    gw.shutdown().await;
    stop.shutdown();
}
