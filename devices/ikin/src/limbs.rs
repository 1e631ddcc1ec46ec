//! The iCub limbs of iKin (`iCubArm`, `iCubLeg`, `iCubEye`, `iCubEyeNeckRef`,
//! `iCubHeadCenter`, `iCubInertialSensor`, `iCubTorso`, `iCubFinger`) with
//! their DH tables and hardware versions, from icub-main
//! `src/libraries/iKin/src/iKinFwd.cpp`.
//!
//! | limb | type strings | geometry by version |
//! |---|---|---|
//! | arm | `left`, `right`, `<side>_v1`, `_v1.5`, `_v1.7`, `_v2`, `_v2.5`, `_v2.6`, `_v2.7`, `_v3` | < 1.7 hand link d = 137.3 mm, else 141.3; < 2 palm d = 16 mm, else 25.98; ≥ 3 the iCub 3 torso and arm |
//! | leg | `left`, `right`, `<side>_v1`, `_v2.5`, `_v3` | one table each |
//! | eye, eye-neck-ref, head-center | `left`, `right`, `<side>_v1`, `_v2`, `_v2.5`, `_v2.6`, `_v2.7`, `_v2.8`, `_v2.10`, `_v3` | v1; v2 = v2.5 = v2.6 = v2.7; v2.8 its cameras' image plane 1 cm back; v2.10 its own table and plane; v3 |
//! | inertial sensor | `v1`, `v2`, `v2.5`, `v2.6`, `v3` | v2/v2.5/v2.6 share links; HN differs for v2.5, v2.6, v3 |
//! | torso | `""`, `v1` … `v3` (as the arm) | < 3 or iCub 3 |
//! | finger | `<side>_<thumb\|index\|middle\|ring\|little>[_<na\|a\|b>]` | thumb `a` or `b` (default) |
//!
//! iKin parses the version as a number and picks the geometry by thresholds, so
//! a version between the listed ones (`left_v2.7` for a leg) is taken as C++
//! takes it; a side other than `left`/`right` or a version that is no number is a
//! [`KinError::UnknownType`] listing the usual strings.

use std::f64::consts::{FRAC_PI_2 as P2, PI};

use nalgebra::Matrix4;

use crate::chain::Chain;
use crate::error::{KinError, Result};
use crate::link::{Link, DEG2RAD};
use crate::pose::Vector7;

/// Which iKin limb class a [`Limb`] reproduces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LimbKind {
    /// `iCubArm`: 3 torso links (blocked by default) + 7 arm links.
    Arm,
    /// `iCubLeg`: 6 links.
    Leg,
    /// `iCubEye`: 3 torso links (blocked) + 3 neck + eye tilt + eye pan.
    Eye,
    /// `iCubEyeNeckRef`: `iCubEye` without the torso links.
    EyeNeckRef,
    /// `iCubHeadCenter`: `iCubEye` with the eye links zeroed and blocked.
    HeadCenter,
    /// `iCubInertialSensor`: 3 torso + 3 neck links to the head IMU.
    InertialSensor,
    /// `iCubTorso`: the 3 torso links.
    Torso,
    /// `iCubFinger`: one finger, relative to the arm end-effector frame.
    Finger,
}

impl LimbKind {
    /// The iKin class name.
    pub fn class_name(self) -> &'static str {
        match self {
            LimbKind::Arm => "iCubArm",
            LimbKind::Leg => "iCubLeg",
            LimbKind::Eye => "iCubEye",
            LimbKind::EyeNeckRef => "iCubEyeNeckRef",
            LimbKind::HeadCenter => "iCubHeadCenter",
            LimbKind::InertialSensor => "iCubInertialSensor",
            LimbKind::Torso => "iCubTorso",
            LimbKind::Finger => "iCubFinger",
        }
    }
}

/// Hardware versions of the arm (iKin picks the geometry by numeric
/// thresholds 1.7, 2.0 and 3.0 on the number after `_v`).
pub const ARM_VERSIONS: &[&str] = &["v1", "v1.5", "v1.7", "v2", "v2.5", "v2.6", "v2.7", "v3"];
/// Hardware versions of the leg (< 2, < 3 and 3 by iKin's thresholds).
pub const LEG_VERSIONS: &[&str] = &["v1", "v2.5", "v3"];
/// Hardware versions of the eye, eye-neck-ref and head-center chains.
pub const EYE_VERSIONS: &[&str] = &["v1", "v2", "v2.5", "v2.6", "v2.7", "v2.8", "v2.10", "v3"];
/// Hardware versions (the whole type string) of the inertial sensor chain.
pub const INERTIAL_VERSIONS: &[&str] = &["v1", "v2", "v2.5", "v2.6", "v3"];
/// Fingers known to `iCubFinger`.
pub const FINGERS: &[&str] = &["thumb", "index", "middle", "ring", "little"];
/// Finger hardware versions (`"a"`/`"b"` matter for the thumb only; `"na"` means default).
pub const FINGER_VERSIONS: &[&str] = &["na", "a", "b"];

