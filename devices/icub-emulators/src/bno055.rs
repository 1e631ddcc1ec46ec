//! An emulated Bosch BNO055 (the head IMU `imuBosch_BNO055` drives) on a serial line: the
//! chip's register map (page 0) behind its UART protocol, as the datasheet describes it.
//!
//! Frames from the host: `AA 00 reg len data…` writes, `AA 01 reg len` reads. Answers:
//! `EE 01` to a write done, `BB len data…` to a read, `EE code` to a refused frame (06: not
//! `AA`; 08/09: length above 128 or zero; 04: a register outside the map; 05: a read-only
//! register; 0A: a frame that stops halfway). In NDOF mode the data registers (0x08-0x27)
//! follow a slow motion of the head ([`Motion`]), sampled when read: acceleration (specific
//! force, 1/100 m/s²), magnetic field (1/16 µT), rate of turn (1/16 deg/s), Euler angles
//! (1/16 deg) and quaternion (1/2^14). In CONFIG mode they read zero, as a chip that has not
//! fused anything yet. `SYS_STATUS` says 5 (fusion running) in NDOF, 0 (idle) otherwise.

use icub_can::emulator::mtx::{pty, MtxPort};
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Register addresses of page 0.
pub mod reg {
    pub const CHIP_ID: u8 = 0x00;
    pub const ACC_ID: u8 = 0x01;
    pub const MAG_ID: u8 = 0x02;
    pub const GYR_ID: u8 = 0x03;
    pub const SW_REV_LSB: u8 = 0x04;
    pub const SW_REV_MSB: u8 = 0x05;
    pub const BL_REV: u8 = 0x06;
    pub const PAGE_ID: u8 = 0x07;
    pub const DATA_START: u8 = 0x08;
    pub const DATA_END: u8 = 0x33;
    pub const TEMP: u8 = 0x34;
    pub const CALIB_STAT: u8 = 0x35;
    pub const ST_RESULT: u8 = 0x36;
    pub const SYS_STATUS: u8 = 0x39;
    pub const SYS_ERR: u8 = 0x3A;
    pub const UNIT_SEL: u8 = 0x3B;
    pub const OPR_MODE: u8 = 0x3D;
    pub const PWR_MODE: u8 = 0x3E;
    pub const SYS_TRIGGER: u8 = 0x3F;
    pub const AXIS_MAP_CONFIG: u8 = 0x41;
    pub const LAST: u8 = 0x6A;
}

/// UART status codes (`EE code`).
pub mod status {
    pub const WRITE_SUCCESS: u8 = 0x01;
    pub const REGMAP_INVALID_ADDRESS: u8 = 0x04;
    pub const REGMAP_WRITE_DISABLED: u8 = 0x05;
    pub const WRONG_START_BYTE: u8 = 0x06;
    pub const MAX_LENGTH_ERROR: u8 = 0x08;
    pub const MIN_LENGTH_ERROR: u8 = 0x09;
    pub const RECEIVE_CHARACTER_TIMEOUT: u8 = 0x0A;
}

const NDOF: u8 = 0x0C;
const GRAVITY: f64 = 9.80665;

/// The head's orientation over time (degrees) and the Earth's field it sees.
#[derive(Debug, Clone, Copy)]
pub struct Motion;

impl Motion {
    /// Roll, pitch, yaw (degrees) at `t` seconds.
    pub fn rpy(t: f64) -> [f64; 3] {
        [
            8.0 * (0.4 * t).sin(),
            12.0 * (0.25 * t).sin(),
            25.0 * (0.15 * t).sin(),
        ]
    }

    /// Their rates (deg/s).
    pub fn rates(t: f64) -> [f64; 3] {
        [
            8.0 * 0.4 * (0.4 * t).cos(),
            12.0 * 0.25 * (0.25 * t).cos(),
            25.0 * 0.15 * (0.15 * t).cos(),
        ]
    }

    /// The field in the world frame (µT): north, a little east, down.
    pub const FIELD: [f64; 3] = [22.0, 1.5, -42.0];
}

/// The body-to-world rotation of roll, pitch, yaw (radians), Z-Y-X, as rows.
fn rotation(rpy_deg: [f64; 3]) -> [[f64; 3]; 3] {
    let [r, p, y] = rpy_deg.map(f64::to_radians);
    let (cr, sr, cp, sp, cy, sy) = (r.cos(), r.sin(), p.cos(), p.sin(), y.cos(), y.sin());
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// `R^T v`: a world vector in the body frame.
fn to_body(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|j| (0..3).map(|i| r[i][j] * v[i]).sum())
}

