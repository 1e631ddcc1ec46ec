//! Shared helpers for the tests of every crate: the recorded C++ YARP vectors in
//! `../shared/yarp-vectors/`, a name server per test process, the C++ YARP peer, bounded
//! waits and child processes that are always reaped, and the peers of the live tests (C++
//! YARP, rclpy, Chromium) with the rule for when one is missing ([`peer_missing`]).
#![forbid(unsafe_code)]

mod cpp_tools;
pub mod docs;
mod netns;
mod peer;
mod procs;
mod robot_net;
pub use cpp_tools::*;
pub use netns::*;
pub use peer::*;
pub use procs::*;
pub use robot_net::RobotNet;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use yarp_net::nameserver::{NameClient, NameServer};

/// How long any single wait in a test may take.
pub const T: Duration = Duration::from_secs(10);

/// Directory of the recorded vectors: `$YARP_VECTORS_DIR`, else `../shared/yarp-vectors`
/// beside the repository. Panics with a clear message if missing: these tests must never
/// be skipped silently.
pub fn vectors_dir() -> PathBuf {
    let dir = std::env::var_os("YARP_VECTORS_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/yarp-vectors")
        });
    assert!(
        dir.join("README.md").is_file(),
        "YARP vectors not found at {} (set YARP_VECTORS_DIR)",
        dir.display()
    );
    dir
}

/// Loads every record of one `.jsonl` file.
pub fn load_records(file: &str) -> Vec<serde_json::Value> {
    let path = vectors_dir().join(file);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .enumerate()
        .map(|(i, l)| {
            serde_json::from_str(l)
                .unwrap_or_else(|e| panic!("{}:{}: bad JSON: {e}", path.display(), i + 1))
        })
        .collect()
}

/// `target` as the `href` of an `xi:include` in a file of directory `from`. C++
/// yarprobotinterface (and ours, as C++) joins the including file's directory, "/" and the
/// href, so an absolute path is no href: it is spelled from `from` (`../../work/...`).
pub fn include_href(from: &std::path::Path, target: &std::path::Path) -> String {
    if target.is_relative() {
        return target.display().to_string();
    }
    let up = from
        .components()
        .filter(|c| matches!(c, std::path::Component::Normal(_)))
        .count();
    let rest = target.strip_prefix("/").unwrap_or(target);
    format!("{}{}", "../".repeat(up), rest.display())
}

/// Decodes a lowercase hex field.
pub fn hex_field(rec: &serde_json::Value, key: &str) -> Vec<u8> {
    let s = rec[key]
        .as_str()
        .unwrap_or_else(|| panic!("{}: field {key} missing", rec["id"]));
    hex::decode(s).unwrap_or_else(|e| panic!("{}: field {key}: {e}", rec["id"]))
}

/// A record's `id`, for messages.
pub fn id(rec: &serde_json::Value) -> &str {
    rec["id"].as_str().unwrap_or("?")
}

