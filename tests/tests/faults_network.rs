//! Fault injection on the network layer, with real processes on loopback (run under
//! netns-run): our `yarpserver`, `yarp read`/`write`/`rpc`/`connect`, `yarpdev` and the
//! ROS 2 gateway.
//!
//! - The name server killed and restarted: live connections carry on meanwhile, every
//!   port (the gateway's too) is registered again within a few seconds of the server's
//!   return, and new connections by name are made. C++ YARP ports do not do that (their
//!   registrations live in the server's memory, `--portdb :memory:`); ours check their
//!   registration every `REGISTRATION_CHECK` (README, "Name server restarts").
//! - Peers that send half a message (or half a name-server line) and hang: every other
//!   connection of the same port (reader, rpc server, gateway) and the name server keep
//!   working, and what the hung connections held (descriptors, tasks) is released when
//!   the port is told to drop them (admin `del`), after `STALL_TIMEOUT` without a byte in
//!   the middle of a header or binary message, and when the peers go away.
//! - A reader that stops reading: the writer's memory stays bounded (its per-connection
//!   queue) and its other readers keep receiving.
//!
//! Needs the workspace programs in the same target directory (`cargo build --workspace
//! --bins`; `tests/run.sh` does).

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::{Duration, Instant};
use yarp_interop_tests::{eventually, fd_count, rss_kib, thread_count, Proc, YarpNet, STEP};
use yarp_net::port::STALL_TIMEOUT;
use yarp_proto::wire::{self, Carrier, PortCommand};

/// The network of one test, with the programs these tests start on it.
struct Net(YarpNet);

impl std::ops::Deref for Net {
    type Target = YarpNet;
    fn deref(&self) -> &YarpNet {
        &self.0
    }
}

impl Net {
    fn new() -> Net {
        Net(YarpNet::new())
    }

    fn reader(&self, name: &str) -> Proc {
        let mut c = self.yarp();
        c.args(["read", name]);
        let p = Proc::spawn(&format!("yarp read {name}"), c);
        self.wait_registered(name);
        p
    }

    fn writer(&self, name: &str, to: &str) -> Proc {
        let mut c = self.yarp();
        c.args(["write", name, to]);
        let p = Proc::spawn(&format!("yarp write {name}"), c);
        self.wait_registered(name);
        p
    }

    /// The gateway with one YARP input port `port` (YARP -> ROS std_msgs/String), on this
    /// network's name server (never an embedded one) and a private ROS domain.
    fn gateway(&self, port: &str) -> Proc {
        let mapping = self.dir.path().join("faults.toml");
        std::fs::write(
            &mapping,
            format!(
                "[[topic]]\nname = \"faults\"\ndirection = \"yarp_to_ros\"\n\
                 yarp_port = \"{port}\"\nros_topic = \"/faults\"\n\
                 ros_type = \"std_msgs/msg/String\"\n"
            ),
        )
        .expect("mapping file");
        // no ROS peer here: a domain above those of the gateway's and launcher's tests
        // (20..229), so that this gateway's DDS traffic meets none of theirs
        let domain = 231;
        let mut c = self.cmd("yarp-ros2-gateway", "yarp-ros2-gateway");
        c.args(["--mappings", mapping.to_str().expect("utf-8 path")])
            .args(["--network", "127.0.0.1", "--domain-id", &domain.to_string()])
            .args(["--name-server", &format!("127.0.0.1:{}", self.port)])
            .args(["--no-embedded-name-server", "--diagnostics-period", "0"]);
        let p = Proc::spawn("yarp-ros2-gateway", c);
        self.wait_registered(port);
        p
    }
}

fn send_line(p: &mut Proc, line: &str) {
    let stdin = p.child.stdin.as_mut().expect("piped stdin");
    writeln!(stdin, "{line}").expect("write to stdin");
    stdin.flush().expect("flush");
}

