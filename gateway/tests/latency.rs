//! Latency of the gateway against a direct rclpy hop (a measurement, not a pass/fail
//! check: run with `--ignored --nocapture` under netns-run). Domain indices: 10, 11.
//!
//! * direct: rclpy ping -> rclpy echo -> rclpy ping (String, 100 Hz).
//! * gateway: YARP writer -> gateway -> rclpy echo -> gateway -> YARP reader (String,
//!   100 Hz); the difference to the direct round trip is what two gateway crossings (and
//!   two YARP hops) add.

mod common;

use common::{Peer, T};
use std::time::{Duration, Instant};
use yarp_net::buffered::BufferedPort;
use yarp_net::port::Port;
use yarp_proto::Bottle;

const N: usize = 500;

fn pct(v: &mut [f64], p: usize) -> f64 {
    assert!(!v.is_empty(), "no sample came back");
    v.sort_by(f64::total_cmp);
    v[(v.len() * p / 100).min(v.len() - 1)]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "measurement; run explicitly"]
async fn string_round_trip_latency() {
    for d in common::first_distro("string_round_trip_latency") {
        string_round_trip_latency_on(&d).await;
    }
}

async fn string_round_trip_latency_on(venv: &common::Distro) {
    // Direct rclpy <-> rclpy.
    let d = venv.domain(10);
    let echo = Peer::start(
        venv,
        d,
        &[
            "echo",
            "std_msgs/msg/String",
            "/ping",
            "/pong",
            "--count",
            "100000",
            "--timeout",
            "60",
        ],
    );
    echo.expect_async("READY", T).await;
    let ping = Peer::start(
        venv,
        d,
        &[
            "ping",
            "/ping",
            "/pong",
            "--count",
            &N.to_string(),
            "--rate",
            "100",
            "--timeout",
            "60",
        ],
    );
    let direct = ping.expect_async("RTT", Duration::from_secs(60)).await;
    drop((ping, echo));
    eprintln!("direct rclpy round trip: {direct}");

    // Through the gateway.
    let d = venv.domain(11);
    let (ns, stop) = common::name_server().await;
    let w = Port::open("/lat/ping:o", ns.clone()).await.unwrap();
    let r = BufferedPort::open("/lat/pong:i", ns.clone()).await.unwrap();
    r.set_strict(true);
    let gw = common::gateway(
        r#"
[[topic]]
name = "ping"
direction = "yarp_to_ros"
yarp_port = "/gw/ping:i"
yarp_source = "/lat/ping:o"
ros_topic = "/ping"
ros_type = "std_msgs/msg/String"

[[topic]]
name = "pong"
direction = "ros_to_yarp"
yarp_port = "/gw/pong:o"
yarp_sink = "/lat/pong:i"
ros_topic = "/pong"
ros_type = "std_msgs/msg/String"
"#,
        &ns,
        d,
    )
    .await;
    let echo = Peer::start(
        venv,
        d,
        &[
            "echo",
            "std_msgs/msg/String",
            "/ping",
            "/pong",
            "--count",
            "100000",
            "--timeout",
            "60",
        ],
    );
    echo.expect_async("READY", T).await;
    // Warm up until the loop closes.
    common::repeat_until(
        "the loop to close",
        Duration::from_millis(100),
        async || {
            w.write(&Bottle::from_text("warm")).await;
        },
        || r.try_read(),
    )
    .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    while r.try_read().is_some() {}
    let mut rtts = Vec::with_capacity(N);
    let mut lost = 0;
    let mut tick = tokio::time::interval(Duration::from_millis(10));
    for i in 0..N {
        tick.tick().await;
        let t0 = Instant::now();
        w.write(&Bottle::from_text(format!("\"{i}\""))).await;
        match tokio::time::timeout(Duration::from_millis(200), r.read()).await {
            Ok(Some(m)) if m.bottle.get(0).and_then(|v| v.as_str()) == Some(&i.to_string()) => {
                rtts.push(t0.elapsed().as_secs_f64() * 1e3)
            }
            _ => lost += 1,
        }
    }
    let n = rtts.len();
    let (p50, p99) = (pct(&mut rtts, 50), pct(&mut rtts, 99));
    let inside: Vec<String> = gw
        .bridges()
        .iter()
        .map(|b| {
            let s = b.counters.snapshot();
            format!(
                "{} mean {:?} max {:?}",
                b.name, s.latency_mean, s.latency_max
            )
        })
        .collect();
    eprintln!(
        "gateway round trip: {{\"n\": {n}, \"lost\": {lost}, \"p50_ms\": {p50:.3}, \"p99_ms\": {p99:.3}}}; inside the gateway: {}",
        inside.join("; ")
    );
    drop(echo);
    gw.shutdown().await;
    stop.shutdown();
}
