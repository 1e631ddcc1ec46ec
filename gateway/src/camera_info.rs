//! `sensor_msgs/CameraInfo` beside a camera's Image, from the camera's calibration in an
//! iCub-style `.ini` group (`icubEyes.ini`'s `[CAMERA_CALIBRATION_LEFT]`, as written by
//! icub-main's `stereoCalib` and read by `camCalib`):
//!
//! | key | meaning |
//! |---|---|
//! | `projection` | `pinhole` (default) or `fisheye` |
//! | `w`, `h` | the image size the calibration was made for |
//! | `fx`, `fy`, `cx`, `cy` | focal lengths and principal point, pixels (required) |
//! | `k1`, `k2`, `p1`, `p2` (`k3`) | pinhole: radial and tangential distortion (OpenCV order) |
//! | `k1` ... `k4` | fisheye: the equidistant model's coefficients |
//!
//! Pure: parsing and building the message; the gateway publishes it.

use crate::dynmsg::Value as Ros;
use crate::mapping::{check_ros_name, Conversion, Invalid, TopicEntry};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use yarp_proto::{Bottle, Property};

/// A mapping entry's `camera_info` key: where the intrinsics come from.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraInfoSource {
    /// The `.ini` file, relative to the mapping file (made absolute on loading).
    pub ini: PathBuf,
    /// Its group, e.g. `CAMERA_CALIBRATION_LEFT`.
    pub group: String,
    /// Default: `camera_info` beside the image topic.
    pub ros_topic: Option<String>,
    /// Read on loading.
    #[serde(skip)]
    pub intrinsics: Option<Intrinsics>,
}

impl CameraInfoSource {
    /// Reads the intrinsics (the `.ini` path relative to the mapping `file`).
    pub fn load(&mut self, file: &Path) -> Result<(), String> {
        self.ini = file.parent().unwrap_or(Path::new("")).join(&self.ini);
        let p = Property::from_config_file(&self.ini)
            .map_err(|e| format!("cannot read {}: {e}", self.ini.display()))?;
        self.intrinsics = Some(
            Intrinsics::from_group(&p, &self.group)
                .map_err(|e| format!("{}: {e}", self.ini.display()))?,
        );
        Ok(())
    }
}

/// Checks an entry's `camera_info` and reads its intrinsics (the `.ini` relative to the
/// mapping `file`).
pub(crate) fn validate(t: &mut TopicEntry, file: &Path) -> Result<(), Invalid> {
    let image = t.conversion() == Conversion::Image && t.yarp_port.is_some();
    let Some(ci) = &mut t.camera_info else {
        return Ok(());
    };
    if !image {
        return Err((
            "camera_info",
            "only for image entries (a frame grabber's images as sensor_msgs/msg/Image)".into(),
        ));
    }
    if let Some(topic) = &ci.ros_topic {
        check_ros_name("camera_info.ros_topic", topic)?;
    }
    ci.load(file).map_err(|e| ("camera_info.ini", e))
}

/// The CameraInfo topic of an image topic: `camera_info` in the image topic's namespace
/// (`/icub/cam/left/image_raw` -> `/icub/cam/left/camera_info`), as image_transport's
/// camera publishers name it.
pub fn topic_beside(image_topic: &str) -> String {
    match image_topic.rfind('/') {
        Some(i) => format!("{}/camera_info", &image_topic[..i]),
        None => "camera_info".into(),
    }
}

/// The distortion models of REP-104 / `sensor_msgs/distortion_models.hpp`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Model {
    /// `plumb_bob`: D = (k1, k2, t1, t2, k3).
    PlumbBob,
    /// `equidistant`: D = (k1, k2, k3, k4).
    Equidistant,
}

impl Model {
    pub fn ros_name(self) -> &'static str {
        match self {
            Model::PlumbBob => "plumb_bob",
            Model::Equidistant => "equidistant",
        }
    }
}

