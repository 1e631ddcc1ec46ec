//! Port benchmarks on loopback with an in-process name server: RPC round-trip latency of
//! a 100-byte Bottle, `yarp latency-test`-style round trips (small request, reply carrying
//! a blob of the given size) and one-way streaming throughput.
//!
//! Run (a private loopback-only network namespace):
//!
//! ```text
//! /work/shared/netns-run cargo bench -p yarp-net --bench net [-- <filter>]
//! ```
//!
//! Every case is bounded in count and time; the whole run takes well under two minutes.
//! MB = 10^6 bytes. Round-trip MB/s is `payload / median round trip`, which is how the
//! C++ `yarp latency-test` figures are usually quoted.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_net::nameserver::{NameClient, NameServer};
use yarp_net::port::Port;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Value};

const KB: usize = 1000;
const MB: usize = 1000 * 1000;
/// Upper bound on the time spent measuring one case.
const CASE_TIME: Duration = Duration::from_millis(1500);
/// Bytes moved per streaming case (fewer if the time bound is hit first).
const STREAM_BYTES: usize = 256 * MB;

/// C++ YARP 3.12.3 `yarp latency-test` medians on tcp (from the project issue).
fn cpp_reference(size: usize) -> Option<f64> {
    match size {
        100 => Some(0.15),
        MB => Some(0.91),
        s if s == 8 * MB => Some(9.1),
        _ => None,
    }
}

struct Row {
    case: String,
    carrier: &'static str,
    size: usize,
    n: usize,
    median_ms: Option<f64>,
    p99_ms: Option<f64>,
    mbps: f64,
    note: String,
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// The echo / payload server: `(echo ...)` is answered with itself; `(<frame:int32>
/// <size:int32>)` with `(<frame> <size> {blob of size} <copy seconds:float64>)`, as the
/// C++ latency-test server appends its payload. Replies go back on the same connection
/// when the sender asked for one, otherwise on the server's outputs.
async fn serve(srv: Arc<Port>) {
    let mut blobs: HashMap<usize, Value> = HashMap::new();
    while let Some(mut m) = srv.read().await {
        let Ok(mut b) = m.bottle() else { continue };
        if b.get(0).and_then(Value::as_str) != Some("echo") {
            let size = b.get(1).and_then(Value::as_i64).unwrap_or(0).max(0) as usize;
            let t = Instant::now();
            let blob = blobs
                .entry(size)
                .or_insert_with(|| Value::Blob(vec![b'p'; size]))
                .clone();
            b.push(blob);
            b.push(t.elapsed().as_secs_f64());
        }
        if m.wants_reply() {
            m.reply(b);
        } else {
            drop(m);
            srv.write(&b).await;
        }
    }
}

struct Bench {
    ns: NameClient,
    srv: Arc<Port>,
    next: usize,
    rows: Vec<Row>,
}

impl Bench {
    async fn client(&mut self, carrier: &str) -> Port {
        self.next += 1;
        let name = format!("/bench/client{}", self.next);
        let p = Port::open(&name, self.ns.clone())
            .await
            .expect("open client");
        p.connect("/bench/srv", Some(carrier))
            .await
            .expect("connect client to server");
        if !supports_reply(carrier) {
            self.srv
                .connect(&name, Some(carrier))
                .await
                .expect("connect server back to client");
        }
        p
    }

    async fn done(&self, p: Port) {
        self.srv.disconnect(p.name());
        p.close().await;
    }

    /// One request/response through a port: RPC when the carrier has replies, otherwise
    /// a write and a read of the server's answer on its own connection.
    async fn call(p: &Port, carrier: &str, b: &Bottle) -> Bottle {
        if supports_reply(carrier) {
            p.rpc(b).await.expect("rpc")
        } else {
            p.write(b).await;
            p.read().await.expect("port open").bottle().expect("bottle")
        }
    }

