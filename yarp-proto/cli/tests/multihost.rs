//! `yarp` beyond one machine: a name server, readers and a writer on three test hosts.
//!
//! Each "host" is a network namespace this test creates itself (an `unshare --net` child
//! kept alive with `sleep`, entered with `nsenter --net=/proc/PID/ns/net`, so nothing is
//! mounted under /run/netns). A fourth namespace holds a bridge (multicast snooping off)
//! and one veth pair joins each host to it:
//!
//! ```text
//!   host 1 (10.77.0.1)  name server, reader /r1
//!   host 2 (10.77.0.2)  reader /r
//!   host 3 (10.77.0.3)  writer /w
//! ```
//!
//! Every host has its own YARP_CONFIG_HOME whose yarp.conf points at 10.77.0.1. The test
//! checks that ports register the address from which the other hosts reach them (not
//! 127.0.0.1), that data written on host 3 arrives on hosts 1 and 2, and that multicast
//! (224.0.0.0/4 routed to each host's interface) reaches every host.
//!
//! Killing the `sleep` children destroys the namespaces together with their links and the
//! bridge, so cleanup needs nothing but the Drop guards, whatever happens in the test.
//! Needs root (or root in a user namespace) and `ip`, `unshare`, `nsenter`; otherwise it
//! skips loudly. Run under ../shared/netns-run like the other network tests.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Ipv4Addr, UdpSocket};
use std::path::PathBuf;
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const SUBNET: &str = "10.77.0";
const NS_PORT: u16 = 10077;
const MCAST_GROUP: Ipv4Addr = Ipv4Addr::new(239, 255, 77, 1);
const MCAST_PORT: u16 = 47701;
/// Environment of the `mcast_helper` child processes.
const ROLE_ENV: &str = "YARP_MULTIHOST_MCAST_ROLE";
const IFACE_ENV: &str = "YARP_MULTIHOST_MCAST_IFACE";
const PAYLOAD_ENV: &str = "YARP_MULTIHOST_MCAST_PAYLOAD";

/// Kills and reaps the child when dropped, whatever happens in the test.
struct Reaped(Child);
impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn skip(why: &str) {
    eprintln!();
    eprintln!("!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!");
    eprintln!("!!! SKIPPED multihost test: {why}");
    eprintln!("!!! Run it as root under netns-run:");
    eprintln!(
        "!!!   /work/shared/netns-run cargo test -p yarp-cli --test multihost -- --nocapture"
    );
    eprintln!("!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!");
    eprintln!();
}

fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("Uid:"))
                .and_then(|l| l.split_whitespace().nth(2).map(|e| e == "0"))
        })
        .unwrap_or(false)
}

fn tool_works(prog: &str, args: &[&str]) -> bool {
    Command::new(prog)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Runs `cmd` to completion, killing it (and failing the test) after `limit`.
fn output_within(mut cmd: Command, limit: Duration) -> Output {
    let what = format!("{cmd:?}");
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {what}: {e}"));
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut v = Vec::new();
            let _ = r.read_to_end(&mut v);
            v
        })
    };
    let out = drain(Box::new(child.stdout.take().unwrap()));
    let err = drain(Box::new(child.stderr.take().unwrap()));
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what} did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Output {
        status,
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
    }
}

fn text(v: &[u8]) -> String {
    String::from_utf8_lossy(v).into_owned()
}

/// A network namespace held open by a `sleep` child.
struct Netns {
    holder: Reaped,
}

impl Netns {
    fn new() -> Netns {
        // if the test process is SIGKILLed, the holders still go away after a minute
        let holder = Reaped(
            Command::new("unshare")
                .args(["--net", "--", "sleep", "60"])
                .stdin(Stdio::null())
                .spawn()
                .expect("unshare --net"),
        );
        let pid = holder.0.id();
        let mine = std::fs::read_link("/proc/self/ns/net").unwrap();
        let t0 = Instant::now();
        // until unshare(2) has run, the child is still in our namespace
        while std::fs::read_link(format!("/proc/{pid}/ns/net"))
            .ok()
            .as_ref()
            == Some(&mine)
        {
            assert!(
                t0.elapsed() < Duration::from_secs(5),
                "namespace holder {pid} never left our namespace"
            );
            std::thread::sleep(Duration::from_millis(10));
        }
        Netns { holder }
    }

    fn pid(&self) -> u32 {
        self.holder.0.id()
    }

