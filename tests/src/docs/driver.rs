//! Runs one documented block as its user would, and says what went wrong if it fails.
//!
//! Every command runs in a shell of its own process group from the repository's root,
//! with the workspace's programs first on `PATH` (`target/debug/` in the text means the
//! cargo target directory), and the YARP configuration, runtime and temporary files in a
//! scratch directory, so a block's `yarp conf` touches nothing of the user's.

use super::directives::{Directives, Mode, Pattern};
use super::markdown::Block;
use std::fmt::Write as _;
use std::fs::File;
use std::io::Write as _;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// Where blocks run.
#[derive(Debug, Clone)]
pub struct Setting {
    /// The repository's root: every block starts there.
    pub root: PathBuf,
    /// The cargo target directory (`target/` unless `CARGO_TARGET_DIR` says otherwise).
    pub target: PathBuf,
    /// A scratch directory of this block's own.
    pub scratch: PathBuf,
    /// The block runs in a network namespace of its own: whatever it leaves running there
    /// is killed at the end.
    pub private_net: bool,
}

impl Setting {
    /// The setting for the repository at `root`, `CARGO_TARGET_DIR` honoured.
    pub fn new(root: &Path, scratch: &Path) -> Setting {
        let target = std::env::var_os("CARGO_TARGET_DIR")
            .map(PathBuf::from)
            .map(|t| if t.is_absolute() { t } else { root.join(t) })
            .unwrap_or_else(|| root.join("target"));
        Setting {
            root: root.to_path_buf(),
            target,
            scratch: scratch.to_path_buf(),
            private_net: false,
        }
    }
}

/// Runs a session of blocks in order, each with its parsed directives: all but the last
/// are brought up and left running (`follows: previous`), the last is the block checked.
/// Returns what it printed, or why it failed with everything printed.
pub fn run_session(steps: &[(&Block, &Directives)], s: &Setting) -> Result<String, String> {
    let mut jobs = Vec::new();
    let mut log = String::new();
    let mut result = Ok(());
    let last = steps.len().saturating_sub(1);
    for (i, (block, d)) in steps.iter().enumerate() {
        let mut run = Runner {
            s,
            d,
            deadline: Instant::now() + d.timeout,
            jobs: std::mem::take(&mut jobs),
            leave_up: i < last,
            log: String::new(),
        };
        result = run.block(block);
        jobs = run.jobs;
        log.push_str(&run.log);
        if let Err(why) = result {
            result = Err(if i < last {
                format!(
                    "the block at line {} (which this one follows): {why}",
                    block.line
                )
            } else {
                why
            });
            break;
        }
    }
    let Some((_, d)) = steps.last() else {
        return Err("nothing to run".into());
    };
    let mut run = Runner {
        s,
        d,
        deadline: Instant::now(),
        jobs,
        leave_up: false,
        log,
    };
    run.stop_all();
    let log = run.report();
    match result {
        Ok(()) => Ok(log),
        Err(why) => Err(format!("{why}\n{log}")),
    }
}

/// Whether the doc comments of `file` hold `code` line for line, so that `cargo test
/// --doc` compiles and runs what the Markdown shows.
fn doctest_holds(file: &Path, code: &str) -> Result<(), String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let docs: Vec<&str> = text
        .lines()
        .filter_map(|l| {
            let l = l.trim_start();
            l.strip_prefix("//!").or_else(|| l.strip_prefix("///"))
        })
        .map(|l| l.strip_prefix(' ').unwrap_or(l).trim_end())
        .collect();
    let want: Vec<&str> = code.lines().map(str::trim_end).collect();
    if docs.windows(want.len()).any(|w| w == want.as_slice()) {
        Ok(())
    } else {
        Err(format!(
            "the block is not in the doc comments of {} (keep the two the same)",
            file.display()
        ))
    }
}

/// A command started by the block.
struct Job {
    /// The block's line it came from (1-based), `None` for a whole script or a check.
    line: Option<usize>,
    command: String,
    child: Child,
    stdin: Option<ChildStdin>,
    output: PathBuf,
    status: Option<ExitStatus>,
    /// Stopped by us (Ctrl-C) once up: an exit by SIGINT is then clean.
    interrupted: bool,
}

impl Job {
    fn output(&self) -> String {
        std::fs::read(&self.output)
            .map(|b| String::from_utf8_lossy(&b).into_owned())
            .unwrap_or_default()
    }

    fn poll(&mut self) -> Option<ExitStatus> {
        if self.status.is_none() {
            self.status = self.child.try_wait().ok().flatten();
        }
        self.status
    }

