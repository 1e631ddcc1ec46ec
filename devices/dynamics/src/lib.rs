//! Rigid-body dynamics of a robot read from its URDF, computed as iDynTree
//! computes it for robotology's `wholebodydynamics`; no YARP in it.
//!
//! - [`urdf`]: the model and its F/T, accelerometer and gyroscope sensors
//!   from a URDF file ([`Model`]); massless leaf links become frames.
//! - [`kinematics`]: a [`Traversal`] from any base link; link poses,
//!   twists and proper accelerations from joint states and the base's motion
//!   (fixed with gravity, or measured by an IMU).
//! - [`dynamics`]: inverse dynamics (RNEA) and gravity torques.
//! - [`estimation`]: the model split at the F/T sensors into submodels, the
//!   external wrenches at each submodel's contact frames estimated from the
//!   F/T measurements, and the joint torques that follow; also the
//!   measurements the F/T sensors are expected to read (for their offsets).
//!
//! Conventions are iDynTree's: twists `[v; ω]`, wrenches `[f; τ]`, SI units.
#![forbid(unsafe_code)]

pub mod dynamics;
pub mod error;
pub mod estimation;
pub mod kinematics;
pub mod model;
pub mod sensors;
pub mod solve;
pub mod spatial;
pub mod urdf;

pub use error::{DynError, Result};
pub use kinematics::{BaseMotion, JointState, LinkStates, Traversal};
pub use model::{FrameRef, Joint, JointKind, Link, Model};
pub use nalgebra;
