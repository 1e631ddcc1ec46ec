//! The session of YARP's design paper ("Towards Long-Lived Robot Genes", Fitzpatrick,
//! Metta, Natale; section "YARP without YARP"), played over raw TCP sockets against real
//! processes: our `yarpserver`, then
//!
//! ```text
//! yarpdev --device test_motor --axes 2 --single_port --name /motors
//! ```
//!
//! and a telnet user (no YARP library on this side: the name server is asked in its own
//! text protocol too). While that session is open a second connection reverses itself and
//! receives the encoder Bottles, `yarp read /x /motors` reads them, `yarp connect /motors
//! /x udp` moves that reader to udp and `yarp rpc /motors` asks the same single port.
//!
//! Needs the workspace programs built into the same target directory
//! (`cargo build -p yarp-net -p yarp-device-programs -p yarp-cli`; `tests/run.sh` does).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};
use yarp_interop_tests::Reaped;

/// Longest any single step may take (a loaded 2-core machine starts programs slowly).
const STEP: Duration = Duration::from_secs(20);

/// The help C++ YARP ports give a text-mode user (`?`, `h`, `help`).
const PORT_HELP: &str = "This is a YARP port.  Here are the commands it responds to:\r\n\
*       Gives a description of this port\r\n\
d       Signals the beginning of input for the port's owner\r\n\
do      The same as \"d\" except replies should be suppressed (\"data-only\")\r\n\
q       Disconnects\r\n\
r       Reverse connection type to be a reader\r\n\
/port   Requests to send output to /port\r\n\
!/port  Requests to stop sending output to /port\r\n\
~/port  Requests to stop receiving input from /port\r\n\
a       Signals the beginning of an administrative message\r\n\
?       Gives this help\r\n";

/// What the motor's device responder lists for `help` (YARP 2's ServerControlBoard, two
/// axes): one usage per line, then `[ok]`.
const MOTOR_HELP: &str = "\"[help]\"\r\n\
\"[help] [more]\"\r\n\
\"[get] [axes]\"\r\n\
\"[get] [name] $iAxisNumber\"\r\n\
\"[set] [pos] $iAxisNumber $fPosition\"\r\n\
\"[set] [rel] $iAxisNumber $fPosition\"\r\n\
\"[set] [vmo] $iAxisNumber $fVelocity\"\r\n\
\"[get] [enc] $iAxisNumber\"\r\n\
\"[set] [poss] ($f0 $f1)\"\r\n\
\"[set] [rels] ($f0 $f1)\"\r\n\
\"[set] [vmos] ($f0 $f1)\"\r\n\
\"[set] [aen] $iAxisNumber\"\r\n\
\"[set] [adi] $iAxisNumber\"\r\n\
\"[get] [acu] $iAxisNumber\"\r\n\
\"[get] [acus]\"\r\n\
[ok]\r\n";

/// A workspace program beside this test's target directory; panics with the build
/// command when it is missing (these are our own programs, not an optional peer).
fn program(name: &str, package: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("test path");
    // <target>/<profile>/deps/<test> -> <target>/<profile>/<name>
    let p = exe
        .parent()
        .and_then(Path::parent)
        .expect("target dir")
        .join(name);
    assert!(
        p.is_file(),
        "{} not found: run `cargo build -p {package}` with the same CARGO_TARGET_DIR",
        p.display()
    );
    p
}

/// A TCP port for the name server below the ephemeral range (its registered ports
/// follow it), picked apart from other test processes by pid and clock.
fn name_server_port() -> u16 {
    let mut x = (std::process::id() as u64)
        ^ std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos() as u64)
            .unwrap_or(1)
        | 1;
    for _ in 0..200 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let port = 10_000 + (x % 12_000) as u16;
        if (0..4).all(|i| TcpListener::bind(("127.0.0.1", port + i)).is_ok()) {
            return port;
        }
    }
    panic!("no free port for the name server (run under netns-run)");
}

