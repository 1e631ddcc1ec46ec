//! TF from a URDF and joint positions, as robot_state_publisher computes it (pure).
//!
//! Every joint is a transform from its parent link's frame to its child link's: the
//! joint's `<origin>` (xyz, then roll-pitch-yaw about the fixed axes), then its motion
//! (a rotation of the position about `<axis>` for revolute and continuous joints, a
//! translation along it for prismatic ones; `<mimic>` joints follow theirs). Fixed joints
//! go on `/tf_static` once; the others on `/tf` with each joint state.

use crate::dynmsg::Value as Ros;
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

/// How a joint moves its child.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    Fixed,
    /// Revolute or continuous.
    Rotation,
    Prismatic,
    /// Floating or planar: not driven by one position (left out, as robot_state_publisher
    /// does).
    Other,
}

/// One URDF joint, as far as TF needs it.
#[derive(Debug, Clone, PartialEq)]
pub struct TfJoint {
    pub name: String,
    pub parent: String,
    pub child: String,
    pub origin: Isometry3<f64>,
    pub axis: Unit<Vector3<f64>>,
    pub motion: Motion,
    /// `<mimic joint= multiplier= offset=>`.
    pub mimic: Option<(String, f64, f64)>,
}

impl TfJoint {
    /// The child's frame in the parent's at position `q` (rad or m).
    pub fn transform(&self, q: f64) -> Isometry3<f64> {
        match self.motion {
            Motion::Rotation => {
                self.origin
                    * Isometry3::from_parts(
                        Translation3::identity(),
                        UnitQuaternion::from_axis_angle(&self.axis, q),
                    )
            }
            Motion::Prismatic => {
                self.origin
                    * Isometry3::from_parts(
                        Translation3::from(self.axis.into_inner() * q),
                        UnitQuaternion::identity(),
                    )
            }
            Motion::Fixed | Motion::Other => self.origin,
        }
    }
}

/// The joints of a URDF document (already checked by [`crate::robot::urdf_joints`]).
pub fn tf_joints(urdf: &str) -> Result<Vec<TfJoint>, String> {
    let doc = roxmltree::Document::parse(urdf).map_err(|e| format!("not XML: {e}"))?;
    let mut out = Vec::new();
    for j in doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("joint"))
    {
        let name = j.attribute("name").unwrap_or_default().to_string();
        let child_attr = |tag: &str, attr: &str| {
            j.children()
                .find(|c| c.has_tag_name(tag))
                .and_then(|c| c.attribute(attr))
        };
        let triple = |tag: &str, attr: &str, default: [f64; 3]| -> Result<[f64; 3], String> {
            let Some(text) = child_attr(tag, attr) else {
                return Ok(default);
            };
            let v: Vec<f64> = text
                .split_whitespace()
                .map(str::parse)
                .collect::<Result<_, _>>()
                .map_err(|_| {
                    format!("joint `{name}`: <{tag} {attr}=\"{text}\"> is not 3 numbers")
                })?;
            <[f64; 3]>::try_from(v)
                .map_err(|_| format!("joint `{name}`: <{tag} {attr}=\"{text}\"> is not 3 numbers"))
        };
        let xyz = triple("origin", "xyz", [0.0; 3])?;
        let rpy = triple("origin", "rpy", [0.0; 3])?;
        let axis = triple("axis", "xyz", [1.0, 0.0, 0.0])?;
        let motion = match j.attribute("type").unwrap_or_default() {
            "fixed" => Motion::Fixed,
            "revolute" | "continuous" => Motion::Rotation,
            "prismatic" => Motion::Prismatic,
            _ => Motion::Other,
        };
        // urdfdom reads the axis of movable joints only: fixed ones may have a zero axis
        // (the iCubs' URDFs do).
        let axis = match Unit::try_new(Vector3::from(axis), 1e-12) {
            Some(a) => a,
            None if matches!(motion, Motion::Fixed | Motion::Other) => Vector3::x_axis(),
            None => return Err(format!("joint `{name}`: its axis is zero")),
        };
        let mimic = j.children().find(|c| c.has_tag_name("mimic")).map(|m| {
            let num = |a: &str, d: f64| m.attribute(a).and_then(|v| v.parse().ok()).unwrap_or(d);
            (
                m.attribute("joint").unwrap_or_default().to_string(),
                num("multiplier", 1.0),
                num("offset", 0.0),
            )
        });
        out.push(TfJoint {
            parent: child_attr("parent", "link").unwrap_or_default().to_string(),
            child: child_attr("child", "link").unwrap_or_default().to_string(),
            origin: Isometry3::from_parts(
                Translation3::from(Vector3::from(xyz)),
                UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
            ),
            axis,
            motion,
            mimic,
            name,
        });
    }
    Ok(out)
}

