//! `xsensmtx`: the Xsens MTx IMU of the iCub head on a serial port (icub-main's
//! `XSensMTx`), speaking the MT protocol of [`icub_can::xsens`].
//!
//! Parameters (as icub-main): `serial` (default `/dev/ttyUSB0`), `sensor_name` and
//! `frame_name` (default `sensor_imu_xsens`). The `YARP_ICUB_XSENS_SERIAL` environment
//! variable, when set, replaces `serial`, so a robot's unmodified files can run against an
//! emulated MTx (`icub-board-emulator --xsens PATH`).
//!
//! At open, as C++: 115200 baud, 8 data bits, no parity, 2 stop bits; `GoToConfig`, output
//! mode calibrated + orientation with Euler angles, `GoToMeasurement`. A reader thread
//! keeps the latest sample. Interfaces: gyroscope (deg/s, converted from the sensor's
//! rad/s as C++ does), linear accelerometer (m/s²), magnetometer, orientation (roll,
//! pitch, yaw in degrees), and C++'s 12-channel `IGenericSensor` read as `IAnalogSensor`:
//! `[roll pitch yaw, acc xyz, gyro xyz (deg/s), mag xyz]`.
//!
//! Unlike C++ (whose multiple-analog-sensors status is always OK), a sensor that sent no
//! sample for 0.5 s (C++'s read timeout) reads as `Timeout` and its measures are errors;
//! a sensor that does not answer `GoToConfig` fails the open within 2 s, naming the port.
//! A serial port that fails while measuring is reported and opened and configured again
//! every second, so a replugged sensor (or a restarted emulator) measures again.

use crate::common::device_id;
use icub_can::xsens::{
    mid, Decoder, Message, Sample, OUTPUT_MODE_CALIB, OUTPUT_MODE_ORIENT, OUTPUT_SETTINGS_EULER,
};
use serialport::SerialPort;
use std::io::ErrorKind;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use yarp_devices::driver::{DeviceDriver, Params};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::sensors::interfaces::*;
use yarp_devices::sensors::params::now;
use yarp_proto::Property;

pub(crate) const NAME: &str = "xsensmtx";
/// Replaces the `serial` parameter when set.
pub const SERIAL_ENV: &str = "YARP_ICUB_XSENS_SERIAL";
const DEFAULT_SERIAL: &str = "/dev/ttyUSB0";
const DEFAULT_NAME: &str = "sensor_imu_xsens";
/// A sample older than this is stale (C++ `TO_DEFAULT`).
const STALE_AFTER: Duration = Duration::from_millis(500);
/// `GoToConfig` attempts and the wait for each: a silent port is reported in 2 s.
const CONFIG_TRIES: usize = 4;
const CONFIG_ACK_TIMEOUT: Duration = Duration::from_millis(500);
/// The wait for the acknowledgements of a sensor that has answered (it answers in
/// milliseconds; the margin is for a loaded machine and an emulated sensor behind a pty).
const ACK_TIMEOUT: Duration = Duration::from_secs(2);

/// The latest sample, its YARP timestamp and when it arrived.
#[derive(Debug, Clone, Copy)]
struct Latest {
    sample: Sample,
    stamp: f64,
    at: Instant,
}

/// The `xsensmtx` device.
pub struct XsensMtx {
    id: String,
    sensor_name: String,
    frame_name: String,
    latest: Arc<Mutex<Option<Latest>>>,
    stop: Arc<AtomicBool>,
    reader: Option<JoinHandle<()>>,
}

