//! `rpLidar2` and `rpLidar3` (robotology/yarp-device-rplidar): a Slamtec RPLidar on a
//! serial line as a YARP 2D laser (`IRangefinder2D`), each with the open sequence its
//! SDK 1.12 runs (see the crate's README): `rpLidar2` for A1/A2 lidars (standard or
//! express scans, legacy measurements), `rpLidar3` for A2/A3 (the scan mode named
//! `scan_mode`, HQ measurements). A thread reads the lidar's stream; each revolution
//! becomes a scan as C++ makes it (angles mirrored, `sample_buffer_life`, the `SENSOR`
//! and `SKIP` limits). `YARP_RPLIDAR_PORTS` ([`PORTS_ENV`]) moves a lidar to another
//! serial port than its file names.

use std::io::{Read, Write};
use std::sync::Arc;
use std::time::{Duration, Instant};

use parking_lot::Mutex;
use yarp_devices::device_thread::{stopped, DeviceThread};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::rangefinder::geometry::{LaserGeometry, Lidar2DParams};
use yarp_devices::rangefinder::{IRangefinder2D, LaserStatus};
use yarp_proto::Property;

use crate::protocol::{
    self, ans, cmd, conf, Capsule, CapsuleDecoder, Descriptor, DeviceInfo, Node, UltraCapsule,
    UltraCapsuleDecoder,
};

pub const RPLIDAR2: &str = "rpLidar2";
pub const RPLIDAR3: &str = "rpLidar3";

yarp_devices::device_params! {
    /// What `rpLidar2` and `rpLidar3` read besides the `SENSOR` and `SKIP` groups.
    pub struct RpLidarParams for "rpLidar3" {
        /// The lidar's serial port
        "GENERAL::serial_port" serial_port: String = required,
        /// Its baud rate
        "GENERAL::serial_baudrate" serial_baudrate: u32 = required,
        /// Revolutions a scan keeps its measurements (1: every revolution starts anew)
        "GENERAL::sample_buffer_life" sample_buffer_life: i64 = required,
        /// The reading thread's period (0: as fast as the lidar sends)
        "GENERAL::thread_period" thread_period: i64 = optional; "ms",
        /// rpLidar2: the motor's PWM (1..1022; absent: the SDK's default)
        "GENERAL::motor_pwm" motor_pwm_2: i64 = optional,
        /// rpLidar3: the motor's PWM (1..1022)
        "RPLIDAR::motor_pwm" motor_pwm_3: i64 = 600,
        /// rpLidar3: the scan mode, by name
        "RPLIDAR::scan_mode" scan_mode: String = "Boost",
    }
}

/// Moves a lidar from the serial port its file names to another (`FROM=TO,FROM=TO`, e.g.
/// the pseudo-terminals of `icub-robot-emulator`'s lidars for `/dev/ttyUSB0` and
/// `/dev/ttyUSB1`): ours only, C++ has no such variable.
pub const PORTS_ENV: &str = "YARP_RPLIDAR_PORTS";

/// The port to open for the file's `port`, as [`PORTS_ENV`] maps it.
fn mapped_port(port: &str) -> String {
    let map = std::env::var(PORTS_ENV).unwrap_or_default();
    map.split(',')
        .filter_map(|pair| pair.split_once('='))
        .find(|(from, _)| from.trim() == port)
        .map_or_else(|| port.to_string(), |(_, to)| to.trim().to_string())
}

/// The SDK's answer timeout.
const TIMEOUT: Duration = Duration::from_secs(2);
/// The SDK's default motor PWM.
const DEFAULT_PWM: u16 = 660;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Variant {
    Two,
    Three,
}

/// The serial link to the lidar, as the SDK uses it.
struct Link {
    port: Box<dyn serialport::SerialPort>,
    pending: Vec<u8>,
    device: &'static str,
}

impl Link {
    fn fail(&self, why: impl ToString) -> DeviceError {
        DeviceError::failed(self.device, why)
    }

    fn send(&mut self, command: u8, payload: &[u8]) -> DevResult<()> {
        let bytes = protocol::request(command, payload);
        self.port
            .write_all(&bytes)
            .map_err(|e| self.fail(format!("writing to the lidar: {e}")))
    }

    /// Reads what came (waits at most the port's timeout).
    fn fill(&mut self) {
        let mut buf = [0u8; 1024];
        if let Ok(n) = self.port.read(&mut buf) {
            self.pending.extend_from_slice(&buf[..n]);
        }
    }

