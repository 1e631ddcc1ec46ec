//! A reader that stops reading (it accepts the connection, answers the header, then never
//! reads again) beside one that keeps reading, for each writing policy of the port types
//! (README "Writers and slow readers"): the writer's queue for the stalled connection
//! stays bounded, the live reader keeps receiving, and removing the stalled connection
//! releases it. Real sockets on loopback, in-process name server; run under netns-run.

use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::time::timeout;
use yarp_net::buffered::BufferedPort;
use yarp_net::nameserver::{NameClient, NameServer};
use yarp_net::port::{Port, OUTPUT_QUEUE, OUTPUT_QUEUE_BYTES};
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::{bottle, Bottle};

const T: Duration = Duration::from_secs(10);

async fn name_server() -> NameClient {
    let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
        .await
        .expect("bind ns");
    let addr = ns.local_addr();
    tokio::spawn(ns.serve());
    NameClient::new(addr).with_timeout(T)
}

/// Registers `name` on a listener that takes one connection, answers its header and
/// never reads again; the accepted socket comes back through the join handle.
async fn stalled_reader(ns: &NameClient, name: &str) -> tokio::task::JoinHandle<TcpStream> {
    let l = TcpListener::bind("127.0.0.1:0").await.expect("bind");
    let port = l.local_addr().expect("addr").port();
    let req = RegisterRequest::explicit(name, "tcp", "127.0.0.1", port);
    ns.register_port(&req, &["127.0.0.1"], 0)
        .await
        .expect("register");
    tokio::spawn(async move {
        let (mut s, _) = l.accept().await.expect("accept");
        let mut head = [0u8; 12];
        s.read_exact(&mut head).await.expect("header");
        let n = u32::from_le_bytes(head[8..12].try_into().expect("4 bytes")) as usize;
        let mut sender = vec![0u8; n];
        s.read_exact(&mut sender).await.expect("sender name");
        s.write_all(&yarp_proto::wire::encode_header_reply(i32::from(port)))
            .await
            .expect("header reply");
        s
    })
}

/// A Bottle of about `kib` KiB.
fn big(kib: usize, i: i32) -> Bottle {
    bottle![i, yarp_proto::Value::Blob(vec![7u8; kib * 1024])]
}

/// Counts what `reader` receives until `stop` says so.
fn count(reader: std::sync::Arc<Port>) -> tokio::task::JoinHandle<usize> {
    tokio::spawn(async move {
        let mut n = 0;
        while let Ok(Some(_)) = timeout(Duration::from_secs(2), reader.read()).await {
            n += 1;
        }
        n
    })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn buffered_port_write_keeps_live_readers_fed_past_a_stalled_one() {
    let ns = name_server().await;
    let w = BufferedPort::open("/st/w", ns.clone())
        .await
        .expect("open w");
    let live = std::sync::Arc::new(Port::open("/st/live", ns.clone()).await.expect("live"));
    let stuck = stalled_reader(&ns, "/st/stuck").await;
    w.connect("/st/stuck", None).await.expect("connect stuck");
    let _stuck = timeout(T, stuck).await.expect("accepted").expect("task");
    w.connect("/st/live", None).await.expect("connect live");
    let got = count(live.clone());

    // 3 s of 64 KiB messages at 200 Hz: the stalled socket fills within the first ~100
    let start = Instant::now();
    let mut sent = 0;
    while start.elapsed() < Duration::from_secs(3) {
        w.write(&big(64, sent));
        sent += 1;
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let got = got.await.expect("counter");
    println!("BufferedPort::write: {sent} written, live reader got {got}");
    // C++ BufferedPort drops for a busy connection instead of waiting for it
    assert!(
        got * 2 > sent as usize,
        "the live reader starved behind the stalled one: {got} of {sent}"
    );
    assert!(w.dropped_writes() < sent as u64 / 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn port_write_nowait_bounds_the_stalled_queue_and_disconnect_frees_it() {
    let ns = name_server().await;
    let w = Port::open("/sn/w", ns.clone()).await.expect("open w");
    let live = std::sync::Arc::new(Port::open("/sn/live", ns.clone()).await.expect("live"));
    let stuck = stalled_reader(&ns, "/sn/stuck").await;
    w.connect("/sn/stuck", None).await.expect("connect stuck");
    let mut stuck = timeout(T, stuck).await.expect("accepted").expect("task");
    w.connect("/sn/live", None).await.expect("connect live");
    let got = count(live.clone());

    let n = 400;
    let mut took = Vec::new();
    for i in 0..n {
        took.push(w.write_nowait(&big(64, i), None));
        tokio::time::sleep(Duration::from_millis(2)).await;
    }
    let got = got.await.expect("counter");
    // the stalled connection takes its queue's worth plus what the sockets hold, then
    // misses the rest; the live one takes all
    let both = took.iter().filter(|&&k| k == 2).count();
    println!("Port::write_nowait: {n} written, {both} taken by both outputs, live got {got}");
    assert!(
        both < OUTPUT_QUEUE + 200,
        "the stalled output kept taking messages: {both} of {n}"
    );
    assert!(got as i32 >= n - 5, "live reader got {got} of {n}");

    // removing the stalled connection ends its task and closes its socket, although the
    // task is stuck in a write that the reader will never let finish
    let fds = open_fds();
    assert!(w.disconnect("/sn/stuck"));
    let start = Instant::now();
    while open_fds() >= fds {
        assert!(
            start.elapsed() < T,
            "the writer still holds the stalled connection"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    drop(stuck.shutdown().await);
}

/// Descriptors open in this process.
fn open_fds() -> usize {
    std::fs::read_dir("/proc/self/fd").map_or(0, |d| d.count())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn large_messages_to_a_stalled_reader_are_bounded_in_bytes() {
    let ns = name_server().await;
    let w = Port::open("/sb/w", ns.clone()).await.expect("open w");
    let live = std::sync::Arc::new(Port::open("/sb/live", ns.clone()).await.expect("live"));
    let stuck = stalled_reader(&ns, "/sb/stuck").await;
    w.connect("/sb/stuck", None).await.expect("connect stuck");
    let _stuck = timeout(T, stuck).await.expect("accepted").expect("task");
    w.connect("/sb/live", None).await.expect("connect live");
    let got = count(live.clone());

    // 2 MiB messages (a 1280x720 rgb image is 2.7 MB): 64 of them would be 128 MiB
    let n = 120;
    let mut both = 0;
    for i in 0..n {
        if w.write_nowait(&big(2048, i), None) == 2 {
            both += 1;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let got = got.await.expect("counter");
    // queued bytes within the budget, plus what the two sockets' buffers hold
    let budget = OUTPUT_QUEUE_BYTES / (2048 * 1024) + 8;
    println!("2 MiB messages: {n} written, the stalled output took {both}, live got {got}");
    assert!(
        both <= budget,
        "the stalled output took {both} messages of 2 MiB (budget {budget})"
    );
    assert!(got as i32 >= n - 5, "live reader got {got} of {n}");
}
