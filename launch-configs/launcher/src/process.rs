//! One child process in its own process group: spawning with prefixed log lines, and the
//! escalating stop (SIGINT, then SIGTERM, then SIGKILL to the whole group).

use nix::sys::signal::{killpg, Signal};
use nix::unistd::Pid;
use parking_lot::Mutex;
use std::collections::VecDeque;
use std::path::Path;
use std::process::{ExitStatus, Stdio};
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncBufReadExt, AsyncRead, BufReader};
use tokio::process::{Child, Command};
use tokio::sync::broadcast;

/// Lines kept per module for the dashboard.
pub const LOG_TAIL: usize = 200;

/// The recent output of a module, shared with the dashboard and readiness checks.
#[derive(Debug, Clone)]
pub struct LogTail {
    lines: Arc<Mutex<VecDeque<String>>>,
    tx: broadcast::Sender<String>,
}

impl Default for LogTail {
    fn default() -> Self {
        LogTail {
            lines: Arc::new(Mutex::new(VecDeque::with_capacity(LOG_TAIL))),
            tx: broadcast::channel(256).0,
        }
    }
}

impl LogTail {
    pub fn push(&self, line: String) {
        let mut l = self.lines.lock();
        if l.len() == LOG_TAIL {
            l.pop_front();
        }
        l.push_back(line.clone());
        let _ = self.tx.send(line);
    }

    /// The kept lines, oldest first.
    pub fn lines(&self) -> Vec<String> {
        let l = self.lines.lock();
        l.iter().cloned().collect()
    }

    /// Lines from now on.
    pub fn subscribe(&self) -> broadcast::Receiver<String> {
        self.tx.subscribe()
    }
}

/// What to run.
#[derive(Debug, Clone)]
pub struct Spawn<'a> {
    /// Log prefix.
    pub name: &'a str,
    pub program: &'a Path,
    pub args: &'a [String],
    pub env: &'a [(String, String)],
    pub cwd: Option<&'a Path>,
}

/// A running child: leader of its own process group (pgid = pid).
#[derive(Debug)]
pub struct Running {
    pub child: Child,
    pub pid: i32,
}

/// Starts the program in a new process group with piped output; each line is printed as
/// `[name] line` (stdout to stdout, stderr to stderr) and kept in `tail`.
pub fn spawn(s: &Spawn<'_>, tail: &LogTail) -> std::io::Result<Running> {
    let mut cmd = Command::new(s.program);
    cmd.args(s.args)
        .envs(s.env.iter().map(|(k, v)| (k, v)))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0)
        .kill_on_drop(true);
    if let Some(d) = s.cwd {
        cmd.current_dir(d);
    }
    // SAFETY: the closure runs in the forked child before exec and only makes
    // async-signal-safe system calls (sigaction, prctl).
    unsafe {
        cmd.pre_exec(|| {
            // A launcher started in the background by a shell inherits SIGINT ignored;
            // modules must get the default actions so that the stop sequence works.
            for sig in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGQUIT] {
                nix::sys::signal::signal(sig, nix::sys::signal::SigHandler::SigDfl)
                    .map_err(std::io::Error::from)?;
            }
            // If the launcher dies without stopping its modules, the kernel stops them.
            nix::sys::prctl::set_pdeathsig(Signal::SIGTERM).map_err(std::io::Error::from)
        });
    }
    let mut child = cmd.spawn()?;
    let pid = child.id().map(|p| p as i32).unwrap_or(0);
    if let Some(out) = child.stdout.take() {
        tokio::spawn(forward(out, s.name.to_string(), tail.clone(), false));
    }
    if let Some(err) = child.stderr.take() {
        tokio::spawn(forward(err, s.name.to_string(), tail.clone(), true));
    }
    Ok(Running { child, pid })
}

async fn forward(r: impl AsyncRead + Unpin, name: String, tail: LogTail, is_err: bool) {
    let mut lines = BufReader::new(r).lines();
    while let Ok(Some(line)) = lines.next_line().await {
        if is_err {
            eprintln!("[{name}] {line}");
        } else {
            println!("[{name}] {line}");
        }
        tail.push(line);
    }
}

/// Sends `sig` to the process group `pgid`; false when no process is left in it.
pub fn signal_group(pgid: i32, sig: Option<Signal>) -> bool {
    if pgid <= 0 {
        return false;
    }
    killpg(Pid::from_raw(pgid), sig).is_ok()
}

/// Whether any process of the group is still alive. Zombies (killed, not yet reaped by
/// their new parent) do not count: they hold no resources and cannot be signalled away.
pub fn group_alive(pgid: i32) -> bool {
    if !signal_group(pgid, None) {
        return false;
    }
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return true;
    };
    dir.filter_map(Result::ok)
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .bytes()
                .all(|b| b.is_ascii_digit())
        })
        .filter_map(|e| std::fs::read_to_string(e.path().join("stat")).ok())
        .any(|stat| live_member_of(&stat, pgid))
}

