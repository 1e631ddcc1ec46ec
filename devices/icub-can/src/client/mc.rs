//! `MotorControlClient`: the core of `canmotioncontrol`.
//!
//! Units follow YARP: positions in degrees, speeds in deg/s, accelerations in deg/s²,
//! torques in N·m. Conversions follow `ControlBoardHelper`: `ticks = (deg + Zeros) ·
//! Encoder`, `deg = ticks / Encoder − Zeros`. Joint `j` is CAN axis `AxisMap[j]`, i.e.
//! channel `AxisMap[j] % 2` of board `CanAddresses[AxisMap[j] / 2]`.
//!
//! `canmotioncontrol` parameters (icubmod declares them and reads them into [`McParams`]):
//!
//! | group | supported | ignored (accepted, no effect yet) |
//! |-------|-----------|-----------------------------------|
//! | `CAN` | `CanAddresses`, `CanMyAddress`, `CanTimeout`, `broadcast_pos`, `broadcast_pid`, `broadcast_fault`, `broadcast_current`, `broadcast_overflow`, `broadcast_canprint`, `broadcast_vel_acc`, `broadcast_pid_err`, `broadcast_rotor_pos`, `broadcast_rotor_vel_acc` (bus keys: see [`crate::bus::config`]) | `CanPollingInterval`, `CanTxTimeout`, `CanRxTimeout`, `NetworkId`, `canbusdevice` |
//! | `GENERAL` | `Joints`, `AxisMap`, `AxisName`, `Encoder`, `Zeros`, `Rotor`, `TorqueId`, `TorqueChan`, `TorqueMax` | `AxisType`, `fullscalePWM`, `ampsToSensor`, `Verbose`, `GearBox` |
//! | `LIMITS` | `jntPosMin`, `jntPosMax` | `motorOverloadCurrents` |
//! | `VELOCITY` | `Shifts`, `Timeout`, `JNT_speed_estimation`, `JNT_accel_estimation`, `MOT_speed_estimation`, `MOT_accel_estimation` | |
//! | `POS_PIDS`, `TRQ_PIDS` | `kp`, `kd`, `ki`, `maxOutput`, `maxInt`, `shift`, `ko` | `stictionUp`, `stictionDwn`, `kff` |
//!
//! Torques use a per-joint scale ([`McParams::torque_scale`], sensor units per N·m:
//! `0x8000 / TorqueMax` as icub-main's `_newtonsToSensor`, 1 when `TorqueMax` is absent
//! or 0). Measured joint torques come, as in icub-main `CanBusMotionControl`'s
//! `handleBroadcasts`, from the analog-sensor broadcasts (class 3, types 0xA for channels
//! 0..2 and 0xB for 3..5, values offset by 0x8000) of board `TorqueId` (0 = none),
//! channel `TorqueChan`: `τ = (raw − 0x8000) / torque_scale` ([`MotorControlClient::torque`]).
//! Impedance (stiffness, damping, offset) uses the same torque scale over `Encoder`
//! (sensor units per tick), as YARP's `ImplementImpedanceControl`. Debug parameters and
//! motor-speed broadcasts are not exposed yet.

use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::link::Link;
use super::ClientError;
use crate::bus::{CanBus, IdFilter};
use crate::proto::mc::per;
use crate::proto::{
    make_id, AsPeriodic, ControlMode, McCommand, McPeriodic, McReply, Message, MsgClass, Pid,
    PidKind, PidLimits, VectorKind,
};

/// PID gains in YARP's `Pid` terms; the board takes them as 16-bit integers.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointPid {
    pub kp: f64,
    pub kd: f64,
    pub ki: f64,
    pub max_int: f64,
    /// Right shift applied to the output (YARP's `scale`).
    pub scale: f64,
    pub max_output: f64,
    pub offset: f64,
}

impl JointPid {
    fn to_board(self) -> Result<(Pid, PidLimits), ClientError> {
        let i = |what: &'static str, v: f64| -> Result<i16, ClientError> {
            if v.is_finite() && (f64::from(i16::MIN)..=f64::from(i16::MAX)).contains(&v.round()) {
                Ok(v.round() as i16)
            } else {
                Err(ClientError::Range { what, value: v })
            }
        };
        let shift = if (0.0..=255.0).contains(&self.scale) {
            self.scale as u8
        } else {
            return Err(ClientError::Range {
                what: "PID scale",
                value: self.scale,
            });
        };
        Ok((
            Pid {
                kp: i("kp", self.kp)?,
                ki: i("ki", self.ki)?,
                kd: i("kd", self.kd)?,
                shift,
            },
            PidLimits {
                offset: i("offset", self.offset)?,
                max_output: i("max output", self.max_output)?,
                max_integral: i("max int", self.max_int)?,
            },
        ))
    }

    fn from_board(p: Pid, l: PidLimits) -> Self {
        Self {
            kp: p.kp.into(),
            kd: p.kd.into(),
            ki: p.ki.into(),
            max_int: l.max_integral.into(),
            scale: p.shift.into(),
            max_output: l.max_output.into(),
            offset: l.offset.into(),
        }
    }
}

