//! The analog sensors of the Ethernet boards (icub-main `embObjFTsensor`,
//! `embObjMultipleFTsensors`, `embObjIMU` / `embObjInertials`, `embObjMais`): each opens
//! its service on its board (as `embObjMotionControl` does: `ETH_BOARD`, `PC104`,
//! `SERVICE`) and reads the status the board streams as a regular ROP.
//!
//! - `embObjFTsensor` (`eomn_serv_AS_strain`, iCub): one strain sensor, named by
//!   `SERVICE/PROPERTIES/SENSORS/id`; `SETTINGS/acquisitionRate` (ms) and
//!   `STRAIN_SETTINGS/useCalibration` (calibrated or raw values) configure it. Values are
//!   the board's 16-bit readings scaled by the sensor's full scale (N, N·m). With
//!   `SETTINGS/temperature-acquisitionRate` (ms) above 0, a strain2's temperature service
//!   comes up too (°C, `ITemperatureSensors`).
//! - `embObjMultipleFTsensors` (`eomn_serv_AS_ft`, ergoCub): the FT sensors of
//!   `SETTINGS/enabledSensors` with `ftPeriod`, `temperaturePeriod` (ms) and
//!   `useCalibration`; the board streams N and N·m as floats, temperature in 0.1 °C.
//! - `embObjIMU`, `embObjInertials` (`eomn_serv_AS_inertials3`): the sensors of
//!   `SETTINGS/enabledSensors` (`SENSORS/id`, `type`, `sensorName`), sampled every
//!   `acquisitionRate` ms; BNO055 units as the boards send them: acceleration 100 LSB per
//!   m/s², angular rate and Euler angles 16 LSB per ° (/s), magnetic field 16 LSB per µT.
//! - `embObjMais` (`eomn_serv_AS_mais`): the 15 hall-sensor channels of the hand.
//!
//! A board that falls silent makes every reading fail within its presence timeout,
//! naming IP and board.

use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;

use icub_eth::entities::analog::{
    FtConfig, FtStatus, Inertial3Config, Inertial3Status, MaisStatus, StrainConfig, StrainStatus,
    TemperatureConfig,
};
use icub_eth::entities::mn::{category, service_type, ServiceCommand};
use icub_eth::id::{entity as en, ids, tag};
use icub_eth::{Entity, Id32};
use yarp_devices::sensors::forward::FamilySource;
use yarp_devices::sensors::interfaces::*;
use yarp_devices::sensors::SensorFamily;
use yarp_devices::{DevResult, DeviceDriver, DeviceError};
use yarp_proto::{Property, Value};

use super::config::{Node, ParamError};
use super::manager::{Board, EthManager};
use super::params::{read_eth_board, read_pc104, read_service, ServiceKind};
use super::service::{open_sensor, SensorService, Write};
use super::skin_spec::SkinSpec;

use yarp_proto::stamp::now;

/// `IAnalogSensor` of a single-sensor device with `values()` and `c: Common`: its
/// `channels` values, timed out while they cannot be read.
macro_rules! analog_sensor {
    ($ty:ty, $channels:literal) => {
        impl IAnalogSensor for $ty {
            fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
                match self.values() {
                    Ok(v) => {
                        *out = v;
                        AnalogStatus::Ok
                    }
                    Err(_) => AnalogStatus::Timeout,
                }
            }
            fn get_state(&mut self, _ch: usize) -> AnalogStatus {
                match self.c.status() {
                    MasStatus::Ok => AnalogStatus::Ok,
                    _ => AnalogStatus::Timeout,
                }
            }
            fn get_channels(&mut self) -> usize {
                $channels
            }
            fn calibrate_sensor(&mut self) -> DevResult<()> {
                Ok(())
            }
        }
    };
}

/// What every sensor device shares: its name, its board, its service.
#[derive(Default)]
struct Common {
    id: String,
    board: Option<Arc<Board>>,
}

impl Common {
    /// Reads the Ethernet groups, brings the board and the service up.
    fn open(
        &mut self,
        default_name: &str,
        config: &Property,
        expected_category: u8,
        service: impl FnOnce(&Node, u8) -> Result<SensorService, ParamError>,
    ) -> DevResult<()> {
        self.id = config
            .find("id")
            .map_or_else(|| default_name.to_string(), Value::to_string_bare);
        let id = self.id.clone();
        let pc104 = read_pc104(config).map_err(|e| e.for_device(&id))?;
        let eth = read_eth_board(config).map_err(|e| e.for_device(&id))?;
        // As C++ EmbObjSkin, a skin without a SERVICE group is a skin service all the same.
        let kind = match Node::root(config).group("SERVICE") {
            None if expected_category == category::SKIN => ServiceKind {
                service_type: service_type::SK_SKIN,
                category: category::SKIN,
            },
            _ => read_service(config).map_err(|e| e.for_device(&id))?,
        };
        if kind.category != expected_category {
            return Err(ParamError::bad(
                "SERVICE/type",
                "the service type of this device",
                format!("category {}", kind.category),
            )
            .for_device(&id));
        }
        let spec =
            service(&Node::root(config), kind.service_type).map_err(|e| e.for_device(&id))?;
        let mgr = EthManager::instance(&pc104).map_err(|e| DeviceError::failed(&id, e))?;
        let board = mgr.board(&eth);
        if let Err(e) = open_sensor(&board, &spec) {
            tracing::error!(device = %id, "{default_name}::open() fails for BOARD {}: {e}", board.who());
            return Err(DeviceError::failed(&id, e));
        }
        tracing::info!(device = %id, board = %board.who(), "{default_name} open");
        self.board = Some(board);
        Ok(())
    }

    fn read<T: Entity>(&self, id: Id32) -> DevResult<T> {
        let b = self.board.as_ref().ok_or(DeviceError::NotOpen)?;
        b.read(id).map_err(|e| DeviceError::failed(&self.id, e))
    }

    fn status(&self) -> MasStatus {
        match &self.board {
            Some(b) if !b.is_lost() => MasStatus::Ok,
            Some(_) => MasStatus::Timeout,
            None => MasStatus::Error,
        }
    }
}

fn no_sensor(device: &str, i: usize, n: usize) -> DeviceError {
    DeviceError::BadParam {
        device: device.to_string(),
        param: "sens_index".into(),
        expected: "an index below the number of sensors",
        got: format!("{i} (nr of sensors: {n})"),
    }
}

/// `SERVICE/SETTINGS` and `SERVICE/PROPERTIES/SENSORS`.
fn settings<'a>(root: &Node<'a>) -> Result<(Node<'a>, Node<'a>), ParamError> {
    let s = root.need_group("SERVICE")?;
    let settings = s.need_group("SETTINGS")?;
    let sensors = s.need_group("PROPERTIES")?.need_group("SENSORS")?;
    Ok((settings, sensors))
}

