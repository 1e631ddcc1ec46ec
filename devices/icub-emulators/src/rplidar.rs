//! An emulated Slamtec RPLidar (R1's base lasers, `rpLidar2`/`rpLidar3`), without I/O:
//! what the lidar answers to each request of the SDK, and the measurements it streams
//! while scanning, of a room around it ([`room`]), turning at 10 Hz.
//!
//! Two models, as the robots' files expect them:
//! - [`Model::A2`], firmware 1.20: no lidar configuration (`GET_LIDAR_CONF` came with 1.24),
//!   standard scans (`0x81`, 500 µs a sample) and express scans (capsules `0x82`, 250 µs);
//! - [`Model::A3`], firmware 1.26: three scan modes, Standard (`0x81`), Express (`0x82`) and
//!   Boost (ultra capsules `0x84`, 63 µs a sample, the typical one).

use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use icub_can::emulator::mtx::{pty, MtxPort};
use rplidar::protocol::{
    self, ans, cmd, conf, Capsule, Descriptor, DeviceInfo, RequestReader, UltraCapsule,
};

/// Which lidar.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    A2,
    A3,
}

/// A scan mode: its name, answer type and time per sample.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Mode {
    name: &'static str,
    ans_type: u8,
    us_per_sample: f64,
}

const STANDARD: Mode = Mode {
    name: "Standard",
    ans_type: ans::MEASUREMENT,
    us_per_sample: 500.0,
};
const EXPRESS: Mode = Mode {
    name: "Express",
    ans_type: ans::MEASUREMENT_CAPSULED,
    us_per_sample: 250.0,
};
const BOOST: Mode = Mode {
    name: "Boost",
    ans_type: ans::MEASUREMENT_CAPSULED_ULTRA,
    us_per_sample: 63.0,
};

/// Revolutions a second.
const SCAN_HZ: f64 = 10.0;

/// The distance (m) to the walls of a 6 m × 4 m room whose centre is 0.5 m ahead of the
/// lidar, along `angle` (degrees, the lidar's own: counter-clockwise seen from above).
pub fn room(angle_deg: f64) -> f64 {
    let (c, s) = (angle_deg.to_radians().cos(), angle_deg.to_radians().sin());
    let (x_min, x_max, y_half) = (-2.5, 3.5, 2.0);
    let tx = if c > 1e-9 {
        x_max / c
    } else if c < -1e-9 {
        x_min / c
    } else {
        f64::INFINITY
    };
    let ty = if s.abs() > 1e-9 {
        y_half / s.abs()
    } else {
        f64::INFINITY
    };
    tx.min(ty)
}

/// The lidar's state.
#[derive(Debug)]
pub struct EmulatedLidar {
    pub model: Model,
    reader: RequestReader,
    /// `(mode, seconds when it started)` while scanning.
    scanning: Option<(Mode, f64)>,
    /// Samples (or capsules' first samples) sent since the scan started.
    sent: u64,
    /// The motor's PWM (0: stopped).
    pub motor_pwm: u16,
}

fn answer(ans_type: u8, data: &[u8]) -> Vec<u8> {
    let mut out = Descriptor {
        size: data.len() as u32,
        subtype: 0,
        ans_type,
    }
    .encode()
    .to_vec();
    out.extend_from_slice(data);
    out
}

impl EmulatedLidar {
    pub fn new(model: Model) -> EmulatedLidar {
        EmulatedLidar {
            model,
            reader: RequestReader::default(),
            scanning: None,
            sent: 0,
            motor_pwm: 0,
        }
    }

