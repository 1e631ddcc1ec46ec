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
//! different variables (which C++ leaves to its threads) ignored. Retries are timing, not
//! protocol: a joint status only polled by one host (how soon the joint got there) is no
//! difference, and these count once: repeated asks of a variable (a poll), a value set again
//! unchanged (a command whose reply was late, a PWM limit restored that was never
//! lowered), a `set X, ask` repeated (a setcheck that asked before the board had it).
//! Bytes C++ sends without setting them (uninitialised fields) are zeroed on both sides,
//! each listed in [`UNSET`] with its reason; no other difference is left, and a new one
//! fails the test.
//!
//! No CAN robot is compared: icub-main's CAN devices reach their boards only through CAN
//! drivers (`socketcan`, which needs AF_CAN, absent from this kernel and CI's; `ecan`,
//! `pcan`, `cfw2can`, which need their adapters' hardware and vendor libraries; `fakecan`,
//! which is in-process and reaches no emulator), and our CAN emulator is reached through
//! SocketCAN, cannelloni over UDP or in-process: no transport both can use exists here.

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
            // a command repeated in a row is a retry of one whose reply was late; a value
            // set again unchanged changes nothing (the calibrators' restore of a PWM limit
            // that was never lowered comes or not as the joints reach zero in time)
            if rop.ropcode == "set" && seq.last() == Some(&rop) {
                continue;
            }
            seq.push(rop);
            // `set X, ask` again after `set X, ask`: a setcheck that asked before the
            // board had the value and tried again (both hosts do, on a loaded machine)
            let n = seq.len();
            if n >= 4
                && seq[n - 4..n - 2] == seq[n - 2..]
                && seq[n - 2].ropcode == "set"
                && seq[n - 1].ropcode == "ask"
            {
                seq.truncate(n - 2);
            }
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

/// Whether `rops` only ask a joint's motion-done or control-mode status (a poll).
fn polled_status(var: &str, rops: &[Rop]) -> bool {
    (var.contains(".ismotiondone") || var.contains(".controlmodestatus"))
        && rops.iter().all(|r| r.ropcode == "ask")
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
                // a status polled while waiting for a joint: whether a host asks at all
                // depends on how soon the joint got there
                (Some(r), None) | (None, Some(r)) if polled_status(&name(id), r) => {}
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
    s += "(compared with the bytes C++ leaves unset zeroed on both sides:\n";
    for u in UNSET {
        s += &format!("  {}: {}\n", u.var, u.why);
    }
    s += ")\n";
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

/// Bytes C++ sends without setting them: fields of structs it never zeroes, which hold
/// whatever its memory held (they differ from board to board and run to run: ASCII
/// fragments of its configuration, stack bytes); ours sends zeros there. They are zeroed
/// on both sides before comparing. Each entry: the variable, why, and the bytes.
struct Unset {
    var: &'static str,
    why: &'static str,
    mask: fn(&mut [u8]),
}

fn zero(d: &mut [u8], bytes: std::ops::Range<usize>) {
    let n = d.len();
    d[bytes.start.min(n)..bytes.end.min(n)].fill(0);
}

/// `eOmc_jointset_configuration_t` ×4 from `base`: each one's `filler` (+3) and
/// `constraints.filler` (+5..+8), which icub-main's `JointsSet` never sets.
fn jointset_fillers(d: &mut [u8], base: usize) {
    for s in 0..4 {
        let at = base + 16 * s;
        zero(d, at + 3..at + 4);
        zero(d, at + 5..at + 8);
    }
}

/// A service command's operation, category and service type.
fn service(d: &[u8]) -> (u8, u8, u8) {
    (d[0], d[1], d.get(4).copied().unwrap_or(0))
}
const VERIFYACTIVATE: u8 = 3;

const UNSET: &[Unset] = &[
    Unset {
        var: "mc.joint.setpoint",
        why: "eOmc_setpoint_t::filler: embObjMotionControl fills type and value only",
        mask: |d| zero(d, 1..4),
    },
    Unset {
        var: "mn.service.command",
        why: "the motion-control service configuration (embObjMotionControl::serviceConfig, \
              never zeroed): ServiceParser::parseService sets only the fields it names — foc: \
              its filler; mc4: the MAIS location (parsed for mc4plusmais only); mc4plusfaps: \
              the POS board's inside index and filler; advfoc: the coupling's filler; every \
              type: the joint sets' fillers (JointsSet never sets them) and the union's \
              bytes past the type's struct",
        mask: |d| match service(d) {
            (VERIFYACTIVATE, 0, 1) => {
                zero(d, 14..16);
                jointset_fillers(d, 44);
                zero(d, 332..348);
            }
            (VERIFYACTIVATE, 0, 2) => {
                zero(d, 33..34);
                zero(d, 36..348);
            }
            (VERIFYACTIVATE, 0, 3) => {
                jointset_fillers(d, 36);
                zero(d, 324..348);
            }
            (VERIFYACTIVATE, 0, 0x0e) => {
                if let Some(b) = d.get_mut(14) {
                    *b &= 0x1f;
                }
                zero(d, 15..16);
                jointset_fillers(d, 60);
            }
            (VERIFYACTIVATE, 0, 0x0f) => {
                zero(d, 77..80);
                jointset_fillers(d, 84);
                zero(d, 340..348);
            }
            _ => {}
        },
    },
    Unset {
        var: "mn.service.command",
        why: "the FT service configuration (embObjMultipleFTsensors' ftData, a stack local \
              never zeroed): each sensor's ffu (FtInfo::toEomn leaves it) and everything past \
              eOmn_serv_config_data_as_ft_t",
        mask: |d| {
            if let (VERIFYACTIVATE, 8, _) = service(d) {
                for i in 0..4 {
                    zero(d, 23 + 8 * i..24 + 8 * i);
                }
                zero(d, 48..348);
            }
        },
    },
    Unset {
        var: "mn.service.command",
        why: "the strain2 temperature service (embObjFTsensor's servparamtemp, never zeroed): \
              fillTemperatureEthServiceInfo sets the type and the temperature data only",
        mask: |d| {
            if let (VERIFYACTIVATE, 5, _) = service(d) {
                zero(d, 5..8);
                zero(d, 64..348);
            }
        },
    },
    Unset {
        var: "as.as.config (entity 5)",
        why: "eOas_pos_config_t's bytes after datarate: embObjPOS::sendConfig2boards sets \
              datarate only",
        mask: |d| zero(d, 1..4),
    },
    Unset {
        var: "sk.skin.boardscfg",
        why: "eOsk_cmd_boardsCfg_t::filler1 of the special board configurations: \
              EmbObjSkin::initWithSpecialConfig does not zero its bcfg (the default one is)",
        mask: |d| {
            if d.len() >= 8 && d[..4] != [0xff; 4] {
                d[7] = 0;
            }
        },
    },
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
    for u in UNSET {
        if u.var == var {
            (u.mask)(&mut data);
        }
    }
    data.iter().map(|b| format!("{b:02x}")).collect()
}

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