/// A camera's intrinsic calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct Intrinsics {
    /// The image size it was made for; `None`: whatever size the images have.
    pub size: Option<(u32, u32)>,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub model: Model,
    pub d: Vec<f64>,
}

impl Intrinsics {
    /// The calibration in `group` of a configuration (an `.ini` file read as a Property).
    pub fn from_group(p: &Property, group: &str) -> Result<Intrinsics, String> {
        let g = p.find_group(group).ok_or_else(|| {
            let groups: Vec<String> = p
                .iter()
                .filter(|(_, g)| g.iter().skip(1).any(|v| v.is_list()))
                .map(|(k, _)| String::from_utf8_lossy(k).into_owned())
                .collect();
            format!("no group [{group}] (groups: {})", groups.join(", "))
        })?;
        Intrinsics::from_bottle(g)
    }

    /// The calibration from a group's `(key value)` lists.
    fn from_bottle(g: &Bottle) -> Result<Intrinsics, String> {
        let num = |k: &str| -> Result<Option<f64>, String> {
            match g.find(k) {
                None => Ok(None),
                Some(v) if v.is_int() || v.is_float() => Ok(v.as_f64()),
                Some(v) => Err(format!(
                    "`{k}` is not a number: {}",
                    String::from_utf8_lossy(&v.to_text_bare())
                )),
            }
        };
        let need = |k: &str| num(k)?.ok_or_else(|| format!("`{k}` is missing"));
        let or0 = |k: &str| num(k).map(|v| v.unwrap_or(0.0));
        let model = match g.find("projection") {
            None => Model::PlumbBob,
            Some(v) => match v.as_str() {
                Some("pinhole") => Model::PlumbBob,
                Some("fisheye") => Model::Equidistant,
                _ => {
                    return Err(format!(
                        "projection `{}`: expected pinhole or fisheye",
                        String::from_utf8_lossy(&v.to_text_bare())
                    ))
                }
            },
        };
        let d = match model {
            Model::PlumbBob => vec![or0("k1")?, or0("k2")?, or0("p1")?, or0("p2")?, or0("k3")?],
            Model::Equidistant => vec![or0("k1")?, or0("k2")?, or0("k3")?, or0("k4")?],
        };
        let size = match (num("w")?, num("h")?) {
            (None, None) => None,
            (Some(w), Some(h)) if w >= 1.0 && h >= 1.0 && w.fract() == 0.0 && h.fract() == 0.0 => {
                Some((w as u32, h as u32))
            }
            (w, h) => {
                return Err(format!(
                    "`w` and `h` must be given together, as sizes ({w:?} {h:?})"
                ))
            }
        };
        let i = Intrinsics {
            size,
            fx: need("fx")?,
            fy: need("fy")?,
            cx: need("cx")?,
            cy: need("cy")?,
            model,
            d,
        };
        if !(i.fx > 0.0 && i.fy > 0.0) || [i.cx, i.cy].iter().chain(&i.d).any(|v| !v.is_finite()) {
            return Err("fx and fy must be positive, every value finite".into());
        }
        Ok(i)
    }

    /// The CameraInfo of a `width` x `height` image stamped with `header`. For an image of
    /// another size than the calibration's, focal lengths and principal point scale with
    /// it (as `camCalib` does); distortion coefficients do not depend on the size.
    pub fn message(&self, header: Ros, width: u32, height: u32) -> Ros {
        let (sx, sy) = match self.size {
            Some((w, h)) => (width as f64 / w as f64, height as f64 / h as f64),
            None => (1.0, 1.0),
        };
        let (fx, fy, cx, cy) = (self.fx * sx, self.fy * sy, self.cx * sx, self.cy * sy);
        let f = |v: &[f64]| Ros::Array(v.iter().map(|x| Ros::F64(*x)).collect());
        Ros::Struct(vec![
            header,
            Ros::U32(height),
            Ros::U32(width),
            Ros::Str(self.model.ros_name().into()),
            Ros::List(self.d.iter().map(|x| Ros::F64(*x)).collect()),
            f(&[fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]),
            // A monocular camera: no rectification rotation, P = [K | 0].
            f(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]),
            f(&[fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]),
            Ros::U32(0),
            Ros::U32(0),
            // The whole image (all zeros: "full resolution", REP-104).
            Ros::Struct(vec![
                Ros::U32(0),
                Ros::U32(0),
                Ros::U32(0),
                Ros::U32(0),
                Ros::Bool(false),
            ]),
        ])
    }
}

