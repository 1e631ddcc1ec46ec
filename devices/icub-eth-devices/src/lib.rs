//! icub-main's `embObj*` devices for the Ethernet iCub and ergoCub ([`eth`]) and the
//! Ethernet board emulator `icub-eth-emulator` ([`emulator`]).

pub mod emulator;
pub mod eth;