/// An iCub limb: the kinematic [`Chain`] plus the type it was built from.
#[derive(Debug, Clone, PartialEq)]
pub struct Limb {
    kind: LimbKind,
    type_name: String,
    version: f64,
    chain: Chain,
}

/// Shorthand for a link with `alpha`/`offset` in radians and bounds in degrees.
fn lk(a: f64, d: f64, alpha: f64, offset: f64, min_deg: f64, max_deg: f64) -> Link {
    Link::new(a, d, alpha, offset, min_deg * DEG2RAD, max_deg * DEG2RAD)
}

/// A homogeneous matrix from its first three rows.
fn rows3(r: [[f64; 4]; 3]) -> Matrix4<f64> {
    Matrix4::new(
        r[0][0], r[0][1], r[0][2], r[0][3], r[1][0], r[1][1], r[1][2], r[1][3], r[2][0], r[2][1],
        r[2][2], r[2][3], 0.0, 0.0, 0.0, 1.0,
    )
}

/// Root-to-torso rotation of iCub versions before 3.
fn h0_torso_v1() -> Matrix4<f64> {
    rows3([
        [0.0, -1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
    ])
}

/// Root-to-torso rotation of iCub 3.
fn h0_torso_v3() -> Matrix4<f64> {
    rows3([
        [0.0, 0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
    ])
}

fn torso_links(version: f64) -> [Link; 3] {
    if version < 3.0 {
        [
            lk(0.032, 0.0, P2, 0.0, -22.0, 84.0),
            lk(0.0, -0.0055, P2, -P2, -39.0, 39.0),
            lk(0.00231, -0.1933, -P2, -P2, -59.0, 59.0),
        ]
    } else {
        [
            lk(0.0725, 0.0, -P2, 0.0, -20.0, 20.0),
            lk(0.0, 0.0, P2, -P2, -40.0, 40.0),
            lk(-0.00486151, -0.26377, -P2, PI, -20.0, 60.0),
        ]
    }
}

fn h0_for(version: f64) -> Matrix4<f64> {
    if version < 3.0 {
        h0_torso_v1()
    } else {
        h0_torso_v3()
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    Left,
    Right,
}

fn unknown(kind: LimbKind, given: &str) -> KinError {
    KinError::UnknownType {
        limb: kind.class_name(),
        given: given.to_owned(),
        known: Limb::known_types(kind),
    }
}

/// Splits `"left_v2.5"` into side and version string (`"v1"` when absent).
fn side_version<'a>(kind: LimbKind, t: &'a str, versions: &[&str]) -> Result<(Side, &'a str)> {
    let (side, ver) = match t.split_once('_') {
        Some((s, v)) => (s, v),
        None => (t, "v1"),
    };
    let side = match side {
        "left" => Side::Left,
        "right" => Side::Right,
        _ => return Err(unknown(kind, t)),
    };
    // iKin reads the number after `_v` and picks the geometry by thresholds: a version
    // between the listed ones (a leg's `v2.7`, on seven robots) is as good as C++ takes it
    let numeric = ver
        .strip_prefix('v')
        .is_some_and(|n| n.parse::<f64>().is_ok_and(f64::is_finite));
    if !versions.contains(&ver) && !numeric {
        return Err(unknown(kind, t));
    }
    Ok((side, ver))
}

/// Numeric version as iKin computes it (`strtod` of what follows `_v`).
fn version_number(v: &str) -> f64 {
    v.trim_start_matches('v').parse().unwrap_or(1.0)
}

fn sided_types(versions: &[&str]) -> Vec<String> {
    let mut out = vec!["left".to_owned(), "right".to_owned()];
    for v in versions {
        out.push(format!("left_{v}"));
        out.push(format!("right_{v}"));
    }
    out
}

impl Limb {
    /// Builds the limb of `kind` for an iKin type string, e.g. `"left_v2.5"`
    /// for an arm, `"v2"` for the inertial sensor, `"right_index"` or
    /// `"left_thumb_a"` for a finger, `""` or `"v3"` for the torso.
    ///
    /// Unlike iKin, which silently falls back to a default, an unknown type is
    /// an error listing the known ones.
    pub fn new(kind: LimbKind, type_name: &str) -> Result<Self> {
        let (chain, version) = match kind {
            LimbKind::Arm => arm(type_name)?,
            LimbKind::Leg => leg(type_name)?,
            LimbKind::Eye => eye(type_name)?,
            LimbKind::EyeNeckRef => {
                let (mut c, v) = eye(type_name).map_err(|_| unknown(kind, type_name))?;
                for _ in 0..3 {
                    c.remove_link(0)?;
                }
                (c, v)
            }
            LimbKind::HeadCenter => {
                let (mut c, v) = eye(type_name).map_err(|_| unknown(kind, type_name))?;
                let n = c.n();
                let l = *c.link(n - 2)?;
                c.set_link(n - 2, Link { d: 0.0, ..l })?;
                c.block_link(n - 2, 0.0)?;
                c.block_link(n - 1, 0.0)?;
                (c, v)
            }
            LimbKind::InertialSensor => inertial(type_name)?,
            LimbKind::Torso => torso(type_name)?,
            LimbKind::Finger => finger(type_name)?,
        };
        Ok(Self {
            kind,
            type_name: type_name.to_owned(),
            version,
            chain,
        })
    }

    /// `iCubArm`: 10 links, torso (links 0–2) blocked at 0, so DOF = 7.
    pub fn arm(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::Arm, type_name)
    }
    /// `iCubLeg`: 6 links.
    pub fn leg(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::Leg, type_name)
    }
    /// `iCubEye`: 8 links, torso blocked.
    pub fn eye(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::Eye, type_name)
    }
    /// `iCubEyeNeckRef`: 5 links, root at the neck base (H0 of the torso kept, as iKin).
    pub fn eye_neck_ref(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::EyeNeckRef, type_name)
    }
    /// `iCubHeadCenter`: the point between the eyes.
    pub fn head_center(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::HeadCenter, type_name)
    }
    /// `iCubInertialSensor`: type is the version alone (`"v1"`, `"v2"`, …).
    pub fn inertial_sensor(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::InertialSensor, type_name)
    }
    /// `iCubTorso`: 3 released links.
    pub fn torso(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::Torso, type_name)
    }
    /// `iCubFinger`: `<left|right>_<finger>[_<na|a|b>]`.
    pub fn finger(type_name: &str) -> Result<Self> {
        Self::new(LimbKind::Finger, type_name)
    }

    /// Every type string accepted for `kind`.
    pub fn known_types(kind: LimbKind) -> Vec<String> {
        match kind {
            LimbKind::Arm => sided_types(ARM_VERSIONS),
            LimbKind::Leg => sided_types(LEG_VERSIONS),
            LimbKind::Eye | LimbKind::EyeNeckRef | LimbKind::HeadCenter => {
                sided_types(EYE_VERSIONS)
            }
            LimbKind::InertialSensor => INERTIAL_VERSIONS.iter().map(|s| s.to_string()).collect(),
            LimbKind::Torso => std::iter::once(String::new())
                .chain(ARM_VERSIONS.iter().map(|s| s.to_string()))
                .collect(),
            LimbKind::Finger => {
                let mut out = Vec::new();
                for hand in ["left", "right"] {
                    for f in FINGERS {
                        out.push(format!("{hand}_{f}"));
                        for v in FINGER_VERSIONS {
                            out.push(format!("{hand}_{f}_{v}"));
                        }
                    }
                }
                out
            }
        }
    }

    /// The limb class.
    pub fn kind(&self) -> LimbKind {
        self.kind
    }
    /// The type string it was built from.
    pub fn type_name(&self) -> &str {
        &self.type_name
    }
    /// Numeric hardware version (1.0 when the type has none; 0 for fingers).
    pub fn version(&self) -> f64 {
        self.version
    }
    /// The kinematic chain.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }
    /// The kinematic chain, mutable (to block/release links, set angles, …).
    pub fn chain_mut(&mut self) -> &mut Chain {
        &mut self.chain
    }
    /// Consumes the limb, keeping the chain.
    pub fn into_chain(self) -> Chain {
        self.chain
    }

    /// Sets every link angle (blocked links included) from robot encoders in
    /// degrees, the way the iCub parts order their joints:
    ///
    /// - `torso`: the `torso` part (yaw, roll, pitch); chains of versions
    ///   before 3 run pitch → roll → yaw, so they are reversed as in iKin's
    ///   `alignJointsBounds`. Ignored by legs, fingers and the neck-ref eye.
    /// - `part`: the arm part (≥ 7 values) for arms; the leg part (≥ 6) for
    ///   legs; the head part (≥ 6: neck pitch, roll, yaw, eyes tilt, version,
    ///   vergence) for eyes and the inertial sensor, each eye's pan being
    ///   `version ± vergence/2` (+ left, − right); the hand (9) or arm+hand
    ///   (16) encoders for fingers, coupled as `iCubFinger::getChainJoints`.
    pub fn set_from_encoders(&mut self, torso: &[f64], part: &[f64]) -> Result<()> {
        let need = |v: &[f64], n: usize| -> Result<()> {
            if v.len() < n {
                Err(KinError::DimensionMismatch {
                    expected: n,
                    got: v.len(),
                })
            } else if v.iter().any(|x| !x.is_finite()) {
                Err(KinError::NonFinite("encoders"))
            } else {
                Ok(())
            }
        };
        let mut angles: Vec<f64> = Vec::with_capacity(self.chain.n());
        let with_torso = !matches!(
            self.kind,
            LimbKind::Leg | LimbKind::Finger | LimbKind::EyeNeckRef
        );
        if with_torso {
            need(torso, 3)?;
            if self.version < 3.0 {
                angles.extend([torso[2], torso[1], torso[0]]);
            } else {
                angles.extend_from_slice(&torso[..3]);
            }
        }
        let left = self.type_name.starts_with("left");
        match self.kind {
            LimbKind::Torso => {}
            LimbKind::Arm => {
                need(part, 7)?;
                angles.extend_from_slice(&part[..7]);
            }
            LimbKind::Leg => {
                need(part, 6)?;
                angles.extend_from_slice(&part[..6]);
            }
            LimbKind::InertialSensor => {
                need(part, 3)?;
                angles.extend_from_slice(&part[..3]);
            }
            LimbKind::Eye | LimbKind::EyeNeckRef | LimbKind::HeadCenter => {
                need(part, 6)?;
                let pan = if left {
                    part[4] + part[5] / 2.0
                } else {
                    part[4] - part[5] / 2.0
                };
                angles.extend_from_slice(&part[..4]);
                angles.push(pan);
                if self.kind == LimbKind::HeadCenter {
                    // The eye links of the head center are fixed at zero.
                    let n = angles.len();
                    angles[n - 2] = 0.0;
                    angles[n - 1] = 0.0;
                }
            }
            LimbKind::Finger => return self.set_finger_encoders(part),
        }
        for (i, a) in angles.iter().enumerate() {
            self.chain.set_link_ang(i, a * DEG2RAD)?;
        }
        Ok(())
    }

    /// [`Limb::set_from_encoders`] then the end-effector 7-vector pose
    /// `x y z ax ay az θ` — what the iCub's cartesian `state:o` ports stream.
    pub fn pose_from_encoders(&mut self, torso: &[f64], part: &[f64]) -> Result<Vector7<f64>> {
        self.set_from_encoders(torso, part)?;
        Ok(self.chain.end_eff_pose())
    }

    fn set_finger_encoders(&mut self, m: &[f64]) -> Result<()> {
        if m.len() != 9 && m.len() != 16 {
            return Err(KinError::DimensionMismatch {
                expected: 9,
                got: m.len(),
            });
        }
        if m.iter().any(|x| !x.is_finite()) {
            return Err(KinError::NonFinite("encoders"));
        }
        let o = if m.len() == 16 { 7 } else { 0 };
        let finger = self.type_name.split('_').nth(1).unwrap_or("index");
        let q: Vec<f64> = match finger {
            "thumb" => vec![m[o + 1], m[o + 2], m[o + 3] / 2.0, m[o + 3] / 2.0],
            "index" => vec![m[o] / 3.0, m[o + 4], m[o + 5] / 2.0, m[o + 5] / 2.0],
            "middle" => vec![m[o + 6], m[o + 7] / 2.0, m[o + 7] / 2.0],
            _ => vec![m[o] / 3.0, m[o + 8] / 3.0, m[o + 8] / 3.0, m[o + 8] / 3.0],
        };
        self.chain.set_ang_deg(&q).map(|_| ())
    }
}

