//! `StrainClient`: the core of `canBusAnalogSensor` / `canBusFtSensor` (strain 6-axis
//! F/T, 16-bit) and of MAIS boards (8-bit hall-effect sensors).

use parking_lot::Mutex;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::link::Link;
use super::ClientError;
use crate::bus::{CanBus, IdFilter};
use crate::proto::analog::txmode;
use crate::proto::{make_id, AsCommand, AsPeriodic, AsReply, Message, MsgClass};

/// How old data may be before the sensor reports a timeout (as `CanBusAnalogSensor`).
pub const DATA_TIMEOUT: Duration = Duration::from_millis(100);

/// Data formats of analog boards (`format` key).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AnalogFormat {
    /// 16-bit vectors (strain).
    Bits16,
    /// 8-bit hall-effect values (MAIS).
    Bits8,
}

/// Parameters of a `canBusAnalogSensor` / `canBusFtSensor` device.
#[derive(Debug, Clone)]
pub struct StrainParams {
    /// `canAddress`.
    pub address: u8,
    /// `period`: broadcast period requested from the board, ms.
    pub period_ms: u8,
    /// `useCalibration` > 0: calibrated data scaled by the full scales.
    pub use_calibration: bool,
    /// `channels`.
    pub channels: usize,
    /// `format` (16 or 8).
    pub format: AnalogFormat,
    pub host_address: u8,
    pub reply_timeout: Duration,
}

impl StrainParams {
    /// A calibrated 6-axis strain at `address`.
    pub fn strain(address: u8) -> Self {
        Self {
            address,
            period_ms: 1,
            use_calibration: true,
            channels: 6,
            format: AnalogFormat::Bits16,
            host_address: 0,
            reply_timeout: Duration::from_millis(100),
        }
    }
}

/// Status of a reading (`IAnalogSensor::AS_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensorStatus {
    Ok,
    /// The board flagged saturation.
    Overflow,
    /// No data within [`DATA_TIMEOUT`].
    Timeout,
    /// The board sent an unexpected message.
    Error,
}

struct Shared {
    data: Vec<f64>,
    at: Option<Instant>,
    status: SensorStatus,
}

/// The host side of one strain or MAIS board.
pub struct StrainClient {
    params: StrainParams,
    link: Arc<Link>,
    reader: Option<JoinHandle<()>>,
    state: Arc<Mutex<Shared>>,
    full_scales: Arc<Mutex<[f64; 6]>>,
}

impl StrainClient {
    /// Opens the client: reads the full scales (calibrated strain), then starts streaming.
    pub fn open(bus: Arc<dyn CanBus>, params: StrainParams) -> Result<Self, ClientError> {
        let a = params.address;
        let mut filter = IdFilter::none();
        for kind in 0..16 {
            filter.add(make_id(MsgClass::PeriodicAnalogSensor, a, kind));
        }
        filter.add(make_id(
            MsgClass::PollingAnalogSensor,
            a,
            params.host_address,
        ));
        bus.set_filter(filter);
        let state = Arc::new(Mutex::new(Shared {
            data: vec![0.0; params.channels],
            at: None,
            status: SensorStatus::Timeout,
        }));
        let full_scales = Arc::new(Mutex::new([1.0; 6]));
        let (st, fs, p) = (state.clone(), full_scales.clone(), params.clone());
        let (link, reader) = Link::start(bus, params.host_address, move |msg| {
            let Message::AsPeriodic { board, msg } = msg else {
                return;
            };
            if *board != p.address {
                return;
            }
            let mut s = st.lock();
            match (p.format, msg) {
                (
                    AnalogFormat::Bits16,
                    AsPeriodic::Vector {
                        kind,
                        raw,
                        saturation,
                    },
                ) => {
                    let scales = *fs.lock();
                    let first = kind.first_channel();
                    for (k, v) in AsPeriodic::signed(*raw).into_iter().enumerate() {
                        let ch = first + k;
                        if ch < s.data.len() {
                            let v = f64::from(v);
                            s.data[ch] = if p.use_calibration {
                                v * scales[ch] / 32768.0
                            } else {
                                v
                            };
                        }
                    }
                    s.status = if *saturation == Some(1) {
                        SensorStatus::Overflow
                    } else {
                        SensorStatus::Ok
                    };
                }
                (AnalogFormat::Bits8, AsPeriodic::Hes0To6(v)) => {
                    for (i, x) in v.iter().enumerate().take(s.data.len()) {
                        s.data[i] = f64::from(*x);
                    }
                    s.status = SensorStatus::Ok;
                }
                (AnalogFormat::Bits8, AsPeriodic::Hes7To14(v)) => {
                    for (i, x) in v.iter().enumerate() {
                        if let Some(d) = s.data.get_mut(7 + i) {
                            *d = f64::from(*x);
                        }
                    }
                    s.status = SensorStatus::Ok;
                }
                _ => {
                    s.status = SensorStatus::Error;
                    return;
                }
            }
            s.at = Some(Instant::now());
        })?;
        let client = Self {
            params,
            link,
            reader: Some(reader),
            state,
            full_scales,
        };
        client.start()?;
        Ok(client)
    }