    /// Ctrl-C to the job's whole process group, as a terminal sends it.
    fn interrupt(&mut self) {
        if self.poll().is_none() {
            self.interrupted = true;
            signal_group("INT", self.child.id());
        }
    }

    fn clean_exit(&self) -> bool {
        use std::os::unix::process::ExitStatusExt;
        match self.status {
            Some(st) if st.success() => true,
            // A program stopped by Ctrl-C: 130 from a shell, or SIGINT itself.
            Some(st) if self.interrupted => st.code() == Some(130) || st.signal() == Some(2),
            _ => false,
        }
    }

    fn describe(&self) -> String {
        let what = match self.line {
            Some(n) => format!("line {n}"),
            None => "command".to_string(),
        };
        let status = match self.status {
            Some(st) => format!("{st}"),
            None => "still running".to_string(),
        };
        format!("{what} `{}` ({status})", self.command)
    }
}

fn signal_group(signal: &str, pgid: u32) {
    let _ = Command::new("kill")
        .args([format!("-{signal}"), "--".into(), format!("-{pgid}")])
        .stderr(Stdio::null())
        .status();
}

struct Runner<'a> {
    s: &'a Setting,
    d: &'a Directives,
    deadline: Instant,
    jobs: Vec<Job>,
    /// Bring the block up and leave it running (a later block follows it).
    leave_up: bool,
    log: String,
}

const POLL: Duration = Duration::from_millis(100);

