//! robotology/yarp-device-rplidar's devices on Slamtec's RPLidar serial protocol, as
//! its SDK 1.12 speaks it:
//!
//! - [`protocol`]: the protocol without I/O: requests, response descriptors, the
//!   device's information and configuration answers, and the measurement streams
//!   (standard nodes, express capsules, ultra capsules) turned into measurements as the
//!   SDK turns them, each with the encoder an emulated lidar sends them with.
#![forbid(unsafe_code)]

pub mod protocol;
