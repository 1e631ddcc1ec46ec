//! `imuBosch_BNO055` (C++ YARP `BoschIMU`): the Bosch BNO055 IMU of several iCub heads, on
//! a serial line (`comport`, the chip's UART protocol) or an I2C bus (`i2c`, Linux
//! i2c-dev at address 0x28).
//!
//! As C++: the chip is put in CONFIG mode with its external clock, then in NDOF fusion
//! (page 0); open fails unless a first read gives a valid quaternion within 10 tries. Every
//! `period` ms the 32 bytes from 0x08 (accelerometer, magnetometer, gyroscope, Euler,
//! quaternion) are read; a quaternion whose squared norm is outside [0.9, 1.2] is
//! discarded. Readings: roll, pitch, yaw (degrees, from the quaternion of the cycle
//! before, as C++ converts the one it kept), acceleration (m/s², 1/100 LSB), rate of turn
//! (deg/s, 1/16), magnetic field (µT, 1/16; the magnetometer interface gives tesla).
//! `IGenericSensor` reads the 12 values `[rpy, acc, gyro, mag]`; the four
//! multiple-analog-sensors interfaces one sensor each, named `sensor_name` in `frame_name`.
//!
//! The serial line is 115200 8N1 whatever `baudrate` says (C++ reads and ignores it),
//! each byte awaited at most 0.2 s; a read is tried 3 times and a write 4, with C++'s
//! recovery between (the chip's `SYS_STATUS`/`SYS_ERR` asked, garbage drained).
//!
//! `YARP_BNO055_COMPORT` (when set) puts the chip on that serial line whatever bus the file
//! names, so a robot's unmodified file can run against an emulated chip on a pseudo-terminal
//! (`icub-board-emulator --bno055 PATH`, which speaks the chip's UART protocol; an I2C bus
//! cannot be emulated without the kernel's help); `YARP_BNO055_I2C` replaces `i2c`.

use super::interfaces::*;
use super::params::now;
use crate::device_thread::{stopped, DeviceThread};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use parking_lot::Mutex;
use std::io::{Read, Write};
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_proto::Property;

const NAME: &str = "imuBosch_BNO055";
/// Replaces `comport` when set.
pub const COMPORT_ENV: &str = "YARP_BNO055_COMPORT";
/// Replaces `i2c` when set.
pub const I2C_ENV: &str = "YARP_BNO055_I2C";

crate::device_params! {
    /// What `imuBosch_BNO055` reads (C++ `BoschIMU_params.md`).
    pub struct BoschImuParams for "imuBosch_BNO055" {
        /// full name of device file (ex '/dev/ttyUSB0'), mutually exclusive with 'i2c'
        comport: String = optional,
        /// baudrate setting of COM port (C++ reads it and opens the line at 115200)
        baudrate: i32 = 115200,
        /// full name of device file (ex '/dev/i2c-5'), mutually exclusive with 'comport'
        i2c: String = optional,
        /// period of the thread
        period: i32 = 10; "ms"; min 1,
        /// full name of the device
        sensor_name: String = "sensor_imu_bosch_bno055",
        /// full name of the sensor frame in which the measurements are expressed
        frame_name: String = "sensor_imu_bosch_bno055",
        /// number of channels in the output port (16 also meant the quaternion: C++ still reads 12)
        channels: i32 = 12,
    }
}

/// The chip's registers (page 0) the driver touches.
mod reg {
    pub const CHIP_ID: u8 = 0x00;
    pub const PAGE_ID: u8 = 0x07;
    pub const ACC_DATA: u8 = 0x08;
    pub const SYS_STATUS: u8 = 0x39;
    pub const SYS_ERR: u8 = 0x3A;
    pub const OPR_MODE: u8 = 0x3D;
    pub const SYS_TRIGGER: u8 = 0x3F;
}
const CONFIG_MODE: u8 = 0x00;
const NDOF_MODE: u8 = 0x0C;
const TRIG_EXT_CLK_SEL: u8 = 0x80;
const CHIP_ID_VALUE: u8 = 0xA0;
/// The data block: acc, mag, gyro, Euler, quaternion (16 int16).
const DATA_LEN: u8 = 32;
/// The chip's mode-switch time C++ waits after every configuration write.
const SWITCHING_TIME: Duration = Duration::from_millis(20);
/// How often C++ reports the read errors of the last interval.
const REPORT_INTERVAL: f64 = 30.0;

