//! The gateway in an SROS2-secured graph (DDS Security: PKI-DH authentication, signed
//! governance and permissions, AES-GCM encryption), with a keystore laid out as `ros2
//! security` writes it (`tests/peers/sros2-keystore.sh`). Domain index: 32.
//!
//! PyPI's rclpy cannot join a secured graph: its Fast DDS is built without security, and
//! rmw_fastrtps refuses to create a secured node (the first test shows it). So the secured
//! peers are our own and Debian's Fast DDS: a robot-side gateway (enclave `/robot`) driving a real
//! `controlBoard_nws_yarp` + `fakeMotionControl`, and an operator's gateway (enclave
//! `/operator`) commanding it over ROS 2. Intruders: unsecured rclpy nodes, a gateway
//! whose identity another CA signed, and one whose permissions deny the command topic.
//! Then Fast DDS with security (Debian's libfastrtps, configured as rmw_fastrtps does it:
//! `tests/peers/fastdds_secure_peer.cpp`), a real ROS 2 install's middleware, talks with
//! the gateways both ways.
//! Nothing of the secured exchange is readable on the wire (captured with tcpdump before
//! the intruders, whose own traffic is plain).

mod common;

use common::{blocking, Distro, Peer, T};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_net::buffered::BufferedPort;
use yarp_net::port::Port;
use yarp_proto::Bottle;

fn keystore_script() -> PathBuf {
    common::gateway_dir().join("tests/peers/sros2-keystore.sh")
}

/// Runs the keystore script for `domain` (its governance and permissions name it).
fn sros2(domain: u16, args: &[&str]) {
    let out = Command::new("bash")
        .arg(keystore_script())
        .args(args)
        .env("ROS_DOMAIN_ID", domain.to_string())
        .output()
        .expect("run sros2-keystore.sh");
    assert!(
        out.status.success(),
        "sros2-keystore.sh {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs `cmd` to its end (bounded by `T`; killed past it): exit success and stderr.
fn run_bounded(mut cmd: Command) -> (bool, String) {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut err, &mut s);
        s
    });
    let end = Instant::now() + T;
    let ok = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st.success();
        }
        if Instant::now() > end {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?} did not end within {T:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    (ok, reader.join().unwrap())
}

/// rmw_fastrtps of PyPI's wheels cannot make a secured node: asked to, rclpy fails and
/// says that its Fast DDS lacks the security libraries (so the secured peers below are
/// ours). Shown for every distro.
#[test]
fn pypi_rclpy_cannot_join_a_secured_graph() {
    for venv in common::distros("pypi_rclpy_cannot_join_a_secured_graph") {
        let domain = venv.domain(32);
        let dir = tempfile::tempdir().unwrap();
        let ks = dir.path().join("keystore");
        sros2(domain, &["create_keystore", ks.to_str().unwrap()]);
        sros2(
            domain,
            &["create_enclave", ks.to_str().unwrap(), "/listener"],
        );
        let mut cmd = Command::new(venv.join("bin/python"));
        cmd.arg(common::gateway_dir().join("tests/peers/peer.py"))
            .args(["sub", "std_msgs/msg/String", "/chatter", "--timeout", "2"])
            .env("ROS_DOMAIN_ID", domain.to_string())
            .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
            .env("ROS_DISTRO", venv.name)
            .env("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4")
            .env("ROS_SECURITY_ENABLE", "true")
            .env("ROS_SECURITY_STRATEGY", "Enforce")
            .env("ROS_SECURITY_KEYSTORE", &ks)
            .env("ROS_SECURITY_ENCLAVE_OVERRIDE", "/listener");
        let (ok, err) = run_bounded(cmd);
        eprintln!("{} rclpy with SROS2 enforced: {err}", venv.name);
        assert!(!ok, "{}: a secured rclpy node started", venv.name);
        assert!(
            err.contains("Found security directory")
                && err.contains("doesn't have the security libraries"),
            "{}: {err}",
            venv.name
        );
    }
}

