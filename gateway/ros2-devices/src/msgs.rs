//! The ROS messages of the laser, camera and mobile-base wrappers, built from (and read
//! into) YARP interface values as yarp-devices-ros2 fills them (pure functions over the
//! gateway's dynamic messages, field order as in the gateway's catalog).

use yarp_devices::battery::BatteryStatus;
use yarp_devices::navigation::OdometryData;
use yarp_proto::image::{Image, PixelCode};
use yarp_proto::Property;
use yarp_ros2_gateway::camera_info::{Intrinsics, Model};
use yarp_ros2_gateway::counters::header;
use yarp_ros2_gateway::dynmsg::Value as Ros;

/// A YARP time in seconds as ROS nanoseconds (0 and non-finite: 0).
pub fn stamp_ns(t: f64) -> u64 {
    if t > 0.0 && t.is_finite() {
        (t * 1e9) as u64
    } else {
        0
    }
}

/// The seconds of a `std_msgs/Header` value (0 when it is not one).
pub fn header_time(h: &Ros) -> f64 {
    let stamp = h.fields().and_then(|f| f.first()).and_then(Ros::fields);
    match stamp {
        Some([s, ns]) => s.as_f64().unwrap_or(0.0) + ns.as_f64().unwrap_or(0.0) * 1e-9,
        _ => 0.0,
    }
}

/// The frame id of a `std_msgs/Header` value.
pub fn header_frame(h: &Ros) -> String {
    match h.fields().and_then(|f| f.get(1)) {
        Some(Ros::Str(s)) => s.clone(),
        _ => String::new(),
    }
}

fn f64s(v: impl IntoIterator<Item = f64>) -> Vec<Ros> {
    v.into_iter().map(Ros::F64).collect()
}

fn vec3(x: f64, y: f64, z: f64) -> Ros {
    Ros::Struct(f64s([x, y, z]))
}

/// The laser's fixed description, as `rangefinder2D_nws_ros2` reads it at attach:
/// angles in degrees, distances in meters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserInfo {
    pub min_angle: f64,
    pub max_angle: f64,
    pub resolution: f64,
    pub min_distance: f64,
    pub max_distance: f64,
}

/// `sensor_msgs/LaserScan` of one scan (C++ `Rangefinder2D_nws_ros2::run`): angles in
/// radians, NaN ranges become infinity, intensities zero, `scan_time` the wrapper period.
pub fn laser_scan(
    info: &LaserInfo,
    ranges: &[f64],
    stamp_ns: u64,
    frame: &str,
    period: f64,
) -> Ros {
    let ranges: Vec<Ros> = ranges
        .iter()
        .map(|&r| Ros::F32(if r.is_nan() { f32::INFINITY } else { r as f32 }))
        .collect();
    let intensities = vec![Ros::F32(0.0); ranges.len()];
    Ros::Struct(vec![
        header(stamp_ns, frame),
        Ros::F32(info.min_angle.to_radians() as f32),
        Ros::F32(info.max_angle.to_radians() as f32),
        Ros::F32(info.resolution.to_radians() as f32),
        Ros::F32(0.0),
        Ros::F32(period as f32),
        Ros::F32(info.min_distance as f32),
        Ros::F32(info.max_distance as f32),
        Ros::List(ranges),
        Ros::List(intensities),
    ])
}

/// A received `sensor_msgs/LaserScan`: description (degrees), ranges and stamp.
pub fn read_laser_scan(m: &Ros) -> Option<(LaserInfo, Vec<f64>, f64)> {
    let f = m.fields()?;
    let num = |i: usize| f.get(i).and_then(Ros::as_f64);
    let ranges = match f.get(8)? {
        Ros::List(items) => items.iter().filter_map(Ros::as_f64).collect(),
        _ => return None,
    };
    Some((
        LaserInfo {
            min_angle: num(1)?.to_degrees(),
            max_angle: num(2)?.to_degrees(),
            resolution: num(3)?.to_degrees(),
            min_distance: num(6)?,
            max_distance: num(7)?,
        },
        ranges,
        header_time(&f[0]),
    ))
}