    fn request(&self, cmd: AsCommand) -> crate::CanFrame {
        Message::AsRequest {
            src: self.params.host_address,
            dst: self.params.address,
            cmd,
        }
        .encode()
    }

    fn poll(&self, cmd: AsCommand, what: String) -> Result<AsReply, ClientError> {
        let board = self.params.address;
        let op = cmd.opcode();
        let timeout = self.params.reply_timeout;
        // The C++ driver retries lost full-scale replies; so do we, three times.
        for _ in 0..3 {
            let reply = self.link.request(
                self.request(cmd),
                move |m| matches!(m, Message::AsReply { src, reply, .. } if *src == board && match reply {
                    AsReply::FullScale { .. } => op == crate::proto::analog::op::GET_FULL_SCALES,
                    AsReply::MatrixRc { .. } => op == crate::proto::analog::op::GET_MATRIX_RC,
                }),
                timeout,
            )?;
            if let Some(Message::AsReply { reply, .. }) = reply {
                return Ok(reply);
            }
        }
        Err(ClientError::BoardTimeout {
            board,
            what,
            timeout: timeout * 3,
        })
    }

    fn start(&self) -> Result<(), ClientError> {
        if self.params.format == AnalogFormat::Bits16 && self.params.use_calibration {
            let mut scales = [1.0; 6];
            for (ch, scale) in scales
                .iter_mut()
                .enumerate()
                .take(self.params.channels.min(6))
            {
                match self.poll(
                    AsCommand::GetFullScale { channel: ch as u8 },
                    format!("full scale of channel {ch}"),
                )? {
                    AsReply::FullScale { value, .. } => *scale = f64::from(value),
                    r => return Err(ClientError::Config(format!("unexpected reply {r:?}"))),
                }
            }
            *self.full_scales.lock() = scales;
        }
        let mode = if self.params.format == AnalogFormat::Bits16 && !self.params.use_calibration {
            txmode::RAW
        } else {
            txmode::CALIBRATED
        };
        self.link.send(&[
            self.request(AsCommand::SetCanDataRate(self.params.period_ms)),
            self.request(AsCommand::SetTxMode(mode)),
        ])
    }

    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.params.channels
    }

    /// The full scales read at open (1.0 when uncalibrated).
    pub fn full_scales(&self) -> [f64; 6] {
        *self.full_scales.lock()
    }

    /// Latest values (N, N·m when calibrated) and their status (`IAnalogSensor::read`).
    pub fn read(&self) -> (Vec<f64>, SensorStatus) {
        let s = self.state.lock();
        let status = match s.at {
            Some(t) if t.elapsed() <= DATA_TIMEOUT => s.status,
            _ => SensorStatus::Timeout,
        };
        (s.data.clone(), status)
    }

    /// Latest values, or an error when the board is silent.
    pub fn read_checked(&self) -> Result<Vec<f64>, ClientError> {
        let (data, status) = self.read();
        match status {
            SensorStatus::Timeout => {
                let age = self.state.lock().at.map(|t| t.elapsed());
                Err(ClientError::Stale {
                    joint: 0,
                    board: self.params.address,
                    age,
                    timeout: DATA_TIMEOUT,
                })
            }
            _ => Ok(data),
        }
    }

    /// Reads the 6×6 calibration matrix (Q1.15, returned as floats in [-1, 1)).
    pub fn calibration_matrix(&self) -> Result<[[f64; 6]; 6], ClientError> {
        let mut m = [[0.0; 6]; 6];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, cell) in row.iter_mut().enumerate() {
                let cmd = AsCommand::GetMatrixRc {
                    row: r as u8,
                    col: c as u8,
                };
                match self.poll(cmd, format!("calibration matrix entry ({r},{c})"))? {
                    AsReply::MatrixRc { value, .. } => *cell = f64::from(value) / 32768.0,
                    reply => {
                        return Err(ClientError::Config(format!("unexpected reply {reply:?}")))
                    }
                }
            }
        }
        Ok(m)
    }

    /// Frames that failed to decode.
    pub fn malformed_frames(&self) -> u64 {
        self.link
            .malformed
            .load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl Drop for StrainClient {
    fn drop(&mut self) {
        let _ = self
            .link
            .send(&[self.request(AsCommand::SetTxMode(txmode::STOP))]);
        self.link.stop();
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}
