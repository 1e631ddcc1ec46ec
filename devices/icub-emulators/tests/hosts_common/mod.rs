//! What the host tests share: a robot of robots-configuration brought up, on its own
//! addresses in a network namespace of the test's own, by a host — C++ `yarprobotinterface`
//! with icub-main's embObj plugins (`tests/peers/install-cpp-peers.sh icub`), or ours —
//! against `icub-eth-emulator`, optionally recording every ROP the host sends to each
//! board; C++ `yarp` tools and a C++ `yarpserver` in that namespace.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use yarp_interop_tests::{
    cpp_command, cpp_program, robot_addresses, run_fed, workspace_program, NetNs, Proc,
};

/// A host's start-up on a loaded 2-core machine (the C++ host took 31 s for iCubGenova02
/// by hand).
pub const STARTUP: Duration = Duration::from_secs(240);
pub const STEP: Duration = Duration::from_secs(30);

pub fn robots() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration")
}

/// Which host brings the robot up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Host {
    /// C++ `yarprobotinterface` 3.12.3 with icub-main 2.11.1's plugins.
    Cpp,
    /// Our `yarprobotinterface`.
    Ours,
}

/// The robot's network: its namespace, its YARP configuration, the C++ programs.
pub struct RobotNet {
    pub ns: NetNs,
    pub conf: tempfile::TempDir,
    pub bin: PathBuf,
}

impl RobotNet {
    /// A C++ program of the peer, inside the robot's namespace and YARP network.
    pub fn cpp(&self, program: &str) -> Command {
        let real = cpp_command(&self.bin.join(program));
        let mut c = self.ns.command(real.get_program());
        for (k, v) in real.get_envs() {
            if let Some(v) = v {
                c.env(k, v);
            }
        }
        let lib = self.bin.with_file_name("lib");
        c.env("LD_LIBRARY_PATH", lib)
            .env("YARP_CONFIG_HOME", self.conf.path());
        c
    }

    /// One of our programs, inside the robot's namespace and YARP network.
    pub fn ours(&self, program: &str, package: &str) -> Command {
        let mut c = self.ns.command(workspace_program(program, package));
        c.env("YARP_CONFIG_HOME", self.conf.path())
            .env_remove("YARP_NAMESPACE")
            .env_remove("YARP_ICUB_ETH_ADDRESS_MAP");
        c
    }

    /// C++ `yarp rpc PORT` fed `input`: what it printed (bounded by [`STEP`]).
    pub fn rpc(&self, port: &str, input: &str) -> String {
        let mut c = self.cpp("yarp");
        c.args(["rpc", port]);
        run_fed("C++ yarp rpc", c, input, STEP)
    }

    /// C++ `yarp read READER PORT`: its first data line for which `want` holds, within
    /// [`STEP`].
    pub fn read_until(
        &self,
        reader: &str,
        port: &str,
        mut want: impl FnMut(&str) -> bool,
    ) -> String {
        let mut c = self.cpp("yarp");
        c.args(["read", reader, port]);
        let mut p = Proc::spawn("C++ yarp read", c);
        let end = Instant::now() + STEP;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            let Some(l) = p.try_wait_line("", left) else {
                panic!(
                    "C++ yarp read {port}: nothing wanted within {STEP:?}:\n{}",
                    p.seen.join("\n")
                );
            };
            // C++ yarp read logs with a level in brackets; data lines have none first
            if !l.starts_with('[') && want(&l) {
                return l;
            }
        }
    }
}

/// A robot brought up by a host in a namespace of its own. Fields drop in order: the
/// host first, the namespace last.
pub struct Robot {
    pub host: Proc,
    pub emulator: Proc,
    pub server: Proc,
    pub net: RobotNet,
    /// How long the host took from its start to "startup phase finished.".
    pub startup: Duration,
}

/// What to bring up.
pub struct BringUp<'a> {
    pub test: &'a str,
    pub host: Host,
    pub robot: &'a Path,
    pub xml: &'a str,
    /// The emulator's `--record DIR`.
    pub record: Option<&'a Path>,
}

