//! Emulated sensor boards: strain (6-axis F/T), MAIS (hall-effect hand encoders) and
//! MTB (skin patch and/or inertial sensors).

use std::f64::consts::TAU;
use std::time::Duration;

use super::Board;
use crate::frame::CanFrame;
use crate::proto::analog::txmode;
use crate::proto::{
    AsCommand, AsPeriodic, AsReply, InertialMsg, Message, SkinFrame, TareOp, VectorKind,
};

/// Q1.15 value of 1.0 (the diagonal of an identity calibration matrix).
pub const Q15_ONE: i16 = 0x7FFF;

/// A strain board: streams forces (type 0xA) and torques (type 0xB) once started with
/// `SET_TXMODE`, at the `SET_CANDATARATE` period.
///
/// The emulated wrench is `offset + amplitude·sin(2π·t/period)` per channel, in N and
/// N·m. Every mode sends `wrench / full_scale · 0x8000` counts (the emulated gauges need
/// no calibration), so a host that applies the full scales reads the wrench back; debug
/// mode (`SET_TXMODE 4`) sends the same values as types 8 and 9.
pub struct StrainBoard {
    address: u8,
    pub full_scales: [u16; 6],
    pub matrix: [[i16; 6]; 6],
    pub offset: [f64; 6],
    pub amplitude: [f64; 6],
    pub signal_period: f64,
    tare: [u16; 6],
    mode: Option<u8>,
    period: Duration,
    since: Duration,
    time: f64,
}

impl StrainBoard {
    pub fn new(address: u8) -> Self {
        let mut matrix = [[0; 6]; 6];
        for (i, row) in matrix.iter_mut().enumerate() {
            row[i] = Q15_ONE;
        }
        Self {
            address,
            full_scales: [1000, 1000, 1000, 30, 30, 30],
            matrix,
            offset: [1.0, -2.0, 10.0, 0.1, -0.2, 0.3],
            amplitude: [2.0, 2.0, 5.0, 0.2, 0.2, 0.2],
            signal_period: 2.0,
            tare: [0; 6],
            mode: None,
            period: Duration::from_millis(1),
            since: Duration::ZERO,
            time: 0.0,
        }
    }

    /// Starts streaming as if the host had sent `SET_TXMODE` (used by tests and presets).
    pub fn start(&mut self, mode: u8) {
        self.mode = Some(mode);
    }

    /// The wrench emulated at time `t` seconds.
    pub fn wrench(&self, t: f64) -> [f64; 6] {
        let s = (TAU * t / self.signal_period.max(1e-3)).sin();
        std::array::from_fn(|i| self.offset[i] + self.amplitude[i] * s)
    }

    fn counts(&self, t: f64) -> [i16; 6] {
        let w = self.wrench(t);
        std::array::from_fn(|i| {
            let fs = f64::from(self.full_scales[i].max(1));
            (w[i] / fs * 32768.0).round().clamp(-32768.0, 32767.0) as i16
        })
    }
}

