//! `canBusVirtualAnalogSensor` (icub-main `CanBusVirtualAnalogSensor`): a "virtual strain"
//! board. Joint torques estimated on the PC (wholeBodyDynamics, through
//! `virtualAnalogServer`) are put on a part's CAN network as if a strain board at
//! `canAddress` had measured them; the motor boards configured with that `TorqueId`
//! use them for torque control.
//!
//! Parameters (as `hardware/VFT/*_virtual_strain.xml`): `canAddress` (1..14), `format`
//! (8 or 16), `period` (ms), `channels` (1..6), `fullScale` (one value per channel, in
//! N·m), bus keys `canBackend` / `physDevice` + `canDeviceNum` (`canbusDevice`
//! `"sharedcan"` is accepted). `useCalibration` is accepted and unused: it only affects
//! decoding, and this device only sends. C++ requires `format`, `period`, `channels`,
//! `fullScale` and `canAddress`, and so does this one.
//!
//! Each update (`updateVirtualAnalogSensorMeasure`) clamps every channel to
//! ±`fullScale` (a warning at most every 2 s, as C++), scales it to a signed 16-bit
//! count `trunc(v / fullScale * 0x7fff)` and sends two class-3 frames from `canAddress`:
//! type 0xA (channels 0..3) and type 0xB (channels 3..6), each three little-endian
//! values offset by 0x8000 (`CanBusVirtualAnalogSensor.cpp`; ids
//! `ICUBCANPROTO_PER_AS_MSG__FORCE_VECTOR` / `__TORQUE_VECTOR` of icub-firmware-shared
//! `iCubCanProto_analogSensorMessages.h`). Fewer than 6 channels are padded with 0.
//! A background thread answers `GET_FULL_SCALES` (0x18) requests addressed to
//! `canAddress` with the configured full scale, as the C++ `run()` does. Closing sends
//! `SET_TXMODE 1` (stop) to `canAddress`, as C++ `sensor_stop()`.
//!
//! Status (C++ always answers `VAS_OK`): `Overflow` for a channel clamped by the last
//! update, `Error` when the last send failed (a dead bus is an error returned by the
//! update, never a hang), the device is closed, or the channel does not exist.
//! Not supported: the 8-bit (MAIS) frame layout — `format 8` sends the same 16-bit
//! frames, as the C++ device does.

use parking_lot::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use icub_can::bus::{BusError, CanBus, IdFilter};
use icub_can::proto::analog::txmode;
use icub_can::proto::{
    make_id, AsCommand, AsPeriodic, AsReply, Message, MsgClass, VectorKind, HOST_ADDRESS,
};
use icub_can::CanFrame;
use yarp_proto::Property;

use crate::common::{device_id, CanBusParams};
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::sensors::{IVirtualAnalogSensor, VasStatus};

pub(crate) const NAME: &str = "canBusVirtualAnalogSensor";

/// The strain frame layout carries six channels (two frames of three).
const MAX_CHANNELS: usize = 6;
/// C++ prints a saturation warning at most every 2 s.
const SATURATION_WARN_EVERY: Duration = Duration::from_secs(2);
/// How long the reply thread waits for a frame before checking whether to stop.
const POLL: Duration = Duration::from_millis(50);

/// A torque in N·m as the signed 16-bit count C++ sends: clamped to ±`full_scale`,
/// then `(short)(v / fullScale * 0x7fff)` (truncation toward zero). The second value
/// tells whether the torque was clamped.
pub fn torque_to_count(v: f64, full_scale: f64) -> (i16, bool) {
    let clamped = v.clamp(-full_scale, full_scale);
    let count = (clamped / full_scale * f64::from(0x7fff_i16)) as i16;
    (count, clamped != v)
}

