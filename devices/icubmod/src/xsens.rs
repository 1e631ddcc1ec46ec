//! Xsens IMUs on a serial port, speaking the MT protocol of [`icub_can::xsens`]:
//! - `xsensmtx`, the MTx of the iCub head (icub-main's `XSensMTx`);
//! - `xsensmt`, an MTi 1/10/100/600-series sensor such as the ergoCub waist IMU
//!   (robotology's yarp-device-xsensmt, which drives it through Xsens' XDA library).
//!
//! Parameters: `serial` (default `/dev/ttyUSB0`), `sensor_name` and `frame_name`
//! (`xsensmtx`: both `sensor_imu_xsens`; `xsensmt`: `sensor_imu_xsensmt`, the frame
//! defaulting to the sensor name). `xsensmt` also takes `baud` (115200), `timeout`
//! (0.1 s), `xsensmt_period` (0.01 s) and the per-measure `xsensmt_euler_period`,
//! `xsensmt_acc_period`, `xsensmt_gyro_period`, `xsensmt_mag_period`,
//! `xsensmt_position_period`, `xsensmt_linear_velocity_period` (default `xsensmt_period`).
//! The `YARP_ICUB_XSENS_SERIAL` environment variable, when set, replaces `serial`, so a
//! robot's unmodified files can run against an emulated sensor (`icub-board-emulator
//! --xsens PATH`, `icub-eth-emulator --xsens PATH`).
//!
//! At open, `xsensmtx` as C++: 115200 baud, 8N2; `GoToConfig`, output mode calibrated +
//! orientation with Euler angles, `GoToMeasurement`. `xsensmt` as XDA does it: 8N1;
//! `GoToConfig`; device id, product code and firmware asked; a sensor that is no MTi is
//! refused, naming what it is; the output configuration of its kind, as C++ asks it
//! (IMU: acceleration, rate of turn, magnetic field; VRU/AHRS: Euler angles too; GNSS:
//! also latitude/longitude, altitude and velocity) at `1 / period` Hz, float32 in ENU;
//! `GoToMeasurement`; then `MTData2`, each measure at its own rate.
//!
//! A reader thread keeps the latest of each measure. Interfaces: gyroscope (deg/s,
//! converted from the sensor's rad/s as C++ does), linear accelerometer (m/s²),
//! magnetometer, orientation (roll, pitch, yaw in degrees), and C++'s 12-channel
//! `IGenericSensor` read as `IAnalogSensor`: `[roll pitch yaw, acc xyz, gyro xyz (deg/s),
//! mag xyz]`.
//!
//! Unlike C++ (whose multiple-analog-sensors status is always OK), a sensor that sent
//! nothing for its timeout (`xsensmtx`: C++'s 0.5 s; `xsensmt`: `timeout`) reads as
//! `Timeout` and its measures are errors; a sensor that does not answer `GoToConfig`
//! fails the open within 2 s, naming the port. A serial port that fails while measuring
//! is reported and opened and configured again every second, so a replugged sensor (or a
//! restarted emulator) measures again.

use crate::common::device_id;
use icub_can::xsens::mti::{self, Mtdata2, MtiKind, OutputConfig};
use icub_can::xsens::{
    mid, Decoder, Message, Sample, OUTPUT_MODE_CALIB, OUTPUT_MODE_ORIENT, OUTPUT_SETTINGS_EULER,
};
use parking_lot::Mutex;
use serialport::SerialPort;
use std::io::ErrorKind;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::device_thread::{stopped, DeviceThread};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::sensors::interfaces::*;
use yarp_devices::sensors::params::now;
use yarp_proto::Property;

pub(crate) const MTX_NAME: &str = "xsensmtx";
pub(crate) const MT_NAME: &str = "xsensmt";
/// Replaces the `serial` parameter when set.
pub const SERIAL_ENV: &str = "YARP_ICUB_XSENS_SERIAL";
/// A period greater than zero.
fn positive_period(s: &f64) -> Result<(), &'static str> {
    match *s > 0.0 {
        true => Ok(()),
        false => Err("a period above 0 s"),
    }
}

