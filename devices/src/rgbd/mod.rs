//! RGB-D cameras: the `IRGBDSensor` interface (C++ `yarp::dev::IRGBDSensor`, with its
//! `IRgbVisualParams` and `IDepthVisualParams` parts), `fakeDepthCamera`, the YARP
//! network wrapper `rgbdSensor_nws_yarp` and its client `RGBDSensorClient`.

pub mod fake;
pub mod nwc;
pub mod nws;
pub mod protocol;
pub mod v4;

use crate::driver::Factory;
use crate::error::{DevResult, DeviceError};
use crate::framegrabber::CameraConfig;
use yarp_proto::image::Image;
use yarp_proto::{Property, Stamp};

/// Sensor status (C++ `IRGBDSensor::RGBDSensor_status`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RgbdStatus {
    NotReady = 0,
    OkStandby = 1,
    OkInUse = 2,
    GeneralError = 5,
    Timeout = 6,
}

impl RgbdStatus {
    /// The status C++'s number stands for (an unknown one is a general error).
    pub fn from_code(code: i32) -> RgbdStatus {
        match code {
            0 => RgbdStatus::NotReady,
            1 => RgbdStatus::OkStandby,
            2 => RgbdStatus::OkInUse,
            6 => RgbdStatus::Timeout,
            _ => RgbdStatus::GeneralError,
        }
    }
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

    // What the C++ interface also has, with the answer of a camera that cannot.
    fn rgb_resolution(&mut self) -> DevResult<(i32, i32)> {
        Ok((self.rgb_width(), self.rgb_height()))
    }
    fn depth_resolution(&mut self) -> DevResult<(i32, i32)> {
        Ok((self.depth_width(), self.depth_height()))
    }
    fn rgb_supported_configurations(&mut self) -> DevResult<Vec<CameraConfig>> {
        Ok(Vec::new())
    }
    fn set_rgb_resolution(&mut self, _width: i32, _height: i32) -> DevResult<()> {
        Err(DeviceError::Unsupported("setting the colour resolution"))
    }
    fn set_depth_resolution(&mut self, _width: i32, _height: i32) -> DevResult<()> {
        Err(DeviceError::Unsupported("setting the depth resolution"))
    }
    fn set_rgb_fov(&mut self, _horizontal: f64, _vertical: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setting the colour field of view"))
    }
    fn set_depth_fov(&mut self, _horizontal: f64, _vertical: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setting the depth field of view"))
    }
    fn set_depth_accuracy(&mut self, _accuracy: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setting the depth accuracy"))
    }
    fn set_depth_clip_planes(&mut self, _near: f64, _far: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported("setting the clip planes"))
    }
    fn rgb_mirroring(&mut self) -> DevResult<bool> {
        Ok(false)
    }
    fn set_rgb_mirroring(&mut self, _mirror: bool) -> DevResult<()> {
        Err(DeviceError::Unsupported("mirroring the colour image"))
    }
    fn depth_mirroring(&mut self) -> DevResult<bool> {
        Ok(false)
    }
    fn set_depth_mirroring(&mut self, _mirror: bool) -> DevResult<()> {
        Err(DeviceError::Unsupported("mirroring the depth image"))
    }
}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
    ("fakeDepthCamera", || Box::new(fake::FakeDepthCamera::new())),
    ("rgbdSensor_nws_yarp", || {
        Box::new(nws::RgbdSensorNwsYarp::new())
    }),
    // YARP 4.0's names (the 3.12 ones are its deprecated aliases)
    ("RGBDSensor_nws_yarp", || {
        Box::new(nws::RgbdSensorNwsYarp::new())
    }),
    ("RGBDSensor_nwc_yarp", || {
        Box::new(nwc::RgbdSensorClient::new())
    }),
    ("rgbdSensor_nwc_yarp", || {
        Box::new(nwc::RgbdSensorClient::new())
    }),
    (nwc::NAME, || Box::new(nwc::RgbdSensorClient::new())),
];