/// The parameters a `canmotioncontrol` XML provides.
#[derive(Debug, Clone)]
pub struct McParams {
    /// Group `CAN`, `CanAddresses`: one board per two axes.
    pub can_addresses: Vec<u8>,
    /// Group `CAN`, `CanMyAddress` (0).
    pub host_address: u8,
    /// Group `CAN`, `CanTimeout` (ms): how long to wait for a polling reply.
    pub reply_timeout: Duration,
    /// How old encoder broadcasts may be before reads fail.
    pub broadcast_timeout: Duration,
    /// Group `GENERAL`, `AxisMap`: joint -> CAN axis.
    pub axis_map: Vec<usize>,
    /// Group `GENERAL`, `AxisName`.
    pub axis_names: Vec<String>,
    /// Group `GENERAL`, `Encoder`: ticks per degree (negative flips the direction; 0 marks an unused axis).
    pub encoder: Vec<f64>,
    /// Group `GENERAL`, `Zeros`: degrees.
    pub zeros: Vec<f64>,
    /// Torque sensor units per N·m: group `GENERAL`, `0x8000 / TorqueMax` (1 when not configured).
    pub torque_scale: Vec<f64>,
    /// Group `GENERAL`, `TorqueId` / `TorqueChan`: the analog-sensor board and channel
    /// (0..=5) broadcasting the joint's measured torque (`None`: `TorqueId` 0).
    pub torque_sensors: Vec<Option<(u8, u8)>>,
    /// Group `GENERAL`, `Rotor`: motor encoder ticks per degree (1 when absent).
    pub rotor: Vec<f64>,
    /// Group `LIMITS`, `jntPosMin` / `jntPosMax`, degrees.
    pub limits: Vec<(f64, f64)>,
    /// Group `VELOCITY`, `Shifts`: velocity command shift.
    pub vel_shifts: Vec<u16>,
    /// Group `VELOCITY`, `JNT_speed_estimation`, `JNT_accel_estimation`, `MOT_speed_estimation`, `MOT_accel_estimation`.
    pub estimation_shifts: Vec<[u8; 4]>,
    /// Group `VELOCITY`, `Timeout` (ms) of velocity commands.
    pub vel_timeouts: Vec<u16>,
    /// Group `POS_PIDS`: sent at open when present.
    pub position_pids: Option<Vec<JointPid>>,
    /// Group `TRQ_PIDS`: sent at open when present.
    pub torque_pids: Option<Vec<JointPid>>,
    /// Group `CAN`, `broadcast_*`: broadcast policy mask per board.
    pub broadcast_policy: Option<Vec<u32>>,
}

/// Each joint's torque sensor from `GENERAL`'s `TorqueId` and `TorqueChan` (a missing or
/// short list means none; `TorqueId` 0 means none).
pub fn torque_sensors(ids: &[f64], chans: &[f64], joints: usize) -> Vec<Option<(u8, u8)>> {
    (0..joints)
        .map(|j| {
            let at = |v: &[f64]| v.get(j).copied().unwrap_or(0.0);
            match (at(ids), at(chans)) {
                (id @ 1.0..=14.0, ch @ 0.0..=5.0) => Some((id as u8, ch as u8)),
                (0.0, _) => None,
                (id, ch) => {
                    // icub-main does not check; such a sensor never matches.
                    tracing::warn!(
                        joint = j,
                        "[GENERAL] TorqueId {id} / TorqueChan {ch}: not a CAN address 1..14 and a channel 0..5; no measured torque"
                    );
                    None
                }
            }
        })
        .collect()
}

/// The `CAN` group's per-axis broadcast flags and the periodic message each enables.
pub const BROADCAST_FLAGS: [(&str, u8); 10] = [
    ("broadcast_pos", per::POSITION),
    ("broadcast_pid", per::PID_VAL),
    ("broadcast_fault", per::STATUS),
    ("broadcast_current", per::CURRENT),
    ("broadcast_overflow", per::OVERFLOW),
    ("broadcast_canprint", per::PRINT),
    ("broadcast_vel_acc", per::VELOCITY),
    ("broadcast_pid_err", per::PID_ERROR),
    ("broadcast_rotor_pos", per::MOTOR_POSITION),
    ("broadcast_rotor_vel_acc", per::MOTOR_SPEED),
];

/// The broadcast policy of each of `boards` boards from the lines of [`BROADCAST_FLAGS`]
/// (in its order; `None` where absent): one flag per axis, a board broadcasts a type if
/// either of its two axes asks; `None` when no line is given.
pub fn broadcast_masks(lines: &[Option<Vec<f64>>], boards: usize) -> Option<Vec<u32>> {
    let mut masks: Option<Vec<u32>> = None;
    for (line, (_, bit)) in lines.iter().zip(BROADCAST_FLAGS) {
        if let Some(v) = line {
            let m = masks.get_or_insert_with(|| vec![0; boards]);
            for (axis, flag) in v.iter().enumerate() {
                if *flag != 0.0 && axis / 2 < m.len() {
                    m[axis / 2] |= 1 << bit;
                }
            }
        }
    }
    // Interaction modes ride on the additional status, which the wrappers need.
    masks.map(|m| {
        m.into_iter()
            .map(|x| x | (1 << per::ADDITIONAL_STATUS))
            .collect()
    })
}