yarp_devices::device_params! {
    /// What `xsensmt` and `xsensmtx` read (icub-main's XSensMTx and the MTi driver);
    /// `$XSENS_SERIAL` overrides `serial`. The `xsensmt_*` periods and `baud` are the MTi's.
    pub struct XsensParams for "xsensmt" {
        /// The serial port of the sensor
        serial: String = "/dev/ttyUSB0",
        /// Name of the sensor (and of its frame, unless frame_name is given)
        sensor_name: String = optional,
        /// Name of the sensor's frame
        frame_name: String = optional,
        /// Period of every measure without a period of its own
        xsensmt_period: f64 = 0.01; "s"; check positive_period,
        /// Period of the euler angles
        xsensmt_euler_period: f64 = optional; "s"; check positive_period,
        /// Period of the accelerometer
        xsensmt_acc_period: f64 = optional; "s"; check positive_period,
        /// Period of the gyroscope
        xsensmt_gyro_period: f64 = optional; "s"; check positive_period,
        /// Period of the magnetometer
        xsensmt_mag_period: f64 = optional; "s"; check positive_period,
        /// Period of the position
        xsensmt_position_period: f64 = optional; "s"; check positive_period,
        /// Period of the linear velocity
        xsensmt_linear_velocity_period: f64 = optional; "s"; check positive_period,
        /// Baud rate of the serial line
        baud: u32 = 115200; min 1,
        /// Time after which a sample is stale (at least 1 ms)
        timeout: f64 = optional; "s",
    }
}
/// `GoToConfig` attempts and the wait for each: a silent port is reported in 2 s.
const CONFIG_TRIES: usize = 4;
const CONFIG_ACK_TIMEOUT: Duration = Duration::from_millis(500);
/// The wait for the acknowledgements of a sensor that has answered (it answers in
/// milliseconds; the margin is for a loaded machine and an emulated sensor behind a pty).
const ACK_TIMEOUT: Duration = Duration::from_secs(2);

/// Which sensor, and how it is configured.
#[derive(Debug, Clone)]
enum Model {
    /// The MTx: `MTData` of calibrated data and Euler angles.
    Mtx,
    /// An MTi: `MTData2` at these rates (Hz): euler, acc, gyro, mag, position, velocity.
    Mti { baud: u32, hz: [u16; 6] },
}

impl Model {
    fn name(&self) -> &'static str {
        match self {
            Model::Mtx => MTX_NAME,
            Model::Mti { .. } => MT_NAME,
        }
    }
}

/// One measure, its YARP timestamp and when it arrived.
#[derive(Debug, Clone, Copy)]
struct Timed {
    v: [f64; 3],
    stamp: f64,
}

/// The latest of each measure, and when the sensor last sent anything.
#[derive(Debug, Clone, Copy, Default)]
struct Latest {
    euler: Option<Timed>,
    acc: Option<Timed>,
    gyr: Option<Timed>,
    mag: Option<Timed>,
    at: Option<Instant>,
}

impl Latest {
    fn update(
        &mut self,
        euler: Option<[f64; 3]>,
        acc: Option<[f64; 3]>,
        gyr: Option<[f64; 3]>,
        mag: Option<[f64; 3]>,
    ) {
        let stamp = now();
        let set = |slot: &mut Option<Timed>, v: Option<[f64; 3]>| {
            if let Some(v) = v {
                *slot = Some(Timed { v, stamp });
            }
        };
        set(&mut self.euler, euler);
        set(&mut self.acc, acc);
        set(&mut self.gyr, gyr);
        set(&mut self.mag, mag);
        self.at = Some(Instant::now());
    }
}

/// The `xsensmtx` and `xsensmt` devices.
pub struct XsensImu {
    model: Model,
    id: String,
    sensor_name: String,
    frame_name: String,
    stale_after: Duration,
    latest: Arc<Mutex<Latest>>,
    reader: DeviceThread,
}

