//! `[[action]]`: a ROS 2 action served by a YARP RPC port, against rclpy's `ActionClient`
//! on `test_msgs/action/Fibonacci` (run under netns-run): goal, feedback, result, cancel,
//! a rejected goal and an aborted one. Domain index: 8 (shared with services.rs's text
//! RPC test; the names differ).

mod common;

use common::{Peer, T};
use serde_json::{json, Value as Json};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use yarp_net::buffered::BufferedPort;
use yarp_net::port::Port;
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
        &format!(
            r#"
interfaces = [{:?}]

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
"#,
            venv.venv.display().to_string()
        ),
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