fn arm(t: &str) -> Result<(Chain, f64)> {
    let (side, v) = side_version(LimbKind::Arm, t, ARM_VERSIONS)?;
    let ver = version_number(v);
    let links: Vec<Link> = match (side, ver < 3.0) {
        (Side::Right, true) => vec![
            lk(0.032, 0.0, P2, 0.0, -22.0, 84.0),
            lk(0.0, -0.0055, P2, -P2, -39.0, 39.0),
            lk(-0.0233647, -0.1433, P2, -105.0 * DEG2RAD, -59.0, 59.0),
            lk(0.0, -0.10774, P2, -P2, -95.5, 5.0),
            lk(0.0, 0.0, -P2, -P2, 0.0, 160.8),
            lk(-0.015, -0.15228, -P2, -105.0 * DEG2RAD, -37.0, 100.0),
            lk(0.015, 0.0, P2, 0.0, 5.5, 106.0),
            lk(
                0.0,
                if ver < 1.7 { -0.1373 } else { -0.1413 },
                P2,
                -P2,
                -50.0,
                50.0,
            ),
            lk(0.0, 0.0, P2, P2, -65.0, 10.0),
            lk(
                0.0625,
                if ver < 2.0 { 0.016 } else { 0.02598 },
                0.0,
                PI,
                -25.0,
                25.0,
            ),
        ],
        (Side::Right, false) => vec![
            lk(0.0725, 0.0, -P2, 0.0, -20.0, 20.0),
            lk(0.0, 0.0, P2, -P2, -40.0, 40.0),
            lk(
                -0.0304112,
                -0.161133,
                75.489181 * DEG2RAD,
                165.0 * DEG2RAD,
                -20.0,
                60.0,
            ),
            lk(0.0, -0.163978, P2, -P2, -90.0, 2.0),
            lk(0.0, 0.0, -P2, -104.5 * DEG2RAD, -5.0, 140.0),
            lk(-0.01065, -0.2005, -P2, -105.0 * DEG2RAD, -45.0, 80.0),
            lk(0.0146593, 0.00308819, P2, 0.0, -5.0, 110.0),
            lk(-0.0020075, -0.1628, P2, -P2, -60.0, 60.0),
            lk(0.0, 0.0, P2, P2, -70.0, 25.0),
            lk(0.0625, 0.016, 0.0, PI, -15.0, 35.0),
        ],
        (Side::Left, true) => vec![
            lk(0.032, 0.0, P2, 0.0, -22.0, 84.0),
            lk(0.0, -0.0055, P2, -P2, -39.0, 39.0),
            lk(0.0233647, -0.1433, -P2, 105.0 * DEG2RAD, -59.0, 59.0),
            lk(0.0, 0.10774, -P2, P2, -95.5, 5.0),
            lk(0.0, 0.0, P2, -P2, 0.0, 160.8),
            lk(0.015, 0.15228, -P2, 75.0 * DEG2RAD, -37.0, 100.0),
            lk(-0.015, 0.0, P2, 0.0, 5.5, 106.0),
            lk(
                0.0,
                if ver < 1.7 { 0.1373 } else { 0.1413 },
                P2,
                -P2,
                -50.0,
                50.0,
            ),
            lk(0.0, 0.0, P2, P2, -65.0, 10.0),
            lk(
                0.0625,
                if ver < 2.0 { -0.016 } else { -0.02598 },
                0.0,
                0.0,
                -25.0,
                25.0,
            ),
        ],
        (Side::Left, false) => vec![
            lk(0.0725, 0.0, -P2, 0.0, -20.0, 20.0),
            lk(0.0, 0.0, P2, -P2, -40.0, 40.0),
            lk(
                0.0304112,
                -0.161133,
                -104.510819 * DEG2RAD,
                15.0 * DEG2RAD,
                -20.0,
                60.0,
            ),
            lk(0.0, 0.163978, P2, -P2, -90.0, 2.0),
            lk(0.0, 0.0, P2, 75.5 * DEG2RAD, -5.0, 140.0),
            lk(0.01065, 0.2005, -P2, 75.0 * DEG2RAD, -45.0, 80.0),
            lk(-0.0146593, -0.00308819, P2, 0.0, -5.0, 110.0),
            lk(0.0020075, 0.1628, P2, -P2, -60.0, 60.0),
            lk(0.0, 0.0, P2, P2, -70.0, 25.0),
            lk(0.0625, -0.016, 0.0, 0.0, -15.0, 35.0),
        ],
    };
    let mut c = Chain::from_links(h0_for(ver), links);
    for i in 0..3 {
        c.block_link(i, 0.0)?;
    }
    Ok((c, ver))
}