impl Board for StrainBoard {
    fn address(&self) -> u8 {
        self.address
    }
    fn kind(&self) -> &'static str {
        "strain"
    }
    fn start_streaming(&mut self) {
        self.start(txmode::CALIBRATED);
    }

    fn on_message(&mut self, msg: &Message, out: &mut Vec<CanFrame>) {
        let Message::AsRequest { src, dst, cmd } = msg else {
            return;
        };
        if *dst != self.address {
            return;
        }
        let reply = |r: AsReply| {
            Message::AsReply {
                src: self.address,
                dst: *src,
                reply: r,
            }
            .encode()
        };
        match *cmd {
            AsCommand::SetTxMode(m) => self.mode = (m != txmode::STOP).then_some(m),
            AsCommand::SetCanDataRate(ms) => {
                self.period = Duration::from_millis(u64::from(ms.max(1)))
            }
            AsCommand::GetFullScale { channel } if channel < 6 => {
                out.push(reply(AsReply::FullScale {
                    channel,
                    value: self.full_scales[usize::from(channel)],
                }))
            }
            AsCommand::SetFullScale { channel, value } if channel < 6 => {
                self.full_scales[usize::from(channel)] = value
            }
            AsCommand::GetMatrixRc { row, col } if row < 6 && col < 6 => {
                out.push(reply(AsReply::MatrixRc {
                    row,
                    col,
                    value: self.matrix[usize::from(row)][usize::from(col)],
                }))
            }
            AsCommand::SetMatrixRc { row, col, value } if row < 6 && col < 6 => {
                self.matrix[usize::from(row)][usize::from(col)] = value
            }
            AsCommand::SetCalibTare(TareOp::Reset) => self.tare = [0; 6],
            AsCommand::SetCalibTare(TareOp::Set { channel, value }) if channel < 6 => {
                self.tare[usize::from(channel)] = value
            }
            _ => {}
        }
    }

    fn next_output(&self) -> Option<Duration> {
        super::due_in(self.mode.is_some(), self.period, self.since)
    }

    fn tick(&mut self, dt: Duration, out: &mut Vec<CanFrame>) {
        self.time += dt.as_secs_f64();
        let Some(mode) = self.mode else { return };
        self.since += dt;
        if self.since < self.period {
            return;
        }
        self.since = Duration::ZERO;
        let c = self.counts(self.time);
        let (fk, tk) = if mode == txmode::DEBUG {
            (VectorKind::UncalibForce, VectorKind::UncalibTorque)
        } else {
            (VectorKind::Force, VectorKind::Torque)
        };
        out.push(
            Message::AsPeriodic {
                board: self.address,
                msg: AsPeriodic::vector(fk, [c[0], c[1], c[2]]),
            }
            .encode(),
        );
        out.push(
            Message::AsPeriodic {
                board: self.address,
                msg: AsPeriodic::vector(tk, [c[3], c[4], c[5]]),
            }
            .encode(),
        );
    }
}

/// A MAIS board: 15 hall-effect readings (8-bit) of the fingers, after `SET_TXMODE`.
pub struct MaisBoard {
    address: u8,
    pub values: [u8; 15],
    streaming: bool,
    period: Duration,
    since: Duration,
}

impl MaisBoard {
    pub fn new(address: u8) -> Self {
        Self {
            address,
            values: [128; 15],
            streaming: false,
            period: Duration::from_millis(10),
            since: Duration::ZERO,
        }
    }
}

impl Board for MaisBoard {
    fn address(&self) -> u8 {
        self.address
    }
    fn kind(&self) -> &'static str {
        "mais"
    }
    fn start_streaming(&mut self) {
        self.streaming = true;
    }
    fn on_message(&mut self, msg: &Message, _out: &mut Vec<CanFrame>) {
        let Message::AsRequest { dst, cmd, .. } = msg else {
            return;
        };
        if *dst != self.address {
            return;
        }
        match *cmd {
            AsCommand::SetTxMode(m) => self.streaming = m != txmode::STOP,
            AsCommand::SetCanDataRate(ms) => {
                self.period = Duration::from_millis(u64::from(ms.max(1)))
            }
            _ => {}
        }
    }
    fn next_output(&self) -> Option<Duration> {
        super::due_in(self.streaming, self.period, self.since)
    }

    fn tick(&mut self, dt: Duration, out: &mut Vec<CanFrame>) {
        if !self.streaming {
            return;
        }
        self.since += dt;
        if self.since < self.period {
            return;
        }
        self.since = Duration::ZERO;
        let v = &self.values;
        let a: [u8; 7] = v[..7].try_into().expect("15 values");
        let mut b = [0u8; 8];
        b.copy_from_slice(&v[7..15]);
        out.push(
            Message::AsPeriodic {
                board: self.address,
                msg: AsPeriodic::Hes0To6(a),
            }
            .encode(),
        );
        out.push(
            Message::AsPeriodic {
                board: self.address,
                msg: AsPeriodic::Hes7To14(b),
            }
            .encode(),
        );
    }
}

