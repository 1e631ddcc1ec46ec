//! Slamtec's RPLidar serial protocol (SDK 1.12, as robotology/yarp-device-rplidar's
//! `rpLidar2`/`rpLidar3` use it), without I/O.
//!
//! A request is `A5 cmd`, or `A5 cmd len payload… checksum` for the commands with a
//! payload (bit 7 set), the checksum the XOR of every byte before it. An answer starts
//! with a descriptor `A5 5A size(30 bits)|subtype(2 bits) type`, then the data: once, or
//! for the scans a stream of measurements in the format the descriptor's type names.

use thiserror::Error;

/// Request commands.
pub mod cmd {
    pub const STOP: u8 = 0x25;
    pub const SCAN: u8 = 0x20;
    pub const FORCE_SCAN: u8 = 0x21;
    pub const RESET: u8 = 0x40;
    pub const GET_INFO: u8 = 0x50;
    pub const GET_HEALTH: u8 = 0x52;
    pub const GET_SAMPLERATE: u8 = 0x59;
    pub const EXPRESS_SCAN: u8 = 0x82;
    pub const HQ_SCAN: u8 = 0x83;
    pub const GET_LIDAR_CONF: u8 = 0x84;
    pub const SET_LIDAR_CONF: u8 = 0x85;
    pub const SET_MOTOR_PWM: u8 = 0xF0;
    pub const GET_ACC_BOARD_FLAG: u8 = 0xFF;
}

/// Answer types (the descriptor's last byte).
pub mod ans {
    pub const DEVINFO: u8 = 0x04;
    pub const DEVHEALTH: u8 = 0x06;
    pub const MEASUREMENT: u8 = 0x81;
    pub const MEASUREMENT_CAPSULED: u8 = 0x82;
    pub const MEASUREMENT_HQ: u8 = 0x83;
    pub const MEASUREMENT_CAPSULED_ULTRA: u8 = 0x84;
    pub const MEASUREMENT_DENSE_CAPSULED: u8 = 0x85;
    pub const SAMPLE_RATE: u8 = 0x15;
    pub const GET_LIDAR_CONF: u8 = 0x20;
    pub const ACC_BOARD_FLAG: u8 = 0xFF;
}

/// `GET_LIDAR_CONF` configuration types.
pub mod conf {
    pub const SCAN_MODE_COUNT: u32 = 0x70;
    pub const SCAN_MODE_US_PER_SAMPLE: u32 = 0x71;
    pub const SCAN_MODE_MAX_DISTANCE: u32 = 0x74;
    pub const SCAN_MODE_ANS_TYPE: u32 = 0x75;
    pub const SCAN_MODE_TYPICAL: u32 = 0x7C;
    pub const SCAN_MODE_NAME: u32 = 0x7F;
}

const SYNC: u8 = 0xA5;
const ANSWER_SYNC: u8 = 0x5A;

/// What does not decode.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ProtocolError {
    #[error("{what}: {got} bytes, expected {expected}")]
    Size {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{0}: bad checksum")]
    Checksum(&'static str),
    #[error("{0}: bad sync bytes")]
    Sync(&'static str),
    #[error("a configuration answer for type {got:#x}, asked {asked:#x}")]
    ConfType { asked: u32, got: u32 },
}

/// A request's bytes (`payload` only for the commands that carry one).
pub fn request(cmd: u8, payload: &[u8]) -> Vec<u8> {
    if cmd & 0x80 == 0 {
        return vec![SYNC, cmd];
    }
    let len = payload.len().min(255) as u8;
    let mut out = vec![SYNC, cmd, len];
    out.extend_from_slice(&payload[..usize::from(len)]);
    out.push(out.iter().fold(0, |cs, b| cs ^ b));
    out
}

/// A request as a lidar reads it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    pub cmd: u8,
    pub payload: Vec<u8>,
}

/// Splits a lidar's input into requests; bytes out of sync and requests of a bad
/// checksum are dropped, as the firmware drops them.
#[derive(Debug, Default)]
pub struct RequestReader {
    buf: Vec<u8>,
}

impl RequestReader {
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// The next whole request, if any.
    pub fn next_request(&mut self) -> Option<Request> {
        loop {
            let start = self.buf.iter().position(|&b| b == SYNC)?;
            self.buf.drain(..start);
            let &cmd = self.buf.get(1)?;
            if cmd & 0x80 == 0 {
                self.buf.drain(..2);
                return Some(Request {
                    cmd,
                    payload: Vec::new(),
                });
            }
            let len = usize::from(*self.buf.get(2)?);
            if self.buf.len() < 4 + len {
                return None;
            }
            let frame: Vec<u8> = self.buf.drain(..4 + len).collect();
            if frame[..3 + len].iter().fold(0, |cs, b| cs ^ b) == frame[3 + len] {
                return Some(Request {
                    cmd,
                    payload: frame[3..3 + len].to_vec(),
                });
            }
        }
    }
}

/// An answer's descriptor: its data's size, subtype (1: a stream) and type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Descriptor {
    pub size: u32,
    pub subtype: u8,
    pub ans_type: u8,
}