fn torso(t: &str) -> Result<(Chain, f64)> {
    let ver = if t.is_empty() {
        1.0
    } else if ARM_VERSIONS.contains(&t) {
        version_number(t)
    } else {
        return Err(unknown(LimbKind::Torso, t));
    };
    Ok((Chain::from_links(h0_for(ver), torso_links(ver)), ver))
}

fn leg(t: &str) -> Result<(Chain, f64)> {
    let (side, v) = side_version(LimbKind::Leg, t, LEG_VERSIONS)?;
    let ver = version_number(v);
    let y = if side == Side::Right { 1.0 } else { -1.0 };
    // iKin 2.11: below 2 the first legs, below 3 the v2.5 legs, then the iCub 3's
    let era = if ver < 2.0 {
        "v1"
    } else if ver < 3.0 {
        "v2.5"
    } else {
        "v3"
    };
    let (h0, links) = match (side, era) {
        (Side::Right, "v1") => (
            leg_h0_v1(0.0681),
            vec![
                lk(0.0, 0.0, P2, P2, -44.0, 132.0),
                lk(0.0, 0.0, P2, P2, -119.0, 17.0),
                lk(0.0, 0.2236, -P2, -P2, -79.0, 79.0),
                lk(-0.213, 0.0, PI, P2, -125.0, 0.0),
                lk(0.0, 0.0, P2, 0.0, -42.0, 21.0),
                lk(-0.041, 0.0, PI, 0.0, -24.0, 24.0),
            ],
        ),
        (Side::Left, "v1") => (
            leg_h0_v1(-0.0681),
            vec![
                lk(0.0, 0.0, -P2, P2, -44.0, 132.0),
                lk(0.0, 0.0, -P2, P2, -119.0, 17.0),
                lk(0.0, -0.2236, P2, -P2, -79.0, 79.0),
                lk(-0.213, 0.0, PI, P2, -125.0, 0.0),
                lk(0.0, 0.0, -P2, 0.0, -42.0, 21.0),
                lk(-0.041, 0.0, 0.0, 0.0, -24.0, 24.0),
            ],
        ),
        (_, "v2.5") => (
            leg_h0_v1(y * 0.0681),
            vec![
                lk(0.0, 0.0, y * P2, P2, -44.0, 132.0),
                lk(0.0, 0.0, y * P2, P2, -119.0, 17.0),
                lk(-0.0009175, y * 0.234545, -y * P2, -P2, -79.0, 79.0),
                lk(-0.2005, 0.0, PI, P2, -125.0, 0.0),
                lk(0.0, 0.0, y * P2, 0.0, -42.0, 21.0),
                lk(
                    -0.06805,
                    y * 0.0035,
                    if side == Side::Right { PI } else { 0.0 },
                    0.0,
                    -24.0,
                    24.0,
                ),
            ],
        ),
        _ => (
            rows3([
                [1.0, 0.0, 0.0, -0.0216],
                [0.0, 0.0, 1.0, y * 0.07365],
                [0.0, -1.0, 0.0, -0.0605],
            ]),
            vec![
                lk(0.009, 0.0, y * P2, P2, -40.0, 125.0),
                lk(-0.015, y * 0.0106, y * P2, P2, 5.0, 111.0),
                lk(0.015, y * 0.2668, -y * P2, -P2, -62.5, 62.5),
                lk(-0.255988, 0.0062, PI, P2, -100.0, 0.0),
                lk(-0.035, 0.0, y * P2, 0.0, -40.0, 40.0),
                lk(
                    -0.0532,
                    0.0,
                    if side == Side::Right { PI } else { 0.0 },
                    0.0,
                    -20.0,
                    20.0,
                ),
            ],
        ),
    };
    Ok((Chain::from_links(h0, links), ver))
}

