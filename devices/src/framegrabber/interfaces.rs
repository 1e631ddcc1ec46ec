//! The frame-grabber interfaces (C++ `IFrameGrabberImage`, `IFrameGrabberControls`,
//! `IRgbVisualParams`), apart from the devices that implement them so that the driver
//! framework can name them without importing a driver module.

use crate::error::DevResult;
use yarp_proto::image::{Image, PixelCode};
use yarp_proto::{Property, Stamp};

/// Image acquisition (C++ `IFrameGrabberImage`, i.e. `IFrameGrabberOf<ImageOf<PixelRgb>>`),
/// with the parts of `IPreciselyTimed` and `IRgbVisualParams` a camera offers alongside.
pub trait IFrameGrabberImage {
    /// The latest image (RGB for the C++ `IFrameGrabberImage`).
    fn get_image(&mut self) -> DevResult<Image>;
    /// Image height in pixels (0 when unknown).
    fn height(&mut self) -> usize;
    /// Image width in pixels (0 when unknown).
    fn width(&mut self) -> usize;
    /// The stamp of the last image returned by `get_image` (C++ `IPreciselyTimed`);
    /// `None` when the device does not time its images.
    fn last_input_stamp(&mut self) -> Option<Stamp> {
        None
    }
    /// The device's `IRgbVisualParams`, if it has them. (C++ reaches it with
    /// `PolyDriver::view` on the same device; here it hangs off the image interface.)
    fn rgb_visual_params(&mut self) -> Option<&mut dyn IRgbVisualParams> {
        None
    }
}

/// Camera bus (C++ `BusType`).
pub const BUS_UNKNOWN: i32 = 0;
pub const BUS_FIREWIRE: i32 = 1;
pub const BUS_USB: i32 = 2;

/// Feature modes (C++ `FeatureMode`).
pub const MODE_UNKNOWN: i32 = 0;
pub const MODE_MANUAL: i32 = 1;
pub const MODE_AUTO: i32 = 2;

/// Feature ids (C++ `cameraFeature_id_t`), the first few.
pub const FEATURE_BRIGHTNESS: i32 = 0;
pub const FEATURE_EXPOSURE: i32 = 1;
pub const FEATURE_SHARPNESS: i32 = 2;
pub const FEATURE_WHITE_BALANCE: i32 = 3;
pub const FEATURE_HUE: i32 = 4;
pub const FEATURE_SATURATION: i32 = 5;
pub const FEATURE_GAMMA: i32 = 6;
pub const FEATURE_SHUTTER: i32 = 7;
pub const FEATURE_GAIN: i32 = 8;
pub const FEATURE_IRIS: i32 = 9;

/// What a camera says about itself (C++ `CameraDescriptor`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CameraDescriptor {
    /// One of `BUS_*`.
    pub bus_type: i32,
    pub description: String,
}

/// Camera controls (C++ `IFrameGrabberControls`); features are `FEATURE_*` ids and
/// modes `MODE_*`.
pub trait IFrameGrabberControls {
    fn camera_description(&mut self) -> DevResult<CameraDescriptor>;
    fn has_feature(&mut self, feature: i32) -> DevResult<bool>;
    fn set_feature(&mut self, feature: i32, value: f64) -> DevResult<()>;
    fn get_feature(&mut self, feature: i32) -> DevResult<f64>;
    /// Two-valued features (white balance).
    fn set_feature2(&mut self, feature: i32, v1: f64, v2: f64) -> DevResult<()>;
    fn get_feature2(&mut self, feature: i32) -> DevResult<(f64, f64)>;
    fn has_on_off(&mut self, feature: i32) -> DevResult<bool>;
    fn set_active(&mut self, feature: i32, on: bool) -> DevResult<()>;
    fn get_active(&mut self, feature: i32) -> DevResult<bool>;
    fn has_auto(&mut self, feature: i32) -> DevResult<bool>;
    fn has_manual(&mut self, feature: i32) -> DevResult<bool>;
    fn has_one_push(&mut self, feature: i32) -> DevResult<bool>;
    fn set_mode(&mut self, feature: i32, mode: i32) -> DevResult<()>;
    fn get_mode(&mut self, feature: i32) -> DevResult<i32>;
    fn set_one_push(&mut self, feature: i32) -> DevResult<()>;
}

