//! Analog-sensor messages: class 2 polling (strain/MAIS configuration, skin and MTB
//! setup) and class 3 broadcasts (force/torque vectors, hall-effect sensors), as
//! `iCubCanProto_analogSensorMessages.h` and `CanBusAnalogSensor` define them.

use super::{need, u16_at, MsgClass, ProtoError};

/// Polling opcodes (`ICUBCANPROTO_POL_AS_CMD__*`, `ICUBCANPROTO_POL_SK_CMD__*`).
pub mod op {
    pub const SET_MATRIX_RC: u8 = 0x03;
    pub const SET_TXMODE: u8 = 0x07;
    pub const SET_CANDATARATE: u8 = 0x08;
    pub const SAVE2EE: u8 = 0x09;
    pub const GET_MATRIX_RC: u8 = 0x0A;
    pub const SET_CALIB_TARE: u8 = 0x13;
    pub const SET_FULL_SCALES: u8 = 0x17;
    pub const GET_FULL_SCALES: u8 = 0x18;
    pub const TACT_SETUP: u8 = 0x4C;
    pub const SET_BRD_CFG: u8 = 0x4D;
    pub const TACT_SETUP2: u8 = 0x4E;
    pub const ACC_GYRO_SETUP: u8 = 0x4F;
    pub const SET_TRIANG_CFG: u8 = 0x50;
}

/// `SET_TXMODE` values used by `CanBusAnalogSensor`.
pub mod txmode {
    /// Stream calibrated data.
    pub const CALIBRATED: u8 = 0;
    /// Stop streaming.
    pub const STOP: u8 = 1;
    /// Stream raw (uncalibrated) data.
    pub const RAW: u8 = 3;
    /// Debug mode: uncalibrated vectors on types 8 and 9.
    pub const DEBUG: u8 = 4;
}

/// `SET_CALIB_TARE` operations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TareOp {
    /// Reset the tare to zero.
    Reset,
    /// Use the current reading as tare.
    UseCurrent,
    /// Set the tare of one channel.
    Set { channel: u8, value: u16 },
}

/// Host -> sensor board commands (class 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AsCommand {
    /// Calibration matrix entry (Q1.15 fixed point), sent big-endian.
    SetMatrixRc {
        row: u8,
        col: u8,
        value: i16,
    },
    /// Transmission mode, see [`txmode`].
    SetTxMode(u8),
    /// Broadcast period in ms.
    SetCanDataRate(u8),
    SaveToEeprom,
    GetMatrixRc {
        row: u8,
        col: u8,
    },
    SetCalibTare(TareOp),
    /// Full scale of one channel (N or N·m), sent big-endian.
    SetFullScale {
        channel: u8,
        value: u16,
    },
    GetFullScale {
        channel: u8,
    },
    /// Legacy skin setup (0x4C), seven raw bytes.
    SkinTactSetup([u8; 7]),
    /// Skin board configuration (0x4D): skin type, period in ms, no-load value.
    SkinSetBoardCfg {
        skin_type: u8,
        period: u8,
        no_load: u8,
    },
    /// Legacy skin setup (0x4E), seven raw bytes.
    SkinTactSetup2([u8; 7]),
    /// MTB inertial setup (0x4F): enabled sensor bits, period in ms.
    AccGyroSetup {
        sensors: u8,
        period: u8,
    },
    /// Skin triangle configuration (0x50).
    SkinSetTriangleCfg {
        start: u8,
        end: u8,
        shift: u8,
        flags: u8,
        cdc_offset: u16,
    },
}

impl AsCommand {
    pub fn opcode(&self) -> u8 {
        use AsCommand::*;
        match self {
            SetMatrixRc { .. } => op::SET_MATRIX_RC,
            SetTxMode(_) => op::SET_TXMODE,
            SetCanDataRate(_) => op::SET_CANDATARATE,
            SaveToEeprom => op::SAVE2EE,
            GetMatrixRc { .. } => op::GET_MATRIX_RC,
            SetCalibTare(_) => op::SET_CALIB_TARE,
            SetFullScale { .. } => op::SET_FULL_SCALES,
            GetFullScale { .. } => op::GET_FULL_SCALES,
            SkinTactSetup(_) => op::TACT_SETUP,
            SkinSetBoardCfg { .. } => op::SET_BRD_CFG,
            SkinTactSetup2(_) => op::TACT_SETUP2,
            AccGyroSetup { .. } => op::ACC_GYRO_SETUP,
            SkinSetTriangleCfg { .. } => op::SET_TRIANG_CFG,
        }
    }

