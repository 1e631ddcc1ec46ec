//! The C++ `yarp rpc` tool (YARP 3.5 from `tests/peers/install-cpp-yarp.sh`, or the
//! directory in `YARP_CPP_BIN`) against our multipleanalogsensorsserver: it must print
//! exactly what it printed against C++ 3.12 in imu.jsonl. Without a C++ YARP the test
//! says SKIPPED loudly and passes. Run under netns-run.

use std::io::{Read, Write};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_net::nameserver::NameServer;
use yarp_proto::Property;

const WAIT: Duration = Duration::from_secs(10);

/// The real C++ `yarp` program (pip installs a Python wrapper beside it).
fn cpp_yarp() -> Option<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("YARP_CPP_BIN") {
        dirs.push(PathBuf::from(d));
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../.venv-yarp");
    if let Ok(libs) = std::fs::read_dir(venv.join("lib")) {
        for d in libs.flatten() {
            dirs.push(d.path().join("site-packages/yarp/bin"));
        }
    }
    dirs.push(venv.join("bin"));
    dirs.into_iter()
        .map(|d| d.join("yarp"))
        .find(|p| p.is_file())
}

/// Kills and reaps the child when dropped.
struct Reaped(Child);
impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn name_server() -> SocketAddr {
    static NS: OnceLock<(SocketAddr, tempfile::TempDir)> = OnceLock::new();
    NS.get_or_init(|| {
        let dir = tempfile::tempdir().expect("temp dir");
        std::env::set_var("YARP_CONFIG_HOME", dir.path());
        let addr = yarp_devices::runtime::block_on(async {
            let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
                .await
                .expect("bind name server");
            let addr = ns.local_addr();
            tokio::spawn(ns.serve());
            addr
        });
        yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("yarp.conf");
        (addr, dir)
    })
    .0
}

fn recorded_rpc() -> Option<Vec<(String, Vec<String>)>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/yarp-vectors/imu.jsonl"
    );
    let text = std::fs::read_to_string(path).ok()?;
    Some(
        text.lines()
            .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
            .filter(|r| r["kind"] == "yarp_rpc")
            .map(|r| {
                let lines = r["stdout_lines"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|l| l.as_str().unwrap().to_string())
                    .collect();
                (r["text_in"].as_str().unwrap().to_string(), lines)
            })
            .collect(),
    )
}

#[test]
fn cpp_yarp_rpc_prints_what_it_printed_against_cpp() {
    let (Some(yarp), Some(cases)) = (cpp_yarp(), recorded_rpc()) else {
        eprintln!("SKIPPED: C++ YARP not found (or no imu.jsonl): sensors_cpp");
        return;
    };
    name_server();
    let mut server = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /imu\nperiod 20\n",
        )
        .unwrap(),
    )
    .expect("server");
    let mut child = Reaped(
        Command::new(&yarp)
            .args(["rpc", "/imu/rpc:o"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("run C++ yarp rpc"),
    );
    let mut stdin = child.0.stdin.take().unwrap();
    for (text_in, _) in &cases {
        writeln!(stdin, "{text_in}").unwrap();
    }
    drop(stdin); // yarp rpc stops at end of input
    let mut stdout = child.0.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stdout.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    while child.0.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < WAIT, "C++ yarp rpc did not finish");
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = reader.join().unwrap();
    let printed: Vec<&str> = out
        .lines()
        .filter(|l| !l.starts_with('[') || l.starts_with("[fail]"))
        .filter(|l| !l.trim().is_empty())
        .collect();
    let want: Vec<&str> = cases
        .iter()
        .flat_map(|(_, lines)| lines.iter().map(String::as_str))
        .collect();
    assert_eq!(printed, want, "full output:\n{out}");
    eprintln!("interop: C++ yarp rpc -> multipleanalogsensorsserver OK");
    server.close().unwrap();
}