/// The two frames (type 0xA then 0xB) carrying `counts` for board `address`.
pub fn torque_frames(address: u8, counts: [i16; MAX_CHANNELS]) -> [CanFrame; 2] {
    let vector = |kind, c: &[i16]| {
        Message::AsPeriodic {
            board: address,
            msg: AsPeriodic::vector(kind, [c[0], c[1], c[2]]),
        }
        .encode()
    };
    [
        vector(VectorKind::Force, &counts[0..3]),
        vector(VectorKind::Torque, &counts[3..6]),
    ]
}

/// Everything an open device shares with its reply thread.
struct Core {
    bus: Arc<dyn CanBus>,
    address: u8,
    channels: usize,
    full_scale: Vec<f64>,
    state: Mutex<State>,
}

#[derive(Default)]
struct State {
    /// The torques of the last update (after clamping), to send single-channel updates.
    last: [f64; MAX_CHANNELS],
    /// Channels clamped by the last update.
    saturated: [bool; MAX_CHANNELS],
    saturations: u64,
    last_warning: Option<Instant>,
    /// The error of the last send, if it failed.
    send_error: Option<String>,
}

impl Core {
    fn lock(&self) -> parking_lot::MutexGuard<'_, State> {
        self.state.lock()
    }

    /// Clamps, scales and sends `values` (at most `channels` of them).
    fn send(&self, id: &str, values: &[f64]) -> DevResult<()> {
        let mut counts = [0i16; MAX_CHANNELS];
        let mut st = self.lock();
        for (ch, &v) in values.iter().enumerate() {
            let fs = self.full_scale[ch];
            let (count, clamped) = torque_to_count(v, fs);
            counts[ch] = count;
            st.last[ch] = v.clamp(-fs, fs);
            st.saturated[ch] = clamped;
            if clamped {
                st.saturations += 1;
                let due = st
                    .last_warning
                    .is_none_or(|t| t.elapsed() > SATURATION_WARN_EVERY);
                if due {
                    tracing::warn!(
                        "{id}: virtual F/T sensor id {:#x} saturated channel {ch}: {v:+.4} (full scale {fs}, {} saturations)",
                        self.address,
                        st.saturations
                    );
                    st.last_warning = Some(Instant::now());
                }
            }
        }
        for ch in values.len()..MAX_CHANNELS {
            st.last[ch] = 0.0;
            st.saturated[ch] = false;
        }
        let frames = torque_frames(self.address, counts);
        // C++ writes the two frames one after the other
        let sent = frames.iter().try_for_each(|f| self.bus.send(f));
        match sent {
            Ok(()) => {
                st.send_error = None;
                Ok(())
            }
            Err(e) => {
                tracing::debug!("{id}: sending torques on {}: {e}", self.bus.name());
                st.send_error = Some(e.to_string());
                Err(DeviceError::failed(id, e))
            }
        }
    }

    /// Answers a frame the way C++ `run()` does: `GET_FULL_SCALES` addressed to this
    /// board gets the configured full scale (as an integer, big-endian).
    fn handle(&self, id: &str, frame: &CanFrame) {
        let Ok(Message::AsRequest { dst, cmd, .. }) = Message::decode(frame) else {
            return;
        };
        if dst != self.address {
            return;
        }
        if let AsCommand::GetFullScale { channel } = cmd {
            let Some(fs) = self.full_scale.get(usize::from(channel)) else {
                tracing::debug!("{id}: full scale of channel {channel} asked, it has none");
                return;
            };
            let reply = Message::AsReply {
                src: self.address,
                dst: HOST_ADDRESS,
                reply: AsReply::FullScale {
                    channel,
                    // C++: (int) scaleFactor[channel], sent as two bytes
                    value: *fs as u16,
                },
            };
            if let Err(e) = self.bus.send(&reply.encode()) {
                tracing::debug!("{id}: full-scale reply: {e}");
            }
        }
    }
}