/// The UART protocol's bytes.
mod uart {
    pub const START: u8 = 0xAA;
    pub const WRITE: u8 = 0x00;
    pub const READ: u8 = 0x01;
    pub const REPLY: u8 = 0xBB;
    pub const ERROR: u8 = 0xEE;
    pub const WRITE_SUCCESS: u8 = 0x01;
    /// The chip is busy (BUS_OVER_RUN); C++ retries without logging it.
    pub const NOT_READY: u8 = 0x07;
    /// How long a byte is awaited (C++: VMIN 0, VTIME 2).
    pub const BYTE_TIMEOUT: std::time::Duration = std::time::Duration::from_millis(200);
}

/// How the chip's registers are reached.
trait Bus: Send {
    /// `len` bytes from register `reg`, or `None` when every try failed.
    fn read_registers(&mut self, reg: u8, len: u8) -> Option<Vec<u8>>;
    /// Writes one register (C++'s retries included); `false` when it failed.
    fn write_register(&mut self, reg: u8, value: u8, what: &str) -> bool;
}

/// The chip on a serial line, as C++ talks to it.
struct SerialBus {
    port: Box<dyn serialport::SerialPort>,
    path: String,
    /// Errors by the chip's status code (0: an answer that made no sense).
    errors: [u64; 11],
    /// Set while the recovery reads run, so that they do not recover themselves.
    checking: bool,
}

impl SerialBus {
    fn open(path: &str) -> Result<SerialBus, String> {
        let port = serialport::new(path, 115_200)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(uart::BYTE_TIMEOUT)
            .open()
            .map_err(|e| format!("cannot open the serial port {path}: {e}"))?;
        let _ = port.clear(serialport::ClearBuffer::All);
        Ok(SerialBus {
            port,
            path: path.to_string(),
            errors: [0; 11],
            checking: false,
        })
    }

    /// Up to `n` bytes, each awaited at most [`uart::BYTE_TIMEOUT`] (C++ `readBytes`).
    fn read_bytes(&mut self, n: usize) -> Vec<u8> {
        let mut out = Vec::with_capacity(n);
        let mut byte = [0u8; 1];
        while out.len() < n {
            match self.port.read(&mut byte) {
                Ok(1) => out.push(byte[0]),
                _ => break,
            }
        }
        out
    }

    /// Reads until the line is quiet (C++ `dropGarbage`).
    fn drop_garbage(&mut self) {
        let mut byte = [0u8; 1];
        while matches!(self.port.read(&mut byte), Ok(1)) {}
    }

    /// Asks the chip's status and error registers after a failure, as C++ does (their
    /// values are not used).
    fn read_sys_error(&mut self) {
        if self.checking {
            return;
        }
        self.checking = true;
        std::thread::sleep(Duration::from_millis(2));
        let _ = self.read_registers(reg::SYS_STATUS, 1);
        let _ = self.read_registers(reg::SYS_ERR, 1);
        self.checking = false;
    }

    fn count(&mut self, code: u8) {
        if let Some(c) = self.errors.get_mut(usize::from(code)) {
            *c += 1;
        }
    }

    fn send(&mut self, frame: &[u8]) -> bool {
        self.port.write_all(frame).is_ok() && self.port.flush().is_ok()
    }

    /// One write try (C++ `sendWriteCommandSer`).
    fn write_once(&mut self, reg: u8, value: u8, what: &str) -> bool {
        if !self.send(&[uart::START, uart::WRITE, reg, 1, value]) {
            tracing::error!("{NAME}: {}: FAILED writing {what}", self.path);
            return false;
        }
        match self.read_bytes(2)[..] {
            [uart::ERROR, uart::WRITE_SUCCESS] => return true,
            [uart::ERROR, code] => {
                self.count(code);
                if code != uart::NOT_READY {
                    tracing::error!(
                        "{NAME}: {}: the chip answered error {code:#04x} to writing {what}",
                        self.path
                    );
                }
                self.read_sys_error();
            }
            ref other => {
                self.count(0);
                tracing::error!(
                    "{NAME}: {}: unexpected answer {other:02x?} to writing {what}",
                    self.path
                );
                self.drop_garbage();
                self.read_sys_error();
            }
        }
        tracing::error!("{NAME}: {}: FAILED writing {what}", self.path);
        false
    }
}

