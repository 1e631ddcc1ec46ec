//! Typed network variables with the exact byte layout of their C structs
//! (icub-firmware-shared `eth/embobj/plus/comm-v2/icub`). Every type implements
//! [`Entity`](crate::wire::Entity): `to_bytes()` / `from_bytes()` of exactly `SIZE` bytes.

pub mod analog;
pub mod boards;
pub mod mc;
pub mod mn;
pub mod service;
pub mod skin;
