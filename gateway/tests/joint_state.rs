//! A control board's `state:o` as sensor_msgs/JointState, names asked over its `rpc:i`
//! (here a stand-in that answers like controlBoard_nws_yarp), against rclpy.
//! Domain index: 14.

mod common;

use common::{Peer, T};
use serde_json::Value as Json;
use std::time::Duration;
use yarp_net::buffered::RpcServer;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Stamp};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn control_board_state_becomes_joint_state() {
    let Some(venv) = common::venv_or_skip("control_board_state_becomes_joint_state") else {
        return;
    };
    let domain = common::domain_id(14);
    let (ns, stop) = common::name_server().await;
    let state = Port::open("/test/left_arm/state:o", ns.clone())
        .await
        .unwrap();
    let rpc = RpcServer::open("/test/left_arm/rpc:i", ns.clone())
        .await
        .unwrap();
    let serving = tokio::spawn(async move {
        rpc.serve(|cmd| {
            let names = ["l_shoulder_pitch", "l_shoulder_roll", "l_elbow"];
            match cmd.to_string().as_str() {
                "[get] [axes]" => Bottle::from_text("[is] [axes] 3 [ok]"),
                s => match s
                    .strip_prefix("[get] [name] ")
                    .and_then(|j| j.parse::<usize>().ok())
                {
                    Some(j) if j < 3 => {
                        Bottle::from_text(format!("[is] [name] \"{}\" [ok]", names[j]))
                    }
                    _ => Bottle::from_text("[fail]"),
                },
            }
        })
        .await
    });
    let gw = common::gateway(
        r#"
[[topic]]
name = "left_arm"
direction = "yarp_to_ros"
yarp_port = "/gw/left_arm/state:i"
yarp_source = "/test/left_arm/state:o"
ros_topic = "/left_arm/joint_states"
ros_type = "sensor_msgs/msg/JointState"
joint_names = { from = "axis_info", rpc_port = "/test/left_arm/rpc:i" }
"#,
        &ns,
        domain,
    )
    .await;
    let sub = Peer::start(
        &venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/JointState",
            "/left_arm/joint_states",
        ],
    );
    sub.expect_async("READY", T).await;
    let line = common::repeat_until(
        "a JointState in rclpy",
        Duration::from_millis(50),
        async || {
            let b = Bottle::from_text("10.0 -90.0 45.0");
            state.write_stamped(&b, Stamp::new(7, 1234.5)).await;
        },
        || sub.try_line("MSG"),
    )
    .await;
    let m: Json = serde_json::from_str(&line).unwrap();
    assert_eq!(
        m["name"],
        serde_json::json!(["l_shoulder_pitch", "l_shoulder_roll", "l_elbow"])
    );
    let pos: Vec<f64> = m["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let want = [10.0f64, -90.0, 45.0].map(f64::to_radians);
    assert!(
        pos.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12),
        "{pos:?}"
    );
    assert_eq!(m["header"]["stamp"]["sec"], 1234);
    assert_eq!(m["header"]["stamp"]["nanosec"], 500_000_000);
    gw.shutdown().await;
    serving.abort();
    stop.shutdown();
}