    /// `prog args...` inside this namespace (nsenter execs it: killing the child kills it).
    fn cmd(&self, prog: impl AsRef<std::ffi::OsStr>, args: &[&str]) -> Command {
        let mut c = Command::new("nsenter");
        c.arg(format!("--net=/proc/{}/ns/net", self.pid()))
            .arg("--")
            .arg(prog)
            .args(args);
        c
    }

    /// `ip args...` inside this namespace; must succeed.
    fn ip(&self, args: &[&str]) {
        let out = output_within(self.cmd("ip", args), Duration::from_secs(5));
        assert!(
            out.status.success(),
            "ip {} failed: {}",
            args.join(" "),
            text(&out.stderr)
        );
    }
}

struct Host {
    ns: Netns,
    ip: String,
    conf: PathBuf,
}

impl Host {
    fn yarp(&self, args: &[&str]) -> Command {
        let mut c = self.ns.cmd(env!("CARGO_BIN_EXE_yarp"), args);
        c.env("YARP_CONFIG_HOME", &self.conf)
            .env_remove("YARP_NAMESPACE");
        c
    }

    /// A short `yarp` command, bounded in time.
    fn run(&self, args: &[&str]) -> (bool, String) {
        let out = output_within(self.yarp(args), Duration::from_secs(8));
        (out.status.success(), text(&out.stdout) + &text(&out.stderr))
    }