impl Default for XsensMtx {
    fn default() -> Self {
        XsensMtx {
            id: NAME.into(),
            sensor_name: DEFAULT_NAME.into(),
            frame_name: DEFAULT_NAME.into(),
            latest: Arc::new(Mutex::new(None)),
            stop: Arc::new(AtomicBool::new(false)),
            reader: None,
        }
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

/// C++ `XSensMTx::open`'s configuration sequence.
fn configure(port: &mut dyn SerialPort) -> Result<(), String> {
    let mut dec = Decoder::new();
    let config = Message::new(mid::GO_TO_CONFIG, vec![]);
    let mut last = String::new();
    let in_config =
        (0..CONFIG_TRIES).any(
            |_| match request(port, &mut dec, &config, CONFIG_ACK_TIMEOUT) {
                Ok(_) => true,
                Err(e) => {
                    last = e;
                    false
                }
            },
        );
    if !in_config {
        return Err(format!("no MTx answers ({last})"));
    }
    let mode = (OUTPUT_MODE_CALIB | OUTPUT_MODE_ORIENT)
        .to_be_bytes()
        .to_vec();
    request(
        port,
        &mut dec,
        &Message::new(mid::SET_OUTPUT_MODE, mode),
        ACK_TIMEOUT,
    )?;
    let settings = OUTPUT_SETTINGS_EULER.to_be_bytes().to_vec();
    request(
        port,
        &mut dec,
        &Message::new(mid::SET_OUTPUT_SETTINGS, settings),
        ACK_TIMEOUT,
    )?;
    request(
        port,
        &mut dec,
        &Message::new(mid::GO_TO_MEASUREMENT, vec![]),
        ACK_TIMEOUT,
    )?;
    Ok(())
}

/// Opens the serial port as C++ does: 115200 baud, 8N2, no flow control.
fn open_port(serial: &str) -> Result<Box<dyn SerialPort>, String> {
    serialport::new(serial, 115_200)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::Two)
        .flow_control(serialport::FlowControl::None)
        .timeout(Duration::from_millis(20))
        .open()
        .map_err(|e| format!("cannot open the serial port: {e}"))
}

/// How often a serial port that failed is opened again.
const REOPEN_EVERY: Duration = Duration::from_secs(1);

/// Keeps `latest` up to date from the sensor's `MTData` until `stop`. A port that fails
/// (USB cable pulled, emulator restarted) is reported once and opened and configured
/// again every [`REOPEN_EVERY`] (C++ stays in error until the device is reopened).
fn read_samples(
    id: String,
    serial: String,
    mut port: Box<dyn SerialPort>,
    latest: Arc<Mutex<Option<Latest>>>,
    stop: Arc<AtomicBool>,
) {
    let mut dec = Decoder::new();
    let mut buf = [0u8; 512];
    let mut bad = 0u64;
    let mut lost: Option<(Instant, Instant)> = None;
    while !stop.load(Ordering::SeqCst) {
        if let Some((since, tried)) = lost {
            std::thread::sleep(Duration::from_millis(50));
            if tried.elapsed() < REOPEN_EVERY {
                continue;
            }
            let again = open_port(&serial).and_then(|mut p| configure(p.as_mut()).map(|()| p));
            match again {
                Ok(p) => {
                    port = p;
                    dec = Decoder::new();
                    lost = None;
                    tracing::warn!(
                        "{id}: MTx on {serial} measuring again after {:.1} s",
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
            // the samples go stale and readers see Timeout meanwhile
            tracing::error!(
                "{id}: the MTx on {serial} fails ({why}): its measures read as Timeout; opening {serial} again every {REOPEN_EVERY:?} (check the sensor's cable)"
            );
            lost = Some((Instant::now(), Instant::now()));
            continue;
        }
        while let Some(r) = dec.next_message() {
            let sample = match r {
                Ok(m) if m.mid == mid::MT_DATA => Sample::parse(&m.data).map_err(|e| e.to_string()),
                Ok(_) => continue,
                Err(e) => Err(e.to_string()),
            };
            match sample {
                Ok(sample) => {
                    let l = Latest {
                        sample,
                        stamp: now(),
                        at: Instant::now(),
                    };
                    *latest.lock().unwrap_or_else(|e| e.into_inner()) = Some(l);
                }
                Err(e) => {
                    bad += 1;
                    if bad.is_power_of_two() {
                        tracing::warn!("{id}: {bad} malformed message(s) ignored, latest: {e}");
                    }
                }
            }
        }
    }
}

impl XsensMtx {
    pub fn new() -> Self {
        Self::default()
    }

    /// The latest sample if fresh.
    fn fresh(&self) -> Option<Latest> {
        let l = *self.latest.lock().unwrap_or_else(|e| e.into_inner());
        l.filter(|l| l.at.elapsed() <= STALE_AFTER)
    }

    fn status(&self, i: usize) -> MasStatus {
        match (i, self.fresh()) {
            (0, Some(_)) => MasStatus::Ok,
            (0, None) if self.reader.is_some() => MasStatus::Timeout,
            _ => MasStatus::Error,
        }
    }

    fn measure(
        &self,
        i: usize,
        pick: impl Fn(&Sample) -> [f32; 3],
        scale: f64,
    ) -> DevResult<SensorMeasurement> {
        if i != 0 {
            return Err(no_sensor(NAME, i, 1));
        }
        if self.reader.is_none() {
            return Err(DeviceError::NotOpen);
        }
        let l = self.fresh().ok_or_else(|| {
            DeviceError::failed(
                self.id.as_str(),
                format!("no sample from the MTx for {STALE_AFTER:?}"),
            )
        })?;
        let v = pick(&l.sample)
            .iter()
            .map(|x| f64::from(*x) * scale)
            .collect();
        Ok(SensorMeasurement::new(v, l.stamp))
    }

    fn gyro(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, |s| s.gyr, DEG_PER_RAD)
    }
    fn acc(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, |s| s.acc, 1.0)
    }
    fn mag(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, |s| s.mag, 1.0)
    }
    fn rpy(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, |s| s.euler, 1.0)
    }