impl Descriptor {
    pub const LEN: usize = 7;

    pub fn encode(&self) -> [u8; 7] {
        let word = (self.size & 0x3FFF_FFFF) | u32::from(self.subtype & 3) << 30;
        let w = word.to_le_bytes();
        [SYNC, ANSWER_SYNC, w[0], w[1], w[2], w[3], self.ans_type]
    }

    pub fn decode(b: &[u8]) -> Result<Descriptor, ProtocolError> {
        let b: &[u8; 7] =
            b.get(..7)
                .and_then(|b| b.try_into().ok())
                .ok_or(ProtocolError::Size {
                    what: "descriptor",
                    expected: 7,
                    got: b.len(),
                })?;
        if b[0] != SYNC || b[1] != ANSWER_SYNC {
            return Err(ProtocolError::Sync("descriptor"));
        }
        let word = u32::from_le_bytes([b[2], b[3], b[4], b[5]]);
        Ok(Descriptor {
            size: word & 0x3FFF_FFFF,
            subtype: (word >> 30) as u8,
            ans_type: b[6],
        })
    }
}

/// `GET_INFO`'s answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceInfo {
    pub model: u8,
    /// `major << 8 | minor`.
    pub firmware: u16,
    pub hardware: u8,
    pub serial: [u8; 16],
}

impl DeviceInfo {
    pub const LEN: usize = 20;

    pub fn encode(&self) -> [u8; 20] {
        let mut b = [0u8; 20];
        b[0] = self.model;
        b[1..3].copy_from_slice(&self.firmware.to_le_bytes());
        b[3] = self.hardware;
        b[4..].copy_from_slice(&self.serial);
        b
    }

    pub fn decode(b: &[u8]) -> Result<DeviceInfo, ProtocolError> {
        if b.len() < 20 {
            return Err(ProtocolError::Size {
                what: "device info",
                expected: 20,
                got: b.len(),
            });
        }
        let mut serial = [0u8; 16];
        serial.copy_from_slice(&b[4..20]);
        Ok(DeviceInfo {
            model: b[0],
            firmware: u16::from_le_bytes([b[1], b[2]]),
            hardware: b[3],
            serial,
        })
    }

    /// A time-of-flight lidar (the SDK's `model >> 4 > 5`), whose motor the SDK does not
    /// start.
    pub fn is_tof(&self) -> bool {
        self.model >> 4 > 5
    }

    /// Whether the firmware answers `GET_LIDAR_CONF` (1.24 and later).
    pub fn has_lidar_conf(&self) -> bool {
        self.firmware >= 0x0118
    }

    /// Whether the firmware knows express scans (1.17 and later).
    pub fn has_express(&self) -> bool {
        self.firmware >= 0x0111
    }
}

/// A `GET_LIDAR_CONF` request's payload: the type, and for the per-mode types the mode.
pub fn conf_payload(conf_type: u32, mode: Option<u16>) -> [u8; 36] {
    let mut p = [0u8; 36];
    p[..4].copy_from_slice(&conf_type.to_le_bytes());
    if let Some(m) = mode {
        p[4..6].copy_from_slice(&m.to_le_bytes());
    }
    p
}

/// A `GET_LIDAR_CONF` answer's data: the type echoed, then the value.
pub fn conf_answer(conf_type: u32, value: &[u8]) -> Vec<u8> {
    let mut out = conf_type.to_le_bytes().to_vec();
    out.extend_from_slice(value);
    out
}