/// `verifyactivate` with the service's configuration, built from the device's files.
fn verify(root: &Node, cat: u8, service_type: u8) -> Result<ServiceCommand, ParamError> {
    let data = super::service_config::sensor_config(root, service_type)?;
    Ok(ServiceCommand::verify_activate(
        cat,
        service_type,
        0,
        0,
        &data,
    ))
}

// ---- embObjFTsensor ----

/// `embObjFTsensor`: one strain sensor (iCub), and the temperature of a strain2 board.
#[derive(Default)]
pub struct EmbObjFtSensor {
    c: Common,
    name: String,
    calibrated: bool,
}

pub const FT_SENSOR: &str = "embObjFTsensor";

/// How many times, and how long each, embObjFTsensor waits for the full scales.
const FULL_SCALE_TRIES: u32 = 5;
const FULL_SCALE_WAIT: std::time::Duration = std::time::Duration::from_secs(1);

/// icub-main's `fillScaleFactor`: empties the local full scales, then asks the strain to
/// signal them once (acquiring without transmitting) until they arrive, at most
/// [`FULL_SCALE_TRIES`] times [`FULL_SCALE_WAIT`].
fn fill_full_scales(board: &Board, datarate: u8) -> Result<(), super::manager::EthError> {
    let fullscale = ids::analog(en::AS_STRAIN, 0, tag::AS_STRAIN_STATUS_FULLSCALE);
    let empty = icub_eth::entities::analog::ByteArray::<12>::from_u16(&[]);
    board.set_local(fullscale, &empty.to_bytes())?;
    let ask = StrainConfig {
        mode: 1, // eoas_strainmode_acquirebutdonttx
        datarate,
        signal_once_fullscale: true,
    };
    let config = ids::analog(en::AS_STRAIN, 0, tag::AS_STRAIN_CONFIG);
    for _ in 0..FULL_SCALE_TRIES {
        board.set(config, &ask.to_bytes())?;
        let until = std::time::Instant::now() + FULL_SCALE_WAIT;
        while std::time::Instant::now() < until {
            let got: icub_eth::entities::analog::ByteArray<12> = board.read(fullscale)?;
            match got.size {
                0 => std::thread::sleep(std::time::Duration::from_millis(10)),
                6 => return Ok(()),
                n => {
                    return Err(super::manager::EthError::Board {
                        who: board.who(),
                        reason: format!(
                            "the strain's calibration data has {n} values, not its 6 channels"
                        ),
                    })
                }
            }
        }
    }
    Err(super::manager::EthError::Board {
        who: board.who(),
        reason:
            "fillScaleFactor(): ETH Analog sensor: request for calibration parameters timed out"
                .into(),
    })
}

impl EmbObjFtSensor {
    pub fn new() -> Self {
        Self::default()
    }

    /// The six readings: with calibration, the calibrated values scaled by the full
    /// scales (N, N·m); without, the raw readings (as C++).
    fn values(&self) -> DevResult<Vec<f64>> {
        let st: StrainStatus = self
            .c
            .read(ids::analog(en::AS_STRAIN, 0, tag::AS_STRAIN_STATUS))?;
        if !self.calibrated {
            return Ok(StrainStatus::readings(&st.uncalibrated)
                .into_iter()
                .map(f64::from)
                .collect());
        }
        let full = st.full_scales();
        Ok(StrainStatus::readings(&st.calibrated)
            .iter()
            .take(6)
            .enumerate()
            .map(|(k, v)| f64::from(*v) * f64::from(full.get(k).copied().unwrap_or(0)) / 32768.0)
            .collect())
    }
}

impl DeviceDriver for EmbObjFtSensor {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(FT_SENSOR)
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(FT_SENSOR, config);
        let mut name = String::new();
        let mut calibrated = true;
        self.c
            .open(FT_SENSOR, config, category::STRAIN, |root, st| {
                let (set, sensors) = settings(root)?;
                name = sensors.need_string("id", "the sensor's name")?;
                let rate = set.number("acquisitionRate")?.unwrap_or(10.0);
                // ms; C++ keeps whole seconds of it (an int divided by 1000)
                let t_rate = set.number("temperature-acquisitionRate")?.unwrap_or(0.0) as i64;
                calibrated = root
                    .group("SERVICE")
                    .and_then(|s| s.group("STRAIN_SETTINGS"))
                    .and_then(|s| s.boolean("useCalibration"))
                    .unwrap_or(true);
                let datarate = rate.clamp(1.0, 255.0) as u8;
                // eo_ftsens_privData::sendConfig2Strain: the strain, then the temperature
                let strain_cfg = StrainConfig {
                    mode: if calibrated { 0 } else { 3 },
                    datarate,
                    signal_once_fullscale: false,
                };
                let temperature_cfg = TemperatureConfig {
                    datarate: if t_rate > 0 {
                        (t_rate / 1000) as u16
                    } else {
                        0
                    },
                    enabled: u16::from(t_rate > 0),
                };
                let values = if calibrated {
                    tag::AS_STRAIN_STATUS_CALIBRATEDVALUES
                } else {
                    tag::AS_STRAIN_STATUS_UNCALIBRATEDVALUES
                };
                let mut strain = SensorService::new(verify(root, category::STRAIN, st)?);
                strain.configs = vec![
                    (
                        ids::analog(en::AS_STRAIN, 0, tag::AS_STRAIN_CONFIG),
                        strain_cfg.to_bytes(),
                    ),
                    (
                        ids::analog(en::AS_TEMPERATURE, 0, tag::AS_XX_CONFIG),
                        temperature_cfg.to_bytes(),
                    ),
                ];
                strain.regulars = vec![ids::analog(en::AS_STRAIN, 0, values)];
                if calibrated {
                    strain.prepare = Some(Box::new(move |b: &Board| fill_full_scales(b, datarate)));
                }
                // the strain2's temperature, when the file asks for it (icub-main 2.11);
                // without it C++ still loads the temperature regulars (initRegulars)
                if t_rate <= 0 {
                    strain.other_regulars = vec![(
                        category::TEMPERATURES,
                        vec![ids::analog(en::AS_TEMPERATURE, 0, tag::AS_XX_STATUS)],
                    )];
                }
                if t_rate > 0 {
                    let data = super::service_config::strain_temperature_config(root)?;
                    let mut t = SensorService::new(ServiceCommand::verify_activate(
                        category::TEMPERATURES,
                        service_type::AS_TEMPERATURES,
                        0,
                        0,
                        &data,
                    ));
                    t.regulars = vec![ids::analog(en::AS_TEMPERATURE, 0, tag::AS_XX_STATUS)];
                    t.after_start = vec![(
                        ids::analog(en::AS_TEMPERATURE, 0, tag::AS_XX_CMMNDS_ENABLE),
                        vec![1],
                        Write::Set,
                    )];
                    strain.companion = Some(Box::new(t));
                }
                Ok(strain)
            })?;
        self.name = name;
        self.calibrated = calibrated;
        Ok(())
    }
    yarp_devices::views!(
        as_six_axis_force_torque_sensors,
        as_analog_sensor,
        as_temperature_sensors
    );
}

