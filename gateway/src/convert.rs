//! Bottle <-> ROS message conversions for topics (pure; no I/O).
//!
//! | conversion | YARP side | ROS side |
//! |---|---|---|
//! | `text` | any Bottle, as its text form | `std_msgs/String` |
//! | `scalar` | one value | `std_msgs/Bool`, `Int32`, `Int64`, `Float32`, `Float64` |
//! | `multi_array` | numbers, or a list of equal-length lists of numbers | `std_msgs/*MultiArray` (1 or 2 dims) |
//! | `twist` | six numbers `lx ly lz ax ay az` | `geometry_msgs/Twist` |
//! | `joint_state` | a control board's `state:o` (positions, degrees) | `sensor_msgs/JointState` (radians) |
//! | `imu` | multiple-analog-sensors stream ([`crate::mas`]) | `sensor_msgs/Imu` |
//! | `wrench` | multiple-analog-sensors stream | `geometry_msgs/WrenchStamped` |
//! | `generic` | the message's fields in order ([`crate::generic`]) | any message type |

use crate::counters::header;
use crate::dynmsg::Value as Ros;
use crate::mapping::Conversion;
use crate::mas::{self, Family};
use yarp_proto::{Bottle, Value as Yv};

/// Why a message could not be converted (counted as a drop; never fatal).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConvertError {
    #[error("expected {want} value(s), got {got}")]
    Count { want: usize, got: usize },
    #[error("value {index} is not {want}: {found}")]
    Type {
        index: usize,
        want: &'static str,
        found: String,
    },
    #[error("{0} does not fit the target type")]
    Range(String),
    #[error("array shape: {0}")]
    Shape(String),
    #[error("the ROS message does not have the layout of {0}")]
    Layout(String),
    #[error("conversion {0:?} is not implemented for this direction yet")]
    Unsupported(Conversion),
}

/// What stamped conversions need besides the Bottle.
#[derive(Debug, Clone, Default)]
pub struct Ctx<'a> {
    /// `header.frame_id`.
    pub frame_id: &'a str,
    /// Which sensor of its family (multiple analog sensors).
    pub sensor_index: usize,
    /// Joint names (joint_state), one per axis.
    pub joint_names: &'a [String],
    /// Which axes are prismatic (joint_state: meters, not degrees); missing = revolute.
    pub joint_prismatic: &'a [bool],
    /// The stamp used when the data carries none: the YARP envelope's time, else now
    /// (nanoseconds since the epoch).
    pub stamp_ns: u64,
}

/// Seconds (a YARP timestamp) as nanoseconds; `None` for unset (<= 0) or absurd values.
fn secs_to_ns(t: f64) -> Option<u64> {
    (t > 0.0 && t < 1.0e10).then(|| (t * 1e9).round() as u64)
}

/// Like [`to_ros`], but takes the Bottle so that image pixels move instead of copying.
pub fn to_ros_owned(
    conv: Conversion,
    ros_type: &str,
    b: Bottle,
    ctx: &Ctx,
) -> Result<Ros, ConvertError> {
    match conv {
        Conversion::Image => crate::image::to_ros(b, ctx.frame_id, ctx.stamp_ns),
        Conversion::Generic => {
            let t = crate::types::lookup(ros_type)
                .ok_or_else(|| ConvertError::Layout(ros_type.to_string()))?;
            let mut m = crate::generic::to_ros_owned(t, b, ctx.stamp_ns)?;
            crate::generic::fill_frame_id(t, &mut m, ctx.frame_id);
            Ok(m)
        }
        _ => to_ros(conv, ros_type, &b, ctx),
    }
}

