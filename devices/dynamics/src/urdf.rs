//! Reading a model from a URDF file: links and joints through `urdf-rs`, and
//! the `<sensor>` elements iDynTree's loader adds to URDF (which `urdf-rs`
//! does not know) read from the same text.

use std::path::Path;

use nalgebra::{Matrix3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::error::{DynError, Result};
use crate::model::{JointKind, Link, Model, RawJoint};
use crate::sensors::{FtSensor, ImuKind, ImuSensor, Sensors};
use crate::spatial::{Inertia, Iso};

/// Reads a URDF file into a model with its sensors.
pub fn read_file(path: impl AsRef<Path>) -> Result<Model> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| DynError::Urdf {
        path: path.into(),
        reason: e.to_string(),
    })?;
    read_str(&text).map_err(|e| match e {
        DynError::Urdf { reason, .. } => DynError::Urdf {
            path: path.into(),
            reason,
        },
        other => other,
    })
}

/// Reads URDF text into a model with its sensors.
pub fn read_str(text: &str) -> Result<Model> {
    let urdf_err = |reason: String| DynError::Urdf {
        path: "<urdf>".into(),
        reason,
    };
    let robot = urdf_rs::read_from_string(text).map_err(|e| urdf_err(e.to_string()))?;
    let links = robot
        .links
        .iter()
        .map(|l| {
            let i = &l.inertial;
            let m = &i.inertia;
            let frame = pose(&i.origin);
            let about_com = Matrix3::new(
                m.ixx, m.ixy, m.ixz, m.ixy, m.iyy, m.iyz, m.ixz, m.iyz, m.izz,
            );
            let r = frame.rotation.to_rotation_matrix().into_inner();
            Link {
                name: l.name.clone(),
                inertia: Inertia {
                    mass: i.mass.value,
                    com: frame.translation.vector,
                    rot_com: r * about_com * r.transpose(),
                },
            }
        })
        .collect();
    let joints = robot
        .joints
        .iter()
        .map(|j| {
            let kind = match j.joint_type {
                urdf_rs::JointType::Fixed => JointKind::Fixed,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                    JointKind::Revolute
                }
                urdf_rs::JointType::Prismatic => JointKind::Prismatic,
                ref other => {
                    return Err(DynError::UnsupportedJoint {
                        joint: j.name.clone(),
                        kind: format!("{other:?}").to_lowercase(),
                    })
                }
            };
            let axis = Vector3::from_column_slice(&j.axis.xyz[..]);
            let axis = Unit::try_new(axis, 1e-12).unwrap_or(Vector3::x_axis());
            let limits = (j.joint_type == urdf_rs::JointType::Revolute
                || j.joint_type == urdf_rs::JointType::Prismatic)
                .then_some((j.limit.lower, j.limit.upper));
            Ok(RawJoint {
                name: j.name.clone(),
                kind,
                parent: j.parent.link.clone(),
                child: j.child.link.clone(),
                origin: pose(&j.origin),
                axis,
                limits,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let mut model = Model::new(links, joints)?;
    model.sensors = read_sensors(text, &model)?;
    // iDynTree's `addSensorFramesAsAdditionalFrames`: each sensor's name is a
    // frame too (an F/T sensor's on the joint's child), unless taken.
    let sensor_frames: Vec<_> = model
        .sensors
        .ft
        .iter()
        .map(|s| {
            let child = model.joints[s.joint].child;
            (s.name.clone(), child, s.pose_on(&model, child))
        })
        .chain(
            model
                .sensors
                .imu
                .iter()
                .map(|s| (s.name.clone(), s.link, s.link_h_sensor)),
        )
        .collect();
    for (name, link, pose) in sensor_frames {
        model.add_frame(&name, link, pose);
    }
    Ok(model)
}

fn pose(p: &urdf_rs::Pose) -> Iso {
    let (x, r) = (&p.xyz, &p.rpy);
    Iso::from_parts(
        Translation3::new(x[0], x[1], x[2]),
        UnitQuaternion::from_euler_angles(r[0], r[1], r[2]),
    )
}

/// `xyz="…" rpy="…"` of an `<origin>`, identity when absent.
fn origin_of(node: roxmltree::Node) -> Result<Iso> {
    let Some(o) = node.children().find(|c| c.has_tag_name("origin")) else {
        return Ok(Iso::identity());
    };
    let triple = |attr: &str| -> Result<[f64; 3]> {
        let Some(text) = o.attribute(attr) else {
            return Ok([0.0; 3]);
        };
        let v: Vec<f64> = text
            .split_whitespace()
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| DynError::Urdf {
                path: "<urdf>".into(),
                reason: format!("origin {attr}=\"{text}\" is not three numbers"),
            })?;
        v.try_into().map_err(|_| DynError::Urdf {
            path: "<urdf>".into(),
            reason: format!("origin {attr}=\"{text}\" is not three numbers"),
        })
    };
    let (x, r) = (triple("xyz")?, triple("rpy")?);
    Ok(Iso::from_parts(
        Translation3::new(x[0], x[1], x[2]),
        UnitQuaternion::from_euler_angles(r[0], r[1], r[2]),
    ))
}

fn child_text<'a>(node: roxmltree::Node<'a, 'a>, path: &[&str]) -> Option<&'a str> {
    let mut n = node;
    for tag in path {
        n = n.children().find(|c| c.has_tag_name(*tag))?;
    }
    n.text().map(str::trim)
}

/// The `<sensor>` elements directly under `<robot>` (iDynTree's extension;
/// the copies inside `<gazebo>` are the simulator's).
fn read_sensors(text: &str, model: &Model) -> Result<Sensors> {
    let err = |reason: String| DynError::Urdf {
        path: "<urdf>".into(),
        reason,
    };
    let doc = roxmltree::Document::parse(text).map_err(|e| err(e.to_string()))?;
    let mut sensors = Sensors::default();
    for node in doc
        .root_element()
        .children()
        .filter(|c| c.has_tag_name("sensor"))
    {
        let name = node.attribute("name").unwrap_or_default().to_owned();
        let parent = node.children().find(|c| c.has_tag_name("parent"));
        let origin = origin_of(node)?;
        match node.attribute("type") {
            Some("force_torque") => {
                let joint_name = parent
                    .and_then(|p| p.attribute("joint"))
                    .ok_or_else(|| err(format!("sensor '{name}' has no <parent joint=…>")))?;
                let joint = model.joint(joint_name).ok_or_else(|| {
                    err(format!(
                        "sensor '{name}' names joint '{joint_name}', which is not in the model"
                    ))
                })?;
                let j = &model.joints[joint];
                let (link, link_h_sensor) =
                    match child_text(node, &["force_torque", "frame"]).unwrap_or("child") {
                        "child" => (j.child, Iso::identity()),
                        "parent" => (j.parent, Iso::identity()),
                        "sensor" => (j.child, origin),
                        other => {
                            return Err(err(format!(
                                "sensor '{name}': frame '{other}' is not child, parent or sensor"
                            )))
                        }
                    };
                let applied_on = match child_text(node, &["force_torque", "measure_direction"]).unwrap_or("child_to_parent") {
                    "child_to_parent" => j.parent,
                    "parent_to_child" => j.child,
                    other => return Err(err(format!("sensor '{name}': measure_direction '{other}' is not child_to_parent or parent_to_child"))),
                };
                sensors.ft.push(FtSensor {
                    name,
                    joint,
                    applied_on,
                    link,
                    link_h_sensor,
                });
            }
            Some(kind @ ("accelerometer" | "gyroscope")) => {
                let link_name = parent
                    .and_then(|p| p.attribute("link"))
                    .ok_or_else(|| err(format!("sensor '{name}' has no <parent link=…>")))?;
                let frame = model.frame(link_name).map_err(|_| {
                    err(format!(
                        "sensor '{name}' names link '{link_name}', which is not in the model"
                    ))
                })?;
                let kind = if kind == "accelerometer" {
                    ImuKind::Accelerometer
                } else {
                    ImuKind::Gyroscope
                };
                sensors.imu.push(ImuSensor {
                    name,
                    kind,
                    link: frame.link,
                    link_h_sensor: frame.link_h_frame * origin,
                });
            }
            _ => {}
        }
    }
    Ok(sensors)
}