/// `sensor_msgs/CameraInfo` from a camera's intrinsic parameters (C++ `setCamInfo`),
/// through the gateway's [`Intrinsics::message`]: `None` when `distortionModel` or one of
/// the parameters is missing, as C++ then sends none. `d` is `k1 k2 t1 t2 k3` (zeros for
/// the model `none`, which C++ sends as `none` with no coefficients).
pub fn camera_info(
    intrinsics: &Property,
    width: u32,
    height: u32,
    frame: &str,
    stamp_ns: u64,
) -> Option<Ros> {
    let get = |k: &str| intrinsics.find(k).and_then(|v| v.as_f64());
    let model = intrinsics.find("distortionModel")?.as_str()?.to_string();
    get("physFocalLength")?;
    let d = if model == "none" {
        vec![0.0; 5]
    } else {
        ["k1", "k2", "t1", "t2", "k3"]
            .iter()
            .map(|k| get(k))
            .collect::<Option<Vec<f64>>>()?
    };
    let k = Intrinsics {
        size: None,
        fx: get("focalLengthX")?,
        fy: get("focalLengthY")?,
        cx: get("principalPointX")?,
        cy: get("principalPointY")?,
        model: Model::PlumbBob,
        d,
    };
    Some(k.message(header(stamp_ns, frame), width, height))
}

/// A received `sensor_msgs/CameraInfo` as YARP intrinsic parameters (C++
/// `saveIntrinsics`: K's focal lengths and principal point, D as k1 k2 t1 t2 k3), its
/// frame, stamp and image size.
pub fn read_camera_info(m: &Ros) -> Option<(Property, String, f64, u32, u32)> {
    let f = m.fields()?;
    let (Ros::U32(h), Ros::U32(w), Ros::Str(model)) = (f.get(1)?, f.get(2)?, f.get(3)?) else {
        return None;
    };
    let k = match f.get(5)? {
        Ros::Array(k) if k.len() == 9 => k.iter().filter_map(Ros::as_f64).collect::<Vec<_>>(),
        _ => return None,
    };
    let d: Vec<f64> = match f.get(4)? {
        Ros::List(d) => d.iter().filter_map(Ros::as_f64).collect(),
        _ => return None,
    };
    let mut p = Property::new();
    p.put("physFocalLength", yarp_proto::Value::Float64(0.0));
    for (name, v) in [
        ("focalLengthX", k[0]),
        ("focalLengthY", k[4]),
        ("principalPointX", k[2]),
        ("principalPointY", k[5]),
    ] {
        p.put(name, yarp_proto::Value::Float64(v));
    }
    p.put("distortionModel", yarp_proto::Value::from(model.as_str()));
    for (i, name) in ["k1", "k2", "t1", "t2", "k3"].iter().enumerate() {
        p.put(
            *name,
            yarp_proto::Value::Float64(d.get(i).copied().unwrap_or(0.0)),
        );
    }
    Some((p, header_frame(&f[0]), header_time(&f[0]), *w, *h))
}

/// Bytes of one point of `rgbdToPointCloudSensor_nws_ros2`'s cloud (C++
/// `yarp::sig::DataXYZRGBA`: x, y, z, padding as f32, then b, g, r, a, then padding).
pub const POINT_STEP: usize = 32;

/// `sensor_msgs/PointCloud2` of a depth image (f32 meters) and its colour image (RGB, same
/// size), as C++ `depthRgbToPC` (unorganized, pinhole de-projection with `fx fy cx cy`,
/// points column by column) fills it: fields x y z (float32 at 0, 4, 8) and rgb (float32
/// at 16), height 1. `None` when the images differ in size or are not RGB + float.
pub fn point_cloud(
    depth: &Image,
    color: &Image,
    (fx, fy, cx, cy): (f64, f64, f64, f64),
    frame: &str,
    stamp_ns: u64,
) -> Option<Ros> {
    let (w, h) = (depth.width(), depth.height());
    if (color.width(), color.height()) != (w, h)
        || depth.pixel_code() != PixelCode::MONO_FLOAT
        || color.pixel_code() != PixelCode::RGB
        || w == 0
        || h == 0
    {
        return None;
    }
    let mut data = vec![0u8; w * h * POINT_STEP];
    let mut at = 0;
    for u in 0..w {
        for v in 0..h {
            let z = f32::from_ne_bytes(depth.pixel(u, v).try_into().ok()?) as f64;
            let x = (u as f64 - cx) / fx * z;
            let y = (v as f64 - cy) / fy * z;
            let p = &mut data[at..at + POINT_STEP];
            p[0..4].copy_from_slice(&(x as f32).to_le_bytes());
            p[4..8].copy_from_slice(&(y as f32).to_le_bytes());
            p[8..12].copy_from_slice(&(z as f32).to_le_bytes());
            let rgb = color.pixel(u, v);
            p[16..19].copy_from_slice(&[rgb[2], rgb[1], rgb[0]]);
            at += POINT_STEP;
        }
    }
    let field = |name: &str, offset: u32| {
        Ros::Struct(vec![
            Ros::Str(name.into()),
            Ros::U32(offset),
            Ros::U8(7),
            Ros::U32(1),
        ])
    };
    let n = (w * h) as u32;
    Some(Ros::Struct(vec![
        header(stamp_ns, frame),
        Ros::U32(1),
        Ros::U32(n),
        Ros::List(vec![
            field("x", 0),
            field("y", 4),
            field("z", 8),
            field("rgb", 16),
        ]),
        Ros::Bool(false),
        Ros::U32(POINT_STEP as u32),
        Ros::U32(POINT_STEP as u32 * n),
        Ros::Bytes(data),
        Ros::Bool(true),
    ]))
}

