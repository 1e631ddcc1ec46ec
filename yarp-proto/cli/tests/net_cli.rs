//! The `yarp` networking commands as a user runs them: real child processes against a
//! real name server on loopback, with yarp.conf in a private config directory.
//! Run under ../shared/netns-run.

use std::io::{BufRead, BufReader, Write};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Kills and reaps the child when dropped, whatever happens in the test.
struct Reaped(Child);
impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

struct Env {
    dir: std::path::PathBuf,
    _rt: tokio::runtime::Runtime,
}

impl Env {
    fn new(tag: &str) -> Env {
        let rt = tokio::runtime::Runtime::new().unwrap();
        let ns = rt
            .block_on(yarp_net::nameserver::NameServer::bind(
                "127.0.0.1:0",
                "127.0.0.1",
            ))
            .unwrap();
        let port = ns.local_addr().port();
        rt.spawn(ns.serve());
        let dir = std::env::temp_dir().join(format!("yarp-cli-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("yarp.conf"), format!("127.0.0.1 {port} yarp\n")).unwrap();
        Env { dir, _rt: rt }
    }

    fn yarp(&self, args: &[&str]) -> Command {
        let mut c = Command::new(env!("CARGO_BIN_EXE_yarp"));
        c.args(args)
            .env("YARP_CONFIG_HOME", &self.dir)
            .env_remove("YARP_NAMESPACE");
        c
    }

    fn run(&self, args: &[&str]) -> (bool, String) {
        let out = self.yarp(args).output().expect("run yarp");
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    }

    fn wait_exists(&self, port: &str) {
        let t0 = Instant::now();
        while !self.run(&["exists", port]).0 {
            assert!(
                t0.elapsed() < Duration::from_secs(10),
                "{port} never appeared"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Env {
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

#[test]
fn read_write_connect_disconnect_name() {
    let env = Env::new("rw");
    let mut reader = Reaped(
        env.yarp(&["read", "/r"])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let got = lines(&mut reader.0);
    env.wait_exists("/r");
    let (ok, out) = env.run(&["name", "query", "/r"]);
    assert!(ok);
    assert!(
        out.starts_with("registration name /r ip 127.0.0.1 port "),
        "{out}"
    );
    assert!(out.ends_with(" type tcp\n\n"), "{out:?}");

    let mut writer = Reaped(
        env.yarp(&["write", "/w"])
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    env.wait_exists("/w");
    let (ok, out) = env.run(&["connect", "/w", "/r"]);
    assert!(ok, "{out}");
    assert_eq!(
        out,
        "[INFO] |yarp.os.Network| Success: Added connection from /w to /r\r\n\n"
    );
    assert!(env.run(&["exists", "/w", "/r"]).0);

    let stdin = writer.0.stdin.as_mut().unwrap();
    stdin
        .write_all(b"hello 42\n1 2.5 [ok] \"two words\" (3 4)\n")
        .unwrap();
    stdin.flush().unwrap();
    let t = Duration::from_secs(10);
    assert_eq!(got.recv_timeout(t).unwrap(), "hello 42");
    assert_eq!(
        got.recv_timeout(t).unwrap(),
        "1 2.5 [ok] \"two words\" (3 4)"
    );

    let (ok, out) = env.run(&["disconnect", "/w", "/r"]);
    assert!(ok, "{out}");
    assert!(
        out.ends_with("Success: Removed connection from /w to /r\r\n\n"),
        "{out:?}"
    );
    assert!(!env.run(&["exists", "/w", "/r"]).0);

    // closing the writer (EOF) unregisters it
    drop(writer.0.stdin.take());
    let t0 = Instant::now();
    while env.run(&["exists", "/w"]).0 {
        assert!(t0.elapsed() < t, "/w still registered");
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(!env.run(&["exists", "/nonexistent"]).0);
}

#[test]
fn rpc_against_rpcserver() {
    let env = Env::new("rpc");
    let mut server = Reaped(
        env.yarp(&["rpcserver", "/srv"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let _server_out = lines(&mut server.0);
    server
        .0
        .stdin
        .as_mut()
        .unwrap()
        .write_all(b"[is] 42\n[many] \"a b\" c\n")
        .unwrap();
    env.wait_exists("/srv");
    let mut client = env
        .yarp(&["rpc", "/srv"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    client
        .stdin
        .as_mut()
        .unwrap()
        .write_all(b"[get] x\nsecond\n")
        .unwrap();
    drop(client.stdin.take());
    let out = client.wait_with_output().unwrap();
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "Response: [is] 42\nResponses:\n  a b\n  c\n"
    );
}

#[test]
fn conf_and_where() {
    let env = Env::new("conf");
    let (ok, out) = env.run(&["where"]);
    assert!(ok, "{out}");
    assert!(
        out.contains("Name server /root is available at ip 127.0.0.1 port"),
        "{out}"
    );
    let (ok, out) = env.run(&["conf"]);
    assert!(ok);
    assert!(out.trim_end().ends_with("yarp.conf"));
}

#[test]
fn readwrite_reads_one_port_and_writes_another() {
    let env = Env::new("rwr");
    let mut rw = Reaped(
        env.yarp(&["readwrite", "/rw/in", "/rw/out"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let got = lines(&mut rw.0);
    env.wait_exists("/rw/out");
    let mut reader = Reaped(
        env.yarp(&["read", "/rw/check"])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let checked = lines(&mut reader.0);
    env.wait_exists("/rw/check");
    assert!(env.run(&["connect", "/rw/out", "/rw/check"]).0);
    let stdin = rw.0.stdin.as_mut().unwrap();
    stdin.write_all(b"from stdin 1\n").unwrap();
    stdin.flush().unwrap();
    let t = Duration::from_secs(10);
    assert_eq!(checked.recv_timeout(t).unwrap(), "from stdin 1");
    let mut w = env
        .yarp(&["write", "/rw/w", "/rw/in"])
        .stdin(Stdio::piped())
        .spawn()
        .unwrap();
    w.stdin
        .as_mut()
        .unwrap()
        .write_all(b"to the reader 2\n")
        .unwrap();
    drop(w.stdin.take());
    let _ = w.wait();
    assert_eq!(got.recv_timeout(t).unwrap(), "to the reader 2");
}

#[test]
fn ping_describes_a_port() {
    let env = Env::new("ping");
    let _reader = Reaped(
        env.yarp(&["read", "/pinged"])
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    env.wait_exists("/pinged");
    let (ok, out) = env.run(&["ping", "/pinged"]);
    assert!(ok, "{out}");
    assert!(
        out.starts_with("This is /pinged at tcp://127.0.0.1:"),
        "{out}"
    );
    assert!(
        out.contains("There is an input connection from <ping> to /pinged using text_ack"),
        "{out}"
    );
    let (ok, out) = env.run(&["ping", "--time", "/pinged"]);
    assert!(ok);
    assert!(
        out.starts_with("Timing communication with /pinged...\n"),
        "{out}"
    );
    assert!(out.contains("connection time"), "{out}");
    // C++ says `[ERROR] could not find port` (on stderr) and exits 1
    let (ok, _) = env.run(&["ping", "/nobody"]);
    assert!(!ok);
}