impl Bus for SerialBus {
    fn read_registers(&mut self, reg: u8, len: u8) -> Option<Vec<u8>> {
        for _ in 0..3 {
            if !self.send(&[uart::START, uart::READ, reg, len]) {
                continue;
            }
            let header = self.read_bytes(2);
            match header[..] {
                [uart::REPLY, n] => return Some(self.read_bytes(usize::from(n))),
                [uart::ERROR, code] => {
                    if code != uart::NOT_READY {
                        tracing::error!(
                            "{NAME}: {}: the chip didn't understand the command (error {code:#04x})",
                            self.path
                        );
                    }
                    self.count(code);
                    self.read_sys_error();
                    std::thread::sleep(Duration::from_millis(2));
                }
                [_, _] => {
                    self.count(0);
                    tracing::error!(
                        "{NAME}: {}: Received unknown response message {header:02x?}",
                        self.path
                    );
                    self.drop_garbage();
                    self.read_sys_error();
                    std::thread::sleep(Duration::from_millis(2));
                }
                _ => tracing::debug!(
                    "{NAME}: {}: Expected 2 bytes, read {} instead",
                    self.path,
                    header.len()
                ),
            }
        }
        None
    }

    fn write_register(&mut self, reg: u8, value: u8, what: &str) -> bool {
        (0..4).any(|_| self.write_once(reg, value, what))
    }
}

/// The chip on an I2C bus (Linux i2c-dev, address 0x28), as C++ talks to it.
struct I2cBus {
    dev: i2cdev::linux::LinuxI2CDevice,
}

impl I2cBus {
    fn open(path: &str) -> Result<I2cBus, String> {
        use i2cdev::core::I2CDevice;
        let mut dev = i2cdev::linux::LinuxI2CDevice::new(path, 0x28)
            .map_err(|e| format!("cannot open the I2C bus {path}: {e}"))?;
        // C++ asks the chip's id 11 times, 0.1 s apart, before giving up
        for attempt in 0..11 {
            if dev.smbus_read_byte_data(reg::CHIP_ID).ok() == Some(CHIP_ID_VALUE) {
                return Ok(I2cBus { dev });
            }
            if attempt < 10 {
                std::thread::sleep(Duration::from_millis(100));
            }
        }
        Err(format!("{path}: Wrong device on the bus, it is not BNO055"))
    }
}

impl Bus for I2cBus {
    fn read_registers(&mut self, reg: u8, len: u8) -> Option<Vec<u8>> {
        use i2cdev::core::I2CDevice;
        self.dev.smbus_read_i2c_block_data(reg, len).ok()
    }

    fn write_register(&mut self, reg: u8, value: u8, what: &str) -> bool {
        use i2cdev::core::I2CDevice;
        let ok = self.dev.smbus_write_byte_data(reg, value).is_ok();
        if !ok {
            tracing::error!("{NAME}: FAILED writing {what}");
        }
        ok
    }
}

/// What the reader thread shares with the interfaces.
#[derive(Debug, Clone, Copy, Default)]
struct Readings {
    /// roll pitch yaw (deg), acc (m/s²), gyro (deg/s), mag (µT)
    data: [f64; 12],
    /// Whether the last cycle gave a valid sample (C++ `dataIsValid`).
    valid: bool,
    /// When the last cycle began (C++ `m_timeStamp`, set even when it failed).
    stamp: f64,
}

/// One cycle's state besides the readings: the quaternion kept from the last valid
/// sample (C++ converts it, not the new one), and the error count of the interval.
struct Cycle {
    quaternion: [f64; 4],
    errors: u64,
    last_report: f64,
}

impl Cycle {
    fn new() -> Cycle {
        Cycle {
            quaternion: [1.0, 0.0, 0.0, 0.0],
            errors: 0,
            last_report: now(),
        }
    }