/// One strain sensor in both families C++ serves: its force-torque, and the strain2's
/// temperature (the board's temperature service, 0.1 °C units; `NotReady` while the
/// board sends none), under the sensor's name, which is also its frame.
impl FamilySource for EmbObjFtSensor {
    fn family_count(&self, _family: SensorFamily) -> usize {
        1
    }
    fn family_status(&self, _family: SensorFamily, i: usize) -> MasStatus {
        if i == 0 {
            self.c.status()
        } else {
            MasStatus::Error
        }
    }
    fn family_name(&self, _family: SensorFamily, i: usize) -> DevResult<String> {
        if i != 0 {
            return Err(no_sensor(&self.c.id, i, 1));
        }
        Ok(self.name.clone())
    }
    fn family_frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.family_name(family, i)
    }
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        if i != 0 {
            return Err(no_sensor(&self.c.id, i, 1));
        }
        if family != SensorFamily::TemperatureSensors {
            return Ok(SensorMeasurement::new(self.values()?, now()));
        }
        let st: icub_eth::entities::analog::TemperatureStatus =
            self.c
                .read(ids::analog(en::AS_TEMPERATURE, 0, tag::AS_XX_STATUS))?;
        let v = st
            .data
            .first()
            .map(|d| f64::from(d.value) / 10.0)
            .ok_or(DeviceError::NotReady("no temperature from the board yet"))?;
        Ok(SensorMeasurement::new(vec![v], now()))
    }
}

yarp_devices::mas_interfaces!(EmbObjFtSensor: SixAxisForceTorqueSensors, TemperatureSensors);

analog_sensor!(EmbObjFtSensor, 6);

// ---- embObjMultipleFTsensors ----

/// `embObjMultipleFTsensors`: the FT sensors of a board (ergoCub), with temperatures.
/// As icub-main's `ServiceParserMultipleFt` keeps them in a map by id, the board's
/// sensor `i` is the `i`-th enabled id in sorted order, with that sensor's own
/// `ftPeriod`, `temperaturePeriod` and `useCalibration` (one value per enabled sensor).
#[derive(Default)]
pub struct EmbObjMultipleFtSensors {
    c: Common,
    names: Vec<String>,
    /// `PROPERTIES/SENSORS/framename` of each, empty when the file has none (as C++).
    frames: Vec<String>,
}

pub const MULTIPLE_FT: &str = "embObjMultipleFTsensors";

/// One enabled sensor's settings (`ServiceParserMultipleFt::FtInfo`).
struct FtSettings {
    id: String,
    frame: String,
    config: FtConfig,
}

/// The enabled sensors in the board's order, with their settings.
fn multiple_ft_settings(root: &Node) -> Result<Vec<FtSettings>, ParamError> {
    let (set, sensors) = settings(root)?;
    let enabled = set
        .strings("enabledSensors")
        .filter(|v| !v.is_empty())
        .ok_or_else(|| ParamError::missing("SETTINGS/enabledSensors", "sensor names"))?;
    if enabled.len() > 4 {
        return Err(ParamError::bad(
            "SETTINGS/enabledSensors",
            "at most 4 sensors",
            enabled.join(" "),
        ));
    }
    let n = enabled.len();
    let ft = set.need_numbers("ftPeriod", n)?;
    let temperature = set.need_numbers("temperaturePeriod", n)?;
    let calibration = set.need_strings("useCalibration", n)?;
    let ids = sensors.strings("id").unwrap_or_default();
    let frames = sensors.strings("framename");
    let mut all: Vec<FtSettings> = Vec::with_capacity(n);
    for (k, id) in enabled.iter().enumerate() {
        if all.iter().any(|s| &s.id == id) {
            return Err(ParamError::bad(
                "SETTINGS/enabledSensors",
                "distinct ids",
                id.clone(),
            ));
        }
        let frame = ids
            .iter()
            .position(|i| i == id)
            .and_then(|p| frames.as_ref()?.get(p).cloned())
            .unwrap_or_default();
        let calibrated = matches!(
            calibration[k].trim_matches('"'),
            "true" | "1" | "TRUE" | "True"
        );
        all.push(FtSettings {
            id: id.clone(),
            frame,
            config: FtConfig {
                // eOas_ft_mode_t: raw 0, calibrated 1
                mode: u8::from(calibrated),
                // C++ takes `asInt8()` of each as the board's uint8_t fields
                ftperiod: ft[k] as i64 as u8,
                calibration_set: 0,
                temperature_period: ((temperature[k] as i64 as u32) / 1000) as u8,
            },
        });
    }
    all.sort_by(|a, b| a.id.cmp(&b.id));
    Ok(all)
}

impl EmbObjMultipleFtSensors {
    pub fn new() -> Self {
        Self::default()
    }
    fn status_of(&self, i: usize) -> DevResult<FtStatus> {
        if i >= self.names.len() {
            return Err(no_sensor(&self.c.id, i, self.names.len()));
        }
        self.c
            .read(ids::analog(en::AS_FT, i as u8, tag::AS_FT_STATUS))
    }
}

impl DeviceDriver for EmbObjMultipleFtSensors {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(MULTIPLE_FT)
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(MULTIPLE_FT, config);
        let mut sensors = Vec::new();
        self.c.open(MULTIPLE_FT, config, category::FT, |root, st| {
            sensors = multiple_ft_settings(root)?;
            let mut service = SensorService::new(verify(root, category::FT, st)?);
            for (i, s) in sensors.iter().enumerate() {
                let i = i as u8;
                service.configs.push((
                    ids::analog(en::AS_FT, i, tag::AS_FT_CONFIG),
                    s.config.to_bytes(),
                ));
                service
                    .regulars
                    .push(ids::analog(en::AS_FT, i, tag::AS_FT_STATUS_TIMEDVALUE));
                service.after_start.push((
                    ids::analog(en::AS_FT, i, tag::AS_FT_CMMNDS_ENABLE),
                    vec![1],
                    Write::SetCheck,
                ));
            }
            Ok(service)
        })?;
        self.names = sensors.iter().map(|s| s.id.clone()).collect();
        self.frames = sensors.into_iter().map(|s| s.frame).collect();
        Ok(())
    }
    yarp_devices::views!(as_six_axis_force_torque_sensors, as_temperature_sensors);
}