/// The header, width and height of a `sensor_msgs/Image` value.
pub fn image_geometry(image: &Ros) -> Option<(Ros, u32, u32)> {
    match image.fields()? {
        [header, Ros::U32(height), Ros::U32(width), ..] => Some((header.clone(), *width, *height)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::counters::header;

    const INI: &str = "\
[CAMERA_CALIBRATION_RIGHT]
projection         pinhole
drawCenterCross    0
w 320
h 240
fx 225.904
fy 227.041
cx 157.858
cy 113.51
k1 -0.377318
k2 0.155149
p1 -0.000726514
p2 0.000317

[CAMERA_CALIBRATION_LEFT]
fx 219.057
fy 219.028
cx 174.742
cy 102.874

[FISH]
projection fisheye
w 640
h 480
fx 300
fy 301
cx 320
cy 240
k1 0.1
k2 0.2
k3 0.3
k4 0.4
";

    fn group(g: &str) -> Result<Intrinsics, String> {
        Intrinsics::from_group(&Property::from_config_text(INI).unwrap(), g)
    }

    #[test]
    fn pinhole_groups() {
        let r = group("CAMERA_CALIBRATION_RIGHT").unwrap();
        assert_eq!(r.size, Some((320, 240)));
        assert_eq!(
            (r.fx, r.fy, r.cx, r.cy),
            (225.904, 227.041, 157.858, 113.51)
        );
        assert_eq!(r.model, Model::PlumbBob);
        assert_eq!(r.d, [-0.377318, 0.155149, -0.000726514, 0.000317, 0.0]);
        // Intrinsics only (iKinGazeCtrl's example): no distortion, any image size.
        let l = group("CAMERA_CALIBRATION_LEFT").unwrap();
        assert_eq!(l.size, None);
        assert_eq!(l.d, [0.0; 5]);
    }

    #[test]
    fn fisheye_group() {
        let f = group("FISH").unwrap();
        assert_eq!(f.model, Model::Equidistant);
        assert_eq!(f.d, [0.1, 0.2, 0.3, 0.4]);
    }

    #[test]
    fn bad_groups() {
        assert!(group("NOPE")
            .unwrap_err()
            .contains("CAMERA_CALIBRATION_LEFT"));
        let bad = |text: &str| {
            Intrinsics::from_group(&Property::from_config_text(text).unwrap(), "C").unwrap_err()
        };
        assert!(bad("[C]\nfx 1\nfy 1\ncx 1\n").contains("`cy` is missing"));
        assert!(bad("[C]\nfx one\nfy 1\ncx 1\ncy 1\n").contains("`fx`"));
        assert!(bad("[C]\nprojection spherical\nfx 1\nfy 1\ncx 1\ncy 1\n").contains("spherical"));
        assert!(bad("[C]\nw 320\nfx 1\nfy 1\ncx 1\ncy 1\n").contains("together"));
        assert!(bad("[C]\nfx 0\nfy 1\ncx 1\ncy 1\n").contains("positive"));
    }

    #[test]
    fn message_scales_to_the_image_size() {
        let r = group("CAMERA_CALIBRATION_RIGHT").unwrap();
        let m = r.message(header(1_500_000_000, "cam"), 640, 480);
        assert!(m.conforms_to("sensor_msgs/msg/CameraInfo"), "{m:?}");
        let f = m.fields().unwrap();
        assert_eq!(f[0], header(1_500_000_000, "cam"));
        assert_eq!((&f[1], &f[2]), (&Ros::U32(480), &Ros::U32(640)));
        assert_eq!(f[3], Ros::Str("plumb_bob".into()));
        let k: Vec<f64> = match &f[5] {
            Ros::Array(v) => v.iter().filter_map(Ros::as_f64).collect(),
            _ => panic!(),
        };
        assert_eq!(
            k,
            [
                225.904 * 2.0,
                0.0,
                157.858 * 2.0,
                0.0,
                227.041 * 2.0,
                113.51 * 2.0,
                0.0,
                0.0,
                1.0
            ]
        );
        let same = r.message(header(0, ""), 320, 240);
        assert!(matches!(&same.fields().unwrap()[7], Ros::Array(p) if p[0] == Ros::F64(225.904)));
    }

    #[test]
    fn mapping_key() {
        let dir = std::env::temp_dir().join(format!("gw-camera-info-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("calib")).unwrap();
        std::fs::write(dir.join("calib/eyes.ini"), INI).unwrap();
        let image = r#"
[[topic]]
name = "cam"
direction = "yarp_to_ros"
yarp_port = "/gw/cam:i"
ros_topic = "/cam/left/image_raw"
ros_type = "sensor_msgs/msg/Image"
"#;
        let load = |entry: &str, info: &str| {
            let file = dir.join("m.toml");
            std::fs::write(&file, format!("{entry}camera_info = {info}\n")).unwrap();
            crate::mapping::Mappings::load(&[&file])
        };
        let m = load(image, r#"{ ini = "calib/eyes.ini", group = "FISH" }"#).unwrap();
        let ci = m.topics[0].camera_info.as_ref().unwrap();
        assert_eq!(ci.intrinsics.as_ref().unwrap().model, Model::Equidistant);
        assert_eq!(ci.ini, dir.join("calib/eyes.ini"));
        let key =
            |entry: &str, info: &str| load(entry, info).unwrap_err().key().map(str::to_string);
        let ok = r#"{ ini = "calib/eyes.ini", group = "FISH" }"#;
        let int32 = image.replace("sensor_msgs/msg/Image", "std_msgs/msg/Int32");
        assert_eq!(key(&int32, ok).as_deref(), Some("camera_info"));
        let cases = [
            (
                r#"{ ini = "calib/none.ini", group = "FISH" }"#,
                "camera_info.ini",
            ),
            (
                r#"{ ini = "calib/eyes.ini", group = "NOPE" }"#,
                "camera_info.ini",
            ),
            (r#"{ ini = "calib/eyes.ini" }"#, "camera_info.group"),
            (
                r#"{ ini = "calib/eyes.ini", group = "FISH", grup = 1 }"#,
                "camera_info.grup",
            ),
            (
                r#"{ ini = "calib/eyes.ini", group = "FISH", ros_topic = "/a__b" }"#,
                "camera_info.ros_topic",
            ),
        ];
        for (info, want) in cases {
            assert_eq!(key(image, info).as_deref(), Some(want), "{info}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn topics_beside_images() {
        assert_eq!(
            topic_beside("/icub/cam/left/image_raw"),
            "/icub/cam/left/camera_info"
        );
        assert_eq!(topic_beside("/image_raw"), "/camera_info");
        assert_eq!(topic_beside("image"), "camera_info");
        assert_eq!(topic_beside("cam/image"), "cam/camera_info");
    }

    #[test]
    fn image_geometry_reads_the_header_and_size() {
        let img = crate::dynmsg::Value::Struct(vec![
            header(7, "f"),
            Ros::U32(2),
            Ros::U32(3),
            Ros::Str("rgb8".into()),
            Ros::U8(0),
            Ros::U32(9),
            Ros::Bytes(vec![0; 18]),
        ]);
        assert_eq!(image_geometry(&img), Some((header(7, "f"), 3, 2)));
    }
}