/// `tf2_msgs/TFMessage` of the fixed joints, stamped `stamp_ns`.
pub fn static_message(joints: &[TfJoint], stamp_ns: u64) -> Ros {
    let stamp = Ros::time(stamp_ns);
    tf_message(
        joints
            .iter()
            .filter(|j| j.motion == Motion::Fixed)
            .map(|j| transform_stamped(&stamp, j, &j.origin))
            .collect(),
    )
}

/// `tf2_msgs/TFMessage` of the moving joints whose position (or whose mimicked joint's)
/// is among `names`/`positions`, stamped `stamp` (a `builtin_interfaces/Time`); `None`
/// when there is none.
pub fn moving_message(
    joints: &[TfJoint],
    names: &[&str],
    positions: &[f64],
    stamp: &Ros,
) -> Option<Ros> {
    let position = |n: &str| {
        names
            .iter()
            .position(|x| *x == n)
            .and_then(|i| positions.get(i).copied())
    };
    let transforms: Vec<Ros> = joints
        .iter()
        .filter(|j| matches!(j.motion, Motion::Rotation | Motion::Prismatic))
        .filter_map(|j| {
            let q = match &j.mimic {
                Some((of, k, offset)) => position(of).map(|q| k * q + offset),
                None => position(&j.name),
            }?;
            Some(transform_stamped(stamp, j, &j.transform(q)))
        })
        .collect();
    (!transforms.is_empty()).then(|| tf_message(transforms))
}

fn tf_message(transforms: Vec<Ros>) -> Ros {
    Ros::Struct(vec![Ros::List(transforms)])
}

/// `geometry_msgs/TransformStamped`: `j.child` in `j.parent`.
fn transform_stamped(stamp: &Ros, j: &TfJoint, iso: &Isometry3<f64>) -> Ros {
    let t = iso.translation.vector;
    let r = iso.rotation.quaternion();
    Ros::Struct(vec![
        Ros::Struct(vec![stamp.clone(), Ros::Str(j.parent.clone())]),
        Ros::Str(j.child.clone()),
        Ros::Struct(vec![
            Ros::Struct(vec![Ros::F64(t.x), Ros::F64(t.y), Ros::F64(t.z)]),
            Ros::Struct(vec![
                Ros::F64(r.i),
                Ros::F64(r.j),
                Ros::F64(r.k),
                Ros::F64(r.w),
            ]),
        ]),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    const URDF: &str = r#"<robot name="r">
      <link name="a"/><link name="b"/><link name="c"/><link name="d"/>
      <joint name="fix" type="fixed"><parent link="a"/><child link="b"/>
        <origin xyz="0.1 0 0.2" rpy="0 0 1.5707963267948966"/></joint>
      <joint name="rev" type="revolute"><parent link="b"/><child link="c"/>
        <origin xyz="0 0 -0.3"/><axis xyz="0 1 0"/></joint>
      <joint name="twin" type="continuous"><parent link="c"/><child link="d"/>
        <mimic joint="rev" multiplier="-2" offset="0.1"/></joint>
    </robot>"#;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn origins_axes_and_mimics() {
        let j = tf_joints(URDF).unwrap();
        assert_eq!(j.len(), 3);
        assert_eq!((j[0].parent.as_str(), j[0].child.as_str()), ("a", "b"));
        // A point 1 m along b's x is 1 m along a's y, offset by the origin.
        let p = j[0].transform(0.0) * nalgebra::Point3::new(1.0, 0.0, 0.0);
        assert!(close(p.x, 0.1) && close(p.y, 1.0) && close(p.z, 0.2), "{p}");
        // 90° about y takes c's x to b's -z.
        let p = j[1].transform(std::f64::consts::FRAC_PI_2) * nalgebra::Point3::new(1.0, 0.0, 0.0);
        assert!(
            close(p.x, 0.0) && close(p.y, 0.0) && close(p.z, -1.3),
            "{p}"
        );
        assert_eq!(j[2].mimic, Some(("rev".into(), -2.0, 0.1)));
        let m = moving_message(&j, &["rev"], &[0.5], &Ros::time(7)).unwrap();
        let Ros::Struct(f) = m else { panic!() };
        let Ros::List(t) = &f[0] else { panic!() };
        assert_eq!(t.len(), 2, "rev and its mimic");
        let s = static_message(&j, 5);
        let Ros::Struct(f) = s else { panic!() };
        let Ros::List(t) = &f[0] else { panic!() };
        assert_eq!(t.len(), 1);
        assert!(moving_message(&j, &["other"], &[0.5], &Ros::time(7)).is_none());
    }

    #[test]
    fn bad_numbers_are_named() {
        let bad = URDF.replace("0.1 0 0.2", "0.1 0");
        assert!(tf_joints(&bad).unwrap_err().contains("joint `fix`"));
    }
}