/// Converts a Bottle received from YARP into a message of `ros_type`.
pub fn to_ros(
    conv: Conversion,
    ros_type: &str,
    b: &Bottle,
    ctx: &Ctx,
) -> Result<Ros, ConvertError> {
    let msg = match conv {
        Conversion::Text => Ros::Struct(vec![Ros::Str(
            String::from_utf8_lossy(&b.to_text()).into_owned(),
        )]),
        Conversion::Scalar => {
            count(b, 1)?;
            Ros::Struct(vec![scalar(ros_type, b.items(), 0)?])
        }
        Conversion::MultiArray => multi_array_to_ros(ros_type, b)?,
        Conversion::Twist => {
            count(b, 6)?;
            let v = |i| number(b.items(), i).map(Ros::F64);
            Ros::Struct(vec![
                Ros::Struct(vec![v(0)?, v(1)?, v(2)?]),
                Ros::Struct(vec![v(3)?, v(4)?, v(5)?]),
            ])
        }
        Conversion::Imu => imu(b, ctx)?,
        Conversion::Generic => {
            let t = crate::types::lookup(ros_type)
                .ok_or_else(|| ConvertError::Layout(ros_type.to_string()))?;
            let mut m = crate::generic::to_ros(t, b, ctx.stamp_ns)?;
            crate::generic::fill_frame_id(t, &mut m, ctx.frame_id);
            m
        }
        Conversion::JointCommand => return Err(ConvertError::Unsupported(conv)),
        Conversion::Image => crate::image::to_ros(b.clone(), ctx.frame_id, ctx.stamp_ns)?,
        Conversion::JointState => joint_state(b, ctx)?,
        Conversion::Wrench => {
            let m = mas::measurement(b, Family::SixAxisForceTorqueSensors, ctx.sensor_index, 6)?
                .ok_or_else(|| ConvertError::Shape("no such force/torque sensor".into()))?;
            let v = &m.values;
            let stamp = secs_to_ns(m.timestamp).unwrap_or(ctx.stamp_ns);
            Ros::Struct(vec![
                header(stamp, ctx.frame_id),
                Ros::Struct(vec![vec3(v[0], v[1], v[2]), vec3(v[3], v[4], v[5])]),
            ])
        }
    };
    debug_assert!(msg.conforms_to(ros_type), "{msg:?} vs {ros_type}");
    Ok(msg)
}

/// Converts a message of `ros_type` received from ROS into the Bottle written to YARP.
pub fn to_yarp(conv: Conversion, ros_type: &str, m: &Ros) -> Result<Bottle, ConvertError> {
    if conv == Conversion::Generic {
        // Checks the layout as it goes.
        let t = crate::types::lookup(ros_type)
            .ok_or_else(|| ConvertError::Layout(ros_type.to_string()))?;
        return crate::generic::to_yarp(t, m);
    }
    if !m.conforms_to(ros_type) {
        return Err(ConvertError::Layout(ros_type.to_string()));
    }
    let f = m.fields().unwrap_or_default();
    Ok(match (conv, f) {
        (Conversion::Text, [Ros::Str(s)]) => Bottle::from_text(s),
        (Conversion::Scalar, [v]) => {
            let mut b = Bottle::new();
            b.push(match *v {
                Ros::Bool(x) => Yv::from(x),
                Ros::I32(x) => Yv::Int32(x),
                Ros::I64(x) => Yv::Int64(x),
                Ros::F32(x) => Yv::Float32(x),
                Ros::F64(x) => Yv::Float64(x),
                _ => return Err(ConvertError::Layout(ros_type.to_string())),
            });
            b
        }
        (Conversion::MultiArray, [layout, data]) => multi_array_to_yarp(layout, data)?,
        (Conversion::Twist, [Ros::Struct(lin), Ros::Struct(ang)]) => {
            let mut b = Bottle::with_capacity(6);
            for v in lin.iter().chain(ang) {
                b.push(Yv::Float64(v.as_f64().unwrap_or_default()));
            }
            b
        }
        (c, _) => return Err(ConvertError::Unsupported(c)),
    })
}

