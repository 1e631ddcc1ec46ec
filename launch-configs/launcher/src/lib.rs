//! `yarp-launch`: starts, supervises and stops a set of YARP modules described by a launch
//! config (TOML, or yarpmanager application XML), makes the connections between their
//! ports, and serves a live dashboard (port graph, joint plots, camera, bridge health).
//!
//! ```no_run
//! # async fn demo() -> anyhow::Result<()> {
//! use yarp_launch::{config::LaunchConfig, supervisor::Launcher};
//! let cfg = LaunchConfig::load("launch-configs/demo.toml".as_ref(), &[])?;
//! let mut launcher = Launcher::new(cfg)?;
//! launcher.start().await?;
//! launcher.wait_ready(std::time::Duration::from_secs(30)).await;
//! launcher.shutdown().await;
//! # Ok(()) }
//! ```

pub mod config;
pub mod connections;
pub mod dashboard;
pub mod graph;
pub mod image;
pub mod plan;
pub mod process;
pub mod programs;
pub mod readiness;
pub mod supervisor;
pub mod xmlapp;

/// Prints a launcher message, prefixed like module output.
pub fn say(msg: &str) {
    println!("[yarp-launch] {msg}");
}

/// Resolves once a stop flag turns true (or its sender is gone). The borrow of the flag
/// ends inside, so callers stay `Send` across other awaits.
pub async fn stopped(rx: &mut tokio::sync::watch::Receiver<bool>) {
    let _ = rx.wait_for(|s| *s).await;
}
