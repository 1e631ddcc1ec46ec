//! Our Ethernet host against icub-main's, datagram for datagram: the same robot (iCubGenova02;
//! ergoCubSN001 without its waist MTi and wholebodydynamics) is brought up twice against
//! `icub-eth-emulator --record`, once by C++ `yarprobotinterface` 3.12.3 with icub-main
//! 2.11.1's plugins and once by ours, each in a network namespace of its own on the robot's
//! addresses. The emulator records every ROP each host sends to each board from first
//! contact until the host says "startup phase finished." (every part calibrated); the
//! recordings are then compared board by board.
//!
//! What is compared: for each board and each variable (id32), what the host set or asked,
//! in order — ropcode and data — with sequence numbers, times and the interleaving of
//! different variables (which C++ leaves to its threads) ignored, and repeated asks of a
//! variable counted once (how often a host polls while it waits is timing, not protocol).
//! Every remaining difference must be listed in [`DELIBERATE`] with its reason.

mod hosts_common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use hosts_common::*;

/// One ROP as recorded.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Rop {
    ropcode: String,
    id32: String,
    data: String,
}

/// Per board (its robot IP), per variable: the ROPs in order.
type Recording = BTreeMap<String, BTreeMap<String, Vec<Rop>>>;

fn read_recording(dir: &Path) -> Recording {
    let mut rec = Recording::new();
    for entry in std::fs::read_dir(dir).expect("recording dir").flatten() {
        let path = entry.path();
        let Some(board) = path
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_suffix(".jsonl"))
        else {
            continue;
        };
        let text = std::fs::read_to_string(&path).expect("a board's recording");
        let vars = rec.entry(board.to_string()).or_default();
        for line in text.lines() {
            let v: serde_json::Value = serde_json::from_str(line).expect("a JSON line");
            let Some(id32) = v["id32"].as_str() else {
                continue; // invalid datagrams or malformed ROPs are reported apart
            };
            let rop = Rop {
                ropcode: v["rop"].as_str().unwrap_or("?").to_string(),
                id32: id32.to_string(),
                data: unset_bytes_masked(&name(id32), v["data"].as_str().unwrap_or("")),
            };
            let seq = vars.entry(rop.id32.clone()).or_default();
            // a repeated ask in a row is a poll: counted once
            if rop.ropcode == "ask" && seq.last() == Some(&rop) {
                continue;
            }
            seq.push(rop);
        }
    }
    rec
}

/// Brings the robot up with `host`, recording until its start-up finished.
fn record(
    test: &str,
    host: Host,
    robot: &Path,
    xml: &str,
) -> Option<(Recording, std::time::Duration)> {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut r = bring_up(BringUp {
        test,
        host,
        robot,
        xml,
        record: Some(dir.path()),
    })?;
    // the cut: stop the boards' recording at the end of calibration
    r.emulator.kill();
    let startup = r.startup;
    drop(r);
    if let Some(keep) = std::env::var_os("HOSTS_TEST_LOG") {
        let to = Path::new(&keep).join(format!("{test}-{host:?}"));
        let _ = std::fs::remove_dir_all(&to);
        let _ = std::process::Command::new("cp")
            .arg("-r")
            .arg(dir.path())
            .arg(&to)
            .status();
    }
    Some((read_recording(dir.path()), startup))
}

/// A difference between the hosts, named for the report and the deliberate list.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
enum Difference {
    /// A variable only one host touches.
    OnlyOne {
        board: String,
        id32: String,
        host: &'static str,
        rops: Vec<Rop>,
    },
    /// A variable both touch, with different ROPs.
    Differs {
        board: String,
        id32: String,
        cpp: Vec<Rop>,
        ours: Vec<Rop>,
    },
}

fn compare(cpp: &Recording, ours: &Recording) -> Vec<Difference> {
    let mut out = Vec::new();
    let boards: BTreeSet<&String> = cpp.keys().chain(ours.keys()).collect();
    let empty = BTreeMap::new();
    for b in boards {
        let (c, o) = (cpp.get(b).unwrap_or(&empty), ours.get(b).unwrap_or(&empty));
        let ids: BTreeSet<&String> = c.keys().chain(o.keys()).collect();
        for id in ids {
            match (c.get(id), o.get(id)) {
                (Some(c), Some(o)) if c == o => {}
                (Some(c), Some(o)) => out.push(Difference::Differs {
                    board: b.clone(),
                    id32: id.clone(),
                    cpp: c.clone(),
                    ours: o.clone(),
                }),
                (Some(c), None) => out.push(Difference::OnlyOne {
                    board: b.clone(),
                    id32: id.clone(),
                    host: "C++",
                    rops: c.clone(),
                }),
                (None, Some(o)) => out.push(Difference::OnlyOne {
                    board: b.clone(),
                    id32: id.clone(),
                    host: "ours",
                    rops: o.clone(),
                }),
                (None, None) => {}
            }
        }
    }
    out
}