/// What `battery_nws_ros2` publishes of a battery.
#[derive(Debug, Clone, PartialEq)]
pub struct BatteryReading {
    pub voltage: f64,
    pub current: f64,
    /// Percent, as YARP gives it (C++ puts it in `percentage` unchanged).
    pub charge: f64,
    pub temperature: f64,
    pub status: BatteryStatus,
}

/// `sensor_msgs/BatteryState` (C++ `Battery_nws_ros2::run`): `charge` NaN, the YARP
/// charge in `percentage`, status/health/technology 0 (unknown), present, no frame.
pub fn battery_state(b: &BatteryReading, stamp_ns: u64) -> Ros {
    Ros::Struct(vec![
        header(stamp_ns, ""),
        Ros::F32(b.voltage as f32),
        Ros::F32(b.temperature as f32),
        Ros::F32(b.current as f32),
        Ros::F32(f32::NAN),
        Ros::F32(0.0),
        Ros::F32(0.0),
        Ros::F32(b.charge as f32),
        Ros::U8(0),
        Ros::U8(0),
        Ros::U8(0),
        Ros::Bool(true),
        Ros::List(Vec::new()),
        Ros::List(Vec::new()),
        Ros::Str(String::new()),
        Ros::Str(String::new()),
    ])
}

/// `nav_msgs/Odometry` and the `tf2_msgs/TFMessage` of the same pose (C++
/// `Odometry2D_nws_ros2::run`): yaw in degrees becomes a quaternion about z, the base
/// velocity the twist (theta in rad/s), covariances zero.
pub fn odometry(o: &OdometryData, odom_frame: &str, base_frame: &str, stamp_ns: u64) -> (Ros, Ros) {
    let half = o.odom_theta.to_radians() * 0.5;
    let q = || Ros::Struct(f64s([0.0, 0.0, half.sin(), half.cos()]));
    let odom = Ros::Struct(vec![
        header(stamp_ns, odom_frame),
        Ros::Str(base_frame.into()),
        Ros::Struct(vec![
            Ros::Struct(vec![vec3(o.odom_x, o.odom_y, 0.0), q()]),
            Ros::Array(vec![Ros::F64(0.0); 36]),
        ]),
        Ros::Struct(vec![
            Ros::Struct(vec![
                vec3(o.base_vel_x, o.base_vel_y, 0.0),
                vec3(0.0, 0.0, o.base_vel_theta.to_radians()),
            ]),
            Ros::Array(vec![Ros::F64(0.0); 36]),
        ]),
    ]);
    let tf = Ros::Struct(vec![Ros::List(vec![Ros::Struct(vec![
        header(stamp_ns, odom_frame),
        Ros::Str(base_frame.into()),
        Ros::Struct(vec![vec3(o.odom_x, o.odom_y, 0.0), q()]),
    ])])]);
    (odom, tf)
}

