//! C++ YARP 4.0.0 renumbered the float tags of binary Bottles (`FLOAT64` 20, `FLOAT32`
//! 10, which was 3's `FLOAT64`; `VOCAB64` 18 is new), so a 3.12 reader misreads its
//! floats. Live against C++ 4.0's `yarp` (tests/peers/install-cpp-peers.sh yarp4), under
//! our name server: what it writes reads here with its values and the bytes we would write
//! for a 4.0 peer, and its RPCs get their replies numbered as they asked.
//! Run under ../shared/netns-run.

use std::io::Write;
use std::process::Stdio;
use yarp_interop_tests::*;
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::Bottle;

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .expect("runtime")
}

/// Lines whose floats need the new tags: scalars, a compacted list of doubles, a mixed one.
const LINES: [&str; 3] = [
    "1 2.5 hello [ok] (3.25 4)",
    "(0.5 -1.25 1e+300)",
    "[is] [enc] 0.125 [tsta] 7 1795000000.5 [ok]",
];

#[test]
fn what_cpp_4_writes_reads_here_with_its_floats_and_our_4_0_bytes() {
    let test = "what_cpp_4_writes_reads_here_with_its_floats_and_our_4_0_bytes";
    let Some(yarp) = cpp4_program(test, "yarp") else {
        return;
    };
    let rt = runtime();
    let port = rt
        .block_on(Port::open("/y4/in", name_client()))
        .expect("open /y4/in");
    let (_writer, mut stdin) = cpp_writer(&yarp, "/y4/w", "/y4/in");
    for line in LINES {
        writeln!(stdin, "{line}").unwrap();
    }
    stdin.flush().unwrap();
    for line in LINES {
        let msg = rt
            .block_on(async { tokio::time::timeout(3 * T, port.read()).await })
            .unwrap_or_else(|_| panic!("nothing from C++ 4.0 yarp write for `{line}`"))
            .expect("port open");
        let want = Bottle::from_text(line);
        assert_eq!(msg.bottle().unwrap(), want, "`{line}`");
        assert_eq!(msg.generation(), Generation::V4, "`{line}`");
        assert_eq!(
            msg.payload,
            want.encode_as(Generation::V4),
            "bytes of `{line}`"
        );
        assert_ne!(
            msg.payload,
            want.encode(),
            "3.12's bytes of `{line}` differ"
        );
    }
    drop(stdin);
    rt.block_on(port.close());
}

#[test]
fn cpp_4_rpc_gets_its_reply_numbered_as_it_asked() {
    let test = "cpp_4_rpc_gets_its_reply_numbered_as_it_asked";
    let Some(yarp) = cpp4_program(test, "yarp") else {
        return;
    };
    let rt = runtime();
    let port = std::sync::Arc::new(
        rt.block_on(Port::open("/y4/rpc", name_client()))
            .expect("open /y4/rpc"),
    );
    let server = port.clone();
    rt.spawn(async move {
        while let Some(mut msg) = server.read().await {
            let mut reply = msg.bottle().unwrap_or_default();
            reply
                .push(0.125)
                .push(vec![1.5, 2.5].into_iter().collect::<Bottle>());
            msg.reply(reply);
        }
    });
    let out = cpp_rpc_output(&yarp, "/y4/rpc", "1 2.5\n");
    println!("C++ 4.0 yarp rpc printed:\n{out}");
    assert!(
        out.contains("Response: 1 2.5 0.125 (1.5 2.5)"),
        "C++ 4.0 yarp rpc printed:\n{out}"
    );
    let port = std::sync::Arc::try_unwrap(port).ok();
    if let Some(p) = port {
        rt.block_on(p.close());
    }
}

/// Our port `name`, writing `b` every 20 ms (while C++ readers connect) until the task
/// is aborted.
fn keep_writing(
    rt: &tokio::runtime::Runtime,
    name: &str,
    b: Bottle,
) -> tokio::task::JoinHandle<()> {
    let port = rt
        .block_on(Port::open(name, name_client()))
        .unwrap_or_else(|e| panic!("open {name}: {e}"));
    rt.spawn(async move {
        loop {
            port.write_nowait(&b, None);
            tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        }
    })
}

