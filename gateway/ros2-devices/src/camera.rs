//! Cameras: `frameGrabber_nws_ros2` (an `IFrameGrabberImage` as `sensor_msgs/Image` +
//! `CameraInfo`), `rgbdSensor_nws_ros2` (an `IRGBDSensor`'s colour and depth images, each
//! with its `CameraInfo`) and `rgbdToPointCloudSensor_nws_ros2` (an `IRGBDSensor` as a
//! coloured `sensor_msgs/PointCloud2`).
//!
//! Parameters as yarp-devices-ros2's: all take `node_name`, `namespace` and `period`
//! (0.02 s; the point cloud 0.03 s). `frameGrabber_nws_ros2`: `topic_name`, `frame_id`;
//! `rgbdSensor_nws_ros2`: `color_topic_name`, `depth_topic_name`, `color_frame_id`,
//! `depth_frame_id`, `force_info_synch`, `pub_status_topic` (`/<node_name>/publisher_status`,
//! `std_msgs/UInt8`: 1 colour, 2 depth, 3 both published); `rgbdToPointCloudSensor_nws_ros2`:
//! `topic_name`, `frame_id`. Each `camera_info` topic sits beside its image topic
//! (`/a/b/image` -> `/a/b/camera_info`). Unlike C++, whose `CameraInfo` keeps a zero
//! stamp unless `force_info_synch` is 1 (and whose frame grabber images have none),
//! every message here carries the stamp of its image.

use crate::msgs::{camera_info, point_cloud, stamp_ns};
use crate::node::{DeviceNode, NodeBuilder};
use crate::periodic::{Periodic, Throttle};
use ros2_client::Publisher;
use std::sync::Arc;
use std::time::Duration;
use yarp_devices::rgbd::RgbdStatus;
use yarp_devices::{DevResult, DeviceDriver, DeviceError, IWrapper, SharedDevice};
use yarp_proto::{Property, Stamp};
use yarp_ros2_gateway::dynmsg::Value as Ros;
use yarp_ros2_gateway::image::from_image;

pub const FRAME_GRABBER: &str = "frameGrabber_nws_ros2";
pub const RGBD: &str = "rgbdSensor_nws_ros2";
pub const POINT_CLOUD: &str = "rgbdToPointCloudSensor_nws_ros2";
const IMAGE: &str = "sensor_msgs/msg/Image";
const CAMERA_INFO: &str = "sensor_msgs/msg/CameraInfo";

yarp_devices::device_params! {
    /// What `frameGrabber_nws_ros2` reads (C++ `FrameGrabber_nws_ros2_params.md`).
    pub struct FrameGrabberNwsRos2Params for "frameGrabber_nws_ros2" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::node::period,
        /// set the name for ROS node
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// set the name for ROS topic
        topic_name: String = required; check crate::node::topic_name,
        /// set the name for the reference frame
        frame_id: String = required,
    }
}

yarp_devices::device_params! {
    /// What `rgbdSensor_nws_ros2` reads (C++ `RgbdSensor_nws_ros2_params.md`).
    pub struct RgbdSensorNwsRos2Params for "rgbdSensor_nws_ros2" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::node::period,
        /// name of the ros2 node
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// ros rgb topic (it's also the base name for the rgb camera_info topic)
        color_topic_name: String = required; check crate::node::topic_name,
        /// ros depth topic (it's also the base name for the depth camera_info topic)
        depth_topic_name: String = required; check crate::node::topic_name,
        /// if 1, it forces synching images time stamp with and cameras time stamp
        /// (accepted; here every message carries its image's stamp anyway)
        force_info_synch: i64 = 0,
        /// The depth image frame
        depth_frame_id: String = required,
        /// The color image frame
        color_frame_id: String = required,
        /// If 1 a topic publishing 0 if no image has been published on ros2 topic, 1 if
        /// only the RGB image is bein published, 2 for only the depth image, and 3 for
        /// both images will be opened
        pub_status_topic: i64 = 0,
    }
}

yarp_devices::device_params! {
    /// What `rgbdToPointCloudSensor_nws_ros2` reads (C++
    /// `RgbdToPointCloudSensor_nws_ros2_params.md`).
    pub struct RgbdToPointCloudSensorNwsRos2Params for "rgbdToPointCloudSensor_nws_ros2" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.03; "s"; check crate::node::period,
        /// set the name for ROS point cloud topic
        topic_name: String = required; check crate::node::topic_name,
        /// set the name of the reference frame
        frame_id: String = required,
        /// set the name for ROS node (without a leading '/')
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
    }
}