/// The unit quaternion (w, x, y, z) of roll, pitch, yaw (degrees), Z-Y-X.
pub fn quaternion(rpy_deg: [f64; 3]) -> [f64; 4] {
    let [r, p, y] = rpy_deg.map(|d| d.to_radians() / 2.0);
    let (cr, sr, cp, sp, cy, sy) = (r.cos(), r.sin(), p.cos(), p.sin(), y.cos(), y.sin());
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// The chip's registers and mode.
#[derive(Debug, Clone)]
pub struct Bno055 {
    regs: [u8; 0x80],
    started: Instant,
}

impl Default for Bno055 {
    fn default() -> Self {
        Self::new()
    }
}

fn clamp16(v: f64) -> [u8; 2] {
    (v.round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16).to_le_bytes()
}

impl Bno055 {
    /// A chip at power-on: CONFIG mode, default units, identities as a real BNO055.
    pub fn new() -> Bno055 {
        let mut regs = [0u8; 0x80];
        regs[usize::from(reg::CHIP_ID)] = 0xA0;
        regs[usize::from(reg::ACC_ID)] = 0xFB;
        regs[usize::from(reg::MAG_ID)] = 0x32;
        regs[usize::from(reg::GYR_ID)] = 0x0F;
        regs[usize::from(reg::SW_REV_LSB)] = 0x11;
        regs[usize::from(reg::SW_REV_MSB)] = 0x03;
        regs[usize::from(reg::BL_REV)] = 0x15;
        regs[usize::from(reg::ST_RESULT)] = 0x0F;
        regs[usize::from(reg::TEMP)] = 28;
        regs[usize::from(reg::AXIS_MAP_CONFIG)] = 0x24;
        Bno055 {
            regs,
            started: Instant::now(),
        }
    }

    pub fn mode(&self) -> u8 {
        self.regs[usize::from(reg::OPR_MODE)] & 0x0F
    }

    /// The data registers 0x08..=0x33 at `t` seconds of motion (zeros outside NDOF).
    fn sample(&mut self, t: f64) {
        let ndof = self.mode() == NDOF;
        let data = &mut self.regs[usize::from(reg::DATA_START)..=usize::from(reg::DATA_END)];
        data.fill(0);
        if !ndof {
            return;
        }
        let rpy = Motion::rpy(t);
        let r = rotation(rpy);
        let acc = to_body(&r, [0.0, 0.0, GRAVITY]);
        let mag = to_body(&r, Motion::FIELD);
        let gyro = Motion::rates(t);
        let q = quaternion(rpy);
        let mut words = Vec::with_capacity(22);
        words.extend(acc.map(|v| v * 100.0));
        words.extend(mag.map(|v| v * 16.0));
        words.extend(gyro.map(|v| v * 16.0));
        // Euler registers: heading (yaw, 0..360), roll, pitch
        words.extend([rpy[2].rem_euclid(360.0), rpy[0], rpy[1]].map(|v| v * 16.0));
        words.extend(q.map(|v| v * 16384.0));
        // linear acceleration (none: the head does not translate) and gravity
        words.extend([0.0; 3]);
        words.extend(acc.map(|v| v * 100.0));
        for (k, w) in words.iter().enumerate() {
            data[2 * k..2 * k + 2].copy_from_slice(&clamp16(*w));
        }
        self.regs[usize::from(reg::CALIB_STAT)] = 0xFF;
    }

    /// A register read of `len` bytes from `start`, or the status code refusing it.
    pub fn read(&mut self, start: u8, len: u8) -> Result<Vec<u8>, u8> {
        let end = usize::from(start) + usize::from(len);
        match len {
            0 => return Err(status::MIN_LENGTH_ERROR),
            129.. => return Err(status::MAX_LENGTH_ERROR),
            _ if end > usize::from(reg::LAST) + 1 => return Err(status::REGMAP_INVALID_ADDRESS),
            _ => {}
        }
        if usize::from(start) <= usize::from(reg::DATA_END) && end > usize::from(reg::DATA_START) {
            self.sample(self.started.elapsed().as_secs_f64());
        }
        self.regs[usize::from(reg::SYS_STATUS)] = if self.mode() == NDOF { 5 } else { 0 };
        Ok(self.regs[usize::from(start)..end].to_vec())
    }

    /// A register write, or the status code refusing it.
    pub fn write(&mut self, start: u8, data: &[u8]) -> Result<(), u8> {
        let end = usize::from(start) + data.len();
        if end > usize::from(reg::LAST) + 1 {
            return Err(status::REGMAP_INVALID_ADDRESS);
        }
        for (k, &b) in data.iter().enumerate() {
            let r = start + k as u8;
            match r {
                // identities, data and status registers are read-only
                reg::CHIP_ID..=reg::BL_REV | reg::DATA_START..=reg::SYS_ERR => {
                    return Err(status::REGMAP_WRITE_DISABLED)
                }
                reg::SYS_TRIGGER => {
                    // reset bits clear the chip; the clock selection stays
                    if b & 0x20 != 0 {
                        *self = Bno055::new();
                    }
                    self.regs[usize::from(r)] = b & 0x80;
                }
                _ => self.regs[usize::from(r)] = b,
            }
        }
        Ok(())
    }

    /// The answer to one whole frame.
    pub fn answer(&mut self, frame: &Frame) -> Vec<u8> {
        match frame {
            Frame::Read { reg, len } => match self.read(*reg, *len) {
                Ok(data) => {
                    let mut out = vec![0xBB, *len];
                    out.extend(data);
                    out
                }
                Err(code) => vec![0xEE, code],
            },
            Frame::Write { reg, data } => match self.write(*reg, data) {
                Ok(()) => vec![0xEE, status::WRITE_SUCCESS],
                Err(code) => vec![0xEE, code],
            },
            Frame::Refused(code) => vec![0xEE, *code],
        }
    }
}

/// One frame from the host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Frame {
    Read {
        reg: u8,
        len: u8,
    },
    Write {
        reg: u8,
        data: Vec<u8>,
    },
    /// A frame the chip refuses with this status.
    Refused(u8),
}

