//! Helpers for tests that run the real `yarp-launch` with real modules: a free port, a
//! private YARP config dir, the launcher as a child (always reaped), its output lines,
//! and a minimal HTTP client for the dashboard (no external crates).

#![allow(dead_code)]

pub mod browser;
pub mod ros;

use nix::sys::signal::kill;
pub use nix::sys::signal::Signal;
use nix::unistd::Pid;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

/// The directory holding the workspace programs (`yarp`, `yarpserver`, ...).
pub fn bin_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("YARP_BIN_DIR") {
        return PathBuf::from(d);
    }
    Path::new(env!("CARGO_BIN_EXE_yarp-launch"))
        .parent()
        .expect("bin dir")
        .to_path_buf()
}

/// Path of a workspace program; panics with the build command when it is missing.
pub fn program(name: &str, package: &str) -> PathBuf {
    let p = bin_dir().join(name);
    assert!(
        p.exists(),
        "{} not found: run `cargo build -p {package}` (same CARGO_TARGET_DIR) or set YARP_BIN_DIR",
        p.display()
    );
    p
}

/// A TCP port nobody listens on right now.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("free port")
}

/// The repository's launch-configs directory.
pub fn configs_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A running `yarp-launch`, killed (with its modules, through their parent-death signal)
/// when dropped.
pub struct Launch {
    pub child: Child,
    pub lines: Receiver<String>,
    pub seen: Vec<String>,
    pub conf_home: tempfile::TempDir,
    pub ns_port: u16,
}

impl Launch {
    /// Starts `yarp-launch CONFIG --set name_server.address=127.0.0.1:<free> EXTRA...`
    /// with a private yarp.conf directory.
    pub fn start(config: &Path, extra: &[&str]) -> Launch {
        Launch::start_with_env(config, extra, &[])
    }