/// `/a/b/image` -> `/a/b/camera_info` (C++ `substr(0, rfind('/')) + "/camera_info"`).
pub use yarp_ros2_gateway::camera_info::topic_beside as info_topic;

fn time_of(stamp: Option<Stamp>) -> f64 {
    match stamp {
        Some(s) if s.time > 0.0 => s.time,
        _ => crate::now_s(),
    }
}

/// A node with publishers, made at open.
struct Node {
    node: DeviceNode,
    publishers: Vec<Arc<Publisher<Ros>>>,
}

impl Node {
    fn new(
        device: &'static str,
        namespace: &str,
        name: &str,
        topics: &[(&str, &str)],
    ) -> DevResult<Node> {
        let mut b = NodeBuilder::new(device, namespace, name)?;
        let publishers = topics
            .iter()
            .map(|(t, ty)| b.publisher(t, ty).map(Arc::new))
            .collect::<DevResult<Vec<_>>>()?;
        Ok(Node {
            node: b.spin()?,
            publishers,
        })
    }

    fn wanted(&self) -> Vec<bool> {
        self.publishers
            .iter()
            .map(|p| p.get_subscription_count(&self.node.node) > 0)
            .collect()
    }
}

/// A `*_nws_ros2` camera wrapper: node and topics at open, a publishing thread while
/// attached.
struct Camera {
    node: Arc<Node>,
    period: Duration,
    frame_ids: Vec<String>,
    node_name: String,
}

/// The kind of camera wrapper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    FrameGrabber,
    Rgbd,
    PointCloud,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::FrameGrabber => FRAME_GRABBER,
            Kind::Rgbd => RGBD,
            Kind::PointCloud => POINT_CLOUD,
        }
    }
}

/// One of the three camera wrappers.
pub struct CameraNwsRos2 {
    kind: Kind,
    camera: Option<Camera>,
    streamer: Option<Periodic>,
}

impl CameraNwsRos2 {
    pub fn new(kind: Kind) -> Self {
        CameraNwsRos2 {
            kind,
            camera: None,
            streamer: None,
        }
    }
}

impl DeviceDriver for CameraNwsRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        let params = match self.kind {
            Kind::FrameGrabber => FrameGrabberNwsRos2Params::PARAMS,
            Kind::Rgbd => RgbdSensorNwsRos2Params::PARAMS,
            Kind::PointCloud => RgbdToPointCloudSensorNwsRos2Params::PARAMS,
        };
        params.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let name = self.kind.name();
        let (node_name, namespace, topics, frame_ids, period) = match self.kind {
            Kind::FrameGrabber => {
                let p = FrameGrabberNwsRos2Params::read(config)?;
                let info = info_topic(&p.topic_name);
                (
                    p.node_name,
                    p.namespace,
                    vec![(p.topic_name, IMAGE), (info, CAMERA_INFO)],
                    vec![p.frame_id],
                    p.period,
                )
            }
            Kind::Rgbd => {
                let p = RgbdSensorNwsRos2Params::read(config)?;
                let (color, depth) = (p.color_topic_name, p.depth_topic_name);
                let (ci, di) = (info_topic(&color), info_topic(&depth));
                let mut topics = vec![
                    (color, IMAGE),
                    (ci, CAMERA_INFO),
                    (depth, IMAGE),
                    (di, CAMERA_INFO),
                ];
                if p.pub_status_topic == 1 {
                    topics.push((
                        format!("/{}/publisher_status", p.node_name),
                        "std_msgs/msg/UInt8",
                    ));
                }
                let frames = vec![p.color_frame_id, p.depth_frame_id];
                (p.node_name, p.namespace, topics, frames, p.period)
            }
            Kind::PointCloud => {
                let p = RgbdToPointCloudSensorNwsRos2Params::read(config)?;
                (
                    p.node_name,
                    p.namespace,
                    vec![(p.topic_name, "sensor_msgs/msg/PointCloud2")],
                    vec![p.frame_id],
                    p.period,
                )
            }
        };
        let namespace = namespace.unwrap_or_default();
        let period = Duration::from_secs_f64(period);
        let topics: Vec<(&str, &str)> = topics.iter().map(|(t, ty)| (t.as_str(), *ty)).collect();
        let node = Arc::new(Node::new(name, &namespace, &node_name, &topics)?);
        self.camera = Some(Camera {
            node,
            period,
            frame_ids,
            node_name,
        });
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.streamer = None;
        self.camera = None;
        Ok(())
    }

    yarp_devices::views!(as_wrapper);
}

