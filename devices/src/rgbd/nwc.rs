//! `RGBDSensorClient` (C++ 3.12): an RGB-D camera served by `rgbdSensor_nws_yarp`, seen
//! as a local `IRGBDSensor`.
//!
//! Parameters, all as C++ (every port name is given in full): `localImagePort`,
//! `localDepthPort`, `localRpcPort`, `remoteImagePort`, `remoteDepthPort`,
//! `remoteRpcPort`; `ImageCarrier` and `DepthCarrier` (the streams' carriers, default
//! `udp`). At open the two streams are connected with their carriers, the RPC port to the
//! server, and the server's protocol version is asked (`[rgdb] [get] [prot]`): another
//! major version is refused, another minor one is logged, as C++ does.
//!
//! Images are the latest streamed ones (with their envelopes); sizes, fields of view,
//! intrinsics, depth accuracy and clip planes, extrinsics, status and the last error are
//! asked over RPC (`[visr]`, `[visd]`, `[rgdb]`, see [`super::protocol`]), or, with a
//! YARP 4.0 server (which answers the thrift `getRemoteProtocolVersion` that is asked
//! first, as 4.0's client does), through its `RGBDSensorMsgs` ([`super::v4`]), which
//! also sets resolutions, fields of view, accuracy, clip planes and mirroring. The
//! device answers to 4.0's names `RGBDSensor_nwc_yarp` and `rgbdSensor_nwc_yarp` too.

use super::protocol::{
    ACCURACY, CLIP_PLANES, DEPTH_VISUAL_PARAMS, ERROR_MSG, EXTRINSIC_PARAM, PROTOCOL_VERSION,
    RGBD_PROTOCOL_VERSION, RGBD_SENSOR, STATUS,
};
use super::v4::service as rgbd4;
use super::{IRGBDSensor, RgbdStatus};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::framegrabber::nwc::{reply_float, reply_int, request, ImageStream};
use crate::framegrabber::protocol::{FOV, GET, HEIGHT, INTRINSIC_PARAM, RGB_VISUAL_PARAMS, WIDTH};
use crate::framegrabber::CameraConfig;
use crate::runtime;
use crate::thrift::{Request, Wire4};
use std::sync::Arc;
use yarp_net::port::Port;
use yarp_proto::image::Image;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property, Stamp, Value};

pub(crate) const NAME: &str = "RGBDSensorClient";

crate::device_params! {
    /// What `RGBDSensorClient` reads (C++ `RGBDSensorClient_params.md`).
    pub struct RgbdSensorNwcYarpParams for "RGBDSensorClient" {
        /// refresh period (in s) of the broadcasted values through yarp ports
        period: f64 = 0.03; "s",
        /// Full name of the local image streaming port to open
        "localImagePort" local_image_port: String = required,
        /// Full name of the local depth streaming port to open
        "localDepthPort" local_depth_port: String = required,
        /// Full name of the remote image port to connect to
        "remoteImagePort" remote_image_port: String = required,
        /// Full name of the remote depth port to connect to
        "remoteDepthPort" remote_depth_port: String = required,
        /// Full name of the local rpc port to open
        "localRpcPort" local_rpc_port: String = required,
        /// Full name of the remote rpc port to connect to
        "remoteRpcPort" remote_rpc_port: String = required,
        /// Carrier for the image stream
        "ImageCarrier" image_carrier: String = "udp",
        /// Carrier for the depth stream
        "DepthCarrier" depth_carrier: String = "udp",
    }
}

/// The ports of an open client.
struct Client {
    rgb: ImageStream,
    depth: ImageStream,
    rpc: Arc<Port>,
    /// The server's generation of YARP: which protocol its RPC port speaks.
    generation: Generation,
}

impl Client {
    async fn close(self) {
        self.rgb.close().await;
        self.depth.close().await;
        if let Ok(p) = Arc::try_unwrap(self.rpc) {
            p.close().await;
        }
    }
}

/// The port names and carriers of the parameters.
struct Names {
    local_image: String,
    local_depth: String,
    local_rpc: String,
    remote_image: String,
    remote_depth: String,
    remote_rpc: String,
    image_carrier: String,
    depth_carrier: String,
}

impl Names {
    fn of(p: RgbdSensorNwcYarpParams) -> Names {
        Names {
            local_image: p.local_image_port,
            local_depth: p.local_depth_port,
            local_rpc: p.local_rpc_port,
            remote_image: p.remote_image_port,
            remote_depth: p.remote_depth_port,
            remote_rpc: p.remote_rpc_port,
            image_carrier: p.image_carrier,
            depth_carrier: p.depth_carrier,
        }
    }
}