/// The value of a `GET_LIDAR_CONF` answer to `asked`.
pub fn conf_value(asked: u32, data: &[u8]) -> Result<&[u8], ProtocolError> {
    let t: [u8; 4] = data
        .get(..4)
        .and_then(|b| b.try_into().ok())
        .ok_or(ProtocolError::Size {
            what: "lidar configuration",
            expected: 4,
            got: data.len(),
        })?;
    let got = u32::from_le_bytes(t);
    if got != asked {
        return Err(ProtocolError::ConfType { asked, got });
    }
    Ok(&data[4..])
}

/// A measurement as the SDK hands it on (`rplidar_response_measurement_node_hq_t`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Node {
    /// Angle, 90° = 16384.
    pub angle_z_q14: u16,
    /// Distance, mm × 4 (0: no measurement).
    pub dist_mm_q2: u32,
    /// Quality, in its top 6 bits as the SDK keeps it.
    pub quality: u8,
    /// Bit 0: the first measurement of a revolution.
    pub flag: u8,
}

impl Node {
    pub fn sync(&self) -> bool {
        self.flag & 1 != 0
    }

    /// Degrees, in [0, 360).
    pub fn angle_deg(&self) -> f64 {
        f64::from(self.angle_z_q14) * 90.0 / 16384.0
    }

    /// Metres.
    pub fn distance_m(&self) -> f64 {
        f64::from(self.dist_mm_q2) / 4.0 / 1000.0
    }
}

/// A standard scan's 5-byte measurement (answer type 0x81): `quality<<2 | !S<<1 | S`,
/// `angle_q6<<1 | 1`, `distance_q2`; `None` when its check bits are wrong.
pub fn decode_standard(b: &[u8; 5]) -> Option<Node> {
    let s = b[0] & 1;
    if ((b[0] >> 1) ^ b[0]) & 1 == 0 || b[1] & 1 == 0 {
        return None;
    }
    let angle_q6 = u16::from_le_bytes([b[1], b[2]]) >> 1;
    Some(Node {
        angle_z_q14: ((u32::from(angle_q6) << 8) / 90) as u16,
        dist_mm_q2: u32::from(u16::from_le_bytes([b[3], b[4]])),
        quality: b[0] & 0xFC,
        flag: s,
    })
}

/// The 5 bytes a lidar sends for a standard measurement.
pub fn encode_standard(angle_q6: u16, dist_mm_q2: u16, quality: u8, sync: bool) -> [u8; 5] {
    let s = u8::from(sync);
    let a = (angle_q6 << 1 | 1).to_le_bytes();
    let d = dist_mm_q2.to_le_bytes();
    [quality << 2 | (s ^ 1) << 1 | s, a[0], a[1], d[0], d[1]]
}

/// The SDK's choice of which converted measurement starts a revolution: the first
/// whose next angle falls in (0°, 90°), then none until the angle passes 270°.
#[derive(Debug, Default, Clone)]
struct SyncByAngle {
    found: bool,
}

impl SyncByAngle {
    fn next(&mut self, current_q16: i64, inc_q16: i64) -> u8 {
        let predict = (current_q16 + inc_q16).rem_euclid(360 << 16);
        if !self.found {
            if 0 < predict && predict < (90 << 16) {
                self.found = true;
                return 1;
            }
        } else if predict > (270 << 16) {
            self.found = false;
        }
        0
    }
}

fn node(angle_q16: i64, dist_q2: u32, sync: u8) -> Node {
    let a = angle_q16.rem_euclid(360 << 16);
    Node {
        angle_z_q14: ((a >> 2) / 90) as u16,
        dist_mm_q2: dist_q2,
        quality: if dist_q2 != 0 { 0x2F << 2 } else { 0 },
        flag: sync | (sync ^ 1) << 1,
    }
}

/// A capsule's frame check: `0xA?` `0x5?` carrying the XOR of the bytes after them.
fn check_frame(what: &'static str, b: &[u8]) -> Result<(), ProtocolError> {
    if b[0] >> 4 != 0xA || b[1] >> 4 != 0x5 {
        return Err(ProtocolError::Sync(what));
    }
    let cs = (b[0] & 0xF) | (b[1] << 4);
    if b[2..].iter().fold(0, |x, v| x ^ v) != cs {
        return Err(ProtocolError::Checksum(what));
    }
    Ok(())
}