/// A control board's `state:o` (positions) or `stateExt:o` (C++ `jointData`: positions,
/// velocities and torques, each when valid) as `sensor_msgs/JointState`. Revolute
/// joints go from degrees (deg/s) to radians (rad/s); prismatic ones stay in meters.
fn joint_state(b: &Bottle, ctx: &Ctx) -> Result<Ros, ConvertError> {
    let n = ctx.joint_names.len();
    let si = |values: &[f64]| -> Ros {
        Ros::List(
            values
                .iter()
                .enumerate()
                .map(|(j, &d)| {
                    Ros::F64(if ctx.joint_prismatic.get(j).copied().unwrap_or(false) {
                        d
                    } else {
                        d.to_radians()
                    })
                })
                .collect(),
        )
    };
    let flat = b.items().iter().all(|v| v.is_int() || v.is_float());
    let (pos, vel, eff) = if flat {
        count(b, n)?;
        let pos = (0..b.len())
            .map(|i| number(b.items(), i))
            .collect::<Result<Vec<_>, _>>()?;
        (si(&pos), Ros::List(vec![]), Ros::List(vec![]))
    } else {
        let d = yarp_devices::controlboard::JointData::from_bottle(b)
            .map_err(|e| ConvertError::Shape(format!("stateExt: {e}")))?;
        if !d.joint_position.valid {
            return Err(ConvertError::Shape("stateExt: positions not valid".into()));
        }
        count_values(d.joint_position.values.len(), n)?;
        let channel = |c: &yarp_devices::controlboard::Channel<f64>, conv: bool| {
            if !c.valid || c.values.len() != n {
                Ros::List(vec![])
            } else if conv {
                si(&c.values)
            } else {
                Ros::List(c.values.iter().map(|v| Ros::F64(*v)).collect())
            }
        };
        (
            si(&d.joint_position.values),
            channel(&d.joint_velocity, true),
            channel(&d.torque, false),
        )
    };
    Ok(Ros::Struct(vec![
        header(ctx.stamp_ns, ctx.frame_id),
        Ros::List(
            ctx.joint_names
                .iter()
                .map(|n| Ros::Str(n.clone()))
                .collect(),
        ),
        pos,
        vel,
        eff,
    ]))
}

fn count_values(got: usize, want: usize) -> Result<(), ConvertError> {
    if got == want {
        Ok(())
    } else {
        Err(ConvertError::Count { want, got })
    }
}

fn vec3(x: f64, y: f64, z: f64) -> Ros {
    Ros::Struct(vec![Ros::F64(x), Ros::F64(y), Ros::F64(z)])
}

/// Orientation (roll pitch yaw, degrees), gyroscope (deg/s) and accelerometer (m/s^2) of
/// one IMU as `sensor_msgs/Imu` (SI units; a missing part gets covariance[0] = -1, the
/// ROS "not provided" mark).
fn imu(b: &Bottle, ctx: &Ctx) -> Result<Ros, ConvertError> {
    let i = ctx.sensor_index;
    let orient = mas::measurement(b, Family::OrientationSensors, i, 3)?;
    let gyro = mas::measurement(b, Family::ThreeAxisGyroscopes, i, 3)?;
    let acc = mas::measurement(b, Family::ThreeAxisLinearAccelerometers, i, 3)?;
    let stamp = [&orient, &gyro, &acc]
        .iter()
        .find_map(|m| m.as_ref().and_then(|m| secs_to_ns(m.timestamp)));
    if orient.is_none() && gyro.is_none() && acc.is_none() {
        return Err(ConvertError::Shape(
            "no IMU measurement in the stream".into(),
        ));
    }
    let cov = |present: bool| {
        let mut c = vec![Ros::F64(0.0); 9];
        if !present {
            c[0] = Ros::F64(-1.0);
        }
        Ros::Array(c)
    };
    let q = orient
        .as_ref()
        .map_or([0.0; 4], |m| mas::rpy_deg_to_quaternion(&m.values));
    let w = gyro
        .as_ref()
        .map_or([0.0; 3], |m| [0, 1, 2].map(|k| m.values[k].to_radians()));
    let a = acc
        .as_ref()
        .map_or([0.0; 3], |m| [0, 1, 2].map(|k| m.values[k]));
    Ok(Ros::Struct(vec![
        header(stamp.unwrap_or(ctx.stamp_ns), ctx.frame_id),
        Ros::Struct(q.iter().map(|&x| Ros::F64(x)).collect()),
        cov(orient.is_some()),
        vec3(w[0], w[1], w[2]),
        cov(gyro.is_some()),
        vec3(a[0], a[1], a[2]),
        cov(acc.is_some()),
    ]))
}

