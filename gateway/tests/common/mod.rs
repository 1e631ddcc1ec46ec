//! Shared harness for the gateway's integration tests: finds the rclpy venv, gives every
//! test its own ROS domain, and runs rclpy peer scripts as bounded, always-reaped children.
#![allow(dead_code)] // each test binary uses a different part of the harness

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// How long any single wait in a test may take.
pub const T: Duration = Duration::from_secs(20);

/// A ROS 2 distro the rclpy tests run against, with its venv (`tests/peers/install-ros2.sh
/// [kilted|jazzy]`): Kilted's `ros-*` wheels in `ROS_VENV` (default `<repo>/.venv-ros`),
/// Jazzy's `ros-jazzy-*` wheels in `ROS_JAZZY_VENV` (default `<repo>/.venv-ros-jazzy`).
/// Derefs to the venv directory.
#[derive(Debug, Clone)]
pub struct Distro {
    /// `ROS_DISTRO` of its nodes.
    pub name: &'static str,
    pub venv: PathBuf,
    /// Its place in [`KNOWN`] (keeps the distros' ROS domains apart).
    slot: u16,
}

impl std::ops::Deref for Distro {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.venv
    }
}

impl Distro {
    /// The mapping line that makes the gateway read the venv's interface definitions
    /// (`interfaces = ["<venv>"]`: nav_msgs, test_msgs, ... of the distro's wheels).
    pub fn interfaces_line(&self) -> String {
        format!("interfaces = [{:?}]\n", self.venv.display().to_string())
    }

    /// The ROS domain of test `index` for this distro (see [`domain_id`]).
    pub fn domain(&self, index: u16) -> u16 {
        domain_slot(index) + PER_DISTRO * self.slot
    }
}

/// The gateway crate's directory (its peers and default venvs): this harness is also
/// included (`#[path]`) by tests of other packages, e.g. the programs' ROS 2 robot files.
pub fn gateway_dir() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for dir in here.ancestors() {
        if dir.join("Cargo.lock").exists() {
            return dir.join("gateway");
        }
    }
    here
}

/// The distros, their venv variables and default venv directories.
const KNOWN: [(&str, &str, &str); 2] = [
    ("kilted", "ROS_VENV", "../.venv-ros"),
    ("jazzy", "ROS_JAZZY_VENV", "../.venv-ros-jazzy"),
];

/// The distros to run rclpy tests against: `YARP_ROS_DISTROS` (comma-separated), default
/// every known one. A distro whose venv is missing is skipped with a loud notice (the
/// test passes for it), except under CI=true, where that fails the test.
pub fn distros(test: &str) -> Vec<Distro> {
    let wanted = std::env::var("YARP_ROS_DISTROS").unwrap_or_else(|_| "kilted,jazzy".into());
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let mut found = Vec::new();
    for want in wanted.split(',').map(str::trim).filter(|w| !w.is_empty()) {
        let Some(slot) = KNOWN.iter().position(|k| k.0 == want) else {
            panic!("YARP_ROS_DISTROS names `{want}`: known are kilted, jazzy");
        };
        let (name, var, default) = KNOWN[slot];
        let venv = std::env::var_os(var)
            .map(PathBuf::from)
            .unwrap_or_else(|| gateway_dir().join(default));
        if venv.join("bin/python").exists() {
            found.push(Distro {
                name,
                venv,
                slot: slot as u16,
            });
            continue;
        }
        let why = format!(
            "no ROS 2 {name} rclpy venv at {} (run tests/peers/install-ros2.sh {name} or set {var})",
            venv.display()
        );
        assert!(!ci, "{test}: {why}");
        eprintln!("\n*** SKIPPED for {name}: {test}: {why} ***\n");
    }
    found
}

/// The first distro of [`distros`] only: for measurements (throughput, latency) of the
/// gateway's own path, which one rclpy is enough to drive.
pub fn first_distro(test: &str) -> Vec<Distro> {
    distros(test).into_iter().take(1).collect()
}

/// A ROS domain id unique to this test within this test run (the first distro's; see
/// [`Distro::domain`] for the others).
///
/// `index` is the test's own number (unique across the gateway's tests, < 35). The run
/// picks one of 3 slots of 70 domains (35 per distro) from nextest's run id (or the
/// process id under plain `cargo test`), so two suites running at once rarely share a
/// domain either; the slots stay below 232, the highest domain RTPS's port formula allows.
pub fn domain_id(index: u16) -> u16 {
    domain_slot(index)
}

/// Domain indices per distro and run slot.
const PER_DISTRO: u16 = 35;

