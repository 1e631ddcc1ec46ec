//! The MTi side of the Xsens MT protocol: what `xsensmt` (robotology's
//! yarp-device-xsensmt, the ergoCub waist IMU) asks of an MTi 1/10/100/600-series
//! sensor, and an emulated MTi.
//!
//! Configuration (in config state): `ReqDID` (0x00, answered by `DeviceID` 0x01 with a
//! big-endian u32), `ReqProductCode` (0x1C → 0x1D, ASCII such as `MTi-300-2A8G4`),
//! `ReqFWRev` (0x12 → 0x13: major, minor, revision), `SetOutputConfiguration` (0xC0:
//! pairs of big-endian u16 data identifier and output frequency in Hz, `0xFFFF` for
//! "every packet"; the acknowledgement 0xC1 carries the configuration applied).
//!
//! Measurement: `MTData2` (0x36) is a sequence of items `XDI (u16) | size (u8) | data`.
//! The low nibble of an XDI selects the number format (bits 0-1: 0 float32, 1 fixed
//! 12.20, 2 fixed 16.32, 3 float64) and the coordinate frame (bits 2-3: 0 ENU, 4 NED,
//! 8 NWU); `xsensmt` asks float32 in ENU. Euler angles are roll, pitch, yaw in degrees,
//! acceleration m/s², rate of turn rad/s, magnetic field in arbitrary units (Earth ≈ 1).

use thiserror::Error;

use super::{Message, Sample, ERR_INVALID_MESSAGE};

/// Message ids of the MTi configuration and data (requests; acknowledgement `id + 1`).
pub mod mid {
    pub const REQ_FW_REV: u8 = 0x12;
    pub const FIRMWARE_REV: u8 = 0x13;
    pub const REQ_PRODUCT_CODE: u8 = 0x1C;
    pub const PRODUCT_CODE: u8 = 0x1D;
    pub const MT_DATA2: u8 = 0x36;
    pub const SET_OUTPUT_CONFIGURATION: u8 = 0xC0;
}

/// Data identifiers (`XsDataIdentifier`), format nibble cleared.
pub mod xdi {
    pub const PACKET_COUNTER: u16 = 0x1020;
    pub const SAMPLE_TIME_FINE: u16 = 0x1060;
    pub const EULER_ANGLES: u16 = 0x2030;
    pub const ACCELERATION: u16 = 0x4020;
    pub const RATE_OF_TURN: u16 = 0x8020;
    pub const MAGNETIC_FIELD: u16 = 0xC020;
    pub const LAT_LON: u16 = 0x5040;
    pub const ALTITUDE_ELLIPSOID: u16 = 0x5020;
    pub const VELOCITY_XYZ: u16 = 0xD010;
    /// The type part of an identifier (the low nibble is the format).
    pub const TYPE_MASK: u16 = 0xFFF0;
    pub const FORMAT_MASK: u16 = 0x0003;
    pub const FLOAT32: u16 = 0x0000;
    pub const FP1220: u16 = 0x0001;
    pub const FP1632: u16 = 0x0002;
    pub const FLOAT64: u16 = 0x0003;
}

/// "Every packet" as an output frequency.
pub const EVERY_PACKET: u16 = 0xFFFF;

/// One entry of `SetOutputConfiguration`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutputConfig {
    pub xdi: u16,
    pub freq: u16,
}

impl OutputConfig {
    pub fn new(xdi: u16, freq: u16) -> OutputConfig {
        OutputConfig { xdi, freq }
    }

    /// The data of a `SetOutputConfiguration`.
    pub fn encode_all(cfg: &[OutputConfig]) -> Vec<u8> {
        cfg.iter()
            .flat_map(|c| [c.xdi.to_be_bytes(), c.freq.to_be_bytes()])
            .flatten()
            .collect()
    }

    /// Reads the data of a `SetOutputConfiguration` (or its acknowledgement).
    pub fn decode_all(data: &[u8]) -> Result<Vec<OutputConfig>, Mtdata2Error> {
        if !data.len().is_multiple_of(4) {
            return Err(Mtdata2Error::Truncated(data.len()));
        }
        Ok(data
            .chunks_exact(4)
            .map(|c| OutputConfig {
                xdi: u16::from_be_bytes([c[0], c[1]]),
                freq: u16::from_be_bytes([c[2], c[3]]),
            })
            .collect())
    }
}

