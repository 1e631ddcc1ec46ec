//! The Xsens MT binary protocol of the MTx IMU in the iCub head (icub-main's `xsensmtx`
//! talks it over a serial port), as a pure codec, plus an emulated MTx.
//!
//! A message is `FA BID MID LEN DATA.. CS`: preamble `0xFA`, bus id (`0xFF` master or
//! broadcast), message id, length (`0xFF` announces a big-endian u16 extended length),
//! the data, and a checksum that makes the byte sum from BID to CS zero (mod 256). An
//! acknowledgement has the request's id plus one.
//!
//! `xsensmtx` configures output mode calibrated + orientation (`0x0006`) with Euler
//! angles in float (settings `0x00000004`); each `MTData` then carries 12 big-endian
//! `f32`: acceleration (m/s²), rate of turn (rad/s), magnetic field (a.u.), then roll,
//! pitch, yaw (degrees).
//!
//! [`mti`] adds what the MTi sensors speak (`xsensmt`): device kind, output
//! configuration and `MTData2`.

use thiserror::Error;

pub mod mti;

pub const PREAMBLE: u8 = 0xFA;
/// Bus id of the master (the only device on a direct serial link answers it too).
pub const BID_MASTER: u8 = 0xFF;
/// Largest data length the protocol allows (extended length).
pub const MAX_DATA_LEN: usize = 2048;

/// Message ids (requests; the acknowledgement is `id + 1`).
pub mod mid {
    pub const REQ_DID: u8 = 0x00;
    pub const DEVICE_ID: u8 = 0x01;
    pub const INIT_BUS: u8 = 0x02;
    pub const SET_PERIOD: u8 = 0x04;
    pub const REQ_DATA_LENGTH: u8 = 0x0A;
    pub const GO_TO_MEASUREMENT: u8 = 0x10;
    pub const GO_TO_CONFIG: u8 = 0x30;
    pub const MT_DATA: u8 = 0x32;
    pub const RESET: u8 = 0x40;
    pub const ERROR: u8 = 0x42;
    pub const SET_OUTPUT_MODE: u8 = 0xD0;
    pub const SET_OUTPUT_SETTINGS: u8 = 0xD2;
}

/// Output mode bits (`SetOutputMode`, 2 bytes).
pub const OUTPUT_MODE_CALIB: u16 = 0x0002;
pub const OUTPUT_MODE_ORIENT: u16 = 0x0004;
/// Output settings: Euler angles, float, no sample counter (what `xsensmtx` sets).
pub const OUTPUT_SETTINGS_EULER: u32 = 0x0000_0004;
/// Error code of an invalid message (`Error` data byte).
pub const ERR_INVALID_MESSAGE: u8 = 0x04;

/// One protocol message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Message {
    pub bid: u8,
    pub mid: u8,
    pub data: Vec<u8>,
}

impl Message {
    /// A message to (or from) the master bus id.
    pub fn new(mid: u8, data: Vec<u8>) -> Message {
        Message {
            bid: BID_MASTER,
            mid,
            data,
        }
    }

    /// The bytes on the wire (extended length above 254 data bytes).
    pub fn encode(&self) -> Vec<u8> {
        let n = self.data.len().min(MAX_DATA_LEN);
        let mut out = Vec::with_capacity(n + 7);
        out.extend([PREAMBLE, self.bid, self.mid]);
        if n < 0xFF {
            out.push(n as u8);
        } else {
            out.push(0xFF);
            out.extend((n as u16).to_be_bytes());
        }
        out.extend(&self.data[..n]);
        let sum = out[1..].iter().fold(0u8, |s, b| s.wrapping_add(*b));
        out.push(sum.wrapping_neg());
        out
    }
}

/// Why bytes were skipped while looking for messages.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum FrameError {
    #[error("checksum mismatch in a message with id {mid:#04x}")]
    Checksum { mid: u8 },
    #[error("extended length {0} above the protocol's {MAX_DATA_LEN}")]
    TooLong(usize),
}

/// Splits a byte stream into messages: bytes before a preamble are skipped, a message
/// with a bad checksum or length is reported and the search resumes after its preamble.
/// Memory stays bounded by one maximal message.
#[derive(Debug, Default)]
pub struct Decoder {
    buf: Vec<u8>,
    /// Bytes dropped so far (noise, broken messages).
    pub skipped: u64,
}