/// The `canBusVirtualAnalogSensor` device.
pub struct CanBusVirtualAnalogSensor {
    id: String,
    core: Option<Arc<Core>>,
    stop: Arc<AtomicBool>,
    reader: Option<JoinHandle<()>>,
}

impl Default for CanBusVirtualAnalogSensor {
    fn default() -> Self {
        Self::new()
    }
}

impl CanBusVirtualAnalogSensor {
    pub fn new() -> Self {
        Self {
            id: NAME.to_string(),
            core: None,
            stop: Arc::new(AtomicBool::new(false)),
            reader: None,
        }
    }

    fn core(&self) -> DevResult<&Arc<Core>> {
        self.core.as_ref().ok_or(DeviceError::NotOpen)
    }

    fn bad(&self, param: &str, expected: &'static str, got: impl Into<String>) -> DeviceError {
        DeviceError::BadParam {
            device: self.id.clone(),
            param: param.into(),
            expected,
            got: got.into(),
        }
    }
}

/// A board address on the bus.
fn board_address(a: &i64) -> Result<(), &'static str> {
    match (1..=14).contains(a) {
        true => Ok(()),
        false => Err("a board address 1..14"),
    }
}

yarp_devices::device_params! {
    /// What `canBusVirtualAnalogSensor` reads (icub-main's), besides its bus
    /// ([`CanBusParams`]).
    pub struct CanBusVirtualAnalogSensorParams for "canBusVirtualAnalogSensor" {
        /// The address of the board the torques go to
        "canAddress" can_address: i64 = required; check board_address,
        /// Bits per value of the messages
        format: i64 = required; check crate::common::strain_format,
        /// Period of the messages
        period: i64 = required; "ms"; min 1,
        /// Number of values (the strain frames carry six)
        channels: i64 = required; in 1..=6,
        /// The full scale of each channel (one positive value per channel)
        "fullScale" full_scale: Vec<f64> = required,
        /// Whether the values are calibrated (accepted; the values go as given)
        "useCalibration" use_calibration: i64 = optional,
    }
}

impl DeviceDriver for CanBusVirtualAnalogSensor {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        [
            CanBusVirtualAnalogSensorParams::PARAMS,
            CanBusParams::PARAMS,
        ]
        .concat()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        self.id = device_id(config, NAME);
        yarp_devices::params::help_if_asked(NAME, config, &self.parameters());
        let p = CanBusVirtualAnalogSensorParams::parse(&self.id, config)?;
        let bus_params = CanBusParams::parse(&self.id, config)?;
        let address = p.can_address;
        let channels = p.channels as usize;
        let full_scale: Vec<f64> = p.full_scale.iter().take(channels).copied().collect();
        if full_scale.len() != channels || !full_scale.iter().all(|f| *f > 0.0 && f.is_finite()) {
            let got: Vec<String> = p.full_scale.iter().map(f64::to_string).collect();
            return Err(self.bad(
                "fullScale",
                "one positive full scale per channel",
                got.join(" "),
            ));
        }
        let bus = bus_params.open(&self.id)?;
        // C++ opens the mask for the polling messages host -> canAddress; it has no use
        // for anything else (its own class-3 broadcasts never come back).
        bus.set_filter(IdFilter::ids([make_id(
            MsgClass::PollingAnalogSensor,
            HOST_ADDRESS,
            address as u8,
        )]));
        let core = Arc::new(Core {
            bus,
            address: address as u8,
            channels,
            full_scale,
            state: Mutex::new(State::default()),
        });
        let stop = Arc::new(AtomicBool::new(false));
        let (c, s, id) = (core.clone(), stop.clone(), self.id.clone());
        let reader = std::thread::Builder::new()
            .name(format!("{}-vas", self.id))
            .spawn(move || {
                let mut failed = false;
                while !s.load(Ordering::Relaxed) {
                    match c.bus.recv(POLL) {
                        Ok(frame) => {
                            failed = false;
                            c.handle(&id, &frame);
                        }
                        Err(BusError::Timeout(_)) => failed = false,
                        Err(e) => {
                            if !failed {
                                tracing::warn!("{id}: reading {}: {e}", c.bus.name());
                            }
                            failed = true;
                            std::thread::sleep(POLL);
                        }
                    }
                }
            })
            .map_err(|e| {
                self.bad(
                    "canBackend",
                    "a bus whose reader thread starts",
                    e.to_string(),
                )
            })?;
        self.core = Some(core);
        self.stop = stop;
        self.reader = Some(reader);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
        if let Some(core) = self.core.take() {
            // C++ sensor_stop(): SET_TXMODE 1 to canAddress
            let stop = Message::AsRequest {
                src: HOST_ADDRESS,
                dst: core.address,
                cmd: AsCommand::SetTxMode(txmode::STOP),
            };
            if let Err(e) = core.bus.send(&stop.encode()) {
                tracing::debug!("{}: stop message: {e}", self.id);
            }
        }
        Ok(())
    }

    yarp_devices::views!(as_virtual_analog_sensor);
}

