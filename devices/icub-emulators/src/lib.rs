//! Emulated iCub robots. [`eth`]: the Ethernet boards of a robots-configuration robot
//! (`icub-eth-emulator`); the CAN boards are `icub-board-emulator`'s (over crate
//! `icub_can`'s emulated boards).

pub mod eth;