/// Reads a `/proc/PID/stat` line: is it a live (non-zombie) process of group `pgid`?
fn live_member_of(stat: &str, pgid: i32) -> bool {
    // Fields after the parenthesised command name: state ppid pgrp ...
    let Some((_, rest)) = stat.rsplit_once(')') else {
        return false;
    };
    let mut f = rest.split_whitespace();
    let state = f.next().unwrap_or("Z");
    let pgrp = f.nth(1).and_then(|p| p.parse::<i32>().ok());
    pgrp == Some(pgid) && !matches!(state, "Z" | "X")
}

/// Kills what is left of a group whose leader has exited (grandchildren that kept
/// running), waiting up to `grace` after SIGTERM before SIGKILL.
pub async fn reap_group(pgid: i32, grace: Duration) {
    if !group_alive(pgid) {
        return;
    }
    signal_group(pgid, Some(Signal::SIGTERM));
    let deadline = tokio::time::Instant::now() + grace;
    while group_alive(pgid) && tokio::time::Instant::now() < deadline {
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    if group_alive(pgid) {
        signal_group(pgid, Some(Signal::SIGKILL));
    }
}

/// Stops a child the caller owns: SIGINT, SIGTERM, SIGKILL to its group, waiting `step`
/// after each. Returns the exit status, and which signal finally stopped it.
pub async fn stop(run: &mut Running, step: Duration) -> (Option<ExitStatus>, &'static str) {
    for (sig, label) in [
        (Signal::SIGINT, "SIGINT"),
        (Signal::SIGTERM, "SIGTERM"),
        (Signal::SIGKILL, "SIGKILL"),
    ] {
        signal_group(run.pid, Some(sig));
        if let Ok(Ok(st)) = tokio::time::timeout(step, run.child.wait()).await {
            reap_group(run.pid, step).await;
            return (Some(st), label);
        }
    }
    (None, "SIGKILL")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn sh(script: &str) -> (PathBuf, Vec<String>) {
        (
            PathBuf::from("/bin/sh"),
            vec!["-c".to_string(), script.to_string()],
        )
    }

    #[test]
    fn proc_stat_lines() {
        assert!(live_member_of("12 (a b) S 1 77 77 0", 77));
        assert!(!live_member_of("12 (a) b) Z 1 77 77 0", 77));
        assert!(!live_member_of("12 (a) S 1 78 78 0", 77));
        assert!(!live_member_of("garbage", 77));
    }

    #[tokio::test]
    async fn logs_and_exit_status() {
        let (p, a) = sh("echo hello; echo oops >&2; exit 3");
        let tail = LogTail::default();
        let mut r = spawn(
            &Spawn {
                name: "t",
                program: &p,
                args: &a,
                env: &[],
                cwd: None,
            },
            &tail,
        )
        .unwrap();
        let st = r.child.wait().await.unwrap();
        assert_eq!(st.code(), Some(3));
        tokio::time::sleep(Duration::from_millis(100)).await;
        let lines = tail.lines();
        assert!(lines.contains(&"hello".to_string()), "{lines:?}");
        assert!(lines.contains(&"oops".to_string()), "{lines:?}");
    }

    #[tokio::test]
    async fn stop_escalates_and_kills_the_group() {
        // Ignores SIGINT and SIGTERM, and has a grandchild doing the same.
        let (p, a) = sh("trap '' INT TERM; sh -c \"trap '' INT TERM; sleep 30\" & sleep 30");
        let tail = LogTail::default();
        let mut r = spawn(
            &Spawn {
                name: "t",
                program: &p,
                args: &a,
                env: &[("X".into(), "1".into())],
                cwd: Some(Path::new("/")),
            },
            &tail,
        )
        .unwrap();
        tokio::time::sleep(Duration::from_millis(200)).await;
        let (st, how) = stop(&mut r, Duration::from_millis(300)).await;
        assert!(st.is_some());
        assert_eq!(how, "SIGKILL");
        assert!(!group_alive(r.pid));
    }

    #[tokio::test]
    async fn sigint_is_enough_for_a_polite_child() {
        // The program itself, not a shell around it: a shell that has not finished
        // starting may not act on SIGINT yet.
        let (p, a) = (PathBuf::from("/bin/sleep"), vec!["30".to_string()]);
        let mut r = spawn(
            &Spawn {
                name: "t",
                program: &p,
                args: &a,
                env: &[],
                cwd: None,
            },
            &LogTail::default(),
        )
        .unwrap();
        let (st, how) = stop(&mut r, Duration::from_secs(3)).await;
        assert_eq!(how, "SIGINT");
        assert!(st.is_some());
        assert!(!group_alive(r.pid));
    }
}
