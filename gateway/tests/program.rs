//! The `yarp-ros2-gateway` program end to end: embedded name server, startup table,
//! bridging and /diagnostics, against rclpy (run under netns-run). Domain index: 9.

mod common;

use common::{Peer, T};
use std::process::Command;
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;
use yarp_proto::Bottle;

const MAPPING: &str = r#"
[[topic]]
name = "count"
direction = "yarp_to_ros"
yarp_port = "/gw/count:i"
ros_topic = "/count"
ros_type = "std_msgs/msg/Int32"
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn program_bridges_and_reports_diagnostics() {
    for d in common::distros("program_bridges_and_reports_diagnostics") {
        program_bridges_and_reports_diagnostics_on(&d).await;
    }
}

async fn program_bridges_and_reports_diagnostics_on(venv: &common::Distro) {
    let domain = venv.domain(9);
    let dir = std::env::temp_dir().join(format!("yarp-ros2-gateway-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("m.toml");
    std::fs::write(&file, MAPPING).unwrap();
    let (mut cmd, ns_addr) = gateway(&file, domain);
    cmd.args(["--diagnostics-period", "0.2"])
        .env("YARP_CONFIG_HOME", &dir)
        .env("ROS_DISTRO", "kilted");
    let gw = Peer::spawn(cmd, "yarp-ros2-gateway");
    let banner = gw.expect_async("yarp-ros2-gateway: ROS domain", T).await;
    assert!(banner.contains(&format!("{domain},")), "{banner}");
    let row = gw.expect_async("count", T).await;
    assert!(
        row.contains("/gw/count:i") && row.contains("/count"),
        "{row}"
    );
    assert!(dir.join("yarp.conf").exists(), "first run writes yarp.conf");

    let diag = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "diagnostic_msgs/msg/DiagnosticArray",
            "/diagnostics",
            "--count",
            "1000",
        ],
    );
    let sub = Peer::start(venv, domain, &["sub", "std_msgs/msg/Int32", "/count"]);
    sub.expect_async("READY", T).await;
    let ns = NameClient::new(ns_addr.parse().unwrap()).with_timeout(T);
    let w = Port::open("/test/count:o", ns.clone()).await.unwrap();
    w.connect("/gw/count:i", None).await.unwrap();
    let got = common::repeat_until(
        "the count on ROS",
        Duration::from_millis(50),
        async || {
            w.write(&Bottle::from_text("5")).await;
        },
        || sub.try_line("MSG"),
    )
    .await;
    assert_eq!(got, r#"{"data": 5}"#);

    // The diagnostics soon count the forwarded messages.
    let end = std::time::Instant::now() + T;
    loop {
        let line = diag.expect_async("MSG", T).await;
        let m: serde_json::Value = serde_json::from_str(&line).unwrap();
        let st = &m["status"][0];
        assert_eq!(st["name"], "yarp-ros2-gateway: count");
        let messages = st["values"][0]["value"]
            .as_str()
            .unwrap()
            .parse::<u64>()
            .unwrap();
        if messages >= 1 {
            break;
        }
        assert!(
            std::time::Instant::now() < end,
            "diagnostics never counted: {line}"
        );
    }

    // The same counters as Bottles on the YARP diagnostics port.
    let r = yarp_net::buffered::BufferedPort::open("/test/diag:i", ns.clone())
        .await
        .unwrap();
    yarp_net::network::connect(
        &ns,
        "/yarp_ros2_gateway/diagnostics:o",
        "/test/diag:i",
        None,
    )
    .await
    .unwrap();
    let b = tokio::time::timeout(T, r.read())
        .await
        .unwrap()
        .unwrap()
        .bottle;
    let row = b
        .get(0)
        .and_then(|v| v.as_list())
        .expect("one row per mapping");
    assert_eq!(row.get(0).and_then(|v| v.as_str()), Some("count"), "{b}");
    assert!(row.get(1).and_then(|v| v.as_i64()).unwrap() >= 1, "{b}");
    r.close().await;

    // Stopped and continued (Ctrl-Z and `fg`, a debugger attaching), it goes on
    // bridging: its DDS threads took the interrupted poll for a fatal error and ended.
    let signal = |sig: &str| {
        let ok = Command::new("kill")
            .args([sig, &gw.id().to_string()])
            .status()
            .unwrap();
        assert!(ok.success(), "kill {sig}");
    };
    signal("-STOP");
    tokio::time::sleep(Duration::from_secs(1)).await;
    signal("-CONT");
    let later = Peer::start(venv, domain, &["sub", "std_msgs/msg/Int32", "/count"]);
    later.expect_async("READY", T).await;
    let got = common::repeat_until(
        "the count on ROS after SIGSTOP and SIGCONT",
        Duration::from_millis(50),
        async || {
            w.write(&Bottle::from_text("6")).await;
        },
        || later.try_line("MSG"),
    )
    .await;
    assert_eq!(got, r#"{"data": 6}"#);

    // SIGINT stops it cleanly (unregistering its ports).
    signal("-INT");
    assert!(gw.finish(T), "exits with success after SIGINT");
    w.close().await;
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn check_mode_reports_mapping_errors_with_file_entry_and_key() {
    let dir = std::env::temp_dir().join(format!("yarp-ros2-gateway-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.toml");
    std::fs::write(&file, MAPPING.replace("ros_type", "ros_typ")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_yarp-ros2-gateway"))
        .args(["--check", "--mappings", file.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml: entry topic[0] \"count\": key `ros_typ`"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `launch_ros`'s `Node(...)` appends `--ros-args`: the node name, namespace, a topic remap
/// and a parameter as rclpy then sees them (domain index 30).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ros_args_rename_remap_and_set_parameters() {
    for d in common::distros("ros_args_rename_remap_and_set_parameters") {
        ros_args_on(&d).await;
    }
}

async fn ros_args_on(venv: &common::Distro) {
    let domain = venv.domain(30);
    let dir = tempfile_dir("ros-args");
    let file = dir.join("m.toml");
    std::fs::write(
        &file,
        MAPPING.replace("ros_topic = \"/count\"", "ros_topic = \"/chatter\""),
    )
    .unwrap();
    std::fs::write(
        dir.join("params.yaml"),
        "/**:\n  ros__parameters:\n    robot: icub\n/lab/lab_gateway:\n  ros__parameters:\n    rate: 2.5\n",
    )
    .unwrap();
    let (mut cmd, _) = gateway(&file, domain);
    cmd.args([
        "--ros-args",
        "-r",
        "__node:=lab_gateway",
        "-r",
        "__ns:=/lab",
    ])
    .args(["-r", "/chatter:=/talk", "-p", "answer:=42"])
    .args(["--params-file", dir.join("params.yaml").to_str().unwrap()])
    .args(["--log-level", "info"])
    .env("YARP_CONFIG_HOME", &dir);
    let gw = Peer::spawn(cmd, "yarp-ros2-gateway");
    gw.expect_async("yarp-ros2-gateway: ROS domain", T).await;

    let info = Peer::start(venv, domain, &["info", "/talk", "--pubs", "1", "--named"]);
    let line = info.expect_async("INFO", T).await;
    let v: serde_json::Value = serde_json::from_str(&line).unwrap();
    let pubs = v["pubs"].as_array().expect("pubs");
    assert_eq!(pubs.len(), 1, "{line}");
    assert_eq!(pubs[0]["node"], "lab_gateway", "{line}");
    assert_eq!(pubs[0]["namespace"], "/lab", "{line}");
    let old = Peer::start(venv, domain, &["info", "/chatter", "--timeout", "2"]);
    let line = old.expect_async("INFO", T).await;
    assert!(
        line.contains(r#""pubs": []"#),
        "the remapped-away name is unused: {line}"
    );

    let (resp, v) = get_parameters(
        venv,
        domain,
        "/lab/lab_gateway",
        r#"{"names": ["answer", "rate", "robot"]}"#,
    )
    .await;
    let values = v["values"].as_array().expect("values");
    assert_eq!(values[0]["integer_value"], 42, "{resp}");
    assert_eq!(values[1]["double_value"], 2.5, "{resp}");
    assert_eq!(values[2]["string_value"], "icub", "{resp}");

    // The gateway's settings, read-only.
    let (resp, v) = get_parameters(
        venv,
        domain,
        "/lab/lab_gateway",
        r#"{"names": ["mappings", "domain_id"]}"#,
    )
    .await;
    assert_eq!(
        v["values"][0]["string_array_value"][0],
        file.display().to_string(),
        "{resp}"
    );
    assert_eq!(v["values"][1]["integer_value"], domain, "{resp}");
    let set = Peer::start(
        venv,
        domain,
        &[
            "call",
            "rcl_interfaces/srv/SetParameters",
            "/lab/lab_gateway/set_parameters",
            r#"{"parameters": [{"name": "domain_id", "value": {"type": 2, "integer_value": 3}}]}"#,
        ],
    );
    let resp = set.expect_async("RESP", T).await;
    let v: serde_json::Value = serde_json::from_str(&resp).unwrap();
    assert_eq!(v["results"][0]["successful"], false, "{resp}");
    assert!(
        v["results"][0]["reason"]
            .as_str()
            .unwrap()
            .contains("read-only"),
        "{resp}"
    );

    // `ros2 param list` from 20 fresh nodes in a row: each gets the list at once.
    let fresh = Peer::start(
        venv,
        domain,
        &[
            "call_fresh",
            "rcl_interfaces/srv/ListParameters",
            "/lab/lab_gateway/list_parameters",
            "{}",
            "--count",
            "20",
            "--timeout",
            "120",
        ],
    );
    for i in 0..20 {
        let resp = fresh.expect_async("RESP", T).await;
        let v: serde_json::Value = serde_json::from_str(&resp).unwrap_or_default();
        let names = v["result"]["names"].as_array().cloned().unwrap_or_default();
        for want in ["answer", "rate", "robot", "mappings", "use_sim_time"] {
            assert!(
                names.iter().any(|n| n == want),
                "fresh node {i}: `{want}` not listed: {resp}"
            );
        }
    }
}

/// `--ros-args -p use_sim_time:=true`: the stamps the gateway gives YARP data that carries
/// none come from `/clock` (rosgraph_msgs/Clock, best effort as rosbag2 and Gazebo's bridge
/// publish it), 0 before the first, as rclcpp's; `use_sim_time` reads true. Domain index: 0.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn use_sim_time_stamps_with_the_clock() {
    for d in common::distros("use_sim_time_stamps_with_the_clock") {
        use_sim_time_on(&d).await;
    }
}

async fn use_sim_time_on(venv: &common::Distro) {
    let domain = venv.domain(0);
    let dir = tempfile_dir("sim-time");
    let file = dir.join("m.toml");
    std::fs::write(
        &file,
        r#"
[[topic]]
name = "twist"
direction = "yarp_to_ros"
yarp_port = "/gw/twist:i"
ros_topic = "/twist"
ros_type = "geometry_msgs/msg/TwistStamped"
conversion = "generic"
"#,
    )
    .unwrap();
    let (mut cmd, ns_addr) = gateway(&file, domain);
    cmd.args(["--ros-args", "-p", "use_sim_time:=true"])
        .env("YARP_CONFIG_HOME", &dir);
    let gw = Peer::spawn(cmd, "yarp-ros2-gateway");
    gw.expect_async("yarp-ros2-gateway: ROS domain", T).await;
    let sub = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "geometry_msgs/msg/TwistStamped",
            "/twist",
            "--count",
            "10000",
        ],
    );
    sub.expect_async("READY", T).await;
    let clock = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "rosgraph_msgs/msg/Clock",
            "/clock",
            r#"{"clock": {"sec": 1234, "nanosec": 5}}"#,
            "--count",
            "1000",
            "--rate",
            "10",
            "--best-effort",
        ],
    );
    let ns = NameClient::new(ns_addr.parse().unwrap()).with_timeout(T);
    let w = Port::open("/test/twist:o", ns.clone()).await.unwrap();
    w.connect("/gw/twist:i", None).await.unwrap();
    // A header of (0 0): the gateway stamps it (this port writes no envelope).
    let twist = Bottle::from_text("((0 0) base) ((1 2 3) (4 5 6))");
    let stamp = |line: &str| {
        let m: serde_json::Value = serde_json::from_str(line).unwrap();
        (
            m["header"]["stamp"]["sec"].as_i64().unwrap(),
            m["header"]["stamp"]["nanosec"].as_i64().unwrap(),
        )
    };
    let end = std::time::Instant::now() + 2 * T;
    let mut seen = Vec::new();
    loop {
        w.write(&twist).await;
        tokio::time::sleep(Duration::from_millis(50)).await;
        while let Some(line) = sub.try_line("MSG") {
            seen.push(stamp(&line));
        }
        if seen.last() == Some(&(1234, 5)) {
            break;
        }
        assert!(std::time::Instant::now() < end, "no /clock stamp: {seen:?}");
    }
    assert!(
        seen.iter().all(|s| *s == (0, 0) || *s == (1234, 5)),
        "stamps are the simulated time (0 before the first /clock): {seen:?}"
    );
    drop(clock);
    let (resp, v) = get_parameters(
        venv,
        domain,
        "/yarp_ros2_gateway",
        r#"{"names": ["use_sim_time"]}"#,
    )
    .await;
    assert_eq!(v["values"][0]["bool_value"], true, "{resp}");
}

/// `ROS_STATIC_PEERS`: the gateway announces itself (SPDP) by unicast to each host listed,
/// at the well-known discovery ports of the domain's first participants, as Fast DDS's
/// initial peers do; 127.0.0.5 stands for a host multicast does not reach. Domain index: 1.
#[test]
fn ros_static_peers_get_the_announcements() {
    let domain = common::domain_id(1);
    let dir = tempfile_dir("static-peers");
    let file = dir.join("m.toml");
    std::fs::write(&file, MAPPING).unwrap();
    // participant 1's port: the gateway is not the only participant a host may run
    let port = 7400 + 250 * domain + 10 + 2;
    let peer = std::net::UdpSocket::bind(("127.0.0.5", port)).unwrap();
    peer.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let (mut cmd, _) = gateway(&file, domain);
    cmd.env("YARP_CONFIG_HOME", &dir)
        .env("ROS_STATIC_PEERS", "192.0.2.1;127.0.0.5");
    let _gw = Peer::spawn(cmd, "yarp-ros2-gateway");
    let end = std::time::Instant::now() + T;
    let mut buf = [0u8; 65536];
    loop {
        if let Ok((n, from)) = peer.recv_from(&mut buf) {
            let d = &buf[..n];
            // RTPS header, then a DATA of the SPDP participant writer (entity 0x000100c2)
            let spdp = d.starts_with(b"RTPS") && d.windows(4).any(|w| w == [0, 1, 0, 0xc2]);
            if spdp {
                eprintln!("SPDP from {from}: {n} bytes");
                break;
            }
        }
        assert!(
            std::time::Instant::now() < end,
            "no SPDP announcement at 127.0.0.5:{port}"
        );
    }
}

/// `GetParameters` of `node` from a fresh rclpy node: the response line and its JSON.
async fn get_parameters(
    venv: &common::Distro,
    domain: u16,
    node: &str,
    request: &str,
) -> (String, serde_json::Value) {
    let service = format!("{node}/get_parameters");
    let call = Peer::start(
        venv,
        domain,
        &[
            "call",
            "rcl_interfaces/srv/GetParameters",
            &service,
            request,
        ],
    );
    let resp = call.expect_async("RESP", T).await;
    let v = serde_json::from_str(&resp).unwrap();
    (resp, v)
}

fn tempfile_dir(what: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("yarp-ros2-gateway-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A graph that enforces SROS2 gets no unsecured participant from us: without a keystore
/// the program says why and exits (`security.rs` runs it secured).
#[test]
fn an_enforced_secure_graph_is_refused() {
    let dir = tempfile_dir("sros2");
    let file = dir.join("m.toml");
    std::fs::write(&file, MAPPING).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_yarp-ros2-gateway"))
        .args([
            "--mappings",
            file.to_str().unwrap(),
            "--network",
            "127.0.0.1",
        ])
        .args(["--embedded-name-server", "127.0.0.1:0"])
        .env("YARP_CONFIG_HOME", &dir)
        .env("ROS_SECURITY_ENABLE", "true")
        .env("ROS_SECURITY_STRATEGY", "Enforce")
        .output()
        .expect("run the gateway");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "it ran: {err}");
    assert!(
        err.contains("refusing to join the graph unsecured"),
        "{err}"
    );
}

/// The gateway on mapping `file`, DDS on loopback in `domain`, with a name server of its own
/// (embedded, on a free port: its address is the second value).
fn gateway(file: &std::path::Path, domain: u16) -> (Command, String) {
    let ns_port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let ns_addr = format!("127.0.0.1:{ns_port}");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_yarp-ros2-gateway"));
    cmd.args(["--mappings", file.to_str().unwrap()])
        .args(["--domain-id", &domain.to_string()])
        .args(["--network", "127.0.0.1"])
        .args([
            "--name-server",
            &ns_addr,
            "--embedded-name-server",
            &ns_addr,
        ]);
    (cmd, ns_addr)
}