    /// The next answer descriptor within the SDK's timeout: of type `want`, with at
    /// least `min_size` bytes of data.
    fn descriptor(&mut self, want: u8, min_size: u32) -> DevResult<Descriptor> {
        let start = Instant::now();
        loop {
            if let Some(at) = self.pending.windows(2).position(|w| w == [0xA5, 0x5A]) {
                if self.pending.len() >= at + Descriptor::LEN {
                    let d = Descriptor::decode(&self.pending[at..at + Descriptor::LEN])
                        .map_err(|e| self.fail(e))?;
                    self.pending.drain(..at + Descriptor::LEN);
                    if d.ans_type != want || d.size < min_size {
                        return Err(self.fail(format!(
                            "the lidar answered type {:#x} of {} bytes, expected {want:#x}",
                            d.ans_type, d.size
                        )));
                    }
                    return Ok(d);
                }
            }
            if start.elapsed() > TIMEOUT {
                return Err(DeviceError::Timeout {
                    device: self.device.into(),
                    command: format!("answer {want:#x}"),
                    after: TIMEOUT,
                });
            }
            self.fill();
        }
    }

    /// `n` bytes of data within the timeout.
    fn data(&mut self, n: usize) -> DevResult<Vec<u8>> {
        let start = Instant::now();
        while self.pending.len() < n {
            if start.elapsed() > TIMEOUT {
                return Err(DeviceError::Timeout {
                    device: self.device.into(),
                    command: "answer data".into(),
                    after: TIMEOUT,
                });
            }
            self.fill();
        }
        Ok(self.pending.drain(..n).collect())
    }

    /// A request answered once with data of type `want`.
    fn ask(&mut self, command: u8, payload: &[u8], want: u8) -> DevResult<Vec<u8>> {
        self.pending.clear();
        self.send(command, payload)?;
        let d = self.descriptor(want, 0)?;
        self.data(d.size as usize)
    }

    fn info(&mut self) -> DevResult<DeviceInfo> {
        let data = self.ask(cmd::GET_INFO, &[], ans::DEVINFO)?;
        DeviceInfo::decode(&data).map_err(|e| self.fail(e))
    }

    fn lidar_conf(&mut self, conf_type: u32, mode: Option<u16>) -> DevResult<Vec<u8>> {
        let data = self.ask(
            cmd::GET_LIDAR_CONF,
            &protocol::conf_payload(conf_type, mode),
            ans::GET_LIDAR_CONF,
        )?;
        protocol::conf_value(conf_type, &data)
            .map(<[u8]>::to_vec)
            .map_err(|e| self.fail(e))
    }

    fn pwm(&mut self, pwm: u16) -> DevResult<()> {
        self.send(cmd::SET_MOTOR_PWM, &pwm.to_le_bytes())
    }

    fn stop(&mut self) -> DevResult<()> {
        self.send(cmd::STOP, &[])?;
        std::thread::sleep(Duration::from_millis(1));
        Ok(())
    }
}

/// One scan mode of an `rpLidar3` lidar.
struct ScanMode {
    id: u16,
    ans_type: u8,
    name: String,
}

/// What the reading thread and the interface share.
struct Shared {
    data: Vec<f64>,
    stamp: f64,
    revolutions: u64,
}

pub struct RpLidar {
    variant: Variant,
    name: &'static str,
    geometry: LaserGeometry,
    info: Option<DeviceInfo>,
    shared: Arc<Mutex<Shared>>,
    thread: DeviceThread,
}

impl RpLidar {
    pub fn two() -> RpLidar {
        Self::new(Variant::Two, RPLIDAR2)
    }

    pub fn three() -> RpLidar {
        Self::new(Variant::Three, RPLIDAR3)
    }

    fn new(variant: Variant, name: &'static str) -> RpLidar {
        RpLidar {
            variant,
            name,
            geometry: LaserGeometry::unset(),
            info: None,
            shared: Arc::new(Mutex::new(Shared {
                data: Vec::new(),
                stamp: 0.0,
                revolutions: 0,
            })),
            thread: DeviceThread::default(),
        }
    }