impl IWrapper for CameraNwsRos2 {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let kind = self.kind;
        let name = kind.name();
        let c = self.camera.as_ref().ok_or(DeviceError::NotOpen)?;
        {
            let mut pd = device.lock();
            let ok = match kind {
                Kind::FrameGrabber => pd.device().as_frame_grabber_image().is_some(),
                Kind::Rgbd | Kind::PointCloud => pd.device().as_rgbd_sensor().is_some(),
            };
            if !ok {
                return Err(DeviceError::Unsupported(match kind {
                    Kind::FrameGrabber => {
                        "frameGrabber_nws_ros2 needs an IFrameGrabberImage device"
                    }
                    _ => "this wrapper needs an IRGBDSensor device",
                }));
            }
        }
        let node = c.node.clone();
        let frames = c.frame_ids.clone();
        let mut errors = Throttle::default();
        let mut last = (0.0, 0.0);
        self.streamer = Some(Periodic::start(
            &format!("{name} {}", c.node_name),
            c.period,
            device,
            move |dev| {
                let wanted = node.wanted();
                let r = match kind {
                    Kind::FrameGrabber => frame_grabber_step(dev, &node, &wanted, &frames[0]),
                    Kind::Rgbd => rgbd_step(dev, &node, &wanted, &frames, &mut last),
                    Kind::PointCloud => {
                        point_cloud_step(dev, &node, &wanted, &frames[0], &mut last)
                    }
                };
                if let Err(e) = r {
                    errors.warn(name, e);
                }
            },
        )?);
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        self.streamer = None;
        Ok(())
    }
}

fn publish(node: &Node, i: usize, m: Ros) {
    let _ = node.publishers[i].publish(m);
}

fn frame_grabber_step(
    dev: &mut dyn DeviceDriver,
    node: &Node,
    wanted: &[bool],
    frame: &str,
) -> DevResult<()> {
    if !wanted.iter().any(|&w| w) {
        return Ok(());
    }
    let fg = dev
        .as_frame_grabber_image()
        .ok_or(DeviceError::Unsupported("lost IFrameGrabberImage"))?;
    let img = fg.get_image()?;
    let t = stamp_ns(time_of(fg.last_input_stamp()));
    if wanted[0] {
        let m = from_image(&img, frame, t).map_err(|e| DeviceError::failed(FRAME_GRABBER, e))?;
        publish(node, 0, m);
    }
    if wanted[1] {
        if let Some(vp) = fg.rgb_visual_params() {
            let k = vp.rgb_intrinsic_param()?;
            let (w, h) = (img.width() as u32, img.height() as u32);
            if let Some(m) = camera_info(&k, w, h, frame, t) {
                publish(node, 1, m);
            }
        }
    }
    Ok(())
}

fn rgbd_step(
    dev: &mut dyn DeviceDriver,
    node: &Node,
    wanted: &[bool],
    frames: &[String],
    last: &mut (f64, f64),
) -> DevResult<()> {
    let s = dev
        .as_rgbd_sensor()
        .ok_or(DeviceError::Unsupported("lost IRGBDSensor"))?;
    match s.sensor_status() {
        RgbdStatus::OkInUse => {}
        RgbdStatus::NotReady => return Ok(()),
        other => {
            return Err(DeviceError::failed(
                RGBD,
                format!("sensor status {other:?}"),
            ))
        }
    }
    if !wanted.iter().any(|&w| w) {
        return Ok(());
    }
    let ((color, cs), (depth, ds)) = s.get_images()?;
    // Only images newer than the last published ones (C++ compares the stamps).
    let color_new = cs.time > last.0;
    let depth_new = ds.time > last.1;
    if color_new {
        last.0 = cs.time;
        let t = stamp_ns(cs.time);
        if wanted[0] {
            publish(
                node,
                0,
                from_image(&color, &frames[0], t).map_err(|e| DeviceError::failed(RGBD, e))?,
            );
        }
        if wanted[1] {
            let k = s.rgb_intrinsic_param()?;
            let (w, h) = (s.rgb_width() as u32, s.rgb_height() as u32);
            if let Some(m) = camera_info(&k, w, h, &frames[0], t) {
                publish(node, 1, m);
            }
        }
    }
    if depth_new {
        last.1 = ds.time;
        let t = stamp_ns(ds.time);
        if wanted[2] {
            publish(
                node,
                2,
                from_image(&depth, &frames[1], t).map_err(|e| DeviceError::failed(RGBD, e))?,
            );
        }
        if wanted[3] {
            let k = s.depth_intrinsic_param()?;
            let (w, h) = (s.depth_width() as u32, s.depth_height() as u32);
            if let Some(m) = camera_info(&k, w, h, &frames[1], t) {
                publish(node, 3, m);
            }
        }
    }
    if wanted.get(4) == Some(&true) {
        publish(
            node,
            4,
            Ros::Struct(vec![Ros::U8(color_new as u8 + 2 * depth_new as u8)]),
        );
    }
    Ok(())
}