/// Cuts the host's byte stream into frames. A frame that stops halfway for longer than
/// the chip waits is refused with `RECEIVE_CHARACTER_TIMEOUT` ([`FrameReader::timed_out`]).
#[derive(Debug, Default)]
pub struct FrameReader {
    buf: Vec<u8>,
}

impl FrameReader {
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// The next whole frame, if one is in.
    pub fn next_frame(&mut self) -> Option<Frame> {
        let first = *self.buf.first()?;
        if first != 0xAA {
            self.buf.remove(0);
            return Some(Frame::Refused(status::WRONG_START_BYTE));
        }
        let (&cmd, &reg, &len) = (self.buf.get(1)?, self.buf.get(2)?, self.buf.get(3)?);
        match cmd {
            0x01 => {
                self.buf.drain(..4);
                Some(Frame::Read { reg, len })
            }
            0x00 => {
                if len == 0 {
                    self.buf.drain(..4);
                    return Some(Frame::Refused(status::MIN_LENGTH_ERROR));
                }
                let total = 4 + usize::from(len);
                if self.buf.len() < total {
                    return None;
                }
                let data = self.buf[4..total].to_vec();
                self.buf.drain(..total);
                Some(Frame::Write { reg, data })
            }
            _ => {
                self.buf.drain(..2);
                Some(Frame::Refused(status::WRONG_START_BYTE))
            }
        }
    }

    /// Drops a frame that stopped halfway; whether there was one.
    pub fn timed_out(&mut self) -> bool {
        let partial = !self.buf.is_empty();
        self.buf.clear();
        partial
    }
}

/// A running emulated chip; stops (and removes its link) on drop.
pub struct Bno055Handle {
    stop: Arc<AtomicBool>,
    /// While set, the chip neither hears nor answers (an unplugged cable).
    pub silent: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    link: Option<(PathBuf, PathBuf)>,
}

impl Drop for Bno055Handle {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        if let Some((link, pts)) = self.link.take() {
            if std::fs::read_link(&link).is_ok_and(|target| target == pts) {
                let _ = std::fs::remove_file(&link);
            }
        }
    }
}

/// How long the chip waits for the rest of a frame (its receive-character timeout).
const CHARACTER_TIMEOUT: Duration = Duration::from_millis(100);

/// Serves `chip` on `port` in a thread until the handle is dropped.
pub fn serve(mut port: impl MtxPort, mut chip: Bno055) -> std::io::Result<Bno055Handle> {
    let stop = Arc::new(AtomicBool::new(false));
    let silent = Arc::new(AtomicBool::new(false));
    let (st, si) = (stop.clone(), silent.clone());
    let thread = std::thread::Builder::new()
        .name("bno055".into())
        .spawn(move || {
            let mut frames = FrameReader::default();
            let mut buf = [0u8; 256];
            let mut last_byte = Instant::now();
            let _ = port.set_read_timeout(Duration::from_millis(20));
            while !st.load(Ordering::SeqCst) {
                match port.read(&mut buf) {
                    Ok(n) if !si.load(Ordering::SeqCst) => {
                        frames.push(&buf[..n]);
                        last_byte = Instant::now();
                    }
                    Ok(_) => {}
                    Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::Interrupted) => {}
                    Err(e) => {
                        // the host side closed (pty hang-up): wait for it to come back
                        tracing::trace!("emulated BNO055: {e}");
                        std::thread::sleep(Duration::from_millis(10));
                    }
                }
                while let Some(f) = frames.next_frame() {
                    let _ = port.write_all(&chip.answer(&f));
                }
                if last_byte.elapsed() > CHARACTER_TIMEOUT && frames.timed_out() {
                    let _ = port.write_all(&[0xEE, status::RECEIVE_CHARACTER_TIMEOUT]);
                }
            }
        })?;
    Ok(Bno055Handle {
        stop,
        silent,
        thread: Some(thread),
        link: None,
    })
}

