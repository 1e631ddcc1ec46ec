//! Shared set-up for the control-board tests: one in-process name server per test
//! process, announced through a private `yarp.conf` (YARP_CONFIG_HOME), plus small
//! helpers. Every wait is bounded.
#![allow(dead_code)]

use tokio::io::AsyncReadExt;
use tokio::net::TcpStream;
#[allow(unused_imports)] // each test binary uses its own subset
pub use yarp_interop_tests::{name_client, wait_for, T};

/// Runs `fut` on the device runtime (with a time limit) and returns its output.
pub fn run<F>(fut: F) -> F::Output
where
    F: std::future::Future + Send + 'static,
    F::Output: Send + 'static,
{
    yarp_devices::runtime::block_on(async move {
        tokio::time::timeout(T, fut).await.expect("timed out")
    })
    .expect("the device runtime")
}

/// Reads one tcp-family message (index + blocks) and returns the concatenated blocks.
pub async fn read_message(s: &mut TcpStream) -> Vec<u8> {
    let mut head = [0u8; 18];
    s.read_exact(&mut head).await.unwrap();
    assert_eq!(&head[..8], &hex::decode("59410a0000005250").unwrap()[..]);
    let n_blocks = head[8] as usize;
    assert_eq!(&head[9..], &hex::decode("01ffffffffffffffff").unwrap()[..]);
    let mut lens = vec![0u8; 4 * (n_blocks + 1)];
    s.read_exact(&mut lens).await.unwrap();
    let total: usize = lens[..4 * n_blocks]
        .chunks(4)
        .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize)
        .sum();
    assert_eq!(&lens[4 * n_blocks..], &[0, 0, 0, 0], "reply length slot");
    let mut body = vec![0u8; total];
    s.read_exact(&mut body).await.unwrap();
    body
}

/// The recorded control-board vectors (panics clearly when `../shared` is missing: the
/// vector tests must never be skipped).
pub fn records() -> Option<Vec<serde_json::Value>> {
    Some(yarp_interop_tests::load_records("controlboard.jsonl"))
}

pub fn hex(v: &serde_json::Value) -> Vec<u8> {
    hex::decode(v.as_str().expect("hex string")).expect("hex")
}

/// Same structure: element types recursively, vocabs and strings equal; numbers are
/// compared by type only.
pub fn same_shape(a: &yarp_proto::Value, b: &yarp_proto::Value) -> bool {
    use yarp_proto::Value;
    if a.tag() != b.tag() {
        return false;
    }
    match (a, b) {
        (Value::Vocab32(x), Value::Vocab32(y)) => x == y,
        (Value::String(x), Value::String(y)) => x == y,
        (Value::List(x), Value::List(y)) => same_bottle(x, y),
        _ => true,
    }
}

/// `same_shape` for whole Bottles.
pub fn same_bottle(a: &yarp_proto::Bottle, b: &yarp_proto::Bottle) -> bool {
    a.len() == b.len() && a.iter().zip(b.iter()).all(|(x, y)| same_shape(x, y))
}

/// `got` with the values of its `[tsta] <count> <time>` taken from `want` (the stamp
/// varies by run), so that the rest can be compared byte for byte.
pub fn with_recorded_stamps(
    got: &yarp_proto::Bottle,
    want: &yarp_proto::Bottle,
) -> yarp_proto::Bottle {
    use yarp_proto::{Value, Vocab32};
    let mut out = got.clone();
    let tsta = Value::Vocab32(Vocab32::new("tsta"));
    if let Some(i) = got.iter().position(|v| *v == tsta) {
        if want.get(i) == Some(&tsta) {
            for k in [i + 1, i + 2] {
                if let (Some(slot), Some(w)) = (out.get_mut(k), want.get(k)) {
                    *slot = w.clone();
                }
            }
        }
    }
    out
}

/// Our `controlBoard_nws_yarp` named `name` over our `fakeMotionControl` (4 joints).
pub fn our_board(name: &str) -> yarp_devices::PolyDriver {
    name_client();
    yarp_devices::PolyDriver::open(
        &yarp_proto::Property::from_config_text(format!(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname {name}\n\
             period 0.01\n[GENERAL]\njoints 4\n"
        ))
        .unwrap(),
    )
    .expect("open our wrapper")
}

/// C++ `controlBoard_nws_yarp` (of the peer in `bin`, 3.12 or 4.0) named `name` over
/// its `fakeMotionControl` (4 joints).
pub fn cpp_board(bin: &std::path::Path, name: &str) -> yarp_interop_tests::Reaped {
    yarp_interop_tests::cpp_yarpdev(
        bin,
        &[
            "--device",
            "controlBoard_nws_yarp",
            "--subdevice",
            "fakeMotionControl",
            "--name",
            name,
            "--period",
            "0.01",
            "--GENERAL::Joints",
            "4",
        ],
        &format!("{name}/stateExt:o"),
    )
}

/// Waits for `child` at most `T`, killing it if it is still running; returns its stdout.
pub fn finish(mut child: std::process::Child) -> String {
    let mut stdout = child.stdout.take().expect("piped stdout");
    let reader = std::thread::spawn(move || {
        let mut out = String::new();
        let _ = std::io::Read::read_to_string(&mut stdout, &mut out);
        out
    });
    let start = std::time::Instant::now();
    while child.try_wait().expect("try_wait").is_none() {
        // the paced method table takes ~10 s itself; a loaded machine slows C++ too
        if start.elapsed() > 6 * T {
            let _ = child.kill();
            let _ = child.wait();
            panic!("C++ program did not finish within {:?}", 6 * T);
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    reader.join().unwrap_or_default()
}
