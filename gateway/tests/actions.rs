//! `[[action]]` both ways, against rclpy on `test_msgs/action/Fibonacci` (run under
//! netns-run): a ROS 2 action served by a YARP RPC port for rclpy's `ActionClient`, and a
//! YARP caller reaching rclpy's `ActionServer`: goal, feedback, result, cancel, a rejected
//! goal and an aborted one. Domain index: 8 (shared with services.rs's text RPC test; the
//! names differ).

mod common;

use common::{Peer, T};
use serde_json::{json, Value as Json};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use yarp_net::buffered::BufferedPort;
use yarp_net::network;
use yarp_net::port::Port;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Value};

fn json_line(s: &str) -> Json {
    serde_json::from_str(s).unwrap_or_else(|e| panic!("bad JSON from peer `{s}`: {e}"))
}

/// The YARP side: `fib N` computes the sequence of order N, one term every 50 ms, writing
/// the partial sequence on `/test/fib/feedback:o` and replying with the whole one; `stop`
/// ends the running goal early; `fib` of a negative order is refused.
async fn fibonacci_server(ns: yarp_net::nameserver::NameClient) -> tokio::task::JoinHandle<()> {
    let rpc = BufferedPort::open("/test/fib:i", ns.clone()).await.unwrap();
    let feedback = Arc::new(Port::open("/test/fib/feedback:o", ns).await.unwrap());
    let stop = Arc::new(AtomicBool::new(false));
    tokio::spawn(async move {
        while let Some(mut m) = rpc.read().await {
            let Some(replier) = m.take_replier() else {
                continue;
            };
            let words: Vec<Value> = m.bottle.iter().cloned().collect();
            let (feedback, stop) = (feedback.clone(), stop.clone());
            tokio::spawn(async move {
                let reply = match words.as_slice() {
                    [w] if w.as_str() == Some("stop") => {
                        stop.store(true, Ordering::SeqCst);
                        Bottle::from_text("[ok]")
                    }
                    [w, n] if w.as_str() == Some("fib") && n.as_i64().is_some_and(|n| n >= 0) => {
                        stop.store(false, Ordering::SeqCst);
                        let order = n.as_i64().unwrap_or_default() as usize;
                        let mut seq: Vec<i64> = vec![0, 1];
                        for i in 1..order {
                            if stop.load(Ordering::SeqCst) {
                                break;
                            }
                            tokio::time::sleep(Duration::from_millis(50)).await;
                            seq.push(seq[i] + seq[i - 1]);
                            feedback.write(&sequence(&seq)).await;
                        }
                        sequence(&seq)
                    }
                    _ => Bottle::from_text("[fail] \"not a goal\""),
                };
                replier.send(reply);
            });
        }
    })
}

