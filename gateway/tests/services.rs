//! Service bridges (std_srvs Trigger/SetBool/Empty and generic text RPC) against real
//! rclpy peers and real YARP RPC ports. Domain indices used here: 6..=8.

mod common;

use common::{Peer, T};
use serde_json::{json, Value as Json};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use yarp_net::buffered::RpcServer;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::Bottle;

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
                match cmd.to_string().as_str() {
                    "[home]" => Bottle::from_text("[ok] \"homed\""),
                    "[on]" | "[off]" | "[park]" => Bottle::from_text("[ok]"),
                    _ => Bottle::from_text("[fail] \"unknown\""),
                }
            })
            .await
    });
    let gw = common::gateway(
        r#"
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
"#,
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
    let mut seen = seen.lock().unwrap().clone();
    seen.sort();
    assert_eq!(seen, ["[home]", "[off]", "[park]", "[stop]"]);
    for p in calls {
        assert!(p.finish(T));
    }
    gw.shutdown().await;
    serving.abort();
    stop.shutdown();
}

/// Calls `port` with `cmd` until the reply is not the "no server yet" failure.
async fn rpc_until_answered(
    ns: &yarp_net::nameserver::NameClient,
    port: &str,
    cmd: &str,
) -> Bottle {
    let contact = ns
        .query(port)
        .await
        .unwrap()
        .expect("gateway port registered");
    // DDS discovery of each ROS service can take a while on a loaded machine: the gateway
    // answers `[fail] "...: no answer within ..."` until it matched; ask again until then.
    let deadline = tokio::time::Instant::now() + 2 * T;
    loop {
        let mut c = RpcClient::connect(&contact, "/test/client", Carrier::Tcp)
            .await
            .unwrap();
        let reply = tokio::time::timeout(T, c.call(&Bottle::from_text(cmd)))
            .await
            .expect("reply in time")
            .unwrap();
        c.close().await;
        let unmatched = reply.to_string().contains("no answer within");
        if !unmatched || tokio::time::Instant::now() > deadline {
            return reply;
        }
        eprintln!("{port}: {reply}; asking again");
    }
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
    ];
    for s in &servers {
        s.expect_async("READY", T).await;
    }
    let gw = common::gateway(
        r#"
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
"#,
        &ns,
        domain,
    )
    .await;
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
