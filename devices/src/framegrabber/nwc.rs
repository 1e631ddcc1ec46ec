//! `frameGrabber_nwc_yarp`: a camera on the network, seen as a local device.
//!
//! Parameters (C++ 3.12): `remote` (the server's port prefix, e.g. `/grabber`), `local`
//! (this client's prefix), `carrier` (for the image stream, default `fast_tcp`),
//! `no_stream` (ask for each image over RPC instead of streaming).
//!
//! Ports: `<local>` receives the stream from `<remote>` (connected by the server's
//! port, through its admin protocol, as C++ does); `<local>/rpc_client` talks to
//! `<remote>/rpc`. `height`/`width`/`get_image` come from the last streamed image;
//! controls and visual parameters are RPCs: 3.12's vocabs, built and read by the pure
//! functions below, or YARP 4.0's `FrameGrabberMsgs` ([`super::v4`]) when the server
//! answers `getRemoteProtocolVersion` as 4.0 does (a 3.12 server answers `[nak]`).

use super::image::{decode_image, Image};
use super::protocol::*;
use super::v4::service as fg4;
use super::{CameraConfig, CameraDescriptor, IFrameGrabberControls, IFrameGrabberImage};
use super::{IFrameGrabberControlsDC1394, IRgbVisualParams, PixelCode};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use crate::thrift::{Request, Wire4};
use parking_lot::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::port::{Incoming, Port};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property, Stamp, Value, Vocab32};

const NAME: &str = "frameGrabber_nwc_yarp";

crate::device_params! {
    /// What `frameGrabber_nwc_yarp` reads (C++ `FrameGrabber_nwc_yarp_params.md`).
    pub struct FrameGrabberNwcYarpParams for "frameGrabber_nwc_yarp" {
        /// Prefix of the ports opened locally by the nwc for streaming and rpc operations
        local: String = required,
        /// Name of the remote rpc port opened by the nws
        remote: String = required,
        /// Protocol used for connection with the nws streaming port
        carrier: String = "fast_tcp",
        /// if true, no streaming connection is made: images come by rpc
        no_stream: bool = false,
    }
}
/// How long an RPC to the server may take.
pub const RPC_TIMEOUT: Duration = Duration::from_secs(10);

/// `[iface] [verb] [what] args...`, the form of every request the C++ client sends.
pub fn request(iface: i32, verb: i32, what: i32, args: &[Value]) -> Bottle {
    let mut b = Bottle::with_capacity(3 + args.len());
    b.push(Vocab32(iface))
        .push(Vocab32(verb))
        .push(Vocab32(what));
    for a in args {
        b.push(a.clone());
    }
    b
}

fn refused(reply: &Bottle) -> bool {
    matches!(reply.get(0), Some(Value::Vocab32(v)) if v.0 == FAILED || v.0 == NAK)
        || reply.is_empty()
}

/// The server's `[fail]` (or a reply without what was asked): the peer is alive and
/// refused; the error carries its reply.
fn bad_reply(reply: &Bottle) -> DeviceError {
    DeviceError::Refused {
        device: NAME.into(),
        command: format!("a request (it replied `{reply}`)"),
    }
}

/// Element `i` of a reply as an int.
pub fn reply_int(reply: &Bottle, i: usize) -> DevResult<i32> {
    if refused(reply) {
        return Err(bad_reply(reply));
    }
    reply
        .get(i)
        .and_then(Value::as_i32)
        .ok_or_else(|| bad_reply(reply))
}

/// Element `i` of a reply as a float.
pub fn reply_float(reply: &Bottle, i: usize) -> DevResult<f64> {
    if refused(reply) {
        return Err(bad_reply(reply));
    }
    reply
        .get(i)
        .and_then(Value::as_f64)
        .ok_or_else(|| bad_reply(reply))
}

/// `[fgc] [camd] [is] <bus> "<description>"`.
pub fn parse_camera_description(reply: &Bottle) -> DevResult<CameraDescriptor> {
    Ok(CameraDescriptor {
        bus_type: reply_int(reply, 3)?,
        description: reply
            .get(4)
            .and_then(Value::as_str)
            .unwrap_or_default()
            .to_string(),
    })
}

