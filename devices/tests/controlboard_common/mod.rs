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
