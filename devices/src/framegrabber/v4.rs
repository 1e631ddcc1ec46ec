//! YARP 4.0's frame-grabber protocol: the thrift service `FrameGrabberMsgs`
//! (`frameGrabberMsgs.thrift`) on `<name>/rpc`, where 3.12 spoke `[fgi]`, `[fgc]` and
//! `[visr]` vocabs. Each method is declared once below; C++'s server
//! (`FrameGrabberMsgsImpl`) answers a device without the interface `not ready`, a width
//! or height of 0 or less `generic error`, and otherwise what the device returned.

use super::interfaces::{CameraConfig, CameraDescriptor, IFrameGrabberImage, IRgbVisualParams};
use super::protocol::crop_rect;
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::sensors::wire::WireWriter;
use crate::thrift::{take_list, Cursor4, Wire4};
use yarp_proto::image::{encode_image_as, Image, PixelCode};
use yarp_proto::tags::Generation;
use yarp_proto::Property;

/// A `FlexImage`: nested, in its own wire form (4.0's header).
impl Wire4 for Image {
    fn put4(&self, w: &mut WireWriter) {
        w.raw(&encode_image_as(self, Generation::V4));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        Image::from_bottle(c.item()?.as_list()?).ok()
    }
    fn zero() -> Self {
        Image::empty(PixelCode::RGB)
    }
}

/// `yCameraDescriptor`: its two fields, flat in the reply.
impl Wire4 for CameraDescriptor {
    const COUNT: usize = 2;
    fn put4(&self, w: &mut WireWriter) {
        w.int32(self.bus_type).string(&self.description);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        Some(CameraDescriptor {
            bus_type: i32::take4(c)?,
            description: String::take4(c)?,
        })
    }
    fn zero() -> Self {
        CameraDescriptor::default()
    }
}

/// `list<yCameraConfig>`: a list of nested `(width height framerate pixelCoding)`, the
/// pixel coding an int32.
impl Wire4 for Vec<CameraConfig> {
    fn put4(&self, w: &mut WireWriter) {
        w.list_header(self.len());
        for c in self {
            w.list_header(4)
                .int32(c.width)
                .int32(c.height)
                .float64(c.framerate)
                .int32(c.pixel_code.0);
        }
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_list(c, |v| {
            let l = v.as_list()?;
            Some(CameraConfig {
                width: l.get(0)?.as_i32()?,
                height: l.get(1)?.as_i32()?,
                framerate: l.get(2)?.as_f64()?,
                pixel_code: PixelCode(l.get(3)?.as_i32()?),
            })
        })
    }
    fn zero() -> Self {
        Vec::new()
    }
}

/// A `Property`: nested, as the Bottle of its groups.
impl Wire4 for Property {
    fn put4(&self, w: &mut WireWriter) {
        w.raw(&self.to_bottle().encode_as(Generation::V4));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        Some(Property::from_bottle(c.item()?.as_list()?))
    }
    fn zero() -> Self {
        Property::new()
    }
}

/// `yarp::dev::vertex_t`: a nested `(x y)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Vertex(pub i32, pub i32);

/// `list<yVertex>`.
impl Wire4 for Vec<Vertex> {
    fn put4(&self, w: &mut WireWriter) {
        w.list_header(self.len());
        for v in self {
            w.list_header(2).int32(v.0).int32(v.1);
        }
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_list(c, |v| {
            let l = v.as_list()?;
            Some(Vertex(l.get(0)?.as_i32()?, l.get(1)?.as_i32()?))
        })
    }
    fn zero() -> Self {
        Vec::new()
    }
}

/// The DC1394 windows: `N` int32, flat.
impl<const N: usize> Wire4 for [i32; N] {
    const COUNT: usize = N;
    fn put4(&self, w: &mut WireWriter) {
        for x in self {
            w.int32(*x);
        }
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        let mut out = [0; N];
        for x in &mut out {
            *x = i32::take4(c)?;
        }
        Some(out)
    }
    fn zero() -> Self {
        [0; N]
    }
}