impl Decoder {
    pub fn new() -> Decoder {
        Decoder::default()
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// The next complete message, an error for a broken one, or `None` until more bytes
    /// arrive.
    pub fn next_message(&mut self) -> Option<Result<Message, FrameError>> {
        // Resynchronise on the next preamble.
        let Some(i) = self.buf.iter().position(|b| *b == PREAMBLE) else {
            let n = self.buf.len();
            self.drop_front(n);
            return None;
        };
        self.drop_front(i);
        if self.buf.len() < 4 {
            return None;
        }
        let (len, head) = match self.buf[3] {
            0xFF if self.buf.len() < 6 => return None,
            0xFF => (u16::from_be_bytes([self.buf[4], self.buf[5]]) as usize, 6),
            n => (n as usize, 4),
        };
        if len > MAX_DATA_LEN {
            self.drop_front(1);
            return Some(Err(FrameError::TooLong(len)));
        }
        let total = head + len + 1;
        if self.buf.len() < total {
            return None;
        }
        let sum = self.buf[1..total]
            .iter()
            .fold(0u8, |s, b| s.wrapping_add(*b));
        let mid = self.buf[2];
        if sum != 0 {
            self.drop_front(1);
            return Some(Err(FrameError::Checksum { mid }));
        }
        let m = Message {
            bid: self.buf[1],
            mid,
            data: self.buf[head..head + len].to_vec(),
        };
        self.buf.drain(..total);
        Some(Ok(m))
    }

    fn drop_front(&mut self, n: usize) {
        self.skipped += n as u64;
        self.buf.drain(..n);
    }
}

/// One calibrated sample with Euler orientation, in the sensor's units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// m/s²
    pub acc: [f32; 3],
    /// rad/s
    pub gyr: [f32; 3],
    /// arbitrary units (Earth's field ≈ 1)
    pub mag: [f32; 3],
    /// roll, pitch, yaw in degrees
    pub euler: [f32; 3],
}

/// Why an `MTData` payload is not a sample of the configured mode.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("MTData of {0} bytes; calibrated data with Euler angles needs 48")]
pub struct SampleError(pub usize);

impl Sample {
    pub const LEN: usize = 48;

    /// Reads the 48-byte payload of output mode `0x0006`, settings `0x4`.
    pub fn parse(data: &[u8]) -> Result<Sample, SampleError> {
        if data.len() != Sample::LEN {
            return Err(SampleError(data.len()));
        }
        let f = |k: usize| {
            let b = &data[4 * k..4 * k + 4];
            f32::from_be_bytes([b[0], b[1], b[2], b[3]])
        };
        let v = |k: usize| [f(k), f(k + 1), f(k + 2)];
        Ok(Sample {
            acc: v(0),
            gyr: v(3),
            mag: v(6),
            euler: v(9),
        })
    }

    /// The payload bytes (for the emulator).
    pub fn encode(&self) -> Vec<u8> {
        [self.acc, self.gyr, self.mag, self.euler]
            .iter()
            .flatten()
            .flat_map(|x| x.to_be_bytes())
            .collect()
    }
}

/// An emulated MTx as a state machine: [`EmulatedMtx::handle`] answers host messages,
/// [`EmulatedMtx::sample`] gives the `MTData` to stream while measuring.
#[derive(Debug, Clone)]
pub struct EmulatedMtx {
    pub device_id: u32,
    pub measuring: bool,
    pub output_mode: u16,
    pub output_settings: u32,
    /// Sample period in units of 1/115200 s (`SetPeriod`); 0x0480 is 100 Hz.
    pub period: u16,
}

impl Default for EmulatedMtx {
    fn default() -> Self {
        EmulatedMtx {
            device_id: 0x0050_0322,
            measuring: true, // an MTx powers up measuring with its stored settings
            output_mode: OUTPUT_MODE_CALIB | OUTPUT_MODE_ORIENT,
            output_settings: OUTPUT_SETTINGS_EULER,
            period: 0x0480,
        }
    }
}

impl EmulatedMtx {
    /// The sample period in seconds.
    pub fn period_s(&self) -> f64 {
        f64::from(self.period.max(1)) / 115_200.0
    }