impl McParams {
    /// Minimal parameters: `joints` joints on `addresses`, identity axis map, one encoder
    /// factor, zero offsets, no limits.
    pub fn uniform(addresses: &[u8], joints: usize, encoder: f64) -> Self {
        Self {
            can_addresses: addresses.to_vec(),
            host_address: 0,
            reply_timeout: Duration::from_millis(500),
            broadcast_timeout: Duration::from_millis(500),
            axis_map: (0..joints).collect(),
            axis_names: (0..joints).map(|j| format!("joint{j}")).collect(),
            encoder: vec![encoder; joints],
            zeros: vec![0.0; joints],
            torque_scale: vec![1.0; joints],
            torque_sensors: vec![None; joints],
            rotor: vec![1.0; joints],
            limits: vec![(f64::NEG_INFINITY, f64::INFINITY); joints],
            vel_shifts: vec![0; joints],
            estimation_shifts: vec![[0; 4]; joints],
            vel_timeouts: vec![100; joints],
            position_pids: None,
            torque_pids: None,
            broadcast_policy: None,
        }
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.axis_map.len()
    }

    /// Checks the parameters fit together (one value per joint, each joint on a listed
    /// board, shifts at most 15).
    pub fn validate(&self) -> Result<(), ClientError> {
        let n = self.joints();
        let bad = |m: String| Err(ClientError::Config(m));
        if n == 0 {
            return bad("no joints".into());
        }
        for (name, len) in [
            ("Encoder", self.encoder.len()),
            ("Zeros", self.zeros.len()),
            ("limits", self.limits.len()),
            ("Shifts", self.vel_shifts.len()),
            ("estimation shifts", self.estimation_shifts.len()),
            ("velocity Timeout", self.vel_timeouts.len()),
            ("torque scale", self.torque_scale.len()),
            ("torque sensors", self.torque_sensors.len()),
            ("Rotor", self.rotor.len()),
        ] {
            if len != n {
                return bad(format!("{name} has {len} entries for {n} joints"));
            }
        }
        let mut seen = std::collections::HashSet::new();
        for (j, &axis) in self.axis_map.iter().enumerate() {
            if axis / 2 >= self.can_addresses.len() {
                return bad(format!(
                    "joint {j} maps to axis {axis} but only {} boards are listed",
                    self.can_addresses.len()
                ));
            }
            if !seen.insert(axis) {
                return bad(format!("axis {axis} is mapped twice"));
            }
        }
        if self.vel_shifts.iter().any(|s| *s > 15)
            || self.estimation_shifts.iter().flatten().any(|s| *s > 15)
        {
            return bad("shifts must be at most 15".into());
        }
        Ok(())
    }
}

/// What the broadcasts say about one joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointStatus {
    /// Control mode from the last status broadcast.
    pub mode: Option<ControlMode>,
    /// Axis fault bits (see [`crate::proto::BoardStatus`]).
    pub faults: u8,
    /// CAN status bits of the board (0x02 = bus off).
    pub can_status: u8,
    pub interaction: Option<u8>,
    /// Age of the last encoder broadcast.
    pub position_age: Option<Duration>,
    /// Age of the last status broadcast.
    pub status_age: Option<Duration>,
}

/// Liveness of one board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoardHealth {
    pub address: u8,
    /// Time since anything was heard from the board.
    pub silent_for: Option<Duration>,
    /// Whether it was heard within the broadcast timeout.
    pub alive: bool,
}

#[derive(Debug, Clone, Copy, Default)]
struct JointState {
    ticks: i32,
    position_at: Option<Instant>,
    speed_raw: i16,
    accel_raw: i16,
    pid_output: i16,
    motor_ticks: i32,
    motor_at: Option<Instant>,
    current: i16,
    /// Measured torque, sensor units (value − 0x8000 of the analog broadcast).
    torque_raw: i32,
    torque_at: Option<Instant>,
    mode: Option<ControlMode>,
    faults: u8,
    can_status: u8,
    interaction: Option<u8>,
    status_at: Option<Instant>,
}

#[derive(Default)]
struct Shared {
    joints: Vec<JointState>,
    heard: HashMap<u8, Instant>,
}

/// The host side of a set of motor-control boards (one `canmotioncontrol` device).
pub struct MotorControlClient {
    params: McParams,
    link: Arc<Link>,
    reader: Option<JoinHandle<()>>,
    state: Arc<Mutex<Shared>>,
    /// Locally stored references (as `CanBusMotionControl` keeps them): speed deg/s, acceleration deg/s².
    refs: Mutex<(Vec<f64>, Vec<f64>)>,
}