impl XsensImu {
    fn with_model(model: Model, name: &str, stale_after: Duration) -> Self {
        XsensImu {
            id: model.name().into(),
            model,
            sensor_name: name.into(),
            frame_name: name.into(),
            stale_after,
            latest: Arc::default(),
            reader: DeviceThread::default(),
        }
    }

    /// `xsensmtx`: stale after C++'s read timeout (`TO_DEFAULT`, 0.5 s).
    pub fn mtx() -> Self {
        Self::with_model(Model::Mtx, "sensor_imu_xsens", Duration::from_millis(500))
    }

    /// `xsensmt`, configured at open.
    pub fn mt() -> Self {
        let model = Model::Mti {
            baud: 115_200,
            hz: [100; 6],
        };
        Self::with_model(model, "sensor_imu_xsensmt", Duration::from_millis(100))
    }
}

/// Sends `m` and waits for its acknowledgement (samples in between are skipped).
fn request(
    port: &mut dyn SerialPort,
    dec: &mut Decoder,
    m: &Message,
    timeout: Duration,
) -> Result<Message, String> {
    port.write_all(&m.encode())
        .map_err(|e| format!("write: {e}"))?;
    let want = m.mid.wrapping_add(1);
    let end = Instant::now() + timeout;
    let mut buf = [0u8; 256];
    while Instant::now() < end {
        while let Some(r) = dec.next_message() {
            match r {
                Ok(a) if a.mid == want => return Ok(a),
                Ok(a) if a.mid == mid::ERROR => {
                    let code = a.data.first().copied().unwrap_or(0);
                    return Err(format!(
                        "the sensor answered error {code:#04x} to {:#04x}",
                        m.mid
                    ));
                }
                _ => {}
            }
        }
        match port.read(&mut buf) {
            Ok(n) => dec.push(&buf[..n]),
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::Interrupted) => {}
            Err(e) => return Err(format!("read: {e}")),
        }
    }
    Err(format!(
        "no acknowledgement of {:#04x} within {timeout:?}",
        m.mid
    ))
}

/// `GoToConfig`, a few times: a measuring sensor may miss the first among its data.
fn go_to_config(port: &mut dyn SerialPort, dec: &mut Decoder, what: &str) -> Result<(), String> {
    let config = Message::new(mid::GO_TO_CONFIG, vec![]);
    let mut last = String::new();
    for _ in 0..CONFIG_TRIES {
        match request(port, dec, &config, CONFIG_ACK_TIMEOUT) {
            Ok(_) => return Ok(()),
            Err(e) => last = e,
        }
    }
    Err(format!("no {what} answers ({last})"))
}

fn ask(
    port: &mut dyn SerialPort,
    dec: &mut Decoder,
    mid: u8,
    data: Vec<u8>,
) -> Result<Vec<u8>, String> {
    request(port, dec, &Message::new(mid, data), ACK_TIMEOUT).map(|m| m.data)
}

/// C++ `XSensMTx::open`'s configuration sequence.
fn configure_mtx(port: &mut dyn SerialPort) -> Result<(), String> {
    let mut dec = Decoder::new();
    go_to_config(port, &mut dec, "MTx")?;
    let mode = (OUTPUT_MODE_CALIB | OUTPUT_MODE_ORIENT)
        .to_be_bytes()
        .to_vec();
    ask(port, &mut dec, mid::SET_OUTPUT_MODE, mode)?;
    let settings = OUTPUT_SETTINGS_EULER.to_be_bytes().to_vec();
    ask(port, &mut dec, mid::SET_OUTPUT_SETTINGS, settings)?;
    ask(port, &mut dec, mid::GO_TO_MEASUREMENT, vec![])?;
    Ok(())
}