fn frame(mut body: Vec<u8>) -> Vec<u8> {
    let cs = body[2..].iter().fold(0u8, |x, v| x ^ v);
    body[0] = 0xA0 | (cs & 0xF);
    body[1] = 0x50 | (cs >> 4);
    body
}

/// An express capsule (answer type 0x82, 84 bytes): its start angle (bit 15: a new
/// scan starts) and 16 cabins of two measurements.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Capsule {
    pub start_angle_sync_q6: u16,
    /// `(distance_angle_1, distance_angle_2, offset_angles_q3)`.
    pub cabins: [(u16, u16, u8); 16],
}

impl Capsule {
    pub const LEN: usize = 84;

    pub fn decode(b: &[u8]) -> Result<Capsule, ProtocolError> {
        if b.len() != Self::LEN {
            return Err(ProtocolError::Size {
                what: "express capsule",
                expected: Self::LEN,
                got: b.len(),
            });
        }
        check_frame("express capsule", b)?;
        let mut cabins = [(0, 0, 0); 16];
        for (k, c) in cabins.iter_mut().enumerate() {
            let at = 4 + 5 * k;
            *c = (
                u16::from_le_bytes([b[at], b[at + 1]]),
                u16::from_le_bytes([b[at + 2], b[at + 3]]),
                b[at + 4],
            );
        }
        Ok(Capsule {
            start_angle_sync_q6: u16::from_le_bytes([b[2], b[3]]),
            cabins,
        })
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut b = vec![0u8; 2];
        b.extend_from_slice(&self.start_angle_sync_q6.to_le_bytes());
        for (d1, d2, off) in &self.cabins {
            b.extend_from_slice(&d1.to_le_bytes());
            b.extend_from_slice(&d2.to_le_bytes());
            b.push(*off);
        }
        frame(b)
    }
}

/// An ultra capsule (answer type 0x84, 132 bytes): its start angle and 32 cabins of three
/// measurements packed in 32 bits each.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UltraCapsule {
    pub start_angle_sync_q6: u16,
    pub cabins: [u32; 32],
}

impl UltraCapsule {
    pub const LEN: usize = 132;

    pub fn decode(b: &[u8]) -> Result<UltraCapsule, ProtocolError> {
        if b.len() != Self::LEN {
            return Err(ProtocolError::Size {
                what: "ultra capsule",
                expected: Self::LEN,
                got: b.len(),
            });
        }
        check_frame("ultra capsule", b)?;
        let mut cabins = [0u32; 32];
        for (k, c) in cabins.iter_mut().enumerate() {
            let at = 4 + 4 * k;
            *c = u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        }
        Ok(UltraCapsule {
            start_angle_sync_q6: u16::from_le_bytes([b[2], b[3]]),
            cabins,
        })
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut b = vec![0u8; 2];
        b.extend_from_slice(&self.start_angle_sync_q6.to_le_bytes());
        for c in &self.cabins {
            b.extend_from_slice(&c.to_le_bytes());
        }
        frame(b)
    }
}

/// The span from one capsule's start angle to the next's, in q8 degrees.
fn diff_q8(prev_q6: u16, cur_q6: u16) -> i64 {
    let (prev, cur) = (
        i64::from(prev_q6 & 0x7FFF) << 2,
        i64::from(cur_q6 & 0x7FFF) << 2,
    );
    if prev > cur {
        cur - prev + (360 << 8)
    } else {
        cur - prev
    }
}

/// Turns express capsules into measurements as the SDK does: a capsule's measurements
/// come out when the next one arrives (its start angle closes the span), none across a
/// capsule that starts a new scan.
#[derive(Debug, Default, Clone)]
pub struct CapsuleDecoder {
    previous: Option<Capsule>,
    sync: SyncByAngle,
}