fn image(dev: &mut dyn DeviceDriver) -> DevResult<&mut dyn IFrameGrabberImage> {
    dev.as_frame_grabber_image()
        .ok_or(DeviceError::NoInterface("IFrameGrabberImage"))
}

fn visual(dev: &mut dyn DeviceDriver) -> DevResult<&mut dyn IRgbVisualParams> {
    image(dev)
        .ok()
        .and_then(|fg| fg.rgb_visual_params())
        .ok_or(DeviceError::NoInterface("IRgbVisualParams"))
}

pub(crate) fn controls(
    dev: &mut dyn DeviceDriver,
) -> DevResult<&mut dyn super::interfaces::IFrameGrabberControls> {
    dev.as_frame_grabber_controls()
        .ok_or(DeviceError::NoInterface("IFrameGrabberControls"))
}

fn dc1394(
    dev: &mut dyn DeviceDriver,
) -> DevResult<&mut dyn super::interfaces::IFrameGrabberControlsDC1394> {
    dev.as_frame_grabber_controls_dc1394()
        .ok_or(DeviceError::NoInterface("IFrameGrabberControlsDC1394"))
}

/// DC1394's unsigned values travel as i32.
fn int(x: u32) -> i32 {
    x as i32
}

const WRAPPER: &str = "frameGrabber_nws_yarp";

fn refused(command: impl Into<String>) -> DeviceError {
    DeviceError::Refused {
        device: WRAPPER.into(),
        command: command.into(),
    }
}

/// A size of 0 or less is a failure (C++'s `return_value_error_generic`; ours says
/// `method failed`, the one code a refusal maps to).
pub(crate) fn positive(wrapper: &str, n: i32, what: &str) -> DevResult<i32> {
    if n > 0 {
        Ok(n)
    } else {
        Err(DeviceError::Refused {
            device: wrapper.into(),
            command: format!("{what} (the device reports {n})"),
        })
    }
}

/// `cropType_id_t`: 0 a rectangle between two vertices, 1 a list of points.
const CROP_RECT: i32 = 0;