/// Polls `f` every 10 ms until it gives `Some`, at most [`T`] (then panics naming `what`).
pub fn wait_for<R>(what: &str, mut f: impl FnMut() -> Option<R>) -> R {
    let start = Instant::now();
    loop {
        if let Some(r) = f() {
            return r;
        }
        assert!(start.elapsed() < T, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

struct Net {
    addr: SocketAddr,
    _rt: tokio::runtime::Runtime,
}

/// A directory of this test process's own, `<tmp>/<prefix>-<pid>`, for what a `static`
/// keeps for the whole process (statics are never dropped, so a `TempDir` there leaks):
/// on each call the directories of this prefix whose process is gone are removed.
pub fn process_dir(prefix: &str) -> PathBuf {
    let tmp = std::env::temp_dir();
    let me = std::process::id();
    let stem = format!("{prefix}-");
    for entry in std::fs::read_dir(&tmp).into_iter().flatten().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let pid = name.strip_prefix(&stem).and_then(|p| p.parse::<u32>().ok());
        if pid
            .is_some_and(|pid| pid != me && !std::path::Path::new(&format!("/proc/{pid}")).exists())
        {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
    let dir = tmp.join(format!("{stem}{me}"));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}

/// Candidate ports for a test name server (ours or C++ `yarpserver`), below the kernel's
/// ephemeral range: see [`bind_name_server`] for why. A name server hands out numbers
/// from its own port upwards, so two servers whose ports are close give the same
/// numbers to different processes, and a C++ port given a taken one fails with
/// "address conflict". Each candidate is therefore the base of a block of
/// [`PORT_BLOCK`] numbers that this process claims, with a lock file, until it ends;
/// only when every block is taken do candidates fall back to scattered numbers.
pub fn low_ports() -> impl Iterator<Item = u16> {
    let seed = std::process::id() as u64
        ^ std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos() as u64)
            .unwrap_or(0);
    let blocks = (BLOCKS_TO - BLOCKS_FROM) / PORT_BLOCK;
    let first = seed % blocks as u64;
    let claimed = (0..blocks)
        .map(move |i| ((first + i as u64) % blocks as u64) as u16)
        .filter_map(claim_block);
    let mut x = seed | 1;
    let scattered = (0..200).map(move |_| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        BLOCKS_FROM + (x % (BLOCKS_TO - BLOCKS_FROM - 10_000) as u64) as u16
    });
    claimed.chain(scattered)
}

/// Port numbers a test name server may use: its own and what it hands out.
pub const PORT_BLOCK: u16 = 1000;
const BLOCKS_FROM: u16 = 10_000;
/// The kernel's ephemeral range starts at 32768.
const BLOCKS_TO: u16 = 32_000;

/// Holds, for the rest of this process, the block of [`low_ports`] numbers holding
/// `port`: a test that binds fixed ports there (an emulated robot's UDP hubs, 20000+n)
/// keeps other tests' name servers from handing them out. Waits up to two minutes for a
/// process holding it to end; false if it never did.
pub fn hold_port_block(port: u16) -> bool {
    if !(BLOCKS_FROM..BLOCKS_TO).contains(&port) {
        return true;
    }
    let n = (port - BLOCKS_FROM) / PORT_BLOCK;
    let end = Instant::now() + Duration::from_secs(120);
    loop {
        if claim_block(n).is_some() {
            return true;
        }
        if Instant::now() > end {
            return false;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// Claims block `n` for this process (its lock is held until the process ends) and
/// gives its first port number, or `None` when another process holds it.
fn claim_block(n: u16) -> Option<u16> {
    static HELD: std::sync::Mutex<Vec<(u16, std::fs::File)>> = std::sync::Mutex::new(Vec::new());
    let mut held = HELD.lock().unwrap_or_else(|e| e.into_inner());
    // this process's own block (its name server's) is as good as claimed
    if held.iter().any(|(k, _)| *k == n) {
        return Some(BLOCKS_FROM + n * PORT_BLOCK);
    }
    let dir = std::env::temp_dir().join("yarp-rs-test-port-blocks");
    std::fs::create_dir_all(&dir).ok()?;
    let file = std::fs::File::create(dir.join(n.to_string())).ok()?;
    file.try_lock().ok()?;
    held.push((n, file));
    Some(BLOCKS_FROM + n * PORT_BLOCK)
}

/// Binds a name server for a test process on 127.0.0.1 below the kernel's ephemeral
/// port range (32768 and up here). The server hands out port numbers from its own
/// upwards, as `yarpserver` does; from an ephemeral base those numbers collide with the
/// outgoing connections of every test in the namespace, and a C++ port given one fails
/// with "address conflict". The port is the base of a block this process claims
/// ([`low_ports`]), so concurrent test processes hand out numbers apart.
pub async fn bind_name_server() -> NameServer {
    for port in low_ports() {
        if let Ok(ns) = NameServer::bind(("127.0.0.1", port), "127.0.0.1").await {
            return ns;
        }
    }
    NameServer::bind("127.0.0.1:0", "127.0.0.1")
        .await
        .expect("bind name server (run under netns-run)")
}

/// The address of this test process's name server, started on first use on 127.0.0.1
/// and announced through a private `yarp.conf` (`YARP_CONFIG_HOME` points at a temp dir,
/// so child processes and `yarp_net::network::name_client()` find it too).
pub fn name_server() -> SocketAddr {
    static NET: OnceLock<Net> = OnceLock::new();
    NET.get_or_init(|| {
        let dir = process_dir("yarp-rs-test-conf");
        std::env::set_var("YARP_CONFIG_HOME", &dir);
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .expect("name-server runtime");
        let addr = rt.block_on(async {
            let ns = bind_name_server().await;
            let addr = ns.local_addr();
            tokio::spawn(ns.serve());
            addr
        });
        yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("write yarp.conf");
        Net { addr, _rt: rt }
    })
    .addr
}

/// A client of [`name_server`] (starting it if needed).
pub fn name_client() -> NameClient {
    NameClient::new(name_server()).with_timeout(T)
}

/// Spawns `cmd` so that it ends with this test process even when its handle is kept in a
/// `static` (statics are never dropped, so a [`Reaped`] there never runs): it runs under
/// `sh`, which kills it once this process's end of a pipe closes. Keep the returned
/// `ChildStdin` as long as the program should run.
pub fn spawn_tied_to_process(cmd: &Command) -> std::io::Result<(Reaped, ChildStdin)> {
    let mut sh = Command::new("sh");
    sh.arg("-c")
        .arg(r#""$@" & p=$!; read _; kill $p 2>/dev/null; wait $p"#)
        .arg("sh")
        .arg(cmd.get_program())
        .args(cmd.get_args());
    for (k, v) in cmd.get_envs() {
        match v {
            Some(v) => sh.env(k, v),
            None => sh.env_remove(k),
        };
    }
    if let Some(dir) = cmd.get_current_dir() {
        sh.current_dir(dir);
    }
    let mut child = sh
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()?;
    let stdin = child.stdin.take().expect("piped stdin");
    Ok((Reaped(child), stdin))
}

/// A child process killed and reaped when dropped, so no test leaves one behind.
pub struct Reaped(pub Child);

impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}