fn count(b: &Bottle, want: usize) -> Result<(), ConvertError> {
    if b.len() == want {
        Ok(())
    } else {
        Err(ConvertError::Count { want, got: b.len() })
    }
}

fn type_err(items: &[Yv], index: usize, want: &'static str) -> ConvertError {
    ConvertError::Type {
        index,
        want,
        found: items
            .get(index)
            .map(|v| String::from_utf8_lossy(&v.to_text_bare()).into_owned())
            .unwrap_or_else(|| "nothing".into()),
    }
}

fn number(items: &[Yv], i: usize) -> Result<f64, ConvertError> {
    match items.get(i) {
        Some(v) if v.is_int() || v.is_float() => Ok(v.as_f64().unwrap_or_default()),
        _ => Err(type_err(items, i, "a number")),
    }
}

fn integer(items: &[Yv], i: usize) -> Result<i64, ConvertError> {
    match items.get(i) {
        Some(v) if v.is_int() => Ok(v.as_i64().unwrap_or_default()),
        _ => Err(type_err(items, i, "an integer")),
    }
}

/// One element of the target type from `items[i]`.
fn element(elem: Elem, items: &[Yv], i: usize) -> Result<Ros, ConvertError> {
    Ok(match elem {
        Elem::Bool => match items.get(i) {
            Some(v) if v.is_int() || v.is_vocab() => Ros::Bool(v.as_bool().unwrap_or_default()),
            _ => return Err(type_err(items, i, "a bool (number or vocab)")),
        },
        Elem::I32 => {
            let v = integer(items, i)?;
            Ros::I32(i32::try_from(v).map_err(|_| ConvertError::Range(v.to_string()))?)
        }
        Elem::I64 => Ros::I64(integer(items, i)?),
        Elem::F32 => Ros::F32(number(items, i)? as f32),
        Elem::F64 => Ros::F64(number(items, i)?),
    })
}

#[derive(Clone, Copy)]
enum Elem {
    Bool,
    I32,
    I64,
    F32,
    F64,
}

fn elem_of(ros_type: &str) -> Elem {
    match ros_type {
        "std_msgs/msg/Bool" => Elem::Bool,
        "std_msgs/msg/Int32" | "std_msgs/msg/Int32MultiArray" => Elem::I32,
        "std_msgs/msg/Int64" | "std_msgs/msg/Int64MultiArray" => Elem::I64,
        "std_msgs/msg/Float32" | "std_msgs/msg/Float32MultiArray" => Elem::F32,
        _ => Elem::F64,
    }
}

fn scalar(ros_type: &str, items: &[Yv], i: usize) -> Result<Ros, ConvertError> {
    element(elem_of(ros_type), items, i)
}

fn dim(label: &str, size: usize, stride: usize) -> Ros {
    Ros::Struct(vec![
        Ros::Str(label.into()),
        Ros::U32(size as u32),
        Ros::U32(stride as u32),
    ])
}

