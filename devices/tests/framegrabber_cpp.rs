//! C++ YARP tools (3.5, from `tests/peers/install-cpp-yarp.sh` or `YARP_CPP_BIN`) against
//! our frameGrabber_nws_yarp + fakeFrameGrabber: `yarp rpc` must print what it printed
//! against C++ 3.12 in framegrabber.jsonl, and `yarp read ... envelope` must read our
//! image stream. Without a C++ YARP the tests say SKIPPED loudly (in CI: fail). Run under
//! netns-run.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use yarp_devices::framegrabber::Image;
use yarp_devices::{runtime, PolyDriver};
use yarp_net::nameserver::NameClient;
use yarp_proto::{Bottle, Property};

const WAIT: Duration = Duration::from_secs(10);

fn cpp_yarp(test: &str) -> Option<PathBuf> {
    yarp_interop_tests::cpp_program(test, "yarp")
}

/// Kills and reaps the child when dropped.
struct Reaped(Child);
impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn name_client() -> NameClient {
    static NS: OnceLock<(std::net::SocketAddr, tempfile::TempDir)> = OnceLock::new();
    let addr = NS
        .get_or_init(|| {
            let dir = tempfile::tempdir().expect("temp dir");
            std::env::set_var("YARP_CONFIG_HOME", dir.path());
            let addr = runtime::block_on(async {
                let ns = yarp_interop_tests::bind_name_server().await;
                let addr = ns.local_addr();
                tokio::spawn(ns.serve());
                addr
            });
            yarp_net::network::write_conf("127.0.0.1", addr.port()).expect("yarp.conf");
            (addr, dir)
        })
        .0;
    NameClient::new(addr).with_timeout(WAIT)
}

fn grabber(name: &str) -> PolyDriver {
    name_client();
    let cfg = format!(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname {name}\n\
         width 8\nheight 6\nperiod 0.1\n"
    );
    PolyDriver::open(&Property::from_config_text(cfg).unwrap()).expect("server")
}

/// (text typed, lines printed) of every recorded `yarp rpc` case.
fn recorded_rpc() -> Option<Vec<(String, Vec<String>)>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/yarp-vectors/framegrabber.jsonl"
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

/// `[fgc]` replies of the recorded fake carry uninitialised memory: keep the words up
/// to the first number.
fn comparable(line: &str) -> String {
    if !line.starts_with("Response: [fgc]") {
        return line.to_string();
    }
    line.split(' ')
        .take_while(|w| w.starts_with('[') || *w == "Response:")
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn cpp_yarp_rpc_prints_what_it_printed_against_cpp() {
    let cases = recorded_rpc().expect("../shared/yarp-vectors/framegrabber.jsonl");
    let Some(yarp) = cpp_yarp("cpp_yarp_rpc_prints_what_it_printed_against_cpp") else {
        return;
    };
    let mut server = grabber("/grabber");
    let mut child = Reaped(
        Command::new(&yarp)
            .args(["rpc", "/grabber/rpc"])
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
    drop(stdin);
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
    let printed: Vec<String> = out
        .lines()
        .filter(|l| l.starts_with("Response"))
        .map(comparable)
        .collect();
    let want: Vec<String> = cases
        .iter()
        .flat_map(|(_, lines)| lines.iter().map(|l| comparable(l)))
        .collect();
    assert_eq!(printed, want, "full output:\n{out}");
    eprintln!(
        "interop: C++ yarp rpc -> frameGrabber_nws_yarp OK ({} cases)",
        want.len()
    );
    server.close().unwrap();
}

#[test]
fn cpp_yarp_read_reads_our_images() {
    let Some(yarp) = cpp_yarp("cpp_yarp_read_reads_our_images") else {
        return;
    };
    let mut server = grabber("/cam");
    let mut child = Reaped(
        Command::new(&yarp)
            .args(["read", "/rd", "envelope"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("run C++ yarp read"),
    );
    let ns = name_client();
    let start = Instant::now();
    loop {
        let ns = ns.clone();
        let found = runtime::block_on(async move { ns.query("/rd").await.ok().flatten() });
        if found.is_some() {
            break;
        }
        assert!(start.elapsed() < WAIT, "C++ yarp read did not register");
        std::thread::sleep(Duration::from_millis(20));
    }
    let (ok, msg) =
        runtime::block_on(
            async move { yarp_net::network::connect(&ns, "/cam", "/rd", None).await },
        )
        .expect("connect");
    assert!(ok, "{msg}");
    let stdout = child.0.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    // 3.12 prints `<envelope>     <data>` on one line, 3.5 the envelope on a line of
    // its own: accept both
    let mut seen = 0;
    let mut envelope: Option<String> = None;
    let mut other = Vec::new();
    let start = Instant::now();
    while seen < 2 {
        assert!(
            start.elapsed() < WAIT,
            "no image lines; yarp read printed {other:?}"
        );
        let line = rx.recv_timeout(WAIT).expect("yarp read printed nothing");
        let (env, data) = match line.split_once("     ") {
            Some((e, d)) => (e.to_string(), d.to_string()),
            None if line.starts_with("[mat]") => match envelope.take() {
                Some(e) => (e, line.clone()),
                None => continue,
            },
            None => {
                if line
                    .split(' ')
                    .next()
                    .is_some_and(|w| w.parse::<i32>().is_ok())
                {
                    envelope = Some(line.trim().to_string());
                } else {
                    other.push(line);
                }
                continue;
            }
        };
        let mut e = env.split(' ');
        assert_eq!(e.next(), Some(seen.to_string().as_str()), "{env}");
        let t: f64 = e.next().unwrap().parse().unwrap();
        assert!(((t * 1000.0).fract() - 0.42).abs() < 1e-3, "{env}");
        let img = Image::from_bottle(&Bottle::from_text(&data)).expect("an image");
        assert_eq!((img.width(), img.height()), (8, 6));
        assert!(
            data.starts_with("[mat] [rgb] (3 144 65544 8 6) {"),
            "{data}"
        );
        seen += 1;
    }
    eprintln!("interop: C++ yarp read <- frameGrabber_nws_yarp OK");
    server.close().unwrap();
}
