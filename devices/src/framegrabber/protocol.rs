//! The frame-grabber RPC protocol of C++ 3.12 `frameGrabber_nws_yarp` (its
//! `FrameGrabberOf_Responder`, `FrameGrabberControls_Responder` and
//! `RgbVisualParams_Responder`, behind a `DeviceResponder`), as a pure function.
//!
//! The first vocab picks the interface: `[fgi]` image, `[fgir]` raw image, `[fgc]`
//! controls, `[visr]` RGB visual parameters, `[fgfw]` DC1394 controls. Whatever leaves
//! the reply empty is answered `[nak]` (unknown interfaces, `[fgc] [set] ...`, failures
//! of `[fgc] [has|get]` with an unknown parameter). `[fgc] [has|get]` replies carry the
//! device's values even when the call failed, as C++ does (zeros here).

use super::image::Image;
use super::{IFrameGrabberControls, IFrameGrabberImage, IRgbVisualParams};
use crate::driver::DeviceDriver;
use yarp_proto::{Bottle, Value, Vocab32};

const fn v(s: &str) -> i32 {
    Vocab32::new(s).0
}

pub const FRAMEGRABBER_IMAGE: i32 = v("fgi");
pub const FRAMEGRABBER_IMAGERAW: i32 = v("fgir");
pub const FRAMEGRABBER_CONTROL: i32 = v("fgc");
pub const FRAMEGRABBER_CONTROL_DC1394: i32 = v("fgfw");
pub const RGB_VISUAL_PARAMS: i32 = v("visr");

pub const GET: i32 = v("get");
pub const SET: i32 = v("set");
pub const IS: i32 = v("is");
pub const FAILED: i32 = v("fail");
pub const NAK: i32 = v("nak");
pub const HEIGHT: i32 = v("h");
pub const WIDTH: i32 = v("w");
pub const RGB_IMAGE: i32 = v("imgr");
pub const CROP: i32 = v("crop");
pub const CROP_RECT: i32 = v("rect");
pub const CROP_LIST: i32 = v("list");

pub const CAMERA_DESCRIPTION: i32 = v("camd");
pub const HAS: i32 = v("has");
pub const FEATURE: i32 = v("feat");
pub const FEATURE2: i32 = v("fea2");
pub const ONOFF: i32 = v("onof");
pub const AUTO: i32 = v("auto");
pub const MANUAL: i32 = v("man");
pub const ONEPUSH: i32 = v("onep");
pub const ACTIVE: i32 = v("actv");
pub const MODE: i32 = v("mode");

pub const RESOLUTION: i32 = v("res");
pub const FOV: i32 = v("fov");
pub const INTRINSIC_PARAM: i32 = v("intp");
pub const SUPPORTED_CONF: i32 = v("conf");
pub const MIRROR: i32 = v("mirr");

/// C++ `Value::asVocab32` (strings count as their packed vocab).
fn vocab(cmd: &Bottle, i: usize) -> i32 {
    match cmd.get(i) {
        Some(Value::Vocab32(x)) => x.0,
        Some(Value::String(s)) => Vocab32::encode(s).0,
        _ => 0,
    }
}
fn int(cmd: &Bottle, i: usize) -> i32 {
    cmd.get(i).and_then(Value::as_i32).unwrap_or(0)
}
fn float(cmd: &Bottle, i: usize) -> f64 {
    cmd.get(i).and_then(Value::as_f64).unwrap_or(0.0)
}
fn vocabs(r: &mut Bottle, vs: &[i32]) {
    for &x in vs {
        r.push(Vocab32(x));
    }
}
fn fail_with(r: &mut Bottle, why: &str) {
    r.clear();
    r.push(Vocab32(FAILED)).push(why);
}

/// Answers one RPC command for `dev` as C++ `frameGrabber_nws_yarp` would.
pub fn handle_rpc(cmd: &Bottle, dev: &mut dyn DeviceDriver) -> Bottle {
    let mut reply = Bottle::new();
    match vocab(cmd, 0) {
        FRAMEGRABBER_IMAGE => match dev.as_frame_grabber_image() {
            Some(fg) => image(cmd, fg, &mut reply),
            None => fail_with(
                &mut reply,
                "Selected camera device has no IFrameGrabberImage interface",
            ),
        },
        // no device of this crate offers the raw (mono) grabber interface
        FRAMEGRABBER_IMAGERAW => fail_with(
            &mut reply,
            "Selected camera device has no IFrameGrabberImageRaw interface",
        ),
        FRAMEGRABBER_CONTROL => {
            if let Some(c) = dev.as_frame_grabber_controls() {
                controls(cmd, c, &mut reply);
            }
        }
        RGB_VISUAL_PARAMS => {
            match dev
                .as_frame_grabber_image()
                .and_then(|fg| fg.rgb_visual_params())
            {
                Some(vp) => visual(cmd, vp, &mut reply),
                None => {
                    reply.push(Vocab32(FAILED));
                }
            }
        }
        other => {
            tracing::debug!(
                "frameGrabber rpc: command not recognized: {cmd} ({})",
                Vocab32(other).as_string()
            );
        }
    }
    if reply.is_empty() {
        reply.push(Vocab32(NAK));
    }
    reply
}

