//! A whole iCub (53 DOF: head 6, torso 3, arms 2×16 with the hands, legs 2×6) laid out
//! on CAN networks exactly as robots-configuration `iCubGenova01` does:
//!
//! | net | boards |
//! |-----|--------|
//! | 0 | head MC 1 2 3, torso MC 5 6 |
//! | 1 | left arm MC 1 2 3 4, strain 0x0D |
//! | 2 | right arm MC 1 2 3 4, strain 0x0D |
//! | 3 | left leg MC 5 6 7, leg strain 0x0D, foot strain 0x01 |
//! | 4 | right leg MC 8 9 10, leg strain 0x0E, foot strain 0x01 |
//! | 5 | left hand MC 5 6 7 8, MAIS 0x0E |
//! | 6 | right hand MC 5 6 7 8, MAIS 0x0E |
//! | 7 | left arm skin MTB 8..14 (14 also hand inertial) |
//! | 8 | right arm skin MTB 8..14 |
//! | 9 | torso skin MTB 7..10, foot skin MTB 2 3 13 14, foot inertial MTB 3 and 0x0C |
//!
//! Given the robot directory, initial encoder values are derived from each part's
//! `hardware/motorControl/icub_*.xml` (`CanAddresses`, `AxisMap`, `Encoder`, `Zeros`,
//! `jntPosMin`/`jntPosMax`) so every joint starts at 0° clamped into its limits, and the
//! joint-torque sensors from `GENERAL::TorqueId`/`TorqueChan`/`TorqueMax` (iCubGenova01:
//! arms 0x0C channels 0..4, legs 0x0C/0x0B channels 0..5, torso 0x0C channels 0..2):
//! each joint with a `TorqueId` publishes its simulated torque (sensor units
//! `τ·0x8000/TorqueMax`, sign of its `Encoder`, so positive torques turn the joint in
//! its positive YARP direction) and the network gets a [`JointTorqueSensor`] at that
//! address broadcasting them every 10 ms. Without the directory no joint torques are
//! broadcast. Every motor board starts with [`super::mc::DEFAULT_POSITION_PID`] gains
//! (the host's `POS_PIDS`/`TRQ_PIDS` replace them).

use std::collections::HashMap;
use std::path::Path;

use super::mc::{JointPlant, JointTorqueSensor, TorqueHub, TorqueLink};
use super::{Board, MaisBoard, McBoard, McBoardConfig, MtbBoard, SpecError, StrainBoard};

/// A board of the preset.
#[derive(Debug, Clone, PartialEq)]
pub enum BoardKind {
    Mc {
        address: u8,
        initial: [f64; 2],
        /// Plant and torque sensor of each axis.
        plants: [JointPlant; 2],
    },
    /// A virtual joint-torque sensor (the `TorqueId` of some joints).
    JointTorque(u8),
    Strain(u8),
    Mais(u8),
    Skin(u8),
    Mtb(u8),
}

/// One CAN network of the preset.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkSpec {
    /// `CanDeviceNum` of the network.
    pub num: u32,
    pub boards: Vec<BoardKind>,
}

/// Motor-control parts: (XML part name, network, board addresses, joints).
pub const MC_PARTS: [(&str, u32, &[u8], usize); 8] = [
    ("head", 0, &[1, 2, 3], 6),
    ("torso", 0, &[5, 6], 3),
    ("left_arm", 1, &[1, 2, 3, 4], 8),
    ("right_arm", 2, &[1, 2, 3, 4], 8),
    ("left_leg", 3, &[5, 6, 7], 6),
    ("right_leg", 4, &[8, 9, 10], 6),
    ("left_hand", 5, &[5, 6, 7, 8], 8),
    ("right_hand", 6, &[5, 6, 7, 8], 8),
];

/// Total degrees of freedom of the preset.
pub fn dof() -> usize {
    MC_PARTS.iter().map(|p| p.3).sum()
}