/// The board's sensors as both families C++ serves them: force-torque, and each sensor's
/// temperature (°C, the board's 0.1 °C units) under the same name and frame.
impl FamilySource for EmbObjMultipleFtSensors {
    fn family_count(&self, _family: SensorFamily) -> usize {
        self.names.len()
    }
    fn family_status(&self, _family: SensorFamily, i: usize) -> MasStatus {
        if i < self.names.len() {
            self.c.status()
        } else {
            MasStatus::Error
        }
    }
    fn family_name(&self, _family: SensorFamily, i: usize) -> DevResult<String> {
        self.names
            .get(i)
            .cloned()
            .ok_or_else(|| no_sensor(&self.c.id, i, self.names.len()))
    }
    fn family_frame_name(&self, _family: SensorFamily, i: usize) -> DevResult<String> {
        self.frames
            .get(i)
            .cloned()
            .ok_or_else(|| no_sensor(&self.c.id, i, self.names.len()))
    }
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        let s = self.status_of(i)?;
        let values = match family {
            SensorFamily::TemperatureSensors => vec![f64::from(s.timed_value.temperature) / 10.0],
            _ => s.timed_value.values.iter().map(|v| f64::from(*v)).collect(),
        };
        Ok(SensorMeasurement::new(values, now()))
    }
}

yarp_devices::mas_interfaces!(EmbObjMultipleFtSensors: SixAxisForceTorqueSensors, TemperatureSensors);

// ---- embObjIMU / embObjInertials ----

/// `eOas_sensor_t` of the inertial sensors.
pub mod sensor_type {
    pub use icub_eth::entities::analog::sensor_type::*;

    /// The `eoas_*` names of `SENSORS/type`.
    pub fn from_name(s: &str) -> Option<u8> {
        Some(match s.trim_matches('"') {
            "eoas_accel_mtb_int" => ACCEL_MTB_INT,
            "eoas_accel_mtb_ext" => ACCEL_MTB_EXT,
            "eoas_gyros_mtb_ext" => GYROS_MTB_EXT,
            "eoas_accel_st_lis3x" => ACCEL_ST_LIS3X,
            "eoas_gyros_st_l3g4200d" => GYROS_ST_L3G4200D,
            "eoas_imu_acc" => IMU_ACC,
            "eoas_imu_mag" => IMU_MAG,
            "eoas_imu_gyr" => IMU_GYR,
            "eoas_imu_eul" => IMU_EUL,
            "eoas_imu_qua" => IMU_QUA,
            "eoas_imu_lia" => IMU_LIA,
            "eoas_imu_grv" => IMU_GRV,
            "eoas_imu_status" => IMU_STATUS,
            _ => return None,
        })
    }
}

/// One enabled inertial sensor.
#[derive(Debug, Clone)]
pub struct InertialSensor {
    pub id: String,
    /// `sensorName` (the IMU the reading belongs to), else the id.
    pub name: String,
    pub kind: u8,
    /// The id its readings carry: `port << 4 | address` of its CAN board (icub-main's
    /// `PositionMaps::getCanAddress`); `None` for the Ethernet board's own gyroscope,
    /// whose readings are known by their type alone.
    pub can_id: Option<u8>,
}

/// The enabled sensors of an inertials3 service (`SETTINGS/enabledSensors` looked up in
/// `PROPERTIES/SENSORS`), in the order the board numbers them.
pub fn inertial_sensors(config: &Property) -> Result<Vec<InertialSensor>, ParamError> {
    let root = Node::root(config);
    let (set, sensors) = settings(&root)?;
    let ids = sensors
        .strings("id")
        .ok_or_else(|| ParamError::missing("SENSORS/id", "sensor ids"))?;
    let types = sensors.need_strings("type", ids.len())?;
    let locations = sensors.need_strings("location", ids.len())?;
    let names = sensors
        .strings("sensorName")
        .filter(|v| v.len() == ids.len())
        .unwrap_or_else(|| ids.clone());
    let enabled = set.strings("enabledSensors").unwrap_or_else(|| ids.clone());
    enabled
        .iter()
        .map(|e| {
            let k = ids.iter().position(|i| i == e).ok_or_else(|| {
                ParamError::bad("SETTINGS/enabledSensors", "ids of SENSORS/id", e)
            })?;
            let kind = sensor_type::from_name(&types[k]).ok_or_else(|| {
                ParamError::bad("SENSORS/type", "an eoas_* inertial type", &types[k])
            })?;
            let can_id = if kind == sensor_type::GYROS_ST_L3G4200D {
                None
            } else {
                super::service_config::can_location(&locations[k])
                    .map(|l| l.port << 4 | (l.addr & 0x0F))
            };
            Ok(InertialSensor {
                id: e.clone(),
                name: names[k].clone(),
                kind,
                can_id,
            })
        })
        .collect()
}

/// The latest reading of every sensor of an inertials3 service, by type and id (the
/// board sends at most four readings per status ROP, so every ROP is folded in).
#[derive(Default)]
struct InertialCache {
    by_key: HashMap<(u8, Option<u8>), [i16; 4]>,
}
/// `embObjIMU` / `embObjInertials`: the IMUs (or MTB accelerometers / gyroscopes) of a
/// board.
#[derive(Default)]
pub struct EmbObjImu {
    kind_name: &'static str,
    c: Common,
    sensors: Vec<InertialSensor>,
    cache: Mutex<InertialCache>,
}

pub const IMU: &str = "embObjIMU";
pub const INERTIALS: &str = "embObjInertials";

impl EmbObjImu {
    pub fn new(kind_name: &'static str) -> Self {
        Self {
            kind_name,
            ..Default::default()
        }
    }

    /// The C++ name this device was made as (`embObjIMU` by default).
    fn device_name(&self) -> &'static str {
        if self.kind_name.is_empty() {
            IMU
        } else {
            self.kind_name
        }
    }

    /// Folds every status received since the last call into the cache (as C++ does in
    /// `update()`, ROP by ROP) and returns the reading of sensor `k`.
    fn reading(&self, k: usize) -> DevResult<[i16; 4]> {
        let board = self.c.board.as_ref().ok_or(DeviceError::NotOpen)?;
        // a silent board makes the read fail, naming it
        let _: Inertial3Status = self.c.read(STATUS)?;
        let mut cache = self.cache.lock();
        for bytes in board.take_kept(STATUS) {
            let Ok(st) = Inertial3Status::from_bytes(&bytes) else {
                continue;
            };
            for d in &st.data {
                // C++ PositionMaps: the Ethernet board's gyroscope by its type, the
                // others by type, CAN port and address
                let key = if d.type_of_sensor == sensor_type::GYROS_ST_L3G4200D {
                    (d.type_of_sensor, None)
                } else {
                    (d.type_of_sensor, Some(d.id))
                };
                cache.by_key.insert(key, [d.x, d.y, d.z, d.w]);
            }
        }
        let s = &self.sensors[k];
        Ok(cache
            .by_key
            .get(&(s.kind, s.can_id))
            .copied()
            .unwrap_or_default())
    }

    /// The sensors of an interface, in C++'s order: by type as `kinds` lists them, then
    /// in the configuration's order.
    fn of_kind(&self, kinds: &[u8]) -> Vec<usize> {
        kinds
            .iter()
            .flat_map(|kind| {
                self.sensors
                    .iter()
                    .enumerate()
                    .filter(move |(_, s)| s.kind == *kind)
                    .map(|(k, _)| k)
            })
            .collect()
    }

    fn nth(&self, kinds: &[u8], i: usize) -> DevResult<usize> {
        let v = self.of_kind(kinds);
        v.get(i)
            .copied()
            .ok_or_else(|| no_sensor(&self.c.id, i, v.len()))
    }

    /// Sensor `i` of the interface, its values divided by its type's factor (icub-main's
    /// `SensorsData::init`: only the IMU's sensors have one; the MTBs' and the Ethernet
    /// board's readings pass as they are).
    fn measure(&self, kinds: &[u8], i: usize) -> DevResult<SensorMeasurement> {
        let k = self.nth(kinds, i)?;
        let r = self.reading(k)?;
        let factor = match self.sensors[k].kind {
            sensor_type::IMU_ACC => 100.0,
            sensor_type::IMU_MAG => 16.0e6,
            sensor_type::IMU_GYR | sensor_type::IMU_EUL => 16.0,
            _ => 1.0,
        };
        Ok(SensorMeasurement::new(
            r[..3].iter().map(|v| f64::from(*v) / factor).collect(),
            now(),
        ))
    }

    fn name(&self, kinds: &[u8], i: usize) -> DevResult<String> {
        Ok(self.sensors[self.nth(kinds, i)?].name.clone())
    }

    fn status(&self, kinds: &[u8], i: usize) -> MasStatus {
        if i < self.of_kind(kinds).len() {
            self.c.status()
        } else {
            MasStatus::Error
        }
    }
}

