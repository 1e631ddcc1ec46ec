//! RGB-D cameras: the `IRGBDSensor` interface (C++ `yarp::dev::IRGBDSensor`, with its
//! `IRgbVisualParams` and `IDepthVisualParams` parts), `fakeDepthCamera`, the YARP
//! network wrapper `rgbdSensor_nws_yarp` and its client `RGBDSensorClient`.

pub mod fake;
pub mod nwc;
pub mod nws;
pub mod protocol;

use crate::driver::Factory;
use crate::error::DevResult;
use yarp_proto::image::Image;
use yarp_proto::{Property, Stamp};

/// Sensor status (C++ `IRGBDSensor::RGBDSensor_status`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RgbdStatus {
    NotReady = 0,
    OkStandby = 1,
    OkInUse = 2,
    GeneralError = 3,
    Timeout = 4,
}

/// A colour + depth camera (C++ `IRGBDSensor`). Depth images are `PixelCode::MONO_FLOAT`
/// (C++ `ImageOf<PixelFloat>`), in meters.
pub trait IRGBDSensor {
    fn rgb_height(&mut self) -> i32;
    fn rgb_width(&mut self) -> i32;
    fn depth_height(&mut self) -> i32;
    fn depth_width(&mut self) -> i32;
    /// Horizontal and vertical field of view (degrees).
    fn rgb_fov(&mut self) -> DevResult<(f64, f64)>;
    fn depth_fov(&mut self) -> DevResult<(f64, f64)>;
    /// Intrinsic parameters as C++ puts them in a `Property` (`focalLengthX`,
    /// `principalPointX`, `distortionModel`, `k1`...).
    fn rgb_intrinsic_param(&mut self) -> DevResult<Property>;
    fn depth_intrinsic_param(&mut self) -> DevResult<Property>;
    fn depth_accuracy(&mut self) -> DevResult<f64>;
    /// Near and far clip planes (m).
    fn depth_clip_planes(&mut self) -> DevResult<(f64, f64)>;
    /// The 4x4 transform from the colour to the depth camera, row by row.
    fn extrinsic_param(&mut self) -> DevResult<[f64; 16]>;
    fn get_rgb_image(&mut self) -> DevResult<(Image, Stamp)>;
    fn get_depth_image(&mut self) -> DevResult<(Image, Stamp)>;
    /// Both images, taken together.
    fn get_images(&mut self) -> DevResult<((Image, Stamp), (Image, Stamp))> {
        Ok((self.get_rgb_image()?, self.get_depth_image()?))
    }
    fn sensor_status(&mut self) -> RgbdStatus;
    fn last_error_msg(&mut self) -> String {
        String::new()
    }
}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
    ("fakeDepthCamera", || Box::new(fake::FakeDepthCamera::new())),
    ("rgbdSensor_nws_yarp", || {
        Box::new(nws::RgbdSensorNwsYarp::new())
    }),
    (nwc::NAME, || Box::new(nwc::RgbdSensorClient::new())),
];