    /// The SDK's start for this device: the scan started, its answer type.
    fn start(&self, link: &mut Link, p: &RpLidarParams, flag: bool) -> DevResult<(u8, DeviceInfo)> {
        let info = link.info()?;
        let motor = |link: &mut Link, pwm: u16| -> DevResult<()> {
            if info.is_tof() {
                return Ok(());
            }
            if flag {
                link.pwm(pwm)?;
            } else {
                let _ = link.port.write_data_terminal_ready(false);
            }
            std::thread::sleep(Duration::from_millis(500));
            Ok(())
        };
        match self.variant {
            Variant::Two => {
                let express = info.has_express() && {
                    link.info()?;
                    link.ask(cmd::GET_SAMPLERATE, &[], ans::SAMPLE_RATE)?;
                    true
                };
                let pwm = match p.motor_pwm_2 {
                    Some(v) if (1..=1022).contains(&v) => v as u16,
                    Some(v) => return Err(bad(self.name, "GENERAL::motor_pwm", "1..1022", v)),
                    None => DEFAULT_PWM,
                };
                motor(link, pwm)?;
                if express && info.has_lidar_conf() {
                    let typical = link.lidar_conf(conf::SCAN_MODE_TYPICAL, None)?;
                    let mode = u16::from_le_bytes([typical[0], *typical.get(1).unwrap_or(&0)]);
                    if mode != 0 {
                        let ans_type = *link
                            .lidar_conf(conf::SCAN_MODE_ANS_TYPE, Some(mode))?
                            .first()
                            .unwrap_or(&0);
                        let working = if mode <= 1 { 0 } else { mode as u8 };
                        return self.express(link, working, ans_type).map(|t| (t, info));
                    }
                } else if express {
                    link.info()?;
                    link.ask(cmd::GET_SAMPLERATE, &[], ans::SAMPLE_RATE)?;
                    return self
                        .express(link, 0, ans::MEASUREMENT_CAPSULED)
                        .map(|t| (t, info));
                }
                link.stop()?;
                link.pending.clear();
                link.send(cmd::SCAN, &[])?;
                link.descriptor(ans::MEASUREMENT, 5)?;
                Ok((ans::MEASUREMENT, info))
            }
            Variant::Three => {
                if !(1..=1022).contains(&p.motor_pwm_3) {
                    return Err(bad(
                        self.name,
                        "RPLIDAR::motor_pwm",
                        "1..1022",
                        p.motor_pwm_3,
                    ));
                }
                motor(link, DEFAULT_PWM)?;
                link.pwm(p.motor_pwm_3 as u16)?;
                let modes = if info.has_lidar_conf() {
                    scan_modes(link)?
                } else {
                    Vec::new()
                };
                let Some(mode) = modes.iter().find(|m| m.name == p.scan_mode) else {
                    return Err(link.fail(format!(
                        "the lidar has no scan mode {} (it has {})",
                        p.scan_mode,
                        if modes.is_empty() {
                            "Standard and Express".into()
                        } else {
                            modes
                                .iter()
                                .map(|m| m.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        }
                    )));
                };
                link.stop()?;
                link.info()?;
                for t in [
                    conf::SCAN_MODE_US_PER_SAMPLE,
                    conf::SCAN_MODE_MAX_DISTANCE,
                    conf::SCAN_MODE_ANS_TYPE,
                    conf::SCAN_MODE_NAME,
                    conf::SCAN_MODE_ANS_TYPE,
                ] {
                    link.lidar_conf(t, Some(mode.id))?;
                }
                self.express(link, mode.id as u8, mode.ans_type)
                    .map(|t| (t, info))
            }
        }
    }

    fn express(&self, link: &mut Link, working_mode: u8, ans_type: u8) -> DevResult<u8> {
        link.stop()?;
        link.pending.clear();
        link.send(cmd::EXPRESS_SCAN, &[working_mode, 0, 0, 0, 0])?;
        let size = match ans_type {
            ans::MEASUREMENT_CAPSULED_ULTRA => UltraCapsule::LEN,
            ans::MEASUREMENT => 5,
            _ => Capsule::LEN,
        } as u32;
        link.descriptor(ans_type, size)?;
        Ok(ans_type)
    }
}

fn bad(device: &str, param: &str, expected: &'static str, got: impl ToString) -> DeviceError {
    DeviceError::BadParam {
        device: device.into(),
        param: param.into(),
        expected,
        got: got.to_string(),
    }
}

/// `rpLidar3`'s scan modes (firmware 1.24 and later).
fn scan_modes(link: &mut Link) -> DevResult<Vec<ScanMode>> {
    link.info()?;
    let count = link.lidar_conf(conf::SCAN_MODE_COUNT, None)?;
    let n = u16::from_le_bytes([count[0], *count.get(1).unwrap_or(&0)]);
    let mut modes = Vec::new();
    for id in 0..n {
        link.lidar_conf(conf::SCAN_MODE_US_PER_SAMPLE, Some(id))?;
        link.lidar_conf(conf::SCAN_MODE_MAX_DISTANCE, Some(id))?;
        let ans_type = *link
            .lidar_conf(conf::SCAN_MODE_ANS_TYPE, Some(id))?
            .first()
            .unwrap_or(&0);
        let name = link.lidar_conf(conf::SCAN_MODE_NAME, Some(id))?;
        let name = String::from_utf8_lossy(name.split(|&b| b == 0).next().unwrap_or_default())
            .into_owned();
        modes.push(ScanMode { id, ans_type, name });
    }
    Ok(modes)
}

fn now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// Turns the lidar's stream into measurements.
enum Stream {
    Standard,
    Express(CapsuleDecoder),
    Ultra(UltraCapsuleDecoder),
}

impl Stream {
    fn unit(&self) -> usize {
        match self {
            Stream::Standard => 5,
            Stream::Express(_) => Capsule::LEN,
            Stream::Ultra(_) => UltraCapsule::LEN,
        }
    }

