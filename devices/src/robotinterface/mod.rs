//! `yarprobotinterface`'s robot description: the robots-configuration XML format (DTD
//! 3.x, as C++ YARP 3.12 reads it) and the runner that brings a robot up and down.
//!
//! - [`tree`]: XML files as an owned element tree with `xi:include`s expanded, each
//!   element knowing its file and line.
//! - [`reader`]: the DTD rules, element tree -> [`model::Robot`].
//! - [`model`]: robot, devices, params, actions; how params become a device `Property`.
//! - [`runner`]: open devices, run the actions of each phase by level, close.
//! - [`resource`]: where the programs find `--from` / `--config` files.
//! - [`rpc`]: the `/<portprefix>/yarprobotinterface` RPC service (phase, level, ready).
//!
//! Differences from C++ YARP 3.12, all where C++ would fail badly or not at all:
//! - a device whose type is not in the registry is reported by name and skipped, with the
//!   actions on it, aimed at it, or aimed at wrappers left unattached because of it;
//! - include cycles, runaway includes, unknown phase names and duplicate plain params are
//!   errors naming file and line (C++ recurses forever, ignores, or aborts);
//! - DTD 1.x files (and their `file=` attributes) are refused, as C++ does without
//!   `--allow-deprecated-dtd`, which is not offered;
//! - an `attach` with `all` leaves out the device itself; an interrupt stops the startup
//!   between actions but cannot cut a running calibration short.
//!
//! ```no_run
//! use yarp_devices::robotinterface::{read_robot_file, ActionPhase, RobotRunner};
//! let loaded = read_robot_file("icub_all.xml".as_ref(), &Default::default()).unwrap();
//! let mut runner = RobotRunner::new(loaded.robot);
//! runner.enter_phase(ActionPhase::Startup).unwrap();
//! runner.enter_phase(ActionPhase::Run).unwrap();
//! // ... on Ctrl-C:
//! let _ = runner.enter_phase(ActionPhase::Interrupt1);
//! let _ = runner.enter_phase(ActionPhase::Shutdown);
//! ```

pub mod error;
pub mod model;
pub mod reader;
pub mod resource;
pub mod rpc;
pub mod runner;
pub mod tree;

pub use error::{Location, XmlError};
pub use model::{Action, ActionPhase, ActionType, Device, Param, Robot};
pub use reader::{read_robot_file, read_robot_str, LoadedRobot};
pub use runner::{DeviceFactory, PhaseError, Progress, RegistryFactory, RobotRunner};