fn image(cmd: &Bottle, fg: &mut dyn IFrameGrabberImage, r: &mut Bottle) {
    if vocab(cmd, 1) != GET {
        fail_with(r, "Received an unknown command");
        return;
    }
    match vocab(cmd, 2) {
        HEIGHT => {
            vocabs(r, &[FRAMEGRABBER_IMAGE, HEIGHT, IS]);
            r.push(fg.height() as i32);
        }
        WIDTH => {
            vocabs(r, &[FRAMEGRABBER_IMAGE, WIDTH, IS]);
            r.push(fg.width() as i32);
        }
        RGB_IMAGE => match fg.get_image() {
            Ok(img) if img.width() > 0 && img.height() > 0 => {
                vocabs(r, &[FRAMEGRABBER_IMAGE, RGB_IMAGE, IS]);
                r.push(Value::List(img.to_bottle()));
            }
            _ => fail_with(r, "Could not retrieve image from device."),
        },
        CROP => crop(cmd, fg, r),
        _ => {}
    }
}

/// `[fgi] [get] [crop] [rect] (x0 y0 x1 y1)`: the rectangle between two vertices,
/// both included.
fn crop(cmd: &Bottle, fg: &mut dyn IFrameGrabberImage, r: &mut Bottle) {
    if cmd.len() != 5 {
        return fail_with(r, "GetImageCrop failed: Invalid command received.");
    }
    let Some(list) = cmd.get(4).and_then(Value::as_list) else {
        return fail_with(r, "GetImageCrop failed: Empty vertices list received.");
    };
    let pts: Vec<i32> = list.iter().map(|v| v.as_i32().unwrap_or(0)).collect();
    match vocab(cmd, 3) {
        CROP_RECT => {
            if pts.len() / 2 != 2 {
                return fail_with(r, "GetImageCrop failed: RECT mode requires 2 vertices.");
            }
            let cut = fg
                .get_image()
                .ok()
                .and_then(|full| crop_rect(&full, (pts[0], pts[1]), (pts[2], pts[3])));
            match cut {
                Some(img) => {
                    vocabs(r, &[FRAMEGRABBER_IMAGE, CROP, IS]);
                    r.push(Value::List(img.to_bottle()));
                }
                None => fail_with(r, "GetImageCrop failed: utils::cropRect error."),
            }
        }
        CROP_LIST => fail_with(r, "List type not yet implemented"),
        _ => fail_with(r, "Crop type unknown"),
    }
}

/// C++ `utils::cropRect`: vertices inside the image, the second not left of / above the
/// first.
pub fn crop_rect(full: &Image, v0: (i32, i32), v1: (i32, i32)) -> Option<Image> {
    let inside = |(x, y): (i32, i32)| {
        x >= 0 && y >= 0 && (x as usize) < full.width() && (y as usize) < full.height()
    };
    if !inside(v0) || !inside(v1) || v1.0 < v0.0 || v1.1 < v0.1 {
        return None;
    }
    let (x0, y0) = (v0.0 as usize, v0.1 as usize);
    let (w, h) = (v1.0 as usize - x0 + 1, v1.1 as usize - y0 + 1);
    let mut out =
        Image::with_layout(full.pixel_code(), w, h, full.quantum(), full.top_is_low()).ok()?;
    let d = full.pixel_size();
    for y in 0..h {
        out.row_mut(y)
            .copy_from_slice(&full.row(y0 + y)[x0 * d..(x0 + w) * d]);
    }
    Some(out)
}