/// What kind of MTi a sensor is (XDA's `XsDeviceId::isImu/isVru/isAhrs/isGnss`), which
/// decides what `xsensmt` asks it for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MtiKind {
    /// Inertial data only: no orientation.
    Imu,
    /// Vertical reference unit: orientation too.
    Vru,
    /// Attitude and heading reference: orientation too.
    Ahrs,
    /// With a GNSS receiver: orientation, position and velocity too.
    Gnss,
}

impl MtiKind {
    /// As XDA: from the product code (`MTi-<family>...`) when it is one, else from the
    /// legacy device id's type bits; `None` for a sensor that is no MTi.
    pub fn of(device_id: u32, product_code: &str) -> Option<MtiKind> {
        if let Some(rest) = product_code.strip_prefix("MTi-") {
            if let Some(g) = rest.strip_prefix("G-") {
                return matches!(leading_number(g), Some(700 | 710)).then_some(MtiKind::Gnss);
            }
            let family = leading_number(rest).filter(|f| *f > 0)?;
            if matches!(family, 7 | 670 | 680 | 870 | 880) {
                return Some(MtiKind::Gnss);
            }
            let digits = rest.as_bytes();
            let mut kind = digits[0].wrapping_sub(b'0');
            if kind == 6 || kind == 8 {
                kind = digits.get(1).map_or(0, |d| d.wrapping_sub(b'0'));
            }
            return match kind {
                1 => Some(MtiKind::Imu),
                2 => Some(MtiKind::Vru),
                3 => Some(MtiKind::Ahrs),
                _ => None,
            };
        }
        // XS_DID_TYPEH: 0x6 10-series, 0x7 100-series, 0x8 1-series, 0xD 3x0.
        let typeh = (device_id >> 20) & 0xF;
        if !matches!(typeh, 0x6 | 0x7 | 0x8 | 0xD) {
            return None;
        }
        // XS_DID_GPL: 1 IMU, 2 VRU, 3 AHRS, 7 (MTi-G-700 / MTi-7) and 8 GNSS.
        match (device_id >> 24) & 0xF {
            1 => Some(MtiKind::Imu),
            2 => Some(MtiKind::Vru),
            3 => Some(MtiKind::Ahrs),
            7 | 8 => Some(MtiKind::Gnss),
            _ => None,
        }
    }

    /// What `xsensmt` configures for this kind, float32 in ENU, at the given rates (Hz):
    /// `[euler, acc, gyro, mag, position, linear velocity]`.
    pub fn output_configuration(self, hz: [u16; 6]) -> Vec<OutputConfig> {
        let [euler, acc, gyro, mag, position, velocity] = hz;
        let imu = [
            OutputConfig::new(xdi::ACCELERATION, acc),
            OutputConfig::new(xdi::RATE_OF_TURN, gyro),
            OutputConfig::new(xdi::MAGNETIC_FIELD, mag),
        ];
        let mut cfg = Vec::new();
        match self {
            MtiKind::Imu => {}
            MtiKind::Vru | MtiKind::Ahrs => cfg.push(OutputConfig::new(xdi::EULER_ANGLES, euler)),
            MtiKind::Gnss => cfg.extend([
                OutputConfig::new(xdi::EULER_ANGLES, euler),
                OutputConfig::new(xdi::LAT_LON, position),
                OutputConfig::new(xdi::ALTITUDE_ELLIPSOID, position),
                OutputConfig::new(xdi::VELOCITY_XYZ, velocity),
            ]),
        }
        cfg.extend(imu);
        cfg
    }
}

fn leading_number(s: &str) -> Option<u32> {
    let end = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    s[..end].parse().ok()
}

/// Why an `MTData2` payload was not read.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum Mtdata2Error {
    #[error("MTData2 item cut short at byte {0}")]
    Truncated(usize),
    #[error("MTData2 item {xdi:#06x} of {size} bytes; its format needs {need}")]
    Size { xdi: u16, size: usize, need: usize },
}