    fn modes(&self) -> &'static [Mode] {
        match self.model {
            Model::A2 => &[STANDARD, EXPRESS],
            Model::A3 => &[STANDARD, EXPRESS, BOOST],
        }
    }

    fn info(&self) -> DeviceInfo {
        match self.model {
            Model::A2 => DeviceInfo {
                model: 0x28,
                firmware: 0x0114,
                hardware: 5,
                serial: *b"EMULATED-A2-0001",
            },
            Model::A3 => DeviceInfo {
                model: 0x31,
                firmware: 0x011A,
                hardware: 6,
                serial: *b"EMULATED-A3-0001",
            },
        }
    }

    /// Takes the host's bytes at `now` (seconds); the lidar's answers.
    pub fn handle(&mut self, bytes: &[u8], now: f64) -> Vec<u8> {
        self.reader.push(bytes);
        let mut out = Vec::new();
        while let Some(r) = self.reader.next_request() {
            out.extend(self.request(r.cmd, &r.payload, now));
        }
        out
    }

    fn request(&mut self, command: u8, payload: &[u8], now: f64) -> Vec<u8> {
        match command {
            cmd::STOP | cmd::RESET => {
                self.scanning = None;
                Vec::new()
            }
            cmd::GET_ACC_BOARD_FLAG => answer(ans::ACC_BOARD_FLAG, &1u32.to_le_bytes()),
            cmd::SET_MOTOR_PWM => {
                self.motor_pwm = payload
                    .get(..2)
                    .map_or(0, |p| u16::from_le_bytes([p[0], p[1]]));
                Vec::new()
            }
            cmd::GET_INFO => answer(ans::DEVINFO, &self.info().encode()),
            cmd::GET_HEALTH => answer(ans::DEVHEALTH, &[0, 0, 0]),
            cmd::GET_SAMPLERATE => {
                let mut d = (STANDARD.us_per_sample as u16).to_le_bytes().to_vec();
                d.extend_from_slice(&(EXPRESS.us_per_sample as u16).to_le_bytes());
                answer(ans::SAMPLE_RATE, &d)
            }
            cmd::GET_LIDAR_CONF if self.info().has_lidar_conf() => self.lidar_conf(payload),
            cmd::SCAN | cmd::FORCE_SCAN => self.start(STANDARD, now),
            cmd::EXPRESS_SCAN => {
                let working = payload.first().copied().unwrap_or(0);
                let mode = match (self.model, working) {
                    (Model::A3, 2) => BOOST,
                    _ => EXPRESS,
                };
                self.start(mode, now)
            }
            // unknown commands get no answer, as the firmware gives none
            _ => Vec::new(),
        }
    }

    fn lidar_conf(&self, payload: &[u8]) -> Vec<u8> {
        let Some(t) = payload
            .get(..4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        else {
            return Vec::new();
        };
        let id = payload
            .get(4..6)
            .map_or(0, |b| usize::from(u16::from_le_bytes([b[0], b[1]])));
        let modes = self.modes();
        let mode = modes.get(id).copied().unwrap_or(STANDARD);
        let value: Vec<u8> = match t {
            conf::SCAN_MODE_COUNT => (modes.len() as u16).to_le_bytes().to_vec(),
            conf::SCAN_MODE_US_PER_SAMPLE => {
                (((mode.us_per_sample * 256.0) as u32).to_le_bytes()).to_vec()
            }
            conf::SCAN_MODE_MAX_DISTANCE => ((25u32 << 8).to_le_bytes()).to_vec(),
            conf::SCAN_MODE_ANS_TYPE => vec![mode.ans_type],
            conf::SCAN_MODE_TYPICAL => ((modes.len() as u16 - 1).to_le_bytes()).to_vec(),
            conf::SCAN_MODE_NAME => {
                let mut n = mode.name.as_bytes().to_vec();
                n.push(0);
                n
            }
            _ => return Vec::new(),
        };
        answer(ans::GET_LIDAR_CONF, &protocol::conf_answer(t, &value))
    }

    fn start(&mut self, mode: Mode, now: f64) -> Vec<u8> {
        self.scanning = Some((mode, now));
        self.sent = 0;
        let size = match mode.ans_type {
            ans::MEASUREMENT => 5,
            ans::MEASUREMENT_CAPSULED => Capsule::LEN,
            _ => UltraCapsule::LEN,
        } as u32;
        Descriptor {
            size,
            subtype: 1,
            ans_type: mode.ans_type,
        }
        .encode()
        .to_vec()
    }

    /// Whether a scan streams.
    pub fn scanning(&self) -> bool {
        self.scanning.is_some()
    }

    /// The measurements due by `now` (seconds) since the last call.
    pub fn stream(&mut self, now: f64) -> Vec<u8> {
        let Some((mode, since)) = self.scanning else {
            return Vec::new();
        };
        let per_rev = (1e6 / SCAN_HZ / mode.us_per_sample).round() as u64;
        let due = ((now - since).max(0.0) * 1e6 / mode.us_per_sample) as u64;
        let angle = |i: u64| (i % per_rev) as f64 * 360.0 / per_rev as f64;
        let mut out = Vec::new();
        match mode.ans_type {
            ans::MEASUREMENT => {
                while self.sent < due {
                    let i = self.sent;
                    let a = angle(i);
                    let mm = (room(a) * 1000.0).round() as u16;
                    out.extend(protocol::encode_standard(
                        (a * 64.0) as u16,
                        mm.saturating_mul(4),
                        47,
                        i.is_multiple_of(per_rev),
                    ));
                    self.sent += 1;
                }
            }
            ans::MEASUREMENT_CAPSULED => {
                while self.sent + 32 <= due {
                    let i = self.sent;
                    let d = |k: u64| {
                        (((room(angle(i + k)) * 1000.0).round() as u16).saturating_mul(4)) & 0xFFFC
                    };
                    let cabins = std::array::from_fn(|c| (d(2 * c as u64), d(2 * c as u64 + 1), 0));
                    let first = if i == 0 { 0x8000 } else { 0 };
                    out.extend(
                        Capsule {
                            start_angle_sync_q6: (angle(i) * 64.0) as u16 | first,
                            cabins,
                        }
                        .encode(),
                    );
                    self.sent += 32;
                }
            }
            _ => {
                while self.sent + 96 <= due {
                    out.extend(self.ultra_capsule(self.sent, per_rev).encode());
                    self.sent += 96;
                }
            }
        }
        out
    }

    /// The ultra capsule of samples `i..i + 96`: each measurement aimed so that, less the
    /// optics' offset the SDK subtracts, it falls on its even place.
    fn ultra_capsule(&self, i: u64, per_rev: u64) -> UltraCapsule {
        let step = 360.0 / per_rev as f64;
        let at = |k: u64| ((i + k) % per_rev) as f64 * step;
        // the distance seen along the direction the SDK will give this sample
        let mm = |k: u64| -> u32 {
            let mut d = room(at(k));
            for _ in 0..2 {
                let off = protocol::ultra_offset_q16((d * 4000.0) as i64) as f64 / 65536.0;
                d = room(at(k) - off);
            }
            (d * 1000.0).round() as u32
        };
        let majors: Vec<u32> = (0..=32)
            .map(|c| protocol::varbitscale_encode(mm(3 * c)))
            .collect();
        let decoded = |scaled: u32| protocol::varbitscale_decode(scaled);
        let cabins = std::array::from_fn(|c| {
            let (base1, level1) = decoded(majors[c]);
            let (base2, level2) = decoded(majors[c + 1]);
            let predict = |mm: u32, base: u32, level: u32| -> u32 {
                let delta = (mm as i64 - base as i64) >> level;
                if (-511..=510).contains(&delta) {
                    (delta as u32) & 0x3FF
                } else {
                    0x1FF // no measurement
                }
            };
            majors[c]
                | predict(mm(3 * c as u64 + 1), base1, level1) << 12
                | predict(mm(3 * c as u64 + 2), base2, level2) << 22
        });
        let first = if i == 0 { 0x8000 } else { 0 };
        UltraCapsule {
            start_angle_sync_q6: (at(0) * 64.0) as u16 | first,
            cabins,
        }
    }
}

