//! `fakeDepthCamera` (C++ `FakeDepthCameraDriver`): a `fakeFrameGrabber`, opened with the
//! same configuration, gives the colour image; the depth image is the mean of its three
//! channels, scaled to [0, 1] m.
//!
//! Parameters as in C++ 3.12: `rgb_h`, `rgb_w`, `dep_h`, `dep_w` (read but, as in C++,
//! the images have the grabber's `width` x `height`), `accuracy` (0.001), `rgb_Vfov` /
//! `rgb_Hfov` (50 / 36), `dep_Vfov` / `dep_Hfov` (50 / 36), `dep_near` / `dep_far` (0.2 /
//! 6), plus every `fakeFrameGrabber` parameter. The intrinsic parameters are C++'s
//! constants (focal length 512 px, principal point (235, 231), `plumb_bob` with zero
//! distortion).

use super::{IRGBDSensor, RgbdStatus};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::framegrabber::fake::FakeFrameGrabber;
use crate::framegrabber::IFrameGrabberImage;
use std::time::{SystemTime, UNIX_EPOCH};
use yarp_proto::image::{Image, PixelCode};
use yarp_proto::{Property, Stamp, Value};

crate::device_params! {
    /// What `fakeDepthCamera` reads (C++ `FakeDepthCameraDriver_params.md`; the image
    /// sizes are those of the fakeFrameGrabber inside, so `rgb_*`/`dep_*` sizes are only
    /// checked).
    pub struct FakeDepthCameraParams for "fakeDepthCamera" {
        /// rgb_h
        rgb_h: f64 = 480.0,
        /// rgb_w
        rgb_w: f64 = 640.0,
        /// dep_h
        dep_h: f64 = 480.0,
        /// dep_w
        dep_w: f64 = 640.0,
        /// accuracy
        accuracy: f64 = 0.001,
        /// rgb_Vfov
        "rgb_Vfov" rgb_vfov: f64 = 50.0,
        /// rgb_Hfov
        "rgb_Hfov" rgb_hfov: f64 = 36.0,
        /// dep_Vfov
        "dep_Vfov" dep_vfov: f64 = 50.0,
        /// dep_Hfov
        "dep_Hfov" dep_hfov: f64 = 36.0,
        /// dep_near
        dep_near: f64 = 0.2,
        /// dep_far
        dep_far: f64 = 6.0,
    }
}

pub struct FakeDepthCamera {
    grabber: FakeFrameGrabber,
    accuracy: f64,
    rgb_fov: (f64, f64),
    dep_fov: (f64, f64),
    clip: (f64, f64),
    count: i32,
    open: bool,
}

impl Default for FakeDepthCamera {
    fn default() -> Self {
        Self::new()
    }
}

/// The depth of a colour image: per pixel the mean of r, g and b over 255 (C++
/// `getDepthImage`), as native-endian f32 (`PixelFloat`).
pub fn depth_of(rgb: &Image) -> Image {
    let (w, h) = (rgb.width(), rgb.height());
    let mut depth = Image::new(PixelCode::MONO_FLOAT, w, h)
        .unwrap_or_else(|_| Image::empty(PixelCode::MONO_FLOAT));
    // Same rows, same orientation flag: fakeFrameGrabber's images are bottom-up.
    depth.set_top_is_low(rgb.top_is_low());
    for y in 0..h {
        for x in 0..w {
            let p = rgb.pixel(x, y);
            let d = (p[2] as f32 / 255.0) / 3.0
                + (p[1] as f32 / 255.0) / 3.0
                + (p[0] as f32 / 255.0) / 3.0;
            depth.pixel_mut(x, y).copy_from_slice(&d.to_ne_bytes());
        }
    }
    depth
}

fn now_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

impl FakeDepthCamera {
    pub fn new() -> FakeDepthCamera {
        FakeDepthCamera {
            grabber: FakeFrameGrabber::new(),
            accuracy: 0.001,
            rgb_fov: (36.0, 50.0),
            dep_fov: (36.0, 50.0),
            clip: (0.2, 6.0),
            count: 0,
            open: false,
        }
    }

    fn intrinsics() -> Property {
        let mut p = Property::new();
        p.put("physFocalLength", Value::Float64(0.5));
        p.put("focalLengthX", Value::Float64(512.0));
        p.put("focalLengthY", Value::Float64(512.0));
        p.put("principalPointX", Value::Float64(235.0));
        p.put("principalPointY", Value::Float64(231.0));
        p.put("distortionModel", Value::from("plumb_bob"));
        for k in ["k1", "k2", "t1", "t2", "k3"] {
            p.put(k, Value::Float64(0.0));
        }
        p.put("stamp", Value::Float64(now_s()));
        p
    }

    fn stamp(&mut self) -> Stamp {
        self.count = self.count.wrapping_add(1);
        Stamp::new(self.count, now_s())
    }
}