const STATUS: Id32 = ids::analog(en::AS_INERTIAL3, 0, tag::AS_XX_STATUS);

/// The accelerometers and gyroscopes in icub-main's order (`getAccSubIndex`,
/// `getGyroSubIndex`).
const ACC: &[u8] = &[
    sensor_type::IMU_ACC,
    sensor_type::ACCEL_MTB_INT,
    sensor_type::ACCEL_MTB_EXT,
];
const GYR: &[u8] = &[
    sensor_type::IMU_GYR,
    sensor_type::GYROS_ST_L3G4200D,
    sensor_type::GYROS_MTB_EXT,
];
const MAG: &[u8] = &[sensor_type::IMU_MAG];
const EUL: &[u8] = &[sensor_type::IMU_EUL];

impl DeviceDriver for EmbObjImu {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(self.device_name())
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(self.device_name(), config);
        let name = self.device_name();
        let sensors = inertial_sensors(config).map_err(|e| e.for_device(name))?;
        let n = sensors.len();
        self.c
            .open(name, config, category::INERTIALS3, |root, st| {
                let (set, _) = settings(root)?;
                let rate = set.number("acquisitionRate")?.unwrap_or(10.0);
                let cfg = Inertial3Config {
                    datarate: rate.clamp(1.0, 255.0) as u8,
                    items_to_fill_at_each_tick: 0,
                    enabled: if n >= 32 { u32::MAX } else { (1u32 << n) - 1 },
                };
                Ok(SensorService {
                    activate: verify(root, category::INERTIALS3, st)?,
                    configs: vec![(
                        ids::analog(en::AS_INERTIAL3, 0, tag::AS_XX_CONFIG),
                        cfg.to_bytes(),
                    )],
                    regulars: vec![ids::analog(en::AS_INERTIAL3, 0, tag::AS_XX_STATUS)],
                    prepare: None,
                    companion: None,
                    other_regulars: Vec::new(),
                    before_start: Vec::new(),
                    after_start: vec![(
                        ids::analog(en::AS_INERTIAL3, 0, tag::AS_XX_CMMNDS_ENABLE),
                        vec![1],
                        Write::Set,
                    )],
                })
            })?;
        self.sensors = sensors;
        if let Some(b) = &self.c.board {
            b.keep_values(STATUS);
        }
        Ok(())
    }
    yarp_devices::imu_views!();
}

/// The board's sensors by family: each family is the sensors of its types (the frame of
/// a sensor is its name, as C++).
impl FamilySource for EmbObjImu {
    fn family_count(&self, family: SensorFamily) -> usize {
        kinds_of(family).map_or(0, |k| self.of_kind(k).len())
    }
    fn family_status(&self, family: SensorFamily, i: usize) -> MasStatus {
        kinds_of(family).map_or(MasStatus::Error, |k| self.status(k, i))
    }
    fn family_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.name(kinds_of(family).unwrap_or(&[]), i)
    }
    fn family_frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.name(kinds_of(family).unwrap_or(&[]), i)
    }
    /// Magnetometers in tesla (16 LSB per µT).
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(kinds_of(family).unwrap_or(&[]), i)
    }
}

/// The board's sensor types of a family.
fn kinds_of(family: SensorFamily) -> Option<&'static [u8]> {
    match family {
        SensorFamily::ThreeAxisGyroscopes => Some(GYR),
        SensorFamily::ThreeAxisLinearAccelerometers => Some(ACC),
        SensorFamily::ThreeAxisMagnetometers => Some(MAG),
        SensorFamily::OrientationSensors => Some(EUL),
        _ => None,
    }
}

yarp_devices::mas_interfaces!(EmbObjImu: ThreeAxisGyroscopes, ThreeAxisLinearAccelerometers,
    ThreeAxisMagnetometers, OrientationSensors);

// ---- embObjMais ----

/// `embObjMais`: the 15 channels of a hand's MAIS board, as icub-main 2.11 serves them:
/// one encoder array (`IEncoderArrays`, what the robots' `multipleanalogsensorsserver`
/// publishes) named by `SENSORS/id`, and as an `IAnalogSensor` (older wrappers).
#[derive(Default)]
pub struct EmbObjMais {
    c: Common,
    name: String,
}

pub const MAIS: &str = "embObjMais";

impl EmbObjMais {
    pub fn new() -> Self {
        Self::default()
    }

    /// The 15 values and when they were read.
    fn values(&self) -> DevResult<Vec<f64>> {
        let s: MaisStatus = self
            .c
            .read(ids::analog(en::AS_MAIS, 0, tag::AS_MAIS_STATUS))?;
        let mut v: Vec<f64> = s
            .the15values
            .u8_values()
            .iter()
            .take(15)
            .map(|v| f64::from(*v))
            .collect();
        if v.is_empty() {
            // C++ keeps its values when the items are not bytes: none yet here
            return Err(DeviceError::failed(
                &self.c.id,
                "no MAIS values from the board yet",
            ));
        }
        v.resize(15, 0.0);
        Ok(v)
    }
}