#[test]
fn name_server_killed_and_restarted() {
    let net = Net::new();
    let mut server = net.server();
    let mut reader = net.reader("/fault/in");
    let mut writer = net.writer("/fault/out", "/fault/in");
    let gw_port = "/fault/gw:i";
    let _gateway = net.gateway(gw_port);
    let before: Vec<Option<u16>> = ["/fault/in", "/fault/out", gw_port]
        .iter()
        .map(|p| net.query(p))
        .collect();
    send_line(&mut writer, "before 1");
    reader.wait_line("before 1", STEP);

    server.kill();
    // the live connection does not need the name server
    send_line(&mut writer, "during 1");
    reader.wait_line("during 1", STEP);
    assert_eq!(net.query("/fault/in"), None, "server is down");

    let t0 = Instant::now();
    let _server = net.server();
    for (port, was) in ["/fault/in", "/fault/out", gw_port].iter().zip(&before) {
        let again = net.wait_registered(port);
        assert_eq!(
            Some(again),
            *was,
            "{port} registered again where it listens"
        );
    }
    let took = t0.elapsed();
    // REGISTRATION_CHECK is 2 s; allow a loaded machine its start-up time on top
    assert!(
        took < Duration::from_secs(12),
        "re-registration took {took:?}"
    );
    println!("every port registered again {took:?} after the server restarted");

    // connections by name work again: a new reader, and the gateway's input
    let mut reader2 = net.reader("/fault/in2");
    assert!(
        net.connect("/fault/out", "/fault/in2"),
        "connect to a new reader"
    );
    assert!(net.connect("/fault/out", gw_port), "connect to the gateway");
    send_line(&mut writer, "after 1");
    reader.wait_line("after 1", STEP);
    reader2.wait_line("after 1", STEP);
}

/// The connection header of a tcp connection from `sender`.
fn tcp_header(sender: &str) -> Vec<u8> {
    wire::encode_connection_start(&Carrier::Tcp.spec(), sender.as_bytes())
}

/// A data message carrying `text` as a Bottle.
fn data_message(text: &str) -> Vec<u8> {
    let payload = yarp_proto::Bottle::from_text(text).encode();
    let mut out = Vec::new();
    wire::encode_message(&PortCommand::data(false), &[&payload], &mut out);
    out
}

/// Opens a connection to `port` that stops in the middle of something: the header, a
/// message's index, a message's payload, a text line. Returns the socket (kept open).
fn half_connection(port: u16, how: usize) -> TcpStream {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    let header = tcp_header("/fault/half");
    let msg = data_message("a message that never ends 1 2 3 4 5 6 7 8 9");
    let bytes: Vec<u8> = match how % 4 {
        0 => header[..5].to_vec(),
        1 => [&header[..], &msg[..6]].concat(),
        2 => [&header[..], &msg[..msg.len() - 3]].concat(),
        _ => b"CONNECT /fault/half\nd\n(half a bott".to_vec(),
    };
    s.write_all(&bytes).expect("send half");
    s
}

/// Sends half a name-server request (text line, binary) and keeps the socket open.
fn half_name_request(port: u16, binary: bool) -> TcpStream {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    let bytes: Vec<u8> = if binary {
        tcp_header("/fault/half")[..10].to_vec()
    } else {
        b"NAME_SERVER query /fault".to_vec()
    };
    s.write_all(&bytes).expect("send half");
    s
}

/// An admin command over a text connection, as a telnet user types it; the reply line.
fn admin_text(port: u16, cmd: &str) -> String {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    s.set_read_timeout(Some(STEP)).expect("timeout");
    s.write_all(format!("CONNECT /fault/admin\na\n{cmd}\n").as_bytes())
        .expect("admin");
    let mut got = Vec::new();
    let mut buf = [0u8; 512];
    // the welcome line, then the reply line
    while got.iter().filter(|&&b| b == b'\n').count() < 2 {
        match s.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => got.extend_from_slice(&buf[..n]),
        }
    }
    String::from_utf8_lossy(&got).into_owned()
}

fn rpc(net: &Net, port: &str, input: &str) -> String {
    net.rpc(port, input)
}

