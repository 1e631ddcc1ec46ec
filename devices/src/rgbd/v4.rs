//! YARP 4.0's RGB-D protocol: the thrift service `RGBDSensorMsgs`
//! (`RGBDSensorMsgs.thrift`) on `<name>/rpc:i`, where 3.12 spoke `[rgdb]`, `[visr]` and
//! `[visd]` vocabs. Each method is declared once below; C++'s server
//! (`RGBDSensorMsgsImpl`) answers a device without the interface `not ready`.

use super::IRGBDSensor;
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::framegrabber::interfaces::{CameraConfig, CameraDescriptor};
use crate::framegrabber::v4::{controls, positive};
use crate::sensors::wire::WireWriter;
use crate::thrift::{Cursor4, Wire4};
use yarp_proto::image::Image;
use yarp_proto::tags::Generation;
use yarp_proto::{Property, Stamp, Value};

/// A `yarp::os::Stamp`: nested `(seq time)`.
impl Wire4 for Stamp {
    fn put4(&self, w: &mut WireWriter) {
        w.list_header(2).int32(self.count).float64(self.time);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        let l = c.item()?.as_list()?;
        Some(Stamp::new(l.get(0)?.as_i32()?, l.get(1)?.as_f64()?))
    }
    fn zero() -> Self {
        Stamp::new(0, 0.0)
    }
}

/// The extrinsic `yarp::sig::Matrix`, 4x4: nested `(rows cols (data...))`, the data a
/// compact float64 list.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extrinsic(pub [f64; 16]);

impl Wire4 for Extrinsic {
    fn put4(&self, w: &mut WireWriter) {
        w.list_header(3).int32(4).int32(4).float_vector(&self.0);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        let l = c.item()?.as_list()?;
        let data: Vec<f64> = l
            .get(2)?
            .as_list()?
            .iter()
            .map(Value::as_f64)
            .collect::<Option<_>>()?;
        Some(Extrinsic(data.try_into().ok()?))
    }
    fn zero() -> Self {
        Extrinsic([0.0; 16])
    }
}

/// `getImagesRPC`'s fields: both images, then both stamps.
#[derive(Debug, Clone, PartialEq)]
pub struct Images {
    pub rgb: (Image, Stamp),
    pub depth: (Image, Stamp),
}

impl Wire4 for Images {
    const COUNT: usize = 4;
    fn put4(&self, w: &mut WireWriter) {
        self.rgb.0.put4(w);
        self.depth.0.put4(w);
        self.rgb.1.put4(w);
        self.depth.1.put4(w);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        let (rgb, depth) = (Image::take4(c)?, Image::take4(c)?);
        let (rs, ds) = (Stamp::take4(c)?, Stamp::take4(c)?);
        Some(Images {
            rgb: (rgb, rs),
            depth: (depth, ds),
        })
    }
    fn zero() -> Self {
        Images {
            rgb: <(Image, Stamp)>::zero(),
            depth: <(Image, Stamp)>::zero(),
        }
    }
}

fn sensor(dev: &mut dyn DeviceDriver) -> DevResult<&mut dyn IRGBDSensor> {
    dev.as_rgbd_sensor()
        .ok_or(DeviceError::NoInterface("IRGBDSensor"))
}

const WRAPPER: &str = "RGBDSensor_nws_yarp";