fn controls(cmd: &Bottle, c: &mut dyn IFrameGrabberControls, r: &mut Bottle) {
    let param = vocab(cmd, 2);
    let feature = int(cmd, 3);
    match vocab(cmd, 1) {
        HAS => {
            // C++ answers `[fgc] [has] [feat] <param as int> <bool>` for every `has`
            vocabs(r, &[FRAMEGRABBER_CONTROL, HAS, FEATURE]);
            r.push(param);
            let has = match param {
                FEATURE => c.has_feature(feature),
                ONOFF => c.has_on_off(feature),
                AUTO => c.has_auto(feature),
                MANUAL => c.has_manual(feature),
                ONEPUSH => c.has_one_push(feature),
                _ => {
                    r.clear();
                    return;
                }
            };
            r.push(i32::from(has.unwrap_or(false)));
        }
        SET => {
            // the reply stays empty (hence `[nak]`), whatever the outcome, as in C++
            let done = match param {
                FEATURE => c.set_feature(feature, float(cmd, 4)),
                FEATURE2 => c.set_feature2(feature, float(cmd, 4), float(cmd, 5)),
                ACTIVE => c.set_active(feature, int(cmd, 4) != 0),
                MODE => c.set_mode(feature, int(cmd, 4)),
                ONEPUSH => c.set_one_push(feature),
                _ => return,
            };
            if let Err(e) = done {
                tracing::debug!("frameGrabber rpc: {cmd}: {e}");
            }
        }
        GET => {
            vocabs(r, &[FRAMEGRABBER_CONTROL, param, IS]);
            match param {
                CAMERA_DESCRIPTION => {
                    let d = c.camera_description().unwrap_or_default();
                    r.push(d.bus_type).push(d.description.as_str());
                }
                FEATURE => {
                    r.push(c.get_feature(feature).unwrap_or(0.0));
                }
                FEATURE2 => {
                    let (a, b) = c.get_feature2(feature).unwrap_or((0.0, 0.0));
                    r.push(a).push(b);
                }
                ACTIVE => {
                    r.push(i32::from(c.get_active(feature).unwrap_or(false)));
                }
                MODE => {
                    r.push(c.get_mode(feature).unwrap_or(0));
                }
                _ => r.clear(),
            }
        }
        _ => {}
    }
}

fn visual(cmd: &Bottle, vp: &mut dyn IRgbVisualParams, r: &mut Bottle) {
    let what = vocab(cmd, 2);
    match vocab(cmd, 1) {
        GET => {
            let head = |r: &mut Bottle| vocabs(r, &[RGB_VISUAL_PARAMS, what, IS]);
            match what {
                HEIGHT => {
                    head(r);
                    r.push(vp.rgb_height());
                }
                WIDTH => {
                    head(r);
                    r.push(vp.rgb_width());
                }
                SUPPORTED_CONF => match vp.rgb_supported_configurations() {
                    Ok(confs) => {
                        head(r);
                        r.push(confs.len() as i32);
                        for c in confs {
                            r.push(c.width)
                                .push(c.height)
                                .push(c.framerate)
                                .push(c.pixel_code.vocab());
                        }
                    }
                    Err(_) => {
                        r.push(Vocab32(FAILED));
                    }
                },
                RESOLUTION => match vp.rgb_resolution() {
                    Ok((w, h)) => {
                        head(r);
                        r.push(w).push(h);
                    }
                    Err(_) => {
                        r.push(Vocab32(FAILED));
                    }
                },
                FOV => match vp.rgb_fov() {
                    Ok((hf, vf)) => {
                        head(r);
                        r.push(hf).push(vf);
                    }
                    Err(_) => {
                        r.push(Vocab32(FAILED));
                    }
                },
                INTRINSIC_PARAM => match vp.rgb_intrinsic_param() {
                    Ok(p) => {
                        head(r);
                        r.push(Value::List(p.to_bottle()));
                    }
                    Err(_) => {
                        r.push(Vocab32(FAILED));
                    }
                },
                MIRROR => match vp.rgb_mirroring() {
                    Ok(m) => {
                        head(r);
                        r.push(i32::from(m));
                    }
                    Err(_) => {
                        r.push(Vocab32(FAILED));
                    }
                },
                _ => {
                    r.push(Vocab32(FAILED));
                }
            }
        }
        SET => {
            let ok = match what {
                RESOLUTION => vp.set_rgb_resolution(int(cmd, 3), int(cmd, 4)),
                FOV => vp.set_rgb_fov(float(cmd, 3), float(cmd, 4)),
                MIRROR => {
                    vp.set_rgb_mirroring(cmd.get(3).and_then(Value::as_bool).unwrap_or(false))
                }
                _ => {
                    r.push(Vocab32(FAILED));
                    return;
                }
            };
            vocabs(r, &[RGB_VISUAL_PARAMS, SET]);
            r.push(i32::from(ok.is_ok()));
        }
        _ => {
            r.push(Vocab32(FAILED));
        }
    }
}
