//! iCub kinematics equivalent to robotology/icub-main's iKin library
//! (`iKinFwd`), built on [`nalgebra`].
//!
//! - [`Link`]: one revolute joint with standard Denavit-Hartenberg
//!   parameters (`a`, `d`, `alpha`, `offset`, bounds), transform
//!   `Rz(q + offset) · Tz(d) · Tx(a) · Rx(alpha)` exactly as `iKinLink::getH`.
//! - [`Chain`]: `H0 · links · HN` with blocked/released links (`iKinChain`):
//!   forward kinematics as a 4×4 transform ([`Chain::h`]) or iKin's 7-vector
//!   `x y z ax ay az θ` ([`Chain::end_eff_pose`]), geometric
//!   ([`Chain::geo_jacobian`]) and analytical ([`Chain::ana_jacobian`])
//!   Jacobians, in radians with degree helpers ([`Chain::set_ang_deg`], …).
//! - [`Limb`]: the iCub chains with every hardware version iKin knows —
//!   arms, legs, eyes (also neck-referenced and head-center), inertial
//!   sensor, torso, fingers — selected by iKin's type strings such as
//!   `"left_v2.5"`; unknown strings are an error listing the known ones.
//! - [`properties`]: generic chains from YARP properties in iKin's
//!   `link_<i>` format (`fromLinksProperties` / `toLinksProperties`).
//! - [`IkSolver`]: damped-least-squares inverse kinematics that respects the
//!   joint bounds, in position-only or full-pose mode.
//!
//! Units are SI: metres and radians. Joint vectors cover the released links
//! only, in chain order, as in iKin.
//!
//! # Example
//!
//! ```
//! use icub_ikin::{IkConfig, IkSolver, Limb};
//!
//! // Left arm of an iCub 2.5: 10 links, torso blocked, 7 DOF.
//! let mut arm = Limb::arm("left_v2.5")?;
//! assert_eq!((arm.chain().n(), arm.chain().dof()), (10, 7));
//!
//! // Forward kinematics from joint values in degrees.
//! arm.chain_mut().set_ang_deg(&[-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 0.0])?;
//! let pose = arm.chain().end_eff_pose(); // x y z ax ay az θ
//! let jac = arm.chain().geo_jacobian(); // 6 × 7
//! assert_eq!(jac.ncols(), 7);
//!
//! // Release the torso (10 DOF) and solve back for that pose.
//! for i in 0..3 {
//!     arm.chain_mut().release_link(i)?;
//! }
//! let target = arm.chain().h();
//! let solver = IkSolver::new(IkConfig::default())?;
//! let sol = solver.solve(arm.chain(), &target, None)?;
//! assert!(sol.converged && sol.pos_error < 1e-3);
//! arm.chain_mut().set_ang(sol.q.as_slice())?;
//! # let _ = pose;
//!
//! // Unknown sides are rejected with the list of known types.
//! let err = Limb::arm("middle_v2").unwrap_err().to_string();
//! assert!(err.contains("left_v2.5"));
//! # Ok::<(), icub_ikin::KinError>(())
//! ```
#![forbid(unsafe_code)]

pub mod chain;
pub mod error;
pub mod ik;
pub mod limbs;
pub mod link;
pub mod minjerk;
pub mod pose;
pub mod properties;

pub use chain::Chain;
pub use error::{KinError, Result};
pub use ik::{IkConfig, IkMode, IkSolution, IkSolver};
pub use limbs::{Limb, LimbKind};
pub use link::{Link, DEG2RAD, RAD2DEG};
pub use nalgebra;
