//! Analog-sensors endpoint (`EoAnalogSensors.h`, `EoProtocolAS.h`): strain (F/T), MAIS,
//! temperatures, inertials, POS, FT and battery.

use crate::wire::{Entity, Reader, Writer};

/// `eOas_sensor_t` (`EoAnalogSensors.h`): the kind of a reading (`type_of_sensor` of
/// [`Inertial3Data`], [`TemperatureData`] and the sensor descriptors of the services).
pub mod sensor_type {
    pub const ACCEL_MTB_INT: u8 = 2;
    pub const ACCEL_MTB_EXT: u8 = 3;
    pub const GYROS_MTB_EXT: u8 = 4;
    pub const ACCEL_ST_LIS3X: u8 = 5;
    /// The Ethernet board's own gyroscope: its readings are known by their type alone.
    pub const GYROS_ST_L3G4200D: u8 = 6;
    pub const IMU_ACC: u8 = 7;
    pub const IMU_MAG: u8 = 8;
    pub const IMU_GYR: u8 = 9;
    pub const IMU_EUL: u8 = 10;
    pub const IMU_QUA: u8 = 11;
    pub const IMU_LIA: u8 = 12;
    pub const IMU_GRV: u8 = 13;
    pub const IMU_STATUS: u8 = 14;
    /// `eoas_temperature_t1`: a strain2's temperature.
    pub const TEMPERATURE_T1: u8 = 15;
}

/// An `EOarray` of at most `N` bytes of items (`eOas_arrayofupto12bytes_t` and
/// `eOas_arrayofupto36bytes_t`): head (capacity, itemsize, size, internalmem) + data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ByteArray<const N: usize> {
    pub capacity: u8,
    pub item_size: u8,
    pub size: u8,
    pub data: [u8; N],
}

impl<const N: usize> ByteArray<N> {
    /// An array of `u16` items (the strain's six values, MAIS at 16-bit resolution).
    pub fn from_u16(values: &[u16]) -> Self {
        let cap = N / 2;
        let n = values.len().min(cap);
        let mut data = [0u8; N];
        for (i, v) in values.iter().take(n).enumerate() {
            data[2 * i..2 * i + 2].copy_from_slice(&v.to_le_bytes());
        }
        Self {
            capacity: cap as u8,
            item_size: 2,
            size: n as u8,
            data,
        }
    }
    /// An array of `u8` items (MAIS at 8-bit resolution).
    pub fn from_u8(values: &[u8]) -> Self {
        let n = values.len().min(N);
        let mut data = [0u8; N];
        data[..n].copy_from_slice(&values[..n]);
        Self {
            capacity: N as u8,
            item_size: 1,
            size: n as u8,
            data,
        }
    }
    /// The items as `u16` (nothing if the items are not 2 bytes).
    pub fn u16_values(&self) -> Vec<u16> {
        if self.item_size != 2 {
            return Vec::new();
        }
        let n = usize::from(self.size).min(N / 2);
        (0..n)
            .map(|i| u16::from_le_bytes([self.data[2 * i], self.data[2 * i + 1]]))
            .collect()
    }
    /// The items as `u8` (nothing if the items are not 1 byte).
    pub fn u8_values(&self) -> Vec<u8> {
        if self.item_size != 1 {
            return Vec::new();
        }
        self.data[..usize::from(self.size).min(N)].to_vec()
    }
}

impl<const N: usize> Default for ByteArray<N> {
    fn default() -> Self {
        Self {
            capacity: 0,
            item_size: 0,
            size: 0,
            data: [0; N],
        }
    }
}

impl<const N: usize> Entity for ByteArray<N> {
    const C_TYPE: &'static str = "eOas_arrayofupto<N>bytes_t";
    const SIZE: usize = 4 + N;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.capacity, self.item_size, self.size, 0]);
        w.bytes(&self.data);
    }
    fn read(r: &mut Reader) -> Self {
        let [capacity, item_size, size, _] = r.array();
        Self {
            capacity,
            item_size,
            size,
            data: r.array(),
        }
    }
}

/// `eOas_strain_config_t` (4 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StrainConfig {
    /// `eOas_strainmode_t`: 0 calibrated, 1 acquire only, 3 uncalibrated, 4 all.
    pub mode: u8,
    /// ms.
    pub datarate: u8,
    pub signal_once_fullscale: bool,
}