/// A lidar served on a pseudo-terminal; stops (and removes its link) when dropped.
pub struct LidarHandle {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    link: Option<(PathBuf, PathBuf)>,
}

impl Drop for LidarHandle {
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

/// Serves `lidar` on `port` in a thread until the handle is dropped: answers as requests
/// come, streams its scan as it turns.
pub fn serve(mut port: impl MtxPort, mut lidar: EmulatedLidar) -> std::io::Result<LidarHandle> {
    let stop = Arc::new(AtomicBool::new(false));
    let st = stop.clone();
    let thread = std::thread::Builder::new()
        .name("rplidar".into())
        .spawn(move || {
            let start = Instant::now();
            let mut buf = [0u8; 256];
            let _ = port.set_read_timeout(Duration::from_millis(2));
            while !st.load(Ordering::SeqCst) {
                let now = start.elapsed().as_secs_f64();
                match port.read(&mut buf) {
                    Ok(n) => {
                        let answer = lidar.handle(&buf[..n], now);
                        let _ = port.write_all(&answer);
                    }
                    Err(e)
                        if matches!(
                            e.kind(),
                            ErrorKind::TimedOut | ErrorKind::Interrupted | ErrorKind::WouldBlock
                        ) => {}
                    Err(e) => {
                        // the host side closed (pty hang-up): wait for it to come back
                        tracing::trace!("emulated RPLidar: {e}");
                        std::thread::sleep(Duration::from_millis(10));
                    }
                }
                let out = lidar.stream(start.elapsed().as_secs_f64());
                if !out.is_empty() {
                    let _ = port.write_all(&out);
                }
            }
        })?;
    Ok(LidarHandle {
        stop,
        thread: Some(thread),
        link: None,
    })
}

/// Serves a new lidar on a pseudo-terminal reachable as `link` (the `serial_port` a
/// robot file names, or the path the device is pointed at); the terminal's own path too.
pub fn pty_link(link: &Path, model: Model) -> std::io::Result<(LidarHandle, PathBuf)> {
    let (port, path) = pty()?;
    if link.symlink_metadata().is_ok() {
        std::fs::remove_file(link)?;
    }
    std::os::unix::fs::symlink(&path, link)?;
    let mut handle = serve(port, EmulatedLidar::new(model))?;
    handle.link = Some((link.to_path_buf(), path.clone()));
    Ok((handle, path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rplidar::protocol::{request, CapsuleDecoder, UltraCapsuleDecoder};

    fn descriptor(bytes: &[u8]) -> Descriptor {
        Descriptor::decode(&bytes[..7]).unwrap()
    }

    #[test]
    fn it_answers_the_sdks_queries() {
        let mut l = EmulatedLidar::new(Model::A3);
        let info = l.handle(&request(cmd::GET_INFO, &[]), 0.0);
        assert_eq!(descriptor(&info).ans_type, ans::DEVINFO);
        assert!(DeviceInfo::decode(&info[7..]).unwrap().has_lidar_conf());
        let count = l.handle(
            &request(
                cmd::GET_LIDAR_CONF,
                &protocol::conf_payload(conf::SCAN_MODE_COUNT, None),
            ),
            0.0,
        );
        assert_eq!(
            protocol::conf_value(conf::SCAN_MODE_COUNT, &count[7..]).unwrap(),
            [3, 0]
        );
        let name = l.handle(
            &request(
                cmd::GET_LIDAR_CONF,
                &protocol::conf_payload(conf::SCAN_MODE_NAME, Some(2)),
            ),
            0.0,
        );
        assert_eq!(
            protocol::conf_value(conf::SCAN_MODE_NAME, &name[7..]).unwrap(),
            b"Boost\0"
        );
        assert!(l
            .handle(&request(cmd::SET_MOTOR_PWM, &600u16.to_le_bytes()), 0.0)
            .is_empty());
        assert_eq!(l.motor_pwm, 600);
        // the A2's firmware predates the lidar configuration: no answer
        let mut a2 = EmulatedLidar::new(Model::A2);
        assert!(a2
            .handle(
                &request(
                    cmd::GET_LIDAR_CONF,
                    &protocol::conf_payload(conf::SCAN_MODE_COUNT, None)
                ),
                0.0
            )
            .is_empty());
    }

    /// Decoded measurements against the room, mirrored or not as they come from the lidar.
    fn check(nodes: &[protocol::Node], what: &str) {
        assert!(nodes.len() > 100, "{what}: {} measurements", nodes.len());
        let mut worst = 0.0f64;
        for n in nodes.iter().filter(|n| n.dist_mm_q2 > 0) {
            let expected = room(n.angle_deg());
            worst = worst.max((n.distance_m() - expected).abs());
        }
        assert!(worst < 0.03, "{what}: a measurement off by {worst} m");
    }

    #[test]
    fn standard_express_and_boost_scans_are_the_room() {
        for (model, express, what) in [
            (Model::A2, None, "standard"),
            (Model::A2, Some(0), "express"),
            (Model::A3, Some(2), "boost"),
        ] {
            let mut l = EmulatedLidar::new(model);
            let start = match express {
                None => l.handle(&request(cmd::SCAN, &[]), 0.0),
                Some(m) => l.handle(&request(cmd::EXPRESS_SCAN, &[m, 0, 0, 0, 0]), 0.0),
            };
            let d = descriptor(&start);
            let bytes = l.stream(0.25);
            let nodes: Vec<protocol::Node> = match d.ans_type {
                ans::MEASUREMENT => bytes
                    .chunks_exact(5)
                    .filter_map(|c| protocol::decode_standard(c.try_into().unwrap()))
                    .collect(),
                ans::MEASUREMENT_CAPSULED => {
                    let mut dec = CapsuleDecoder::default();
                    bytes
                        .chunks_exact(Capsule::LEN)
                        .flat_map(|c| dec.push(Capsule::decode(c).unwrap()))
                        .collect()
                }
                _ => {
                    let mut dec = UltraCapsuleDecoder::default();
                    bytes
                        .chunks_exact(UltraCapsule::LEN)
                        .flat_map(|c| dec.push(UltraCapsule::decode(c).unwrap()))
                        .collect()
                }
            };
            check(&nodes, what);
            assert!(
                nodes.iter().filter(|n| n.sync()).count() >= 2,
                "{what}: revolutions"
            );
        }
    }
}