impl CapsuleDecoder {
    pub fn push(&mut self, capsule: Capsule) -> Vec<Node> {
        let mut out = Vec::new();
        let restart = capsule.start_angle_sync_q6 & 0x8000 != 0;
        if let (Some(prev), false) = (&self.previous, restart) {
            let inc = diff_q8(prev.start_angle_sync_q6, capsule.start_angle_sync_q6) << 3;
            let mut current = (i64::from(prev.start_angle_sync_q6 & 0x7FFF) << 2) << 8;
            for &(d1, d2, off) in &prev.cabins {
                let offsets = [
                    i64::from((off & 0xF) | ((d1 & 3) as u8) << 4),
                    i64::from((off >> 4) | ((d2 & 3) as u8) << 4),
                ];
                for (d, o) in [d1, d2].into_iter().zip(offsets) {
                    let angle = current - (o << 13);
                    let s = self.sync.next(current, inc);
                    current += inc;
                    out.push(node(angle, u32::from(d & 0xFFFC), s));
                }
            }
        }
        self.previous = Some(capsule);
        out
    }
}

/// Varbitscale: the ultra capsules' 12-bit distances, scaled by ranges.
const VBS_SCALED_BASE: [u32; 5] = [3328, 1792, 1280, 512, 0];
const VBS_SCALED_LEVEL: [u32; 5] = [4, 3, 2, 1, 0];
const VBS_TARGET_BASE: [u32; 5] = [1 << 14, 1 << 12, 1 << 11, 1 << 9, 0];

/// A scaled distance (mm) and its scale level.
pub fn varbitscale_decode(scaled: u32) -> (u32, u32) {
    for i in 0..5 {
        if scaled >= VBS_SCALED_BASE[i] {
            let level = VBS_SCALED_LEVEL[i];
            return (
                VBS_TARGET_BASE[i] + ((scaled - VBS_SCALED_BASE[i]) << level),
                level,
            );
        }
    }
    (0, 0)
}

/// The scaled value a distance (mm) is sent as (the nearest one below it).
pub fn varbitscale_encode(mm: u32) -> u32 {
    for i in 0..5 {
        if mm >= VBS_TARGET_BASE[i] {
            let scaled = VBS_SCALED_BASE[i] + ((mm - VBS_TARGET_BASE[i]) >> VBS_SCALED_LEVEL[i]);
            return scaled.min(0xFFF);
        }
    }
    0
}

/// The angle (q16 degrees) the SDK subtracts from an ultra measurement at `dist_q2`: the
/// mean offset of the lidar's optics, shorter for near targets.
// The SDK's own approximations of π, kept for the same integers.
#[allow(clippy::approx_constant)]
pub fn ultra_offset_q16(dist_q2: i64) -> i64 {
    let mut offset = (7.5 * 3.1415926535 * 65536.0 / 180.0) as i64;
    if dist_q2 >= 200 {
        let k2 = 98361 / dist_q2;
        offset = (8.0 * 3.1415926535 * 65536.0 / 180.0) as i64 - (k2 << 6) - (k2 * k2 * k2) / 98304;
    }
    (offset as f64 * 180.0 / 3.14159265) as i64
}

/// Turns ultra capsules into measurements as the SDK does (see [`CapsuleDecoder`]); a
/// cabin's third measurement predicts from the next cabin's major distance.
#[derive(Debug, Default, Clone)]
pub struct UltraCapsuleDecoder {
    previous: Option<UltraCapsule>,
    sync: SyncByAngle,
}