impl Runner<'_> {
    fn block(&mut self, block: &Block) -> Result<(), String> {
        let d = self.d;
        for before in &d.before {
            let before = self.prepare(before);
            self.run_until_done(None, &before, None, None)?;
        }
        let code = self.prepare(&block.code);
        match &d.mode {
            Mode::Run => self.script(&code),
            Mode::Lines => self.lines(&code),
            Mode::Terminals => self.terminals(&code),
            Mode::Transcript => self.transcript(&code),
            Mode::Synopsis => self.synopsis(&code),
            Mode::Example { .. } => d.checks.iter().try_for_each(|c| {
                let c = self.prepare(c);
                self.run_until_done(None, &c, None, None)
            }),
            Mode::Text { .. } => Ok(()),
            Mode::Doctest { file } => doctest_holds(&self.s.root.join(file), &block.code),
        }
    }

    /// A usage block: the program's `--help` names every `--flag` the block shows.
    fn synopsis(&mut self, code: &str) -> Result<(), String> {
        let program = code
            .split_whitespace()
            .next()
            .ok_or("an empty synopsis")?
            .to_string();
        self.run_until_done(None, &format!("{program} --help"), None, None)?;
        let help = self.jobs[self.jobs.len() - 1].output();
        let flags = regex::Regex::new(r"--[a-z][a-z0-9-]*").expect("regex");
        let missing: Vec<&str> = flags
            .find_iter(code)
            .map(|m| m.as_str())
            .filter(|f| !help.contains(f))
            .collect();
        if missing.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "`{program} --help` does not name {}",
                missing.join(", ")
            ))
        }
    }

    /// The block's text as run: `replace:` applied, `target/debug` the real target dir.
    fn prepare(&self, code: &str) -> String {
        let mut code = code.to_string();
        for (old, new) in &self.d.replace {
            code = code.replace(old, new);
        }
        let debug = self.s.target.join("debug");
        if debug != self.s.root.join("target/debug") {
            let re = regex::Regex::new(r#"(^|[\s="'(])(\$PWD/)?target/debug"#).expect("regex");
            let with = format!("${{1}}{}", debug.display());
            code = re.replace_all(&code, with.as_str()).into_owned();
        }
        code
    }

    fn shell(&self, script: &str) -> Command {
        let mut cmd = Command::new("bash");
        cmd.arg("-o").arg("pipefail").arg("-c").arg(script);
        let path = std::env::var("PATH").unwrap_or_default();
        cmd.env(
            "PATH",
            format!("{}:{path}", self.s.target.join("debug").display()),
        );
        for (k, dir) in [
            ("XDG_CONFIG_HOME", "config"),
            ("XDG_RUNTIME_DIR", "runtime"),
            ("YARP_RUNTIME_DIR", "runtime/yarp"),
            ("TMPDIR", "tmp"),
        ] {
            let p = self.s.scratch.join(dir);
            let _ = std::fs::create_dir_all(&p);
            cmd.env(k, p);
        }
        cmd.env_remove("YARP_CONF").env_remove("YARP_NAMESPACE");
        for (k, v) in &self.d.env {
            cmd.env(k, self.prepare(v));
        }
        cmd.current_dir(&self.s.root).process_group(0);
        cmd
    }

    /// Starts `script` in a shell; `stdin`: `None` for no input, `Some(text)` to pipe it
    /// (`keep_open`: and leave the pipe open, as a terminal).
    fn start(
        &mut self,
        line: Option<usize>,
        script: &str,
        stdin: Option<&str>,
        keep_open: bool,
    ) -> Result<usize, String> {
        let output = self.s.scratch.join(format!("job{}.out", self.jobs.len()));
        let file = File::create(&output).map_err(|e| format!("{}: {e}", output.display()))?;
        let err = file.try_clone().map_err(|e| e.to_string())?;
        let mut cmd = self.shell(script);
        cmd.stdout(file).stderr(err);
        cmd.stdin(if stdin.is_some() || keep_open {
            Stdio::piped()
        } else {
            Stdio::null()
        });
        let mut child = cmd.spawn().map_err(|e| format!("cannot start bash: {e}"))?;
        let mut pipe = child.stdin.take();
        if let (Some(p), Some(text)) = (pipe.as_mut(), stdin) {
            // A program that exits before reading its input is not our failure here.
            let _ = p.write_all(text.as_bytes());
            let _ = p.flush();
        }
        if !keep_open {
            pipe = None;
        }
        self.jobs.push(Job {
            line,
            command: script.to_string(),
            child,
            stdin: pipe,
            output,
            status: None,
            interrupted: false,
        });
        Ok(self.jobs.len() - 1)
    }

    fn left(&self) -> Duration {
        self.deadline.saturating_duration_since(Instant::now())
    }

    fn timed_out(&self, what: &str) -> String {
        format!("timed out after {:?}: {what}", self.d.timeout)
    }

    /// Waits until job `j` exits or, when it has a `ready` pattern, is up (then stops it
    /// with Ctrl-C). Either way it must end cleanly.
    fn run_until_done(
        &mut self,
        line: Option<usize>,
        script: &str,
        stdin: Option<&str>,
        ready: Option<&Pattern>,
    ) -> Result<(), String> {
        let j = self.start(line, script, stdin, false)?;
        loop {
            if let Some(st) = self.jobs[j].poll() {
                return if !st.success() {
                    Err(format!("{} failed", self.jobs[j].describe()))
                } else if ready.is_some()
                    && !ready.is_some_and(|p| p.found_in(&self.jobs[j].output()))
                    // In `lines`, the block's `ready:` is for the lines that stay up; a
                    // line that succeeds and ends (a build, `--check`) is done.
                    && line.is_none_or(|n| self.d.ready.contains_key(&Some(n)))
                {
                    Err(format!(
                        "{} ended before it was up (its output never held {})",
                        self.jobs[j].describe(),
                        ready.expect("ready")
                    ))
                } else {
                    Ok(())
                };
            }
            if let Some(p) = ready {
                if p.found_in(&self.jobs[j].output()) {
                    return if self.leave_up { Ok(()) } else { self.stop(j) };
                }
            }
            if self.left().is_zero() {
                let what = match ready {
                    Some(p) => format!("{} never printed {p}", self.jobs[j].describe()),
                    None => format!("{} did not end", self.jobs[j].describe()),
                };
                return Err(self.timed_out(&what));
            }
            std::thread::sleep(POLL);
        }
    }

    /// Ctrl-C, then it must end cleanly within the block's `stop` time.
    fn stop(&mut self, j: usize) -> Result<(), String> {
        self.jobs[j].interrupt();
        let started = Instant::now();
        let limit = started + self.d.stop;
        while self.jobs[j].poll().is_none() {
            if Instant::now() > limit {
                return Err(format!(
                    "{} did not stop within {:?} of Ctrl-C",
                    self.jobs[j].describe(),
                    self.d.stop
                ));
            }
            std::thread::sleep(POLL);
        }
        let _ = writeln!(
            self.log,
            "stopped line {:?} {:.1} s after Ctrl-C",
            self.jobs[j].line,
            started.elapsed().as_secs_f64()
        );
        if self.jobs[j].clean_exit() {
            Ok(())
        } else {
            Err(format!(
                "{} did not stop cleanly on Ctrl-C",
                self.jobs[j].describe()
            ))
        }
    }

    fn script(&mut self, code: &str) -> Result<(), String> {
        // `set -m`: as in an interactive shell, each `cmd &` is a job of its own, so the
        // Ctrl-C that stops the script reaches its foreground command only (a robot parks
        // on boards that are still there).
        let script = format!("set -e -m\n{code}");
        let d = self.d;
        self.run_until_done(None, &script, d.stdin.as_deref(), d.ready_for(None))?;
        self.expectations()
    }

    fn lines(&mut self, code: &str) -> Result<(), String> {
        let d = self.d;
        for (n, line) in logical_lines(code) {
            self.run_until_done(Some(n), &line, d.stdin.as_deref(), d.ready_for(Some(n)))?;
        }
        self.expectations()
    }

    fn terminals(&mut self, code: &str) -> Result<(), String> {
        for (n, line) in logical_lines(code) {
            let line = strip_background(&line);
            let typed = self.d.typed.get(&n).cloned();
            let interactive = typed.is_some() || self.d.expect.iter().any(|(l, _)| *l == Some(n));
            let j = self.start(Some(n), &line, typed.as_deref(), true)?;
            if let Some(probe) = self.d.after.get(&n).cloned() {
                self.until_succeeds(j, &probe)?;
            } else if !interactive {
                // A command that ends by itself: it must succeed before the next one.
                while self.jobs[j].poll().is_none() {
                    if self.left().is_zero() {
                        return Err(self.timed_out(&format!(
                            "{} still runs: give it an `after {n}:` probe",
                            self.jobs[j].describe()
                        )));
                    }
                    std::thread::sleep(POLL);
                }
            }
            if self.jobs[j].status.is_some_and(|st| !st.success()) {
                return Err(format!("{} failed", self.jobs[j].describe()));
            }
        }
        self.expectations()?;
        if self.leave_up {
            return Ok(());
        }
        // Everything that still runs is stopped as a user would: end of input (Ctrl-D)
        // in each terminal, then Ctrl-C in those still running.
        for j in &mut self.jobs {
            j.stdin = None;
        }
        let limit = Instant::now() + Duration::from_secs(2);
        while Instant::now() < limit && self.jobs.iter_mut().any(|j| j.poll().is_none()) {
            std::thread::sleep(POLL);
        }
        for j in 0..self.jobs.len() {
            if self.jobs[j].poll().is_none() {
                self.stop(j)?;
            }
        }
        match self.jobs.iter().find(|j| !j.clean_exit()) {
            Some(j) => Err(format!("{} failed", j.describe())),
            None => Ok(()),
        }
    }

    /// Retries `probe` until it succeeds; job `j` (what it waits for) must not fail meanwhile.
    fn until_succeeds(&mut self, j: usize, probe: &str) -> Result<(), String> {
        loop {
            if let Some(st) = self.jobs[j].poll() {
                if !st.success() {
                    return Err(format!("{} failed", self.jobs[j].describe()));
                }
            }
            let mut cmd = self.shell(probe);
            cmd.stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null());
            if cmd.status().is_ok_and(|st| st.success()) {
                return Ok(());
            }
            if self.left().is_zero() {
                return Err(self.timed_out(&format!("`{probe}` never succeeded")));
            }
            std::thread::sleep(Duration::from_millis(300));
        }
    }

    /// Waits until every `expect` holds in its line's output (or in all the output).
    fn expectations(&mut self) -> Result<(), String> {
        loop {
            let missing: Vec<String> = self
                .d
                .expect
                .iter()
                .filter(|(line, p)| {
                    !self
                        .jobs
                        .iter()
                        .filter(|j| line.is_none() || j.line == *line)
                        .any(|j| p.found_in(&j.output()))
                })
                .map(|(line, p)| match line {
                    Some(n) => format!("line {n} never printed {p}"),
                    None => format!("nothing printed {p}"),
                })
                .collect();
            if missing.is_empty() {
                return Ok(());
            }
            if self.left().is_zero() {
                return Err(self.timed_out(&missing.join("; ")));
            }
            std::thread::sleep(POLL);
        }
    }

    fn transcript(&mut self, code: &str) -> Result<(), String> {
        let mut steps: Vec<(String, Vec<&str>)> = Vec::new();
        for line in code.lines() {
            match line.strip_prefix("$ ") {
                Some(cmd) => steps.push((cmd.to_string(), Vec::new())),
                None => match steps.last_mut() {
                    Some((_, out)) => out.push(line),
                    None => return Err(format!("a transcript starts with `$ `, not `{line}`")),
                },
            }
        }
        for (cmd, want) in steps {
            self.run_until_done(None, &cmd, None, None)?;
            let j = self.jobs.len() - 1;
            let got = self.jobs[j].output();
            let got: Vec<&str> = got.lines().map(str::trim_end).collect();
            let want: Vec<&str> = want.iter().map(|l| l.trim_end()).collect();
            if got != want {
                return Err(format!(
                    "`{cmd}` printed\n{}\nwhere the block shows\n{}",
                    got.join("\n"),
                    want.join("\n")
                ));
            }
        }
        Ok(())
    }

    /// Stops what is left: Ctrl-C, a moment, then SIGKILL; in a namespace of the block's
    /// own, every process still in it.
    fn stop_all(&mut self) {
        for j in &mut self.jobs {
            j.stdin = None;
            j.interrupt();
        }
        let limit = Instant::now() + Duration::from_secs(5);
        while self.jobs.iter_mut().any(|j| j.poll().is_none()) && Instant::now() < limit {
            std::thread::sleep(POLL);
        }
        for j in &mut self.jobs {
            if j.poll().is_none() {
                signal_group("KILL", j.child.id());
                let _ = j.child.wait();
            }
        }
        if self.s.private_net {
            // Background jobs: Ctrl-C as their terminals would get it, then SIGKILL.
            if signal_namespace("INT") > 0 {
                let limit = Instant::now() + Duration::from_secs(3);
                while Instant::now() < limit && !namespace_pids().is_empty() {
                    std::thread::sleep(POLL);
                }
                signal_namespace("KILL");
            }
        }
    }

    fn report(&self) -> String {
        let mut log = self.log.clone();
        for j in &self.jobs {
            let out = j.output();
            let lines: Vec<&str> = out.lines().collect();
            let tail = &lines[lines.len().saturating_sub(40)..];
            let _ = writeln!(log, "--- {}", j.describe());
            if lines.len() > tail.len() {
                let _ = writeln!(log, "    ... ({} lines before)", lines.len() - tail.len());
            }
            for l in tail {
                let _ = writeln!(log, "    {l}");
            }
        }
        log
    }
}