fn domain_slot(index: u16) -> u16 {
    assert!(index < PER_DISTRO, "domain index {index} out of range");
    let seed = std::env::var("NEXTEST_RUN_ID").unwrap_or_else(|_| std::process::id().to_string());
    let h = seed.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    });
    20 + (h % 3) as u16 * 2 * PER_DISTRO + index
}

/// A running rclpy peer (`gateway/tests/peers/peer.py`); killed and reaped on drop.
pub struct Peer {
    child: Child,
    lines: mpsc::Receiver<String>,
    name: String,
}

impl Peer {
    /// Starts `peer.py <args>` in `domain`.
    pub fn start(distro: &Distro, domain: u16, args: &[&str]) -> Peer {
        Peer::start_with_profile(distro, domain, args, None)
    }

    /// Like [`Peer::start`], with a Fast DDS XML profile from `tests/peers/` (which then
    /// chooses the transports).
    pub fn start_with_profile(
        distro: &Distro,
        domain: u16,
        args: &[&str],
        profile: Option<&str>,
    ) -> Peer {
        let script = gateway_dir().join("tests/peers/peer.py");
        let mut cmd = Command::new(distro.join("bin/python"));
        cmd.arg("-u")
            .arg(script)
            .args(args)
            .env("ROS_DOMAIN_ID", domain.to_string())
            .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
            .env("ROS_DISTRO", distro.name)
            // UDP only: Fast DDS's /dev/shm segments are not isolated by netns-run.
            .env("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4");
        if let Some(p) = profile {
            let path = gateway_dir().join("tests/peers").join(p);
            cmd.env_remove("FASTDDS_BUILTIN_TRANSPORTS")
                .env("FASTDDS_DEFAULT_PROFILES_FILE", path);
        }
        Peer::spawn(cmd, &args.join(" "))
    }

    /// Runs any program with its stdout lines collected (killed and reaped on drop).
    pub fn spawn(mut cmd: Command, name: &str) -> Peer {
        let mut child = cmd
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap_or_else(|e| panic!("start {name}: {e}"));
        let out = child.stdout.take().expect("child stdout");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Peer {
            child,
            lines: rx,
            name: name.to_string(),
        }
    }