    /// Measurements from `buf`, consuming what it used; bytes out of sync are skipped.
    fn decode(&mut self, buf: &mut Vec<u8>) -> Vec<Node> {
        let mut out = Vec::new();
        let unit = self.unit();
        while buf.len() >= unit {
            let chunk: Vec<u8> = buf[..unit].to_vec();
            let used = match self {
                Stream::Standard => {
                    protocol::decode_standard(chunk[..5].try_into().expect("5 bytes"))
                        .map(|n| out.push(n))
                        .is_some()
                }
                Stream::Express(d) => Capsule::decode(&chunk)
                    .map(|c| out.extend(d.push(c)))
                    .is_ok(),
                Stream::Ultra(d) => UltraCapsule::decode(&chunk)
                    .map(|c| out.extend(d.push(c)))
                    .is_ok(),
            };
            // out of sync: move on by a byte, as the SDK's readers do
            buf.drain(..if used { unit } else { 1 });
        }
        out
    }
}

impl DeviceDriver for RpLidar {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        let mut p = RpLidarParams::PARAMS.to_vec();
        p.extend_from_slice(Lidar2DParams::PARAMS);
        p
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = RpLidarParams::read_as(self.name, config)?;
        let mut geometry = LaserGeometry::unset();
        if self.variant == Variant::Two {
            (geometry.min_distance, geometry.max_distance) = (0.1, 5.0);
        }
        geometry.configure(Lidar2DParams::parse(self.name, config)?, self.name)?;
        let path = mapped_port(&p.serial_port);
        let port = serialport::new(&path, p.serial_baudrate)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(20))
            .open()
            .map_err(|e| {
                DeviceError::failed(
                    self.name,
                    format!("cannot open the serial port {path}: {e}"),
                )
            })?;
        let mut link = Link {
            port,
            pending: Vec::new(),
            device: self.name,
        };
        let _ = link.port.clear(serialport::ClearBuffer::All);
        let _ = link.port.write_data_terminal_ready(false);
        // connect: the accessory board's flag, then the motor stopped
        let flag = link
            .ask(cmd::GET_ACC_BOARD_FLAG, &[0, 0, 0, 0], ans::ACC_BOARD_FLAG)
            .map(|d| d.first().is_some_and(|f| f & 1 != 0))
            .unwrap_or(false);
        if flag {
            link.pwm(0)?;
        } else {
            let _ = link.port.write_data_terminal_ready(true);
        }
        std::thread::sleep(Duration::from_millis(500));
        let (ans_type, info) = self.start(&mut link, &p, flag)?;
        self.info = Some(info);
        let n = geometry.samples();
        *self.shared.lock() = Shared {
            data: vec![f64::INFINITY; n],
            stamp: now_s(),
            revolutions: 0,
        };
        self.geometry = geometry.clone();
        let (shared, variant) = (self.shared.clone(), self.variant);
        let life = p.sample_buffer_life.max(0) as u64;
        let mut stream = match ans_type {
            ans::MEASUREMENT => Stream::Standard,
            ans::MEASUREMENT_CAPSULED_ULTRA => Stream::Ultra(UltraCapsuleDecoder::default()),
            _ => Stream::Express(CapsuleDecoder::default()),
        };
        self.thread
            .spawn(self.name.into(), move |stop| {
                let mut revolution: Vec<Node> = Vec::new();
                let mut data = vec![f64::INFINITY; n];
                let mut count = 0u64;
                while !stopped(stop) {
                    link.fill();
                    let mut pending = std::mem::take(&mut link.pending);
                    for node in stream.decode(&mut pending) {
                        if node.sync() && !revolution.is_empty() {
                            if revolution[0].sync() {
                                count += 1;
                                fill_scan(&mut data, &revolution, variant, &geometry, life, count);
                                let mut s = shared.lock();
                                s.data.clone_from(&data);
                                s.stamp = now_s();
                                s.revolutions = count;
                            }
                            revolution.clear();
                        }
                        revolution.push(node);
                    }
                    link.pending = pending;
                }
                // close: motor stopped, scan stopped
                let _ = link.pwm(0);
                let _ = link.stop();
            })
            .map_err(|e| DeviceError::failed(self.name, e))?;
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.thread.stop();
        Ok(())
    }

    yarp_devices::views!(as_rangefinder_2d);
}