impl UltraCapsuleDecoder {
    pub fn push(&mut self, capsule: UltraCapsule) -> Vec<Node> {
        let mut out = Vec::new();
        let restart = capsule.start_angle_sync_q6 & 0x8000 != 0;
        if let (Some(prev), false) = (&self.previous, restart) {
            let inc = (diff_q8(prev.start_angle_sync_q6, capsule.start_angle_sync_q6) << 3) / 3;
            let mut current = (i64::from(prev.start_angle_sync_q6 & 0x7FFF) << 2) << 8;
            for (pos, &c) in prev.cabins.iter().enumerate() {
                let next = if pos == 31 {
                    capsule.cabins[0]
                } else {
                    prev.cabins[pos + 1]
                };
                let (major, level1) = varbitscale_decode(c & 0xFFF);
                let (major2, level2) = varbitscale_decode(next & 0xFFF);
                let (base1, level1) = if major == 0 && major2 != 0 {
                    (major2, level2)
                } else {
                    (major, level1)
                };
                let p1 = ((c << 10) as i32) >> 22;
                let p2 = (c as i32) >> 22;
                let predicted = |p: i32, base: u32, level: u32| -> u32 {
                    if p == -512 || p == 0x1FF {
                        0
                    } else {
                        (((p << level) + base as i32) << 2) as u32
                    }
                };
                let dists = [
                    major << 2,
                    predicted(p1, base1, level1),
                    predicted(p2, major2, level2),
                ];
                for d in dists {
                    let s = self.sync.next(current, inc);
                    let angle_q6 = (current - ultra_offset_q16(i64::from(d))) >> 10;
                    current += inc;
                    out.push(node(angle_q6 << 10, d, s));
                }
            }
        }
        self.previous = Some(capsule);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_are_the_sdks_bytes() {
        assert_eq!(request(cmd::STOP, &[]), [0xA5, 0x25]);
        assert_eq!(
            request(cmd::GET_ACC_BOARD_FLAG, &[0, 0, 0, 0]),
            [0xA5, 0xFF, 0x04, 0, 0, 0, 0, 0x5E]
        );
        assert_eq!(
            request(cmd::SET_MOTOR_PWM, &660u16.to_le_bytes()),
            [0xA5, 0xF0, 0x02, 0x94, 0x02, 0xC1]
        );
        assert_eq!(
            request(cmd::SET_MOTOR_PWM, &600u16.to_le_bytes()),
            [0xA5, 0xF0, 0x02, 0x58, 0x02, 0x0D]
        );
        assert_eq!(
            *request(cmd::EXPRESS_SCAN, &[2, 0, 0, 0, 0]).last().unwrap(),
            0x22 ^ 2
        );
        let conf = request(
            cmd::GET_LIDAR_CONF,
            &conf_payload(conf::SCAN_MODE_COUNT, None),
        );
        assert_eq!((conf.len(), *conf.last().unwrap()), (40, 0x75));
        assert_eq!(
            *request(
                cmd::GET_LIDAR_CONF,
                &conf_payload(conf::SCAN_MODE_TYPICAL, None)
            )
            .last()
            .unwrap(),
            0x79
        );
    }

    #[test]
    fn a_reader_splits_requests_and_drops_bad_ones() {
        let mut r = RequestReader::default();
        let mut bytes = vec![0x00, 0x13];
        bytes.extend(request(cmd::GET_INFO, &[]));
        let mut bad = request(cmd::SET_MOTOR_PWM, &[1, 2]);
        *bad.last_mut().unwrap() ^= 0xFF;
        bytes.extend(bad);
        bytes.extend(request(cmd::EXPRESS_SCAN, &[2, 0, 0, 0, 0]));
        r.push(&bytes[..7]);
        assert_eq!(
            r.next_request(),
            Some(Request {
                cmd: cmd::GET_INFO,
                payload: vec![]
            })
        );
        assert_eq!(r.next_request(), None);
        r.push(&bytes[7..]);
        assert_eq!(
            r.next_request(),
            Some(Request {
                cmd: cmd::EXPRESS_SCAN,
                payload: vec![2, 0, 0, 0, 0]
            })
        );
        assert_eq!(r.next_request(), None);
    }

    #[test]
    fn descriptors_and_info_round_trip() {
        let d = Descriptor {
            size: 84,
            subtype: 1,
            ans_type: ans::MEASUREMENT_CAPSULED,
        };
        assert_eq!(Descriptor::decode(&d.encode()), Ok(d));
        assert!(Descriptor::decode(&[0xA5, 0x5B, 0, 0, 0, 0, 0]).is_err());
        let i = DeviceInfo {
            model: 0x31,
            firmware: 0x0119,
            hardware: 6,
            serial: [7; 16],
        };
        assert_eq!(DeviceInfo::decode(&i.encode()), Ok(i));
        assert!(i.has_lidar_conf() && i.has_express() && !i.is_tof());
        assert_eq!(
            conf_value(0x70, &conf_answer(0x70, &[3, 0])),
            Ok(&[3u8, 0][..])
        );
        assert!(conf_value(0x71, &conf_answer(0x70, &[3, 0])).is_err());
    }

    #[test]
    fn standard_measurements_round_trip() {
        let b = encode_standard(90 * 64, 1234 * 4, 15, true);
        let n = decode_standard(&b).unwrap();
        assert_eq!(
            (n.angle_deg(), n.distance_m(), n.quality >> 2, n.sync()),
            (90.0, 1.234, 15, true)
        );
        let mut bad = b;
        bad[0] ^= 2;
        assert_eq!(decode_standard(&bad), None);
    }

    /// Capsules of a lidar turning at a steady speed, with distances `d(k)`.
    fn express_stream(
        start_deg: f64,
        step_deg: f64,
        n: usize,
        d: impl Fn(usize) -> u16,
    ) -> Vec<Capsule> {
        (0..n)
            .map(|k| {
                let start = ((start_deg + k as f64 * step_deg) % 360.0 * 64.0) as u16;
                let cabins = std::array::from_fn(|c| {
                    ((d(2 * c) << 2) & 0xFFFC, (d(2 * c + 1) << 2) & 0xFFFC, 0)
                });
                Capsule {
                    start_angle_sync_q6: start,
                    cabins,
                }
            })
            .collect()
    }

    #[test]
    fn express_capsules_become_evenly_spaced_measurements() {
        let capsules = express_stream(10.0, 16.0, 3, |i| 1000 + i as u16);
        for c in &capsules {
            assert_eq!(Capsule::decode(&c.encode()).as_ref(), Ok(c));
        }
        let mut bad = capsules[0].encode();
        bad[10] ^= 1;
        assert_eq!(
            Capsule::decode(&bad),
            Err(ProtocolError::Checksum("express capsule"))
        );
        let mut dec = CapsuleDecoder::default();
        assert!(dec.push(capsules[0].clone()).is_empty());
        let nodes = dec.push(capsules[1].clone());
        assert_eq!(nodes.len(), 32);
        // 16° over 32 measurements from 10°
        for (k, n) in nodes.iter().enumerate() {
            assert!(
                (n.angle_deg() - (10.0 + 0.5 * k as f64)).abs() < 0.01,
                "{k}: {}",
                n.angle_deg()
            );
            assert_eq!(n.dist_mm_q2, (1000 + k as u32) * 4);
        }
        // a capsule that starts a new scan drops the one before
        let mut restart = capsules[2].clone();
        restart.start_angle_sync_q6 |= 0x8000;
        assert!(dec.push(restart).is_empty());
    }

    #[test]
    fn varbitscale_round_trips_within_its_resolution() {
        for mm in [
            0u32, 100, 511, 512, 700, 2047, 2048, 3000, 4095, 4096, 9000, 16383, 16384, 25000,
        ] {
            let (back, level) = varbitscale_decode(varbitscale_encode(mm));
            assert!(back <= mm && mm - back < (1 << level), "{mm} -> {back}");
        }
    }

    #[test]
    fn ultra_capsules_carry_three_measurements_a_cabin() {
        // every cabin: major 2000 mm, the two predicted ones +4 and -8 mm (level 1: ×2)
        let major = varbitscale_encode(2000);
        let (base, level) = varbitscale_decode(major);
        assert_eq!((base, level), (2000, 1));
        let p = |delta: i32| ((delta >> level) as u32) & 0x3FF;
        let cabin = major | p(4) << 12 | p(-8) << 22;
        let capsules: Vec<UltraCapsule> = (0..2)
            .map(|k| UltraCapsule {
                start_angle_sync_q6: (k * 20 * 64) as u16,
                cabins: [cabin; 32],
            })
            .collect();
        for c in &capsules {
            assert_eq!(UltraCapsule::decode(&c.encode()).as_ref(), Ok(c));
        }
        let mut dec = UltraCapsuleDecoder::default();
        assert!(dec.push(capsules[0].clone()).is_empty());
        let nodes = dec.push(capsules[1].clone());
        assert_eq!(nodes.len(), 96);
        assert_eq!(
            [
                nodes[0].dist_mm_q2,
                nodes[1].dist_mm_q2,
                nodes[2].dist_mm_q2
            ],
            [2000 * 4, 2004 * 4, 1992 * 4]
        );
        // 20° over 96 measurements, each less the optics' offset at its distance
        let offset = ultra_offset_q16(2000 * 4) as f64 / 65536.0;
        let expected = (0.0 - offset).rem_euclid(360.0);
        assert!(
            (nodes[0].angle_deg() - expected).abs() < 0.02,
            "{} vs {expected}",
            nodes[0].angle_deg()
        );
    }
}