/// One supported camera configuration (C++ `CameraConfig`).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraConfig {
    pub width: i32,
    pub height: i32,
    pub framerate: f64,
    pub pixel_code: PixelCode,
}

/// Colour-camera geometry (C++ `IRgbVisualParams`).
pub trait IRgbVisualParams {
    fn rgb_height(&mut self) -> i32;
    fn rgb_width(&mut self) -> i32;
    fn rgb_supported_configurations(&mut self) -> DevResult<Vec<CameraConfig>>;
    fn rgb_resolution(&mut self) -> DevResult<(i32, i32)>;
    fn set_rgb_resolution(&mut self, width: i32, height: i32) -> DevResult<()>;
    /// Horizontal and vertical field of view (degrees).
    fn rgb_fov(&mut self) -> DevResult<(f64, f64)>;
    fn set_rgb_fov(&mut self, horizontal: f64, vertical: f64) -> DevResult<()>;
    /// Intrinsic parameters as C++ puts them in a `Property`.
    fn rgb_intrinsic_param(&mut self) -> DevResult<Property>;
    fn rgb_mirroring(&mut self) -> DevResult<bool>;
    fn set_rgb_mirroring(&mut self, mirror: bool) -> DevResult<()>;
}

/// IEEE 1394 (FireWire) camera settings (C++ `IFrameGrabberControlsDC1394`), as the
/// iCub's Dragonfly2 cameras offer them. Masks and modes are the DC1394 library's
/// numbers; Format 7 windows are (xdim, ydim, x0, y0).
pub trait IFrameGrabberControlsDC1394 {
    fn video_mode_mask(&mut self) -> DevResult<u32>;
    fn video_mode(&mut self) -> DevResult<u32>;
    fn set_video_mode(&mut self, mode: i32) -> DevResult<()>;
    fn fps_mask(&mut self) -> DevResult<u32>;
    fn fps(&mut self) -> DevResult<u32>;
    fn set_fps(&mut self, fps: i32) -> DevResult<()>;
    fn iso_speed(&mut self) -> DevResult<u32>;
    fn set_iso_speed(&mut self, speed: i32) -> DevResult<()>;
    fn color_coding_mask(&mut self, video_mode: u32) -> DevResult<u32>;
    fn color_coding(&mut self) -> DevResult<u32>;
    fn set_color_coding(&mut self, coding: i32) -> DevResult<()>;
    /// (xdim, ydim, xstep, ystep, xoffstep, yoffstep).
    fn format7_max_window(&mut self) -> DevResult<[u32; 6]>;
    fn format7_window(&mut self) -> DevResult<(u32, u32, i32, i32)>;
    fn set_format7_window(&mut self, xdim: u32, ydim: u32, x0: i32, y0: i32) -> DevResult<()>;
    fn operation_mode(&mut self) -> DevResult<bool>;
    fn set_operation_mode(&mut self, b1394b: bool) -> DevResult<()>;
    fn transmission(&mut self) -> DevResult<bool>;
    fn set_transmission(&mut self, on: bool) -> DevResult<()>;
    fn set_broadcast(&mut self, on: bool) -> DevResult<()>;
    fn set_defaults(&mut self) -> DevResult<()>;
    fn set_reset(&mut self) -> DevResult<()>;
    fn set_power(&mut self, on: bool) -> DevResult<()>;
    fn set_capture(&mut self, on: bool) -> DevResult<()>;
    fn bytes_per_packet(&mut self) -> DevResult<u32>;
    fn set_bytes_per_packet(&mut self, bpp: u32) -> DevResult<()>;
}