    /// The replies to one host message.
    pub fn handle(&mut self, m: &Message) -> Vec<Message> {
        let ack = |data: Vec<u8>| vec![Message::new(m.mid.wrapping_add(1), data)];
        let is_request = m.data.is_empty();
        match m.mid {
            mid::GO_TO_CONFIG => {
                self.measuring = false;
                ack(vec![])
            }
            mid::GO_TO_MEASUREMENT => {
                self.measuring = true;
                ack(vec![])
            }
            mid::REQ_DID => ack(self.device_id.to_be_bytes().to_vec()),
            mid::INIT_BUS => ack(self.device_id.to_be_bytes().to_vec()),
            mid::RESET => {
                self.measuring = true;
                ack(vec![])
            }
            mid::REQ_DATA_LENGTH => ack((self.data_length() as u16).to_be_bytes().to_vec()),
            mid::SET_OUTPUT_MODE if is_request => ack(self.output_mode.to_be_bytes().to_vec()),
            mid::SET_OUTPUT_MODE if m.data.len() == 2 => {
                self.output_mode = u16::from_be_bytes([m.data[0], m.data[1]]);
                ack(vec![])
            }
            mid::SET_OUTPUT_SETTINGS if is_request => {
                ack(self.output_settings.to_be_bytes().to_vec())
            }
            mid::SET_OUTPUT_SETTINGS if m.data.len() == 4 => {
                let d = &m.data;
                self.output_settings = u32::from_be_bytes([d[0], d[1], d[2], d[3]]);
                ack(vec![])
            }
            mid::SET_PERIOD if is_request => ack(self.period.to_be_bytes().to_vec()),
            mid::SET_PERIOD if m.data.len() == 2 => {
                self.period = u16::from_be_bytes([m.data[0], m.data[1]]);
                ack(vec![])
            }
            _ => vec![Message::new(mid::ERROR, vec![ERR_INVALID_MESSAGE])],
        }
    }

    /// Bytes of one `MTData` in the current mode (only mode `0x0006`/Euler is produced).
    pub fn data_length(&self) -> usize {
        Sample::LEN
    }

    /// The `MTData` message of `s` (when measuring).
    pub fn sample(&self, s: &Sample) -> Option<Message> {
        self.measuring
            .then(|| Message::new(mid::MT_DATA, s.encode()))
    }
}

/// A smooth, plausible head motion for the emulator at time `t` (s): a slow nod and
/// turn, gravity rotated accordingly, rates as the angles' derivatives.
pub fn emulated_motion(t: f64) -> Sample {
    let (roll, pitch, yaw) = (
        5.0 * (0.5 * t).sin(),
        10.0 * (0.3 * t).sin(),
        20.0 * (0.2 * t).sin(),
    );
    let rad = std::f64::consts::PI / 180.0;
    let (r, p) = (roll * rad, pitch * rad);
    let g = 9.81;
    let acc = [g * p.sin(), -g * r.sin() * p.cos(), -g * r.cos() * p.cos()];
    let gyr = [
        5.0 * 0.5 * (0.5 * t).cos() * rad,
        10.0 * 0.3 * (0.3 * t).cos() * rad,
        20.0 * 0.2 * (0.2 * t).cos() * rad,
    ];
    let y = yaw * rad;
    let mag = [y.cos(), -y.sin(), 0.4];
    let f = |v: [f64; 3]| v.map(|x| x as f32);
    Sample {
        acc: f(acc),
        gyr: f(gyr),
        mag: f(mag),
        euler: f([roll, pitch, yaw]),
    }
}