fn leg_h0_v1(y: f64) -> Matrix4<f64> {
    rows3([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, y],
        [0.0, -1.0, 0.0, -0.1199],
    ])
}

fn eye(t: &str) -> Result<(Chain, f64)> {
    let (side, v) = side_version(LimbKind::Eye, t, EYE_VERSIONS)?;
    let ver = version_number(v);
    // The eye-pan link is displaced towards the eye: +y (right), -y (left).
    let d_eye = if side == Side::Right { 0.034 } else { -0.034 };
    let mut links: Vec<Link> = torso_links(ver).to_vec();
    if ver < 2.0 {
        links.extend([
            lk(0.033, 0.0, P2, P2, -40.0, 30.0),
            lk(0.0, 0.001, -P2, -P2, -70.0, 60.0),
            lk(-0.054, 0.0825, -P2, P2, -55.0, 55.0),
        ]);
    } else if v == "v2.10" {
        // the 4k cameras' head (iKin compares versions as major.minor integers: 2.10 > 2.8)
        links[2] = lk(0.0053, -0.2233, -P2, -P2, -59.0, 59.0);
        links.extend([
            lk(0.0110, 0.0, P2, P2, -40.0, 30.0),
            lk(0.0, 0.0, -P2, -P2, -70.0, 60.0),
            lk(-0.0510, 0.08052, -P2, P2, -55.0, 55.0),
        ]);
    } else if ver < 3.0 {
        links[2] = lk(0.0, -0.2233, -P2, -P2, -59.0, 59.0);
        links.extend([
            lk(0.0095, 0.0, P2, P2, -40.0, 30.0),
            lk(0.0, 0.0, -P2, -P2, -70.0, 60.0),
            lk(-0.0509, 0.08205, -P2, P2, -55.0, 55.0),
        ]);
    } else {
        links.extend([
            lk(0.0095, 0.0, P2, P2, -30.0, 22.0),
            lk(0.0, 0.0, -P2, -P2, -20.0, 20.0),
            lk(-0.0509, 0.08205, -P2, P2, -45.0, 45.0),
        ]);
    }
    links.extend([
        lk(0.0, d_eye, -P2, 0.0, -35.0, 15.0),
        lk(0.0, 0.0, P2, -P2, -50.0, 50.0),
    ]);
    // iKin's v3 eye zeroes H0 including H0(3,3); only the rotation matters
    // for positions, and we keep a proper homogeneous matrix.
    let mut c = Chain::from_links(h0_for(ver), links);
    // the image planes of the event-driven (2.8) and 4k (2.10) cameras
    let plane = match v {
        "v2.8" => Some(-0.01),
        "v2.10" => Some(-9.83e-3),
        _ => None,
    };
    if let Some(z) = plane {
        let mut hn = Matrix4::identity();
        hn[(2, 3)] = z;
        c.set_hn(hn)?;
    }
    for i in 0..3 {
        c.block_link(i, 0.0)?;
    }
    Ok((c, ver))
}