fn multi_array_to_ros(ros_type: &str, b: &Bottle) -> Result<Ros, ConvertError> {
    let elem = elem_of(ros_type);
    let items = b.items();
    let nested = !items.is_empty() && items.iter().all(Yv::is_list);
    let (dims, data) = if nested {
        let cols = items[0].as_list().map_or(0, Bottle::len);
        let mut data = Vec::with_capacity(items.len() * cols);
        for (r, row) in items.iter().enumerate() {
            let row = row.as_list().map(Bottle::items).unwrap_or_default();
            if row.len() != cols {
                return Err(ConvertError::Shape(format!(
                    "row {r} has {} values, row 0 has {cols}",
                    row.len()
                )));
            }
            for c in 0..cols {
                data.push(element(elem, row, c)?);
            }
        }
        let rows = items.len();
        (
            vec![dim("rows", rows, rows * cols), dim("cols", cols, cols)],
            data,
        )
    } else {
        let data = (0..items.len())
            .map(|i| element(elem, items, i))
            .collect::<Result<Vec<_>, _>>()?;
        (vec![dim("", data.len(), data.len())], data)
    };
    Ok(Ros::Struct(vec![
        Ros::Struct(vec![Ros::List(dims), Ros::U32(0)]),
        Ros::List(data),
    ]))
}