    fn name(&self, i: usize) -> DevResult<String> {
        if i == 0 {
            Ok(self.sensor_name.clone())
        } else {
            Err(no_sensor(NAME, i, 1))
        }
    }

    fn frame(&self, i: usize) -> DevResult<String> {
        self.name(i).map(|_| self.frame_name.clone())
    }
}

const DEG_PER_RAD: f64 = 180.0 / std::f64::consts::PI;

impl DeviceDriver for XsensMtx {
    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = Params::new(NAME, config);
        self.id = device_id(config, NAME);
        let serial = match std::env::var(SERIAL_ENV) {
            Ok(s) if !s.is_empty() => s,
            _ => p.string("serial")?.unwrap_or_else(|| DEFAULT_SERIAL.into()),
        };
        if let Some(s) = p.string("sensor_name")? {
            self.sensor_name = s;
        }
        if let Some(s) = p.string("frame_name")? {
            self.frame_name = s;
        }
        let fail =
            |what: String| DeviceError::failed(self.id.as_str(), format!("{serial}: {what}"));
        let mut port = open_port(&serial).map_err(fail)?;
        configure(port.as_mut()).map_err(fail)?;
        self.stop.store(false, Ordering::SeqCst);
        let (id, latest, stop) = (self.id.clone(), self.latest.clone(), self.stop.clone());
        let path = serial.clone();
        let reader = std::thread::Builder::new()
            .name(format!("{NAME} {serial}"))
            .spawn(move || read_samples(id, path, port, latest, stop))
            .map_err(|e| fail(format!("cannot start the reader: {e}")))?;
        self.reader = Some(reader);
        tracing::info!("{}: MTx on {serial} measuring", self.id);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
        *self.latest.lock().unwrap_or_else(|e| e.into_inner()) = None;
        Ok(())
    }

    fn as_analog_sensor(&mut self) -> Option<&mut dyn IAnalogSensor> {
        Some(self)
    }
    yarp_devices::imu_views!();
}

impl Drop for XsensMtx {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

/// C++ `IGenericSensor::read`: roll pitch yaw, acc, gyro (deg/s), mag.
impl IAnalogSensor for XsensMtx {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        let Some(l) = self.fresh() else {
            return if self.reader.is_some() {
                AnalogStatus::Timeout
            } else {
                AnalogStatus::Error
            };
        };
        let s = l.sample;
        let f = |v: [f32; 3], k: f64| v.map(|x| f64::from(x) * k);
        out.clear();
        out.extend(f(s.euler, 1.0));
        out.extend(f(s.acc, 1.0));
        out.extend(f(s.gyr, DEG_PER_RAD));
        out.extend(f(s.mag, 1.0));
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
        Err(DeviceError::Unsupported("xsensmtx calibration"))
    }
}

yarp_devices::single_imu_interfaces!(XsensMtx {
    gyro: gyro,
    acc: acc,
    mag: mag,
    rpy: rpy
});
