//! A CAN network of emulated boards, as data ([`NetworkSpec`]) and as running boards
//! ([`build`]); [`mc_boards`] lays out the motor-control boards of one part from what its
//! `canmotioncontrol` file says of them ([`McLayout`]: `CanAddresses`, `AxisMap`, `Encoder`,
//! `Zeros`, `jntPosMin`/`jntPosMax`, `TorqueId`/`TorqueChan`/`TorqueMax`): every joint starts at 0°
//! clamped into its limits, and each joint with a `TorqueId` publishes its simulated
//! torque (sensor units `τ·0x8000/TorqueMax`, sign of its `Encoder`, so positive torques
//! turn the joint in its positive YARP direction) through a [`JointTorqueSensor`] at that
//! address broadcasting every 10 ms. Every motor board starts with
//! [`super::mc::DEFAULT_POSITION_PID`] gains (the host's `POS_PIDS`/`TRQ_PIDS` replace
//! them). Crate `icub-emulators` reads a robot's files into these.

use super::mc::{JointPlant, JointTorqueSensor, TorqueHub, TorqueLink};
use super::{Board, MaisBoard, McBoard, McBoardConfig, MtbBoard, SpecError, StrainBoard};

/// A board of a network.
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

/// One CAN network.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkSpec {
    /// `CanDeviceNum` of the network.
    pub num: u32,
    pub boards: Vec<BoardKind>,
}

/// What the boards of one motor-control part are, as its file lays them out (the
/// emulator reads it itself: it shares no reader with the driver).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct McLayout {
    /// `CAN/CanAddresses`: the boards, two axes each.
    pub can_addresses: Vec<u8>,
    /// `GENERAL/AxisMap`: each joint's axis.
    pub axis_map: Vec<usize>,
    /// Per joint: `GENERAL/Encoder` (units per degree), `GENERAL/Zeros` (degrees).
    pub encoder: Vec<f64>,
    pub zeros: Vec<f64>,
    /// Per joint: `LIMITS/jntPosMin`, `LIMITS/jntPosMax`.
    pub limits: Vec<(f64, f64)>,
    /// Per joint: `GENERAL/TorqueMax` (N·m), and the board and channel of its torque sensor
    /// (`TorqueId`, `TorqueChan`; none for `TorqueId` 0).
    pub torque_max: Vec<f64>,
    pub torque_sensors: Vec<Option<(u8, u8)>>,
}

/// The motor-control boards of one part, with the joint-torque sensors its joints name.
pub fn mc_boards(params: &McLayout) -> Vec<BoardKind> {
    let torque_max = &params.torque_max;
    let mut axes: Vec<[(f64, JointPlant); 2]> =
        vec![[(0.0, JointPlant::default()); 2]; params.can_addresses.len()];
    for (j, &axis) in params.axis_map.iter().enumerate() {
        let Some(slot) = axes.get_mut(axis / 2) else {
            continue;
        };
        let (lo, hi) = params
            .limits
            .get(j)
            .copied()
            .unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
        let angle = if lo <= hi { 0f64.clamp(lo, hi) } else { 0.0 };
        let e = params.encoder.get(j).copied().unwrap_or(1.0);
        let zero = params.zeros.get(j).copied().unwrap_or(0.0);
        let mut plant = JointPlant::with_torque_max(torque_max.get(j).copied().unwrap_or(0.0));
        plant.sensor_sign = Some(if e < 0.0 { -1.0 } else { 1.0 });
        plant.sensor = params
            .torque_sensors
            .get(j)
            .copied()
            .flatten()
            .map(|(address, channel)| TorqueLink { address, channel });
        slot[axis % 2] = ((angle + zero) * e, plant);
    }
    let mut boards = Vec::new();
    for (&address, axes) in params.can_addresses.iter().zip(&axes) {
        let plants = axes.map(|a| a.1);
        boards.push(BoardKind::Mc {
            address,
            initial: axes.map(|a| a.0),
            plants,
        });
        for link in plants.iter().filter_map(|p| p.sensor) {
            if !boards.contains(&BoardKind::JointTorque(link.address)) {
                boards.push(BoardKind::JointTorque(link.address));
            }
        }
    }
    boards
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
