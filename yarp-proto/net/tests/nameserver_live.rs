//! The `yarpserver` binary as a child process, talked to over real loopback sockets:
//! start-up lines, `yarp.conf`, the C++ client sequence, text and binary sessions,
//! garbage, and a clean SIGTERM shutdown. Every wait is bounded; the child is always
//! killed and reaped (drop guard).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use yarp_net::nameserver::NameClient;
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::Bottle;

const WAIT: Duration = Duration::from_secs(20);

struct Guard {
    child: Option<Child>,
    lines: mpsc::Receiver<String>,
    seen: Vec<String>,
    dir: PathBuf,
}

impl Drop for Guard {
    fn drop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl Guard {
    /// Waits for a stdout line containing `needle`.
    fn wait_line(&mut self, needle: &str) -> Option<String> {
        if let Some(l) = self.seen.iter().find(|l| l.contains(needle)) {
            return Some(l.clone());
        }
        let deadline = Instant::now() + WAIT;
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match self.lines.recv_timeout(left) {
                Ok(l) => {
                    self.seen.push(l.clone());
                    if l.contains(needle) {
                        return Some(l);
                    }
                }
                Err(_) => return None,
            }
        }
        None
    }

    fn wait_exit(&mut self) -> Option<ExitStatus> {
        let deadline = Instant::now() + WAIT;
        let child = self.child.as_mut()?;
        while Instant::now() < deadline {
            if let Ok(Some(st)) = child.try_wait() {
                self.child = None;
                return Some(st);
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        None
    }
}

fn free_port() -> u16 {
    let l = TcpListener::bind("127.0.0.1:0").expect("bind probe");
    l.local_addr().expect("addr").port()
}

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "yarpserver-live-{tag}-{}-{}",
        std::process::id(),
        free_port()
    ));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn spawn(args: &[&str], dir: &PathBuf) -> Guard {
    let mut child = Command::new(env!("CARGO_BIN_EXE_yarpserver"))
        .args(args)
        .env("YARP_CONFIG_HOME", dir)
        .env_remove("YARP_NAMESPACE")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn yarpserver");
    let (tx, rx) = mpsc::channel();
    if let Some(out) = child.stdout.take() {
        let tx = tx.clone();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines().map_while(Result::ok) {
                let _ = tx.send(l);
            }
        });
    }
    if let Some(err) = child.stderr.take() {
        std::thread::spawn(move || {
            for l in BufReader::new(err).lines().map_while(Result::ok) {
                let _ = tx.send(format!("stderr: {l}"));
            }
        });
    }
    Guard {
        child: Some(child),
        lines: rx,
        seen: Vec::new(),
        dir: dir.clone(),
    }
}

fn connect(addr: SocketAddr) -> TcpStream {
    let s = TcpStream::connect_timeout(&addr, WAIT).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(5)))
        .expect("timeout");
    s.set_write_timeout(Some(Duration::from_secs(5)))
        .expect("timeout");
    s
}

fn read_until(s: &mut TcpStream, end: &[u8]) -> Vec<u8> {
    let mut buf = Vec::new();
    let mut b = [0u8; 4096];
    while !buf.ends_with(end) {
        match s.read(&mut b) {
            Ok(0) | Err(_) => break,
            Ok(n) => buf.extend_from_slice(&b[..n]),
        }
    }
    buf
}

fn read_n(s: &mut TcpStream, n: usize) -> Vec<u8> {
    let mut buf = vec![0u8; n];
    let mut got = 0;
    while got < n {
        match s.read(&mut buf[got..]) {
            Ok(0) | Err(_) => break,
            Ok(k) => got += k,
        }
    }
    buf.truncate(got);
    buf
}

fn yarp_number(v: i32) -> Vec<u8> {
    let mut out = b"YA".to_vec();
    out.extend_from_slice(&v.to_le_bytes());
    out.extend_from_slice(b"RP");
    out
}