    /// The child's process id.
    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// The next line starting with `prefix` (others are skipped), within `timeout`.
    pub fn expect(&self, prefix: &str, timeout: Duration) -> String {
        let end = Instant::now() + timeout;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) if l.starts_with(prefix) => return l[prefix.len()..].trim().to_string(),
                Ok(_) => continue,
                Err(_) => panic!(
                    "peer `{}`: no `{prefix}` line within {timeout:?}",
                    self.name
                ),
            }
        }
    }

    /// Like [`Peer::expect`] but without blocking the async runtime.
    pub async fn expect_async(&self, prefix: &str, timeout: Duration) -> String {
        let end = Instant::now() + timeout;
        loop {
            match self.lines.try_recv() {
                Ok(l) if l.starts_with(prefix) => return l[prefix.len()..].trim().to_string(),
                Ok(_) => continue,
                Err(mpsc::TryRecvError::Empty) if Instant::now() < end => {
                    tokio::time::sleep(Duration::from_millis(2)).await
                }
                Err(_) => panic!(
                    "peer `{}`: no `{prefix}` line within {timeout:?}",
                    self.name
                ),
            }
        }
    }

    /// Waits (bounded) for the peer to exit by itself; kills it when it does not.
    pub fn finish(mut self, timeout: Duration) -> bool {
        let end = Instant::now() + timeout;
        while Instant::now() < end {
            if let Ok(Some(st)) = self.child.try_wait() {
                return st.success();
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        false
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

impl Peer {
    /// The next line starting with `prefix`, if one is already there (never blocks).
    pub fn try_line(&self, prefix: &str) -> Option<String> {
        while let Ok(l) = self.lines.try_recv() {
            if let Some(rest) = l.strip_prefix(prefix) {
                return Some(rest.trim().to_string());
            }
        }
        None
    }
}

/// An in-test YARP name server on 127.0.0.1 (any free port).
pub async fn name_server() -> (
    yarp_net::nameserver::NameClient,
    yarp_net::nameserver::ShutdownHandle,
) {
    let ns = yarp_net::nameserver::NameServer::bind("127.0.0.1:0", "127.0.0.1")
        .await
        .expect("bind name server");
    let addr = ns.local_addr();
    let stop = ns.shutdown_handle();
    tokio::spawn(ns.serve());
    (
        yarp_net::nameserver::NameClient::new(addr).with_timeout(T),
        stop,
    )
}

/// Starts a gateway for the mapping text `toml` in `domain`, DDS on loopback only.
pub async fn gateway(
    toml: &str,
    ns: &yarp_net::nameserver::NameClient,
    domain: u16,
) -> yarp_ros2_gateway::gateway::Gateway {
    std::env::set_var("ROS_DISTRO", "kilted");
    let m = yarp_ros2_gateway::mapping::Mappings::parse(toml, std::path::Path::new("test.toml"))
        .expect("test mapping");
    let opt = yarp_ros2_gateway::gateway::Options {
        domain_id: domain,
        networks: vec!["127.0.0.1".parse().unwrap()],
        ..Default::default()
    };
    yarp_ros2_gateway::gateway::Gateway::start(&m, ns.clone(), opt)
        .await
        .expect("gateway starts")
}

/// Repeats `step` every `every` until `done` yields a value (bounded by `T`).
pub async fn repeat_until<R>(
    what: &str,
    every: Duration,
    mut step: impl AsyncFnMut(),
    mut done: impl FnMut() -> Option<R>,
) -> R {
    let end = Instant::now() + T;
    loop {
        step().await;
        if let Some(r) = done() {
            return r;
        }
        assert!(Instant::now() < end, "timed out waiting for {what}");
        tokio::time::sleep(every).await;
    }
}

/// A process-wide YARP name server for tests that open `yarp-devices` devices, which find
/// it through `yarp.conf`: `YARP_CONFIG_HOME` points at a directory private to this test
/// process. Runs on its own runtime so that it outlives every test's runtime.
pub fn device_name_server() -> yarp_net::nameserver::NameClient {
    use std::sync::OnceLock;
    static NS: OnceLock<(std::net::SocketAddr, tokio::runtime::Runtime)> = OnceLock::new();
    let (addr, _) = NS.get_or_init(|| {
        let dir = yarp_interop_tests::process_dir("gw-test-yarp");
        std::env::set_var("YARP_CONFIG_HOME", &dir);
        // Built on a plain thread: tests call this from inside their own runtime.
        let (addr, rt) = std::thread::spawn(|| {
            let rt = tokio::runtime::Builder::new_multi_thread()
                .worker_threads(1)
                .enable_all()
                .build()
                .expect("name-server runtime");
            let addr = rt.block_on(async {
                let ns = yarp_interop_tests::bind_name_server().await;
                let addr = ns.local_addr();
                tokio::spawn(ns.serve());
                addr
            });
            (addr, rt)
        })
        .join()
        .expect("name-server thread");
        yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("write yarp.conf");
        (addr, rt)
    });
    yarp_net::nameserver::NameClient::new(*addr).with_timeout(T)
}

/// Opens a `yarp-devices` device from configuration text (name server from
/// [`device_name_server`]); panics with the device's error.
pub fn open_device(text: &str) -> yarp_devices::PolyDriver {
    device_name_server();
    let prop = yarp_proto::Property::from_config_text(text).expect("device config");
    yarp_devices::PolyDriver::open(&prop).unwrap_or_else(|e| panic!("open {text:?}: {e}"))
}

/// Runs blocking device calls off the async runtime.
pub async fn blocking<R: Send + 'static>(f: impl FnOnce() -> R + Send + 'static) -> R {
    tokio::task::spawn_blocking(f).await.expect("blocking task")
}

/// Calls the YARP RPC port `port` as `me` with `cmd` (a connection per call, each reply
/// awaited up to `within`) until the reply does not say `unanswered`: the gateway answers
/// so until DDS discovery has matched the ROS side, which can take a while on a loaded
/// machine. After 2 T the last reply is returned as it is.
pub async fn rpc_until_answered(
    ns: &yarp_net::nameserver::NameClient,
    port: &str,
    me: &str,
    cmd: &str,
    unanswered: &str,
    within: Duration,
) -> yarp_proto::Bottle {
    let contact = ns
        .query(port)
        .await
        .unwrap()
        .expect("gateway port registered");
    let deadline = tokio::time::Instant::now() + 2 * T;
    loop {
        let mut c = yarp_net::rpc::RpcClient::connect(&contact, me, yarp_proto::wire::Carrier::Tcp)
            .await
            .unwrap();
        let reply = tokio::time::timeout(within, c.call(&yarp_proto::Bottle::from_text(cmd)))
            .await
            .expect("reply in time")
            .unwrap();
        c.close().await;
        if !reply.to_string().contains(unanswered) || tokio::time::Instant::now() > deadline {
            return reply;
        }
        eprintln!("{port}: {reply}; asking again");
    }
}