crate::thrift_service! {
    /// `service RGBDSensorMsgs`.
    pub mod service for dev {
        getExtrinsicParamRPC() -> Extrinsic = sensor(dev)?.extrinsic_param().map(Extrinsic);
        getLastErrorMsgRPC() -> (String, Stamp) =
            Ok((sensor(dev)?.last_error_msg(), Stamp::new(0, 0.0)));
        getRgbImageRPC() -> (Image, Stamp) = sensor(dev)?.get_rgb_image();
        getDepthImageRPC() -> (Image, Stamp) = sensor(dev)?.get_depth_image();
        getImagesRPC() -> Images = sensor(dev)?
            .get_images()
            // C++ gives the colour stamp for both
            .map(|(rgb, depth)| Images { depth: (depth.0, rgb.1), rgb });
        getSensorStatusRPC() -> i32 = Ok(sensor(dev)?.sensor_status() as i32);

        getRgbWidthRPC() -> i32 = positive(WRAPPER, sensor(dev)?.rgb_width(), "getRgbWidth");
        getRgbHeightRPC() -> i32 = positive(WRAPPER, sensor(dev)?.rgb_height(), "getRgbHeight");
        getRgbSupportedConfigurationsRPC() -> Vec<CameraConfig> =
            sensor(dev)?.rgb_supported_configurations();
        getRgbResolutionRPC() -> (i32, i32) = sensor(dev)?.rgb_resolution();
        setRgbResolutionRPC(width: i32, height: i32) -> () =
            sensor(dev)?.set_rgb_resolution(width, height);
        getRgbFOVRPC() -> (f64, f64) = sensor(dev)?.rgb_fov();
        setRgbFOVRPC(horizontal: f64, vertical: f64) -> () =
            sensor(dev)?.set_rgb_fov(horizontal, vertical);
        getRgbIntrinsicParamRPC() -> Property = sensor(dev)?.rgb_intrinsic_param();
        getRgbMirroringRPC() -> bool = sensor(dev)?.rgb_mirroring();
        setRgbMirroringRPC(mirror: bool) -> () = sensor(dev)?.set_rgb_mirroring(mirror);

        getDepthWidthRPC() -> i32 = positive(WRAPPER, sensor(dev)?.depth_width(), "getDepthWidth");
        getDepthHeightRPC() -> i32 = positive(WRAPPER, sensor(dev)?.depth_height(), "getDepthHeight");
        getDepthResolutionRPC() -> (i32, i32) = sensor(dev)?.depth_resolution();
        setDepthResolutionRPC(width: i32, height: i32) -> () =
            sensor(dev)?.set_depth_resolution(width, height);
        getDepthFOVRPC() -> (f64, f64) = sensor(dev)?.depth_fov();
        setDepthFOVRPC(horizontal: f64, vertical: f64) -> () =
            sensor(dev)?.set_depth_fov(horizontal, vertical);
        getDepthAccuracyRPC() -> f64 = sensor(dev)?.depth_accuracy();
        setDepthAccuracyRPC(accuracy: f64) -> () = sensor(dev)?.set_depth_accuracy(accuracy);
        getDepthClipPlanesRPC() -> (f64, f64) = sensor(dev)?.depth_clip_planes();
        setDepthClipPlanesRPC(near: f64, far: f64) -> () =
            sensor(dev)?.set_depth_clip_planes(near, far);
        getDepthMirroringRPC() -> bool = sensor(dev)?.depth_mirroring();
        setDepthMirroringRPC(mirror: bool) -> () = sensor(dev)?.set_depth_mirroring(mirror);
        getDepthIntrinsicParamRPC() -> Property = sensor(dev)?.depth_intrinsic_param();

        getCameraDescriptionRPC() -> CameraDescriptor = controls(dev)?.camera_description();
        hasFeatureRPC(feature: i32) -> bool = controls(dev)?.has_feature(feature);
        setFeature1RPC(feature: i32, value: f64) -> () = controls(dev)?.set_feature(feature, value);
        getFeature1RPC(feature: i32) -> f64 = controls(dev)?.get_feature(feature);
        setFeature2RPC(feature: i32, value1: f64, value2: f64) -> () =
            controls(dev)?.set_feature2(feature, value1, value2);
        getFeature2RPC(feature: i32) -> (f64, f64) = controls(dev)?.get_feature2(feature);
        hasOnOffRPC(feature: i32) -> bool = controls(dev)?.has_on_off(feature);
        setActiveRPC(feature: i32, onoff: bool) -> () = controls(dev)?.set_active(feature, onoff);
        getActiveRPC(feature: i32) -> bool = controls(dev)?.get_active(feature);
        hasAutoRPC(feature: i32) -> bool = controls(dev)?.has_auto(feature);
        hasManualRPC(feature: i32) -> bool = controls(dev)?.has_manual(feature);
        hasOnePushRPC(feature: i32) -> bool = controls(dev)?.has_one_push(feature);
        setModeRPC(feature: i32, mode: i32) -> () = controls(dev)?.set_mode(feature, mode);
        getModeRPC(feature: i32) -> i32 = controls(dev)?.get_mode(feature);
        setOnePushRPC(feature: i32) -> () = controls(dev)?.set_one_push(feature);
    }
}

/// Whether `cmd` is a call of this service (or `getRemoteProtocolVersion`) rather than
/// a 3.12 vocab command.
pub fn is_call(cmd: &yarp_proto::Bottle) -> bool {
    crate::thrift::is_call_of(cmd, service::METHODS)
}

/// Answers a 4.0 call on `dev` (`None`: nothing attached, every method `not ready`).
pub fn handle_rpc(cmd: &yarp_proto::Bottle, dev: Option<&mut dyn DeviceDriver>) -> Vec<u8> {
    if crate::thrift::is_protocol_version_request(cmd) {
        return crate::thrift::protocol_version_reply(Generation::V4);
    }
    struct Nothing;
    impl DeviceDriver for Nothing {
        fn open(&mut self, _: &Property) -> DevResult<()> {
            Ok(())
        }
    }
    match service::Call::decode(cmd) {
        Some(call) => match dev {
            Some(d) => call.serve(d),
            None => call.serve(&mut Nothing),
        },
        None => crate::thrift::fail_reply(),
    }
}
