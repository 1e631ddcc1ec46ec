//! The RPC protocol of C++ 3.12 `rgbdSensor_nws_yarp` (its `RGBDSensorParser`, with the
//! `RgbVisualParams_Responder` and `DepthVisualParams_Responder`), as a pure function.
//!
//! The first vocab picks the interface: `[visr]` colour and `[visd]` depth visual
//! parameters (`[get] [h]|[w]|[fov]|[intp]|[res]`, and for depth `[acrc]`, `[clip]`),
//! `[rgdb]` the sensor (`[get] [stat]|[prot]|[mess]|[ext]`). Replies repeat the request
//! head with `[is]`; failures answer `[fail]`. The interface of this crate has no
//! setters, so `[set]` requests answer `<iface> [set] 0`, as C++ does when the device
//! refuses. Frame-grabber controls (`[fgc]`) are not offered by the RGB-D devices here
//! and answer `[fail]`.

use super::IRGBDSensor;
use crate::framegrabber::protocol::{
    FAILED, FOV, GET, HEIGHT, INTRINSIC_PARAM, IS, RESOLUTION, RGB_VISUAL_PARAMS, SET, WIDTH,
};
use yarp_proto::{Bottle, Value, Vocab32};

const fn v(s: &str) -> i32 {
    Vocab32::new(s).0
}

pub const DEPTH_VISUAL_PARAMS: i32 = v("visd");
pub const RGBD_SENSOR: i32 = v("rgdb");
pub const RGBD_PROTOCOL_VERSION: i32 = v("prot");
pub const ACCURACY: i32 = v("acrc");
pub const CLIP_PLANES: i32 = v("clip");
pub const EXTRINSIC_PARAM: i32 = v("ext");
pub const ERROR_MSG: i32 = v("mess");
pub const STATUS: i32 = v("stat");

/// C++ `RGBD_INTERFACE_PROTOCOL_VERSION_MAJOR` / `_MINOR`.
pub const PROTOCOL_VERSION: (i32, i32) = (1, 0);

/// C++ `Value::asVocab32` (strings count as their packed vocab).
fn vocab(cmd: &Bottle, i: usize) -> i32 {
    match cmd.get(i) {
        Some(Value::Vocab32(x)) => x.0,
        Some(Value::String(s)) => Vocab32::encode(s).0,
        _ => 0,
    }
}

fn head(r: &mut Bottle, iface: i32, what: i32) {
    r.push(Vocab32(iface)).push(Vocab32(what)).push(Vocab32(IS));
}

fn failed(r: &mut Bottle) {
    r.clear();
    r.push(Vocab32(FAILED));
}

/// Answers one RPC command for `dev` (`None`: nothing attached) as C++ would.
pub fn handle_rpc(cmd: &Bottle, dev: Option<&mut dyn IRGBDSensor>) -> Bottle {
    let mut r = Bottle::new();
    let Some(dev) = dev else {
        failed(&mut r);
        return r;
    };
    let iface = vocab(cmd, 0);
    match iface {
        RGB_VISUAL_PARAMS | DEPTH_VISUAL_PARAMS => visual(cmd, iface, dev, &mut r),
        RGBD_SENSOR if vocab(cmd, 1) == GET => sensor(cmd, dev, &mut r),
        _ => {}
    }
    if r.is_empty() {
        failed(&mut r);
    }
    r
}