/// `[visr] [conf] [is] n (w h fps code)*n`, flattened.
pub fn parse_configurations(reply: &Bottle) -> DevResult<Vec<CameraConfig>> {
    let n = usize::try_from(reply_int(reply, 3)?).map_err(|_| bad_reply(reply))?;
    if reply.len() < 4 + 4 * n {
        return Err(bad_reply(reply));
    }
    (0..n)
        .map(|k| {
            let at = 4 + 4 * k;
            Ok(CameraConfig {
                width: reply_int(reply, at)?,
                height: reply_int(reply, at + 1)?,
                framerate: reply_float(reply, at + 2)?,
                pixel_code: PixelCode(match reply.get(at + 3) {
                    Some(Value::Vocab32(v)) => v.0,
                    _ => reply_int(reply, at + 3)?,
                }),
            })
        })
        .collect()
}

/// The latest streamed image and its envelope.
#[derive(Default)]
pub(crate) struct Latest {
    pub image: Option<Image>,
    pub stamp: Option<Stamp>,
}

/// Reads one streamed message as an image.
fn image_of(msg: &Incoming) -> Result<Image, String> {
    if !msg.is_text && !msg.payload.is_empty() {
        return decode_image(&msg.payload).map_err(|e| e.to_string());
    }
    let b = msg.shared_bottle().map_err(|e| e.to_string())?;
    Image::from_bottle(&b).map_err(|e| e.to_string())
}

/// A port fed by a server's image stream, keeping the latest image (frameGrabber and
/// RGB-D clients).
pub(crate) struct ImageStream {
    port: Arc<Port>,
    task: tokio::task::JoinHandle<()>,
    latest: Arc<Mutex<Latest>>,
    rejected: Arc<AtomicU64>,
}

impl ImageStream {
    /// Opens `local` and has `remote` connect to it with `carrier`.
    pub(crate) async fn open(
        device: &'static str,
        ns: &NameClient,
        local: &str,
        remote: &str,
        carrier: &str,
    ) -> Result<ImageStream, String> {
        let port = Arc::new(
            Port::open(local, ns.clone())
                .await
                .map_err(|e| format!("{local}: {e}"))?,
        );
        let connected = yarp_net::network::connect(ns, remote, local, Some(carrier))
            .await
            .map_err(|e| e.to_string())
            .and_then(|(ok, msg)| if ok { Ok(()) } else { Err(msg) });
        if let Err(e) = connected {
            if let Ok(p) = Arc::try_unwrap(port) {
                p.close().await;
            }
            return Err(format!(
                "connecting {remote} to {local} with {carrier}: {e}"
            ));
        }
        let latest = Arc::new(Mutex::new(Latest::default()));
        let rejected = Arc::new(AtomicU64::new(0));
        let task = tokio::spawn(receive(
            device,
            port.clone(),
            latest.clone(),
            rejected.clone(),
        ));
        Ok(ImageStream {
            port,
            task,
            latest,
            rejected,
        })
    }

    /// `f` of the latest image and stamp.
    pub(crate) fn latest<R>(&self, f: impl FnOnce(&Latest) -> R) -> R {
        f(&self.latest.lock())
    }

    /// Streamed messages dropped because they were not valid images.
    pub(crate) fn rejected(&self) -> u64 {
        self.rejected.load(Ordering::Relaxed)
    }

    pub(crate) async fn close(self) {
        self.task.abort();
        let _ = self.task.await;
        if let Ok(p) = Arc::try_unwrap(self.port) {
            p.close().await;
        }
    }
}

struct Client {
    stream: Option<ImageStream>,
    rpc: Arc<Port>,
    /// The server's generation of YARP: which protocol its RPC port speaks.
    generation: Generation,
}