    fn wait_exists(&self, port: &str) {
        let t0 = Instant::now();
        while !self.run(&["exists", port]).0 {
            assert!(
                t0.elapsed() < Duration::from_secs(10),
                "{port} never appeared (asked from {})",
                self.ip
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// The address `yarp name query` reports for `port`.
    fn registered_ip(&self, port: &str) -> String {
        let (ok, out) = self.run(&["name", "query", port]);
        assert!(ok, "name query {port}: {out}");
        let prefix = format!("registration name {port} ip ");
        let rest = out
            .lines()
            .find_map(|l| l.strip_prefix(&prefix))
            .unwrap_or_else(|| panic!("no registration for {port} in {out:?}"));
        rest.split_whitespace().next().unwrap().to_string()
    }
}

/// Three hosts on one bridge. Dropping it kills every namespace holder, which removes the
/// namespaces with their veths and the bridge, and removes the config directories.
struct Lab {
    hosts: Vec<Host>,
    _switch: Netns,
    dir: PathBuf,
}

impl Lab {
    fn new() -> Lab {
        let dir = std::env::temp_dir().join(format!("yarp-multihost-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let switch = Netns::new();
        let mut lab = Lab {
            hosts: Vec::new(),
            _switch: switch,
            dir,
        };
        let sw = &lab._switch;
        sw.ip(&["link", "set", "lo", "up"]);
        sw.ip(&[
            "link",
            "add",
            "yb0",
            "type",
            "bridge",
            "mcast_snooping",
            "0",
        ]);
        sw.ip(&["link", "set", "yb0", "up"]);
        for i in 1..=3 {
            let ns = Netns::new();
            let ip = format!("{SUBNET}.{i}");
            let port = format!("yp{i}");
            let pid = ns.pid().to_string();
            sw.ip(&[
                "link", "add", &port, "type", "veth", "peer", "name", "eth0", "netns", &pid,
            ]);
            sw.ip(&["link", "set", &port, "master", "yb0", "up"]);
            ns.ip(&["link", "set", "lo", "up"]);
            ns.ip(&["addr", "add", &format!("{ip}/24"), "dev", "eth0"]);
            ns.ip(&["link", "set", "eth0", "up", "multicast", "on"]);
            ns.ip(&["route", "add", "224.0.0.0/4", "dev", "eth0"]);
            let conf = lab.dir.join(format!("h{i}"));
            std::fs::create_dir_all(&conf).unwrap();
            std::fs::write(
                conf.join("yarp.conf"),
                format!("{SUBNET}.1 {NS_PORT} yarp\n"),
            )
            .unwrap();
            lab.hosts.push(Host { ns, ip, conf });
        }
        lab
    }

    fn host(&self, n: usize) -> &Host {
        &self.hosts[n - 1]
    }
}

impl Drop for Lab {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Lines of a child's stdout, with a timeout per line.
fn lines(child: &mut Child) -> mpsc::Receiver<String> {
    let out = child.stdout.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for l in BufReader::new(out).lines().map_while(Result::ok) {
            if tx.send(l).is_err() {
                break;
            }
        }
    });
    rx
}

/// Waits (bounded) for `want` among the lines coming from a reader.
fn expect_line(rx: &mpsc::Receiver<String>, want: &str, who: &str) {
    let t0 = Instant::now();
    let limit = Duration::from_secs(8);
    let mut seen = Vec::new();
    while let Some(left) = limit.checked_sub(t0.elapsed()) {
        match rx.recv_timeout(left) {
            Ok(l) if l == want => return,
            Ok(l) => seen.push(l),
            Err(_) => break,
        }
    }
    panic!("{who} never printed {want:?}; it printed {seen:?}");
}

/// Not a test of its own: the multicast sender/receiver that `multihost` runs inside the
/// test hosts (this test binary, `--exact mcast_helper`, with the role in the environment).
/// Does nothing when run by the test harness directly.
#[test]
fn mcast_helper() {
    let Ok(role) = std::env::var(ROLE_ENV) else {
        return;
    };
    let iface: Ipv4Addr = std::env::var(IFACE_ENV).unwrap().parse().unwrap();
    let payload = std::env::var(PAYLOAD_ENV).unwrap();
    match role.as_str() {
        "recv" => {
            let s = UdpSocket::bind((Ipv4Addr::UNSPECIFIED, MCAST_PORT)).unwrap();
            s.join_multicast_v4(&MCAST_GROUP, &iface).unwrap();
            s.set_read_timeout(Some(Duration::from_millis(200)))
                .unwrap();
            println!("MCAST-READY {iface}");
            let t0 = Instant::now();
            let mut buf = [0u8; 1500];
            while t0.elapsed() < Duration::from_secs(8) {
                if let Ok((n, from)) = s.recv_from(&mut buf) {
                    if buf[..n] == *payload.as_bytes() {
                        println!("MCAST-GOT {iface} from {from}");
                        return;
                    }
                }
            }
            panic!("{iface}: nothing from {MCAST_GROUP}:{MCAST_PORT}");
        }
        "send" => {
            // no IP_MULTICAST_IF: the 224.0.0.0/4 route of the host picks the interface
            let s = UdpSocket::bind((iface, 0)).unwrap();
            s.set_multicast_ttl_v4(1).unwrap();
            let t0 = Instant::now();
            while t0.elapsed() < Duration::from_secs(10) {
                s.send_to(payload.as_bytes(), (MCAST_GROUP, MCAST_PORT))
                    .unwrap();
                std::thread::sleep(Duration::from_millis(100));
            }
        }
        other => panic!("unknown role {other}"),
    }
}

fn mcast_helper_cmd(host: &Host, role: &str, payload: &str) -> Command {
    let exe = std::env::current_exe().unwrap();
    let mut c = host.ns.cmd(
        &exe,
        &["mcast_helper", "--exact", "--nocapture", "--test-threads=1"],
    );
    c.env(ROLE_ENV, role)
        .env(IFACE_ENV, &host.ip)
        .env(PAYLOAD_ENV, payload);
    c
}

/// Socket-level multicast: a sender on host 3, receivers on every host (3 by loopback).
fn check_socket_mcast(lab: &Lab) {
    let payload = format!("yarp-multihost-{}", std::process::id());
    let receivers: Vec<(String, Reaped)> = lab
        .hosts
        .iter()
        .map(|h| {
            let child = mcast_helper_cmd(h, "recv", &payload)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            (h.ip.clone(), Reaped(child))
        })
        .collect();
    let _sender = Reaped(
        mcast_helper_cmd(lab.host(3), "send", &payload)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    for (ip, mut r) in receivers {
        let mut out = String::new();
        let mut err = String::new();
        let _ = r.0.stdout.take().unwrap().read_to_string(&mut out);
        let _ = r.0.stderr.take().unwrap().read_to_string(&mut err);
        // the receiver ends by itself within 8 s (success or panic)
        let status = r.0.wait().unwrap();
        assert!(
            status.success() && out.contains("MCAST-GOT"),
            "multicast from {SUBNET}.3 did not reach {ip}:\n{out}\n{err}"
        );
        let got = out.lines().find(|l| l.starts_with("MCAST-GOT")).unwrap();
        println!("multihost: socket-level mcast ok: {got}");
    }
}

#[test]
fn multihost() {
    if !is_root() {
        return skip("not running as root");
    }
    for (prog, arg) in [
        ("ip", "-V"),
        ("unshare", "--version"),
        ("nsenter", "--version"),
    ] {
        if !tool_works(prog, &[arg]) {
            return skip(&format!("`{prog}` is missing"));
        }
    }
    if !tool_works("unshare", &["--net", "--", "true"]) {
        return skip("`unshare --net` does not work here (no CAP_SYS_ADMIN?)");
    }
    let t_start = Instant::now();
    let lab = Lab::new();
    let (h1, h2, h3) = (lab.host(1), lab.host(2), lab.host(3));

    // name server on host 1, on its own address
    let mut server = Reaped(
        h1.yarp(&["server", "--ip", &h1.ip, "--socket", &NS_PORT.to_string()])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let t0 = Instant::now();
    loop {
        let (ok, out) = h2.run(&["where"]);
        if ok {
            assert!(
                out.contains(&format!("available at ip {} port {NS_PORT}", h1.ip)),
                "{out}"
            );
            break;
        }
        if let Some(s) = server.0.try_wait().unwrap() {
            panic!("name server exited: {s}");
        }
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "name server on {} never reachable from {}: {out}",
            h1.ip,
            h2.ip
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(h3.registered_ip("/root"), h1.ip, "the name server itself");

    // readers on host 2 and on the name server's own host
    let mut reader = Reaped(
        h2.yarp(&["read", "/r"])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let got2 = lines(&mut reader.0);
    let mut reader1 = Reaped(
        h1.yarp(&["read", "/r1"])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let got1 = lines(&mut reader1.0);
    h3.wait_exists("/r");
    h3.wait_exists("/r1");
    for (asker, port, want) in [(h1, "/r", &h2.ip), (h3, "/r", &h2.ip), (h2, "/r1", &h1.ip)] {
        let ip = asker.registered_ip(port);
        println!(
            "multihost: from {} `yarp name query {port}` says ip {ip}",
            asker.ip
        );
        assert_eq!(
            &ip, want,
            "{port} must advertise its host's address, not {ip}"
        );
    }

    // writer on host 3, connected to both readers at start
    let mut writer = Reaped(
        h3.yarp(&["write", "/w", "/r", "/r1"])
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    h2.wait_exists("/w");
    let ip = h1.registered_ip("/w");
    println!("multihost: `yarp name query /w` says ip {ip}");
    assert_eq!(ip, h3.ip, "/w must advertise host 3's address");
    let t0 = Instant::now();
    while !(h1.run(&["exists", "/w", "/r"]).0 && h1.run(&["exists", "/w", "/r1"]).0) {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "/w never connected to /r and /r1"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    {
        let stdin = writer.0.stdin.as_mut().unwrap();
        stdin
            .write_all(b"hello from 3 42\n(nested [ok]) \"two words\"\n")
            .unwrap();
        stdin.flush().unwrap();
    }
    for (rx, who) in [(&got2, "/r on host 2"), (&got1, "/r1 on host 1")] {
        expect_line(rx, "hello from 3 42", who);
        expect_line(rx, "(nested [ok]) \"two words\"", who);
        println!("multihost: tcp data from host 3 reached {who}");
    }

    // multicast: first at the socket level, which is what YARP's mcast carrier relies on
    check_socket_mcast(&lab);

    // then the YARP mcast carrier, if our ports support it (tcp dropped first, so nothing
    // can arrive by tcp instead)
    for r in ["/r", "/r1"] {
        let (ok, out) = h3.run(&["disconnect", "/w", r]);
        assert!(ok, "disconnect /w {r}: {out}");
    }
    let (ok, out) = h3.run(&["connect", "/w", "/r", "mcast"]);
    if !ok {
        println!(
            "multihost: PENDING: YARP-level mcast (`yarp connect /w /r mcast`) is not supported \
             by our ports yet (output ports refuse the carrier, input ports close datagram \
             handshakes); multicast reachability across the hosts was checked at the socket \
             level only. connect said: {}",
            out.trim()
        );
    } else {
        println!("multihost: `yarp connect /w /r mcast`: {}", out.trim());
        let (ok, out) = h1.run(&["connect", "/w", "/r1", "mcast"]);
        assert!(ok, "mcast to /r succeeded but not to /r1: {out}");
        let stdin = writer.0.stdin.as_mut().unwrap();
        stdin.write_all(b"over mcast 7\n").unwrap();
        stdin.flush().unwrap();
        for (rx, who) in [(&got2, "/r on host 2"), (&got1, "/r1 on host 1")] {
            expect_line(rx, "over mcast 7", who);
            println!("multihost: mcast data from host 3 reached {who}");
        }
    }

    drop(writer);
    drop(reader);
    drop(reader1);
    drop(server);
    println!("multihost: done in {:?}", t_start.elapsed());
}