/// What `xsensmt` does through XDA: identify the MTi, configure its outputs, measure.
fn configure_mti(port: &mut dyn SerialPort, hz: [u16; 6]) -> Result<String, String> {
    let mut dec = Decoder::new();
    go_to_config(port, &mut dec, "MTi")?;
    let did = ask(port, &mut dec, mid::REQ_DID, vec![])?;
    let device_id = match did.as_slice() {
        [a, b, c, d, ..] => u32::from_be_bytes([*a, *b, *c, *d]),
        _ => return Err(format!("a device id of {} bytes", did.len())),
    };
    // Older sensors know neither request: the device id then tells what they are.
    let code = ask(port, &mut dec, mti::mid::REQ_PRODUCT_CODE, vec![]).unwrap_or_default();
    let code = String::from_utf8_lossy(&code)
        .trim_matches(|c: char| c == '\0' || c.is_whitespace())
        .to_string();
    let fw = ask(port, &mut dec, mti::mid::REQ_FW_REV, vec![]).unwrap_or_default();
    let fw = match fw.as_slice() {
        [major, minor, rev, ..] => format!("{major}.{minor}.{rev}"),
        _ => "unknown".to_string(),
    };
    let kind = MtiKind::of(device_id, &code).ok_or_else(|| {
        format!("no MTi device found: device id {device_id:08X}, product code `{code}`")
    })?;
    let wanted = kind.output_configuration(hz);
    let applied = ask(
        port,
        &mut dec,
        mti::mid::SET_OUTPUT_CONFIGURATION,
        OutputConfig::encode_all(&wanted),
    )?;
    match OutputConfig::decode_all(&applied) {
        Ok(got) if got == wanted => {}
        Ok(got) => tracing::warn!("the MTi applied {got:?} for the asked {wanted:?}"),
        Err(e) => return Err(format!("its output configuration acknowledgement: {e}")),
    }
    ask(port, &mut dec, mid::GO_TO_MEASUREMENT, vec![])?;
    Ok(format!(
        "{code} ({kind:?}, device id {device_id:08X}, firmware {fw})"
    ))
}

/// Opens the serial port: 8 data bits, no parity, no flow control; the MTx with 2 stop
/// bits, as C++.
fn open_port(serial: &str, model: &Model) -> Result<Box<dyn SerialPort>, String> {
    let (baud, stop) = match model {
        Model::Mtx => (115_200, serialport::StopBits::Two),
        Model::Mti { baud, .. } => (*baud, serialport::StopBits::One),
    };
    serialport::new(serial, baud)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(stop)
        .flow_control(serialport::FlowControl::None)
        .timeout(Duration::from_millis(20))
        .open()
        .map_err(|e| format!("cannot open the serial port: {e}"))
}

/// Opens and configures the sensor; what it is.
fn connect(serial: &str, model: &Model) -> Result<(Box<dyn SerialPort>, String), String> {
    let mut port = open_port(serial, model)?;
    let what = match model {
        Model::Mtx => configure_mtx(port.as_mut()).map(|()| "MTx".to_string())?,
        Model::Mti { hz, .. } => configure_mti(port.as_mut(), *hz)?,
    };
    Ok((port, what))
}

/// How often a serial port that failed is opened again.
const REOPEN_EVERY: Duration = Duration::from_secs(1);

/// The measures of one data message of `model`.
fn measures(model: &Model, m: &Message, latest: &Mutex<Latest>) -> Result<(), String> {
    let f = |v: [f32; 3]| Some(v.map(f64::from));
    let mut l = latest.lock();
    match model {
        Model::Mtx => {
            let s = Sample::parse(&m.data).map_err(|e| e.to_string())?;
            l.update(f(s.euler), f(s.acc), f(s.gyr), f(s.mag));
        }
        Model::Mti { .. } => {
            let d = Mtdata2::parse(&m.data).map_err(|e| e.to_string())?;
            l.update(d.euler, d.acc, d.gyr, d.mag);
        }
    }
    Ok(())
}

