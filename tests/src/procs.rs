//! Child processes of the fault tests: the workspace's programs, their output as lines,
//! and what the kernel says they hold (open descriptors, threads, resident memory).

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

/// A workspace program beside the running test's target directory; panics with the
/// build command when it is missing (our own programs are never an optional peer).
pub fn workspace_program(name: &str, package: &str) -> PathBuf {
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

/// A child whose stdout and stderr lines arrive on one channel; killed and reaped when
/// dropped (or by [`Proc::kill`]).
pub struct Proc {
    pub child: Child,
    lines: Receiver<String>,
    /// Every line seen so far, for failure messages.
    pub seen: Vec<String>,
    name: String,
}

fn forward(r: impl Read + Send + 'static, tx: mpsc::Sender<String>) {
    std::thread::spawn(move || {
        for l in BufReader::new(r).lines().map_while(Result::ok) {
            if tx.send(l).is_err() {
                return;
            }
        }
    });
}

impl Proc {
    /// Starts `cmd` with its stdin piped (take it from `child.stdin` to feed it).
    pub fn spawn(name: &str, mut cmd: Command) -> Proc {
        let mut child = cmd
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("spawn {name}: {e}"));
        let (tx, rx) = mpsc::channel();
        forward(child.stdout.take().expect("stdout"), tx.clone());
        forward(child.stderr.take().expect("stderr"), tx);
        Proc {
            child,
            lines: rx,
            seen: Vec::new(),
            name: name.to_string(),
        }
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The first line (from now on) containing `text`, within `limit`; panics with what
    /// the program printed otherwise.
    pub fn wait_line(&mut self, text: &str, limit: Duration) -> String {
        self.try_wait_line(text, limit).unwrap_or_else(|| {
            panic!(
                "{}: no line with {text:?} within {limit:?}; it printed:\n{}",
                self.name,
                self.seen.join("\n")
            )
        })
    }

    /// As [`Proc::wait_line`], `None` on timeout.
    pub fn try_wait_line(&mut self, text: &str, limit: Duration) -> Option<String> {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let l = self.lines.recv_timeout(left).ok()?;
            self.seen.push(l.clone());
            if l.contains(text) {
                return Some(l);
            }
        }
    }

    /// Lines printed since the last call (without waiting).
    pub fn drain(&mut self) -> Vec<String> {
        let new: Vec<String> = self.lines.try_iter().collect();
        self.seen.extend(new.iter().cloned());
        new
    }

    /// Kills (SIGKILL) and reaps the program.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Open file descriptors of process `pid`.
pub fn fd_count(pid: u32) -> usize {
    std::fs::read_dir(format!("/proc/{pid}/fd"))
        .map(|d| d.count())
        .unwrap_or(0)
}

/// Threads of process `pid`.
pub fn thread_count(pid: u32) -> usize {
    std::fs::read_dir(format!("/proc/{pid}/task"))
        .map(|d| d.count())
        .unwrap_or(0)
}

/// Resident memory of process `pid`, KiB (`VmRSS`).
pub fn rss_kib(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse().ok())
        })
        .unwrap_or(0)
}

/// Polls `f` every 50 ms until it holds, at most `limit`; whether it did.
pub fn eventually(limit: Duration, mut f: impl FnMut() -> bool) -> bool {
    let deadline = Instant::now() + limit;
    loop {
        if f() {
            return true;
        }
        if Instant::now() >= deadline {
            return false;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}