impl Client {
    async fn open(
        ns: NameClient,
        local: String,
        remote: String,
        carrier: String,
        no_stream: bool,
    ) -> Result<Client, String> {
        let stream = if no_stream {
            None
        } else {
            Some(ImageStream::open(NAME, &ns, &local, &remote, &carrier).await?)
        };
        let rpc_name = format!("{local}/rpc_client");
        let rpc = Port::open(&rpc_name, ns)
            .await
            .map_err(|e| format!("{rpc_name}: {e}"))?;
        rpc.connect(&format!("{remote}/rpc"), None)
            .await
            .map_err(|e| format!("connecting {rpc_name} to {remote}/rpc: {e}"))?;
        let asked = tokio::time::timeout(
            RPC_TIMEOUT,
            rpc.rpc_encoded(crate::thrift::protocol_version_request()),
        )
        .await
        .map_err(|_| format!("{remote}/rpc did not answer within {RPC_TIMEOUT:?}"))?;
        let generation = match asked {
            // 4.0's reply is no Bottle
            Err(yarp_net::port::PortError::BadReply { bytes, .. }) => {
                match crate::thrift::protocol_version_of(&bytes) {
                    Some((crate::thrift::PROTOCOL, v)) => crate::thrift::generation_of_version(v),
                    Some((p, v)) => {
                        return Err(format!(
                            "invalid communication protocol: {remote}/rpc (YARP {v:?}) speaks {p}"
                        ))
                    }
                    None => Generation::V3,
                }
            }
            Err(e) => return Err(format!("{remote}/rpc: {e}")),
            // 3.12's server answers `[nak]`
            Ok(_) => Generation::V3,
        };
        Ok(Client {
            stream,
            rpc: Arc::new(rpc),
            generation,
        })
    }

    async fn close(self) {
        if let Some(stream) = self.stream {
            stream.close().await;
        }
        if let Ok(p) = Arc::try_unwrap(self.rpc) {
            p.close().await;
        }
    }
}

async fn receive(
    device: &'static str,
    port: Arc<Port>,
    latest: Arc<Mutex<Latest>>,
    rejected: Arc<AtomicU64>,
) {
    while let Some(msg) = port.read().await {
        match image_of(&msg) {
            Ok(img) => {
                let mut l = latest.lock();
                l.image = Some(img);
                l.stamp = msg.stamp;
            }
            Err(e) => {
                rejected.fetch_add(1, Ordering::Relaxed);
                tracing::warn!("{device}: ignoring a message that is not an image: {e}");
            }
        }
    }
}

/// The `frameGrabber_nwc_yarp` device.
#[derive(Default)]
pub struct FrameGrabberNwc {
    client: Option<Client>,
}

impl FrameGrabberNwc {
    pub fn new() -> FrameGrabberNwc {
        FrameGrabberNwc::default()
    }

    /// Streamed messages dropped because they were not valid images.
    pub fn rejected_messages(&self) -> u64 {
        self.client
            .as_ref()
            .and_then(|c| c.stream.as_ref())
            .map_or(0, ImageStream::rejected)
    }

    fn rpc(&self, cmd: Bottle) -> DevResult<Bottle> {
        let port = self
            .client
            .as_ref()
            .ok_or(DeviceError::NotOpen)?
            .rpc
            .clone();
        crate::nwc_ports::call_within(NAME, &port, cmd, RPC_TIMEOUT)
    }

    /// Whether the server speaks YARP 4.0's `FrameGrabberMsgs`.
    fn four(&self) -> bool {
        self.client
            .as_ref()
            .is_some_and(|c| c.generation == Generation::V4)
    }

    /// A 4.0 call and what its reply says.
    fn ask<R: Wire4>(&self, req: Request<R>) -> DevResult<R> {
        let port = self
            .client
            .as_ref()
            .ok_or(DeviceError::NotOpen)?
            .rpc
            .clone();
        let reply = crate::nwc_ports::call_encoded_within(
            NAME,
            &port,
            req.bytes.clone(),
            req.name,
            RPC_TIMEOUT,
        )?;
        req.answer(&reply, NAME)
    }

    /// A DC1394 call: only a 4.0 server takes them.
    fn dc1394<R: Wire4>(&self, req: Request<R>) -> DevResult<R> {
        if self.four() {
            self.ask(req)
        } else {
            Err(DeviceError::Unsupported(
                "DC1394 settings through a YARP 3.12 frameGrabber_nws_yarp",
            ))
        }
    }