    /// RPC round trip of a 100-byte Bottle echoed by the server.
    async fn rpc_small(&mut self, carrier: &'static str) {
        let p = self.client(carrier).await;
        let b = small_bottle();
        let size = b.encode().len();
        for _ in 0..200 {
            Self::call(&p, carrier, &b).await;
        }
        let mut rtt = Vec::new();
        let start = Instant::now();
        while rtt.len() < 20_000 && start.elapsed() < CASE_TIME {
            let t = Instant::now();
            let r = Self::call(&p, carrier, &b).await;
            rtt.push(t.elapsed().as_secs_f64() * 1e3);
            assert_eq!(r.len(), b.len());
        }
        self.done(p).await;
        let how = if supports_reply(carrier) {
            "Port::rpc"
        } else {
            "write+read"
        };
        self.push_rtt(format!("echo ({how})"), carrier, size, rtt, 0.0);
    }

    /// The same over a direct `RpcClient` (no client port: `yarp rpc`).
    async fn rpc_client_small(&mut self, carrier: Carrier) {
        let c = self.ns.query("/bench/srv").await.unwrap().unwrap();
        let mut cl = RpcClient::connect(&c, "anon_rpc", carrier)
            .await
            .expect("rpc client");
        let b = small_bottle();
        let size = b.encode().len();
        for _ in 0..200 {
            cl.call(&b).await.unwrap();
        }
        let mut rtt = Vec::new();
        let start = Instant::now();
        while rtt.len() < 20_000 && start.elapsed() < CASE_TIME {
            let t = Instant::now();
            cl.call(&b).await.unwrap();
            rtt.push(t.elapsed().as_secs_f64() * 1e3);
        }
        cl.close().await;
        self.push_rtt(
            "echo (RpcClient)".to_string(),
            carrier.name(),
            size,
            rtt,
            0.0,
        );
    }

    /// latency-test style: small request, reply with `size` bytes of blob; the server's
    /// copy time is subtracted as C++ does.
    async fn round_trip(&mut self, carrier: &'static str, size: usize) {
        let p = self.client(carrier).await;
        let max_n = (512 * MB / size).clamp(20, 5000);
        let mut rtt = Vec::new();
        let mut copy_total = 0.0;
        let start = Instant::now();
        let mut frame = 0i32;
        while rtt.len() < max_n && (start.elapsed() < CASE_TIME || rtt.len() < 10) {
            let mut req = Bottle::new();
            req.push(frame);
            req.push(size as i32);
            let t = Instant::now();
            let r = Self::call(&p, carrier, &req).await;
            let el = t.elapsed().as_secs_f64();
            let copy = r.get(3).and_then(Value::as_f64).unwrap_or(0.0);
            let got = r.get(2).and_then(Value::as_bytes).map_or(0, <[u8]>::len);
            assert_eq!(got, size, "payload size");
            // first frames warm up the caches and the server's blob
            if frame >= 3 {
                rtt.push((el - copy) * 1e3);
                copy_total += copy;
            }
            frame += 1;
        }
        self.done(p).await;
        let n = rtt.len().max(1) as f64;
        self.push_rtt(
            "round trip (reply = blob)".to_string(),
            carrier,
            size,
            rtt,
            copy_total / n * 1e3,
        );
    }