impl Entity for StrainConfig {
    const C_TYPE: &'static str = "eOas_strain_config_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[
            self.mode,
            self.datarate,
            u8::from(self.signal_once_fullscale),
            0,
        ]);
    }
    fn read(r: &mut Reader) -> Self {
        let [mode, datarate, s, _] = r.array();
        Self {
            mode,
            datarate,
            signal_once_fullscale: s != 0,
        }
    }
}

/// `eOas_strain_status_t` (48 bytes): three arrays of six `u16`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StrainStatus {
    pub fullscale: ByteArray<12>,
    pub calibrated: ByteArray<12>,
    pub uncalibrated: ByteArray<12>,
}

impl Entity for StrainStatus {
    const C_TYPE: &'static str = "eOas_strain_status_t";
    const SIZE: usize = 48;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.fullscale);
        w.entity(&self.calibrated);
        w.entity(&self.uncalibrated);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            fullscale: r.entity(),
            calibrated: r.entity(),
            uncalibrated: r.entity(),
        }
    }
}

impl StrainStatus {
    /// The six values of a strain array as signed readings: the boards send them in
    /// offset binary (`0x8000` is zero), little endian (icub-main
    /// `embObjFTsensor::updateStrainValues`).
    pub fn readings(values: &ByteArray<12>) -> Vec<i16> {
        values
            .u16_values()
            .iter()
            .map(|v| v.wrapping_sub(0x8000) as i16)
            .collect()
    }

    /// A strain array of the given signed readings, as a board sends it.
    pub fn values_of(readings: &[i16]) -> ByteArray<12> {
        let raw: Vec<u16> = readings
            .iter()
            .map(|r| (*r as u16).wrapping_add(0x8000))
            .collect();
        ByteArray::from_u16(&raw)
    }

    /// The full scales: six `u16` sent big endian, unlike the values (icub-main
    /// `eo_ftsens_privData::fillScaleFactor`: "order of bytes seems inverted").
    pub fn full_scales(&self) -> Vec<u16> {
        self.fullscale
            .u16_values()
            .iter()
            .map(|v| v.swap_bytes())
            .collect()
    }

    /// A full-scale array as a board sends it.
    pub fn full_scales_of(values: &[u16]) -> ByteArray<12> {
        let swapped: Vec<u16> = values.iter().map(|v| v.swap_bytes()).collect();
        ByteArray::from_u16(&swapped)
    }
}

/// `eOas_mais_config_t` (4 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MaisConfig {
    /// `eOas_maismode_t`: 0 tx continuously, 1 acquire only, 5 off.
    pub mode: u8,
    pub datarate: u8,
    /// `eOas_maisresolution_t`: 0 8-bit, 1 16-bit.
    pub resolution: u8,
}

impl Entity for MaisConfig {
    const C_TYPE: &'static str = "eOas_mais_config_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.mode, self.datarate, self.resolution, 0]);
    }
    fn read(r: &mut Reader) -> Self {
        let [mode, datarate, resolution, _] = r.array();
        Self {
            mode,
            datarate,
            resolution,
        }
    }
}

/// `eOas_mais_status_t` (40 bytes): the 15 values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MaisStatus {
    pub the15values: ByteArray<36>,
}

impl Entity for MaisStatus {
    const C_TYPE: &'static str = "eOas_mais_status_t";
    const SIZE: usize = 40;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.the15values);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            the15values: r.entity(),
        }
    }
}

/// `eOas_temperature_data_t` (8 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TemperatureData {
    pub id: u8,
    pub type_of_sensor: u8,
    /// 0.1 °C.
    pub value: i16,
    /// ms.
    pub timestamp: u32,
}

impl Entity for TemperatureData {
    const C_TYPE: &'static str = "eOas_temperature_data_t";
    const SIZE: usize = 8;
    fn write(&self, w: &mut Writer) {
        w.u8(self.id);
        w.u8(self.type_of_sensor);
        w.i16(self.value);
        w.u32(self.timestamp);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            id: r.u8(),
            type_of_sensor: r.u8(),
            value: r.i16(),
            timestamp: r.u32(),
        }
    }
}

/// `eOas_temperature_config_t` (4 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TemperatureConfig {
    pub datarate: u16,
    pub enabled: u16,
}

impl Entity for TemperatureConfig {
    const C_TYPE: &'static str = "eOas_temperature_config_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.u16(self.datarate);
        w.u16(self.enabled);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            datarate: r.u16(),
            enabled: r.u16(),
        }
    }
}

/// `eOas_temperature_status_t` (20 bytes): an `EOarray` of up to 2 readings.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct TemperatureStatus {
    pub data: Vec<TemperatureData>,
}

