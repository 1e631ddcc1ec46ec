//! The iCub CAN layer: bus backends, the iCub CAN protocol, a board emulator, and the
//! driver cores that the YARP devices (`canmotioncontrol`, `canBusAnalogSensor`,
//! `canBusFtSensor`, `canBusSkin`, `canBusInertialMTB`) wrap.
//!
//! | module | what |
//! |--------|------|
//! | [`frame`] | [`CanFrame`]: classic CAN frames with Linux identifier-word flags |
//! | [`bus`] | [`CanBus`] endpoints (ICanBus role): in-process, cannelloni/UDP, SocketCAN; [`bus::config`] picks one from `canBackend` / `physDevice` / `CanDeviceNum` |
//! | [`proto`] | the iCub protocol as a pure codec: [`proto::Message`], [`proto::decode_any`] (fuzz entry point) |
//! | [`emulator`] | emulated motor-control, strain, MAIS, skin and MTB boards (run as a robot by `icub-board-emulator`, crate `icub-emulators`) |
//! | [`xsens`] | the Xsens MT serial protocol of the head IMU (`xsensmtx`) as a pure codec, and an emulated MTx ([`emulator::mtx`] serves it on a serial port or pseudo-terminal) |
//! | [`client`] | synchronous driver cores: [`client::MotorControlClient`], [`client::StrainClient`], [`client::SkinClient`], [`client::InertialClient`] |
//!
//! # Choosing a bus
//!
//! Device configuration names the bus like the iCub XML does; one extra key,
//! `canBackend`, selects a backend that exists on this machine:
//!
//! ```text
//! physDevice   cfw2can            # the real adapter (no driver here -> clear error)
//! CanDeviceNum 1
//! canBackend   udp://127.0.0.1:20000+n    # -> cannelloni peer of 127.0.0.1:20001
//! ```
//!
//! See [`bus::config`] for the URL forms (`inproc://`, `udp://`, `udp-hub://`,
//! `socketcan://`) and [`bus::cannelloni`] for the exact wire format.
//!
//! # Driver cores (for the YARP device wrappers)
//!
//! Each client owns one [`CanBus`] endpoint (`Arc<dyn CanBus>`) and a reader thread;
//! every method is synchronous and bounded by a timeout:
//!
//! - [`client::McParams`] holds a `canmotioncontrol`'s groups (`CAN`, `GENERAL`, `LIMITS`,
//!   `VELOCITY`, `POS_PIDS`, `TRQ_PIDS`), as icubmod reads them.
//! - [`client::MotorControlClient::open`]`(bus, params)` checks every board answers
//!   (else [`client::ClientError::BoardsSilent`]) and configures them. Methods take
//!   joint indices and degrees: `position_move`, `position_move_all`, `set_ref_speed`,
//!   `set_ref_acceleration`, `motion_done`, `stop`, `set_position` (direct),
//!   `velocity_move`, `set_ref_torque`/`ref_torque`, `set_control_mode`/`control_mode`,
//!   `set_interaction_mode`/`interaction_mode`, `enable_amp`/`disable_amp`, `current`,
//!   `set_max_current`, `calibrate`, `set_pid`/`pid` ([`client::JointPid`]),
//!   `pid_output`, `set_limits`/`limits`, `encoder`/`encoders`/`encoders_timed`,
//!   `encoder_speed`, `encoder_acceleration`, `motor_encoder`, `poll_encoder`, `joint_status`,
//!   `board_health`, `malformed_frames`, `bus_stats`.
//! - [`client::StrainClient::open`]`(bus, `[`client::StrainParams`]`)` reads the full
//!   scales and starts streaming; `read()` gives values in N / N·m with a
//!   [`client::SensorStatus`] (`Timeout` after 100 ms of silence), `calibration_matrix()`.
//! - [`client::SkinClient`] (`skinCanIds`, 192 taxels per board) and
//!   [`client::InertialClient`] (`canAddress`, `sensorType`, `sensorPeriod`).
//!
//! Errors are [`client::ClientError`]: a silent board is `BoardTimeout` (polls) or
//! `Stale` (broadcasts older than `McParams::broadcast_timeout`), a bus in bus-off is
//! `Bus(BusError::BusOff)`; nothing blocks longer than its timeout.
#![forbid(unsafe_code)]

pub mod bus;
pub mod client;
pub mod emulator;
pub mod frame;
pub mod proto;
pub mod xsens;

pub use bus::{BusError, BusStats, CanBus, IdFilter};
pub use frame::{CanFrame, FrameError};