/// The measures one `MTData2` carries (those it does not are `None`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Mtdata2 {
    pub packet_counter: Option<u16>,
    /// roll, pitch, yaw in degrees
    pub euler: Option<[f64; 3]>,
    /// m/s²
    pub acc: Option<[f64; 3]>,
    /// rad/s
    pub gyr: Option<[f64; 3]>,
    /// arbitrary units
    pub mag: Option<[f64; 3]>,
}

/// Three values of an item's format (big-endian).
fn vector3(xdi: u16, data: &[u8]) -> Result<[f64; 3], Mtdata2Error> {
    let width = match xdi & xdi::FORMAT_MASK {
        xdi::FLOAT32 | xdi::FP1220 => 4,
        xdi::FP1632 => 6,
        _ => 8,
    };
    if data.len() != 3 * width {
        return Err(Mtdata2Error::Size {
            xdi,
            size: data.len(),
            need: 3 * width,
        });
    }
    let one = |b: &[u8]| -> f64 {
        match xdi & xdi::FORMAT_MASK {
            xdi::FLOAT32 => f64::from(f32::from_be_bytes([b[0], b[1], b[2], b[3]])),
            xdi::FP1220 => f64::from(i32::from_be_bytes([b[0], b[1], b[2], b[3]])) / 1_048_576.0,
            // 32 fraction bits, then the 16-bit integer part
            xdi::FP1632 => {
                let frac = u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
                let int = i16::from_be_bytes([b[4], b[5]]);
                ((i64::from(int) << 32) | i64::from(frac)) as f64 / 4_294_967_296.0
            }
            _ => f64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    };
    Ok([
        one(&data[..width]),
        one(&data[width..2 * width]),
        one(&data[2 * width..]),
    ])
}

impl Mtdata2 {
    /// Reads an `MTData2` payload; items this driver does not use are skipped.
    pub fn parse(data: &[u8]) -> Result<Mtdata2, Mtdata2Error> {
        let mut out = Mtdata2::default();
        let mut at = 0;
        while at < data.len() {
            if data.len() - at < 3 {
                return Err(Mtdata2Error::Truncated(at));
            }
            let id = u16::from_be_bytes([data[at], data[at + 1]]);
            let size = data[at + 2] as usize;
            let body = data
                .get(at + 3..at + 3 + size)
                .ok_or(Mtdata2Error::Truncated(at))?;
            match id & xdi::TYPE_MASK {
                xdi::PACKET_COUNTER if size == 2 => {
                    out.packet_counter = Some(u16::from_be_bytes([body[0], body[1]]))
                }
                xdi::EULER_ANGLES => out.euler = Some(vector3(id, body)?),
                xdi::ACCELERATION => out.acc = Some(vector3(id, body)?),
                xdi::RATE_OF_TURN => out.gyr = Some(vector3(id, body)?),
                xdi::MAGNETIC_FIELD => out.mag = Some(vector3(id, body)?),
                _ => {}
            }
            at += 3 + size;
        }
        Ok(out)
    }
}

/// One float32 vector item.
fn item(xdi: u16, v: [f32; 3]) -> impl Iterator<Item = u8> {
    xdi.to_be_bytes()
        .into_iter()
        .chain([12])
        .chain(v.into_iter().flat_map(f32::to_be_bytes))
}

/// An emulated MTi-300 AHRS (legacy device id `0x0370xxxx`) as a state machine:
/// [`EmulatedMti::handle`] answers host messages, [`EmulatedMti::sample`] gives the
/// `MTData2` due at a time while measuring, each item at its configured frequency.
#[derive(Debug, Clone)]
pub struct EmulatedMti {
    pub device_id: u32,
    pub product_code: String,
    pub firmware: [u8; 3],
    pub measuring: bool,
    pub config: Vec<OutputConfig>,
    /// When each configured item is next due (s since the start of measurement).
    due: Vec<f64>,
    counter: u16,
}

/// The fastest output an emulated MTi gives (Hz).
pub const MAX_FREQ: u16 = 400;

impl Default for EmulatedMti {
    fn default() -> Self {
        let mut mti = EmulatedMti {
            device_id: 0x0370_1A2B,
            product_code: "MTi-300-2A8G4".into(),
            firmware: [1, 8, 2],
            measuring: true, // an MTi powers up measuring with its stored configuration
            config: Vec::new(),
            due: Vec::new(),
            counter: 0,
        };
        mti.set_config(MtiKind::Ahrs.output_configuration([100; 6]));
        mti
    }
}

impl EmulatedMti {
    fn set_config(&mut self, cfg: Vec<OutputConfig>) {
        self.due = vec![0.0; cfg.len()];
        self.config = cfg;
    }

    /// The replies to one host message.
    pub fn handle(&mut self, m: &Message) -> Vec<Message> {
        use super::mid as base;
        let ack = |data: Vec<u8>| vec![Message::new(m.mid.wrapping_add(1), data)];
        let error = || vec![Message::new(base::ERROR, vec![ERR_INVALID_MESSAGE])];
        match m.mid {
            base::GO_TO_CONFIG => {
                self.measuring = false;
                ack(vec![])
            }
            base::GO_TO_MEASUREMENT => {
                self.measuring = true;
                self.due.iter_mut().for_each(|d| *d = 0.0);
                ack(vec![])
            }
            base::RESET => {
                self.measuring = true;
                ack(vec![])
            }
            base::REQ_DID => ack(self.device_id.to_be_bytes().to_vec()),
            mid::REQ_PRODUCT_CODE => ack(self.product_code.as_bytes().to_vec()),
            mid::REQ_FW_REV => ack(self.firmware.to_vec()),
            mid::SET_OUTPUT_CONFIGURATION if m.data.is_empty() => {
                ack(OutputConfig::encode_all(&self.config))
            }
            mid::SET_OUTPUT_CONFIGURATION if !self.measuring => {
                let Ok(cfg) = OutputConfig::decode_all(&m.data) else {
                    return error();
                };
                // Rates above the sensor's are lowered to it, as a sensor does.
                let applied: Vec<OutputConfig> = cfg
                    .into_iter()
                    .map(|c| OutputConfig {
                        freq: if c.freq == EVERY_PACKET {
                            c.freq
                        } else {
                            c.freq.clamp(1, MAX_FREQ)
                        },
                        ..c
                    })
                    .collect();
                self.set_config(applied);
                ack(OutputConfig::encode_all(&self.config))
            }
            _ => error(),
        }
    }

    /// The tick of the fastest configured item (s), at which [`Self::sample`] is asked.
    pub fn period_s(&self) -> f64 {
        let fastest = self
            .config
            .iter()
            .filter(|c| c.freq != EVERY_PACKET)
            .map(|c| c.freq)
            .max()
            .unwrap_or(100);
        1.0 / f64::from(fastest.max(1))
    }

    /// The `MTData2` with the items due at `t` (s since measuring started) of motion
    /// `s`, or `None` when not measuring or nothing is due.
    pub fn sample(&mut self, t: f64, s: &Sample) -> Option<Message> {
        if !self.measuring {
            return None;
        }
        let mut data = Vec::new();
        let mut any = false;
        for (k, c) in self.config.iter().enumerate() {
            if c.freq == EVERY_PACKET || c.freq == 0 {
                continue;
            }
            if t + 1e-6 < self.due[k] {
                continue;
            }
            let period = 1.0 / f64::from(c.freq);
            self.due[k] = (self.due[k] + period).max(t - period);
            let v = match c.xdi & xdi::TYPE_MASK {
                xdi::EULER_ANGLES => s.euler,
                xdi::ACCELERATION => s.acc,
                xdi::RATE_OF_TURN => s.gyr,
                xdi::MAGNETIC_FIELD => s.mag,
                _ => continue,
            };
            data.extend(item(c.xdi & xdi::TYPE_MASK, v));
            any = true;
        }
        if !any {
            return None;
        }
        let counted = self
            .config
            .iter()
            .any(|c| c.xdi & xdi::TYPE_MASK == xdi::PACKET_COUNTER);
        if counted {
            let mut head = xdi::PACKET_COUNTER.to_be_bytes().to_vec();
            head.push(2);
            head.extend(self.counter.to_be_bytes());
            data.splice(0..0, head);
        }
        self.counter = self.counter.wrapping_add(1);
        Some(Message::new(mid::MT_DATA2, data))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{emulated_motion, mid as base, Decoder};
    use super::*;

    #[test]
    fn mtdata2_items_have_the_documented_layout() {
        // MT Low-Level Communication Protocol: FA FF 36 LEN, then per item XDI (2 bytes,
        // big-endian), size (1 byte), data; float32 Euler angles are 12 bytes.
        let euler = [1.5f32, -2.0, 90.0];
        let mut data = vec![0x20, 0x30, 0x0C];
        data.extend(euler.iter().flat_map(|x| x.to_be_bytes()));
        data.extend([0x10, 0x20, 0x02, 0x01, 0x02]); // PacketCounter 0x0102
        let m = Message::new(mid::MT_DATA2, data.clone());
        let wire = m.encode();
        assert_eq!(&wire[..4], &[0xFA, 0xFF, 0x36, 20]);
        let sum = wire[1..].iter().fold(0u8, |s, b| s.wrapping_add(*b));
        assert_eq!(sum, 0, "checksum makes BID..CS sum to 0");
        let d = Mtdata2::parse(&data).unwrap();
        assert_eq!(d.euler, Some([1.5, -2.0, 90.0]));
        assert_eq!(d.packet_counter, Some(0x0102));
        assert_eq!(d.acc, None);
    }

    #[test]
    fn every_number_format_reads() {
        // fixed 12.20: 1.5 = 0x00180000; fixed 16.32: -2.25 = int -3, fraction 0.75
        let mut fp1220 = vec![0x40, 0x21, 12];
        for _ in 0..3 {
            fp1220.extend(0x0018_0000i32.to_be_bytes());
        }
        assert_eq!(Mtdata2::parse(&fp1220).unwrap().acc, Some([1.5; 3]));
        let mut fp1632 = vec![0x80, 0x22, 18];
        for _ in 0..3 {
            fp1632.extend(0xC000_0000u32.to_be_bytes());
            fp1632.extend((-3i16).to_be_bytes());
        }
        assert_eq!(Mtdata2::parse(&fp1632).unwrap().gyr, Some([-2.25; 3]));
        let mut f64s = vec![0xC0, 0x23, 24];
        for x in [0.25f64, 0.5, -1.0] {
            f64s.extend(x.to_be_bytes());
        }
        assert_eq!(Mtdata2::parse(&f64s).unwrap().mag, Some([0.25, 0.5, -1.0]));
    }

    #[test]
    fn broken_payloads_are_errors() {
        assert_eq!(
            Mtdata2::parse(&[0x20, 0x30]),
            Err(Mtdata2Error::Truncated(0))
        );
        assert_eq!(
            Mtdata2::parse(&[0x20, 0x30, 0x0C, 0, 0]),
            Err(Mtdata2Error::Truncated(0))
        );
        assert_eq!(
            Mtdata2::parse(&[0x20, 0x30, 0x02, 0, 0]),
            Err(Mtdata2Error::Size {
                xdi: 0x2030,
                size: 2,
                need: 12
            })
        );
        // unknown items are skipped
        let d = Mtdata2::parse(&[0x70, 0x10, 0x01, 0xAA]).unwrap();
        assert_eq!(d, Mtdata2::default());
    }

    #[test]
    fn kinds_follow_xda() {
        assert_eq!(MtiKind::of(0, "MTi-300-2A8G4"), Some(MtiKind::Ahrs));
        assert_eq!(MtiKind::of(0, "MTi-630-8A1G6"), Some(MtiKind::Ahrs));
        assert_eq!(MtiKind::of(0, "MTi-610"), Some(MtiKind::Imu));
        assert_eq!(MtiKind::of(0, "MTi-20"), Some(MtiKind::Vru));
        assert_eq!(MtiKind::of(0, "MTi-680G"), Some(MtiKind::Gnss));
        assert_eq!(MtiKind::of(0, "MTi-G-710-2A8G4"), Some(MtiKind::Gnss));
        assert_eq!(MtiKind::of(0, "MTi-7"), Some(MtiKind::Gnss));
        // legacy ids: XS_DID_TYPEH_MT_X00 | XS_DID_GPL_300, an MTx (type 0x5) is no MTi
        assert_eq!(MtiKind::of(0x0370_1A2B, ""), Some(MtiKind::Ahrs));
        assert_eq!(MtiKind::of(0x0160_0001, ""), Some(MtiKind::Imu));
        assert_eq!(MtiKind::of(0x0050_0322, ""), None);
        assert_eq!(MtiKind::of(0, "MTx"), None);
    }

    #[test]
    fn output_configuration_as_xsensmt_asks() {
        let ahrs = MtiKind::Ahrs.output_configuration([200, 200, 200, 100, 100, 100]);
        assert_eq!(
            OutputConfig::encode_all(&ahrs),
            [
                0x20, 0x30, 0x00, 0xC8, 0x40, 0x20, 0x00, 0xC8, 0x80, 0x20, 0x00, 0xC8, 0xC0, 0x20,
                0x00, 0x64
            ]
        );
        assert_eq!(MtiKind::Imu.output_configuration([1; 6]).len(), 3);
        assert_eq!(MtiKind::Gnss.output_configuration([1; 6]).len(), 7);
        assert!(OutputConfig::decode_all(&[0, 1, 2]).is_err());
    }

    #[test]
    fn emulator_configures_and_streams_each_item_at_its_rate() {
        let mut e = EmulatedMti::default();
        let r = e.handle(&Message::new(base::GO_TO_CONFIG, vec![]));
        assert_eq!(r, [Message::new(0x31, vec![])]);
        assert_eq!(
            e.handle(&Message::new(base::REQ_DID, vec![]))[0].data,
            [0x03, 0x70, 0x1A, 0x2B]
        );
        let code = e.handle(&Message::new(mid::REQ_PRODUCT_CODE, vec![]));
        assert_eq!(code[0].mid, mid::PRODUCT_CODE);
        assert_eq!(code[0].data, b"MTi-300-2A8G4");
        assert_eq!(
            e.handle(&Message::new(mid::REQ_FW_REV, vec![]))[0].mid,
            mid::FIRMWARE_REV
        );
        let cfg = MtiKind::Ahrs.output_configuration([200, 200, 200, 100, 100, 100]);
        let r = e.handle(&Message::new(
            mid::SET_OUTPUT_CONFIGURATION,
            OutputConfig::encode_all(&cfg),
        ));
        assert_eq!(r[0].mid, 0xC1);
        assert_eq!(OutputConfig::decode_all(&r[0].data).unwrap(), cfg);
        assert!(e.sample(0.0, &Sample::default()).is_none(), "config state");
        e.handle(&Message::new(base::GO_TO_MEASUREMENT, vec![]));
        assert!((e.period_s() - 0.005).abs() < 1e-9);
        let mut mags = 0;
        for k in 0..200 {
            let t = k as f64 * 0.005;
            let m = e
                .sample(t, &emulated_motion(t))
                .expect("a packet every tick");
            let d = Mtdata2::parse(&m.data).unwrap();
            assert!(d.euler.is_some() && d.acc.is_some() && d.gyr.is_some());
            mags += usize::from(d.mag.is_some());
        }
        assert_eq!(mags, 100, "the magnetometer at half the rate");
        // whole messages survive the shared decoder
        let m = e.sample(1.0, &emulated_motion(1.0)).unwrap();
        let mut dec = Decoder::new();
        dec.push(&m.encode());
        assert_eq!(dec.next_message(), Some(Ok(m)));
        // no configuration while measuring
        let r = e.handle(&Message::new(
            mid::SET_OUTPUT_CONFIGURATION,
            vec![0x20, 0x30, 0, 1],
        ));
        assert_eq!(r[0].mid, base::ERROR);
    }
}