impl DeviceDriver for EmbObjMais {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(MAIS)
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(MAIS, config);
        let mut name = String::new();
        self.c.open(MAIS, config, category::MAIS, |root, st| {
            let (set, sensors) = settings(root)?;
            name = sensors.string("id").unwrap_or_default();
            let rate = set.number("acquisitionRate")?.unwrap_or(10.0);
            let mut service = SensorService::new(verify(root, category::MAIS, st)?);
            // embObjMais::sendConfig2Mais: the datarate, then the mode (tx continuously);
            // the resolution is left as the board has it
            service.configs = vec![
                (
                    ids::analog(en::AS_MAIS, 0, tag::AS_MAIS_CONFIG_DATARATE),
                    vec![rate.clamp(0.0, 255.0) as u8],
                ),
                (
                    ids::analog(en::AS_MAIS, 0, tag::AS_MAIS_CONFIG_MODE),
                    vec![0],
                ),
            ];
            service.regulars = vec![ids::analog(en::AS_MAIS, 0, tag::AS_MAIS_STATUS_THE15VALUES)];
            Ok(service)
        })?;
        self.name = name;
        Ok(())
    }
    yarp_devices::views!(as_analog_sensor, as_encoder_arrays);
}

/// One encoder array of the 15 values, as C++'s `IEncoderArrays`.
impl FamilySource for EmbObjMais {
    fn family_count(&self, _family: SensorFamily) -> usize {
        1
    }
    fn family_status(&self, _family: SensorFamily, i: usize) -> MasStatus {
        if i == 0 {
            MasStatus::Ok
        } else {
            MasStatus::Unknown
        }
    }
    fn family_name(&self, _family: SensorFamily, i: usize) -> DevResult<String> {
        if i != 0 {
            return Err(no_sensor(&self.c.id, i, 1));
        }
        Ok(self.name.clone())
    }
    fn family_frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.family_name(family, i)
    }
    fn family_size(&self, _family: SensorFamily, i: usize) -> usize {
        if i == 0 {
            15
        } else {
            0
        }
    }
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        self.family_name(family, i)?;
        Ok(SensorMeasurement::new(self.values()?, now()))
    }
}

yarp_devices::mas_interfaces!(EmbObjMais: EncoderArrays);

analog_sensor!(EmbObjMais, 15);

// ---- embObjSkin ----

/// One configuration command of a skin, sent after `pause`.
struct SkinCommand {
    pause: std::time::Duration,
    id: Id32,
    data: Vec<u8>,
}

/// Sends a skin's board and triangle configurations (between its service's verification
/// and its regulars, as C++), then waits the 10 ms C++ waits after them.
fn send_skin_commands(
    board: &Board,
    commands: &[SkinCommand],
) -> Result<(), super::manager::EthError> {
    for c in commands {
        std::thread::sleep(c.pause);
        board.set(c.id, &c.data)?;
    }
    std::thread::sleep(std::time::Duration::from_millis(10));
    Ok(())
}

/// The skin patches of a board: `patches/skinCanAddrsPatchN` (N = the CAN port, 1 or 2,
/// as C++ reads them) list the MTB addresses of each patch; every MTB has 16 triangles
/// of 12 taxels.
pub fn skin_patches(config: &Property) -> Result<Vec<Vec<u8>>, ParamError> {
    Ok(skin_patches_on_ports(config)?
        .into_iter()
        .map(|(_, addrs)| addrs)
        .collect())
}

/// [`skin_patches`] with the CAN port (1 or 2) of each.
pub fn skin_patches_on_ports(config: &Property) -> Result<Vec<(u8, Vec<u8>)>, ParamError> {
    let g = Node::root(config).need_group("patches")?;
    let mut patches = Vec::new();
    for port in 1..=2u8 {
        let key = format!("skinCanAddrsPatch{port}");
        if let Some(v) = g.strings(&key) {
            let addrs: Option<Vec<u8>> = v
                .iter()
                .map(|s| super::config::parse_number(s).map(|n| n as u8))
                .collect();
            patches.push((
                port,
                addrs.ok_or_else(|| {
                    ParamError::bad(format!("patches/{key}"), "MTB CAN addresses", v.join(" "))
                })?,
            ));
        }
    }
    if patches.is_empty() {
        return Err(ParamError::missing(
            "patches/skinCanAddrsPatchN",
            "MTB CAN addresses",
        ));
    }
    Ok(patches)
}

/// The iCub CAN id of a skin triangle's periodic message (`ICUBCANPROTO_CLASS_PERIODIC_SKIN`).
pub fn skin_can_id(addr: u8, triangle: u8) -> u16 {
    (4 << 8) | (u16::from(addr & 0xf) << 4) | u16::from(triangle & 0xf)
}

/// `embObjSkin`: the taxels of a board's skin patches, as `IAnalogSensor` (the
/// `skinWrapper` splits them into parts).
#[derive(Default)]
pub struct EmbObjSkin {
    c: Common,
    patches: Vec<Vec<u8>>,
    taxels: Mutex<Vec<f64>>,
}

pub const SKIN: &str = "embObjSkin";

impl EmbObjSkin {
    pub fn new() -> Self {
        Self::default()
    }

    /// The first taxel of MTB `addr` of patch `p` (C++ `EmbObjSkin::update`: with two
    /// patches the second one's boards come first).
    fn board_index(&self, p: usize, addr: u8) -> Option<usize> {
        let i = self.patches.get(p)?.iter().position(|a| *a == addr)?;
        Some(if self.patches.len() == 2 && p == 0 {
            i + self.patches[1].len()
        } else {
            i
        })
    }

    /// The commands of `EmbObjSkin::init` and `initWithSpecialConfig`, in order, each
    /// with the pause C++ makes before it; the special boards' noLoad set in `taxels`.
    fn skin_commands(
        &self,
        spec: &SkinSpec,
        on_ports: &[(u8, Vec<u8>)],
        taxels: &mut [f64],
    ) -> Result<Vec<SkinCommand>, ParamError> {
        use super::skin_spec as ss;
        let ms = std::time::Duration::from_millis;
        let mut out = Vec::new();
        for p in 0..on_ports.len() {
            out.push(SkinCommand {
                pause: ms(0),
                id: ids::skin(p as u8, tag::SK_SKIN_CMMNDS_BOARDSCFG),
                data: ss::default_boards(&spec.board).to_bytes(),
            });
        }
        for p in 0..on_ports.len() {
            out.push(SkinCommand {
                pause: ms(if p == 0 { 10 } else { 0 }),
                id: ids::skin(p as u8, tag::SK_SKIN_CMMNDS_TRIANGLESCFG),
                data: ss::default_triangles(&spec.triangle).to_bytes(),
            });
        }
        // "enough time to skin boards to configure all its triangles"
        let mut pause = ms(500);
        let patch_of = |id: u8, what: &str| {
            on_ports
                .iter()
                .position(|(port, _)| *port == id)
                .ok_or_else(|| {
                    ParamError::bad(
                        what.to_string(),
                        "a patch of patches/",
                        format!("patch {id}"),
                    )
                })
        };
        for s in &spec.special_boards {
            let p = patch_of(s.patch, "specialCfgBoards")?;
            let (port, addrs) = &on_ports[p];
            out.push(SkinCommand {
                pause,
                id: ids::skin(p as u8, tag::SK_SKIN_CMMNDS_BOARDSCFG),
                data: ss::special_boards(s, *port, addrs)?.to_bytes(),
            });
            pause = ms(0);
            for a in s.first..=s.last {
                if let Some(b) = self.board_index(p, a) {
                    if let Some(t) = taxels.get_mut(b * 192..b * 192 + 192) {
                        t.fill(f64::from(s.cfg.no_load));
                    }
                }
            }
        }
        pause += ms(10);
        for s in &spec.special_triangles {
            let p = patch_of(s.patch, "specialCfgTriangles")?;
            let (port, addrs) = &on_ports[p];
            // one command at a time, or the board cannot send on its CAN bus
            out.push(SkinCommand {
                pause: pause + ms(10),
                id: ids::skin(p as u8, tag::SK_SKIN_CMMNDS_TRIANGLESCFG),
                data: ss::special_triangles(s, *port, addrs)?.to_bytes(),
            });
            pause = ms(0);
        }
        Ok(out)
    }