/// `(linear.x, linear.y, angular.z)` of a `geometry_msgs/Twist`.
pub fn read_twist(m: &Ros) -> Option<(f64, f64, f64)> {
    let [lin, ang] = m.fields()? else {
        return None;
    };
    let (l, a) = (lin.fields()?, ang.fields()?);
    Some((
        l.first()?.as_f64()?,
        l.get(1)?.as_f64()?,
        a.get(2)?.as_f64()?,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use yarp_proto::Value;

    #[test]
    fn messages_conform_to_the_catalog() {
        let info = LaserInfo {
            min_angle: 0.0,
            max_angle: 360.0,
            resolution: 1.0,
            min_distance: 0.1,
            max_distance: 8.0,
        };
        let scan = laser_scan(&info, &[1.0, f64::NAN], 1_500_000_000, "laser", 0.1);
        assert!(scan.conforms_to("sensor_msgs/msg/LaserScan"));
        let (back, ranges, t) = read_laser_scan(&scan).unwrap();
        assert!((back.max_angle - 360.0).abs() < 1e-4 && back.max_distance == 8.0);
        assert_eq!((ranges[0], ranges[1].is_infinite(), t), (1.0, true, 1.5));

        let mut k = Property::new();
        for (n, v) in [
            ("physFocalLength", 0.5),
            ("focalLengthX", 512.0),
            ("focalLengthY", 500.0),
            ("principalPointX", 235.0),
            ("principalPointY", 231.0),
        ] {
            k.put(n, Value::Float64(v));
        }
        assert!(camera_info(&k, 320, 240, "cam", 0).is_none(), "no model");
        k.put("distortionModel", Value::from("none"));
        let ci = camera_info(&k, 320, 240, "cam", 0).unwrap();
        assert!(ci.conforms_to("sensor_msgs/msg/CameraInfo"));
        let (back, frame, _, w, h) = read_camera_info(&ci).unwrap();
        assert_eq!((frame.as_str(), w, h), ("cam", 320, 240));
        for key in [
            "focalLengthX",
            "focalLengthY",
            "principalPointX",
            "principalPointY",
        ] {
            assert_eq!(
                back.find(key).and_then(Value::as_f64),
                k.find(key).and_then(Value::as_f64)
            );
        }
        assert_eq!(
            ci.fields().unwrap()[5].clone(),
            Ros::Array(f64s([512.0, 0.0, 235.0, 0.0, 500.0, 231.0, 0.0, 0.0, 1.0]))
        );

        let b = BatteryReading {
            voltage: 30.0,
            current: 3.0,
            charge: 50.0,
            temperature: 20.0,
            status: BatteryStatus::OkInUse,
        };
        assert!(battery_state(&b, 0).conforms_to("sensor_msgs/msg/BatteryState"));
        let o = OdometryData {
            odom_x: 1.0,
            odom_theta: 90.0,
            base_vel_theta: 180.0,
            ..Default::default()
        };
        let (odom, tf) = odometry(&o, "odom", "base_link", 0);
        assert!(odom.conforms_to("nav_msgs/msg/Odometry"));
        assert!(tf.conforms_to("tf2_msgs/msg/TFMessage"));
        let twist = Ros::Struct(vec![vec3(0.5, -0.1, 0.0), vec3(0.0, 0.0, 1.0)]);
        assert_eq!(read_twist(&twist), Some((0.5, -0.1, 1.0)));
    }

    #[test]
    fn point_cloud_of_a_depth_image() {
        let mut color = Image::new(PixelCode::RGB, 2, 2).unwrap();
        color.pixel_mut(1, 0).copy_from_slice(&[10, 20, 30]);
        let mut depth = Image::new(PixelCode::MONO_FLOAT, 2, 2).unwrap();
        depth.pixel_mut(1, 0).copy_from_slice(&2.0f32.to_ne_bytes());
        let pc = point_cloud(&depth, &color, (1.0, 1.0, 0.0, 0.0), "cam", 0).unwrap();
        assert!(pc.conforms_to("sensor_msgs/msg/PointCloud2"));
        let Ros::Bytes(data) = &pc.fields().unwrap()[7] else {
            panic!()
        };
        assert_eq!(data.len(), 4 * POINT_STEP);
        // column-major: (u=1, v=0) is the third point
        let p = &data[2 * POINT_STEP..3 * POINT_STEP];
        assert_eq!(f32::from_le_bytes(p[0..4].try_into().unwrap()), 2.0);
        assert_eq!(f32::from_le_bytes(p[8..12].try_into().unwrap()), 2.0);
        assert_eq!(&p[16..19], &[30, 20, 10]);
        let odd = Image::new(PixelCode::RGB, 3, 2).unwrap();
        assert!(point_cloud(&depth, &odd, (1.0, 1.0, 0.0, 0.0), "", 0).is_none());
    }
}