/// Brings the robot up; `None` after the missing-peer rule when the C++ peer is missing
/// (a failure under CI).
pub fn bring_up(b: BringUp<'_>) -> Option<Robot> {
    let yri = cpp_program(b.test, "yarprobotinterface")?;
    let bin = yri.parent().expect("bin").to_path_buf();
    let ns = NetNs::new().expect("a network namespace of the test's own");
    ns.add_addresses(&robot_addresses(b.robot))
        .expect("the robot's addresses");
    let conf = tempfile::tempdir().expect("temp dir");
    let net = RobotNet { ns, conf, bin };
    // a fresh namespace: every port is free; `--write` makes the network's yarp.conf
    let mut server = Proc::spawn("C++ yarpserver", {
        let mut c = net.cpp("yarpserver");
        c.args(["--ip", "127.0.0.1", "--socket", "10000", "--write"]);
        c
    });
    // its "Ok. Ready!" may sit in stdio's buffer of a pipe: ask the network instead
    let end = Instant::now() + STEP;
    while !net
        .cpp("yarp")
        .args(["exists", "/root"])
        .output()
        .is_ok_and(|o| o.status.success())
    {
        assert!(
            Instant::now() < end,
            "C++ yarpserver not reachable within {STEP:?}: {}",
            server.drain().join("\n")
        );
        std::thread::sleep(Duration::from_millis(200));
    }

    let mut emulator = Proc::spawn("icub-eth-emulator", {
        let mut c = net.ours("icub-eth-emulator", "icub-emulators");
        c.arg(b.robot)
            .args(["--config", b.xml])
            .env("RUST_LOG", "warn");
        if let Some(dir) = b.record {
            c.arg("--record").arg(dir);
        }
        c
    });
    emulator.wait_line("icub-eth-emulator: serving", STEP);

    let start = Instant::now();
    let mut host = match b.host {
        Host::Cpp => Proc::spawn("C++ yarprobotinterface", {
            let mut c = net.cpp("yarprobotinterface");
            c.current_dir(b.robot)
                .arg("--config")
                .arg(b.robot.join(b.xml));
            c
        }),
        Host::Ours => Proc::spawn("our yarprobotinterface", {
            let mut c = net.ours("yarprobotinterface", "yarp-device-programs");
            c.current_dir(b.robot)
                .arg("--config")
                .arg(b.robot.join(b.xml))
                .env("RUST_LOG", "info");
            c
        }),
    };
    wait_phase(&mut host, "startup");
    let startup = start.elapsed();
    if let Some(dir) = std::env::var_os("HOSTS_TEST_LOG") {
        let _ = std::fs::write(
            std::path::Path::new(&dir).join(format!("{}-{:?}.log", b.test, b.host)),
            host.seen.join("\n"),
        );
    }
    eprintln!("{}: {:?} host calibrated in {startup:?}", b.test, b.host);
    Some(Robot {
        host,
        emulator,
        server,
        net,
        startup,
    })
}

/// Waits (at most [`STARTUP`]) until `host` says "PHASE phase finished." (C++ and ours say
/// it alike); panics with what it printed if it says it failed or exits first.
pub fn wait_phase(host: &mut Proc, phase: &str) {
    let done = format!(" {phase} phase finished.");
    let end = Instant::now() + STARTUP;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        let line = host.try_wait_line("phase", left.min(Duration::from_millis(500)));
        match line {
            Some(l) if l.ends_with(&done) && !l.contains("action level") => return,
            Some(l) if l.contains(&format!("Error in {phase} phase")) => {
                panic!("{l}; the host printed:\n{}", host.seen.join("\n"))
            }
            _ => {}
        }
        if let Ok(Some(status)) = host.child.try_wait() {
            let _ = host.try_wait_line("\u{0}", Duration::from_millis(300));
            panic!(
                "the host exited ({status}) before its {phase} phase finished:\n{}",
                host.seen.join("\n")
            );
        }
        assert!(
            Instant::now() < end,
            "the host's {phase} phase did not finish within {STARTUP:?}:\n{}",
            host.seen.join("\n")
        );
    }
}

