//! `rgbdSensor_nwc_ros2` (yarp-devices-ros2's `RgbdSensor_nwc_ros2`): colour and depth
//! `sensor_msgs/Image` topics, each with its `camera_info` beside it, as an
//! `IRGBDSensor`. Depth arrives as `32FC1` (meters) or `16UC1` (millimeters, converted to
//! meters); an image is served once its `CameraInfo` came too, stamped and sized by it.
//! Parameters: `node_name`, `namespace`, `color_topic_name`, `depth_topic_name`,
//! `verbose_on`.

use crate::camera::info_topic;
use crate::msgs::read_camera_info;
use crate::node::{on_messages, DeviceNode, NodeBuilder};
use parking_lot::Mutex;
use std::sync::Arc;
use yarp_devices::rgbd::{IRGBDSensor, RgbdStatus};
use yarp_devices::{DevResult, DeviceDriver, DeviceError};
use yarp_proto::image::{Image, PixelCode};
use yarp_proto::{Property, Stamp};
use yarp_ros2_gateway::dynmsg::Value as Ros;
use yarp_ros2_gateway::image::to_image;

pub const NAME: &str = "rgbdSensor_nwc_ros2";

yarp_devices::device_params! {
    /// What `rgbdSensor_nwc_ros2` reads (C++ `RgbdSensor_nwc_ros2_params.md`).
    pub struct RgbdSensorNwcRos2Params for "rgbdSensor_nwc_ros2" {
        /// name of the ros2 node
        node_name: String = required,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// ros rgb topic (it's also the base name for the rgb camera_info topic)
        color_topic_name: String = required,
        /// ros depth topic (it's also the base name for the depth camera_info topic)
        depth_topic_name: String = required,
        /// if 1, it enables the verbose mode of the device (accepted, no effect here)
        verbose_on: i64 = 0,
    }
}

/// What one camera (colour or depth) last received.
#[derive(Default, Clone)]
struct Side {
    image: Option<Image>,
    info: Option<(Property, String, f64, u32, u32)>,
    count: i32,
}

impl Side {
    fn get(&self, what: &str) -> DevResult<(Image, Stamp)> {
        let img = self
            .image
            .clone()
            .ok_or_else(|| DeviceError::failed(NAME, format!("no {what} image yet")))?;
        let (_, _, t, ..) = self
            .info
            .as_ref()
            .ok_or_else(|| DeviceError::failed(NAME, format!("no {what} camera info yet")))?;
        Ok((img, Stamp::new(self.count, *t)))
    }
}

/// A depth image in meters (C++ `convertDepthImageRos2ToYarpImageOf`: `16UC1` is mm).
pub fn depth_in_meters(img: Image) -> DevResult<Image> {
    if img.pixel_code() == PixelCode::MONO_FLOAT {
        return Ok(img);
    }
    if img.pixel_code() != PixelCode::MONO16 {
        return Err(DeviceError::failed(
            NAME,
            "depth images must be 32FC1 or 16UC1",
        ));
    }
    let (w, h) = (img.width(), img.height());
    let mut out =
        Image::new(PixelCode::MONO_FLOAT, w, h).map_err(|e| DeviceError::failed(NAME, e))?;
    for y in 0..h {
        for x in 0..w {
            let p = img.pixel(x, y);
            let mm = u16::from_le_bytes([p[0], p[1]]);
            out.pixel_mut(x, y)
                .copy_from_slice(&(mm as f32 / 1000.0).to_ne_bytes());
        }
    }
    Ok(out)
}

#[derive(Default)]
struct State {
    color: Side,
    depth: Side,
}

#[derive(Default)]
pub struct RgbdSensorNwcRos2 {
    state: Arc<Mutex<State>>,
    node: Option<DeviceNode>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
}

impl RgbdSensorNwcRos2 {
    fn state(&self) -> parking_lot::MutexGuard<'_, State> {
        self.state.lock()
    }
}

/// Which stream a subscription feeds.
#[derive(Clone, Copy)]
enum Feed {
    ColorImage,
    ColorInfo,
    DepthImage,
    DepthInfo,
}