#[test]
fn yarpserver_binary_end_to_end() {
    let port = free_port();
    let dir = temp_dir("main");
    let ps = port.to_string();
    let mut g = spawn(&["--ip", "127.0.0.1", "--socket", &ps], &dir);
    let ready = g
        .wait_line("Name server can be browsed at")
        .unwrap_or_else(|| panic!("no start-up line; saw {:?}", g.seen));
    assert_eq!(
        ready,
        format!(
            "[INFO] |yarp.serversql.Server| Name server can be browsed at http://127.0.0.1:{port}/"
        )
    );
    assert!(g.wait_line("Ok. Ready!").is_some());
    let conf = std::fs::read_to_string(dir.join("yarp.conf")).expect("yarp.conf written");
    assert_eq!(conf, format!("127.0.0.1 {port} yarp\n"));
    let addr: SocketAddr = format!("127.0.0.1:{port}").parse().expect("addr");

    // The C++ client's six-request registration, then queries, over real sockets.
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    rt.block_on(async {
        let client = NameClient::new(addr).with_timeout(Duration::from_secs(5));
        let c = client
            .register_port(&RegisterRequest::name("/live/a"), &["127.0.0.1"], 4242)
            .await
            .expect("register");
        assert_eq!(c.name, "/live/a");
        assert_eq!(c.host, "127.0.0.1");
        assert_eq!(c.port, port + 2);
        assert_eq!(c.carrier, "tcp");
        let q = client.query("/live/a").await.expect("query");
        assert_eq!(q, Some(c.clone()));
        assert_eq!(client.query("/nope").await.expect("query"), None);
        let ips = client
            .get("/live/a", "ips")
            .await
            .expect("get")
            .expect("known");
        assert_eq!(ips.values, vec!["127.0.0.1"]);
        let offers = client
            .get("/live/a", "offers")
            .await
            .expect("get")
            .expect("known");
        assert_eq!(offers.values.first().map(String::as_str), Some("bayer"));
        let list = client.list(None).await.expect("list");
        let names: Vec<&str> = list.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, vec!["/live/a", "/root", "fallback"]);
        assert_eq!(list[1].port, port);
        assert_eq!(list[2].port, 10000);
        client.unregister("/live/a").await.expect("unregister");
        assert_eq!(client.query("/live/a").await.expect("query"), None);
    });

    // Text carrier session with acks.
    let mut s = connect(addr);
    s.write_all(b"CONNACK /t\n").expect("write");
    assert_eq!(read_until(&mut s, b"\r\n"), b"Welcome /t\r\n");
    s.write_all(b"d\nquery /root\n").expect("write");
    let r = read_until(&mut s, b"<ACK>\r\n");
    assert_eq!(
        String::from_utf8_lossy(&r),
        format!("registration name /root ip 127.0.0.1 port {port} type tcp\r\n*** end of message\r\n<ACK>\r\n")
    );
    s.write_all(b"x\n").expect("write");
    assert!(
        read_n(&mut s, 1).is_empty(),
        "server closes on a non-data line"
    );

    // Binary tcp session: header, sender name, one 'd' message holding `bot query /root`.
    let mut s = connect(addr);
    let mut msg = yarp_number(7777 + 3 + 128);
    msg.extend_from_slice(&3i32.to_le_bytes());
    msg.extend_from_slice(b"/b\0");
    s.write_all(&msg).expect("write");
    assert_eq!(read_n(&mut s, 8), yarp_number(port as i32));
    let body = Bottle::from_text("bot query /root").encode();
    let pc: &[u8] = &[0, 0, 0, 0, b'~', b'd', 0, 1];
    let mut m = yarp_number(10);
    m.extend_from_slice(&[2, 1]);
    m.extend_from_slice(&[0xff; 8]);
    m.extend_from_slice(&(pc.len() as i32).to_le_bytes());
    m.extend_from_slice(&(body.len() as i32).to_le_bytes());
    m.extend_from_slice(&0i32.to_le_bytes());
    m.extend_from_slice(pc);
    m.extend_from_slice(&body);
    s.write_all(&m).expect("write");
    let mut want = Bottle::from_text(format!(
        "port (name \"/root\") (ip \"127.0.0.1\") (port_number {port}) (carrier tcp)"
    ))
    .encode();
    want.extend_from_slice(&yarp_number(0));
    assert_eq!(read_n(&mut s, want.len()), want);
    drop(s);

    // Garbage: the protocol-not-found text, then close; the server keeps running.
    let mut s = connect(addr);
    s.write_all(b"\x00\x01garbage!!").expect("write");
    let r = read_until(&mut s, b"Goodbye.\r\n");
    assert!(r.starts_with(b"* Error. Protocol not found."));
    assert!(read_n(&mut s, 1).is_empty());
    let mut s = connect(addr);
    s.write_all(b"NAME_SERVER list /root\n").expect("write");
    let r = read_until(&mut s, b"*** end of message\r\n");
    assert!(String::from_utf8_lossy(&r).starts_with("registration name /root"));
    drop(s);

    // SIGTERM: clean shutdown.
    let pid = g.child.as_ref().map(|c| c.id()).expect("child");
    let killed = Command::new("kill")
        .args(["-TERM", &pid.to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let st = g.wait_exit().expect("yarpserver did not exit on SIGTERM");
    assert!(st.success(), "exit status {st:?}");
    assert!(g.wait_line("closing yarp server").is_some());
}

#[test]
fn yarpserver_read_requires_conf() {
    let port = free_port();
    let dir = temp_dir("read");
    let ps = port.to_string();
    let mut g = spawn(&["--ip", "127.0.0.1", "--socket", &ps, "--read"], &dir);
    let st = g
        .wait_exit()
        .expect("yarpserver --read without yarp.conf must exit");
    assert_eq!(st.code(), Some(1));
    assert!(g.wait_line("Could not read configuration file").is_some());

    // With a matching file it starts and does not rewrite it.
    std::fs::write(dir.join("yarp.conf"), format!("127.0.0.1 {port}\n")).expect("write conf");
    let mut g2 = spawn(&["--ip", "127.0.0.1", "--socket", &ps, "--read"], &dir);
    assert!(g2.wait_line("Ok. Ready!").is_some(), "saw {:?}", g2.seen);
    assert_eq!(
        std::fs::read_to_string(dir.join("yarp.conf")).expect("conf"),
        format!("127.0.0.1 {port}\n")
    );
    // A different port with --read is refused, as in C++.
    let other = free_port().to_string();
    let mut g3 = spawn(&["--ip", "127.0.0.1", "--socket", &other, "--read"], &dir);
    let st = g3.wait_exit().expect("must exit");
    assert_eq!(st.code(), Some(1));
    assert!(g3.wait_line("PROBLEM: need to change settings").is_some());
    drop(g2);
}