fn report(robot: &str, diffs: &[Difference]) -> String {
    let mut s = format!("{robot}: {} differences\n", diffs.len());
    for d in diffs {
        match d {
            Difference::OnlyOne {
                board,
                id32,
                host,
                rops,
            } => {
                s += &format!("  {board} {}: only {host}: {}\n", name(id32), summary(rops));
            }
            Difference::Differs {
                board,
                id32,
                cpp,
                ours,
            } => {
                s += &format!(
                    "  {board} {}: C++ {}\n  {:w$}          ours {}\n",
                    name(id32),
                    summary(cpp),
                    "",
                    summary(ours),
                    w = board.len()
                );
            }
        }
    }
    s
}

/// A variable's name for the report (`eOprotID32_t`: endpoint, entity, index, tag).
fn name(id32: &str) -> String {
    let v = u32::from_str_radix(id32.trim_start_matches("0x"), 16).unwrap_or(0);
    let (ep, en, index, tag) = (v >> 24, (v >> 16) & 0xff, (v >> 8) & 0xff, v & 0xff);
    const MN: &[&[&str]] = &[
        &[
            "comm",
            "comm.status",
            "comm.protocolversion",
            "comm.querynumof",
            "comm.queryarray",
            "comm.replynumof",
            "comm.replyarray",
            "comm.config",
        ],
        &[
            "appl",
            "appl.config",
            "appl.txratedivider",
            "appl.status",
            "appl.go2state",
            "appl.timeset",
        ],
        &[
            "info",
            "info.config",
            "info.enabled",
            "info.status",
            "info.status.basic",
        ],
        &["service", "service.commandresult", "service.command"],
    ];
    const MC: &[&[&str]] = &[
        &[
            "joint",
            "joint.config",
            "joint.pidposition",
            "joint.pidvelocity",
            "joint.pidtorque",
            "joint.userlimits",
            "joint.impedance",
            "joint.motorparams",
            "joint.tcfilter",
            "joint.status",
            "joint.status.core",
            "joint.status.target",
            "joint.controlmodestatus",
            "joint.interactionmodestatus",
            "joint.ismotiondone",
            "joint.multienc",
            "joint.debug",
            "joint.inputs",
            "joint.externaltorque",
            "joint.calibration",
            "joint.setpoint",
            "joint.stoptrajectory",
            "joint.controlmode",
            "joint.interactionmode",
        ],
        &[
            "motor",
            "motor.config",
            "motor.currentlimits",
            "motor.gearbox",
            "motor.rotorencoder",
            "motor.pwmlimit",
            "motor.temperaturelimit",
            "motor.pidcurrent",
            "motor.pidspeed",
            "motor.status",
            "motor.status.basic",
        ],
        &["controller", "controller.config", "controller.status"],
    ];
    let ens: &[&str] = match (ep, en) {
        (2, 0) => &[
            "strain",
            "strain.config",
            "strain.status",
            "strain.fullscale",
            "strain.calibrated",
            "strain.uncalibrated",
        ],
        (2, 1) => &[
            "mais",
            "mais.config",
            "mais.mode",
            "mais.datarate",
            "mais.resolution",
            "mais.status",
            "mais.15values",
        ],
        (2, 6) => &[
            "ft.config",
            "ft.enable",
            "ft.status",
            "ft.timedvalue",
            "ft.fullscale",
        ],
        (2, 7) => &[
            "battery.config",
            "battery.enable",
            "battery.status",
            "battery.timedvalue",
        ],
        (2, _) => &["as", "as.config", "as.status", "as.enable"],
        (3, _) => &[
            "skin",
            "skin.sigmode",
            "skin.status",
            "skin.boardscfg",
            "skin.trianglescfg",
        ],
        (0, e) => MN.get(e as usize).copied().unwrap_or(&[]),
        (1, e) => MC.get(e as usize).copied().unwrap_or(&[]),
        _ => &[],
    };
    let kind = ["mn", "mc", "as", "sk"]
        .get(ep as usize)
        .copied()
        .unwrap_or("?");
    match ens.get(tag as usize) {
        Some(n) => format!(
            "{kind}.{n}[{index}]{}",
            if ep == 2 {
                format!(" (entity {en})")
            } else {
                String::new()
            }
        ),
        None => format!("{kind} {en}/{index}/{tag}"),
    }
}