/// The block's commands with their line numbers: `\`-continued lines joined, blank and
/// comment-only lines left out.
pub fn logical_lines(code: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in code.lines().enumerate() {
        let (n, mut text) = current.take().unwrap_or((i + 1, String::new()));
        match line.trim_end().strip_suffix('\\') {
            Some(head) => {
                text.push_str(head);
                text.push(' ');
                current = Some((n, text));
            }
            None => {
                text.push_str(line);
                let t = text.trim();
                if !t.is_empty() && !t.starts_with('#') {
                    out.push((n, t.to_string()));
                }
            }
        }
    }
    if let Some((n, text)) = current {
        out.push((n, text.trim().to_string()));
    }
    out
}

/// A terminal's line without its trailing `&` (each line has a terminal of its own).
fn strip_background(line: &str) -> String {
    // Cut a trailing comment first: `cmd &   # or: ...`.
    let code = match line.find(" #") {
        Some(i) => &line[..i],
        None => line,
    };
    let code = code.trim_end();
    match code.strip_suffix('&') {
        Some(head) if !head.ends_with('&') => head.trim_end().to_string(),
        _ => line.to_string(),
    }
}

/// The other processes of this network namespace.
fn namespace_pids() -> Vec<String> {
    let Ok(own) = std::fs::read_link("/proc/self/ns/net") else {
        return Vec::new();
    };
    let me = std::process::id();
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    dir.flatten()
        .filter_map(|e| e.file_name().to_str().map(str::to_string))
        .filter(|p| p.parse::<u32>().is_ok_and(|p| p != me))
        .filter(|p| std::fs::read_link(format!("/proc/{p}/ns/net")).is_ok_and(|ns| ns == own))
        .collect()
}

/// `signal` to every other process of this network namespace; how many there were.
fn signal_namespace(signal: &str) -> usize {
    let pids = namespace_pids();
    if !pids.is_empty() {
        let _ = Command::new("kill")
            .arg(format!("-{signal}"))
            .args(&pids)
            .stderr(Stdio::null())
            .status();
    }
    pids.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logical_lines_join_continuations_and_skip_comments() {
        let l = logical_lines("a \\\n  b\n\n# c\nd &   # e");
        assert_eq!(
            l,
            vec![(1, "a    b".to_string()), (5, "d &   # e".to_string())]
        );
        assert_eq!(strip_background("d &   # e"), "d");
        assert_eq!(strip_background("a && b"), "a && b");
    }
}