impl Entity for TemperatureStatus {
    const C_TYPE: &'static str = "eOas_temperature_status_t";
    const SIZE: usize = 20;
    fn write(&self, w: &mut Writer) {
        write_array(w, 2, &self.data);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            data: read_array(r, 2),
        }
    }
}

fn write_array<T: Entity>(w: &mut Writer, capacity: usize, items: &[T]) {
    let n = items.len().min(capacity);
    w.bytes(&[capacity as u8, T::SIZE as u8, n as u8, 0]);
    for it in &items[..n] {
        w.entity(it);
    }
    w.zeros((capacity - n) * T::SIZE);
}

fn read_array<T: Entity>(r: &mut Reader, capacity: usize) -> Vec<T> {
    let [_, item_size, size, _] = r.array();
    let n = if usize::from(item_size) == T::SIZE {
        usize::from(size).min(capacity)
    } else {
        0
    };
    let v = (0..n).map(|_| r.entity()).collect();
    r.skip((capacity - n) * T::SIZE);
    v
}

/// `eOas_inertial3_data_t` (16 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Inertial3Data {
    pub id: u8,
    /// `eOas_inertial3_type_t`.
    pub type_of_sensor: u8,
    pub status: u8,
    pub seq: u8,
    /// ms.
    pub timestamp: u32,
    pub w: i16,
    pub x: i16,
    pub y: i16,
    pub z: i16,
}

impl Entity for Inertial3Data {
    const C_TYPE: &'static str = "eOas_inertial3_data_t";
    const SIZE: usize = 16;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.id, self.type_of_sensor, self.status, self.seq]);
        w.u32(self.timestamp);
        w.i16(self.w);
        w.i16(self.x);
        w.i16(self.y);
        w.i16(self.z);
    }
    fn read(r: &mut Reader) -> Self {
        let [id, type_of_sensor, status, seq] = r.array();
        Self {
            id,
            type_of_sensor,
            status,
            seq,
            timestamp: r.u32(),
            w: r.i16(),
            x: r.i16(),
            y: r.i16(),
            z: r.i16(),
        }
    }
}

/// `eOas_inertial3_config_t` (8 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Inertial3Config {
    /// ms.
    pub datarate: u8,
    pub items_to_fill_at_each_tick: u8,
    /// Bit mask of the enabled sensors of the service's descriptor array.
    pub enabled: u32,
}

impl Entity for Inertial3Config {
    const C_TYPE: &'static str = "eOas_inertial3_config_t";
    const SIZE: usize = 8;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.datarate, self.items_to_fill_at_each_tick, 0, 0]);
        w.u32(self.enabled);
    }
    fn read(r: &mut Reader) -> Self {
        let [datarate, items, _, _] = r.array();
        Self {
            datarate,
            items_to_fill_at_each_tick: items,
            enabled: r.u32(),
        }
    }
}

/// `eOas_inertial3_status_t` (68 bytes): an `EOarray` of up to 4 readings.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Inertial3Status {
    pub data: Vec<Inertial3Data>,
}

impl Entity for Inertial3Status {
    const C_TYPE: &'static str = "eOas_inertial3_status_t";
    const SIZE: usize = 68;
    fn write(&self, w: &mut Writer) {
        write_array(w, 4, &self.data);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            data: read_array(r, 4),
        }
    }
}

/// `eOas_pos_config_t` (4 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PosConfig {
    pub datarate: u8,
}

impl Entity for PosConfig {
    const C_TYPE: &'static str = "eOas_pos_config_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.datarate, 0, 0, 0]);
    }
    fn read(r: &mut Reader) -> Self {
        let [datarate, ..] = r.array::<4>();
        Self { datarate }
    }
}

/// `eOas_pos_status_t` (32 bytes): an `EOarray` of up to 14 `int16` deci-degrees.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PosStatus {
    pub values: Vec<i16>,
}

impl Entity for PosStatus {
    const C_TYPE: &'static str = "eOas_pos_status_t";
    const SIZE: usize = 32;
    fn write(&self, w: &mut Writer) {
        let n = self.values.len().min(14);
        w.bytes(&[14, 2, n as u8, 0]);
        for v in &self.values[..n] {
            w.i16(*v);
        }
        w.zeros((14 - n) * 2);
    }
    fn read(r: &mut Reader) -> Self {
        let [_, item, size, _] = r.array();
        let n = if item == 2 {
            usize::from(size).min(14)
        } else {
            0
        };
        let values = (0..n).map(|_| r.i16()).collect();
        r.skip((14 - n) * 2);
        Self { values }
    }
}