/// Extracts `<param name="X"> values </param>` (first occurrence, comments removed).
pub fn xml_params(text: &str) -> HashMap<String, Vec<String>> {
    let mut clean = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<!--") {
        clean.push_str(&rest[..start]);
        rest = rest[start..]
            .find("-->")
            .map_or("", |end| &rest[start + end + 3..]);
    }
    clean.push_str(rest);
    let mut out = HashMap::new();
    let mut s = clean.as_str();
    while let Some(pos) = s.find("<param") {
        s = &s[pos + 6..];
        let Some(close) = s.find('>') else { break };
        let attrs = &s[..close];
        let Some(end) = s.find("</param>") else { break };
        if close < end {
            if let Some(name) = attrs
                .split("name=\"")
                .nth(1)
                .and_then(|n| n.split('"').next())
            {
                let values = s[close + 1..end]
                    .split_whitespace()
                    .map(|v| v.trim_matches('"').to_string())
                    .collect();
                out.entry(name.to_string()).or_insert(values);
            }
        }
        s = &s[end..];
    }
    out
}

/// Per (board, axis): initial ticks and plant, from a part's motor-control file.
fn part_joints(robot_dir: &Path, part: &str) -> Option<HashMap<(u8, u8), (f64, JointPlant)>> {
    let path = robot_dir.join(format!("hardware/motorControl/icub_{part}.xml"));
    let p = xml_params(&std::fs::read_to_string(path).ok()?);
    let nums =
        |k: &str| -> Option<Vec<f64>> { p.get(k)?.iter().map(|v| v.parse::<f64>().ok()).collect() };
    let addrs = nums("CanAddresses")?;
    let axis_map = nums("AxisMap")?;
    let (enc, zeros) = (nums("Encoder")?, nums("Zeros")?);
    let (min, max) = (nums("jntPosMin")?, nums("jntPosMax")?);
    // GENERAL::TorqueId / TorqueChan / TorqueMax (icub-main CanBusMotionControl); the
    // hex ids (`0x0C`) are parsed here, 0 means no sensor.
    let ids: Vec<u8> = p
        .get("TorqueId")
        .map(|v| {
            v.iter()
                .map(|s| {
                    let s = s.trim();
                    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
                        Some(h) => u8::from_str_radix(h, 16).unwrap_or(0),
                        None => s.parse().unwrap_or(0),
                    }
                })
                .collect()
        })
        .unwrap_or_default();
    let chans = nums("TorqueChan").unwrap_or_default();
    let tmax = nums("TorqueMax").unwrap_or_default();
    let mut out = HashMap::new();
    for (j, axis) in axis_map.iter().enumerate() {
        let axis = *axis as usize;
        let addr = *addrs.get(axis / 2)? as u8;
        let (lo, hi) = (*min.get(j)?, *max.get(j)?);
        let angle = if lo <= hi { 0f64.clamp(lo, hi) } else { 0.0 };
        let e = *enc.get(j)?;
        let mut plant = JointPlant::with_torque_max(tmax.get(j).copied().unwrap_or(0.0));
        plant.sensor_sign = Some(if e < 0.0 { -1.0 } else { 1.0 });
        let (id, ch) = (ids.get(j).copied().unwrap_or(0), chans.get(j).copied());
        if let (1..=14, Some(ch @ 0.0..=5.0)) = (id, ch) {
            plant.sensor = Some(TorqueLink {
                address: id,
                channel: ch as u8,
            });
        }
        out.insert(
            (addr, (axis % 2) as u8),
            ((angle + zeros.get(j)?) * e, plant),
        );
    }
    Some(out)
}