    /// Applies every status the board sent since the last call, in order (C++ does it in
    /// `update()`, ROP by ROP: a taxel's frame in one status is not overwritten by the
    /// next status, which carries other triangles).
    fn update(&self) -> DevResult<()> {
        let board = self.c.board.as_ref().ok_or(DeviceError::NotOpen)?;
        let mut taxels = self.taxels.lock();
        for p in 0..self.patches.len() {
            let id = ids::skin(p as u8, tag::SK_SKIN_STATUS_ARRAYOFCANDATA);
            // a silent board makes the read fail, naming it
            let _: icub_eth::entities::skin::SkinStatus = self.c.read(id)?;
            for bytes in board.take_kept(id) {
                let Ok(st) = icub_eth::entities::skin::SkinStatus::from_bytes(&bytes) else {
                    continue;
                };
                for f in &st.frames {
                    self.apply(&mut taxels, p, f);
                }
            }
        }
        Ok(())
    }

    /// One CAN frame of an MTB: taxels 0-6 (`0x40`) or 7-11 (`0xC0`) of a triangle.
    fn apply(&self, taxels: &mut [f64], p: usize, f: &icub_eth::entities::skin::SkinCanData) {
        let id = f.can_id();
        if !matches!((id >> 8) & 0xf, 3 | 4) {
            return;
        }
        let Some(b) = self.board_index(p, ((id >> 4) & 0xf) as u8) else {
            return;
        };
        let base = b * 192 + usize::from(id & 0xf) * 12;
        let d = f.payload();
        let (first, count) = match d.first() {
            Some(0x40) => (0, 7),
            Some(0xC0) => (7, 5),
            _ => return,
        };
        for k in 0..count {
            if let (Some(v), Some(t)) = (d.get(k + 1), taxels.get_mut(base + first + k)) {
                *t = f64::from(*v);
            }
        }
    }
}

impl DeviceDriver for EmbObjSkin {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(SKIN)
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(SKIN, config);
        let id = config
            .find("id")
            .map_or_else(|| SKIN.to_string(), Value::to_string_bare);
        let on_ports = skin_patches_on_ports(config).map_err(|e| e.for_device(&id))?;
        let spec = SkinSpec::read(&Node::root(config)).map_err(|e| e.for_device(&id))?;
        let patches: Vec<Vec<u8>> = on_ports.iter().map(|(_, a)| a.clone()).collect();
        self.patches = patches.clone();
        // C++ starts every taxel at 240, then (new style) at the boards' noLoad
        let boards: usize = patches.iter().map(Vec::len).sum();
        let mut taxels = vec![240.0; boards * 192];
        let commands = match &spec {
            Some(spec) => {
                taxels.fill(f64::from(spec.board.no_load));
                self.skin_commands(spec, &on_ports, &mut taxels)
                    .map_err(|e| e.for_device(&id))?
            }
            None => Vec::new(),
        };
        *self.taxels.lock() = taxels;
        let n = patches.len();
        self.c.open(SKIN, config, category::SKIN, |root, st| {
            let mut service = SensorService::new(verify(root, category::SKIN, st)?);
            let mode = if spec.is_some() {
                icub_eth::entities::skin::sigmode::SIGNAL
            } else {
                icub_eth::entities::skin::sigmode::SIGNAL_OLDWAY
            };
            for p in 0..n as u8 {
                // C++ start(): setRemoteValue, after the regulars, before the service starts
                service.before_start.push((
                    ids::skin(p, tag::SK_SKIN_CONFIG_SIGMODE),
                    vec![mode],
                    Write::Set,
                ));
                service
                    .regulars
                    .push(ids::skin(p, tag::SK_SKIN_STATUS_ARRAYOFCANDATA));
            }
            if !commands.is_empty() {
                service.prepare = Some(Box::new(move |b: &Board| send_skin_commands(b, &commands)));
            }
            Ok(service)
        })?;
        if let Some(b) = &self.c.board {
            for p in 0..n {
                b.keep_values(ids::skin(p as u8, tag::SK_SKIN_STATUS_ARRAYOFCANDATA));
            }
        }
        Ok(())
    }
    yarp_devices::views!(as_analog_sensor);
}

impl IAnalogSensor for EmbObjSkin {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        if self.update().is_err() {
            return AnalogStatus::Timeout;
        }
        out.clone_from(&self.taxels.lock());
        AnalogStatus::Ok
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        match self.c.status() {
            MasStatus::Ok => AnalogStatus::Ok,
            _ => AnalogStatus::Timeout,
        }
    }
    fn get_channels(&mut self) -> usize {
        self.taxels.lock().len()
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        Ok(())
    }
}

// ---- embObjPOS ----

/// `embObjPOS`: the position sensors of the hands (FAP encoders, deci-degrees on the
/// wire), as `IEncoderArrays` (one angle in degrees per enabled sensor), as C++.
#[derive(Default)]
pub struct EmbObjPos {
    c: Common,
    names: Vec<String>,
}

pub const POS: &str = "embObjPOS";

impl EmbObjPos {
    pub fn new() -> Self {
        Self::default()
    }
    /// The enabled sensors' names.
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// The angles (degrees) of the enabled sensors, in their order.
    pub fn angles(&self) -> DevResult<Vec<f64>> {
        let st: icub_eth::entities::analog::PosStatus =
            self.c.read(ids::analog(en::AS_POS, 0, tag::AS_XX_STATUS))?;
        (0..self.names.len())
            .map(|i| {
                let at = pos_data_index(self.names.len(), i).ok_or_else(|| {
                    DeviceError::failed(
                        POS,
                        format!(
                            "{} enabled sensors: C++ knows 4 (open/close) or 2 (abduction)",
                            self.names.len()
                        ),
                    )
                })?;
                Ok(st.values.get(at).map_or(0.0, |v| f64::from(*v) / 10.0))
            })
            .collect()
    }
}

/// Where sensor `i` of a POS service with `enabled` sensors is in the board's data: at
/// its hand port (`eObrd_portpos_t`), as C++'s `helper_remapperFromSensorToDataIndex`.
/// Four sensors are the open/close ones (thumb, index, middle, ring-pinky: 0-3), two the
/// abductions (thumb 4, index 6).
fn pos_data_index(enabled: usize, i: usize) -> Option<usize> {
    match (enabled, i) {
        (4, 0..=3) => Some(i),
        (2, 0) => Some(4),
        (2, 1) => Some(6),
        _ => None,
    }
}