/// Fuzz entry point: every byte string decodes to messages, errors, or nothing, and
/// every message's data either is a sample or says why not.
pub fn decode_any(bytes: &[u8]) -> usize {
    let mut d = Decoder::new();
    d.push(bytes);
    let mut n = 0;
    while let Some(r) = d.next_message() {
        if let Ok(m) = r {
            let _ = Sample::parse(&m.data);
            let _ = mti::Mtdata2::parse(&m.data);
            let _ = mti::OutputConfig::decode_all(&m.data);
        }
        n += 1;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_have_the_documented_bytes() {
        // Checksums by the rule (sum of BID..CS == 0 mod 256).
        assert_eq!(
            Message::new(mid::GO_TO_CONFIG, vec![]).encode(),
            [0xFA, 0xFF, 0x30, 0x00, 0xD1]
        );
        assert_eq!(
            Message::new(mid::GO_TO_MEASUREMENT, vec![]).encode(),
            [0xFA, 0xFF, 0x10, 0x00, 0xF1]
        );
        assert_eq!(
            Message::new(mid::SET_OUTPUT_MODE, vec![0x00, 0x06]).encode(),
            [0xFA, 0xFF, 0xD0, 0x02, 0x00, 0x06, 0x29]
        );
        assert_eq!(
            Message::new(mid::SET_OUTPUT_SETTINGS, vec![0, 0, 0, 4]).encode(),
            [0xFA, 0xFF, 0xD2, 0x04, 0x00, 0x00, 0x00, 0x04, 0x27]
        );
    }

    #[test]
    fn decoder_resyncs_after_noise_and_bad_checksums() {
        let good = Message::new(mid::MT_DATA, emulated_motion(1.0).encode());
        let mut bad = good.encode();
        *bad.last_mut().unwrap() ^= 0x55;
        let mut d = Decoder::new();
        d.push(&[0x00, 0x13, 0xFA]); // noise, then a lone preamble
        d.push(&bad);
        d.push(&good.encode());
        let mut got = Vec::new();
        while let Some(r) = d.next_message() {
            got.push(r);
        }
        assert!(got.iter().any(|r| r.is_err()));
        assert_eq!(got.last(), Some(&Ok(good.clone())));
        assert!(d.skipped >= 3);
        // split at every byte
        let bytes = good.encode();
        for cut in 0..bytes.len() {
            let mut d = Decoder::new();
            d.push(&bytes[..cut]);
            assert_eq!(d.next_message(), None, "cut {cut}");
            d.push(&bytes[cut..]);
            assert_eq!(d.next_message(), Some(Ok(good.clone())));
        }
    }

    #[test]
    fn extended_length_round_trip_and_limits() {
        let m = Message::new(0x99, vec![7; 300]);
        let b = m.encode();
        assert_eq!(&b[3..6], &[0xFF, 0x01, 0x2C]);
        let mut d = Decoder::new();
        d.push(&b);
        assert_eq!(d.next_message(), Some(Ok(m)));
        let mut d = Decoder::new();
        d.push(&[0xFA, 0xFF, 0x32, 0xFF, 0xFF, 0xFF]);
        assert_eq!(d.next_message(), Some(Err(FrameError::TooLong(0xFFFF))));
    }

    #[test]
    fn samples_round_trip_and_wrong_sizes_are_errors() {
        let s = emulated_motion(2.5);
        assert_eq!(Sample::parse(&s.encode()), Ok(s));
        assert_eq!(Sample::parse(&[0; 50]), Err(SampleError(50)));
    }

    #[test]
    fn emulator_follows_the_configuration_sequence() {
        let mut e = EmulatedMtx::default();
        let r = e.handle(&Message::new(mid::GO_TO_CONFIG, vec![]));
        assert_eq!(r, [Message::new(0x31, vec![])]);
        assert!(e.sample(&Sample::default()).is_none());
        e.handle(&Message::new(mid::SET_OUTPUT_MODE, vec![0, 6]));
        let r = e.handle(&Message::new(mid::SET_OUTPUT_SETTINGS, vec![]));
        assert_eq!(r[0].data, [0, 0, 0, 4]);
        let r = e.handle(&Message::new(mid::REQ_DATA_LENGTH, vec![]));
        assert_eq!(r[0].data, [0, 48]);
        e.handle(&Message::new(mid::GO_TO_MEASUREMENT, vec![]));
        assert!(e.sample(&Sample::default()).is_some());
        let r = e.handle(&Message::new(0x77, vec![]));
        assert_eq!(r, [Message::new(mid::ERROR, vec![ERR_INVALID_MESSAGE])]);
    }

    #[test]
    fn any_bytes_decode_without_panic() {
        let mut x = 0x1234_5678u32;
        for _ in 0..2000 {
            let n = (x % 300) as usize;
            let bytes: Vec<u8> = (0..n)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    if x.is_multiple_of(7) {
                        0xFA
                    } else {
                        x as u8
                    }
                })
                .collect();
            decode_any(&bytes);
        }
    }
}