fn inertial(t: &str) -> Result<(Chain, f64)> {
    if !INERTIAL_VERSIONS.contains(&t) {
        return Err(unknown(LimbKind::InertialSensor, t));
    }
    let ver = version_number(t);
    let mut links: Vec<Link> = torso_links(ver).to_vec();
    if ver < 2.0 {
        links.extend([
            lk(0.033, 0.0, P2, P2, -40.0, 30.0),
            lk(0.0, 0.001, -P2, -P2, -70.0, 60.0),
            lk(0.0225, 0.1005, -P2, P2, -55.0, 55.0),
        ]);
    } else if ver < 3.0 {
        links[2] = lk(0.0, -0.2233, -P2, -P2, -59.0, 59.0);
        links.extend([
            lk(0.0095, 0.0, P2, P2, -40.0, 30.0),
            lk(0.0, 0.0, -P2, -P2, -70.0, 60.0),
            lk(0.0185, 0.1108, -P2, P2, -55.0, 55.0),
        ]);
    } else {
        links.extend([
            lk(0.0095, 0.0, P2, P2, -30.0, 22.0),
            lk(0.0, 0.0, -P2, -P2, -20.0, 20.0),
            lk(0.0185, 0.1108, -P2, P2, -45.0, 45.0),
        ]);
    }
    let mut c = Chain::from_links(h0_for(ver), links);
    // T_nls of http://wiki.icub.org/wiki/ICubInertiaSensorKinematics
    let mut hn = rows3([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, -1.0, 0.0],
        [0.0, 1.0, 0.0, 0.0066],
    ]);
    if matches!(t, "v2.5" | "v2.6" | "v3") {
        hn *= rows3([
            [1.0, 0.0, 0.0, 0.0087],
            [0.0, 1.0, 0.0, 0.01795],
            [0.0, 0.0, 1.0, -0.0105],
        ]);
    }
    if t == "v2.6" {
        hn *= rows3([
            [0.0, 1.0, 0.0, 0.0323779],
            [1.0, 0.0, 0.0, -0.0139537],
            [0.0, 0.0, -1.0, 0.072],
        ]);
    }
    c.set_hn(hn)?;
    Ok((c, ver))
}