impl DeviceDriver for FakeDepthCamera {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeDepthCameraParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeDepthCameraParams::read(config)?;
        self.accuracy = p.accuracy;
        self.rgb_fov = (p.rgb_hfov, p.rgb_vfov);
        self.dep_fov = (p.dep_hfov, p.dep_vfov);
        self.clip = (p.dep_near, p.dep_far);
        let mut cfg = config.clone();
        cfg.put("device", Value::from("fakeFrameGrabber"));
        self.grabber.open(&cfg)?;
        self.open = true;
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.open = false;
        self.grabber.close()
    }

    crate::views!(as_rgbd_sensor);
}

impl IRGBDSensor for FakeDepthCamera {
    fn rgb_height(&mut self) -> i32 {
        self.grabber.height() as i32
    }
    fn rgb_width(&mut self) -> i32 {
        self.grabber.width() as i32
    }
    fn depth_height(&mut self) -> i32 {
        self.grabber.height() as i32
    }
    fn depth_width(&mut self) -> i32 {
        self.grabber.width() as i32
    }
    fn rgb_fov(&mut self) -> DevResult<(f64, f64)> {
        Ok(self.rgb_fov)
    }
    fn depth_fov(&mut self) -> DevResult<(f64, f64)> {
        Ok(self.dep_fov)
    }
    fn rgb_intrinsic_param(&mut self) -> DevResult<Property> {
        Ok(Self::intrinsics())
    }
    fn depth_intrinsic_param(&mut self) -> DevResult<Property> {
        Ok(Self::intrinsics())
    }
    fn depth_accuracy(&mut self) -> DevResult<f64> {
        Ok(self.accuracy)
    }
    fn depth_clip_planes(&mut self) -> DevResult<(f64, f64)> {
        Ok(self.clip)
    }
    // C++ 3.12's fake keeps fields of view, accuracy and clip planes, and refuses new
    // resolutions and mirroring
    fn set_rgb_fov(&mut self, horizontal: f64, vertical: f64) -> DevResult<()> {
        self.rgb_fov = (horizontal, vertical);
        Ok(())
    }
    fn set_depth_fov(&mut self, horizontal: f64, vertical: f64) -> DevResult<()> {
        self.dep_fov = (horizontal, vertical);
        Ok(())
    }
    fn set_depth_accuracy(&mut self, accuracy: f64) -> DevResult<()> {
        self.accuracy = accuracy;
        Ok(())
    }
    fn set_depth_clip_planes(&mut self, near: f64, far: f64) -> DevResult<()> {
        self.clip = (near, far);
        Ok(())
    }
    fn extrinsic_param(&mut self) -> DevResult<[f64; 16]> {
        let mut m = [0.0; 16];
        for i in 0..4 {
            m[i * 5] = 1.0;
        }
        Ok(m)
    }
    fn get_rgb_image(&mut self) -> DevResult<(Image, Stamp)> {
        if !self.open {
            return Err(DeviceError::NotOpen);
        }
        let img = self.grabber.get_image()?;
        Ok((img, self.stamp()))
    }
    fn get_depth_image(&mut self) -> DevResult<(Image, Stamp)> {
        let (rgb, stamp) = self.get_rgb_image()?;
        Ok((depth_of(&rgb), stamp))
    }
    fn get_images(&mut self) -> DevResult<((Image, Stamp), (Image, Stamp))> {
        let (rgb, stamp) = self.get_rgb_image()?;
        let depth = depth_of(&rgb);
        Ok(((rgb, stamp), (depth, stamp)))
    }
    fn sensor_status(&mut self) -> RgbdStatus {
        if self.open {
            RgbdStatus::OkInUse
        } else {
            RgbdStatus::NotReady
        }
    }
    fn last_error_msg(&mut self) -> String {
        "no error".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_and_depth() {
        let mut c = FakeDepthCamera::new();
        c.open(&Property::from_config_text("width 64\nheight 48\nmode grid").unwrap())
            .unwrap();
        let ((rgb, s1), (depth, s2)) = c.get_images().unwrap();
        assert_eq!(
            (rgb.width(), rgb.height(), rgb.pixel_code()),
            (64, 48, PixelCode::RGB)
        );
        assert_eq!(depth.pixel_code(), PixelCode::MONO_FLOAT);
        assert_eq!(s1, s2);
        let p = rgb.pixel(63, 47).to_vec();
        let d = f32::from_ne_bytes(depth.pixel(63, 47).try_into().unwrap());
        let want = p.iter().map(|&c| c as f32 / 255.0 / 3.0).sum::<f32>();
        assert!((d - want).abs() < 1e-6);
        let k = c.rgb_intrinsic_param().unwrap();
        assert_eq!(k.find("focalLengthX").and_then(Value::as_f64), Some(512.0));
        assert_eq!(c.depth_clip_planes().unwrap(), (0.2, 6.0));
    }
}