crate::thrift_service! {
    /// `service FrameGrabberMsgs`.
    pub mod service for dev {
        getHeightRPC() -> i32 = Ok(image(dev)?.height() as i32);
        getWidthRPC() -> i32 = Ok(image(dev)?.width() as i32);
        getImageRPC() -> Image = image(dev)?.get_image();
        getImageCropRPC(crop_type: i32, vertices: Vec<Vertex>) -> Image = {
            let fg = image(dev)?;
            match (crop_type, vertices.as_slice()) {
                (CROP_RECT, [a, b]) => {
                    let full = fg.get_image()?;
                    crop_rect(&full, (a.0, a.1), (b.0, b.1)).ok_or_else(|| refused(
                        "getImageCrop: vertices outside the image or not top-left then bottom-right",
                    ))
                }
                (CROP_RECT, _) => Err(refused("getImageCrop: a rectangle takes 2 vertices")),
                _ => Err(DeviceError::Unsupported("crop types other than a rectangle")),
            }
        };
        getRgbWidthRPC() -> i32 = positive(WRAPPER, visual(dev)?.rgb_width(), "getRgbWidth");
        getRgbHeightRPC() -> i32 = positive(WRAPPER, visual(dev)?.rgb_height(), "getRgbHeight");
        getRgbSupportedConfigurationsRPC() -> Vec<CameraConfig> =
            visual(dev)?.rgb_supported_configurations();
        getRgbResolutionRPC() -> (i32, i32) = visual(dev)?.rgb_resolution();
        setRgbResolutionRPC(width: i32, height: i32) -> () =
            visual(dev)?.set_rgb_resolution(width, height);
        getRgbFOVRPC() -> (f64, f64) = visual(dev)?.rgb_fov();
        setRgbFOVRPC(horizontal: f64, vertical: f64) -> () =
            visual(dev)?.set_rgb_fov(horizontal, vertical);
        getRgbIntrinsicParamRPC() -> Property = visual(dev)?.rgb_intrinsic_param();
        getRgbMirroringRPC() -> bool = visual(dev)?.rgb_mirroring();
        setRgbMirroringRPC(mirror: bool) -> () = visual(dev)?.set_rgb_mirroring(mirror);

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

        getVideoModeMaskDC1394RPC() -> i32 = dc1394(dev)?.video_mode_mask().map(int);
        getVideoModeDC1394RPC() -> i32 = dc1394(dev)?.video_mode().map(int);
        setVideoModeDC1394RPC(videomode: i32) -> () = dc1394(dev)?.set_video_mode(videomode);
        getFPSMaskDC1394RPC() -> i32 = dc1394(dev)?.fps_mask().map(int);
        getFPSDC1394RPC() -> i32 = dc1394(dev)?.fps().map(int);
        setFPSDC1394RPC(fps: i32) -> () = dc1394(dev)?.set_fps(fps);
        getISOSpeedDC1394RPC() -> i32 = dc1394(dev)?.iso_speed().map(int);
        setISOSpeedDC1394RPC(speed: i32) -> () = dc1394(dev)?.set_iso_speed(speed);
        getColorCodingMaskDC1394RPC(videomode: i32) -> i32 =
            dc1394(dev)?.color_coding_mask(videomode as u32).map(int);
        getColorCodingDC1394RPC() -> i32 = dc1394(dev)?.color_coding().map(int);
        setColorCodingDC1394RPC(coding: i32) -> () = dc1394(dev)?.set_color_coding(coding);
        getFormat7MaxWindowDC1394RPC() -> [i32; 6] =
            dc1394(dev)?.format7_max_window().map(|w| w.map(int));
        getFormat7WindowDC1394RPC() -> [i32; 4] = dc1394(dev)?
            .format7_window()
            .map(|(xd, yd, x0, y0)| [int(xd), int(yd), x0, y0]);
        setFormat7WindowDC1394RPC(xdim: i32, ydim: i32, x0: i32, y0: i32) -> () =
            dc1394(dev)?.set_format7_window(xdim as u32, ydim as u32, x0, y0);
        setOperationModeDC1394RPC(b1394b: bool) -> () = dc1394(dev)?.set_operation_mode(b1394b);
        getOperationModeDC1394RPC() -> bool = dc1394(dev)?.operation_mode();
        setTransmissionDC1394RPC(tx_on: bool) -> () = dc1394(dev)?.set_transmission(tx_on);
        getTransmissionDC1394RPC() -> bool = dc1394(dev)?.transmission();
        setBroadcastDC1394RPC(onoff: bool) -> () = dc1394(dev)?.set_broadcast(onoff);
        setDefaultsDC1394RPC() -> () = dc1394(dev)?.set_defaults();
        setResetDC1394RPC() -> () = dc1394(dev)?.set_reset();
        setPowerDC1394RPC(onoff: bool) -> () = dc1394(dev)?.set_power(onoff);
        setCaptureDC1394RPC(on: bool) -> () = dc1394(dev)?.set_capture(on);
        getBytesPerPacketDC1394RPC() -> i32 = dc1394(dev)?.bytes_per_packet().map(int);
        setBytesPerPacketDC1394RPC(bpp: i32) -> () = dc1394(dev)?.set_bytes_per_packet(bpp as u32);
    }
}

/// Whether `cmd` is a call of this service (its first word one of its methods, or
/// `getRemoteProtocolVersion`), rather than a 3.12 vocab command.
pub fn is_call(cmd: &yarp_proto::Bottle) -> bool {
    crate::thrift::is_call_of(cmd, service::METHODS)
}

