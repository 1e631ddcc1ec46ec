//! `SkinClient` (core of `canBusSkin`) and `InertialClient` (core of `canBusInertialMTB`).

use parking_lot::Mutex;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::link::Link;
use super::strain::{SensorStatus, DATA_TIMEOUT};
use super::ClientError;
use crate::bus::{CanBus, IdFilter};
use crate::proto::sensors::inertial_bits;
use crate::proto::{make_id, AsCommand, InertialMsg, Message, MsgClass};

/// Latest values and, per board, when they were last updated.
type Readings<T> = Arc<Mutex<(Vec<f64>, Vec<T>)>>;

/// Taxels per MTB board: 16 triangles × 12.
pub const TAXELS_PER_BOARD: usize = 192;

/// Skin patches on one bus (`skinCanIds`); values are ordered board by board, triangle
/// by triangle, as `CanBusSkin` lays them out.
pub struct SkinClient {
    boards: Vec<u8>,
    link: Arc<Link>,
    reader: Option<JoinHandle<()>>,
    state: Readings<Option<Instant>>,
}

impl SkinClient {
    pub fn open(bus: Arc<dyn CanBus>, boards: &[u8]) -> Result<Self, ClientError> {
        if boards.is_empty() || boards.iter().any(|b| !(1..=14).contains(b)) {
            return Err(ClientError::Config(format!(
                "skinCanIds {boards:?} must be 1..14"
            )));
        }
        let mut filter = IdFilter::none();
        for &b in boards {
            for t in 0..16 {
                filter.add(make_id(MsgClass::PeriodicSkin, b, t));
            }
        }
        bus.set_filter(filter);
        let state = Arc::new(Mutex::new((
            vec![0.0; boards.len() * TAXELS_PER_BOARD],
            vec![None; boards.len()],
        )));
        let (st, ids) = (state.clone(), boards.to_vec());
        let (link, reader) = Link::start(bus, 0, move |msg| {
            let Message::Skin { board, msg } = msg else {
                return;
            };
            let Some(i) = ids.iter().position(|b| b == board) else {
                return;
            };
            let base = i * TAXELS_PER_BOARD + usize::from(msg.triangle) * 12 + msg.first_taxel();
            let mut s = st.lock();
            for (k, v) in msg.taxels().iter().enumerate() {
                s.0[base + k] = f64::from(*v);
            }
            s.1[i] = Some(Instant::now());
        })?;
        Ok(Self {
            boards: boards.to_vec(),
            link,
            reader: Some(reader),
            state,
        })
    }

    /// Number of taxels (`getChannels`).
    pub fn channels(&self) -> usize {
        self.boards.len() * TAXELS_PER_BOARD
    }

    /// All taxels; the status is `Timeout` if any board was silent for `timeout`.
    pub fn read(&self, timeout: Duration) -> (Vec<f64>, SensorStatus) {
        let s = self.state.lock();
        let ok =
            s.1.iter()
                .all(|t| t.is_some_and(|t| t.elapsed() <= timeout));
        (
            s.0.clone(),
            if ok {
                SensorStatus::Ok
            } else {
                SensorStatus::Timeout
            },
        )
    }

    /// Boards not heard from within `timeout`.
    pub fn silent_boards(&self, timeout: Duration) -> Vec<u8> {
        let s = self.state.lock();
        self.boards
            .iter()
            .zip(&s.1)
            .filter(|(_, t)| !t.is_some_and(|t| t.elapsed() <= timeout))
            .map(|(b, _)| *b)
            .collect()
    }