/// Polls `f` until it gives `Some`, at most [`STEP`]; panics naming `what`.
fn within<R>(what: &str, mut f: impl FnMut() -> Option<R>) -> R {
    let start = Instant::now();
    loop {
        if let Some(r) = f() {
            return r;
        }
        assert!(start.elapsed() < STEP, "timed out: {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A raw TCP connection, as telnet makes one.
struct Telnet {
    stream: TcpStream,
    got: Vec<u8>,
}

impl Telnet {
    fn connect(port: u16) -> std::io::Result<Telnet> {
        let stream = TcpStream::connect(("127.0.0.1", port))?;
        stream.set_read_timeout(Some(Duration::from_millis(200)))?;
        Ok(Telnet {
            stream,
            got: Vec::new(),
        })
    }

    fn send(&mut self, line: &str) {
        self.stream.write_all(line.as_bytes()).expect("send");
    }

    /// Reads until the bytes received end with `end`; returns them all (and forgets them).
    fn until(&mut self, end: &str) -> String {
        let deadline = Instant::now() + STEP;
        let mut buf = [0u8; 4096];
        while !self.got.ends_with(end.as_bytes()) {
            assert!(
                Instant::now() < deadline,
                "timed out waiting for {end:?}; got {:?}",
                String::from_utf8_lossy(&self.got)
            );
            match self.stream.read(&mut buf) {
                Ok(0) => panic!("closed; got {:?}", String::from_utf8_lossy(&self.got)),
                Ok(n) => self.got.extend_from_slice(&buf[..n]),
                Err(e) if is_timeout(&e) => {}
                Err(e) => panic!("read: {e}"),
            }
        }
        String::from_utf8(std::mem::take(&mut self.got)).expect("text")
    }

    /// Sends `line` and expects exactly `answer` back.
    fn expect(&mut self, line: &str, answer: &str) {
        self.send(line);
        let got = self.until(answer);
        assert_eq!(got, answer, "after {line:?}");
    }

    /// Waits for the peer to close the connection (nothing more may arrive).
    fn closed(&mut self) {
        let deadline = Instant::now() + STEP;
        let mut buf = [0u8; 256];
        loop {
            assert!(Instant::now() < deadline, "connection still open");
            match self.stream.read(&mut buf) {
                Ok(0) => return,
                Ok(n) => panic!("unexpected {:?}", String::from_utf8_lossy(&buf[..n])),
                Err(e) if is_timeout(&e) => {}
                // a reset is a close as well
                Err(_) => return,
            }
        }
    }
}

fn is_timeout(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
    )
}

/// Lines read by a thread from `r` (a reversed connection, a child's stdout).
fn lines_of(r: impl Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(r).lines() {
            let Ok(line) = line else { return };
            if tx.send(line.trim_end_matches('\r').to_string()).is_err() {
                return;
            }
        }
    });
    rx
}

/// The next line within [`STEP`].
fn next_line(rx: &Receiver<String>, what: &str) -> String {
    rx.recv_timeout(STEP)
        .unwrap_or_else(|_| panic!("timed out waiting for a line from {what}"))
}

/// The two encoder values of a line such as `75.88 0.0`, if it is one.
fn encoders(line: &str) -> Option<(f64, f64)> {
    let v: Vec<f64> = line
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .ok()?;
    match v[..] {
        [a, b] => Some((a, b)),
        _ => None,
    }
}

/// Reads encoder Bottles from `rx` until axis 0 reads 100.0; returns how many values
/// strictly between 0 and 100 went by (the motion, seen as it happened).
fn until_axis0_at_100(rx: &Receiver<String>, what: &str) -> usize {
    let deadline = Instant::now() + STEP;
    let mut moving = 0;
    loop {
        assert!(Instant::now() < deadline, "{what}: axis 0 never read 100.0");
        let line = next_line(rx, what);
        if let Some((a0, a1)) = encoders(&line) {
            assert_eq!(a1, 0.0, "{what}: axis 1 was not moved: {line}");
            assert!((0.0..=100.0).contains(&a0), "{what}: {line}");
            if a0 == 100.0 {
                assert_eq!(line, "100.0 0.0", "{what}");
                return moving;
            }
            if a0 > 0.0 {
                moving += 1;
            }
        }
    }
}

/// Runs `yarp ARGS` to completion (bounded) and returns its stdout and stderr.
fn yarp(env: &Env, args: &[&str]) -> String {
    let mut child = Reaped(
        env.command("yarp", "yarp-cli")
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn yarp"),
    );
    let status = within(&format!("yarp {args:?} to finish"), || {
        child.0.try_wait().expect("wait")
    });
    let mut out = String::new();
    child.0.stdout.take().unwrap().read_to_string(&mut out).ok();
    child.0.stderr.take().unwrap().read_to_string(&mut out).ok();
    assert!(status.success(), "yarp {args:?}: {status}: {out}");
    out
}

/// The programs' shared setting: a private `yarp.conf` naming our name server.
struct Env {
    conf: tempfile::TempDir,
}

impl Env {
    fn command(&self, name: &str, package: &str) -> Command {
        let mut c = Command::new(program(name, package));
        c.env("YARP_CONFIG_HOME", self.conf.path())
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        c
    }
}

/// Asks the name server where `port` is, in its text protocol (as the paper's user may).
fn name_query(ns_port: u16, port: &str) -> Option<u16> {
    let mut ns = Telnet::connect(ns_port).ok()?;
    ns.expect("CONNECT foo\n", "Welcome foo\r\n");
    ns.send(&format!("d\nquery {port}\n"));
    let answer = ns.until("*** end of message\r\n");
    let words: Vec<&str> = answer.split_whitespace().collect();
    let at = words.iter().position(|w| *w == "port")?;
    words.get(at + 1)?.parse().ok()
}