    /// One-way streaming: a writer port sends `(blob)` messages to a reader port as fast
    /// as the output queue takes them; MB/s at the reader.
    async fn stream(&mut self, carrier: &'static str, size: usize) {
        self.next += 1;
        let wname = format!("/bench/w{}", self.next);
        let rname = format!("/bench/r{}", self.next);
        let w = Port::open(&wname, self.ns.clone()).await.unwrap();
        let r = Arc::new(Port::open(&rname, self.ns.clone()).await.unwrap());
        // the writer shares its Bottle (no copy per write); `local+copy` lends it instead,
        // as `write(&Bottle)` does, to show the cost of the one copy that makes
        let (carrier_name, copy) = match carrier.strip_suffix("+copy") {
            Some(c) => (c, true),
            None => (carrier, false),
        };
        w.connect(&rname, Some(carrier_name)).await.unwrap();
        let mut msg = Bottle::new();
        msg.push(Value::Blob(vec![b'p'; size]));
        let msg = Arc::new(msg);
        // warm up
        for _ in 0..3 {
            w.write_shared(msg.clone(), None).await;
            r.read().await.unwrap();
        }
        let n_max = (STREAM_BYTES / size).clamp(16, 50_000);
        // the writer tells the reader how many messages to wait for once it knows
        let (target_tx, mut target_rx) = tokio::sync::watch::channel(usize::MAX);
        let reader = {
            let r = r.clone();
            tokio::spawn(async move {
                let mut n = 0usize;
                let mut last = Instant::now();
                let work = async {
                    while n < *target_rx.borrow() {
                        tokio::select! {
                            m = r.read() => {
                                if m.is_none() { break }
                                n += 1;
                                last = Instant::now();
                            }
                            _ = target_rx.changed() => {}
                        }
                    }
                };
                let _ = tokio::time::timeout(Duration::from_secs(20), work).await;
                (n, last)
            })
        };
        let start = Instant::now();
        let mut sent = 0usize;
        while sent < n_max && start.elapsed() < CASE_TIME {
            // waits for room in the output queue instead of dropping
            sent += if copy {
                w.write_strict(&msg, None).await
            } else {
                w.write_shared(msg.clone(), None).await
            };
        }
        let _ = target_tx.send(sent);
        let (n, end) = reader.await.unwrap();
        let secs = end.duration_since(start).as_secs_f64();
        w.close().await;
        if let Ok(r) = Arc::try_unwrap(r) {
            r.close().await;
        }
        let mbps = (n * size) as f64 / secs / MB as f64;
        self.rows.push(Row {
            case: "stream one-way (blob)".to_string(),
            carrier,
            size,
            n,
            median_ms: None,
            p99_ms: None,
            mbps,
            note: format!(
                "sent {sent}, {:.3} ms/msg ({})",
                secs * 1e3 / n.max(1) as f64,
                if copy {
                    "Port::write_strict, one copy"
                } else {
                    "Port::write_shared"
                }
            ),
        });
    }