    pub fn malformed_frames(&self) -> u64 {
        self.link
            .malformed
            .load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl Drop for SkinClient {
    fn drop(&mut self) {
        self.link.stop();
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}

/// MTB inertial sensors (`canAddress` list, `sensorType` `acc` or `extAccAndGyro`):
/// per board 3 accelerometer channels, plus 3 gyroscope channels with `extAccAndGyro`.
pub struct InertialClient {
    boards: Vec<u8>,
    with_gyro: bool,
    link: Arc<Link>,
    reader: Option<JoinHandle<()>>,
    state: Readings<[Option<Instant>; 2]>,
}

impl InertialClient {
    /// Opens the client and enables the sensors with period `period_ms`.
    pub fn open(
        bus: Arc<dyn CanBus>,
        boards: &[u8],
        sensor_type: &str,
        period_ms: u8,
    ) -> Result<Self, ClientError> {
        let (with_gyro, bits) = match sensor_type {
            "acc" => (false, inertial_bits::INTERNAL_ACC),
            "extAccAndGyro" => (
                true,
                inertial_bits::EXTERNAL_GYRO | inertial_bits::EXTERNAL_ACC,
            ),
            other => {
                return Err(ClientError::Config(format!(
                    "unknown sensorType {other:?} (acc or extAccAndGyro)"
                )))
            }
        };
        if boards.is_empty() || boards.iter().any(|b| !(1..=14).contains(b)) {
            return Err(ClientError::Config(format!(
                "canAddress {boards:?} must be 1..14"
            )));
        }
        let mut filter = IdFilter::none();
        for &b in boards {
            filter.add(make_id(MsgClass::PeriodicInertial, b, 0));
            filter.add(make_id(MsgClass::PeriodicInertial, b, 1));
        }
        bus.set_filter(filter);
        let per = if with_gyro { 6 } else { 3 };
        let state = Arc::new(Mutex::new((
            vec![0.0; boards.len() * per],
            vec![[None; 2]; boards.len()],
        )));
        let (st, ids) = (state.clone(), boards.to_vec());
        let (link, reader) = Link::start(bus, 0, move |msg| {
            let Message::Inertial { board, msg } = msg else {
                return;
            };
            let Some(i) = ids.iter().position(|b| b == board) else {
                return;
            };
            let mut s = st.lock();
            let (offset, v, slot) = match msg {
                InertialMsg::Accelerometer(v) => (0, v, 0),
                InertialMsg::Gyroscope(v) if with_gyro => (3, v, 1),
                InertialMsg::Gyroscope(_) => return,
            };
            for (k, x) in v.iter().enumerate() {
                s.0[i * per + offset + k] = f64::from(*x);
            }
            s.1[i][slot] = Some(Instant::now());
        })?;
        let setup: Vec<_> = boards
            .iter()
            .map(|&b| {
                Message::AsRequest {
                    src: 0,
                    dst: b,
                    cmd: AsCommand::AccGyroSetup {
                        sensors: bits,
                        period: period_ms.max(1),
                    },
                }
                .encode()
            })
            .collect();
        link.send(&setup)?;
        Ok(Self {
            boards: boards.to_vec(),
            with_gyro,
            link,
            reader: Some(reader),
            state,
        })
    }

    pub fn channels(&self) -> usize {
        self.boards.len() * if self.with_gyro { 6 } else { 3 }
    }

    /// Raw readings and status (`Timeout` if a sensor was silent for 100 ms).
    pub fn read(&self) -> (Vec<f64>, SensorStatus) {
        let s = self.state.lock();
        let fresh = |t: Option<Instant>| t.is_some_and(|t| t.elapsed() <= DATA_TIMEOUT);
        let ok =
            s.1.iter()
                .all(|[acc, gyro]| fresh(*acc) && (!self.with_gyro || fresh(*gyro)));
        (
            s.0.clone(),
            if ok {
                SensorStatus::Ok
            } else {
                SensorStatus::Timeout
            },
        )
    }
}

impl Drop for InertialClient {
    fn drop(&mut self) {
        let stop: Vec<_> = self
            .boards
            .iter()
            .map(|&b| {
                Message::AsRequest {
                    src: 0,
                    dst: b,
                    cmd: AsCommand::AccGyroSetup {
                        sensors: 0,
                        period: 1,
                    },
                }
                .encode()
            })
            .collect();
        let _ = self.link.send(&stop);
        self.link.stop();
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}