    /// C++ `run`: reads the data block and updates `shared`.
    fn run(&mut self, bus: &mut dyn Bus, shared: &Mutex<Readings>) {
        let stamp = now();
        shared.lock().stamp = stamp;
        let block = bus
            .read_registers(reg::ACC_DATA, DATA_LEN)
            .filter(|b| b.len() >= usize::from(DATA_LEN));
        let Some(block) = block else {
            tracing::error!("{NAME}: Failed to read all the data");
            self.errors += 1;
            shared.lock().valid = false;
            return;
        };
        let raw: Vec<f64> = block
            .chunks_exact(2)
            .map(|b| f64::from(i16::from_le_bytes([b[0], b[1]])))
            .collect();
        let q = [raw[12], raw[13], raw[14], raw[15]].map(|x| x / 16384.0);
        let norm2: f64 = q.iter().map(|x| x * x).sum();
        if !(0.9..=1.2).contains(&norm2) {
            shared.lock().valid = false;
            return;
        }
        let rpy = rpy_of(self.quaternion);
        let mut data = [0.0; 12];
        data[..3].copy_from_slice(&rpy);
        for i in 0..3 {
            data[3 + i] = raw[i] / 100.0; // acc
            data[6 + i] = raw[6 + i] / 16.0; // gyro
            data[9 + i] = raw[3 + i] / 16.0; // mag
        }
        self.quaternion = q;
        *shared.lock() = Readings {
            data,
            valid: true,
            stamp,
        };
        if stamp - self.last_report > REPORT_INTERVAL {
            if self.errors != 0 {
                tracing::debug!(
                    "{NAME}: Periodic error report of last {REPORT_INTERVAL} sec: errors while reading data: {}",
                    self.errors
                );
            }
            self.errors = 0;
            self.last_report = stamp;
        }
    }
}

/// Roll, pitch, yaw (degrees) of the rotation `q` = (w, x, y, z) (normalised first), as
/// YARP's `dcm2rpy` of the quaternion's rotation matrix.
fn rpy_of(q: [f64; 4]) -> [f64; 3] {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    let [w, x, y, z] = q.map(|v| v / n);
    let r00 = w * w + x * x - y * y - z * z;
    let r10 = 2.0 * (x * y + w * z);
    let r20 = 2.0 * (x * z - w * y);
    let r21 = 2.0 * (y * z + w * x);
    let r22 = w * w - x * x - y * y + z * z;
    let r12 = 2.0 * (y * z - w * x);
    let r11 = w * w - x * x + y * y - z * z;
    let half_pi = std::f64::consts::FRAC_PI_2;
    let (roll, pitch, yaw) = if r20 < 1.0 && r20 > -1.0 {
        (r21.atan2(r22), (-r20).asin(), r10.atan2(r00))
    } else if r20 <= -1.0 {
        tracing::warn!("{NAME}: dcm2rpy: singular orientation");
        (0.0, half_pi, -(-r12).atan2(r11))
    } else {
        tracing::warn!("{NAME}: dcm2rpy: singular orientation");
        (0.0, -half_pi, (-r12).atan2(r11))
    };
    [roll, pitch, yaw].map(f64::to_degrees)
}

/// The `imuBosch_BNO055` device.
pub struct BoschImu {
    sensor_name: String,
    frame_name: String,
    channels: usize,
    readings: Arc<Mutex<Readings>>,
    reader: DeviceThread,
}

impl Default for BoschImu {
    fn default() -> Self {
        BoschImu {
            sensor_name: "sensor_imu_bosch_bno055".into(),
            frame_name: "sensor_imu_bosch_bno055".into(),
            channels: 12,
            readings: Arc::default(),
            reader: DeviceThread::default(),
        }
    }
}

/// `env` when set and not empty, else the parameter.
fn overridden(env: &str, param: Option<String>) -> Option<String> {
    match std::env::var(env) {
        Ok(s) if !s.trim().is_empty() => Some(s),
        _ => param,
    }
    .map(|s| s.trim().to_string())
    .filter(|s| !s.is_empty())
}