/// One revolution into the scan, as C++ fills it: a fresh all-infinity scan every
/// `life` revolutions, each measurement at its mirrored angle, then the limits.
fn fill_scan(
    data: &mut [f64],
    nodes: &[Node],
    variant: Variant,
    g: &LaserGeometry,
    life: u64,
    count: u64,
) {
    if life > 0 && count.is_multiple_of(life) {
        data.iter_mut().for_each(|d| *d = f64::INFINITY);
    }
    let mut sorted = nodes.to_vec();
    sorted.sort_by_key(|n| n.angle_z_q14);
    for n in &sorted {
        let distance = n.distance_m();
        let mut angle = match variant {
            // rpLidar2 reads the legacy form: q6 degrees
            Variant::Two => f64::from((u32::from(n.angle_z_q14) * 90) >> 8) / 64.0,
            Variant::Three => f64::from(n.angle_z_q14) * 90.0 / 16384.0,
        };
        angle = 360.0 - angle;
        if angle >= 360.0 {
            angle -= 360.0;
        }
        let value = if n.quality >> 2 == 0 || distance == 0.0 {
            f64::INFINITY
        } else {
            distance
        };
        let elem = (angle / g.resolution) as i64;
        if elem >= 0 && (elem as usize) < data.len() {
            data[elem as usize] = value;
        }
    }
    g.apply_limits(data);
}

impl IRangefinder2D for RpLidar {
    fn get_raw_data(&mut self) -> DevResult<(Vec<f64>, f64)> {
        let s = self.shared.lock();
        Ok((s.data.clone(), s.stamp))
    }
    fn get_device_status(&mut self) -> DevResult<LaserStatus> {
        Ok(LaserStatus::OkStandby)
    }
    fn get_distance_range(&mut self) -> DevResult<(f64, f64)> {
        Ok((self.geometry.min_distance, self.geometry.max_distance))
    }
    fn set_distance_range(&mut self, min: f64, max: f64) -> DevResult<()> {
        (self.geometry.min_distance, self.geometry.max_distance) = (min, max);
        Ok(())
    }
    fn get_scan_limits(&mut self) -> DevResult<(f64, f64)> {
        Ok((self.geometry.min_angle, self.geometry.max_angle))
    }
    fn set_scan_limits(&mut self, min: f64, max: f64) -> DevResult<()> {
        (self.geometry.min_angle, self.geometry.max_angle) = (min, max);
        Ok(())
    }
    fn get_horizontal_resolution(&mut self) -> DevResult<f64> {
        Ok(self.geometry.resolution)
    }
    fn set_horizontal_resolution(&mut self, step: f64) -> DevResult<()> {
        self.geometry.resolution = step;
        Ok(())
    }
    fn get_scan_rate(&mut self) -> DevResult<f64> {
        Ok(0.0)
    }
    fn set_scan_rate(&mut self, _rate: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "rpLidar: setScanRate is not implemented by the device",
        ))
    }
    fn get_device_info(&mut self) -> DevResult<String> {
        let i = self.info.ok_or(DeviceError::NotOpen)?;
        let serial: String = i.serial.iter().map(|b| b.to_string()).collect();
        Ok(format!(
            "Firmware Version: {}\nHardware Version: {}\nModel: {}\nSerial Number:{serial}",
            i.firmware, i.hardware, i.model
        ))
    }
}