/// `eOas_ft_config_t` (4 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FtConfig {
    /// `eOas_ft_mode_t`: 0 raw, 1 calibrated.
    pub mode: u8,
    /// ms (0: no TX).
    pub ftperiod: u8,
    pub calibration_set: u8,
    /// s.
    pub temperature_period: u8,
}

impl Entity for FtConfig {
    const C_TYPE: &'static str = "eOas_ft_config_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[
            self.mode,
            self.ftperiod,
            self.calibration_set,
            self.temperature_period,
        ]);
    }
    fn read(r: &mut Reader) -> Self {
        let [mode, ftperiod, calibration_set, temperature_period] = r.array();
        Self {
            mode,
            ftperiod,
            calibration_set,
            temperature_period,
        }
    }
}

/// `eOas_ft_timedvalue_t` (40 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FtTimedValue {
    /// Board time of life, µs.
    pub age: u64,
    pub info: u32,
    /// 0.1 °C.
    pub temperature: i16,
    /// Forces (N) then torques (N·m), or the raw ADC values.
    pub values: [f32; 6],
}

impl Entity for FtTimedValue {
    const C_TYPE: &'static str = "eOas_ft_timedvalue_t";
    const SIZE: usize = 40;
    fn write(&self, w: &mut Writer) {
        w.u64(self.age);
        w.u32(self.info);
        w.u16(0);
        w.i16(self.temperature);
        for v in self.values {
            w.f32(v);
        }
    }
    fn read(r: &mut Reader) -> Self {
        let age = r.u64();
        let info = r.u32();
        r.skip(2);
        let temperature = r.i16();
        let mut values = [0f32; 6];
        for v in values.iter_mut() {
            *v = r.f32();
        }
        Self {
            age,
            info,
            temperature,
            values,
        }
    }
}

/// `eOas_ft_status_t` (56 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FtStatus {
    pub timed_value: FtTimedValue,
    pub fullscale: [u16; 6],
    pub mode: u8,
}

impl Entity for FtStatus {
    const C_TYPE: &'static str = "eOas_ft_status_t";
    const SIZE: usize = 56;
    fn write(&self, w: &mut Writer) {
        w.entity(&self.timed_value);
        for v in self.fullscale {
            w.u16(v);
        }
        w.u8(self.mode);
        w.zeros(3);
    }
    fn read(r: &mut Reader) -> Self {
        let timed_value = r.entity();
        let mut fullscale = [0u16; 6];
        for v in fullscale.iter_mut() {
            *v = r.u16();
        }
        let mode = r.u8();
        r.skip(3);
        Self {
            timed_value,
            fullscale,
            mode,
        }
    }
}

/// `eOas_battery_config_t` (4 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BatteryConfig {
    /// 0: no TX.
    pub period: u8,
}

impl Entity for BatteryConfig {
    const C_TYPE: &'static str = "eOas_battery_config_t";
    const SIZE: usize = 4;
    fn write(&self, w: &mut Writer) {
        w.bytes(&[self.period, 0, 0, 0]);
    }
    fn read(r: &mut Reader) -> Self {
        let [period, ..] = r.array::<4>();
        Self { period }
    }
}

/// `eOas_battery_timedvalue_t` = `eOas_battery_status_t` (32 bytes; 2 bytes of alignment
/// padding after `status`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BatteryStatus {
    pub age: u64,
    /// 0.1 °C.
    pub temperature: i16,
    pub status: u16,
    /// V.
    pub voltage: f32,
    /// A.
    pub current: f32,
    /// %.
    pub charge: f32,
}

impl Entity for BatteryStatus {
    const C_TYPE: &'static str = "eOas_battery_status_t";
    const SIZE: usize = 32;
    fn write(&self, w: &mut Writer) {
        w.u64(self.age);
        w.i16(self.temperature);
        w.i16(0);
        w.u16(self.status);
        w.zeros(2);
        w.f32(self.voltage);
        w.f32(self.current);
        w.f32(self.charge);
        w.u32(0);
    }
    fn read(r: &mut Reader) -> Self {
        let age = r.u64();
        let temperature = r.i16();
        r.skip(2);
        let status = r.u16();
        r.skip(2);
        let v = Self {
            age,
            temperature,
            status,
            voltage: r.f32(),
            current: r.f32(),
            charge: r.f32(),
        };
        r.skip(4);
        v
    }
}

/// The `cmmnds.enable` byte of temperature, inertial3, psc, pos, ft and battery.
pub fn enable_bytes(on: bool) -> Vec<u8> {
    vec![u8::from(on)]
}