    fn streaming(&self) -> bool {
        self.client.as_ref().is_some_and(|c| c.stream.is_some())
    }

    fn latest<R>(&self, f: impl FnOnce(&Latest) -> R) -> Option<R> {
        Some(self.client.as_ref()?.stream.as_ref()?.latest(f))
    }

    fn visr(&self, verb: i32, what: i32, args: &[Value]) -> DevResult<Bottle> {
        self.rpc(request(RGB_VISUAL_PARAMS, verb, what, args))
    }

    fn fgc(&self, verb: i32, what: i32, feature: i32, extra: &[Value]) -> DevResult<Bottle> {
        let mut args = vec![Value::Int32(feature)];
        args.extend_from_slice(extra);
        self.rpc(request(FRAMEGRABBER_CONTROL, verb, what, &args))
    }

    /// `[fgc] [set] ...` is answered `[nak]` by C++ whatever happens: only the
    /// transport can fail.
    fn fgc_set(&self, what: i32, feature: i32, extra: &[Value]) -> DevResult<()> {
        self.fgc(SET, what, feature, extra).map(|_| ())
    }

    fn fgc_has(&self, what: i32, feature: i32) -> DevResult<bool> {
        Ok(reply_int(&self.fgc(HAS, what, feature, &[])?, 4)? != 0)
    }

    /// `[visr] [set] ...` answers `[visr] [set] <1|0>`.
    fn visr_set(&self, what: i32, args: &[Value]) -> DevResult<()> {
        match reply_int(&self.visr(SET, what, args)?, 2)? {
            0 => Err(DeviceError::Refused {
                device: NAME.into(),
                command: format!("[visr] [set] {}", Vocab32(what)),
            }),
            _ => Ok(()),
        }
    }
}

impl DeviceDriver for FrameGrabberNwc {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FrameGrabberNwcYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let FrameGrabberNwcYarpParams {
            local,
            remote,
            carrier,
            no_stream,
        } = FrameGrabberNwcYarpParams::read(config)?;
        let network = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "remote".into(),
            expected: "a running frameGrabber_nws_yarp prefix (is the name server running?)",
            got: e,
        };
        let ns = yarp_net::network::name_client().map_err(|e| network(e.to_string()))?;
        let client = runtime::block_on_result(Client::open(ns, local, remote, carrier, no_stream))
            .map_err(network)?;
        self.close()?;
        self.client = Some(client);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(c) = self.client.take() {
            runtime::block_on_logged("nwc: closing", c.close());
        }
        Ok(())
    }

    crate::views!(
        as_frame_grabber_image,
        as_frame_grabber_controls,
        as_frame_grabber_controls_dc1394
    );
}

impl Drop for FrameGrabberNwc {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

impl IFrameGrabberImage for FrameGrabberNwc {
    fn get_image(&mut self) -> DevResult<Image> {
        if self.client.is_none() {
            return Err(DeviceError::NotOpen);
        }
        if !self.streaming() && self.four() {
            return self.ask(fg4::getImageRPC());
        }
        if !self.streaming() {
            let reply = self.rpc(request(FRAMEGRABBER_IMAGE, GET, RGB_IMAGE, &[]))?;
            if refused(&reply) {
                return Err(bad_reply(&reply));
            }
            let b = reply
                .get(3)
                .and_then(Value::as_list)
                .ok_or_else(|| bad_reply(&reply))?;
            return Image::from_bottle(b).map_err(|e| {
                tracing::error!("{NAME}: bad image in RPC reply: {e}");
                DeviceError::failed(NAME, format!("the server sent a malformed image: {e}"))
            });
        }
        self.latest(|l| l.image.clone())
            .flatten()
            .ok_or(DeviceError::NotReady("no image received yet"))
    }

    fn height(&mut self) -> usize {
        if !self.streaming() && self.four() {
            return self
                .ask(fg4::getHeightRPC())
                .map_or(0, |v| v.max(0) as usize);
        }
        if !self.streaming() {
            let r = self.rpc(request(FRAMEGRABBER_IMAGE, GET, HEIGHT, &[]));
            return r
                .and_then(|r| reply_int(&r, 3))
                .map_or(0, |v| v.max(0) as usize);
        }
        self.latest(|l| l.image.as_ref().map_or(0, Image::height))
            .unwrap_or(0)
    }