/// C++ `threadInit`: the serial line's configuration writes (the I2C path's order
/// differs, as in C++), then up to 10 cycles until one is valid.
fn start_chip(
    bus: &mut dyn Bus,
    serial: bool,
    cycle: &mut Cycle,
    shared: &Mutex<Readings>,
) -> Result<(), String> {
    let page = (reg::PAGE_ID, 0x00, "page id 0");
    let config = (reg::OPR_MODE, CONFIG_MODE, "config mode");
    let clock = (reg::SYS_TRIGGER, TRIG_EXT_CLK_SEL, "external clock");
    let ndof = (reg::OPR_MODE, NDOF_MODE, "config NDOF_MODE");
    let steps = if serial {
        [page, config, clock, ndof]
    } else {
        [config, clock, page, ndof]
    };
    for (reg, value, what) in steps {
        if !bus.write_register(reg, value, what) {
            return Err(format!("Set {what} failed"));
        }
        std::thread::sleep(SWITCHING_TIME);
    }
    for _ in 0..10 {
        cycle.run(bus, shared);
        if shared.lock().valid {
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Err("First read from the device failed, check everything is fine and retry".into())
}

impl BoschImu {
    pub fn new() -> Self {
        Self::default()
    }

    fn status(&self, i: usize) -> MasStatus {
        // C++ reports OK whatever its reads do
        match i {
            0 => MasStatus::Ok,
            _ => MasStatus::Error,
        }
    }

    fn measure(&self, i: usize, from: usize, scale: f64) -> DevResult<SensorMeasurement> {
        if i != 0 {
            return Err(no_sensor(NAME, i, 1));
        }
        let r = *self.readings.lock();
        Ok(SensorMeasurement::new(
            r.data[from..from + 3].iter().map(|v| v * scale).collect(),
            r.stamp,
        ))
    }

    fn gyro(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, 6, 1.0)
    }
    fn acc(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, 3, 1.0)
    }
    /// In tesla, as C++ converts the chip's µT.
    fn mag(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, 9, 1e-6)
    }
    fn rpy(&self, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(i, 0, 1.0)
    }
    fn name(&self, i: usize) -> DevResult<String> {
        match i {
            0 => Ok(self.sensor_name.clone()),
            _ => Err(no_sensor(NAME, i, 1)),
        }
    }
    fn frame(&self, i: usize) -> DevResult<String> {
        self.name(i).map(|_| self.frame_name.clone())
    }
}

impl DeviceDriver for BoschImu {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        BoschImuParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = BoschImuParams::read(config)?;
        let comport = overridden(COMPORT_ENV, p.comport);
        // an emulated chip on a serial line stands for the robot's, on whatever bus
        let i2c = match std::env::var(COMPORT_ENV) {
            Ok(s) if !s.trim().is_empty() => None,
            _ => overridden(I2C_ENV, p.i2c),
        };
        let refuse = |got: &str| DeviceError::BadParam {
            device: NAME.into(),
            param: "comport".into(),
            expected: "exactly one of 'comport' and 'i2c'",
            got: got.into(),
        };
        let (mut bus, serial, path): (Box<dyn Bus>, bool, String) = match (comport, i2c) {
            (None, None) => return Err(refuse(
                "Params 'comport' and 'i2c' not found. At least one of the two must be specified",
            )),
            (Some(_), Some(_)) => return Err(refuse("Params 'comport' and 'i2c' both specified")),
            (None, Some(path)) => (
                Box::new(I2cBus::open(&path).map_err(|e| DeviceError::failed(NAME, e))?),
                false,
                path,
            ),
            (Some(path), None) => (
                Box::new(SerialBus::open(&path).map_err(|e| DeviceError::failed(NAME, e))?),
                true,
                path,
            ),
        };
        self.sensor_name = p.sensor_name;
        self.frame_name = p.frame_name;
        self.channels = usize::try_from(p.channels).unwrap_or(12);
        let period = Duration::from_millis(u64::try_from(p.period).unwrap_or(10));
        let mut cycle = Cycle::new();
        start_chip(bus.as_mut(), serial, &mut cycle, &self.readings)
            .map_err(|e| DeviceError::failed(NAME, format!("{path}: {e}")))?;
        let readings = self.readings.clone();
        self.reader
            .spawn(format!("{NAME} {path}"), move |stop| {
                let mut next = Instant::now() + period;
                while !stopped(stop) {
                    std::thread::sleep(next.saturating_duration_since(Instant::now()));
                    next = (next + period).max(Instant::now());
                    cycle.run(bus.as_mut(), &readings);
                }
            })
            .map_err(|e| DeviceError::failed(NAME, format!("cannot start the reader: {e}")))?;
        tracing::info!("{NAME}: measuring on {path}");
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.reader.stop();
        Ok(())
    }

    crate::views!(as_analog_sensor);
    crate::imu_views!();
}

/// C++ `IGenericSensor::read`: the 12 values, valid or not as the last cycle was.
impl IAnalogSensor for BoschImu {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        let r = *self.readings.lock();
        out.clear();
        out.extend(r.data);
        if r.valid {
            AnalogStatus::Ok
        } else {
            AnalogStatus::Error
        }
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        let mut v = Vec::new();
        self.read(&mut v)
    }
    fn get_channels(&mut self) -> usize {
        self.channels
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        Err(DeviceError::Unsupported("BNO055 calibration"))
    }
}