    pub fn encode(&self, b: &mut [u8; 8]) -> usize {
        use AsCommand::*;
        b[0] = self.opcode();
        match *self {
            SetMatrixRc { row, col, value } => {
                b[1] = row;
                b[2] = col;
                b[3..5].copy_from_slice(&value.to_be_bytes());
                5
            }
            SetTxMode(v) | SetCanDataRate(v) => {
                b[1] = v;
                2
            }
            SaveToEeprom => 1,
            GetMatrixRc { row, col } => {
                b[1] = row;
                b[2] = col;
                3
            }
            SetCalibTare(TareOp::Reset) => {
                b[1] = 0;
                2
            }
            SetCalibTare(TareOp::UseCurrent) => {
                b[1] = 1;
                2
            }
            SetCalibTare(TareOp::Set { channel, value }) => {
                b[1] = 2;
                b[2] = channel;
                b[3..5].copy_from_slice(&value.to_be_bytes());
                5
            }
            SetFullScale { channel, value } => {
                b[1] = channel;
                b[2..4].copy_from_slice(&value.to_be_bytes());
                4
            }
            GetFullScale { channel } => {
                b[1] = channel;
                2
            }
            SkinTactSetup(raw) | SkinTactSetup2(raw) => {
                b[1..8].copy_from_slice(&raw);
                8
            }
            SkinSetBoardCfg {
                skin_type,
                period,
                no_load,
            } => {
                b[1] = skin_type;
                b[2] = period;
                b[3] = no_load;
                4
            }
            AccGyroSetup { sensors, period } => {
                b[1] = sensors;
                b[2] = period;
                3
            }
            SkinSetTriangleCfg {
                start,
                end,
                shift,
                flags,
                cdc_offset,
            } => {
                b[1] = start;
                b[2] = end;
                b[3] = shift;
                b[4] = flags;
                b[5..7].copy_from_slice(&cdc_offset.to_le_bytes());
                7
            }
        }
    }

    pub fn decode(opcode: u8, d: &[u8]) -> Result<Self, ProtoError> {
        use AsCommand::*;
        let n = |min: usize, what: &'static str, exp: &'static str| need(what, d, min, 8, exp);
        let raw7 = |d: &[u8]| -> [u8; 7] { d[1..8].try_into().expect("length checked") };
        Ok(match opcode {
            op::SET_MATRIX_RC => {
                n(5, "set matrix entry", "at least 5")?;
                SetMatrixRc {
                    row: d[1],
                    col: d[2],
                    value: i16::from_be_bytes([d[3], d[4]]),
                }
            }
            op::SET_TXMODE => {
                n(2, "set tx mode", "at least 2")?;
                SetTxMode(d[1])
            }
            op::SET_CANDATARATE => {
                n(2, "set data rate", "at least 2")?;
                SetCanDataRate(d[1])
            }
            op::SAVE2EE => SaveToEeprom,
            op::GET_MATRIX_RC => {
                n(3, "get matrix entry", "at least 3")?;
                GetMatrixRc {
                    row: d[1],
                    col: d[2],
                }
            }
            op::SET_CALIB_TARE => {
                n(2, "set tare", "at least 2")?;
                SetCalibTare(match d[1] {
                    0 => TareOp::Reset,
                    1 => TareOp::UseCurrent,
                    2 => {
                        n(5, "set channel tare", "at least 5")?;
                        TareOp::Set {
                            channel: d[2],
                            value: u16::from_be_bytes([d[3], d[4]]),
                        }
                    }
                    v => {
                        return Err(ProtoError::Value {
                            what: "tare operation",
                            value: v.into(),
                        })
                    }
                })
            }
            op::SET_FULL_SCALES => {
                n(4, "set full scale", "at least 4")?;
                SetFullScale {
                    channel: d[1],
                    value: u16::from_be_bytes([d[2], d[3]]),
                }
            }
            op::GET_FULL_SCALES => {
                n(2, "get full scale", "at least 2")?;
                GetFullScale { channel: d[1] }
            }
            op::TACT_SETUP => {
                n(8, "skin setup", "8")?;
                SkinTactSetup(raw7(d))
            }
            op::TACT_SETUP2 => {
                n(8, "skin setup 2", "8")?;
                SkinTactSetup2(raw7(d))
            }
            op::SET_BRD_CFG => {
                n(4, "skin board config", "at least 4")?;
                SkinSetBoardCfg {
                    skin_type: d[1],
                    period: d[2],
                    no_load: d[3],
                }
            }
            op::ACC_GYRO_SETUP => {
                n(3, "inertial setup", "at least 3")?;
                AccGyroSetup {
                    sensors: d[1],
                    period: d[2],
                }
            }
            op::SET_TRIANG_CFG => {
                n(7, "skin triangle config", "at least 7")?;
                SkinSetTriangleCfg {
                    start: d[1],
                    end: d[2],
                    shift: d[3],
                    flags: d[4],
                    cdc_offset: u16_at(d, 5),
                }
            }
            code => {
                return Err(ProtoError::Unknown {
                    class: MsgClass::PollingAnalogSensor,
                    code,
                })
            }
        })
    }
}

/// Sensor board -> host replies (class 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AsReply {
    FullScale { channel: u8, value: u16 },
    MatrixRc { row: u8, col: u8, value: i16 },
}