impl DeviceDriver for RgbdSensorNwcRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        RgbdSensorNwcRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let RgbdSensorNwcRos2Params {
            node_name,
            namespace,
            color_topic_name: color,
            depth_topic_name: depth,
            ..
        } = RgbdSensorNwcRos2Params::read(config)?;
        let namespace = namespace.unwrap_or_default();
        let mut b = NodeBuilder::new(NAME, &namespace, &node_name)?;
        let subs = [
            (
                b.subscription(&color, "sensor_msgs/msg/Image")?,
                Feed::ColorImage,
                "sensor_msgs/msg/Image",
            ),
            (
                b.subscription(&info_topic(&color), "sensor_msgs/msg/CameraInfo")?,
                Feed::ColorInfo,
                "sensor_msgs/msg/CameraInfo",
            ),
            (
                b.subscription(&depth, "sensor_msgs/msg/Image")?,
                Feed::DepthImage,
                "sensor_msgs/msg/Image",
            ),
            (
                b.subscription(&info_topic(&depth), "sensor_msgs/msg/CameraInfo")?,
                Feed::DepthInfo,
                "sensor_msgs/msg/CameraInfo",
            ),
        ];
        let node = b.spin()?;
        for (sub, feed, ty) in subs {
            let state = self.state.clone();
            self.tasks
                .push(on_messages(sub, ty, move |m| update(&state, feed, m)));
        }
        self.node = Some(node);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        for t in self.tasks.drain(..) {
            t.abort();
        }
        self.node = None;
        Ok(())
    }

    yarp_devices::views!(as_rgbd_sensor);
}

fn update(state: &Mutex<State>, feed: Feed, m: &Ros) {
    let mut s = state.lock();
    match feed {
        Feed::ColorImage => match to_image(m) {
            Ok(img) => {
                s.color.image = Some(img);
                s.color.count = s.color.count.wrapping_add(1);
            }
            Err(e) => tracing::warn!("{NAME}: colour image: {e}"),
        },
        Feed::DepthImage => match to_image(m)
            .map_err(|e| DeviceError::failed(NAME, e))
            .and_then(depth_in_meters)
        {
            Ok(img) => {
                s.depth.image = Some(img);
                s.depth.count = s.depth.count.wrapping_add(1);
            }
            Err(e) => tracing::warn!("{NAME}: depth image: {e}"),
        },
        Feed::ColorInfo => s.color.info = read_camera_info(m),
        Feed::DepthInfo => s.depth.info = read_camera_info(m),
    }
}

fn info_of(side: &Side, what: &str) -> DevResult<Property> {
    side.info
        .as_ref()
        .map(|i| i.0.clone())
        .ok_or_else(|| DeviceError::failed(NAME, format!("no {what} camera info yet")))
}

impl IRGBDSensor for RgbdSensorNwcRos2 {
    fn rgb_height(&mut self) -> i32 {
        self.state().color.info.as_ref().map_or(0, |i| i.4 as i32)
    }
    fn rgb_width(&mut self) -> i32 {
        self.state().color.info.as_ref().map_or(0, |i| i.3 as i32)
    }
    fn depth_height(&mut self) -> i32 {
        self.state().depth.info.as_ref().map_or(0, |i| i.4 as i32)
    }
    fn depth_width(&mut self) -> i32 {
        self.state().depth.info.as_ref().map_or(0, |i| i.3 as i32)
    }
    fn rgb_fov(&mut self) -> DevResult<(f64, f64)> {
        Err(DeviceError::Unsupported(
            "rgbdSensor_nwc_ros2 has no field of view",
        ))
    }
    fn depth_fov(&mut self) -> DevResult<(f64, f64)> {
        Err(DeviceError::Unsupported(
            "rgbdSensor_nwc_ros2 has no field of view",
        ))
    }
    fn rgb_intrinsic_param(&mut self) -> DevResult<Property> {
        info_of(&self.state().color, "colour")
    }
    fn depth_intrinsic_param(&mut self) -> DevResult<Property> {
        info_of(&self.state().depth, "depth")
    }
    fn depth_accuracy(&mut self) -> DevResult<f64> {
        Err(DeviceError::Unsupported(
            "rgbdSensor_nwc_ros2 has no depth accuracy",
        ))
    }
    fn depth_clip_planes(&mut self) -> DevResult<(f64, f64)> {
        Err(DeviceError::Unsupported(
            "rgbdSensor_nwc_ros2 has no clip planes",
        ))
    }
    fn extrinsic_param(&mut self) -> DevResult<[f64; 16]> {
        Err(DeviceError::Unsupported(
            "rgbdSensor_nwc_ros2 has no extrinsic parameters",
        ))
    }
    fn get_rgb_image(&mut self) -> DevResult<(Image, Stamp)> {
        self.state().color.get("colour")
    }
    fn get_depth_image(&mut self) -> DevResult<(Image, Stamp)> {
        self.state().depth.get("depth")
    }
    fn sensor_status(&mut self) -> RgbdStatus {
        let s = self.state();
        if s.color.get("").is_ok() && s.depth.get("").is_ok() {
            RgbdStatus::OkInUse
        } else {
            RgbdStatus::NotReady
        }
    }
}