/// Answers a 4.0 call on `dev`: the reply bytes (`[fail]` for what the generated reader
/// does not accept).
pub fn handle_rpc(cmd: &yarp_proto::Bottle, dev: &mut dyn DeviceDriver) -> Vec<u8> {
    if crate::thrift::is_protocol_version_request(cmd) {
        return crate::thrift::protocol_version_reply(Generation::V4);
    }
    match service::Call::decode(cmd) {
        Some(call) => call.serve(dev),
        None => crate::thrift::fail_reply(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::framegrabber::fake::FakeFrameGrabber;
    use yarp_proto::Bottle;

    fn grabber() -> FakeFrameGrabber {
        let mut g = FakeFrameGrabber::new();
        g.open(&Property::from_config_text("width 64\nheight 48\n").unwrap())
            .unwrap();
        g
    }

    fn ask(dev: &mut dyn DeviceDriver, bytes: Vec<u8>) -> Bottle {
        let cmd = Bottle::decode(&bytes).unwrap();
        assert!(is_call(&cmd), "{cmd}");
        Bottle::decode(&handle_rpc(&cmd, dev)).unwrap()
    }

    #[test]
    fn calls_read_back_as_written() {
        let calls = [
            service::Call::getImageCropRPC {
                crop_type: 0,
                vertices: vec![Vertex(1, 2), Vertex(3, 4)],
            },
            service::Call::setRgbFOVRPC {
                horizontal: 1.5,
                vertical: 2.5,
            },
            service::Call::setActiveRPC {
                feature: 3,
                onoff: true,
            },
            service::Call::getFormat7WindowDC1394RPC {},
        ];
        for call in calls {
            let cmd = Bottle::decode(&call.encode()).unwrap();
            assert_eq!(service::Call::decode(&cmd), Some(call.clone()), "{cmd}");
        }
        // a missing or extra argument is no call
        assert_eq!(
            service::Call::decode(&Bottle::from_text("\"setRgbFOVRPC\" 1.0")),
            None
        );
        assert_eq!(
            service::Call::decode(&Bottle::from_text("\"getWidthRPC\" 1")),
            None
        );
        assert!(!is_call(&Bottle::from_text("[fgi] [get] [w]")));
    }

    #[test]
    fn served_as_cpp_serves() {
        let mut g = grabber();
        let r = ask(&mut g, service::getWidthRPC().bytes);
        assert_eq!(r.to_string(), "([ok]) 64");
        let req = service::getRgbResolutionRPC();
        let r = ask(&mut g, req.bytes.clone());
        assert_eq!(req.answer(&r, "test").unwrap(), (64, 48));
        let req = service::getImageRPC();
        let img = req.answer(&ask(&mut g, req.bytes.clone()), "test").unwrap();
        assert_eq!((img.width(), img.height()), (64, 48));
        let req = service::getImageCropRPC(0, vec![Vertex(0, 0), Vertex(9, 4)]);
        let img = req.answer(&ask(&mut g, req.bytes.clone()), "test").unwrap();
        assert_eq!((img.width(), img.height()), (10, 5));
        // C++ 4.0's fake's DC1394 values
        let req = service::getFPSDC1394RPC();
        assert_eq!(
            req.answer(&ask(&mut g, req.bytes.clone()), "test").unwrap(),
            13
        );
        // a device without the interface: C++ answers "not ready"
        struct Bare;
        impl DeviceDriver for Bare {
            fn open(&mut self, _: &Property) -> DevResult<()> {
                Ok(())
            }
        }
        let err = req
            .answer(&ask(&mut Bare, req.bytes.clone()), "test")
            .unwrap_err();
        assert!(matches!(err, DeviceError::NotReady(_)), "{err}");
        let bare = handle_rpc(
            &Bottle::decode(&service::setRgbMirroringRPC(true).bytes).unwrap(),
            &mut g,
        );
        assert_eq!(bare, crate::thrift::ReturnValue::Ok.bare(Generation::V4));
        let version = handle_rpc(&Bottle::from_text("getRemoteProtocolVersion"), &mut g);
        assert_eq!(
            crate::thrift::protocol_version_of(&version),
            Some((0, [4, 0, 0]))
        );
    }
}