fn visual(cmd: &Bottle, iface: i32, dev: &mut dyn IRGBDSensor, r: &mut Bottle) {
    let rgb = iface == RGB_VISUAL_PARAMS;
    let what = vocab(cmd, 2);
    match vocab(cmd, 1) {
        GET => match what {
            HEIGHT => {
                head(r, iface, what);
                r.push(if rgb {
                    dev.rgb_height()
                } else {
                    dev.depth_height()
                });
            }
            WIDTH => {
                head(r, iface, what);
                r.push(if rgb {
                    dev.rgb_width()
                } else {
                    dev.depth_width()
                });
            }
            RESOLUTION if rgb => {
                head(r, iface, what);
                r.push(dev.rgb_width()).push(dev.rgb_height());
            }
            FOV => {
                let fov = if rgb { dev.rgb_fov() } else { dev.depth_fov() };
                if let Ok((h, v)) = fov {
                    head(r, iface, what);
                    r.push(h).push(v);
                }
            }
            INTRINSIC_PARAM => {
                let p = if rgb {
                    dev.rgb_intrinsic_param()
                } else {
                    dev.depth_intrinsic_param()
                };
                if let Ok(p) = p {
                    head(r, iface, what);
                    r.push(Value::List(p.to_bottle()));
                }
            }
            ACCURACY if !rgb => {
                head(r, iface, what);
                r.push(dev.depth_accuracy().unwrap_or(0.0));
            }
            CLIP_PLANES if !rgb => {
                // C++ ignores the call's result here
                let (near, far) = dev.depth_clip_planes().unwrap_or((0.0, 0.0));
                head(r, iface, what);
                r.push(near).push(far);
            }
            _ => {}
        },
        SET => {
            r.push(Vocab32(iface)).push(Vocab32(SET)).push(0);
        }
        _ => {}
    }
}

fn sensor(cmd: &Bottle, dev: &mut dyn IRGBDSensor, r: &mut Bottle) {
    let what = vocab(cmd, 2);
    match what {
        EXTRINSIC_PARAM => {
            if let Ok(m) = dev.extrinsic_param() {
                // a yarp::sig::Matrix copied into the reply: rows, cols, the data
                head(r, RGBD_SENSOR, what);
                let data: Vec<Value> = m.iter().map(|&x| Value::Float64(x)).collect();
                r.push(4).push(4).push(Value::List(Bottle::from(data)));
            }
        }
        ERROR_MSG => {
            head(r, RGBD_SENSOR, what);
            r.push(dev.last_error_msg());
        }
        RGBD_PROTOCOL_VERSION => {
            head(r, RGBD_SENSOR, what);
            r.push(PROTOCOL_VERSION.0).push(PROTOCOL_VERSION.1);
        }
        STATUS => {
            head(r, RGBD_SENSOR, what);
            r.push(dev.sensor_status() as i32);
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rgbd::fake::FakeDepthCamera;
    use crate::DeviceDriver;
    use yarp_proto::Property;

    fn camera() -> FakeDepthCamera {
        let mut c = FakeDepthCamera::new();
        c.open(&Property::from_config_text("width 32\nheight 24\n").unwrap())
            .unwrap();
        c
    }

    fn ask(c: &mut FakeDepthCamera, text: &str) -> String {
        handle_rpc(&Bottle::from_text(text), Some(c)).to_string()
    }

    #[test]
    fn sizes_status_and_version() {
        let mut c = camera();
        assert_eq!(ask(&mut c, "[visr] [get] [w]"), "[visr] [w] [is] 32");
        assert_eq!(ask(&mut c, "[visd] [get] [h]"), "[visd] [h] [is] 24");
        assert_eq!(ask(&mut c, "[rgdb] [get] [stat]"), "[rgdb] [stat] [is] 2");
        assert_eq!(ask(&mut c, "[rgdb] [get] [prot]"), "[rgdb] [prot] [is] 1 0");
        let r = handle_rpc(&Bottle::from_text("[visd] [get] [intp]"), Some(&mut c));
        let p = r.get(3).and_then(Value::as_list).unwrap().to_string();
        assert!(p.contains("focalLengthX") && p.contains("plumb_bob"), "{p}");
        let r = handle_rpc(&Bottle::from_text("[rgdb] [get] [ext]"), Some(&mut c));
        assert_eq!(r.len(), 6);
        assert_eq!(r.get(5).and_then(Value::as_list).map(Bottle::len), Some(16));
    }

    #[test]
    fn failures() {
        let mut c = camera();
        for bad in [
            "",
            "[visr] [get] [zzz]",
            "[rgdb] [set] [stat]",
            "[fgc] [get]",
            "42",
        ] {
            assert_eq!(ask(&mut c, bad), "[fail]", "{bad}");
        }
        assert_eq!(ask(&mut c, "[visd] [set] [clip] 0.1 3"), "[visd] [set] 0");
        assert_eq!(
            handle_rpc(&Bottle::from_text("[visr] [get] [w]"), None).to_string(),
            "[fail]"
        );
    }
}