#[test]
fn half_messages_block_nothing_else() {
    let net = Net::new();
    let server = net.server();
    let mut reader = net.reader("/fault/in");
    let mut writer = net.writer("/fault/out", "/fault/in");
    let mut motor = net.cmd("yarpdev", "yarp-device-programs");
    motor.args([
        "--device",
        "test_motor",
        "--axes",
        "2",
        "--single_port",
        "--name",
        "/fault/motors",
    ]);
    let motor = Proc::spawn("yarpdev", motor);
    net.wait_registered("/fault/motors");
    let gw_port = "/fault/gw:i";
    let gateway = net.gateway(gw_port);
    send_line(&mut writer, "warm 1");
    reader.wait_line("warm 1", STEP);
    assert!(rpc(&net, "/fault/motors", "[get] [axes]\n").contains("[is] [axes] 2"));

    let targets = [
        ("reader", net.query("/fault/in").unwrap(), reader.pid()),
        (
            "rpc server",
            net.query("/fault/motors").unwrap(),
            motor.pid(),
        ),
        ("gateway", net.query(gw_port).unwrap(), gateway.pid()),
    ];
    std::thread::sleep(Duration::from_millis(500));
    let base: Vec<(usize, usize)> = targets
        .iter()
        .map(|t| (fd_count(t.2), thread_count(t.2)))
        .collect();
    let ns_base = fd_count(server.pid());

    const HALF: usize = 8;
    let hung_at = Instant::now();
    let mut hung = Vec::new();
    for (_, port, _) in &targets {
        for how in 0..HALF {
            hung.push(half_connection(*port, how));
        }
    }
    let hung_ns: Vec<TcpStream> = (0..4)
        .map(|i| half_name_request(net.port, i % 2 == 0))
        .collect();
    // every process now holds the hung connections...
    for ((what, _, pid), (fds, _)) in targets.iter().zip(&base) {
        assert!(
            eventually(STEP, || fd_count(*pid) >= fds + HALF),
            "{what}: the half connections were not accepted"
        );
    }
    // ...and everything else carries on: the stream, rpc, the name server, new connections
    for i in 0..3 {
        send_line(&mut writer, &format!("while hung {i}"));
        reader.wait_line(&format!("while hung {i}"), STEP);
    }
    let reply = rpc(&net, "/fault/motors", "[get] [axes]\n");
    assert!(reply.contains("[is] [axes] 2"), "rpc while hung: {reply}");
    assert!(net.query("/fault/in").is_some(), "name server while hung");
    assert!(
        net.connect("/fault/out", gw_port),
        "gateway accepts while hung"
    );

    // the reader is told to drop the half connections (admin `del`, as `yarp disconnect`
    // asks a destination): without any peer closing
    let (_, reader_port, reader_pid) = targets[0];
    let reply = admin_text(reader_port, "[del] /fault/half");
    assert!(
        reply.contains("Removing connection from /fault/half"),
        "admin del: {reply:?}"
    );
    // (left: the two that never finished their header)
    assert!(
        eventually(STEP, || fd_count(reader_pid) <= base[0].0 + HALF / 4 + 1),
        "reader still holds {} descriptors (baseline {})",
        fd_count(reader_pid),
        base[0].0
    );

    // the peers never close: every connection stuck in a header or a binary message is
    // closed by its port after STALL_TIMEOUT; the text ones (a person typing) stay open,
    // as in C++
    let stalled = hung_at.elapsed();
    for ((what, _, pid), (fds, _)) in targets.iter().zip(&base) {
        let text_left = if *what == "reader" { 0 } else { HALF / 4 };
        let limit = (STALL_TIMEOUT + STEP).saturating_sub(stalled);
        assert!(
            eventually(limit, || fd_count(*pid) <= fds + text_left + 1),
            "{what}: {} descriptors {:?} after the half messages (baseline {fds})",
            fd_count(*pid),
            hung_at.elapsed()
        );
    }
    println!(
        "stalled connections closed by their ports {:?} after they stopped",
        hung_at.elapsed()
    );

    // the peers go away: everything they held is released
    drop(hung);
    drop(hung_ns);
    for ((what, _, pid), (fds, threads)) in targets.iter().zip(&base) {
        assert!(
            eventually(STEP, || fd_count(*pid) <= *fds + 1),
            "{what}: {} descriptors after the peers left (baseline {fds})",
            fd_count(*pid)
        );
        let now = thread_count(*pid);
        assert!(
            now <= threads + 2,
            "{what}: {now} threads (baseline {threads})"
        );
    }
    assert!(
        eventually(STEP, || fd_count(server.pid()) <= ns_base + 1),
        "name server: {} descriptors (baseline {ns_base})",
        fd_count(server.pid())
    );
    send_line(&mut writer, "after 1");
    reader.wait_line("after 1", STEP);
}