#[test]
fn yarp_without_yarp_the_papers_session() {
    let env = Env {
        conf: tempfile::tempdir().expect("temp dir"),
    };

    // yarp server
    let ns_port = name_server_port();
    let _server = Reaped(
        env.command("yarpserver", "yarp-net")
            .args([
                "--ip",
                "127.0.0.1",
                "--socket",
                &ns_port.to_string(),
                "--write",
            ])
            .spawn()
            .expect("spawn yarpserver"),
    );
    within("the name server's yarp.conf", || {
        let conf = std::fs::read_to_string(env.conf.path().join("yarp.conf")).ok()?;
        conf.contains(&ns_port.to_string()).then_some(())
    });

    // yarpdev --device test_motor --axes 2 --single_port --name /motors
    let _motors = Reaped(
        env.command("yarpdev", "yarp-device-programs")
            .args([
                "--device",
                "test_motor",
                "--axes",
                "2",
                "--single_port",
                "--name",
                "/motors",
            ])
            .spawn()
            .expect("spawn yarpdev"),
    );
    // where /motors is, asked over telnet as well
    let port = within("/motors registered", || name_query(ns_port, "/motors"));

    // The table: the user types, the system responds.
    let mut user = Telnet::connect(port).expect("connect to /motors");
    user.expect("CONNECT foo\n", "Welcome foo\r\n");
    user.expect("help\n", PORT_HELP);
    user.send("*\n");
    let described = user.until("using text\r\n");
    assert!(
        described.starts_with(&format!("This is /motors at tcp://127.0.0.1:{port}/\r\n")),
        "{described}"
    );
    assert!(
        described.ends_with("There is an input connection from foo to /motors using text\r\n"),
        "{described}"
    );
    user.expect("d\nhelp\n", MOTOR_HELP);
    user.expect("d\n[get] [axes]\n", "[is] [axes] 2 [ok]\r\n");

    // "By default, the motor port will stream encoder readings to any reader that
    // connects": a second telnet user reverses its connection.
    let mut reader = Telnet::connect(port).expect("connect to /motors");
    reader.expect("CONNECT bar\n", "Welcome bar\r\n");
    reader.send("r\n");
    reader.stream.set_read_timeout(None).unwrap();
    let reversed = lines_of(reader.stream.try_clone().unwrap());
    let first = within("an encoder Bottle on the reversed connection", || {
        encoders(&next_line(&reversed, "the reversed connection"))
    });
    assert_eq!(first, (0.0, 0.0));

    // ... and at the same time other programs on the same single port: a tcp reader,
    // which then moves to udp, and an RPC client.
    let mut read_x = Reaped(
        env.command("yarp", "yarp-cli")
            .args(["read", "/x", "/motors"])
            .stdout(Stdio::piped())
            .spawn()
            .expect("spawn yarp read"),
    );
    let x_lines = lines_of(read_x.0.stdout.take().unwrap());
    within("yarp read /x /motors prints encoders (tcp)", || {
        encoders(&next_line(&x_lines, "yarp read /x"))
    });
    let out = yarp(&env, &["connect", "/motors", "/x", "udp"]);
    assert!(out.contains("Success"), "{out}");
    let mut rpc = Reaped(
        env.command("yarp", "yarp-cli")
            .args(["rpc", "/motors"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("spawn yarp rpc"),
    );
    let mut rpc_in = rpc.0.stdin.take().unwrap();
    let rpc_out = lines_of(rpc.0.stdout.take().unwrap());
    rpc_in.write_all(b"[get] [axes]\n").unwrap();
    assert_eq!(
        next_line(&rpc_out, "yarp rpc"),
        "Response: [is] [axes] 2 [ok]"
    );

    // the port now serves all of them at once (a command with a known answer marks the
    // end of the description)
    user.send("*\nd\n[get] [axes]\n");
    let described = user.until("[is] [axes] 2 [ok]\r\n");
    for line in [
        "There is an output connection from /motors to bar using text",
        "There is an output connection from /motors to /x using udp",
        "There is an input connection from foo to /motors using text",
    ] {
        assert!(described.contains(line), "{line}: {described}");
    }
    assert!(
        described.contains("There is an input connection from ")
            && described.matches("There is an input connection").count() == 2,
        "the yarp rpc client: {described}"
    );
    // drop what /x read over tcp: from here on its Bottles come by udp
    while x_lines.try_recv().is_ok() {}

    user.expect("d\n[set] [pos] 0 100.0\n", "[ok]\r\n");
    let moving = until_axis0_at_100(&reversed, "the reversed connection");
    assert!(
        moving > 0,
        "the reversed connection saw axis 0 jump, not move"
    );
    until_axis0_at_100(&x_lines, "yarp read /x over udp");
    rpc_in.write_all(b"[get] [enc] 0\n").unwrap();
    assert_eq!(
        next_line(&rpc_out, "yarp rpc"),
        "Response: [is] [enc] 100.0 [ok]"
    );

    user.send("q\n");
    user.closed();
    // the others were not disturbed by that
    within("the reversed connection still streaming", || {
        encoders(&next_line(&reversed, "the reversed connection"))
    });
    rpc_in.write_all(b"[get] [axes]\n").unwrap();
    assert_eq!(
        next_line(&rpc_out, "yarp rpc"),
        "Response: [is] [axes] 2 [ok]"
    );
    drop(rpc_in);
    let _ = reader.stream.shutdown(Shutdown::Both);
}
