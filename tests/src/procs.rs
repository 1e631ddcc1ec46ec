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

/// Longest a step of [`YarpNet`] may take (a loaded 2-core machine starts programs slowly).
pub const STEP: Duration = Duration::from_secs(20);

/// A private YARP network for child processes: a config dir (`YARP_CONFIG_HOME`) naming
/// a name server on a free port below the ephemeral range ([`crate::low_ports`]).
pub struct YarpNet {
    pub dir: tempfile::TempDir,
    pub port: u16,
}

impl Default for YarpNet {
    fn default() -> Self {
        Self::new()
    }
}

impl YarpNet {
    pub fn new() -> YarpNet {
        let port = crate::low_ports()
            .find(|&p| (0..4).all(|i| std::net::TcpListener::bind(("127.0.0.1", p + i)).is_ok()))
            .expect("a free port for the name server (run under netns-run)");
        YarpNet {
            dir: tempfile::tempdir().expect("temp dir"),
            port,
        }
    }

    /// A workspace program (see [`workspace_program`]) on this network.
    pub fn cmd(&self, program: &str, package: &str) -> Command {
        let mut c = Command::new(workspace_program(program, package));
        c.env("YARP_CONFIG_HOME", self.dir.path())
            .env_remove("YARP_NAMESPACE")
            .env("RUST_LOG", "info");
        c
    }

    /// Our `yarp` companion.
    pub fn yarp(&self) -> Command {
        self.cmd("yarp", "yarp-cli")
    }

    /// Starts our `yarpserver` on the network's port (again after a kill: same port).
    pub fn server(&self) -> Proc {
        let mut c = self.cmd("yarpserver", "yarp-net");
        c.args([
            "--ip",
            "127.0.0.1",
            "--socket",
            &self.port.to_string(),
            "--write",
        ]);
        let mut p = Proc::spawn("yarpserver", c);
        p.wait_line("Ok. Ready!", STEP);
        p
    }

    /// `yarp name query PORT`: the registered TCP port, if any.
    pub fn query(&self, port: &str) -> Option<u16> {
        let out = self.yarp().args(["name", "query", port]).output().ok()?;
        if !out.status.success() {
            return None;
        }
        // registration name /p ip 127.0.0.1 port 10002 type tcp
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        let words: Vec<&str> = text.split_whitespace().collect();
        let at = words.iter().position(|w| *w == "port")?;
        words.get(at + 1)?.parse().ok()
    }

    /// Waits (at most `limit`) until `port` is registered; its TCP port.
    pub fn wait_registered_within(&self, port: &str, limit: Duration) -> u16 {
        let start = Instant::now();
        loop {
            if let Some(p) = self.query(port) {
                return p;
            }
            assert!(start.elapsed() < limit, "{port} never registered");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// As [`YarpNet::wait_registered_within`], at most [`STEP`].
    pub fn wait_registered(&self, port: &str) -> u16 {
        self.wait_registered_within(port, STEP)
    }

    /// `yarp connect FROM TO`: whether it succeeded.
    pub fn connect(&self, from: &str, to: &str) -> bool {
        self.yarp()
            .args(["connect", from, to])
            .output()
            .is_ok_and(|o| o.status.success())
    }

    /// `yarp rpc PORT` fed `input`: every line it printed, bounded by [`STEP`].
    pub fn rpc(&self, port: &str, input: &str) -> String {
        let mut c = self.yarp();
        c.args(["rpc", port]);
        run_fed("yarp rpc", c, input, STEP)
    }
}

/// Runs `cmd` with `input` on its stdin (then closed) until it exits, at most `limit`
/// (then it is killed): every line it printed.
pub fn run_fed(name: &str, cmd: Command, input: &str, limit: Duration) -> String {
    let mut p = Proc::spawn(name, cmd);
    {
        use std::io::Write;
        let mut stdin = p.child.stdin.take().expect("stdin");
        let _ = stdin.write_all(input.as_bytes());
    }
    let start = Instant::now();
    while p.child.try_wait().ok().flatten().is_none() && start.elapsed() < limit {
        std::thread::sleep(Duration::from_millis(20));
    }
    // the reader threads deliver what is left once the pipes close
    let _ = p.try_wait_line("\u{0}", Duration::from_millis(300));
    p.seen.join("\n")
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