fn point_cloud_step(
    dev: &mut dyn DeviceDriver,
    node: &Node,
    wanted: &[bool],
    frame: &str,
    last: &mut (f64, f64),
) -> DevResult<()> {
    let s = dev
        .as_rgbd_sensor()
        .ok_or(DeviceError::Unsupported("lost IRGBDSensor"))?;
    if !wanted[0] {
        return Ok(());
    }
    let ((color, cs), (depth, ds)) = s.get_images()?;
    if cs.time <= last.0 || ds.time <= last.1 {
        return Ok(());
    }
    *last = (cs.time, ds.time);
    let k = s.rgb_intrinsic_param()?;
    let get = |n: &str| k.find(n).and_then(|v| v.as_f64());
    let (Some(fx), Some(fy), Some(cx), Some(cy)) = (
        get("focalLengthX"),
        get("focalLengthY"),
        get("principalPointX"),
        get("principalPointY"),
    ) else {
        return Err(DeviceError::failed(
            POINT_CLOUD,
            "the camera has no intrinsic parameters",
        ));
    };
    match point_cloud(&depth, &color, (fx, fy, cx, cy), frame, stamp_ns(ds.time)) {
        Some(m) => publish(node, 0, m),
        None => {
            return Err(DeviceError::failed(
                POINT_CLOUD,
                "colour (RGB) and depth (float) images of different sizes",
            ))
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_info_topics() {
        assert_eq!(
            info_topic("/camera_rgbd/color/image_rect_color"),
            "/camera_rgbd/color/camera_info"
        );
        assert_eq!(info_topic("/img"), "/camera_info");
        assert_eq!(info_topic("/a/b/image_raw"), "/a/b/camera_info");
    }

    #[test]
    fn parameters_are_checked_as_before() {
        let read = |t: &str| RgbdToPointCloudSensorNwsRos2Params::read(&Property::from_text(t));
        let p = read("(node_name pc) (topic_name /pc) (frame_id f)").unwrap();
        assert_eq!(p.period, 0.03);
        let e = read("(node_name /pc) (topic_name /pc) (frame_id f)").unwrap_err();
        assert!(e.to_string().contains("`node_name`"), "{e}");
        let e = read("(node_name pc) (topic_name /pc)").unwrap_err();
        assert!(e.to_string().contains("`frame_id`"), "{e}");

        let read = |t: &str| RgbdSensorNwsRos2Params::read(&Property::from_text(t));
        let all = "(node_name r) (color_topic_name /c) (depth_topic_name /d) \
                   (color_frame_id cf) (depth_frame_id df)";
        let p = read(all).unwrap();
        assert_eq!(
            (p.period, p.pub_status_topic, p.force_info_synch),
            (0.02, 0, 0)
        );
        let e = read(&all.replace("/d)", "d)")).unwrap_err();
        assert!(e.to_string().contains("`depth_topic_name`"), "{e}");
        let e = read(&format!("{all} (force_info_synch yes)")).unwrap_err();
        assert!(e.to_string().contains("`force_info_synch`"), "{e}");

        let read = |t: &str| FrameGrabberNwsRos2Params::read(&Property::from_text(t));
        let e = read("(node_name g) (topic_name /g) (frame_id f) (period -1)").unwrap_err();
        assert!(e.to_string().contains("greater than 0"), "{e}");
    }
}
