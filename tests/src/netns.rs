//! A network namespace of one test's own, nested in the one `netns-run` gives the whole
//! suite: a robot's addresses (`10.0.1.x`) go on its loopback without clashing with another
//! test's robot at the same addresses, and nothing of it is seen outside. Programs enter it
//! through `nsenter`, which execs them, so signals and exit codes are theirs.

use std::ffi::OsStr;
use std::net::Ipv4Addr;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A private network namespace, held by a sleeping child; gone when dropped.
pub struct NetNs {
    holder: Child,
}

impl NetNs {
    /// A new namespace with its loopback up (and multicast routed to it, as netns-run's).
    pub fn new() -> std::io::Result<NetNs> {
        let holder = Command::new("unshare")
            .args(["--net", "--", "sleep", "86400"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()?;
        let ns = NetNs { holder };
        // `unshare` execs `sleep` once the namespace exists: wait until it differs from ours.
        let ours = std::fs::read_link("/proc/self/ns/net")?;
        let start = Instant::now();
        loop {
            let theirs = std::fs::read_link(ns.path());
            if theirs.as_ref().is_ok_and(|t| *t != ours) {
                break;
            }
            if start.elapsed() > Duration::from_secs(10) {
                return Err(std::io::Error::other(
                    "unshare --net: no new network namespace within 10 s (needs root or \
                     unprivileged user namespaces)",
                ));
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        ns.ip(&["link", "set", "lo", "up"])?;
        ns.ip(&["link", "set", "lo", "multicast", "on"])?;
        let _ = ns.ip(&["route", "add", "224.0.0.0/4", "dev", "lo"]);
        Ok(ns)
    }

    fn path(&self) -> String {
        format!("/proc/{}/ns/net", self.holder.id())
    }

    /// `program` to be run inside the namespace.
    pub fn command(&self, program: impl AsRef<OsStr>) -> Command {
        let mut c = Command::new("nsenter");
        c.arg(format!("--net={}", self.path()))
            .arg("--")
            .arg(program.as_ref());
        c
    }

    /// `ip ARGS` inside the namespace.
    pub fn ip(&self, args: &[&str]) -> std::io::Result<()> {
        let out = self.command("ip").args(args).output()?;
        if out.status.success() {
            Ok(())
        } else {
            Err(std::io::Error::other(format!(
                "ip {}: {}",
                args.join(" "),
                String::from_utf8_lossy(&out.stderr).trim()
            )))
        }
    }

    /// Puts `ips` on the namespace's loopback (each a /32).
    pub fn add_addresses(&self, ips: &[Ipv4Addr]) -> std::io::Result<()> {
        for ip in ips {
            self.ip(&["addr", "add", &format!("{ip}/32"), "dev", "lo"])?;
        }
        Ok(())
    }
}

impl Drop for NetNs {
    fn drop(&mut self) {
        let _ = self.holder.kill();
        let _ = self.holder.wait();
    }
}

/// The addresses of a robots-configuration robot: the host's (`PC104IpAddress` of
/// `hardware/electronics/pc104.xml`, else of any hardware file) first, then every board's `IpAddress` of its
/// `hardware/` files, as `../shared/peers/run-netns.sh` finds them.
pub fn robot_addresses(robot: &Path) -> Vec<Ipv4Addr> {
    fn values(text: &str, key: &str) -> Vec<Ipv4Addr> {
        let pat = format!("name=\"{key}\">");
        text.match_indices(&pat)
            .filter_map(|(i, _)| {
                let rest = &text[i + pat.len()..];
                rest[..rest.find('<')?].trim().parse().ok()
            })
            .collect()
    }
    fn walk(dir: &Path, key: &str, out: &mut Vec<Ipv4Addr>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, key, out);
            } else if p.extension().is_some_and(|e| e == "xml") {
                if let Ok(t) = std::fs::read_to_string(&p) {
                    out.extend(values(&t, key));
                }
            }
        }
    }
    let mut ips = std::fs::read_to_string(robot.join("hardware/electronics/pc104.xml"))
        .map(|t| values(&t, "PC104IpAddress"))
        .unwrap_or_default();
    // robots without a pc104.xml name the host in another electronics file (nao_client.xml)
    if ips.is_empty() {
        walk(&robot.join("hardware"), "PC104IpAddress", &mut ips);
        ips.dedup();
    }
    let mut boards = Vec::new();
    walk(&robot.join("hardware"), "IpAddress", &mut boards);
    boards.sort();
    boards.dedup();
    for b in boards {
        if !ips.contains(&b) {
            ips.push(b);
        }
    }
    ips
}