pub use crate::proto::sensors::inertial_bits;

/// An MTB board: optionally a skin patch (16 triangles of 12 taxels, streaming from
/// power-up) and inertial sensors (streaming once `ACC_GYRO_SETUP` enables them).
pub struct MtbBoard {
    address: u8,
    skin: bool,
    /// Taxel values per triangle (MTB raw: 255 is no contact, lower is pressure).
    pub taxels: [[u8; 12]; 16],
    skin_period: Duration,
    since_skin: Duration,
    sensors: u8,
    inertial_period: Duration,
    since_inertial: Duration,
    /// Accelerometer reading (raw units), gravity along +z by default.
    pub accel: [i16; 3],
    pub gyro: [i16; 3],
}

impl MtbBoard {
    pub fn new(address: u8, skin: bool) -> Self {
        Self {
            address,
            skin,
            taxels: [[244; 12]; 16],
            skin_period: Duration::from_millis(50),
            since_skin: Duration::ZERO,
            sensors: 0,
            inertial_period: Duration::from_millis(10),
            since_inertial: Duration::ZERO,
            accel: [0, 0, 16384],
            gyro: [0, 0, 0],
        }
    }
}

impl Board for MtbBoard {
    fn address(&self) -> u8 {
        self.address
    }
    fn kind(&self) -> &'static str {
        if self.skin {
            "skin"
        } else {
            "mtb"
        }
    }
    fn start_streaming(&mut self) {
        if self.sensors == 0 {
            self.sensors = inertial_bits::INTERNAL_ACC;
        }
    }
    fn on_message(&mut self, msg: &Message, _out: &mut Vec<CanFrame>) {
        let Message::AsRequest { dst, cmd, .. } = msg else {
            return;
        };
        if *dst != self.address {
            return;
        }
        match *cmd {
            AsCommand::AccGyroSetup { sensors, period } => {
                self.sensors = sensors;
                self.inertial_period = Duration::from_millis(u64::from(period.max(1)));
            }
            AsCommand::SkinSetBoardCfg { period, .. } if period > 0 => {
                self.skin_period = Duration::from_millis(u64::from(period))
            }
            _ => {}
        }
    }
    fn next_output(&self) -> Option<Duration> {
        let skin = super::due_in(self.skin, self.skin_period, self.since_skin);
        let inertial = super::due_in(self.sensors != 0, self.inertial_period, self.since_inertial);
        skin.into_iter().chain(inertial).min()
    }

    fn tick(&mut self, dt: Duration, out: &mut Vec<CanFrame>) {
        if self.skin {
            self.since_skin += dt;
            if self.since_skin >= self.skin_period {
                self.since_skin = Duration::ZERO;
                for (t, tri) in self.taxels.iter().enumerate() {
                    let head: [u8; 7] = tri[..7].try_into().expect("12 taxels");
                    let tail: [u8; 5] = tri[7..].try_into().expect("12 taxels");
                    out.push(
                        Message::Skin {
                            board: self.address,
                            msg: SkinFrame::head(t as u8, head),
                        }
                        .encode(),
                    );
                    out.push(
                        Message::Skin {
                            board: self.address,
                            msg: SkinFrame::tail(t as u8, tail),
                        }
                        .encode(),
                    );
                }
            }
        }
        if self.sensors != 0 {
            self.since_inertial += dt;
            if self.since_inertial >= self.inertial_period {
                self.since_inertial = Duration::ZERO;
                if self.sensors & (inertial_bits::INTERNAL_ACC | inertial_bits::EXTERNAL_ACC) != 0 {
                    out.push(
                        Message::Inertial {
                            board: self.address,
                            msg: InertialMsg::Accelerometer(self.accel),
                        }
                        .encode(),
                    );
                }
                if self.sensors & inertial_bits::EXTERNAL_GYRO != 0 {
                    out.push(
                        Message::Inertial {
                            board: self.address,
                            msg: InertialMsg::Gyroscope(self.gyro),
                        }
                        .encode(),
                    );
                }
            }
        }
    }
}
