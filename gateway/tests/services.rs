//! Service bridges (std_srvs Trigger/SetBool/Empty, any `.srv` through the generic Bottle
//! layout, and generic text RPC) against real rclpy peers and real YARP RPC ports. Domain
//! indices used here: 6..=8.

mod common;

use common::{Peer, T};
use serde_json::{json, Value as Json};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use yarp_net::buffered::RpcServer;
use yarp_proto::{Bottle, Value};

fn json_line(s: &str) -> Json {
    serde_json::from_str(s).unwrap_or_else(|e| panic!("bad JSON from peer `{s}`: {e}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ros_clients_call_yarp_rpc_ports() {
    for d in common::distros("ros_clients_call_yarp_rpc_ports") {
        ros_clients_call_yarp_rpc_ports_on(&d).await;
    }
}

async fn ros_clients_call_yarp_rpc_ports_on(venv: &common::Distro) {
    let domain = venv.domain(6);
    let (ns, stop) = common::name_server().await;
    // A YARP RPC server that records commands and answers like a device would.
    let server = RpcServer::open("/test/arm/rpc:i", ns.clone())
        .await
        .unwrap();
    let seen = Arc::new(Mutex::new(Vec::<String>::new()));
    let log = seen.clone();
    let serving = tokio::spawn(async move {
        server
            .serve(move |cmd| {
                log.lock().unwrap().push(cmd.to_string());
                // A generic request: `basic` and test_msgs/BasicTypes' request fields;
                // the response (the same fields) is the request with int32_value + 1.
                if cmd.get(0).and_then(|v| v.as_str()) == Some("basic") {
                    let mut reply = Bottle::new();
                    for (i, v) in cmd.iter().skip(1).enumerate() {
                        match (i, v.as_i64()) {
                            (9, Some(n)) => reply.push(Value::Int32(n as i32 + 1)),
                            _ => reply.push(v.clone()),
                        };
                    }
                    return reply;
                }
                match cmd.to_string().as_str() {
                    "[home]" => Bottle::from_text("[ok] \"homed\""),
                    "[on]" | "[off]" | "[park]" => Bottle::from_text("[ok]"),
                    _ => Bottle::from_text("[fail] \"unknown\""),
                }
            })
            .await
    });
    let gw = common::gateway(
        &(venv.interfaces_line()
            + r#"
[[service]]
name = "basic"
direction = "ros_to_yarp"
yarp_port = "/test/arm/rpc:i"
ros_service = "/arm/basic"
ros_type = "test_msgs/srv/BasicTypes"
command = "basic"

[[service]]
name = "refused"
direction = "ros_to_yarp"
yarp_port = "/test/arm/rpc:i"
ros_service = "/arm/refused"
ros_type = "test_msgs/srv/BasicTypes"
command = "refuse"

[[service]]
name = "home"
direction = "ros_to_yarp"
yarp_port = "/test/arm/rpc:i"
ros_service = "/arm/home"
ros_type = "std_srvs/srv/Trigger"
command = "[home]"

[[service]]
name = "enable"
direction = "ros_to_yarp"
yarp_port = "/test/arm/rpc:i"
ros_service = "/arm/enable"
ros_type = "std_srvs/srv/SetBool"
command_true = "[on]"
command_false = "[off]"

[[service]]
name = "park"
direction = "ros_to_yarp"
yarp_port = "/test/arm/rpc:i"
ros_service = "/arm/park"
ros_type = "std_srvs/srv/Empty"
command = "[park]"

[[service]]
name = "stop"
direction = "ros_to_yarp"
yarp_port = "/test/arm/rpc:i"
ros_service = "/arm/stop"
ros_type = "std_srvs/srv/Trigger"
command = "[stop]"
"#),
        &ns,
        domain,
    )
    .await;
    let calls = [
        ["call", "std_srvs/srv/Trigger", "/arm/home", "{}"],
        [
            "call",
            "std_srvs/srv/SetBool",
            "/arm/enable",
            r#"{"data": false}"#,
        ],
        ["call", "std_srvs/srv/Empty", "/arm/park", "{}"],
        ["call", "std_srvs/srv/Trigger", "/arm/stop", "{}"],
        ["call", "test_msgs/srv/BasicTypes", "/arm/basic", BASIC],
        ["call", "test_msgs/srv/BasicTypes", "/arm/refused", BASIC],
    ]
    // Four rclpy processes start at once: on a starved machine each may take many
    // seconds to discover the service, so they get a minute (they print RESP at once).
    .map(|a| {
        let args = [a.as_slice(), &["--timeout", "60"]].concat();
        Peer::start(venv, domain, &args)
    });
    let resp: Vec<Json> = {
        let mut v = Vec::new();
        for p in &calls {
            v.push(json_line(&p.expect_async("RESP", 3 * T).await));
        }
        v
    };
    assert_eq!(resp[0], json!({"success": true, "message": "[ok] homed"}));
    assert_eq!(resp[1], json!({"success": true, "message": "[ok]"}));
    assert_eq!(resp[2], json!({}), "rclpy hides the dummy byte");
    assert_eq!(
        resp[3],
        json!({"success": false, "message": "[fail] unknown"})
    );
    // Every field crossed YARP and came back (the YARP side added 1 to int32_value).
    let mut want = json_line(BASIC);
    want["int32_value"] = json!(-2147483647);
    want["byte_value"] = json!([0]);
    assert_eq!(resp[4], want, "{:?}", seen.lock().unwrap());
    // A refused call answers the default response (a ROS service has no error reply).
    assert_eq!(resp[5]["int64_value"], json!(0));
    assert_eq!(resp[5]["string_value"], json!(""));
    let mut seen = seen.lock().unwrap().clone();
    seen.sort();
    assert_eq!(seen.len(), 6, "{seen:?}");
    assert!(seen[0].starts_with("[home]"), "{seen:?}");
    assert_eq!(&seen[1..4], ["[off]", "[park]", "[stop]"]);
    assert!(seen[4].starts_with("basic true 0 65 "), "{seen:?}");
    assert_eq!(seen[5], format!("refuse {BASIC_BOTTLE}"));
    for p in calls {
        assert!(p.finish(T));
    }
    gw.shutdown().await;
    serving.abort();
    stop.shutdown();
}

/// A test_msgs/BasicTypes request at the edges of every field's range (byte_value stays
/// 0: rclpy takes bytes for it).
const BASIC: &str = r#"{"bool_value": true, "char_value": 65, "float32_value": 1.5, "float64_value": -2.25, "int8_value": -128, "uint8_value": 255, "int16_value": -32768, "uint16_value": 65535, "int32_value": -2147483648, "uint32_value": 4294967295, "int64_value": -9223372036854775808, "uint64_value": 9223372036854775807, "string_value": "a \"quoted\" word"}"#;

/// [`BASIC`] in the generic layout (a bool is YARP's bool, the string quoted).
const BASIC_BOTTLE: &str = r#"true 0 65 1.5 -2.25 -128 255 -32768 65535 -2147483648 4294967295 -9223372036854775808 9223372036854775807 "a \"quoted\" word""#;

/// Calls `port` with `cmd` until the reply is not the "no server yet" failure (the
/// gateway answers `[fail] "...: no answer within ..."` until discovery matched).
async fn rpc_until_answered(
    ns: &yarp_net::nameserver::NameClient,
    port: &str,
    cmd: &str,
) -> Bottle {
    common::rpc_until_answered(ns, port, "/test/client", cmd, "no answer within", T).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn yarp_clients_call_ros_services() {
    for d in common::distros("yarp_clients_call_ros_services") {
        yarp_clients_call_ros_services_on(&d).await;
    }
}

async fn yarp_clients_call_ros_services_on(venv: &common::Distro) {
    let domain = venv.domain(7);
    let (ns, stop) = common::name_server().await;
    // Each server answers until the test ends (not only its first request), so a call
    // that the test repeats while discovery settles still finds it.
    let serve = |srv: &str, name: &str, reply: &str| {
        let args = [
            "serve",
            srv,
            name,
            reply,
            "--count",
            "1000",
            "--timeout",
            "300",
        ];
        Peer::start(venv, domain, &args)
    };
    let servers = [
        serve(
            "std_srvs/srv/Trigger",
            "/ros/reset",
            r#"{"success": true, "message": "done"}"#,
        ),
        serve(
            "std_srvs/srv/SetBool",
            "/ros/motors",
            r#"{"success": false, "message": "estop"}"#,
        ),
        serve("std_srvs/srv/Empty", "/ros/beep", "{}"),
        serve("test_msgs/srv/BasicTypes", "/ros/basic", BASIC),
    ];
    for s in &servers {
        s.expect_async("READY", T).await;
    }
    let gw = common::gateway(
        &(venv.interfaces_line()
            + r#"
[[service]]
name = "basic"
direction = "yarp_to_ros"
yarp_port = "/gw/basic:rpc"
ros_service = "/ros/basic"
ros_type = "test_msgs/srv/BasicTypes"

[[service]]
name = "reset"
direction = "yarp_to_ros"
yarp_port = "/gw/reset:rpc"
ros_service = "/ros/reset"
ros_type = "std_srvs/srv/Trigger"

[[service]]
name = "motors"
direction = "yarp_to_ros"
yarp_port = "/gw/motors:rpc"
ros_service = "/ros/motors"
ros_type = "std_srvs/srv/SetBool"

[[service]]
name = "beep"
direction = "yarp_to_ros"
yarp_port = "/gw/beep:rpc"
ros_service = "/ros/beep"
ros_type = "std_srvs/srv/Empty"
"#),
        &ns,
        domain,
    )
    .await;
    // Any .srv: the Bottle is the request's fields (trailing ones left out take their
    // defaults), the reply the response's.
    let r = rpc_until_answered(
        &ns,
        "/gw/basic:rpc",
        "[ok] 0 66 0.5 1e300 -1 2 -3 4 -5 6 -7 8 \"yarp\"",
    )
    .await;
    assert_eq!(r.to_string(), BASIC_BOTTLE);
    assert_eq!(
        json_line(&servers[3].expect_async("REQ", T).await),
        json!({"bool_value": true, "byte_value": [0], "char_value": 66, "float32_value": 0.5,
               "float64_value": 1e300, "int8_value": -1, "uint8_value": 2, "int16_value": -3,
               "uint16_value": 4, "int32_value": -5, "uint32_value": 6, "int64_value": -7,
               "uint64_value": 8, "string_value": "yarp"})
    );
    // A Bottle that is not a BasicTypes request is answered with why, not forwarded.
    let r = rpc_until_answered(&ns, "/gw/basic:rpc", "[ok] 0 \"not a char\"").await;
    assert!(r.to_string().starts_with("[fail]"), "{r}");
    assert!(r.to_string().contains("char_value"), "{r}");
    let r = rpc_until_answered(&ns, "/gw/reset:rpc", "[reset]").await;
    assert_eq!(r.get(1).and_then(|v| v.as_str()), Some("done"), "{r}");
    assert_eq!(
        r.get(0)
            .and_then(|v| v.as_vocab())
            .map(|v| v.as_string())
            .as_deref(),
        Some("ok")
    );
    let r = rpc_until_answered(&ns, "/gw/motors:rpc", "[on]").await;
    assert_eq!(r.to_string(), "[fail] estop");
    assert_eq!(
        json_line(&servers[1].expect_async("REQ", T).await),
        json!({"data": true})
    );
    let r = rpc_until_answered(&ns, "/gw/beep:rpc", "[beep]").await;
    assert_eq!(r.to_string(), "[ok]");
    // A Bottle that cannot become a SetBool request is answered, not forwarded.
    let r = rpc_until_answered(&ns, "/gw/motors:rpc", "\"perhaps\"").await;
    assert!(r.to_string().starts_with("[fail]"), "{r}");
    drop(servers);
    gw.shutdown().await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn generic_text_rpc_over_string_topics() {
    for d in common::distros("generic_text_rpc_over_string_topics") {
        generic_text_rpc_over_string_topics_on(&d).await;
    }
}

async fn generic_text_rpc_over_string_topics_on(venv: &common::Distro) {
    let domain = venv.domain(8);
    let (ns, stop) = common::name_server().await;
    let server = RpcServer::open("/test/board/rpc:i", ns.clone())
        .await
        .unwrap();
    let serving = tokio::spawn(async move {
        server
            .serve(|cmd| {
                let mut r = Bottle::from_text("[is]");
                for v in cmd.iter() {
                    r.push(v.clone());
                }
                r.push(4);
                r
            })
            .await
    });
    let gw = common::gateway(
        r#"
[[service]]
name = "board"
direction = "ros_to_yarp"
yarp_port = "/test/board/rpc:i"
ros_service = "/board/rpc"
ros_type = "std_msgs/msg/String"
"#,
        &ns,
        domain,
    )
    .await;
    let sub = Peer::start(
        venv,
        domain,
        &["sub", "std_msgs/msg/String", "/board/rpc/reply"],
    );
    sub.expect_async("READY", T).await;
    let _pubr = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "std_msgs/msg/String",
            "/board/rpc/request",
            r#"{"data": "[get] [axes]"}"#,
            "--count",
            "100",
            "--rate",
            "5",
        ],
    );
    let got = json_line(&sub.expect_async("MSG", T).await);
    assert_eq!(got, json!({"data": "[is] [get] [axes] 4"}));
    tokio::time::sleep(Duration::from_millis(10)).await;
    gw.shutdown().await;
    serving.abort();
    stop.shutdown();
}