    fn width(&mut self) -> usize {
        if !self.streaming() && self.four() {
            return self
                .ask(fg4::getWidthRPC())
                .map_or(0, |v| v.max(0) as usize);
        }
        if !self.streaming() {
            let r = self.rpc(request(FRAMEGRABBER_IMAGE, GET, WIDTH, &[]));
            return r
                .and_then(|r| reply_int(&r, 3))
                .map_or(0, |v| v.max(0) as usize);
        }
        self.latest(|l| l.image.as_ref().map_or(0, Image::width))
            .unwrap_or(0)
    }

    fn last_input_stamp(&mut self) -> Option<Stamp> {
        self.latest(|l| l.stamp).flatten()
    }

    fn rgb_visual_params(&mut self) -> Option<&mut dyn IRgbVisualParams> {
        Some(self)
    }
}

impl IRgbVisualParams for FrameGrabberNwc {
    fn rgb_height(&mut self) -> i32 {
        if self.four() {
            return self.ask(fg4::getRgbHeightRPC()).unwrap_or(0);
        }
        self.visr(GET, HEIGHT, &[])
            .and_then(|r| reply_int(&r, 3))
            .unwrap_or(0)
    }
    fn rgb_width(&mut self) -> i32 {
        if self.four() {
            return self.ask(fg4::getRgbWidthRPC()).unwrap_or(0);
        }
        self.visr(GET, WIDTH, &[])
            .and_then(|r| reply_int(&r, 3))
            .unwrap_or(0)
    }
    fn rgb_supported_configurations(&mut self) -> DevResult<Vec<CameraConfig>> {
        if self.four() {
            return self.ask(fg4::getRgbSupportedConfigurationsRPC());
        }
        parse_configurations(&self.visr(GET, SUPPORTED_CONF, &[])?)
    }
    fn rgb_resolution(&mut self) -> DevResult<(i32, i32)> {
        if self.four() {
            return self.ask(fg4::getRgbResolutionRPC());
        }
        let r = self.visr(GET, RESOLUTION, &[])?;
        Ok((reply_int(&r, 3)?, reply_int(&r, 4)?))
    }
    fn set_rgb_resolution(&mut self, width: i32, height: i32) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setRgbResolutionRPC(width, height));
        }
        self.visr_set(RESOLUTION, &[Value::Int32(width), Value::Int32(height)])
    }
    fn rgb_fov(&mut self) -> DevResult<(f64, f64)> {
        if self.four() {
            return self.ask(fg4::getRgbFOVRPC());
        }
        let r = self.visr(GET, FOV, &[])?;
        Ok((reply_float(&r, 3)?, reply_float(&r, 4)?))
    }
    fn set_rgb_fov(&mut self, horizontal: f64, vertical: f64) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setRgbFOVRPC(horizontal, vertical));
        }
        self.visr_set(FOV, &[Value::Float64(horizontal), Value::Float64(vertical)])
    }
    fn rgb_intrinsic_param(&mut self) -> DevResult<Property> {
        if self.four() {
            return self.ask(fg4::getRgbIntrinsicParamRPC());
        }
        let r = self.visr(GET, INTRINSIC_PARAM, &[])?;
        match r.get(3).and_then(Value::as_list) {
            Some(l) if !refused(&r) => Ok(Property::from_bottle(l)),
            _ => Err(bad_reply(&r)),
        }
    }
    fn rgb_mirroring(&mut self) -> DevResult<bool> {
        if self.four() {
            return self.ask(fg4::getRgbMirroringRPC());
        }
        Ok(reply_int(&self.visr(GET, MIRROR, &[])?, 3)? != 0)
    }
    fn set_rgb_mirroring(&mut self, mirror: bool) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setRgbMirroringRPC(mirror));
        }
        self.visr_set(MIRROR, &[Value::Int32(i32::from(mirror))])
    }
}