async fn open_client(n: Names) -> Result<Client, String> {
    let ns = yarp_net::network::name_client().map_err(|e| e.to_string())?;
    let rgb =
        ImageStream::open(NAME, &ns, &n.local_image, &n.remote_image, &n.image_carrier).await?;
    let depth =
        match ImageStream::open(NAME, &ns, &n.local_depth, &n.remote_depth, &n.depth_carrier).await
        {
            Ok(d) => d,
            Err(e) => {
                rgb.close().await;
                return Err(e);
            }
        };
    let rpc = match Port::open(&n.local_rpc, ns).await {
        Ok(p) => p,
        Err(e) => {
            rgb.close().await;
            depth.close().await;
            return Err(format!("{}: {e}", n.local_rpc));
        }
    };
    if let Err(e) = rpc.connect(&n.remote_rpc, None).await {
        rpc.close().await;
        rgb.close().await;
        depth.close().await;
        return Err(format!(
            "connecting {} to {}: {e}",
            n.local_rpc, n.remote_rpc
        ));
    }
    // 4.0's server does not answer 3.12's `[rgdb] [get] [prot]`: ask 4.0's way first
    let asked = tokio::time::timeout(
        crate::nwc_ports::RPC_TIMEOUT,
        rpc.rpc_encoded(crate::thrift::protocol_version_request()),
    )
    .await;
    let generation = match asked {
        Ok(Err(yarp_net::port::PortError::BadReply { bytes, .. })) => {
            crate::thrift::protocol_version_of(&bytes).map_or(Generation::V3, |(_, v)| {
                crate::thrift::generation_of_version(v)
            })
        }
        _ => Generation::V3,
    };
    Ok(Client {
        rgb,
        depth,
        rpc: Arc::new(rpc),
        generation,
    })
}

/// The `RGBDSensorClient` device.
#[derive(Default)]
pub struct RgbdSensorClient {
    client: Option<Client>,
}

impl RgbdSensorClient {
    pub fn new() -> RgbdSensorClient {
        RgbdSensorClient::default()
    }

    fn client(&self) -> DevResult<&Client> {
        self.client.as_ref().ok_or(DeviceError::NotOpen)
    }
    /// Whether the server speaks YARP 4.0's `RGBDSensorMsgs`.
    fn four(&self) -> bool {
        self.client
            .as_ref()
            .is_some_and(|c| c.generation == Generation::V4)
    }
    /// A 4.0 call and what its reply says.
    fn ask<R: Wire4>(&self, req: Request<R>) -> DevResult<R> {
        let reply = crate::nwc_ports::call_encoded_within(
            NAME,
            &self.client()?.rpc,
            req.bytes.clone(),
            req.name,
            crate::nwc_ports::RPC_TIMEOUT,
        )?;
        req.answer(&reply, NAME)
    }
    /// A setter: 4.0's servers take it; 3.12's protocol has no answer worth the name.
    fn set4(&self, req: Request<()>, what: &'static str) -> DevResult<()> {
        if self.four() {
            self.ask(req)
        } else {
            Err(DeviceError::Unsupported(what))
        }
    }

    fn call(&self, iface: i32, what: i32) -> DevResult<Bottle> {
        crate::nwc_ports::call(NAME, &self.client()?.rpc, request(iface, GET, what, &[]))
    }

    fn int(&self, iface: i32, what: i32) -> DevResult<i32> {
        reply_int(&self.call(iface, what)?, 3)
    }

    fn pair(&self, iface: i32, what: i32) -> DevResult<(f64, f64)> {
        let r = self.call(iface, what)?;
        Ok((reply_float(&r, 3)?, reply_float(&r, 4)?))
    }

    fn intrinsics(&self, iface: i32) -> DevResult<Property> {
        let r = self.call(iface, INTRINSIC_PARAM)?;
        reply_int(&r, 0).ok(); // a refusal is reported by the line below
        r.get(3)
            .and_then(Value::as_list)
            .map(Property::from_bottle)
            .ok_or_else(|| malformed(&r))
    }

    fn image(&self, depth: bool) -> DevResult<(Image, Stamp)> {
        let c = self.client()?;
        let stream = if depth { &c.depth } else { &c.rgb };
        stream
            .latest(|l| Some((l.image.clone()?, l.stamp.unwrap_or(Stamp::new(0, 0.0)))))
            .ok_or(DeviceError::NotReady("no image received yet"))
    }
}

fn malformed(reply: &Bottle) -> DeviceError {
    DeviceError::failed(NAME, format!("unexpected reply {reply}"))
}