impl Drop for CanBusVirtualAnalogSensor {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

impl IVirtualAnalogSensor for CanBusVirtualAnalogSensor {
    fn get_virtual_analog_sensor_status(&mut self, ch: usize) -> VasStatus {
        let Ok(core) = self.core() else {
            return VasStatus::Error;
        };
        if ch >= core.channels {
            return VasStatus::Error;
        }
        let st = core.lock();
        if st.send_error.is_some() {
            VasStatus::Error
        } else if st.saturated[ch] {
            VasStatus::Overflow
        } else {
            VasStatus::Ok
        }
    }

    fn get_virtual_analog_sensor_channels(&mut self) -> usize {
        self.core().map_or(0, |c| c.channels)
    }

    fn update_virtual_analog_sensor_measure(&mut self, measure: &[f64]) -> DevResult<()> {
        let core = self.core()?;
        if measure.is_empty() || measure.len() > core.channels {
            return Err(DeviceError::WrongSize {
                expected: core.channels,
                got: measure.len(),
            });
        }
        if let Some(v) = measure.iter().find(|v| !v.is_finite()) {
            return Err(self.bad("measure", "finite torques", v.to_string()));
        }
        core.send(&self.id, measure)
    }

    fn update_virtual_analog_sensor_channel(&mut self, ch: usize, measure: f64) -> DevResult<()> {
        let core = self.core()?;
        if ch >= core.channels {
            return Err(DeviceError::InvalidJoint {
                joint: ch as i64,
                axes: core.channels,
            });
        }
        // C++ leaves this one unimplemented; here the other channels keep their last value
        let mut values = core.lock().last[..core.channels].to_vec();
        values[ch] = measure;
        self.update_virtual_analog_sensor_measure(&values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use icub_can::bus::inproc::VirtualBus;

    fn config(bus: &str, extra: &str) -> Property {
        Property::from_text(format!(
            "(device canBusVirtualAnalogSensor) (id vs) (canBackend {bus}) (canbusDevice \"sharedcan\") (canDeviceNum 1) (canAddress 0x0C) (format 16) (channels 6) (period 1) (useCalibration 1) (fullScale 8 8 8 8 8 8) {extra}"
        ))
    }

    /// The torques of a pair of frames, decoded with the protocol codec.
    fn decode(frames: &[CanFrame], fs: f64) -> (u8, [f64; 6]) {
        let mut out = [f64::NAN; 6];
        let mut board = 0;
        for f in frames {
            let Message::AsPeriodic {
                board: b,
                msg: AsPeriodic::Vector { kind, raw, .. },
            } = Message::decode(f).unwrap()
            else {
                panic!("{f:?}");
            };
            board = b;
            for (k, v) in AsPeriodic::signed(raw).into_iter().enumerate() {
                out[kind.first_channel() + k] = f64::from(v) * fs / 32768.0;
            }
        }
        (board, out)
    }

    #[test]
    fn scaling_matches_cpp() {
        assert_eq!(torque_to_count(0.0, 8.0), (0, false));
        assert_eq!(torque_to_count(8.0, 8.0), (0x7fff, false));
        assert_eq!(torque_to_count(-100.0, 8.0), (-0x7fff, true));
        // truncation toward zero, as the C cast
        assert_eq!(torque_to_count(1.0, 8.0).0, 4095);
        assert_eq!(torque_to_count(-1.0, 8.0).0, -4095);
        let [a, b] = torque_frames(0x0C, [1, -1, 0, 0x7fff, -0x7fff, 2]);
        assert_eq!(a.std_id(), Some(0x3CA));
        assert_eq!(a.data(), &[0x01, 0x80, 0xff, 0x7f, 0x00, 0x80]);
        assert_eq!(b.std_id(), Some(0x3CB));
        assert_eq!(b.data(), &[0xff, 0xff, 0x01, 0x00, 0x02, 0x80]);
    }

    #[test]
    fn sends_torques_answers_full_scale_and_reports_status() {
        let named = VirtualBus::named("vas-unit");
        let tap2 = named.endpoint();
        let name = "inproc://vas-unit";
        let mut dev = CanBusVirtualAnalogSensor::new();
        dev.open(&config(name, "")).unwrap();
        assert_eq!(dev.get_virtual_analog_sensor_channels(), 6);
        let torques = [1.0, -2.0, 0.5, 7.9, -7.9, 0.0];
        dev.update_virtual_analog_sensor_measure(&torques).unwrap();
        let frames = [
            tap2.recv(Duration::from_secs(1)).unwrap(),
            tap2.recv(Duration::from_secs(1)).unwrap(),
        ];
        let (board, got) = decode(&frames, 8.0);
        assert_eq!(board, 0x0C);
        for (g, t) in got.iter().zip(torques) {
            assert!((g - t).abs() < 8.0 / 32767.0 * 2.0, "{got:?}");
        }
        assert_eq!(dev.get_virtual_analog_sensor_status(0), VasStatus::Ok);

        // saturation clamps and is reported per channel
        dev.update_virtual_analog_sensor_measure(&[100.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            .unwrap();
        let frames = [
            tap2.recv(Duration::from_secs(1)).unwrap(),
            tap2.recv(Duration::from_secs(1)).unwrap(),
        ];
        assert!((decode(&frames, 8.0).1[0] - 8.0).abs() < 1e-3);
        assert_eq!(dev.get_virtual_analog_sensor_status(0), VasStatus::Overflow);
        assert_eq!(dev.get_virtual_analog_sensor_status(1), VasStatus::Ok);
        assert_eq!(dev.get_virtual_analog_sensor_status(6), VasStatus::Error);

        // one channel: the others keep their last value
        dev.update_virtual_analog_sensor_channel(2, -3.0).unwrap();
        let frames = [
            tap2.recv(Duration::from_secs(1)).unwrap(),
            tap2.recv(Duration::from_secs(1)).unwrap(),
        ];
        let got = decode(&frames, 8.0).1;
        assert!(
            (got[0] - 8.0).abs() < 1e-3 && (got[2] + 3.0).abs() < 1e-3,
            "{got:?}"
        );

        // wrong sizes and garbage are refused without sending
        assert!(dev.update_virtual_analog_sensor_measure(&[0.0; 7]).is_err());
        assert!(dev.update_virtual_analog_sensor_measure(&[]).is_err());
        assert!(dev
            .update_virtual_analog_sensor_measure(&[f64::NAN; 6])
            .is_err());
        assert!(dev.update_virtual_analog_sensor_channel(6, 0.0).is_err());

        // GET_FULL_SCALES from the host is answered as C++ does
        let ask = Message::AsRequest {
            src: 0,
            dst: 0x0C,
            cmd: AsCommand::GetFullScale { channel: 3 },
        };
        tap2.send(&ask.encode()).unwrap();
        let reply = tap2.recv(Duration::from_secs(1)).unwrap();
        assert_eq!(reply.std_id(), Some(0x2C0));
        assert_eq!(
            Message::decode(&reply).unwrap(),
            Message::AsReply {
                src: 0x0C,
                dst: 0,
                reply: AsReply::FullScale {
                    channel: 3,
                    value: 8
                }
            }
        );

        // a dead bus is an error at once, and the status says so
        named.set_bus_off(true);
        let t0 = Instant::now();
        assert!(dev.update_virtual_analog_sensor_measure(&[0.0; 6]).is_err());
        assert!(t0.elapsed() < Duration::from_secs(1));
        assert_eq!(dev.get_virtual_analog_sensor_status(0), VasStatus::Error);
        named.set_bus_off(false);
        while tap2.try_recv().unwrap().is_some() {}

        // closing stops the "board"
        dev.close().unwrap();
        let stop = tap2.recv(Duration::from_secs(1)).unwrap();
        assert_eq!(stop.std_id(), Some(0x20C));
        assert_eq!(stop.data(), &[0x07, 0x01]);
        assert_eq!(dev.get_virtual_analog_sensor_channels(), 0);
        assert!(dev.update_virtual_analog_sensor_measure(&[0.0; 6]).is_err());
    }

    #[test]
    fn parameters_are_checked() {
        let bus = "inproc://vas-params";
        let mut dev = CanBusVirtualAnalogSensor::new();
        let missing = Property::from_text(format!(
            "(canBackend {bus}) (canAddress 12) (format 16) (channels 6) (period 1)"
        ));
        assert!(dev
            .open(&missing)
            .unwrap_err()
            .to_string()
            .contains("fullScale"));
        for (extra, what) in [
            ("(fullScale 8 8 8)", "fullScale"),
            ("(fullScale 8 8 8 8 8 0)", "fullScale"),
        ] {
            let err = dev.open(&config(bus, extra)).unwrap_err().to_string();
            assert!(err.contains(what), "{err}");
        }
        let bad = Property::from_text(format!(
            "(canBackend {bus}) (canAddress 15) (format 16) (channels 6) (period 1) (fullScale 1 1 1 1 1 1)"
        ));
        assert!(dev
            .open(&bad)
            .unwrap_err()
            .to_string()
            .contains("canAddress"));
        let bad = Property::from_text(format!(
            "(canBackend {bus}) (canAddress 12) (format 16) (channels 7) (period 1) (fullScale 1 1 1 1 1 1 1)"
        ));
        assert!(dev.open(&bad).unwrap_err().to_string().contains("channels"));
        // three channels: the rest of the frames is zero
        let three = Property::from_text(format!(
            "(canBackend {bus}) (canAddress 12) (format 16) (channels 3) (period 1) (fullScale 2 2 2)"
        ));
        dev.open(&three).unwrap();
        assert_eq!(dev.get_virtual_analog_sensor_channels(), 3);
        assert!(dev.update_virtual_analog_sensor_measure(&[1.0; 6]).is_err());
        dev.update_virtual_analog_sensor_measure(&[1.0, 1.0])
            .unwrap();
        // the physDevice of the real files is refused with a message naming canBackend
        if std::env::var_os(crate::common::BACKEND_ENV).is_some() {
            return;
        }
        let real = Property::from_text(
            "(canbusDevice \"sharedcan\") (physDevice \"cfw2can\") (canDeviceNum 1) (canAddress 0x0C) (format 16) (channels 6) (period 1) (useCalibration 1) (fullScale 8 8 8 8 8 8)",
        );
        let err = CanBusVirtualAnalogSensor::new().open(&real).unwrap_err();
        assert!(err.to_string().contains("canBackend"), "{err}");
    }
}
