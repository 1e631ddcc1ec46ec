//! icub-main's gaze controller: the `iKinGazeCtrl` module ([`core`] without its ports,
//! [`service`] with them, [`kinematics`] of the head) and, in [`crate::gaze_client`],
//! `gazecontrollerclient`.

pub mod core;
pub mod kinematics;
pub mod service;