impl MotorControlClient {
    /// Opens the client: starts the reader, checks that every board answers (fails with
    /// [`ClientError::BoardsSilent`] otherwise) and sends the configuration (broadcast
    /// policy, shifts, velocity timeouts, PIDs, limits).
    pub fn open(bus: Arc<dyn CanBus>, params: McParams) -> Result<Self, ClientError> {
        params.validate()?;
        let n = params.joints();
        // (board, channel) -> joint, for routing broadcasts.
        let mut route: HashMap<(u8, u8), usize> = HashMap::new();
        for (j, &axis) in params.axis_map.iter().enumerate() {
            route.insert((params.can_addresses[axis / 2], (axis % 2) as u8), j);
        }
        let mut filter = IdFilter::none();
        for &a in &params.can_addresses {
            filter.add(make_id(
                MsgClass::PollingMotorControl,
                a,
                params.host_address,
            ));
            for kind in 0..16 {
                filter.add(make_id(MsgClass::PeriodicMotorControl, a, kind));
            }
        }
        // Joint-torque sensors: (board, channel) -> joints reading that channel.
        let mut torque_route: HashMap<(u8, u8), Vec<usize>> = HashMap::new();
        for (j, s) in params.torque_sensors.iter().enumerate() {
            if let Some((board, ch)) = *s {
                torque_route.entry((board, ch)).or_default().push(j);
                // ICUBCANPROTO_PER_AS_MSG__FORCE_VECTOR (0xA) / __TORQUE_VECTOR (0xB).
                filter.add(make_id(MsgClass::PeriodicAnalogSensor, board, 0xA));
                filter.add(make_id(MsgClass::PeriodicAnalogSensor, board, 0xB));
            }
        }
        bus.set_filter(filter);
        let state = Arc::new(Mutex::new(Shared {
            joints: vec![JointState::default(); n],
            heard: HashMap::new(),
        }));
        let st = state.clone();
        let (link, reader) = Link::start(bus, params.host_address, move |msg| {
            if let Message::AsPeriodic {
                board,
                msg:
                    AsPeriodic::Vector {
                        kind: kind @ (VectorKind::Force | VectorKind::Torque),
                        raw,
                        ..
                    },
            } = msg
            {
                let now = Instant::now();
                let mut s = st.lock();
                let first = kind.first_channel();
                for (i, v) in AsPeriodic::signed(*raw).into_iter().enumerate() {
                    for &j in torque_route
                        .get(&(*board, (first + i) as u8))
                        .map_or(&[][..], Vec::as_slice)
                    {
                        s.joints[j].torque_raw = v;
                        s.joints[j].torque_at = Some(now);
                    }
                }
                return;
            }
            let Message::McPeriodic { board, msg } = msg else {
                return;
            };
            let now = Instant::now();
            let mut s = st.lock();
            s.heard.insert(*board, now);
            let mut each = |ch: u8, f: &mut dyn FnMut(&mut JointState, usize)| {
                if let Some(&j) = route.get(&(*board, ch)) {
                    f(&mut s.joints[j], usize::from(ch));
                }
            };
            for ch in 0..2u8 {
                match msg {
                    McPeriodic::Position(p) => each(ch, &mut |js, c| {
                        js.ticks = p[c];
                        js.position_at = Some(now);
                    }),
                    McPeriodic::Velocity { speed, accel } => each(ch, &mut |js, c| {
                        js.speed_raw = speed[c];
                        js.accel_raw = accel[c];
                    }),
                    McPeriodic::PidValue(v) => each(ch, &mut |js, c| js.pid_output = v[c]),
                    McPeriodic::Current(v) => each(ch, &mut |js, c| js.current = v[c]),
                    McPeriodic::MotorPosition(p) => each(ch, &mut |js, c| {
                        js.motor_ticks = p[c];
                        js.motor_at = Some(now);
                    }),
                    McPeriodic::Status(b) => each(ch, &mut |js, c| {
                        js.mode = Some(b.control_mode[c]);
                        js.faults = b.axis_faults[c];
                        js.can_status = b.can_status;
                        js.status_at = Some(now);
                    }),
                    McPeriodic::AdditionalStatus { interaction } => {
                        each(ch, &mut |js, c| js.interaction = Some(interaction[c]))
                    }
                    _ => {}
                }
            }
        })?;
        let refs = Mutex::new((vec![10.0; n], vec![1000.0; n]));
        let client = Self {
            params,
            link,
            reader: Some(reader),
            state,
            refs,
        };
        client.check_firmware()?;
        client.configure()?;
        Ok(client)
    }

    fn check_firmware(&self) -> Result<(), ClientError> {
        let mut silent = Vec::new();
        for &board in &self.params.can_addresses {
            let cmd = McCommand::GetFirmwareVersion {
                proto_major: 1,
                proto_minor: 6,
            };
            if self.poll_board(board, 0, cmd).is_err() {
                silent.push(board);
            }
        }
        if silent.is_empty() {
            Ok(())
        } else {
            Err(ClientError::BoardsSilent { boards: silent })
        }
    }

    fn configure(&self) -> Result<(), ClientError> {
        let p = &self.params;
        let mut frames = Vec::new();
        if let Some(policy) = &p.broadcast_policy {
            for (b, &mask) in policy.iter().enumerate() {
                if let Some(&board) = p.can_addresses.get(b) {
                    frames.push(self.frame_for_board(board, 0, McCommand::SetBcastPolicy(mask)));
                }
            }
        }
        for j in 0..p.joints() {
            let [jv, ja, mv, ma] = p.estimation_shifts[j];
            frames.push(self.frame(j, McCommand::SetVelShift(p.vel_shifts[j])));
            frames.push(self.frame(
                j,
                McCommand::SetSpeedEstimShift {
                    jnt_vel: jv,
                    jnt_acc: ja,
                    mot_vel: mv,
                    mot_acc: ma,
                },
            ));
            frames.push(self.frame(j, McCommand::SetVelTimeout(p.vel_timeouts[j])));
            if p.encoder[j] != 0.0 && p.limits[j].0.is_finite() && p.limits[j].1.is_finite() {
                let (a, b) = (
                    self.to_ticks(j, p.limits[j].0)?,
                    self.to_ticks(j, p.limits[j].1)?,
                );
                frames.push(self.frame(j, McCommand::SetMinPosition(a.min(b))));
                frames.push(self.frame(j, McCommand::SetMaxPosition(a.max(b))));
            }
            for (kind, pids) in [
                (PidKind::Position, &p.position_pids),
                (PidKind::Torque, &p.torque_pids),
            ] {
                if let Some(pid) = pids.as_ref().and_then(|v| v.get(j)) {
                    let (gains, limits) = pid.to_board()?;
                    frames.push(self.frame(j, McCommand::SetPid(kind, gains)));
                    frames.push(self.frame(j, McCommand::SetPidLimits(kind, limits)));
                }
            }
        }
        self.link.send(&frames)
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.params.joints()
    }