/// One encoder array of one angle per enabled sensor, as C++'s `IEncoderArrays`.
impl FamilySource for EmbObjPos {
    fn family_count(&self, _family: SensorFamily) -> usize {
        self.names.len()
    }
    fn family_status(&self, _family: SensorFamily, i: usize) -> MasStatus {
        if i < self.names.len() {
            MasStatus::Ok
        } else {
            MasStatus::Unknown
        }
    }
    fn family_name(&self, _family: SensorFamily, i: usize) -> DevResult<String> {
        self.names
            .get(i)
            .cloned()
            .ok_or_else(|| no_sensor(POS, i, self.names.len()))
    }
    fn family_frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.family_name(family, i)
    }
    fn family_size(&self, _family: SensorFamily, i: usize) -> usize {
        usize::from(i < self.names.len())
    }
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        self.family_name(family, i)?;
        let angle = self.angles()?[i];
        // C++ stamps the reading with the time it is asked for
        Ok(SensorMeasurement::new(vec![angle], now()))
    }
}

yarp_devices::mas_interfaces!(EmbObjPos: EncoderArrays);

impl DeviceDriver for EmbObjPos {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(POS)
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(POS, config);
        let mut names = Vec::new();
        self.c.open(POS, config, category::POS, |root, st| {
            let (set, _) = settings(root)?;
            names = set.strings("enabledSensors").unwrap_or_default();
            let rate = set.number("acquisitionRate")?.unwrap_or(50.0);
            let cfg = icub_eth::entities::analog::PosConfig {
                datarate: rate.clamp(1.0, 255.0) as u8,
            };
            Ok(SensorService {
                activate: verify(root, category::POS, st)?,
                configs: vec![(
                    ids::analog(en::AS_POS, 0, tag::AS_XX_CONFIG),
                    cfg.to_bytes(),
                )],
                regulars: vec![ids::analog(en::AS_POS, 0, tag::AS_XX_STATUS)],
                prepare: None,
                companion: None,
                other_regulars: Vec::new(),
                before_start: Vec::new(),
                after_start: vec![(
                    ids::analog(en::AS_POS, 0, tag::AS_XX_CMMNDS_ENABLE),
                    vec![1],
                    Write::SetCheck,
                )],
            })
        })?;
        self.names = names;
        Ok(())
    }

    yarp_devices::views!(as_encoder_arrays);
}

// ---- embObjBattery ----

/// `embObjBattery`: the battery behind a board (ergoCub's BMS or BAT on CAN), as
/// `IBattery`, with C++'s units and roundings.
#[derive(Default)]
pub struct EmbObjBattery {
    c: Common,
}

pub const BATTERY: &str = "embObjBattery";

impl EmbObjBattery {
    pub fn new() -> Self {
        Self::default()
    }

    fn status(&self) -> DevResult<icub_eth::entities::analog::BatteryStatus> {
        self.c.read(ids::analog(
            en::AS_BATTERY,
            0,
            tag::AS_BATTERY_STATUS_TIMEDVALUE,
        ))
    }
}

impl DeviceDriver for EmbObjBattery {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(BATTERY)
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(BATTERY, config);
        self.c.open(BATTERY, config, category::BATTERY, |root, st| {
            let (set, _) = settings(root)?;
            let rate = set.number("acquisitionRate")?.unwrap_or(1000.0);
            // C++ assigns acquisitionRate (ms) to the one-byte period as it is, so 1000
            // goes out as 232: send what C++ sends.
            let cfg = icub_eth::entities::analog::BatteryConfig {
                period: (rate.max(0.0) as u32 & 0xff) as u8,
            };
            Ok(SensorService {
                activate: verify(root, category::BATTERY, st)?,
                configs: vec![(
                    ids::analog(en::AS_BATTERY, 0, tag::AS_BATTERY_CONFIG),
                    cfg.to_bytes(),
                )],
                regulars: vec![ids::analog(
                    en::AS_BATTERY,
                    0,
                    tag::AS_BATTERY_STATUS_TIMEDVALUE,
                )],
                prepare: None,
                companion: None,
                other_regulars: Vec::new(),
                before_start: Vec::new(),
                after_start: vec![(
                    ids::analog(en::AS_BATTERY, 0, tag::AS_BATTERY_CMMNDS_ENABLE),
                    vec![1],
                    Write::SetCheck,
                )],
            })
        })
    }

    yarp_devices::views!(as_battery);
}

/// C++'s `std::trunc(10 * v) / 10` on the board's float (in single precision, so 48.3
/// stays 48.3f: in double it would truncate to 48.2).
fn tenths(v: f32) -> f32 {
    (10.0 * v).trunc() / 10.0
}

impl yarp_devices::battery::IBattery for EmbObjBattery {
    // Volts and amperes truncated to 0.1 (in single precision, as C++ computes them),
    // degrees Celsius in whole degrees (the board's 0.1 °C divided as integers), as C++
    // embObjBattery gives them.
    fn get_battery_voltage(&mut self) -> DevResult<f64> {
        Ok(f64::from(tenths(self.status()?.voltage)))
    }
    fn get_battery_current(&mut self) -> DevResult<f64> {
        Ok(f64::from(tenths(self.status()?.current)))
    }
    /// %; NaN while the BMS reports 0 (not measured yet), as C++.
    fn get_battery_charge(&mut self) -> DevResult<f64> {
        let charge = f64::from(self.status()?.charge);
        Ok(if charge != 0.0 { charge } else { f64::NAN })
    }
    fn get_battery_status(&mut self) -> DevResult<yarp_devices::battery::BatteryStatus> {
        use yarp_devices::battery::BatteryStatus as S;
        // C++ casts the board's status word to IBattery's enum as it is.
        Ok(match self.status()?.status {
            0 => S::OkStandby,
            1 => S::OkInCharge,
            2 => S::OkInUse,
            4 => S::Timeout,
            5 => S::LowWarning,
            6 => S::CriticalWarning,
            _ => S::GeneralError,
        })
    }
    /// °C in whole degrees (the board's 0.1 °C divided as integers, as C++); NaN while
    /// the board reports 0.
    fn get_battery_temperature(&mut self) -> DevResult<f64> {
        let t = self.status()?.temperature / 10;
        Ok(if t != 0 { f64::from(t) } else { f64::NAN })
    }
    fn get_battery_info(&mut self) -> DevResult<String> {
        let s = self.status()?;
        Ok(format!(
            "{{\"temperature\":{},\"voltage\":{},\"current\":{},\"charge\":{},\"status\":{},\"ts\":{}}}",
            s.temperature / 10,
            tenths(s.voltage),
            tenths(s.current),
            s.charge,
            s.status,
            now()
        ))
    }
}