/// A reader registered as `name` that accepts one connection, answers its header and
/// then never reads again: the writer's socket buffers fill and its queue with them.
fn stalled_reader(net: &Net, name: &str) -> (TcpListener, std::thread::JoinHandle<TcpStream>) {
    let l = TcpListener::bind("127.0.0.1:0").expect("bind");
    let port = l.local_addr().expect("addr").port();
    let ok = net
        .yarp()
        .args([
            "name",
            "register",
            name,
            "tcp",
            "127.0.0.1",
            &port.to_string(),
        ])
        .output()
        .expect("yarp name register");
    assert!(ok.status.success(), "register {name}");
    let l2 = l.try_clone().expect("clone listener");
    let t = std::thread::spawn(move || {
        let (mut s, _) = l2.accept().expect("accept");
        // 8-byte carrier header, then the 4-byte name length and the name
        let mut head = [0u8; 12];
        s.read_exact(&mut head).expect("header");
        let n = u32::from_le_bytes(head[8..12].try_into().expect("4 bytes")) as usize;
        let mut name = vec![0u8; n];
        s.read_exact(&mut name).expect("sender name");
        s.write_all(&wire::encode_header_reply(i32::from(port)))
            .expect("header reply");
        s
    });
    (l, t)
}

#[test]
fn stalled_reader_keeps_writer_memory_bounded() {
    let net = Net::new();
    let _server = net.server();
    let mut cam = net.cmd("yarpdev", "yarp-device-programs");
    // 320x240 rgb at 100 Hz: 230 kB a frame, 23 MB/s
    cam.args([
        "--device",
        "fakeFrameGrabber",
        "--name",
        "/fault/cam",
        "--period",
        "0.01",
    ]);
    let cam = Proc::spawn("yarpdev fakeFrameGrabber", cam);
    net.wait_registered("/fault/cam");

    std::thread::sleep(Duration::from_millis(500));
    let (fds_alone, rss_alone) = (fd_count(cam.pid()), rss_kib(cam.pid()));
    let (_l, accepted) = stalled_reader(&net, "/fault/stuck");
    assert!(
        net.connect("/fault/cam", "/fault/stuck"),
        "connect the stalled reader"
    );
    let _stuck = accepted.join().expect("stalled reader accepted");
    // a reader that keeps reading, in this process
    let yarp = yarp_net::blocking::Network::with_name_server(
        format!("127.0.0.1:{}", net.port).parse().expect("addr"),
    )
    .expect("network");
    let live = yarp_net::blocking::Port::open(&yarp, "/fault/live").expect("open reader");
    assert!(
        net.connect("/fault/cam", "/fault/live"),
        "connect the live reader"
    );

    // warm-up: the stalled connection's socket buffers and queue fill
    std::thread::sleep(Duration::from_secs(3));
    let rss0 = rss_kib(cam.pid());
    let start = Instant::now();
    let mut frames = 0;
    let mut peak = rss0;
    while start.elapsed() < Duration::from_secs(6) {
        if live.read_timeout(Duration::from_millis(100)).is_some() {
            frames += 1;
        }
        peak = peak.max(rss_kib(cam.pid()));
    }
    let rss1 = rss_kib(cam.pid());
    println!(
        "writer RSS {rss_alone} kB without readers, {rss0} kB after 3 s with the stalled \
         one, {rss1} kB 6 s later (peak {peak} kB); live reader got {frames} frames meanwhile"
    );
    // an unbounded queue would grow by 23 MB/s here
    assert!(
        peak < rss0 + 8 * 1024,
        "writer memory grew from {rss0} kB to {peak} kB with a stalled reader"
    );
    assert!(
        frames >= 100,
        "the live reader starved: {frames} frames in 6 s"
    );

    // removing the stalled connection frees it, although its writer is stuck mid-write
    let out = net
        .yarp()
        .args(["disconnect", "/fault/cam", "/fault/stuck"])
        .output()
        .expect("yarp disconnect");
    assert!(out.status.success(), "yarp disconnect");
    assert!(
        eventually(STEP, || fd_count(cam.pid()) <= fds_alone + 1),
        "writer holds {} descriptors, {fds_alone} before the readers came",
        fd_count(cam.pid())
    );
}