    /// The parameters in use.
    pub fn params(&self) -> &McParams {
        &self.params
    }

    fn check(&self, j: usize) -> Result<(), ClientError> {
        if j < self.joints() {
            Ok(())
        } else {
            Err(ClientError::BadJoint {
                joint: j,
                joints: self.joints(),
            })
        }
    }

    fn locate(&self, j: usize) -> (u8, u8) {
        let axis = self.params.axis_map[j];
        (self.params.can_addresses[axis / 2], (axis % 2) as u8)
    }

    fn frame_for_board(&self, board: u8, axis: u8, cmd: McCommand) -> crate::CanFrame {
        Message::McRequest {
            src: self.params.host_address,
            dst: board,
            axis,
            cmd,
        }
        .encode()
    }

    fn frame(&self, j: usize, cmd: McCommand) -> crate::CanFrame {
        let (board, axis) = self.locate(j);
        self.frame_for_board(board, axis, cmd)
    }

    fn send(&self, j: usize, cmd: McCommand) -> Result<(), ClientError> {
        self.check(j)?;
        self.link.send(&[self.frame(j, cmd)])
    }

    fn poll_board(&self, board: u8, axis: u8, cmd: McCommand) -> Result<McReply, ClientError> {
        let op = cmd.opcode();
        let timeout = self.params.reply_timeout;
        let reply = self.link.request(
            self.frame_for_board(board, axis, cmd),
            move |m| matches!(m, Message::McReply { src, axis: a, reply, .. } if *src == board && *a == axis && reply.opcode() == op),
            timeout,
        )?;
        match reply {
            Some(Message::McReply { reply, .. }) => Ok(reply),
            _ => Err(ClientError::BoardTimeout {
                board,
                what: format!("{cmd:?}"),
                timeout,
            }),
        }
    }

    fn poll(&self, j: usize, cmd: McCommand) -> Result<McReply, ClientError> {
        self.check(j)?;
        let (board, axis) = self.locate(j);
        self.poll_board(board, axis, cmd)
    }

    fn unexpected(&self, j: usize, r: McReply) -> ClientError {
        ClientError::BoardTimeout {
            board: self.locate(j).0,
            what: format!("a matching reply (got {r:?})"),
            timeout: self.params.reply_timeout,
        }
    }

    fn to_ticks(&self, j: usize, deg: f64) -> Result<i32, ClientError> {
        let t = (deg + self.params.zeros[j]) * self.params.encoder[j];
        if t.is_finite() && (f64::from(i32::MIN)..=f64::from(i32::MAX)).contains(&t.round()) {
            Ok(t.round() as i32)
        } else {
            Err(ClientError::Range {
                what: "position",
                value: deg,
            })
        }
    }

    fn to_deg(&self, j: usize, ticks: i32) -> f64 {
        let e = self.params.encoder[j];
        if e == 0.0 {
            0.0
        } else {
            f64::from(ticks) / e - self.params.zeros[j]
        }
    }

    fn i16_of(what: &'static str, v: f64) -> Result<i16, ClientError> {
        if v.is_finite() {
            Ok(v.round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16)
        } else {
            Err(ClientError::Range { what, value: v })
        }
    }

    // ---- position control ----

    /// Sets the speed of subsequent position moves (deg/s), as `setRefSpeed`.
    pub fn set_ref_speed(&self, j: usize, deg_s: f64) -> Result<(), ClientError> {
        self.check(j)?;
        if !deg_s.is_finite() {
            return Err(ClientError::Range {
                what: "reference speed",
                value: deg_s,
            });
        }
        self.refs.lock().0[j] = deg_s.abs();
        Ok(())
    }

    pub fn ref_speed(&self, j: usize) -> Result<f64, ClientError> {
        self.check(j)?;
        Ok(self.refs.lock().0[j])
    }

    /// Sets the acceleration of velocity moves (deg/s²), as `setRefAcceleration`.
    pub fn set_ref_acceleration(&self, j: usize, deg_s2: f64) -> Result<(), ClientError> {
        self.check(j)?;
        if !deg_s2.is_finite() {
            return Err(ClientError::Range {
                what: "reference acceleration",
                value: deg_s2,
            });
        }
        self.refs.lock().1[j] = deg_s2.abs();
        Ok(())
    }

    pub fn ref_acceleration(&self, j: usize) -> Result<f64, ClientError> {
        self.check(j)?;
        Ok(self.refs.lock().1[j])
    }

    /// Moves joint `j` to `deg` at the reference speed (`positionMove`).
    pub fn position_move(&self, j: usize, deg: f64) -> Result<(), ClientError> {
        self.check(j)?;
        let speed = self.ref_speed(j)? * self.params.encoder[j].abs() / 10.0;
        let cmd = McCommand::PositionMove {
            position: self.to_ticks(j, deg)?,
            speed: Self::i16_of("speed", speed)?.max(1),
        };
        self.send(j, cmd)
    }