/// The robot's 3-axis board `/sec32/arm` (two revolute joints, one prismatic).
fn board() -> PolyDriver {
    common::open_device(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /sec32/arm\n\
         period 0.01\n[GENERAL]\njoints 3\nAxisName \"shoulder\" \"elbow\" \"slide\"\n\
         AxisType \"revolute\" \"revolute\" \"prismatic\"\n",
    )
}

/// The robot side: joint states of the board to ROS, position commands from ROS to it,
/// and a text topic whose words the wire check looks for.
const ROBOT: &str = r#"
[[topic]]
name = "arm_state"
direction = "yarp_to_ros"
yarp_port = "/robot/gw/arm_state:i"
yarp_source = "/sec32/arm/state:o"
ros_topic = "/joint_states"
ros_type = "sensor_msgs/msg/JointState"
joint_names = { from = "list", names = ["shoulder", "elbow", "slide"] }

[[topic]]
name = "arm_command"
direction = "ros_to_yarp"
yarp_port = "/robot/gw/arm_cmd"
ros_topic = "/arm/position_command"
ros_type = "std_msgs/msg/Float64MultiArray"
control_board = { remote = "/sec32/arm", mode = "position" }

[[topic]]
name = "say"
direction = "ros_to_yarp"
yarp_port = "/robot/gw/say:o"
ros_topic = "/robot/say"
ros_type = "std_msgs/msg/String"
"#;

/// An operator's side (ports under `/<who>`): commands and words from YARP to ROS, the
/// joint states from ROS to YARP.
fn operator(who: &str) -> String {
    format!(
        r#"
[[topic]]
name = "command"
direction = "yarp_to_ros"
yarp_port = "/{who}/command:i"
ros_topic = "/arm/position_command"
ros_type = "std_msgs/msg/Float64MultiArray"

[[topic]]
name = "state"
direction = "ros_to_yarp"
yarp_port = "/{who}/joint_states:o"
ros_topic = "/joint_states"
ros_type = "sensor_msgs/msg/JointState"
conversion = "generic"

[[topic]]
name = "say"
direction = "yarp_to_ros"
yarp_port = "/{who}/say:i"
ros_topic = "/robot/say"
ros_type = "std_msgs/msg/String"
"#
    )
}

/// The gateway program for `mapping` as node `who`, secured (Enforce) with `enclave`
/// of `keystore`; YARP through this test's name server (its yarp.conf).
fn gateway(
    dir: &Path,
    who: &str,
    mapping: &str,
    domain: u16,
    keystore: &Path,
    enclave: &str,
) -> Command {
    let file = dir.join(format!("{who}.toml"));
    std::fs::write(&file, mapping).unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_yarp-ros2-gateway"));
    cmd.args(["--mappings", file.to_str().unwrap()])
        .args(["--domain-id", &domain.to_string(), "--network", "127.0.0.1"])
        .args(["--no-embedded-name-server", "--node-name", who])
        .args(["--diagnostics-period", "0"])
        .args(["--diagnostics-port", &format!("/{who}/diagnostics:o")])
        .args(["--ros-args", "--enclave", enclave])
        .env("ROS_DISTRO", "kilted")
        .env("ROS_SECURITY_ENABLE", "true")
        .env("ROS_SECURITY_STRATEGY", "Enforce")
        .env("ROS_SECURITY_KEYSTORE", keystore);
    cmd
}

fn encoders(d: &mut PolyDriver) -> Option<Vec<f64>> {
    d.device().as_encoders()?.get_encoders().ok()
}

fn near_all(q: &[f64], want: &[f64]) -> bool {
    q.len() == want.len() && q.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6)
}

/// The joints as ROS commands them (radians, meters) seen as the board's encoders
/// (degrees for the revolute ones).
fn as_encoders(cmd: [f64; 3]) -> Vec<f64> {
    vec![cmd[0].to_degrees(), cmd[1].to_degrees(), cmd[2]]
}

/// A loopback capture of the test's domain (tcpdump, inside the suite's netns-run): the
/// secured exchange must never show its words or topic names on the wire.
struct Capture {
    child: Child,
    file: PathBuf,
}