/// Serves a new chip on a pseudo-terminal reachable as `link` (replacing any earlier
/// link, removed when the handle is dropped): the `comport` a robot file names, or the
/// path given in `YARP_BNO055_COMPORT`. Returns the terminal's own path too.
pub fn pty_link(link: &Path) -> std::io::Result<(Bno055Handle, PathBuf)> {
    let (port, path) = pty()?;
    if link.symlink_metadata().is_ok() {
        std::fs::remove_file(link)?;
    }
    std::os::unix::fs::symlink(&path, link)?;
    let mut handle = serve(port, Bno055::new())?;
    handle.link = Some((link.to_path_buf(), path.clone()));
    Ok((handle, path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(bytes: &[u8]) -> Vec<Frame> {
        let mut r = FrameReader::default();
        r.push(bytes);
        std::iter::from_fn(|| r.next_frame()).collect()
    }

    #[test]
    fn frames_are_cut_and_bad_ones_refused() {
        assert_eq!(
            frames(&[0xAA, 0x01, 0x08, 0x20, 0xAA, 0x00, 0x3D, 0x01, 0x0C]),
            vec![
                Frame::Read { reg: 0x08, len: 32 },
                Frame::Write {
                    reg: 0x3D,
                    data: vec![0x0C]
                }
            ]
        );
        assert_eq!(
            frames(&[0x55]),
            vec![Frame::Refused(status::WRONG_START_BYTE)]
        );
        assert_eq!(frames(&[0xAA, 0x00, 0x3D]), vec![]);
        let mut r = FrameReader::default();
        r.push(&[0xAA, 0x00, 0x3D, 0x02, 0x00]);
        assert_eq!(r.next_frame(), None);
        assert!(r.timed_out());
    }

    #[test]
    fn the_chip_answers_as_the_datasheet() {
        let mut c = Bno055::new();
        assert_eq!(
            c.answer(&Frame::Read { reg: 0, len: 1 }),
            vec![0xBB, 1, 0xA0]
        );
        assert_eq!(
            c.answer(&Frame::Read { reg: 0x6A, len: 2 }),
            vec![0xEE, 0x04]
        );
        assert_eq!(c.answer(&Frame::Read { reg: 0, len: 0 }), vec![0xEE, 0x09]);
        assert_eq!(
            c.answer(&Frame::Write {
                reg: 0,
                data: vec![1]
            }),
            vec![0xEE, 0x05]
        );
        // CONFIG mode: no data
        let block = c.read(0x08, 32).unwrap();
        assert!(block.iter().all(|&b| b == 0));
        assert_eq!(c.read(reg::SYS_STATUS, 1), Ok(vec![0]));
        assert_eq!(
            c.answer(&Frame::Write {
                reg: 0x3D,
                data: vec![0x0C]
            }),
            vec![0xEE, 1]
        );
        assert_eq!(c.read(reg::SYS_STATUS, 1), Ok(vec![5]));
        let block = c.read(0x08, 32).unwrap();
        let w: Vec<f64> = block
            .chunks_exact(2)
            .map(|b| f64::from(i16::from_le_bytes([b[0], b[1]])))
            .collect();
        let acc = (w[0].powi(2) + w[1].powi(2) + w[2].powi(2)).sqrt() / 100.0;
        assert!((acc - GRAVITY).abs() < 0.05, "{acc}");
        let q2: f64 = w[12..16].iter().map(|v| (v / 16384.0).powi(2)).sum();
        assert!((q2 - 1.0).abs() < 1e-3, "{q2}");
    }

    #[test]
    fn gravity_and_field_turn_with_the_head() {
        let r = rotation([0.0, 90.0, 0.0]);
        let g = to_body(&r, [0.0, 0.0, 1.0]);
        // pitched 90 degrees nose down: up is the body's -x
        assert!((g[0] + 1.0).abs() < 1e-12 && g[2].abs() < 1e-12, "{g:?}");
        let q = quaternion([0.0, 0.0, 90.0]);
        assert!((q[0] - q[3]).abs() < 1e-12);
    }
}