    /// Moves all joints (`positionMove(const double*)`).
    pub fn position_move_all(&self, deg: &[f64]) -> Result<(), ClientError> {
        if deg.len() != self.joints() {
            return Err(ClientError::Config(format!(
                "{} targets for {} joints",
                deg.len(),
                self.joints()
            )));
        }
        let refs = self.refs.lock().0.clone();
        let frames = deg
            .iter()
            .enumerate()
            .map(|(j, &d)| {
                let speed =
                    Self::i16_of("speed", refs[j] * self.params.encoder[j].abs() / 10.0)?.max(1);
                Ok(self.frame(
                    j,
                    McCommand::PositionMove {
                        position: self.to_ticks(j, d)?,
                        speed,
                    },
                ))
            })
            .collect::<Result<Vec<_>, ClientError>>()?;
        self.link.send(&frames)
    }

    /// Whether the last position move of `j` finished (`checkMotionDone`).
    pub fn motion_done(&self, j: usize) -> Result<bool, ClientError> {
        match self.poll(j, McCommand::MotionDone)? {
            McReply::MotionDone(d) => Ok(d),
            r => Err(self.unexpected(j, r)),
        }
    }

    /// Stops the trajectory of `j`.
    pub fn stop(&self, j: usize) -> Result<(), ClientError> {
        self.send(j, McCommand::StopTrajectory)
    }

    /// Streams a position reference in position-direct mode (`setPosition`).
    pub fn set_position(&self, j: usize, deg: f64) -> Result<(), ClientError> {
        self.check(j)?;
        self.send(j, McCommand::SetCommandPosition(self.to_ticks(j, deg)?))
    }

    // ---- velocity control ----

    /// Velocity command in deg/s (`velocityMove`); it expires after the velocity timeout.
    pub fn velocity_move(&self, j: usize, deg_s: f64) -> Result<(), ClientError> {
        self.check(j)?;
        let enc = self.params.encoder[j];
        let scale = f64::from(1u32 << self.params.vel_shifts[j]);
        let speed = Self::i16_of("velocity", deg_s * enc / 1000.0 * scale)?;
        let acc = self.ref_acceleration(j)? * enc.abs() / 1e6 * scale;
        let accel = Self::i16_of("acceleration", acc)?.max(1);
        self.send(j, McCommand::VelocityMove { speed, accel })
    }

    // ---- torque control ----

    /// Torque reference in N·m (`setRefTorque`).
    pub fn set_ref_torque(&self, j: usize, nm: f64) -> Result<(), ClientError> {
        self.check(j)?;
        self.send(
            j,
            McCommand::SetDesiredTorque(Self::i16_of("torque", nm * self.params.torque_scale[j])?),
        )
    }

    /// Measured joint torque in N·m (`getTorque`), from the latest analog broadcast of
    /// the joint's `TorqueId`/`TorqueChan`; fails for a joint without a sensor and when
    /// no broadcast came within the broadcast timeout.
    pub fn torque(&self, j: usize) -> Result<f64, ClientError> {
        self.check(j)?;
        let Some((board, ch)) = self.params.torque_sensors[j] else {
            return Err(ClientError::Config(format!(
                "joint {j} has no torque sensor (TorqueId 0)"
            )));
        };
        let js = self.state.lock().joints[j];
        let timeout = self.params.broadcast_timeout;
        match js.torque_at.map(|t| t.elapsed()) {
            Some(age) if age <= timeout => {
                Ok(f64::from(js.torque_raw) / self.params.torque_scale[j])
            }
            age => {
                tracing::debug!(joint = j, board, channel = ch, "no torque broadcast");
                Err(ClientError::Stale {
                    joint: j,
                    board,
                    age,
                    timeout,
                })
            }
        }
    }

    /// The board's torque reference in N·m (`getRefTorque`).
    pub fn ref_torque(&self, j: usize) -> Result<f64, ClientError> {
        match self.poll(j, McCommand::GetDesiredTorque)? {
            McReply::DesiredTorque(t) => Ok(f64::from(t) / self.params.torque_scale[j]),
            r => Err(self.unexpected(j, r)),
        }
    }

    // ---- modes ----

    pub fn set_control_mode(&self, j: usize, mode: ControlMode) -> Result<(), ClientError> {
        self.send(j, McCommand::SetControlMode(mode))
    }

    /// The control mode, asked to the board (`getControlMode`).
    pub fn control_mode(&self, j: usize) -> Result<ControlMode, ClientError> {
        match self.poll(j, McCommand::GetControlMode)? {
            McReply::ControlMode(m) => Ok(m),
            r => Err(self.unexpected(j, r)),
        }
    }

    /// 0 = stiff, 1 = compliant.
    pub fn set_interaction_mode(&self, j: usize, mode: u8) -> Result<(), ClientError> {
        self.send(j, McCommand::SetInteractionMode(mode))
    }

    pub fn interaction_mode(&self, j: usize) -> Result<u8, ClientError> {
        match self.poll(j, McCommand::GetInteractionMode)? {
            McReply::InteractionMode(m) => Ok(m),
            r => Err(self.unexpected(j, r)),
        }
    }

    // ---- amplifiers and calibration ----

    /// Enables the amplifier and the controller (`enableAmp` + `enablePid`).
    pub fn enable_amp(&self, j: usize) -> Result<(), ClientError> {
        self.send(j, McCommand::EnablePwm)?;
        self.send(j, McCommand::ControllerRun)
    }