impl IFrameGrabberControls for FrameGrabberNwc {
    fn camera_description(&mut self) -> DevResult<CameraDescriptor> {
        if self.four() {
            return self.ask(fg4::getCameraDescriptionRPC());
        }
        let r = self.rpc(request(FRAMEGRABBER_CONTROL, GET, CAMERA_DESCRIPTION, &[]))?;
        parse_camera_description(&r)
    }
    fn has_feature(&mut self, feature: i32) -> DevResult<bool> {
        if self.four() {
            return self.ask(fg4::hasFeatureRPC(feature));
        }
        self.fgc_has(FEATURE, feature)
    }
    fn set_feature(&mut self, feature: i32, value: f64) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setFeature1RPC(feature, value));
        }
        self.fgc_set(FEATURE, feature, &[Value::Float64(value)])
    }
    fn get_feature(&mut self, feature: i32) -> DevResult<f64> {
        if self.four() {
            return self.ask(fg4::getFeature1RPC(feature));
        }
        reply_float(&self.fgc(GET, FEATURE, feature, &[])?, 3)
    }
    fn set_feature2(&mut self, feature: i32, v1: f64, v2: f64) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setFeature2RPC(feature, v1, v2));
        }
        self.fgc_set(FEATURE2, feature, &[Value::Float64(v1), Value::Float64(v2)])
    }
    fn get_feature2(&mut self, feature: i32) -> DevResult<(f64, f64)> {
        if self.four() {
            return self.ask(fg4::getFeature2RPC(feature));
        }
        let r = self.fgc(GET, FEATURE2, feature, &[])?;
        Ok((reply_float(&r, 3)?, reply_float(&r, 4)?))
    }
    fn has_on_off(&mut self, feature: i32) -> DevResult<bool> {
        if self.four() {
            return self.ask(fg4::hasOnOffRPC(feature));
        }
        self.fgc_has(ONOFF, feature)
    }
    fn set_active(&mut self, feature: i32, on: bool) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setActiveRPC(feature, on));
        }
        self.fgc_set(ACTIVE, feature, &[Value::Int32(i32::from(on))])
    }
    fn get_active(&mut self, feature: i32) -> DevResult<bool> {
        if self.four() {
            return self.ask(fg4::getActiveRPC(feature));
        }
        Ok(reply_int(&self.fgc(GET, ACTIVE, feature, &[])?, 3)? != 0)
    }
    fn has_auto(&mut self, feature: i32) -> DevResult<bool> {
        if self.four() {
            return self.ask(fg4::hasAutoRPC(feature));
        }
        self.fgc_has(AUTO, feature)
    }
    fn has_manual(&mut self, feature: i32) -> DevResult<bool> {
        if self.four() {
            return self.ask(fg4::hasManualRPC(feature));
        }
        self.fgc_has(MANUAL, feature)
    }
    fn has_one_push(&mut self, feature: i32) -> DevResult<bool> {
        if self.four() {
            return self.ask(fg4::hasOnePushRPC(feature));
        }
        self.fgc_has(ONEPUSH, feature)
    }
    fn set_mode(&mut self, feature: i32, mode: i32) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setModeRPC(feature, mode));
        }
        self.fgc_set(MODE, feature, &[Value::Int32(mode)])
    }
    fn get_mode(&mut self, feature: i32) -> DevResult<i32> {
        if self.four() {
            return self.ask(fg4::getModeRPC(feature));
        }
        reply_int(&self.fgc(GET, MODE, feature, &[])?, 3)
    }
    fn set_one_push(&mut self, feature: i32) -> DevResult<()> {
        if self.four() {
            return self.ask(fg4::setOnePushRPC(feature));
        }
        self.fgc_set(ONEPUSH, feature, &[])
    }
}

