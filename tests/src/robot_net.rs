//! A robot's own network for a live test: a network namespace holding the robot's
//! addresses (the host's and its boards'), a YARP configuration naming a name server in
//! it, and the programs started there, each in a process group of its own, all stopped
//! (SIGTERM, then SIGKILL) when it is dropped, however the test ends.

use std::cell::RefCell;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use crate::{robot_addresses, run_fed, workspace_program, NetNs, Proc};

pub struct RobotNet {
    pub ns: NetNs,
    conf: tempfile::TempDir,
    groups: RefCell<Vec<u32>>,
}

impl RobotNet {
    /// The network of the robot whose files are in `robot_dir`.
    pub fn new(robot_dir: &Path) -> RobotNet {
        let net = RobotNet {
            ns: NetNs::new().expect("a network namespace (run under netns-run)"),
            conf: tempfile::tempdir().expect("a temporary directory"),
            groups: RefCell::default(),
        };
        net.ns
            .add_addresses(&robot_addresses(robot_dir))
            .expect("the robot's addresses");
        net
    }

    /// A workspace program (see [`workspace_program`]) in the network, in a process group
    /// of its own, with the robot's own addresses (no address map).
    pub fn cmd(&self, program: &str, package: &str) -> Command {
        use std::os::unix::process::CommandExt;
        let mut c = self.ns.command(workspace_program(program, package));
        c.process_group(0)
            .env("YARP_CONFIG_HOME", self.conf.path())
            .env_remove("YARP_NAMESPACE")
            // icub_eth::ADDRESS_MAP_ENV: the boards are at the robot's own addresses here
            .env_remove("YARP_ICUB_ETH_ADDRESS_MAP")
            .env("RUST_LOG", "info");
        c
    }

    /// Starts `cmd`; its process group is stopped with the network.
    pub fn spawn(&self, name: &str, cmd: Command) -> Proc {
        let p = Proc::spawn(name, cmd);
        self.groups.borrow_mut().push(p.pid());
        p
    }

    /// Our `yarpserver` on 127.0.0.1:10000 (the configuration's), ready.
    pub fn server(&self) -> Proc {
        let mut c = self.cmd("yarpserver", "yarp-net");
        c.args(["--ip", "127.0.0.1", "--socket", "10000", "--write"]);
        let mut p = self.spawn("yarpserver", c);
        p.wait_line("Ok. Ready!", Duration::from_secs(20));
        p
    }

    /// `yarp ARGS` fed `input`: every line it printed (at most 20 s).
    pub fn yarp(&self, args: &[&str], input: &str) -> String {
        let mut c = self.cmd("yarp", "yarp-cli");
        c.args(args);
        run_fed("yarp", c, input, Duration::from_secs(20))
    }

    /// `yarp rpc PORT` fed `input` (at most 30 s).
    pub fn rpc(&self, port: &str, input: &str) -> String {
        let mut c = self.cmd("yarp", "yarp-cli");
        c.args(["rpc", port]);
        run_fed("yarp rpc", c, input, Duration::from_secs(30))
    }
}

impl Drop for RobotNet {
    fn drop(&mut self) {
        let groups = self.groups.borrow();
        for signal in ["-TERM", "-KILL"] {
            for pgid in groups.iter() {
                let _ = Command::new("kill")
                    .args([signal, "--", &format!("-{pgid}")])
                    .stderr(std::process::Stdio::null())
                    .status();
            }
            if signal == "-TERM" {
                std::thread::sleep(Duration::from_millis(300));
            }
        }
    }
}