/// What a host says when one ask's reply came late (a loaded machine: C++ waits 0.2 s
/// for some replies) and what that ask's caller then says: timing, not a failure of a
/// device, printed but not counted.
const LATE_REPLY: &[&str] = &[
    "had a timeout for BOARD",
    "DID NOT have replies from BOARD",
    "Failure of askRemoteValue() inside",
];

impl Robot {
    /// Lines of the host that report an error (late replies printed, not returned).
    pub fn errors(&self) -> Vec<String> {
        let (late, errors): (Vec<String>, Vec<String>) = self
            .host
            .seen
            .iter()
            .filter(|l| l.contains("[ERROR]") || l.contains(" ERROR "))
            .cloned()
            .partition(|l| LATE_REPLY.iter().any(|t| l.contains(t)));
        if !late.is_empty() {
            eprintln!("late replies (timing):\n{}", late.join("\n"));
        }
        errors
    }

    /// Moves joint `j` of `part` to `to` by C++ `yarp rpc` and sees it arrive on
    /// `state:o` through C++ `yarp read`.
    pub fn move_joint(&self, prefix: &str, part: &str, j: usize, to: f64) {
        let rpc = format!("{prefix}/{part}/rpc:i");
        let out = self.net.rpc(&rpc, &format!("set pos {j} {to}\n"));
        assert!(out.contains("[ok]"), "C++ yarp rpc {rpc}: {out}");
        let state = format!("{prefix}/{part}/state:o");
        let line = self
            .net
            .read_until(&format!("/test/{part}/state:i"), &state, |l| {
                l.split_whitespace()
                    .nth(j)
                    .and_then(|v| v.parse::<f64>().ok())
                    .is_some_and(|q| (q - to).abs() < 0.5)
            });
        eprintln!("{state}: {line}");
    }

    /// Ctrl-C: the host parks and closes, then exits.
    pub fn interrupt(&mut self) {
        let pid = self.host.pid();
        let _ = Command::new("kill")
            .args(["-INT", &pid.to_string()])
            .status();
        wait_phase(&mut self.host, "shutdown");
        let end = Instant::now() + STEP;
        while self.host.child.try_wait().ok().flatten().is_none() {
            assert!(
                Instant::now() < end,
                "the host did not exit after its shutdown phase"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// A copy of ergoCubSN001 without the lines of `ergocub.xml` that include its waist Xsens
/// MTi (`xsensmt`) and `wholebodydynamics`: both come from repositories `../shared/peers`
/// does not build. The devices that attach to the waist IMU go with it (its wrapper, and
/// the all-joints inertials remapper with its wrapper, which name `waist-inertial`).
/// Everything else is the robot's own.
pub fn ergocub_without_xsens_and_wbd() -> (tempfile::TempDir, PathBuf) {
    let src = robots().join("ergoCubSN001");
    let copy = tempfile::tempdir().expect("temp dir");
    let status = Command::new("cp")
        .arg("-r")
        .arg(&src)
        .arg(copy.path())
        .status()
        .expect("cp");
    assert!(status.success());
    let dir = copy.path().join("ergoCubSN001");
    let top = dir.join("ergocub.xml");
    let text = std::fs::read_to_string(&top).expect("ergocub.xml");
    let dropped = [
        "hardware/inertials/waist-inertial.xml",
        "wrappers/inertials/waist-inertials_wrapper.xml",
        "wrappers/inertials/alljoints-inertials_wrapper.xml",
        "wrappers/inertials/alljoints-inertials_remapper.xml",
        "estimators/wholebodydynamics.xml",
    ];
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !dropped.iter().any(|d| l.contains(d)))
        .collect();
    assert_eq!(kept.len() + dropped.len(), text.lines().count());
    std::fs::write(&top, kept.join("\n")).expect("write the copy");
    (copy, dir)
}