/// DC1394 settings: YARP 4.0's servers forward them; 3.12's `[fgfw]` responder reads
/// each argument from the wrong place, so they are not offered against 3.12.
impl IFrameGrabberControlsDC1394 for FrameGrabberNwc {
    fn video_mode_mask(&mut self) -> DevResult<u32> {
        self.dc1394(fg4::getVideoModeMaskDC1394RPC())
            .map(|v| v as u32)
    }
    fn video_mode(&mut self) -> DevResult<u32> {
        self.dc1394(fg4::getVideoModeDC1394RPC()).map(|v| v as u32)
    }
    fn set_video_mode(&mut self, mode: i32) -> DevResult<()> {
        self.dc1394(fg4::setVideoModeDC1394RPC(mode))
    }
    fn fps_mask(&mut self) -> DevResult<u32> {
        self.dc1394(fg4::getFPSMaskDC1394RPC()).map(|v| v as u32)
    }
    fn fps(&mut self) -> DevResult<u32> {
        self.dc1394(fg4::getFPSDC1394RPC()).map(|v| v as u32)
    }
    fn set_fps(&mut self, fps: i32) -> DevResult<()> {
        self.dc1394(fg4::setFPSDC1394RPC(fps))
    }
    fn iso_speed(&mut self) -> DevResult<u32> {
        self.dc1394(fg4::getISOSpeedDC1394RPC()).map(|v| v as u32)
    }
    fn set_iso_speed(&mut self, speed: i32) -> DevResult<()> {
        self.dc1394(fg4::setISOSpeedDC1394RPC(speed))
    }
    fn color_coding_mask(&mut self, video_mode: u32) -> DevResult<u32> {
        self.dc1394(fg4::getColorCodingMaskDC1394RPC(video_mode as i32))
            .map(|v| v as u32)
    }
    fn color_coding(&mut self) -> DevResult<u32> {
        self.dc1394(fg4::getColorCodingDC1394RPC())
            .map(|v| v as u32)
    }
    fn set_color_coding(&mut self, coding: i32) -> DevResult<()> {
        self.dc1394(fg4::setColorCodingDC1394RPC(coding))
    }
    fn format7_max_window(&mut self) -> DevResult<[u32; 6]> {
        self.dc1394(fg4::getFormat7MaxWindowDC1394RPC())
            .map(|w| w.map(|v| v as u32))
    }
    fn format7_window(&mut self) -> DevResult<(u32, u32, i32, i32)> {
        self.dc1394(fg4::getFormat7WindowDC1394RPC())
            .map(|[xd, yd, x0, y0]| (xd as u32, yd as u32, x0, y0))
    }
    fn set_format7_window(&mut self, xdim: u32, ydim: u32, x0: i32, y0: i32) -> DevResult<()> {
        self.dc1394(fg4::setFormat7WindowDC1394RPC(
            xdim as i32,
            ydim as i32,
            x0,
            y0,
        ))
    }
    fn operation_mode(&mut self) -> DevResult<bool> {
        self.dc1394(fg4::getOperationModeDC1394RPC())
    }
    fn set_operation_mode(&mut self, b1394b: bool) -> DevResult<()> {
        self.dc1394(fg4::setOperationModeDC1394RPC(b1394b))
    }
    fn transmission(&mut self) -> DevResult<bool> {
        self.dc1394(fg4::getTransmissionDC1394RPC())
    }
    fn set_transmission(&mut self, on: bool) -> DevResult<()> {
        self.dc1394(fg4::setTransmissionDC1394RPC(on))
    }
    fn set_broadcast(&mut self, on: bool) -> DevResult<()> {
        self.dc1394(fg4::setBroadcastDC1394RPC(on))
    }
    fn set_defaults(&mut self) -> DevResult<()> {
        self.dc1394(fg4::setDefaultsDC1394RPC())
    }
    fn set_reset(&mut self) -> DevResult<()> {
        self.dc1394(fg4::setResetDC1394RPC())
    }
    fn set_power(&mut self, on: bool) -> DevResult<()> {
        self.dc1394(fg4::setPowerDC1394RPC(on))
    }
    fn set_capture(&mut self, on: bool) -> DevResult<()> {
        self.dc1394(fg4::setCaptureDC1394RPC(on))
    }
    fn bytes_per_packet(&mut self) -> DevResult<u32> {
        self.dc1394(fg4::getBytesPerPacketDC1394RPC())
            .map(|v| v as u32)
    }
    fn set_bytes_per_packet(&mut self, bpp: u32) -> DevResult<()> {
        self.dc1394(fg4::setBytesPerPacketDC1394RPC(bpp as i32))
    }
}