/// The networks of the preset; `robot_dir` (an `iCubGenova01`-like directory) refines
/// the initial joint encoders.
pub fn icub_networks(robot_dir: Option<&Path>) -> Vec<NetworkSpec> {
    let mut nets: Vec<NetworkSpec> = (0..10)
        .map(|num| NetworkSpec {
            num,
            boards: Vec::new(),
        })
        .collect();
    for (part, net, addrs, _) in MC_PARTS.iter() {
        let init = robot_dir
            .and_then(|d| part_joints(d, part))
            .unwrap_or_default();
        for &address in *addrs {
            let joint = |ch: u8| init.get(&(address, ch)).copied().unwrap_or_default();
            let initial = [0u8, 1].map(|ch| joint(ch).0);
            let plants = [0u8, 1].map(|ch| joint(ch).1);
            let boards = &mut nets[*net as usize].boards;
            boards.push(BoardKind::Mc {
                address,
                initial,
                plants,
            });
            for link in plants.iter().filter_map(|p| p.sensor) {
                if !boards.contains(&BoardKind::JointTorque(link.address)) {
                    boards.push(BoardKind::JointTorque(link.address));
                }
            }
        }
    }
    let push = |nets: &mut Vec<NetworkSpec>, net: usize, b: BoardKind| nets[net].boards.push(b);
    push(&mut nets, 1, BoardKind::Strain(0x0D));
    push(&mut nets, 2, BoardKind::Strain(0x0D));
    push(&mut nets, 3, BoardKind::Strain(0x0D));
    push(&mut nets, 3, BoardKind::Strain(0x01));
    push(&mut nets, 4, BoardKind::Strain(0x0E));
    push(&mut nets, 4, BoardKind::Strain(0x01));
    push(&mut nets, 5, BoardKind::Mais(0x0E));
    push(&mut nets, 6, BoardKind::Mais(0x0E));
    for net in [7, 8] {
        for a in 8..=14 {
            push(&mut nets, net, BoardKind::Skin(a));
        }
    }
    for a in [2, 3, 7, 8, 9, 10, 13, 14] {
        push(&mut nets, 9, BoardKind::Skin(a));
    }
    push(&mut nets, 9, BoardKind::Mtb(0x0C));
    nets
}

/// Instantiates the boards of one network.
pub fn build(net: &NetworkSpec) -> Vec<Box<dyn Board>> {
    let hub = TorqueHub::new();
    net.boards
        .iter()
        .map(|b| -> Box<dyn Board> {
            match b {
                BoardKind::Mc {
                    address,
                    initial,
                    plants,
                } => {
                    let mut cfg = McBoardConfig::new(*address);
                    cfg.initial = *initial;
                    cfg.plants = *plants;
                    cfg.torque_hub = Some(hub.clone());
                    Box::new(McBoard::new(cfg))
                }
                BoardKind::JointTorque(a) => Box::new(JointTorqueSensor::new(
                    *a,
                    hub.clone(),
                    std::time::Duration::from_millis(10),
                )),
                BoardKind::Strain(a) => Box::new(StrainBoard::new(*a)),
                BoardKind::Mais(a) => Box::new(MaisBoard::new(*a)),
                BoardKind::Skin(a) => Box::new(MtbBoard::new(*a, true)),
                BoardKind::Mtb(a) => Box::new(MtbBoard::new(*a, false)),
            }
        })
        .collect()
}

/// A bus URL and the boards on it.
pub type BusBoards = (String, Vec<Box<dyn Board>>);

/// Parses an emulator description file:
///
/// ```text
/// # comment
/// bus udp-hub://127.0.0.1:20001
/// board 1 mc
/// board 0x0D strain
/// bus inproc://head
/// board 3 mc
/// ```
///
/// Each `board` line belongs to the last `bus` line.
pub fn parse_file(path: &str, text: &str) -> Result<Vec<BusBoards>, SpecError> {
    let mut out: Vec<BusBoards> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let err = |msg: String| SpecError::File {
            path: path.into(),
            line: i + 1,
            msg,
        };
        let line = line.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        match (words.next(), words.next(), words.next(), words.next()) {
            (None, ..) => {}
            (Some("bus"), Some(url), None, _) => out.push((url.to_string(), Vec::new())),
            (Some("board"), Some(addr), Some(kind), None) => {
                let board = super::board_from_spec(&format!("{addr}:{kind}"))
                    .map_err(|e| err(e.to_string()))?;
                out.last_mut()
                    .ok_or_else(|| err("`board` before any `bus` line".into()))?
                    .1
                    .push(board);
            }
            _ => {
                return Err(err(format!(
                    "cannot parse {line:?} (expected `bus URL` or `board ADDRESS KIND`)"
                )))
            }
        }
    }
    Ok(out)
}
