//! C++ YARP tools (3.12.3, from `tests/peers/install-cpp-peers.sh icub` or `YARP_CPP_BIN`) against
//! our frameGrabber_nws_yarp + fakeFrameGrabber: `yarp rpc` must print what it printed
//! against C++ 3.12 in framegrabber.jsonl, and `yarp read ... envelope` must read our
//! image stream. Without a C++ YARP the tests say SKIPPED loudly (in CI: fail). Run under
//! netns-run.

mod framegrabber_common;

use framegrabber_common::{cpp_client_chain, cpp_grabber, grabber};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
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

/// The test process's name server (the shared one, which the C++ programs also use).
fn name_client() -> NameClient {
    yarp_interop_tests::name_client().with_timeout(WAIT)
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
        let found = runtime::block_on(async move { ns.query("/rd").await.ok().flatten() })
            .expect("the device runtime");
        if found.is_some() {
            break;
        }
        assert!(start.elapsed() < WAIT, "C++ yarp read did not register");
        std::thread::sleep(Duration::from_millis(20));
    }
    // C++ registers the name before its port listens: connect once it accepts.
    loop {
        let ns = ns.clone();
        let (ok, msg) =
            runtime::block_on(
                async move { yarp_net::network::connect(&ns, "/cam", "/rd", None).await },
            )
            .expect("the device runtime")
            .expect("connect");
        if ok {
            break;
        }
        assert!(start.elapsed() < WAIT, "{msg}");
        std::thread::sleep(Duration::from_millis(50));
    }
    let stdout = child.0.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    // C++ 3.12.3 prints `<count> <time, 4 decimals>     <data>` on one line
    let mut seen = 0;
    let mut other = Vec::new();
    let start = Instant::now();
    while seen < 2 {
        assert!(
            start.elapsed() < WAIT,
            "no image lines; yarp read printed {other:?}"
        );
        let line = rx.recv_timeout(WAIT).expect("yarp read printed nothing");
        let Some((env, data)) = line.split_once("     ") else {
            other.push(line);
            continue;
        };
        let mut e = env.split(' ');
        assert_eq!(e.next(), Some(seen.to_string().as_str()), "{env}");
        let t = e.next().unwrap();
        assert_eq!(t.split_once('.').map(|(_, f)| f.len()), Some(4), "{env}");
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_secs_f64();
        let t: f64 = t.parse().unwrap();
        assert!((now - t).abs() < 60.0, "{env}: not a stamp of now");
        let img = Image::from_bottle(&Bottle::from_text(data)).expect("an image");
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

/// The `Response` lines of a C++ `yarp rpc` session, made comparable.
fn responses(out: &str) -> Vec<String> {
    out.lines()
        .filter(|l| l.starts_with("Response"))
        .map(comparable)
        .collect()
}

/// C++ `frameGrabber_nwc_yarp` reads our `frameGrabber_nws_yarp`. C++ has no command-line
/// frame grabber client, so C++'s own `frameGrabber_nws_yarp` wraps the C++ client
/// (attached to it in C++ `yarprobotinterface`, see `cpp_yarpdev`): its
/// images are the ones the C++ client read from ours, and each `yarp rpc` line at it is a
/// call of the C++ client answered by ours. The same session over C++'s
/// `frameGrabber_nws_yarp` + `fakeFrameGrabber` must print the same.
#[test]
fn cpp_frame_grabber_client_reads_ours() {
    let test = "cpp_frame_grabber_client_reads_ours";
    let Some(bin) = yarp_interop_tests::cpp_devices(
        test,
        &[
            "frameGrabber_nws_yarp",
            "frameGrabber_nwc_yarp",
            "fakeFrameGrabber",
        ],
    ) else {
        return;
    };
    let cases = recorded_rpc().expect("../shared/yarp-vectors/framegrabber.jsonl");
    let input: String = cases.iter().map(|(t, _)| format!("{t}\n")).collect();
    let mut ours = grabber("/fg_ours");
    let _chain_ours = cpp_client_chain(&bin, "/fg_chain_ours", "/fg_ours");
    let yarp = bin.join("yarp");
    let over_ours = responses(&yarp_interop_tests::cpp_rpc_output(
        &yarp,
        "/fg_chain_ours/rpc",
        &input,
    ));
    let _cpp = cpp_grabber(&bin, "/fg_cpp", "0.1");
    let _chain_cpp = cpp_client_chain(&bin, "/fg_chain_cpp", "/fg_cpp");
    let over_cpp = responses(&yarp_interop_tests::cpp_rpc_output(
        &yarp,
        "/fg_chain_cpp/rpc",
        &input,
    ));
    assert_eq!(over_cpp.len(), cases.len(), "C++ reference: {over_cpp:#?}");
    let mut bad = Vec::new();
    for (((text, _), o), c) in cases.iter().zip(&over_ours).zip(&over_cpp) {
        let verdict = if o == c { "ok" } else { "DIFFERS" };
        eprintln!("{verdict:7} {text:40} {o}");
        if o != c {
            bad.push(format!("`{text}`: over ours {o:?}, over C++ {c:?}"));
        }
    }
    assert_eq!(over_ours.len(), cases.len(), "over ours: {over_ours:#?}");
    assert!(
        bad.is_empty(),
        "{} rows differ:\n{}",
        bad.len(),
        bad.join("\n")
    );

    // the C++ client's images, republished by C++'s wrapper, are ours (8x6 RGB)
    let reader = Reaped(
        yarp_interop_tests::cpp_command(&yarp)
            .args(["read", "/fg_rd", "/fg_chain_ours"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("C++ yarp read"),
    );
    let mut reader = reader;
    let stdout = reader.0.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < WAIT, "no image from the C++ chain");
        let Ok(line) = rx.recv_timeout(WAIT) else {
            continue;
        };
        if line.starts_with("[mat] [rgb] (3 144 65544 8 6) {") {
            break;
        }
    }
    ours.close().unwrap();
}

/// Our `frameGrabber_nwc_yarp` reads C++'s `frameGrabber_nws_yarp` + `fakeFrameGrabber`.
#[test]
fn our_frame_grabber_client_reads_cpp() {
    let test = "our_frame_grabber_client_reads_cpp";
    let Some(bin) =
        yarp_interop_tests::cpp_devices(test, &["frameGrabber_nws_yarp", "fakeFrameGrabber"])
    else {
        return;
    };
    name_client();
    let _cpp = cpp_grabber(&bin, "/fgr_cpp", "0.05");
    let mut client = PolyDriver::open(
        &Property::from_config_text(
            "device frameGrabber_nwc_yarp\nremote /fgr_cpp\nlocal /fgr_ours\n",
        )
        .unwrap(),
    )
    .expect("our client opens against C++");
    let d = client.device();
    let fg = d.as_frame_grabber_image().expect("IFrameGrabberImage");
    let start = Instant::now();
    let img = loop {
        if let Ok(img) = fg.get_image() {
            if img.width() > 0 {
                break img;
            }
        }
        assert!(start.elapsed() < WAIT, "no image from C++");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!((img.width(), img.height()), (8, 6));
    // the size of the images read, as C++'s client reports it
    assert_eq!((fg.width(), fg.height()), (8, 6));
    client.close().unwrap();
}