impl DeviceDriver for RgbdSensorClient {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        RgbdSensorNwcYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let names = Names::of(RgbdSensorNwcYarpParams::read(config)?);
        let remote = names.remote_rpc.clone();
        let client =
            runtime::block_on_result(open_client(names)).map_err(|got| DeviceError::BadParam {
                device: NAME.into(),
                param: "remoteRpcPort".into(),
                expected:
                    "the ports of a running rgbdSensor_nws_yarp (is the name server running?)",
                got,
            })?;
        self.close()?;
        self.client = Some(client);
        if self.four() {
            return Ok(());
        }
        let version = self.call(RGBD_SENSOR, RGBD_PROTOCOL_VERSION);
        let (major, minor) = match &version {
            Ok(r) => (reply_int(r, 3).unwrap_or(-1), reply_int(r, 4).unwrap_or(-1)),
            Err(_) => (-1, -1),
        };
        if major != PROTOCOL_VERSION.0 {
            self.close()?;
            return Err(DeviceError::failed(
                NAME,
                format!(
                    "major protocol number of {remote} does not match: expected {} received {major}{}",
                    PROTOCOL_VERSION.0,
                    version.err().map(|e| format!(" ({e})")).unwrap_or_default()
                ),
            ));
        }
        if minor != PROTOCOL_VERSION.1 {
            tracing::warn!("{NAME}: minor protocol number of {remote} does not match: expected {} received {minor}", PROTOCOL_VERSION.1);
        }
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(c) = self.client.take() {
            runtime::block_on_logged("nwc: closing", c.close());
        }
        Ok(())
    }

    crate::views!(as_rgbd_sensor);
}