fn summary(rops: &[Rop]) -> String {
    rops.iter()
        .map(|r| {
            if r.data.is_empty() {
                r.ropcode.clone()
            } else {
                format!("{} {}", r.ropcode, &r.data[..r.data.len().min(200)])
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Bytes C++ sends without setting them (uninitialised fields of structs on its stack,
/// which differ from run to run and board to board); ours sends zeros there. They are
/// compared as `..`: (variable, whether a ROP's data holds such a field, its bytes, why).
type Unset = (
    &'static str,
    fn(&[u8]) -> bool,
    std::ops::Range<usize>,
    &'static str,
);
const UNSET: &[Unset] = &[
    (
        "mc.joint.setpoint",
        |_| true,
        1..4,
        "eOmc_setpoint_t::filler: embObjMotionControl fills type and value only",
    ),
    (
        "mn.service.command",
        // verifyactivate (3) of motion control (0) of type eomn_serv_MC_foc (1)
        |d| d.len() > 16 && d[0] == 3 && d[1] == 0 && d[4] == 1,
        14..16,
        "eOmn_serv_config_data_mc_foc_t::filler: ServiceParser::parseService sets version, \
         type, descriptors and coupling only",
    ),
    (
        "as.as.config (entity 5)",
        |_| true,
        1..4,
        "eOas_pos_config_t's bytes after datarate: embObjPOS::sendConfig2boards sets \
         datarate only",
    ),
];

fn unset_bytes_masked(var: &str, hex: &str) -> String {
    let Ok(mut data) = (0..hex.len() / 2)
        .map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16))
        .collect::<Result<Vec<u8>, _>>()
    else {
        return hex.to_string();
    };
    // the variable without its index: `mc.joint.setpoint`, `as.as.config (entity 5)`
    let var = match (var.find('['), var.find(']')) {
        (Some(a), Some(b)) if a < b => format!("{}{}", &var[..a], &var[b + 1..]),
        _ => var.to_string(),
    };
    let mut masked = vec![false; data.len()];
    for (v, holds, range, _why) in UNSET {
        if *v == var && holds(&data) {
            let n = data.len();
            for i in range.clone().filter(|i| *i < n) {
                data[i] = 0;
                masked[i] = true;
            }
        }
    }
    data.iter()
        .zip(masked)
        .map(|(b, m)| {
            if m {
                "..".to_string()
            } else {
                format!("{b:02x}")
            }
        })
        .collect()
}

/// The differences left on purpose: (variable, what differs, why).
const DELIBERATE: &[(&str, &str)] = &[];

fn hosts_compared(test: &str, robot: &Path, xml: &str) {
    let Some((cpp, t_cpp)) = record(test, Host::Cpp, robot, xml) else {
        return;
    };
    let (ours, t_ours) = record(test, Host::Ours, robot, xml).expect("our host");
    eprintln!("{test}: start-up C++ {t_cpp:?}, ours {t_ours:?}");
    let diffs = compare(&cpp, &ours);
    let rep = report(test, &diffs);
    if let Some(dir) = std::env::var_os("HOSTS_TEST_LOG") {
        let _ = std::fs::write(Path::new(&dir).join(format!("{test}.diff")), &rep);
    }
    let _ = DELIBERATE;
    assert!(diffs.is_empty(), "{rep}");
}

#[test]
fn icub_genova02_hosts_compared() {
    let dir = robots().join("iCubGenova02");
    hosts_compared("icub_genova02_hosts_compared", &dir, "icub_all.xml");
}

#[test]
fn ergocub_sn001_hosts_compared() {
    let (_copy, dir) = ergocub_without_xsens_and_wbd();
    hosts_compared("ergocub_sn001_hosts_compared", &dir, "ergocub.xml");
}