impl Capture {
    /// Captures the UDP ports of ROS `domain` (RTPS: 7400 + 250 × domain and the 250
    /// after), not the other tests' traffic on the same loopback.
    fn start(dir: &Path, domain: u16) -> Option<Capture> {
        let file = dir.join("lo.pcap");
        let base = 7400 + 250 * u32::from(domain);
        let child = Command::new("tcpdump")
            .args(["-i", "lo", "-U", "-n", "-Z", "root", "-w"])
            .arg(&file)
            .arg(format!("udp portrange {base}-{}", base + 249))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn();
        match child {
            Ok(child) => Some(Capture { child, file }),
            Err(e) => {
                let why = format!("tcpdump: {e} (.ci/run installs it)");
                assert!(std::env::var("CI").as_deref() != Ok("true"), "{why}");
                eprintln!("\n*** SKIPPED the wire check: {why} ***\n");
                None
            }
        }
    }

    /// Stops the capture (flushed) and returns what it holds.
    fn finish(mut self) -> Vec<u8> {
        let _ = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status();
        let end = Instant::now() + T;
        while self.child.try_wait().unwrap().is_none() && Instant::now() < end {
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        std::fs::read(&self.file).unwrap_or_default()
    }
}

impl Drop for Capture {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn contains(hay: &[u8], needle: &str) -> bool {
    hay.windows(needle.len()).any(|w| w == needle.as_bytes())
}

/// Writes `text` to `port` every 100 ms until `stop` says so (a YARP writer of the test).
fn keep_writing(
    port: Port,
    text: String,
    stop: tokio::sync::watch::Receiver<bool>,
) -> tokio::task::JoinHandle<Port> {
    tokio::spawn(async move {
        while !*stop.borrow() {
            port.write(&Bottle::from_text(&text)).await;
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
        port
    })
}

/// A YARP writer `/test/<name>` connected to `target`.
async fn writer(ns: &yarp_net::nameserver::NameClient, name: &str, target: &str) -> Port {
    let w = Port::open(&format!("/test/{name}"), ns.clone())
        .await
        .unwrap();
    let end = Instant::now() + T;
    while w.connect(target, None).await.is_err() {
        assert!(Instant::now() < end, "{target} never appeared");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    w
}

/// A YARP reader `/test/<name>` connected from `source`.
async fn reader(ns: &yarp_net::nameserver::NameClient, name: &str, source: &str) -> BufferedPort {
    let r = BufferedPort::open(&format!("/test/{name}"), ns.clone())
        .await
        .unwrap();
    let end = Instant::now() + T;
    while yarp_net::network::connect(ns, source, r.name(), None)
        .await
        .is_err()
    {
        assert!(Instant::now() < end, "{source} never appeared");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    r
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn secured_operator_commands_the_robot_and_intruders_cannot() {
    for venv in common::first_distro("secured_operator_commands_the_robot_and_intruders_cannot") {
        secured_graph_on(&venv).await;
    }
}

async fn secured_graph_on(venv: &Distro) {
    let domain = venv.domain(32);
    let dir = tempfile::tempdir().unwrap();
    let (ks, foreign) = (dir.path().join("keystore"), dir.path().join("foreign"));
    let k = ks.to_str().unwrap();
    sros2(domain, &["create_keystore", k]);
    sros2(domain, &["create_enclave", k, "/robot"]);
    sros2(domain, &["create_enclave", k, "/operator"]);
    sros2(
        domain,
        &["create_enclave", k, "/observer", "/arm/position_command"],
    );
    sros2(domain, &["create_enclave", k, "/listener"]);
    sros2(domain, &["create_enclave", k, "/talker"]);
    // Another lab's CA, with an enclave of the same name.
    sros2(domain, &["create_keystore", foreign.to_str().unwrap()]);
    sros2(
        domain,
        &["create_enclave", foreign.to_str().unwrap(), "/operator"],
    );

    let capture = Capture::start(dir.path(), domain);
    let ns = common::device_name_server();
    let arm = blocking(board).await;
    let check = blocking(|| {
        common::open_device(
            "device remote_controlboard\nremote /sec32/arm\nlocal /sec32/check\ncarrier tcp\n",
        )
    })
    .await;
    let robot = Peer::spawn(
        gateway(dir.path(), "robot", ROBOT, domain, &ks, "/robot"),
        "robot gateway",
    );
    let op = Peer::spawn(
        gateway(
            dir.path(),
            "operator",
            &operator("operator"),
            domain,
            &ks,
            "/operator",
        ),
        "operator gateway",
    );
    robot.expect_async("yarp-ros2-gateway: ROS domain", T).await;
    op.expect_async("yarp-ros2-gateway: ROS domain", T).await;

    // The operator's command and words reach the robot through the secured graph.
    // 21 characters: a CDR string whose length is no multiple of 4 (padded on the wire).
    let secret = format!("secret-words-{:08}", std::process::id());
    let said = reader(&ns, "said:i", "/robot/gw/say:o").await;
    let states = reader(&ns, "op_states:i", "/operator/joint_states:o").await;
    let (stop, stopped) = tokio::sync::watch::channel(false);
    let cmd = keep_writing(
        writer(&ns, "cmd:o", "/operator/command:i").await,
        "0.5 -0.25 0.1".into(),
        stopped.clone(),
    );
    let say = keep_writing(
        writer(&ns, "say:o", "/operator/say:i").await,
        secret.clone(),
        stopped.clone(),
    );
    let want = as_encoders([0.5, -0.25, 0.1]);
    let (mut check, q) = {
        let want = want.clone();
        blocking(move || {
            let mut check = check;
            let end = Instant::now() + T;
            loop {
                let q = encoders(&mut check);
                if q.as_deref().is_some_and(|q| near_all(q, &want)) {
                    return (check, q.unwrap());
                }
                assert!(
                    Instant::now() < end,
                    "the secured command never moved the arm: {q:?}"
                );
                std::thread::sleep(Duration::from_millis(20));
            }
        })
        .await
    };
    eprintln!("encoders after the operator's secured command: {q:?}");
    let heard = tokio::time::timeout(T, said.read())
        .await
        .expect("the words over ROS")
        .unwrap();
    assert_eq!(
        heard.bottle.get(0).and_then(|v| v.as_str()),
        Some(secret.as_str()),
        "{}",
        heard.bottle
    );
    let js = tokio::time::timeout(T, states.read())
        .await
        .expect("joint states over ROS")
        .unwrap();
    eprintln!("joint states at the operator: {}", js.bottle);
    let _ = stop.send(true);
    let (_cmd, say_port) = (cmd.await.unwrap(), say.await.unwrap());
    if let Some(c) = capture {
        let wire = c.finish();
        assert!(
            wire.len() > 10_000,
            "the capture saw the exchange ({} bytes)",
            wire.len()
        );
        for word in [
            secret.as_str(),
            "rt/joint_states",
            "position_command",
            "shoulder",
            "robot/say",
        ] {
            assert!(!contains(&wire, word), "`{word}` is readable on the wire");
        }
    }

    // Intruders, all at once for a few seconds, all commanding another pose: unsecured
    // rclpy nodes, a gateway with another CA's identity, one not permitted to command.
    let evil = "{\"data\": [-0.5, 0.25, 0.05]}";
    let spy = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/JointState",
            "/joint_states",
            "--timeout",
            "8",
        ],
    );
    let rogue = Peer::start(
        venv,
        domain,
        &[
            "pub",
            "std_msgs/msg/Float64MultiArray",
            "/arm/position_command",
            evil,
            "--count",
            "50",
            "--rate",
            "10",
        ],
    );
    spy.expect_async("READY", T).await;
    rogue.expect_async("READY", T).await;
    let foreign_gw = Peer::spawn(
        gateway(
            dir.path(),
            "intruder",
            &operator("intruder"),
            domain,
            &foreign,
            "/operator",
        ),
        "foreign gateway",
    );
    foreign_gw
        .expect_async("yarp-ros2-gateway: ROS domain", T)
        .await;
    let (stop, stopped) = tokio::sync::watch::channel(false);
    let evil_cmd = keep_writing(
        writer(&ns, "evil:o", "/intruder/command:i").await,
        "-0.5 0.25 0.05".into(),
        stopped,
    );
    let foreign_states = reader(&ns, "foreign_states:i", "/intruder/joint_states:o").await;
    let (ok, err) = blocking({
        let cmd = gateway(
            dir.path(),
            "observer",
            &operator("observer"),
            domain,
            &ks,
            "/observer",
        );
        move || run_bounded(cmd)
    })
    .await;
    assert!(!ok, "a gateway denied the command topic started");
    assert!(err.contains("not allowed by security"), "observer: {err}");
    eprintln!(
        "gateway without permission to command: {}",
        err.lines().last().unwrap_or("")
    );

    tokio::time::sleep(Duration::from_secs(4)).await;
    let _ = stop.send(true);
    evil_cmd.await.unwrap();
    let q = blocking(move || encoders(&mut check)).await;
    assert!(
        q.as_deref().is_some_and(|q| near_all(q, &want)),
        "an intruder moved the arm: {q:?}"
    );
    assert_eq!(
        spy.try_line("MSG"),
        None,
        "an unsecured node read the joint states"
    );
    assert!(
        rogue.try_line("SENT").is_some(),
        "the rogue publisher published"
    );
    assert!(
        foreign_states.try_read().is_none(),
        "another CA's identity read the joint states"
    );
    drop((spy, rogue, foreign_gw));

    // Fast DDS with DDS Security (Debian's, as rmw_fastrtps configures it): a ROS 2 node
    // of a real install hears the operator and is heard by the robot.
    let peer = fastdds_peer();
    let listener = Peer::spawn(
        fastdds(
            &peer,
            &[
                "sub",
                &domain.to_string(),
                "/robot/say",
                &enclave(&ks, "listener"),
                "40",
            ],
        ),
        "Fast DDS listener",
    );
    listener.expect_async("READY", T).await;
    let (stop, stopped) = tokio::sync::watch::channel(false);
    let say = keep_writing(say_port, format!("{secret} again"), stopped);
    // A DDS Security handshake with Fast DDS can take long on a loaded machine.
    let got = listener.expect_async("MSG", FAST_DDS_MATCH).await;
    assert_eq!(got, format!("{secret} again"));
    let _ = stop.send(true);
    say.await.unwrap();
    let talker = Peer::spawn(
        fastdds(
            &peer,
            &[
                "pub",
                &domain.to_string(),
                "/robot/say",
                &enclave(&ks, "talker"),
                "hello from Fast DDS",
                "40",
            ],
        ),
        "Fast DDS talker",
    );
    let heard = loop {
        let m = tokio::time::timeout(FAST_DDS_MATCH, said.read())
            .await
            .expect("Fast DDS's words at the robot")
            .unwrap();
        if m.bottle.to_string().contains("Fast") {
            break m.bottle;
        }
    };
    assert_eq!(heard.to_string(), "hello from Fast DDS");
    drop((talker, listener, robot, op));
    blocking(move || drop(arm)).await;
}

/// How long a Fast DDS peer may take to authenticate with a gateway and match.
const FAST_DDS_MATCH: Duration = Duration::from_secs(35);

/// `<keystore>/enclaves/<name>`.
fn enclave(ks: &Path, name: &str) -> String {
    ks.join("enclaves").join(name).to_str().unwrap().to_string()
}

/// The secured Fast DDS node (`tests/peers/fastdds_secure_peer.cpp`), built once by
/// `install-fastdds-peer.sh` against Debian's libfastrtps-dev.
fn fastdds_peer() -> PathBuf {
    let out = Command::new("bash")
        .arg(common::gateway_dir().join("tests/peers/install-fastdds-peer.sh"))
        .output()
        .expect("run install-fastdds-peer.sh");
    assert!(
        out.status.success(),
        "the Fast DDS peer (a missing peer fails): {}",
        String::from_utf8_lossy(&out.stderr)
    );
    PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
}

fn fastdds(peer: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(peer);
    c.args(args);
    c
}