    /// [`Launch::start`] with extra environment variables.
    pub fn start_with_env(config: &Path, extra: &[&str], env: &[(&str, &str)]) -> Launch {
        program("yarp", "yarp-cli");
        program("yarpserver", "yarp-net");
        let conf_home = tempfile::tempdir().expect("tempdir");
        let ns_port = free_port();
        let mut child = Command::new(env!("CARGO_BIN_EXE_yarp-launch"))
            .arg(config)
            .arg("--set")
            .arg(format!("name_server.address=127.0.0.1:{ns_port}"))
            .args(extra)
            .env("YARP_CONFIG_HOME", conf_home.path())
            .env("YARP_BIN_DIR", bin_dir())
            .envs(env.iter().copied())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn yarp-launch");
        let (tx, rx) = mpsc::channel();
        for out in [
            Box::new(child.stdout.take().expect("stdout")) as Box<dyn Read + Send>,
            Box::new(child.stderr.take().expect("stderr")),
        ] {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(out).lines().map_while(Result::ok) {
                    if tx.send(line).is_err() {
                        break;
                    }
                }
            });
        }
        Launch {
            child,
            lines: rx,
            seen: Vec::new(),
            conf_home,
            ns_port,
        }
    }

    /// Waits for an output line containing `text`; panics with the output so far after `limit`.
    pub fn wait_line(&mut self, text: &str, limit: Duration) -> String {
        if let Some(l) = self.seen.iter().find(|l| l.contains(text)) {
            return l.clone();
        }
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) => {
                    self.seen.push(l.clone());
                    if l.contains(text) {
                        return l;
                    }
                }
                Err(_) => panic!(
                    "no line with {text:?} within {limit:?}; output:\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }

    /// Takes every line printed so far.
    pub fn drain(&mut self) -> &[String] {
        while let Ok(l) = self.lines.try_recv() {
            self.seen.push(l);
        }
        &self.seen
    }

    /// The dashboard URL the launcher printed (`http://host:port/`).
    pub fn dashboard_url(&mut self) -> String {
        let line = self.wait_line("dashboard at http://", Duration::from_secs(30));
        line.split_whitespace()
            .find(|w| w.starts_with("http://"))
            .expect("url")
            .to_string()
    }

    /// Sends `sig` and waits (bounded) for the launcher to exit; returns its exit code.
    pub fn stop(&mut self, sig: Signal, limit: Duration) -> Option<i32> {
        let _ = kill(Pid::from_raw(self.child.id() as i32), sig);
        let deadline = Instant::now() + limit;
        loop {
            if let Ok(Some(st)) = self.child.try_wait() {
                // Let the output threads deliver the last lines.
                std::thread::sleep(Duration::from_millis(100));
                self.drain();
                return st.code();
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                let _ = self.child.wait();
                self.drain();
                panic!(
                    "yarp-launch did not stop within {limit:?}; output:\n{}",
                    self.seen.join("\n")
                );
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Launch {
    /// Waits (bounded) for the launcher to exit by itself; returns its exit code.
    pub fn stop_when_exited(&mut self, limit: Duration) -> Option<i32> {
        let deadline = Instant::now() + limit;
        while Instant::now() < deadline {
            if let Ok(Some(st)) = self.child.try_wait() {
                std::thread::sleep(Duration::from_millis(100));
                self.drain();
                return st.code();
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        self.drain();
        panic!(
            "yarp-launch did not exit within {limit:?}; output:\n{}",
            self.seen.join("\n")
        );
    }
}

impl Drop for Launch {
    /// A failed test still stops the launch the way a user would (SIGTERM, so that every
    /// module and its children are stopped), and only then kills the launcher.
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = kill(Pid::from_raw(self.child.id() as i32), Signal::SIGTERM);
            let deadline = Instant::now() + Duration::from_secs(30);
            while Instant::now() < deadline {
                if let Ok(Some(_)) = self.child.try_wait() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Whether a process exists and is not a zombie.
pub fn process_alive(pid: i32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(stat) => stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().next())
            .is_some_and(|state| state != "Z" && state != "X"),
        Err(_) => false,
    }
}

/// Waits (bounded) until none of `pids` is alive; returns the ones still alive.
pub fn wait_gone(pids: &[i32], limit: Duration) -> Vec<i32> {
    let deadline = Instant::now() + limit;
    loop {
        let alive: Vec<i32> = pids.iter().copied().filter(|&p| process_alive(p)).collect();
        if alive.is_empty() || Instant::now() > deadline {
            return alive;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A GET over HTTP/1.0: (status code, body).
pub fn http_get(url: &str) -> (u16, Vec<u8>) {
    let rest = url.strip_prefix("http://").expect("http url");
    let (host, path) = match rest.find('/') {
        Some(i) => (&rest[..i], &rest[i..]),
        None => (rest, "/"),
    };
    let mut s = TcpStream::connect(host).expect("connect to dashboard");
    s.set_read_timeout(Some(Duration::from_secs(10))).ok();
    write!(
        s,
        "GET {path} HTTP/1.0\r\nHost: {host}\r\nConnection: close\r\n\r\n"
    )
    .expect("send");
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).expect("read reply");
    let split = buf
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("header end");
    let head = String::from_utf8_lossy(&buf[..split]).into_owned();
    let code = head
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    (code, buf[split + 4..].to_vec())
}

/// GET returning JSON.
pub fn get_json(url: &str) -> serde_json::Value {
    let (code, body) = http_get(url);
    assert_eq!(code, 200, "{url}: {}", String::from_utf8_lossy(&body));
    serde_json::from_slice(&body).expect("json")
}

/// Polls `f` every 100 ms until it returns Some, up to `limit`.
pub fn eventually<T>(limit: Duration, mut f: impl FnMut() -> Option<T>) -> Option<T> {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(v) = f() {
            return Some(v);
        }
        if Instant::now() > deadline {
            return None;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// Writes `text` to `name` in a fresh temp dir (kept alive by the returned guard).
pub fn write_config(name: &str, text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = dir.path().join(name);
    std::fs::write(&p, text).expect("write config");
    (dir, p)
}