/// Keeps `latest` up to date from the sensor's data until `stop`. A port that fails
/// (USB cable pulled, emulator restarted) is reported once and opened and configured
/// again every [`REOPEN_EVERY`] (C++ stays in error until the device is reopened).
fn read_samples(
    id: String,
    serial: String,
    model: Model,
    mut port: Box<dyn SerialPort>,
    latest: Arc<Mutex<Latest>>,
    stop: &AtomicBool,
) {
    let data_mid = match model {
        Model::Mtx => mid::MT_DATA,
        Model::Mti { .. } => mti::mid::MT_DATA2,
    };
    let mut dec = Decoder::new();
    let mut buf = [0u8; 512];
    let mut bad = 0u64;
    let mut lost: Option<(Instant, Instant)> = None;
    while !stopped(stop) {
        if let Some((since, tried)) = lost {
            std::thread::sleep(Duration::from_millis(50));
            if tried.elapsed() < REOPEN_EVERY {
                continue;
            }
            match connect(&serial, &model) {
                Ok((p, _)) => {
                    port = p;
                    dec = Decoder::new();
                    lost = None;
                    tracing::warn!(
                        "{id}: the sensor on {serial} measures again after {:.1} s",
                        since.elapsed().as_secs_f64()
                    );
                }
                Err(e) => {
                    tracing::debug!("{id}: reopening {serial}: {e}");
                    lost = Some((since, Instant::now()));
                }
            }
            continue;
        }
        let failed = match port.read(&mut buf) {
            Ok(0) => Some("the port hung up".to_string()),
            Ok(n) => {
                dec.push(&buf[..n]);
                None
            }
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::Interrupted) => None,
            Err(e) => Some(e.to_string()),
        };
        if let Some(why) = failed {
            // the measures go stale and readers see Timeout meanwhile
            tracing::error!(
                "{id}: the sensor on {serial} fails ({why}): its measures read as Timeout; opening {serial} again every {REOPEN_EVERY:?} (check the sensor's cable)"
            );
            lost = Some((Instant::now(), Instant::now()));
            continue;
        }
        while let Some(r) = dec.next_message() {
            let read = match r {
                Ok(m) if m.mid == data_mid => measures(&model, &m, &latest),
                Ok(m) if m.mid == mid::ERROR => {
                    let code = m.data.first().copied().unwrap_or(0);
                    Err(format!("the sensor reports error {code:#04x}"))
                }
                Ok(_) => continue,
                Err(e) => Err(e.to_string()),
            };
            if let Err(e) = read {
                bad += 1;
                if bad.is_power_of_two() {
                    tracing::warn!("{id}: {bad} malformed or error message(s), latest: {e}");
                }
            }
        }
    }
}

impl XsensImu {
    /// The latest measures if the sensor sent something recently.
    fn fresh(&self) -> Option<Latest> {
        let l = *self.latest.lock();
        l.at.filter(|at| at.elapsed() <= self.stale_after)
            .map(|_| l)
    }

    fn status(&self, i: usize) -> MasStatus {
        match (i, self.fresh()) {
            (0, Some(_)) => MasStatus::Ok,
            (0, None) if self.reader.is_running() => MasStatus::Timeout,
            _ => MasStatus::Error,
        }
    }

    fn measure(
        &self,
        i: usize,
        what: &str,
        pick: impl Fn(&Latest) -> Option<Timed>,
        scale: f64,
    ) -> DevResult<SensorMeasurement> {
        if i != 0 {
            return Err(no_sensor(self.model.name(), i, 1));
        }
        if !self.reader.is_running() {
            return Err(DeviceError::NotOpen);
        }
        let l = self.fresh().ok_or_else(|| {
            DeviceError::failed(
                self.id.as_str(),
                format!("no sample from the sensor for {:?}", self.stale_after),
            )
        })?;
        let t = pick(&l).ok_or_else(|| {
            DeviceError::failed(self.id.as_str(), format!("the sensor sends no {what}"))
        })?;
        Ok(SensorMeasurement::new(
            t.v.iter().map(|x| x * scale).collect(),
            t.stamp,
        ))
    }