/// `(a b c ...)`: an int32[] field, alone in its message.
fn sequence(seq: &[i64]) -> Bottle {
    let mut list = Bottle::new();
    for n in seq {
        list.push(Value::Int32(*n as i32));
    }
    let mut b = Bottle::new();
    b.push(Value::List(list));
    b
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rclpy_action_clients_reach_a_yarp_rpc_port() {
    for d in common::distros("rclpy_action_clients_reach_a_yarp_rpc_port") {
        rclpy_action_clients_reach_a_yarp_rpc_port_on(&d).await;
    }
}

async fn rclpy_action_clients_reach_a_yarp_rpc_port_on(venv: &common::Distro) {
    let domain = venv.domain(8);
    let (ns, stop) = common::name_server().await;
    let server = fibonacci_server(ns.clone()).await;
    let gw = common::gateway(
        &(venv.interfaces_line()
            + r#"
[[action]]
name = "fib"
direction = "ros_to_yarp"
yarp_port = "/test/fib:i"
ros_action = "/gw_test/fibonacci"
ros_type = "test_msgs/action/Fibonacci"
command = "fib"
cancel = "stop"
yarp_feedback = "/test/fib/feedback:o"

[[action]]
name = "nobody"
direction = "ros_to_yarp"
yarp_port = "/test/nobody:i"
ros_action = "/gw_test/nobody"
ros_type = "test_msgs/action/Fibonacci"
"#),
        &ns,
        domain,
    )
    .await;
    let client = |action: &str, goal: &str, extra: &[&str]| {
        let args = [
            &[
                "action",
                "test_msgs/action/Fibonacci",
                action,
                goal,
                "--timeout",
                "60",
            ],
            extra,
        ]
        .concat();
        Peer::start(venv, domain, &args)
    };

    // A goal: accepted, feedback while it runs, the result.
    let c = client("/gw_test/fibonacci", r#"{"order": 8}"#, &[]);
    c.expect_async("ACCEPTED", 2 * T).await;
    let fb = json_line(&c.expect_async("FEEDBACK", T).await);
    assert!(
        fb["sequence"].as_array().is_some_and(|s| s.len() >= 3),
        "{fb}"
    );
    let r = json_line(&c.expect_async("RESULT", T).await);
    assert_eq!(
        r,
        json!({"status": 4, "result": {"sequence": [0, 1, 1, 2, 3, 5, 8, 13, 21]}})
    );
    assert!(c.finish(T));

    // A long goal canceled 0.4 s after it was accepted: `stop` reaches YARP, the goal
    // ends CANCELED with what it had.
    let c = client(
        "/gw_test/fibonacci",
        r#"{"order": 40}"#,
        &["--cancel-after", "0.4"],
    );
    c.expect_async("ACCEPTED", 2 * T).await;
    let cancel = json_line(&c.expect_async("CANCEL", T).await);
    assert_eq!(cancel, json!({"return_code": 0, "canceling": 1}));
    let r = json_line(&c.expect_async("RESULT", T).await);
    assert_eq!(r["status"], 5, "{r}");
    let got = r["result"]["sequence"].as_array().map_or(0, |s| s.len());
    assert!(got > 2 && got < 41, "{r}");
    assert!(c.finish(T));

    // A goal the YARP side refuses ends ABORTED.
    let c = client("/gw_test/fibonacci", r#"{"order": -1}"#, &[]);
    c.expect_async("ACCEPTED", 2 * T).await;
    let r = json_line(&c.expect_async("RESULT", T).await);
    assert_eq!(r, json!({"status": 6, "result": {"sequence": []}}));
    assert!(c.finish(T));

    // Nobody to run it: rejected.
    let c = client("/gw_test/nobody", r#"{"order": 3}"#, &[]);
    c.expect_async("REJECTED", 2 * T).await;
    assert!(c.finish(T));

    gw.shutdown().await;
    server.abort();
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn yarp_callers_reach_an_rclpy_action_server() {
    for d in common::distros("yarp_callers_reach_an_rclpy_action_server") {
        yarp_callers_reach_an_rclpy_action_server_on(&d).await;
    }
}

/// Calls `/gw/fib:rpc` with `cmd` (on a connection of its own) until an action server
/// answers (discovery may take a while on a loaded machine).
async fn call_goal(ns: &yarp_net::nameserver::NameClient, me: &str, cmd: &str) -> Bottle {
    let unanswered = "no action server answered";
    common::rpc_until_answered(ns, "/gw/fib:rpc", me, cmd, unanswered, 2 * T).await
}

async fn yarp_callers_reach_an_rclpy_action_server_on(venv: &common::Distro) {
    let domain = venv.domain(8);
    let (ns, stop) = common::name_server().await;
    let server = Peer::start(
        venv,
        domain,
        &[
            "action_serve",
            "test_msgs/action/Fibonacci",
            "/gw_test/served_fib",
            "--count",
            "2",
            "--linger",
            "2",
            "--timeout",
            "120",
        ],
    );
    server.expect_async("READY", T).await;
    let gw = common::gateway(
        &(venv.interfaces_line()
            + r#"
[[action]]
name = "fib"
direction = "yarp_to_ros"
yarp_port = "/gw/fib:rpc"
ros_action = "/gw_test/served_fib"
ros_type = "test_msgs/action/Fibonacci"
yarp_feedback = "/gw/fib/feedback:o"
"#),
        &ns,
        domain,
    )
    .await;
    let feedback = BufferedPort::open("/test/fib/feedback:i", ns.clone())
        .await
        .unwrap();
    feedback.set_strict(true);
    network::connect(&ns, "/gw/fib/feedback:o", "/test/fib/feedback:i", None)
        .await
        .unwrap();

    // A goal: the reply is the result; its feedback reached the YARP port.
    let r = call_goal(&ns, "/test/a", "8").await;
    assert_eq!(r.to_string(), "(0 1 1 2 3 5 8 13 21)");
    assert_eq!(
        json_line(&server.expect_async("GOAL", T).await),
        json!({"order": 8})
    );
    let fb = tokio::time::timeout(T, feedback.read())
        .await
        .expect("feedback in time")
        .expect("feedback port open");
    assert!(fb.bottle.to_string().starts_with("(0 1 1"), "{}", fb.bottle);

    // Rejected by the server.
    let r = call_goal(&ns, "/test/b", "-1").await;
    assert_eq!(r.to_string(), "[fail] rejected");

    // A long goal, and `[stop]` from another caller 0.4 s later: canceled.
    let long = tokio::spawn({
        let ns = ns.clone();
        async move { call_goal(&ns, "/test/c", "40").await }
    });
    tokio::time::sleep(Duration::from_millis(400)).await;
    let contact = ns.query("/gw/fib:rpc").await.unwrap().unwrap();
    let mut c = RpcClient::connect(&contact, "/test/d", Carrier::Tcp)
        .await
        .unwrap();
    let r = c.call(&Bottle::from_text("[stop]")).await.unwrap();
    assert_eq!(r.to_string(), "[ok] 1");
    c.close().await;
    let r = tokio::time::timeout(2 * T, long).await.unwrap().unwrap();
    assert!(r.to_string().starts_with("[fail] canceled (0 1 1"), "{r}");

    assert!(server.finish(T), "the action server ended its two goals");
    gw.shutdown().await;
    stop.shutdown();
}