    /// Disables controller and amplifier (`disablePid` + `disableAmp`).
    pub fn disable_amp(&self, j: usize) -> Result<(), ClientError> {
        self.send(j, McCommand::ControllerIdle)?;
        self.send(j, McCommand::DisablePwm)
    }

    /// Motor current from the broadcasts (board units).
    pub fn current(&self, j: usize) -> Result<f64, ClientError> {
        self.check(j)?;
        Ok(self.state.lock().joints[j].current.into())
    }

    /// Sets the amplifier current limit (board units).
    pub fn set_max_current(&self, j: usize, limit: i32) -> Result<(), ClientError> {
        self.send(j, McCommand::SetCurrentLimit(limit))
    }

    /// Starts calibration (`calibrateAxisWithParams`).
    pub fn calibrate(
        &self,
        j: usize,
        kind: u8,
        p1: f64,
        p2: f64,
        p3: f64,
    ) -> Result<(), ClientError> {
        self.check(j)?;
        let cmd = McCommand::CalibrateEncoder {
            kind,
            p1: Self::i16_of("p1", p1)?,
            p2: Self::i16_of("p2", p2)?,
            p3: Self::i16_of("p3", p3)?,
        };
        self.send(j, cmd)
    }

    // ---- impedance ----

    /// Sensor units per encoder tick for joint `j`: icub-main's `ImplementImpedanceControl`
    /// conversion (`newtonsToSensor / angleToEncoder`), for N·m/° and N·m·s/°.
    fn impedance_scale(&self, j: usize) -> f64 {
        let e = self.params.encoder[j];
        if e == 0.0 {
            0.0
        } else {
            self.params.torque_scale[j] / e
        }
    }

    /// Sets the joint's spring, stiffness N·m/°, damping N·m·s/° (`setImpedance`); sent
    /// as `CanBusMotionControl::setImpedanceRaw` does: damping ×1000.
    pub fn set_impedance(&self, j: usize, stiffness: f64, damping: f64) -> Result<(), ClientError> {
        self.check(j)?;
        let s = self.impedance_scale(j);
        self.send(
            j,
            McCommand::SetImpedanceParams {
                stiffness: Self::i16_of("stiffness", stiffness * s)?,
                damping: Self::i16_of("damping", damping * s * 1000.0)?,
            },
        )
    }

    /// The board's (stiffness N·m/°, damping N·m·s/°) (`getImpedance`).
    pub fn impedance(&self, j: usize) -> Result<(f64, f64), ClientError> {
        match self.poll(j, McCommand::GetImpedanceParams)? {
            McReply::ImpedanceParams { stiffness, damping } => {
                let s = self.impedance_scale(j);
                if s == 0.0 {
                    return Ok((0.0, 0.0));
                }
                Ok((f64::from(stiffness) / s, f64::from(damping) / 1000.0 / s))
            }
            r => Err(self.unexpected(j, r)),
        }
    }

    /// Sets the impedance law's torque offset, N·m (`setImpedanceOffset`).
    pub fn set_impedance_offset(&self, j: usize, nm: f64) -> Result<(), ClientError> {
        self.check(j)?;
        self.send(
            j,
            McCommand::SetImpedanceOffset(Self::i16_of(
                "impedance offset",
                nm * self.params.torque_scale[j],
            )?),
        )
    }

    /// The board's impedance torque offset, N·m (`getImpedanceOffset`).
    pub fn impedance_offset(&self, j: usize) -> Result<f64, ClientError> {
        match self.poll(j, McCommand::GetImpedanceOffset)? {
            McReply::ImpedanceOffset(v) => Ok(f64::from(v) / self.params.torque_scale[j]),
            r => Err(self.unexpected(j, r)),
        }
    }

    // ---- PIDs ----

    /// Sends gains and limits of one PID.
    pub fn set_pid(&self, j: usize, kind: PidKind, pid: &JointPid) -> Result<(), ClientError> {
        self.check(j)?;
        let (gains, limits) = pid.to_board()?;
        self.link.send(&[
            self.frame(j, McCommand::SetPid(kind, gains)),
            self.frame(j, McCommand::SetPidLimits(kind, limits)),
        ])
    }

    /// Reads gains and limits of one PID from the board.
    pub fn pid(&self, j: usize, kind: PidKind) -> Result<JointPid, ClientError> {
        let gains = match self.poll(j, McCommand::GetPid(kind))? {
            McReply::Pid(_, p) => p,
            r => return Err(self.unexpected(j, r)),
        };
        let limits = match self.poll(j, McCommand::GetPidLimits(kind))? {
            McReply::PidLimits(_, l) => l,
            r => return Err(self.unexpected(j, r)),
        };
        Ok(JointPid::from_board(gains, limits))
    }

    /// PID output (PWM counts) from the broadcasts.
    pub fn pid_output(&self, j: usize) -> Result<f64, ClientError> {
        self.check(j)?;
        Ok(self.state.lock().joints[j].pid_output.into())
    }

    // ---- limits ----

    /// Sets the software limits in degrees (`setLimits`).
    pub fn set_limits(&self, j: usize, min: f64, max: f64) -> Result<(), ClientError> {
        self.check(j)?;
        let (a, b) = (self.to_ticks(j, min)?, self.to_ticks(j, max)?);
        self.link.send(&[
            self.frame(j, McCommand::SetMinPosition(a.min(b))),
            self.frame(j, McCommand::SetMaxPosition(a.max(b))),
        ])
    }