    fn push_rtt(
        &mut self,
        case: String,
        carrier: &'static str,
        size: usize,
        mut rtt: Vec<f64>,
        copy_ms: f64,
    ) {
        rtt.sort_by(f64::total_cmp);
        let median = percentile(&rtt, 0.5);
        let p99 = percentile(&rtt, 0.99);
        let mut note = String::new();
        if copy_ms > 0.0005 {
            note.push_str(&format!("server copy {copy_ms:.3} ms subtracted; "));
        }
        if let Some(cpp) = cpp_reference(size) {
            note.push_str(&format!(
                "C++ 3.12.3 tcp median {cpp} ms ({:.2}x)",
                cpp / median
            ));
        }
        self.rows.push(Row {
            case,
            carrier,
            size,
            n: rtt.len(),
            median_ms: Some(median),
            p99_ms: Some(p99),
            mbps: size as f64 / (median / 1e3) / MB as f64,
            note,
        });
    }
}

impl Bench {
    /// One memcpy of `size` bytes between two buffers already in memory: the ceiling of a
    /// carrier that copies (shmem copies twice, into the ring and out of it, overlapped).
    fn memcpy(&mut self, size: usize) {
        let src = vec![b'p'; size];
        let mut dst = vec![0u8; size];
        dst.copy_from_slice(&src);
        let mut times = Vec::new();
        let start = Instant::now();
        while times.len() < 200 && start.elapsed() < CASE_TIME {
            let t = Instant::now();
            dst.copy_from_slice(std::hint::black_box(&src));
            std::hint::black_box(&mut dst);
            times.push(t.elapsed().as_secs_f64() * 1000.0);
        }
        times.sort_by(f64::total_cmp);
        let med = percentile(&times, 0.5);
        self.rows.push(Row {
            case: "memcpy (reference)".to_string(),
            carrier: "-",
            size,
            n: times.len(),
            median_ms: Some(med),
            p99_ms: Some(percentile(&times, 0.99)),
            mbps: size as f64 / (med / 1000.0) / MB as f64,
            note: String::new(),
        });
    }
}

fn supports_reply(carrier: &str) -> bool {
    carrier == "local" || Carrier::from_name(carrier).is_some_and(|c| c.spec().supports_reply)
}

/// `("echo" <int32> <float64> "<64 bytes>")`: 100 bytes encoded.
fn small_bottle() -> Bottle {
    let mut b = Bottle::new();
    b.push("echo");
    b.push(7i32);
    b.push(0.5f64);
    b.push("x".repeat(52));
    b
}

fn fmt_size(s: usize) -> String {
    if s >= MB && (s / MB) * MB == s {
        format!("{} MB", s / MB)
    } else if s >= KB && (s / KB) * KB == s {
        format!("{} KB", s / KB)
    } else {
        format!("{s} B")
    }
}

fn opt(x: Option<f64>) -> String {
    x.map_or("-".to_string(), |v| format!("{v:.3}"))
}

fn main() {
    if std::env::var_os("YARP_RUNTIME_DIR").is_none() {
        // unix_stream sockets go here (netns-run may leave USER unset)
        std::env::set_var(
            "YARP_RUNTIME_DIR",
            std::env::temp_dir().join("yarp-rs-bench"),
        );
    }
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with("--"));
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let total = Instant::now();
    let rows = rt.block_on(async {
        let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
            .await
            .expect("bind name server (run under netns-run)");
        let addr = ns.local_addr();
        let stop = ns.shutdown_handle();
        tokio::spawn(ns.serve());
        let client = NameClient::new(addr).with_timeout(Duration::from_secs(10));
        let srv = Arc::new(Port::open("/bench/srv", client.clone()).await.unwrap());
        tokio::spawn(serve(srv.clone()));
        let mut b = Bench {
            ns: client,
            srv,
            next: 0,
            rows: Vec::new(),
        };
        let want = |name: &str| match filter.as_deref() {
            None => true,
            Some(f) => name.contains(f),
        };
        for carrier in ["tcp", "fast_tcp", "text_ack", "text"] {
            if want(&format!("rpc {carrier}")) {
                b.rpc_small(carrier).await;
            }
        }
        for carrier in [Carrier::Tcp, Carrier::TextAck] {
            if want(&format!("rpcclient {}", carrier.name())) {
                b.rpc_client_small(carrier).await;
            }
        }
        for carrier in ["tcp", "fast_tcp", "shmem", "local"] {
            for size in [KB, 64 * KB, MB, 8 * MB] {
                if want(&format!("rtt {carrier} {size}")) {
                    b.round_trip(carrier, size).await;
                }
            }
        }
        if want("rtt text 1000") {
            b.round_trip("text", KB).await;
        }
        for carrier in [
            "tcp",
            "fast_tcp",
            "udp",
            "unix_stream",
            "shmem",
            "local",
            "local+copy",
        ] {
            for size in [KB, 64 * KB, MB, 8 * MB] {
                if want(&format!("stream {carrier} {size}")) {
                    b.stream(carrier, size).await;
                }
            }
        }
        if want("stream text 1000") {
            b.stream("text", KB).await;
        }
        if want("memcpy") {
            b.memcpy(8 * MB);
        }
        stop.shutdown();
        b.rows
    });
    println!(
        "\n{:<27} {:<9} {:>6} {:>6} {:>10} {:>9} {:>9}  notes",
        "case", "carrier", "size", "n", "median ms", "p99 ms", "MB/s"
    );
    for r in &rows {
        println!(
            "{:<27} {:<9} {:>6} {:>6} {:>10} {:>9} {:>9.1}  {}",
            r.case,
            r.carrier,
            fmt_size(r.size),
            r.n,
            opt(r.median_ms),
            opt(r.p99_ms),
            r.mbps,
            r.note
        );
    }
    println!("\ntotal {:.1} s", total.elapsed().as_secs_f64());
}