fn multi_array_to_yarp(layout: &Ros, data: &Ros) -> Result<Bottle, ConvertError> {
    let (Some([Ros::List(dims), Ros::U32(offset)]), Ros::List(data)) = (layout.fields(), data)
    else {
        return Err(ConvertError::Layout("a MultiArray".into()));
    };
    let data = data.get(*offset as usize..).unwrap_or_default();
    let to_yarp = |v: &Ros| match *v {
        Ros::I32(x) => Yv::Int32(x),
        Ros::I64(x) => Yv::Int64(x),
        Ros::F32(x) => Yv::Float32(x),
        _ => Yv::Float64(v.as_f64().unwrap_or_default()),
    };
    let size = |d: &Ros| match d.fields() {
        Some([_, Ros::U32(s), _]) => *s as usize,
        _ => 0,
    };
    let mut b = Bottle::with_capacity(data.len());
    match dims.as_slice() {
        [r, c] if size(r) * size(c) == data.len() && size(c) > 0 => {
            for row in data.chunks(size(c)) {
                let mut rb = Bottle::with_capacity(row.len());
                for v in row {
                    rb.push(to_yarp(v));
                }
                b.push(rb);
            }
        }
        _ => {
            for v in data {
                b.push(to_yarp(v));
            }
        }
    }
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use yarp_proto::bottle;

    fn t(s: &str) -> Bottle {
        Bottle::from_text(s)
    }

    #[test]
    fn text_both_ways_keeps_the_yarp_text_form() {
        let b = t("[set] [pos] 0 100.0 \"two words\" (1 2)");
        let m = to_ros(Conversion::Text, "std_msgs/msg/String", &b, &Ctx::default()).unwrap();
        assert_eq!(
            m,
            Ros::Struct(vec![Ros::Str(
                "[set] [pos] 0 100.0 \"two words\" (1 2)".into()
            )])
        );
        assert_eq!(
            to_yarp(Conversion::Text, "std_msgs/msg/String", &m).unwrap(),
            b
        );
    }

    #[test]
    fn scalars_both_ways() {
        let cases = [
            ("std_msgs/msg/Int32", "42", Ros::I32(42)),
            (
                "std_msgs/msg/Int64",
                "-5000000000",
                Ros::I64(-5_000_000_000),
            ),
            ("std_msgs/msg/Float64", "2.5", Ros::F64(2.5)),
            ("std_msgs/msg/Float64", "3", Ros::F64(3.0)),
            ("std_msgs/msg/Float32", "0.5", Ros::F32(0.5)),
            ("std_msgs/msg/Bool", "1", Ros::Bool(true)),
            ("std_msgs/msg/Bool", "0", Ros::Bool(false)),
        ];
        for (ty, text, want) in cases {
            let m = to_ros(Conversion::Scalar, ty, &t(text), &Ctx::default()).unwrap();
            assert_eq!(m, Ros::Struct(vec![want]), "{ty} {text}");
            let back = to_yarp(Conversion::Scalar, ty, &m).unwrap();
            assert_eq!(back.len(), 1);
            let (got, sent) = (back.get(0).unwrap(), t(text).get(0).cloned().unwrap());
            if ty.ends_with("Bool") {
                assert_eq!(got.as_bool(), sent.as_bool(), "{ty} {text}");
            } else {
                assert_eq!(got.as_f64(), sent.as_f64(), "{ty} {text}");
            }
        }
        let b = to_yarp(
            Conversion::Scalar,
            "std_msgs/msg/Bool",
            &Ros::Struct(vec![Ros::Bool(true)]),
        )
        .unwrap();
        assert_eq!(b, bottle![true]);
    }

    #[test]
    fn scalar_errors() {
        assert_eq!(
            to_ros(
                Conversion::Scalar,
                "std_msgs/msg/Int32",
                &t("1 2"),
                &Ctx::default()
            ),
            Err(ConvertError::Count { want: 1, got: 2 })
        );
        assert!(matches!(
            to_ros(
                Conversion::Scalar,
                "std_msgs/msg/Int32",
                &t("\"x\""),
                &Ctx::default()
            ),
            Err(ConvertError::Type { index: 0, .. })
        ));
        assert!(matches!(
            to_ros(
                Conversion::Scalar,
                "std_msgs/msg/Int32",
                &t("1.5"),
                &Ctx::default()
            ),
            Err(ConvertError::Type { .. })
        ));
        assert_eq!(
            to_ros(
                Conversion::Scalar,
                "std_msgs/msg/Int32",
                &bottle![5_000_000_000i64],
                &Ctx::default()
            ),
            Err(ConvertError::Range("5000000000".into()))
        );
        assert!(to_ros(
            Conversion::Scalar,
            "std_msgs/msg/Float64",
            &t(""),
            &Ctx::default()
        )
        .is_err());
    }

    #[test]
    fn flat_multi_array_both_ways() {
        let b = t("1.0 2.5 -3.0");
        let m = to_ros(
            Conversion::MultiArray,
            "std_msgs/msg/Float64MultiArray",
            &b,
            &Ctx::default(),
        )
        .unwrap();
        let f = m.fields().unwrap();
        assert_eq!(
            f[1],
            Ros::List(vec![Ros::F64(1.0), Ros::F64(2.5), Ros::F64(-3.0)])
        );
        assert_eq!(
            f[0],
            Ros::Struct(vec![Ros::List(vec![dim("", 3, 3)]), Ros::U32(0)])
        );
        let back = to_yarp(Conversion::MultiArray, "std_msgs/msg/Float64MultiArray", &m).unwrap();
        assert_eq!(back, bottle![1.0, 2.5, -3.0]);
    }

    #[test]
    fn two_dim_multi_array_both_ways() {
        let b = t("(1 2 3) (4 5 6)");
        let m = to_ros(
            Conversion::MultiArray,
            "std_msgs/msg/Int32MultiArray",
            &b,
            &Ctx::default(),
        )
        .unwrap();
        let f = m.fields().unwrap();
        assert_eq!(
            f[0],
            Ros::Struct(vec![
                Ros::List(vec![dim("rows", 2, 6), dim("cols", 3, 3)]),
                Ros::U32(0)
            ])
        );
        let back = to_yarp(Conversion::MultiArray, "std_msgs/msg/Int32MultiArray", &m).unwrap();
        assert_eq!(back, b);
        assert!(matches!(
            to_ros(
                Conversion::MultiArray,
                "std_msgs/msg/Int32MultiArray",
                &t("(1 2) (3)"),
                &Ctx::default()
            ),
            Err(ConvertError::Shape(_))
        ));
    }

    #[test]
    fn multi_array_from_ros_honours_data_offset() {
        let m = Ros::Struct(vec![
            Ros::Struct(vec![Ros::List(vec![]), Ros::U32(1)]),
            Ros::List(vec![Ros::I64(9), Ros::I64(1), Ros::I64(2)]),
        ]);
        let b = to_yarp(Conversion::MultiArray, "std_msgs/msg/Int64MultiArray", &m).unwrap();
        assert_eq!(b, bottle![1i64, 2i64]);
    }

    #[test]
    fn twist_both_ways() {
        let b = t("0.1 0 0 0 0 -0.5");
        let m = to_ros(
            Conversion::Twist,
            "geometry_msgs/msg/Twist",
            &b,
            &Ctx::default(),
        )
        .unwrap();
        assert_eq!(
            m,
            Ros::Struct(vec![
                Ros::Struct(vec![Ros::F64(0.1), Ros::F64(0.0), Ros::F64(0.0)]),
                Ros::Struct(vec![Ros::F64(0.0), Ros::F64(0.0), Ros::F64(-0.5)]),
            ])
        );
        let back = to_yarp(Conversion::Twist, "geometry_msgs/msg/Twist", &m).unwrap();
        assert_eq!(back, bottle![0.1, 0.0, 0.0, 0.0, 0.0, -0.5]);
        assert_eq!(
            to_ros(
                Conversion::Twist,
                "geometry_msgs/msg/Twist",
                &t("1 2 3"),
                &Ctx::default()
            ),
            Err(ConvertError::Count { want: 6, got: 3 })
        );
    }

    const MAS: &str = "(((0 0 90) 12.5)) (((0.0 0.0 9.81) 12.5)) () (((0 0 90) 12.5)) () \
                       (((1 2 3 0.1 0.2 0.3) 13.0))";

    #[test]
    fn imu_from_multiple_analog_sensors() {
        // gyro (deg/s) is family 0, orientation (roll pitch yaw, deg) family 3
        let ctx = Ctx {
            frame_id: "imu",
            sensor_index: 0,
            joint_names: &[],
            joint_prismatic: &[],
            stamp_ns: 7,
        };
        let m = to_ros(Conversion::Imu, "sensor_msgs/msg/Imu", &t(MAS), &ctx).unwrap();
        let f = m.fields().unwrap();
        assert_eq!(f[0], header(12_500_000_000, "imu"));
        let q: Vec<f64> = f[1]
            .fields()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(
            (q[2] - h).abs() < 1e-12 && (q[3] - h).abs() < 1e-12,
            "{q:?}"
        );
        let w = f[3].fields().unwrap()[2].as_f64().unwrap();
        assert!((w - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(f[5], vec3(0.0, 0.0, 9.81));
        assert_eq!(f[2], Ros::Array(vec![Ros::F64(0.0); 9]));
    }

    #[test]
    fn imu_marks_missing_parts_and_falls_back_to_the_envelope_stamp() {
        let ctx = Ctx {
            frame_id: "",
            sensor_index: 0,
            joint_names: &[],
            joint_prismatic: &[],
            stamp_ns: 42,
        };
        let only_acc = t("() (((0 0 9.81) 0.0))");
        let m = to_ros(Conversion::Imu, "sensor_msgs/msg/Imu", &only_acc, &ctx).unwrap();
        let f = m.fields().unwrap();
        assert_eq!(f[0], header(42, ""));
        assert_eq!(f[2].clone(), {
            let mut c = vec![Ros::F64(0.0); 9];
            c[0] = Ros::F64(-1.0);
            Ros::Array(c)
        });
        assert!(matches!(
            to_ros(Conversion::Imu, "sensor_msgs/msg/Imu", &t("() ()"), &ctx),
            Err(ConvertError::Shape(_))
        ));
    }

    #[test]
    fn wrench_from_multiple_analog_sensors() {
        let ctx = Ctx {
            frame_id: "ft",
            ..Default::default()
        };
        let m = to_ros(
            Conversion::Wrench,
            "geometry_msgs/msg/WrenchStamped",
            &t(MAS),
            &ctx,
        )
        .unwrap();
        assert_eq!(
            m,
            Ros::Struct(vec![
                header(13_000_000_000, "ft"),
                Ros::Struct(vec![vec3(1.0, 2.0, 3.0), vec3(0.1, 0.2, 0.3)])
            ])
        );
        let other = Ctx {
            sensor_index: 1,
            ..ctx
        };
        assert!(to_ros(
            Conversion::Wrench,
            "geometry_msgs/msg/WrenchStamped",
            &t(MAS),
            &other
        )
        .is_err());
    }

    #[test]
    fn joint_state_from_a_control_board_state() {
        let names = ["j0".to_string(), "j1".to_string()];
        let ctx = Ctx {
            frame_id: "",
            joint_names: &names,
            joint_prismatic: &[],
            stamp_ns: 1_000_000_001,
            ..Default::default()
        };
        let m = to_ros(
            Conversion::JointState,
            "sensor_msgs/msg/JointState",
            &t("90.0 -180"),
            &ctx,
        )
        .unwrap();
        let f = m.fields().unwrap();
        assert_eq!(f[0], header(1_000_000_001, ""));
        assert_eq!(
            f[1],
            Ros::List(vec![Ros::Str("j0".into()), Ros::Str("j1".into())])
        );
        assert_eq!(
            f[2],
            Ros::List(vec![
                Ros::F64(std::f64::consts::FRAC_PI_2),
                Ros::F64(-std::f64::consts::PI)
            ])
        );
        assert_eq!(
            to_ros(
                Conversion::JointState,
                "sensor_msgs/msg/JointState",
                &t("1 2 3"),
                &ctx
            ),
            Err(ConvertError::Count { want: 2, got: 3 })
        );
    }

    #[test]
    fn joint_state_from_state_ext_with_a_prismatic_joint() {
        use yarp_devices::controlboard::{Channel, JointData};
        let ch = |v: &[f64], valid| Channel {
            values: v.to_vec(),
            valid,
        };
        let d = JointData {
            joint_position: ch(&[90.0, 0.25], true),
            joint_velocity: ch(&[-180.0, 0.5], true),
            torque: ch(&[1.5, 2.5], true),
            ..JointData::default()
        };
        let names = ["elbow".to_string(), "slide".to_string()];
        let ctx = Ctx {
            joint_names: &names,
            joint_prismatic: &[false, true],
            ..Default::default()
        };
        let m = to_ros(
            Conversion::JointState,
            "sensor_msgs/msg/JointState",
            &d.to_bottle(),
            &ctx,
        )
        .unwrap();
        let f = m.fields().unwrap();
        let pi = std::f64::consts::PI;
        assert_eq!(f[2], Ros::List(vec![Ros::F64(pi / 2.0), Ros::F64(0.25)]));
        assert_eq!(f[3], Ros::List(vec![Ros::F64(-pi), Ros::F64(0.5)]));
        assert_eq!(f[4], Ros::List(vec![Ros::F64(1.5), Ros::F64(2.5)]));
        // invalid channels are left empty; positions must be valid
        let d2 = JointData {
            joint_velocity: ch(&[0.0, 0.0], false),
            ..d.clone()
        };
        let m = to_ros(
            Conversion::JointState,
            "sensor_msgs/msg/JointState",
            &d2.to_bottle(),
            &ctx,
        )
        .unwrap();
        assert_eq!(m.fields().unwrap()[3], Ros::List(vec![]));
        let d3 = JointData {
            joint_position: ch(&[0.0, 0.0], false),
            ..d
        };
        assert!(to_ros(
            Conversion::JointState,
            "sensor_msgs/msg/JointState",
            &d3.to_bottle(),
            &ctx
        )
        .is_err());
        // the flat state:o form honours prismatic joints too
        let m = to_ros(
            Conversion::JointState,
            "sensor_msgs/msg/JointState",
            &t("90 0.25"),
            &ctx,
        )
        .unwrap();
        assert_eq!(
            m.fields().unwrap()[2],
            Ros::List(vec![Ros::F64(pi / 2.0), Ros::F64(0.25)])
        );
    }

    #[test]
    fn a_foreign_layout_is_rejected() {
        assert_eq!(
            to_yarp(
                Conversion::Twist,
                "geometry_msgs/msg/Twist",
                &Ros::Struct(vec![])
            ),
            Err(ConvertError::Layout("geometry_msgs/msg/Twist".into()))
        );
    }
}