    fn gyro(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, "rate of turn", |l| l.gyr, DEG_PER_RAD)
    }
    fn acc(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, "acceleration", |l| l.acc, 1.0)
    }
    fn mag(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, "magnetic field", |l| l.mag, 1.0)
    }
    fn rpy(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, "orientation", |l| l.euler, 1.0)
    }

    fn name(&self, i: usize) -> DevResult<String> {
        if i == 0 {
            Ok(self.sensor_name.clone())
        } else {
            Err(no_sensor(self.model.name(), i, 1))
        }
    }

    fn frame(&self, i: usize) -> DevResult<String> {
        self.name(i).map(|_| self.frame_name.clone())
    }

    /// `xsensmt`'s parameters (C++ defaults).
    fn read_mt_params(&mut self, p: &XsensParams) -> DevResult<()> {
        let general = p.xsensmt_period;
        let mut hz = [0u16; 6];
        let periods = [
            p.xsensmt_euler_period,
            p.xsensmt_acc_period,
            p.xsensmt_gyro_period,
            p.xsensmt_mag_period,
            p.xsensmt_position_period,
            p.xsensmt_linear_velocity_period,
        ];
        for (slot, period) in hz.iter_mut().zip(periods) {
            let period = period.unwrap_or(general);
            *slot = (1.0 / period).round().clamp(1.0, f64::from(u16::MAX - 1)) as u16;
        }
        let baud = p.baud;
        if let Some(t) = p.timeout {
            self.stale_after = Duration::from_secs_f64(t.max(0.001));
        }
        self.model = Model::Mti { baud, hz };
        let [e, a, g, m, pos, v] = hz;
        tracing::info!("{}: frequencies: accelerometer {a} Hz, gyro {g} Hz, magnetometer {m} Hz, euler angle {e} Hz, position {pos} Hz, linear velocity {v} Hz", self.id);
        Ok(())
    }
}

const DEG_PER_RAD: f64 = 180.0 / std::f64::consts::PI;

impl DeviceDriver for XsensImu {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        XsensParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let kind = self.model.name();
        let p = XsensParams::read_as(kind, config)?;
        self.id = device_id(config, kind);
        let serial = match std::env::var(SERIAL_ENV) {
            Ok(s) if !s.is_empty() => s,
            _ => p.serial.clone(),
        };
        let serial = serial.trim().to_string();
        if let Some(s) = &p.sensor_name {
            self.frame_name.clone_from(s);
            self.sensor_name.clone_from(s);
        }
        if let Some(s) = &p.frame_name {
            self.frame_name.clone_from(s);
        }
        if matches!(self.model, Model::Mti { .. }) {
            self.read_mt_params(&p)?;
        }
        let fail =
            |what: String| DeviceError::failed(self.id.as_str(), format!("{serial}: {what}"));
        let (port, what) = connect(&serial, &self.model).map_err(fail)?;
        let (id, latest) = (self.id.clone(), self.latest.clone());
        let (path, model) = (serial.clone(), self.model.clone());
        self.reader
            .spawn(format!("{kind} {serial}"), move |stop| {
                read_samples(id, path, model, port, latest, stop)
            })
            .map_err(|e| fail(format!("cannot start the reader: {e}")))?;
        tracing::info!("{}: {what} on {serial} measuring", self.id);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.reader.stop();
        *self.latest.lock() = Latest::default();
        Ok(())
    }

    yarp_devices::views!(as_analog_sensor);
    yarp_devices::imu_views!();
}

/// C++ `IGenericSensor::read`: roll pitch yaw, acc, gyro (deg/s), mag; a measure the
/// sensor does not send reads as zeros.
impl IAnalogSensor for XsensImu {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        let Some(l) = self.fresh() else {
            return if self.reader.is_running() {
                AnalogStatus::Timeout
            } else {
                AnalogStatus::Error
            };
        };
        let f = |t: Option<Timed>, k: f64| t.map_or([0.0; 3], |t| t.v.map(|x| x * k));
        out.clear();
        out.extend(f(l.euler, 1.0));
        out.extend(f(l.acc, 1.0));
        out.extend(f(l.gyr, DEG_PER_RAD));
        out.extend(f(l.mag, 1.0));
        AnalogStatus::Ok
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        let mut v = Vec::new();
        self.read(&mut v)
    }
    fn get_channels(&mut self) -> usize {
        12
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported("Xsens calibration"))
    }
}

yarp_devices::single_imu_interfaces!(XsensImu {
    gyro: gyro,
    acc: acc,
    mag: mag,
    rpy: rpy
});