crate::single_imu_interfaces!(BoschImu {
    gyro: gyro,
    acc: acc,
    mag: mag,
    rpy: rpy
});

#[cfg(test)]
mod tests {
    use super::*;

    /// The quaternion of roll, pitch, yaw (degrees), Z-Y-X.
    fn quat(rpy: [f64; 3]) -> [f64; 4] {
        let [r, p, y] = rpy.map(|d| d.to_radians() / 2.0);
        let (cr, sr, cp, sp, cy, sy) = (r.cos(), r.sin(), p.cos(), p.sin(), y.cos(), y.sin());
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    }

    #[test]
    fn rpy_of_a_quaternion_is_yarps_dcm2rpy() {
        for rpy in [[0.0, 0.0, 0.0], [5.0, -10.0, 20.0], [-30.0, 45.0, 170.0]] {
            let got = rpy_of(quat(rpy));
            for k in 0..3 {
                assert!((got[k] - rpy[k]).abs() < 1e-9, "{rpy:?} -> {got:?}");
            }
        }
        // not normalised: normalised first
        let q = quat([5.0, 6.0, 7.0]).map(|v| v * 1.05);
        assert!((rpy_of(q)[2] - 7.0).abs() < 1e-9);
    }

    /// A chip whose data block is fixed, counting the writes it got.
    struct Chip(Option<Vec<u8>>, Vec<(u8, u8)>);
    impl Bus for Chip {
        fn read_registers(&mut self, _reg: u8, _len: u8) -> Option<Vec<u8>> {
            self.0.clone()
        }
        fn write_register(&mut self, reg: u8, value: u8, _what: &str) -> bool {
            self.1.push((reg, value));
            true
        }
    }

    fn block(acc: [i16; 3], mag: [i16; 3], gyro: [i16; 3], q: [f64; 4]) -> Vec<u8> {
        let mut words = Vec::new();
        words.extend(acc);
        words.extend(mag);
        words.extend(gyro);
        words.extend([0i16; 3]);
        words.extend(q.map(|v| (v * 16384.0).round() as i16));
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    #[test]
    fn a_cycle_scales_as_cpp_and_converts_the_previous_quaternion() {
        let q = quat([10.0, 0.0, 0.0]);
        let mut chip = Chip(
            Some(block([0, 0, 981], [320, -160, 16], [16, 32, -48], q)),
            vec![],
        );
        let shared = Mutex::new(Readings::default());
        let mut cycle = Cycle::new();
        start_chip(&mut chip, true, &mut cycle, &shared).unwrap();
        assert_eq!(
            chip.1,
            vec![(0x07, 0), (0x3D, 0), (0x3F, 0x80), (0x3D, 0x0C)]
        );
        let r = *shared.lock();
        assert!(r.valid);
        // the first valid cycle converts the identity C++ starts from
        assert_eq!(&r.data[..3], &[0.0, 0.0, 0.0]);
        assert_eq!(
            &r.data[3..],
            &[0.0, 0.0, 9.81, 1.0, 2.0, -3.0, 20.0, -10.0, 1.0]
        );
        cycle.run(&mut chip, &shared);
        assert!((shared.lock().data[0] - 10.0).abs() < 0.01);
        // I2C's order: CONFIG, clock, page, NDOF
        let mut chip2 = Chip(Some(block([0; 3], [0; 3], [0; 3], q)), vec![]);
        start_chip(&mut chip2, false, &mut Cycle::new(), &shared).unwrap();
        assert_eq!(
            chip2.1,
            vec![(0x3D, 0), (0x3F, 0x80), (0x07, 0), (0x3D, 0x0C)]
        );
    }

    #[test]
    fn a_bad_quaternion_or_a_silent_chip_fails_the_start() {
        let shared = Mutex::new(Readings::default());
        let mut zeros = Chip(Some(block([0; 3], [0; 3], [0; 3], [0.0; 4])), vec![]);
        let e = start_chip(&mut zeros, true, &mut Cycle::new(), &shared).unwrap_err();
        assert!(e.contains("First read from the device failed"), "{e}");
        let mut silent = Chip(None, vec![]);
        assert!(start_chip(&mut silent, true, &mut Cycle::new(), &shared).is_err());
        let mut short = Chip(Some(vec![0; 10]), vec![]);
        assert!(start_chip(&mut short, true, &mut Cycle::new(), &shared).is_err());
    }
}