    /// Reads the limits from the board, in degrees (`getLimits`).
    pub fn limits(&self, j: usize) -> Result<(f64, f64), ClientError> {
        let a = match self.poll(j, McCommand::GetMinPosition)? {
            McReply::MinPosition(v) => v,
            r => return Err(self.unexpected(j, r)),
        };
        let b = match self.poll(j, McCommand::GetMaxPosition)? {
            McReply::MaxPosition(v) => v,
            r => return Err(self.unexpected(j, r)),
        };
        let (x, y) = (self.to_deg(j, a), self.to_deg(j, b));
        Ok((x.min(y), x.max(y)))
    }

    // ---- encoders ----

    fn fresh(&self, j: usize) -> Result<JointState, ClientError> {
        self.check(j)?;
        let js = self.state.lock().joints[j];
        let timeout = self.params.broadcast_timeout;
        let age = js.position_at.map(|t| t.elapsed());
        match age {
            Some(a) if a <= timeout => Ok(js),
            _ => Err(ClientError::Stale {
                joint: j,
                board: self.locate(j).0,
                age,
                timeout,
            }),
        }
    }

    /// Joint position in degrees from the latest broadcast (`getEncoder`).
    pub fn encoder(&self, j: usize) -> Result<f64, ClientError> {
        let js = self.fresh(j)?;
        Ok(self.to_deg(j, js.ticks))
    }

    /// All joint positions (`getEncoders`); fails if any joint is stale.
    pub fn encoders(&self) -> Result<Vec<f64>, ClientError> {
        (0..self.joints()).map(|j| self.encoder(j)).collect()
    }

    /// Positions with the time each was received (`getEncodersTimed`).
    pub fn encoders_timed(&self) -> Result<Vec<(f64, Instant)>, ClientError> {
        (0..self.joints())
            .map(|j| {
                let js = self.fresh(j)?;
                Ok((
                    self.to_deg(j, js.ticks),
                    js.position_at.expect("fresh implies a timestamp"),
                ))
            })
            .collect()
    }

    /// Joint speed in deg/s from the velocity broadcast (`getEncoderSpeed`).
    pub fn encoder_speed(&self, j: usize) -> Result<f64, ClientError> {
        let js = self.fresh(j)?;
        let e = self.params.encoder[j];
        let shift = f64::from(1u32 << self.params.estimation_shifts[j][0]);
        Ok(if e == 0.0 {
            0.0
        } else {
            f64::from(js.speed_raw) * 1000.0 / shift / e
        })
    }

    /// Joint acceleration in deg/s² (`getEncoderAcceleration`).
    pub fn encoder_acceleration(&self, j: usize) -> Result<f64, ClientError> {
        let js = self.fresh(j)?;
        let e = self.params.encoder[j];
        let shift = f64::from(1u32 << self.params.estimation_shifts[j][1]);
        Ok(if e == 0.0 {
            0.0
        } else {
            f64::from(js.accel_raw) * 1e6 / shift / e
        })
    }

    /// Motor (rotor) position in degrees of the rotor from the motor-position broadcast
    /// (`getMotorEncoder`; needs `broadcast_rotor_pos`).
    pub fn motor_encoder(&self, j: usize) -> Result<f64, ClientError> {
        self.check(j)?;
        let js = self.state.lock().joints[j];
        let timeout = self.params.broadcast_timeout;
        match js.motor_at.map(|t| t.elapsed()) {
            Some(age) if age <= timeout => Ok(f64::from(js.motor_ticks) / self.params.rotor[j]),
            age => Err(ClientError::Stale {
                joint: j,
                board: self.locate(j).0,
                age,
                timeout,
            }),
        }
    }

    /// Asks the board for the encoder (bypassing broadcasts).
    pub fn poll_encoder(&self, j: usize) -> Result<f64, ClientError> {
        match self.poll(j, McCommand::GetEncoderPosition)? {
            McReply::EncoderPosition(t) => Ok(self.to_deg(j, t)),
            r => Err(self.unexpected(j, r)),
        }
    }

    // ---- status ----

    /// What the broadcasts say about joint `j`.
    pub fn joint_status(&self, j: usize) -> Result<JointStatus, ClientError> {
        self.check(j)?;
        let js = self.state.lock().joints[j];
        Ok(JointStatus {
            mode: js.mode,
            faults: js.faults,
            can_status: js.can_status,
            interaction: js.interaction,
            position_age: js.position_at.map(|t| t.elapsed()),
            status_age: js.status_at.map(|t| t.elapsed()),
        })
    }

    /// Liveness of every board, judged against the broadcast timeout.
    pub fn board_health(&self) -> Vec<BoardHealth> {
        let s = self.state.lock();
        self.params
            .can_addresses
            .iter()
            .map(|&address| {
                let silent_for = s.heard.get(&address).map(|t| t.elapsed());
                BoardHealth {
                    address,
                    silent_for,
                    alive: silent_for.is_some_and(|d| d <= self.params.broadcast_timeout),
                }
            })
            .collect()
    }

    /// Frames from these boards that failed to decode.
    pub fn malformed_frames(&self) -> u64 {
        self.link
            .malformed
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Counters of the underlying bus endpoint.
    pub fn bus_stats(&self) -> crate::BusStats {
        self.link.bus.stats()
    }
}

impl Drop for MotorControlClient {
    fn drop(&mut self) {
        self.link.stop();
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}
