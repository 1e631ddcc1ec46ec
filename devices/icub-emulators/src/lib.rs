//! Emulated iCub robots as programs, each bringing up the boards a robots-configuration
//! directory describes, read with the robot interface's own XML reader (crate
//! `yarp-devices`), so an emulator sees exactly the devices and parameters
//! `yarprobotinterface` opens:
//!
//! - [`can_robot`]: the CAN boards (`icub-board-emulator`, over crate `icub_can`'s
//!   emulated boards);
//! - [`eth`]: the Ethernet boards (`icub-eth-emulator`);
//! - [`bno055`]: the Bosch BNO055 head IMU on a pseudo-terminal (`--bno055 PATH` of both);
//! - [`body`]: the robot's body under gravity (and pushes), from its URDF, for what the
//!   emulated F/T sensors and IMUs read (`--urdf PATH`);
//! - [`rplidar`]: a Slamtec RPLidar A2/A3 (R1's base lasers) without I/O, scanning a room.

pub mod bno055;
pub mod body;
pub mod can_robot;
pub mod eth;
pub mod rplidar;