fn finger(t: &str) -> Result<(Chain, f64)> {
    let err = || unknown(LimbKind::Finger, t);
    let mut parts = t.split('_');
    let hand = parts.next().ok_or_else(err)?;
    let name = parts.next().ok_or_else(err)?;
    let ver = parts.next().unwrap_or("na");
    if parts.next().is_some()
        || !matches!(hand, "left" | "right")
        || !FINGERS.contains(&name)
        || !FINGER_VERSIONS.contains(&ver)
    {
        return Err(err());
    }
    let left = hand == "left";
    let s = if left { -1.0 } else { 1.0 };
    // Left-hand frames mirror the right ones about the palm plane.
    let mirror = |mut h: Matrix4<f64>, cells: &[(usize, usize)]| {
        if left {
            for &(r, c) in cells {
                h[(r, c)] = -h[(r, c)];
            }
        }
        h
    };
    let std_flip = [(2, 0), (2, 1), (1, 2), (2, 3)];
    let (h0, links, dummy) = match name {
        "thumb" => {
            let h0 = if ver == "a" {
                rows3([
                    [0.121132, 0.043736, -0.991672, -0.025391770],
                    [-0.958978, 0.263104, -0.105535, -0.011783901],
                    [0.256297, 0.963776, 0.073812, -0.0017018],
                ])
            } else {
                rows3([
                    [0.478469, 0.063689, -0.875792, -0.024029759],
                    [-0.878095, 0.039246, -0.476873, -0.01193433],
                    [0.004, 0.997198, 0.074703, -0.00168926],
                ])
            };
            let links = vec![
                lk(0.0, 0.0, -s * P2, 0.0, 10.0, 90.0),
                lk(0.0210, s * 0.0056, 0.0, 0.0, 0.0, 0.0),
                lk(0.0260, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(0.0220, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(0.0168, 0.0, -P2, 0.0, 0.0, 90.0),
            ];
            // iKin does not negate H0(2,0) here: harmless for version "b"
            // (0.004) but it leaves the left "a" base non-orthonormal. Kept
            // as iKin has it, for parity with the robot's software.
            (mirror(h0, &[(2, 1), (0, 2), (1, 2), (2, 3)]), links, true)
        }
        "index" => {
            let h0 = rows3([
                [0.898138, 0.439714, 0.0, 0.00245549],
                [-0.43804, 0.89472, 0.087156, -0.025320433],
                [0.038324, -0.078278, 0.996195, -0.010973325],
            ]);
            let links = vec![
                lk(0.0148, 0.0, s * P2, 0.0, 0.0, 20.0),
                lk(0.0259, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(0.0220, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(0.0168, 0.0, -P2, 0.0, 0.0, 90.0),
            ];
            (mirror(h0, &std_flip), links, false)
        }
        "middle" => {
            let h0 = rows3([
                [1.0, 0.0, 0.0, 0.0178],
                [0.0, 0.0, -1.0, -0.00830233],
                [0.0, 1.0, 0.0, -0.0118],
            ]);
            let links = vec![
                lk(0.0285, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(0.0240, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(0.0168, 0.0, -P2, 0.0, 0.0, 90.0),
            ];
            (mirror(h0, &[(2, 1), (1, 2), (2, 3)]), links, false)
        }
        _ => {
            let ring = name == "ring";
            let h0 = rows3([
                [
                    0.9998,
                    0.0192,
                    0.0,
                    if ring { 0.001569230 } else { -0.00042147 },
                ],
                [
                    0.0191,
                    -0.9960,
                    0.0872,
                    if ring { 0.007158757 } else { 0.0232755 },
                ],
                [
                    0.0017,
                    -0.0871,
                    -0.9962,
                    if ring { -0.011458935 } else { -0.00956329 },
                ],
            ]);
            let links = vec![
                lk(0.0148, 0.0, -s * P2, -20.0 * DEG2RAD, 0.0, 20.0),
                lk(if ring { 0.0259 } else { 0.0219 }, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(if ring { 0.0220 } else { 0.0190 }, 0.0, 0.0, 0.0, 0.0, 90.0),
                lk(0.0168, 0.0, -P2, 0.0, 0.0, 90.0),
            ];
            (mirror(h0, &std_flip), links, false)
        }
    };
    let mut c = Chain::from_links(h0, links);
    if dummy {
        // The thumb's second link is a fixed offset, not a joint.
        c.block_link(1, 0.0)?;
    }
    Ok((c, 0.0))
}