impl AsReply {
    pub fn encode(&self, b: &mut [u8; 8]) -> usize {
        match *self {
            Self::FullScale { channel, value } => {
                b[0] = op::GET_FULL_SCALES;
                b[1] = channel;
                b[2..4].copy_from_slice(&value.to_be_bytes());
                4
            }
            Self::MatrixRc { row, col, value } => {
                b[0] = op::GET_MATRIX_RC;
                b[1] = row;
                b[2] = col;
                b[3..5].copy_from_slice(&value.to_be_bytes());
                5
            }
        }
    }

    pub fn decode(opcode: u8, d: &[u8]) -> Result<Self, ProtoError> {
        match opcode {
            op::GET_FULL_SCALES => {
                need("full scale reply", d, 4, 8, "at least 4")?;
                Ok(Self::FullScale {
                    channel: d[1],
                    value: u16::from_be_bytes([d[2], d[3]]),
                })
            }
            op::GET_MATRIX_RC => {
                need("matrix entry reply", d, 5, 8, "at least 5")?;
                Ok(Self::MatrixRc {
                    row: d[1],
                    col: d[2],
                    value: i16::from_be_bytes([d[3], d[4]]),
                })
            }
            code => Err(ProtoError::Unknown {
                class: MsgClass::PollingAnalogSensor,
                code,
            }),
        }
    }
}

/// Which half of a 6-axis reading a vector message carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VectorKind {
    /// Type 0xA: forces, channels 0..3.
    Force,
    /// Type 0xB: torques, channels 3..6.
    Torque,
    /// Type 0x8: uncalibrated forces (debug mode).
    UncalibForce,
    /// Type 0x9: uncalibrated torques (debug mode).
    UncalibTorque,
}

impl VectorKind {
    fn code(self) -> u8 {
        match self {
            Self::UncalibForce => 0x8,
            Self::UncalibTorque => 0x9,
            Self::Force => 0xA,
            Self::Torque => 0xB,
        }
    }
    /// Index of the first of the three channels carried.
    pub fn first_channel(self) -> usize {
        match self {
            Self::Force | Self::UncalibForce => 0,
            Self::Torque | Self::UncalibTorque => 3,
        }
    }
}

/// Sensor broadcasts (class 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AsPeriodic {
    /// Three 16-bit values, little-endian, offset by 0x8000 (value − 0x8000 is the signed
    /// reading; calibrated readings scale by full scale / 0x8000). A seventh byte, when
    /// present, flags saturation (1 = overflow).
    Vector {
        kind: VectorKind,
        raw: [u16; 3],
        saturation: Option<u8>,
    },
    /// Hall-effect sensors 0..7 of a MAIS board (8-bit).
    Hes0To6([u8; 7]),
    /// Hall-effect sensors 7..15 of a MAIS board (8-bit).
    Hes7To14([u8; 8]),
}

impl AsPeriodic {
    /// Builds a vector message from signed readings (the 0x8000 offset is applied here).
    pub fn vector(kind: VectorKind, values: [i16; 3]) -> Self {
        let raw = values.map(|v| (i32::from(v) + 0x8000) as u16);
        Self::Vector {
            kind,
            raw,
            saturation: None,
        }
    }

    /// The signed readings of a vector message.
    pub fn signed(raw: [u16; 3]) -> [i32; 3] {
        raw.map(|r| i32::from(r) - 0x8000)
    }

    pub fn encode(&self, b: &mut [u8; 8]) -> (u8, usize) {
        match *self {
            Self::Vector {
                kind,
                raw,
                saturation,
            } => {
                for (i, r) in raw.iter().enumerate() {
                    b[2 * i..2 * i + 2].copy_from_slice(&r.to_le_bytes());
                }
                match saturation {
                    Some(s) => {
                        b[6] = s;
                        (kind.code(), 7)
                    }
                    None => (kind.code(), 6),
                }
            }
            Self::Hes0To6(v) => {
                b[..7].copy_from_slice(&v);
                (0xC, 7)
            }
            Self::Hes7To14(v) => {
                b.copy_from_slice(&v);
                (0xD, 8)
            }
        }
    }

    pub fn decode(kind: u8, d: &[u8]) -> Result<Self, ProtoError> {
        let vk = match kind {
            0x8 => Some(VectorKind::UncalibForce),
            0x9 => Some(VectorKind::UncalibTorque),
            0xA => Some(VectorKind::Force),
            0xB => Some(VectorKind::Torque),
            _ => None,
        };
        if let Some(kind) = vk {
            need("force/torque vector", d, 6, 7, "6 or 7")?;
            let raw = [u16_at(d, 0), u16_at(d, 2), u16_at(d, 4)];
            return Ok(Self::Vector {
                kind,
                raw,
                saturation: d.get(6).copied(),
            });
        }
        match kind {
            0xC => {
                need("hall sensors 0..6", d, 7, 8, "at least 7")?;
                Ok(Self::Hes0To6(d[..7].try_into().expect("length checked")))
            }
            0xD => {
                need("hall sensors 7..14", d, 8, 8, "8")?;
                Ok(Self::Hes7To14(d[..8].try_into().expect("length checked")))
            }
            code => Err(ProtoError::Unknown {
                class: MsgClass::PeriodicAnalogSensor,
                code,
            }),
        }
    }
}