impl Drop for RgbdSensorClient {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

impl IRGBDSensor for RgbdSensorClient {
    fn rgb_height(&mut self) -> i32 {
        if self.four() {
            return self.ask(rgbd4::getRgbHeightRPC()).unwrap_or(0);
        }
        self.int(RGB_VISUAL_PARAMS, HEIGHT).unwrap_or(0)
    }
    fn rgb_width(&mut self) -> i32 {
        if self.four() {
            return self.ask(rgbd4::getRgbWidthRPC()).unwrap_or(0);
        }
        self.int(RGB_VISUAL_PARAMS, WIDTH).unwrap_or(0)
    }
    fn depth_height(&mut self) -> i32 {
        if self.four() {
            return self.ask(rgbd4::getDepthHeightRPC()).unwrap_or(0);
        }
        self.int(DEPTH_VISUAL_PARAMS, HEIGHT).unwrap_or(0)
    }
    fn depth_width(&mut self) -> i32 {
        if self.four() {
            return self.ask(rgbd4::getDepthWidthRPC()).unwrap_or(0);
        }
        self.int(DEPTH_VISUAL_PARAMS, WIDTH).unwrap_or(0)
    }
    fn rgb_fov(&mut self) -> DevResult<(f64, f64)> {
        if self.four() {
            return self.ask(rgbd4::getRgbFOVRPC());
        }
        self.pair(RGB_VISUAL_PARAMS, FOV)
    }
    fn depth_fov(&mut self) -> DevResult<(f64, f64)> {
        if self.four() {
            return self.ask(rgbd4::getDepthFOVRPC());
        }
        self.pair(DEPTH_VISUAL_PARAMS, FOV)
    }
    fn rgb_intrinsic_param(&mut self) -> DevResult<Property> {
        if self.four() {
            return self.ask(rgbd4::getRgbIntrinsicParamRPC());
        }
        self.intrinsics(RGB_VISUAL_PARAMS)
    }
    fn depth_intrinsic_param(&mut self) -> DevResult<Property> {
        if self.four() {
            return self.ask(rgbd4::getDepthIntrinsicParamRPC());
        }
        self.intrinsics(DEPTH_VISUAL_PARAMS)
    }
    fn depth_accuracy(&mut self) -> DevResult<f64> {
        if self.four() {
            return self.ask(rgbd4::getDepthAccuracyRPC());
        }
        reply_float(&self.call(DEPTH_VISUAL_PARAMS, ACCURACY)?, 3)
    }
    fn depth_clip_planes(&mut self) -> DevResult<(f64, f64)> {
        if self.four() {
            return self.ask(rgbd4::getDepthClipPlanesRPC());
        }
        self.pair(DEPTH_VISUAL_PARAMS, CLIP_PLANES)
    }
    /// The server appends the matrix as rows, columns and the data list.
    fn extrinsic_param(&mut self) -> DevResult<[f64; 16]> {
        if self.four() {
            return self.ask(rgbd4::getExtrinsicParamRPC()).map(|m| m.0);
        }
        let r = self.call(RGBD_SENSOR, EXTRINSIC_PARAM)?;
        let (rows, cols) = (reply_int(&r, 3)?, reply_int(&r, 4)?);
        let data = r
            .get(5)
            .and_then(Value::as_list)
            .ok_or_else(|| malformed(&r))?;
        if (rows, cols) != (4, 4) || data.len() != 16 {
            return Err(malformed(&r));
        }
        let mut m = [0.0; 16];
        for (slot, v) in m.iter_mut().zip(data) {
            *slot = v.as_f64().ok_or_else(|| malformed(&r))?;
        }
        Ok(m)
    }
    fn get_rgb_image(&mut self) -> DevResult<(Image, Stamp)> {
        self.image(false)
    }
    fn get_depth_image(&mut self) -> DevResult<(Image, Stamp)> {
        self.image(true)
    }
    fn sensor_status(&mut self) -> RgbdStatus {
        if self.four() {
            return self
                .ask(rgbd4::getSensorStatusRPC())
                .map_or(RgbdStatus::GeneralError, RgbdStatus::from_code);
        }
        match self.int(RGBD_SENSOR, STATUS) {
            Ok(code) => RgbdStatus::from_code(code),
            Err(_) => RgbdStatus::GeneralError,
        }
    }
    fn last_error_msg(&mut self) -> String {
        if self.four() {
            return self
                .ask(rgbd4::getLastErrorMsgRPC())
                .map(|(m, _)| m)
                .unwrap_or_default();
        }
        self.call(RGBD_SENSOR, ERROR_MSG)
            .ok()
            .and_then(|r| r.get(3).and_then(Value::as_str).map(str::to_string))
            .unwrap_or_default()
    }
    fn rgb_resolution(&mut self) -> DevResult<(i32, i32)> {
        if self.four() {
            return self.ask(rgbd4::getRgbResolutionRPC());
        }
        Ok((self.rgb_width(), self.rgb_height()))
    }
    fn depth_resolution(&mut self) -> DevResult<(i32, i32)> {
        if self.four() {
            return self.ask(rgbd4::getDepthResolutionRPC());
        }
        Ok((self.depth_width(), self.depth_height()))
    }
    fn rgb_supported_configurations(&mut self) -> DevResult<Vec<CameraConfig>> {
        if self.four() {
            return self.ask(rgbd4::getRgbSupportedConfigurationsRPC());
        }
        Ok(Vec::new())
    }
    fn set_rgb_resolution(&mut self, width: i32, height: i32) -> DevResult<()> {
        self.set4(
            rgbd4::setRgbResolutionRPC(width, height),
            "setting the colour resolution",
        )
    }
    fn set_depth_resolution(&mut self, width: i32, height: i32) -> DevResult<()> {
        self.set4(
            rgbd4::setDepthResolutionRPC(width, height),
            "setting the depth resolution",
        )
    }
    fn set_rgb_fov(&mut self, horizontal: f64, vertical: f64) -> DevResult<()> {
        self.set4(
            rgbd4::setRgbFOVRPC(horizontal, vertical),
            "setting the colour field of view",
        )
    }
    fn set_depth_fov(&mut self, horizontal: f64, vertical: f64) -> DevResult<()> {
        self.set4(
            rgbd4::setDepthFOVRPC(horizontal, vertical),
            "setting the depth field of view",
        )
    }
    fn set_depth_accuracy(&mut self, accuracy: f64) -> DevResult<()> {
        self.set4(
            rgbd4::setDepthAccuracyRPC(accuracy),
            "setting the depth accuracy",
        )
    }
    fn set_depth_clip_planes(&mut self, near: f64, far: f64) -> DevResult<()> {
        self.set4(
            rgbd4::setDepthClipPlanesRPC(near, far),
            "setting the clip planes",
        )
    }
    fn rgb_mirroring(&mut self) -> DevResult<bool> {
        if self.four() {
            return self.ask(rgbd4::getRgbMirroringRPC());
        }
        Ok(false)
    }
    fn set_rgb_mirroring(&mut self, mirror: bool) -> DevResult<()> {
        self.set4(
            rgbd4::setRgbMirroringRPC(mirror),
            "mirroring the colour image",
        )
    }
    fn depth_mirroring(&mut self) -> DevResult<bool> {
        if self.four() {
            return self.ask(rgbd4::getDepthMirroringRPC());
        }
        Ok(false)
    }
    fn set_depth_mirroring(&mut self, mirror: bool) -> DevResult<()> {
        self.set4(
            rgbd4::setDepthMirroringRPC(mirror),
            "mirroring the depth image",
        )
    }
}
