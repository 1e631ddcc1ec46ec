//! icub-main's Cartesian control for the YARP device framework, wire-compatible with C++:
//!
//! | C++ | here |
//! |---|---|
//! | `iKinCartesianSolver` module (iKin's `CartesianSolver`) | [`solver`] (sans I/O), [`solver_service`], the `iKinCartesianSolver` program |
//! | `cartesiancontrollerserver` (`ServerCartesianController`) | [`server`] (sans I/O), [`server_device`] |
//! | `cartesiancontrollerclient` (`ClientCartesianController`) | [`client`], as `yarp_devices`' `ICartesianControl` |
//! | the protocol's vocabs and `CartesianHelper` options | [`protocol`] |
//! | `iKinGazeCtrl` module | [`gaze`] (`core` sans I/O, `service`, head `kinematics`), the `iKinGazeCtrl` program |
//! | `gazecontrollerclient` (`ClientGazeController`) | [`gaze_client`], as `yarp_devices`' `IGazeControl` |
//!
//! The min-jerk controller that plans the joints is iKin's, in [`icub_ikin::minjerk`].
#![forbid(unsafe_code)]

pub mod client;
pub mod gaze;
pub mod gaze_client;
mod module_client;
pub mod protocol;
pub mod server;
pub mod server_device;
pub mod solver;
pub mod solver_service;

use yarp_devices::driver::{Factory, Registry};

/// Raises `stop` at the first SIGINT or SIGTERM (the handlers installed now, so that an
/// early signal is not lost): how `iKinCartesianSolver` and `iKinGazeCtrl` end.
pub fn stop_on_signals(stop: std::sync::Arc<std::sync::atomic::AtomicBool>) -> std::io::Result<()> {
    yarp_net::signals::on_signals(move |_| stop.store(true, std::sync::atomic::Ordering::SeqCst))
}

/// The provider name `yarpdev --list` shows.
pub const PROVIDER: &str = "icub-cartesian";

const DRIVERS: &[(&str, Factory)] = &[
    (server::NAME, || {
        Box::new(server_device::CartesianControllerServer::new())
    }),
    (client::NAME, || {
        Box::new(client::CartesianControllerClient::new())
    }),
    (gaze_client::NAME, || {
        Box::new(gaze_client::GazeControllerClient::new())
    }),
];

/// Adds the Cartesian devices to `registry` (`Registry::install(icub_cartesian::register)`).
pub fn register(registry: &mut Registry) {
    registry.add(PROVIDER, DRIVERS);
}