/// C++ `yarp write <from> <to>` of the `yarp` program given: what is written to the
/// returned stdin, a line at a time, goes out as Bottles.
fn cpp_writer(yarp: &std::path::Path, from: &str, to: &str) -> (Reaped, std::process::ChildStdin) {
    let mut writer = cpp_command(yarp)
        .args(["write", from, to])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn C++ yarp write");
    let stdin = writer.stdin.take().unwrap();
    (Reaped(writer), stdin)
}

/// Starts `yarp read <port>` of the C++ `yarp` program given and waits for its port.
fn cpp_reader(yarp: &std::path::Path, port: &str) -> Reaped {
    name_client();
    let child = cpp_command(yarp)
        .args(["read", port])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn C++ yarp read");
    let child = Reaped(child);
    let start = std::time::Instant::now();
    while !registered(port) {
        assert!(start.elapsed() < T, "{port} never registered");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child
}

/// A server tells its clients' generations by their ports' admin (`getPid`, which 4.0
/// no longer answers): C++ 3.12's, C++ 4.0's and ours.
#[test]
fn peer_generations_of_cpp_3_12_cpp_4_and_our_ports() {
    let test = "peer_generations_of_cpp_3_12_cpp_4_and_our_ports";
    let (Some(yarp3), Some(yarp4)) = (cpp_program(test, "yarp"), cpp4_program(test, "yarp")) else {
        return;
    };
    let _r3 = cpp_reader(&yarp3, "/gen/r3");
    let _r4 = cpp_reader(&yarp4, "/gen/r4");
    let rt = runtime();
    let ours = rt
        .block_on(Port::open("/gen/ours", name_client()))
        .expect("open /gen/ours");
    let peers = yarp_net::peer_generation::PeerGenerations::new(name_client());
    rt.block_on(async {
        assert_eq!(peers.of("/gen/r3").await, Generation::V3);
        assert_eq!(peers.of("/gen/r4").await, Generation::V4);
        assert_eq!(peers.of("/gen/ours").await, Generation::V3);
        // known without asking again; unknown ports are 3's
        assert_eq!(peers.known("/gen/r4"), Some(Generation::V4));
        assert_eq!(peers.of("/gen/nobody").await, Generation::V3);
    });
    rt.block_on(ours.close());
}

/// Our port writing to C++ 4.0's `yarp read`: the connection asked the reader's admin
/// and sends 4.0's float tags, so 4.0 prints the values written (3.12's bytes would
/// misalign it); a C++ 3.12 reader of the same port gets 3.12's bytes.
#[test]
fn cpp_4_and_3_12_readers_each_get_their_floats_from_our_writer() {
    let test = "cpp_4_and_3_12_readers_each_get_their_floats_from_our_writer";
    let (Some(yarp3), Some(yarp4)) = (cpp_program(test, "yarp"), cpp4_program(test, "yarp")) else {
        return;
    };
    let rt = runtime();
    let writer = keep_writing(&rt, "/gen/w", Bottle::from_text(LINES[2]));
    let want = Bottle::from_text(LINES[2]);
    for (yarp, reader) in [(&yarp4, "/gen/rd4"), (&yarp3, "/gen/rd3")] {
        let got = cpp_read_until(yarp, reader, "/gen/w", |l| {
            let b = Bottle::from_text(l);
            (b.len() == want.len() && b.get(0) == want.get(0)).then_some(b)
        });
        assert_eq!(got, want, "read by {reader}");
    }
    writer.abort();
}

/// YARP 4.0's vocab64 (a bracketed word of 5 to 8 characters, as 4.0's text parser makes
/// it) reaches our port as one, in 4.0's bytes; written back by our port to C++ 4.0's
/// reader it prints as typed.
#[test]
fn vocab64_from_cpp_4_and_back() {
    let test = "vocab64_from_cpp_4_and_back";
    let Some(yarp) = cpp4_program(test, "yarp") else {
        return;
    };
    let rt = runtime();
    let port = rt
        .block_on(Port::open("/v64/in", name_client()))
        .expect("open /v64/in");
    let (_writer, mut stdin) = cpp_writer(&yarp, "/v64/w", "/v64/in");
    writeln!(stdin, "[velocity] [ok] 3").unwrap();
    stdin.flush().unwrap();
    let msg = rt
        .block_on(async { tokio::time::timeout(3 * T, port.read()).await })
        .expect("nothing from C++ 4.0 yarp write")
        .expect("port open");
    let want = Bottle::new()
        .with(yarp_proto::Value::vocab64("velocity"))
        .with(yarp_proto::Vocab32::new("ok"))
        .with(3);
    assert_eq!(msg.bottle().unwrap(), want);
    assert_eq!(msg.payload, want.encode_as(Generation::V4));
    drop(stdin);
    rt.block_on(port.close());

    let writing = keep_writing(&rt, "/v64/out", want.clone());
    let line = cpp_read_until(&yarp, "/v64/rd", "/v64/out", |l| {
        l.starts_with("[velocity]").then(|| l.to_string())
    });
    assert_eq!(line, "[velocity] [ok] 3");
    writing.abort();
}

/// YARP 4.0's `throttleDown` monitor and its chains (`file1`/`type1`), our writer to C++
/// 4.0's `yarp read`: our sender-side chain lets one message through every 300 ms and
/// compresses it (`bottle_compression_zlib`), C++ 4.0's receiver expands it, and it prints
/// the counter values we wrote, about 15 apart (one every 20 ms written).
#[test]
fn our_throttled_compressed_chain_to_cpp_4() {
    let test = "our_throttled_compressed_chain_to_cpp_4";
    let Some(yarp) = cpp4_program(test, "yarp") else {
        return;
    };
    let rt = runtime();
    let port = rt
        .block_on(Port::open("/pm4/w", name_client()))
        .expect("open /pm4/w");
    let writing = rt.spawn(async move {
        for n in 0i32.. {
            // (C++'s `yarp read` prints an (int string) pair as a text message)
            port.write_nowait(&Bottle::new().with("counter").with(n), None);
            tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        }
    });
    let chain = "tcp+send.portmonitor+type.dll+file.throttleDown+type1.dll\
                 +file1.bottle_compression_zlib+period_ms.300\
                 +recv.portmonitor+type.dll+file.bottle_compression_zlib";
    let mut seen: Vec<i64> = Vec::new();
    let seen = cpp_read_over(&yarp, "/pm4/r", "/pm4/w", chain, |l| {
        let b = Bottle::from_text(l);
        if b.get(0).and_then(|v| v.as_str()) == Some("counter") {
            seen.push(b.get(1).and_then(|v| v.as_i64()).unwrap());
        }
        (seen.len() == 5).then(|| seen.clone())
    });
    writing.abort();
    let gaps: Vec<i64> = seen.windows(2).map(|w| w[1] - w[0]).collect();
    eprintln!("C++ 4.0 read {seen:?} (gaps {gaps:?})");
    assert!(gaps.iter().all(|g| *g >= 10 && *g <= 30), "{seen:?}");
}

/// C++ 4.0's `yarp write` compresses (`bottle_compression_zlib` on its side), our reader
/// throttles then expands (`+recv.portmonitor+...+file.throttleDown+...+file1.
/// bottle_compression_zlib+period_ms.300`): of the 60 lines written 20 ms apart a few
/// arrive, whole, about 15 apart.
#[test]
fn cpp_4_compressed_to_our_throttled_chain() {
    let test = "cpp_4_compressed_to_our_throttled_chain";
    let Some(yarp) = cpp4_program(test, "yarp") else {
        return;
    };
    let rt = runtime();
    let port = rt
        .block_on(Port::open("/pm4/in", name_client()))
        .expect("open /pm4/in");
    let mut writer = cpp_command(&yarp)
        .args(["write", "/pm4/cw"])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn C++ yarp write");
    let mut stdin = writer.stdin.take().unwrap();
    let _writer = Reaped(writer);
    assert!(
        eventually(T, || registered("/pm4/cw")),
        "/pm4/cw never registered"
    );
    let chain = "tcp+send.portmonitor+type.dll+file.bottle_compression_zlib\
                 +recv.portmonitor+type.dll+file.throttleDown+type1.dll\
                 +file1.bottle_compression_zlib+period_ms.300";
    let (ok, why) = rt
        .block_on(yarp_net::network::connect(
            &name_client(),
            "/pm4/cw",
            "/pm4/in",
            Some(chain),
        ))
        .expect("connect");
    assert!(ok, "{why}");
    for n in 0..60 {
        writeln!(stdin, "{n} line").unwrap();
        stdin.flush().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let mut seen = Vec::new();
    while let Ok(Some(msg)) = rt.block_on(async {
        tokio::time::timeout(std::time::Duration::from_millis(600), port.read()).await
    }) {
        let b = msg.bottle().expect("an expanded Bottle");
        assert_eq!(b.get(1).and_then(|v| v.as_str()), Some("line"), "{b}");
        seen.push(b.get(0).and_then(|v| v.as_i64()).unwrap());
    }
    drop(stdin);
    rt.block_on(port.close());
    let gaps: Vec<i64> = seen.windows(2).map(|w| w[1] - w[0]).collect();
    eprintln!("ours read {seen:?} (gaps {gaps:?})");
    assert!((2..=6).contains(&seen.len()), "{seen:?}");
    assert!(gaps.iter().all(|g| *g >= 10), "{seen:?}");
}

/// YARP 4.0's `YARP_CONNECTIONS_STATS_ENABLE=1`: our `yarp connect` gives the connection a
/// `stats_monitor` (the C++ 4.0 reader takes it), whose ports C++ 4.0's own
/// `yarpconnectionsstats` finds and reads: our writer's 50 messages a second, with their
/// bytes; the ports go when the connection goes.
#[test]
fn cpp_4_yarpconnectionsstats_reads_our_stats_monitor() {
    use std::io::BufRead;
    let test = "cpp_4_yarpconnectionsstats_reads_our_stats_monitor";
    let (Some(yarp), Some(stats_tool)) = (
        cpp4_program(test, "yarp"),
        cpp4_program(test, "yarpconnectionsstats"),
    ) else {
        return;
    };
    let rt = runtime();
    let port = std::sync::Arc::new(
        rt.block_on(Port::open("/st4/w", name_client()))
            .expect("open /st4/w"),
    );
    let writer = port.clone();
    let writing = rt.spawn(async move {
        for n in 0i32.. {
            writer.write_nowait(&Bottle::new().with("counter").with(n), None);
            tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        }
    });
    let _reader = cpp_reader(&yarp, "/st4/r");
    std::env::set_var("YARP_CONNECTIONS_STATS_ENABLE", "1");
    let (ok, why) = rt
        .block_on(yarp_net::network::connect(
            &name_client(),
            "/st4/w",
            "/st4/r",
            None,
        ))
        .expect("connect");
    std::env::remove_var("YARP_CONNECTIONS_STATS_ENABLE");
    assert!(ok, "{why}");
    assert!(why.contains("stats_monitor"), "{why}");
    let forward = "/stats_monitor/st4/w/st4/r/stats:o";
    assert!(
        eventually(T, || registered(forward)
            && registered("/stats_monitor/st4/r/st4/w/stats:o")),
        "{forward} never registered"
    );
    let mut tool = cpp_command(&stats_tool)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn yarpconnectionsstats");
    let out = tool.stdout.take().unwrap();
    let _tool = Reaped(tool);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for l in std::io::BufReader::new(out).lines().map_while(Result::ok) {
            if tx.send(l).is_err() {
                break;
            }
        }
    });
    // `/st4/w -> /st4/r | N B/s | N pkt/s | tcp | time`
    let line = loop {
        let l = rx
            .recv_timeout(3 * T)
            .expect("yarpconnectionsstats printed our connection");
        if l.contains("/st4/w") && l.contains("/st4/r") && l.contains("pkt/s") {
            let fields: Vec<&str> = l.split('|').map(str::trim).collect();
            let pkt: f64 = fields[2]
                .trim_end_matches("pkt/s")
                .trim()
                .parse()
                .unwrap_or(0.0);
            if pkt > 0.0 {
                break l;
            }
        }
    };
    eprintln!("C++ 4.0 yarpconnectionsstats: {line}");
    let fields: Vec<&str> = line.split('|').map(str::trim).collect();
    let bps: f64 = fields[1].trim_end_matches("B/s").trim().parse().unwrap();
    let pkt: f64 = fields[2].trim_end_matches("pkt/s").trim().parse().unwrap();
    assert!((35.0..=55.0).contains(&pkt), "{line}");
    assert!(bps > pkt * 10.0, "{line}");
    assert_eq!(fields[3], "tcp", "{line}");
    writing.abort();
    rt.block_on(yarp_net::network::disconnect(
        &name_client(),
        "/st4/w",
        "/st4/r",
    ))
    .expect("disconnect");
    assert!(
        eventually(T, || !registered(forward)),
        "{forward} stayed after the connection"
    );
}
