//! YARP images (C++ `yarp::sig::FlexImage` on the wire) as `sensor_msgs/Image` (pure).
//!
//! A YARP image travels as a Bottle (C++ `ImageNetworkHeader` followed by the pixels):
//! `[mat] [<pixel code>] (depth imgSize quantum width height) {pixels}`. Rows are padded to
//! a multiple of `quantum` bytes; since YARP 3.5 the third int carries `quantum` in its low
//! 16 bits and "top is NOT the low index" in its high 16 bits.

use crate::convert::ConvertError;
use crate::counters::header;
use crate::dynmsg::Value as Ros;
use yarp_proto::{Bottle, Value, Vocab32};

/// A YARP pixel code and the ROS encoding it becomes (bytes per pixel).
const ENCODINGS: [(&str, &str, usize); 7] = [
    ("rgb", "rgb8", 3),
    ("bgr", "bgr8", 3),
    ("mono", "mono8", 1),
    ("mo16", "mono16", 2),
    ("rgba", "rgba8", 4),
    ("bgra", "bgra8", 4),
    // C++ `PixelFloat` (depth images in meters), as yarp-devices-ros2 names it.
    ("dec", "32FC1", 4),
];

/// Converts a YARP image Bottle (taken by value: the pixels move, not copy) into a
/// `sensor_msgs/msg/Image`.
pub fn to_ros(b: Bottle, frame_id: &str, stamp_ns: u64) -> Result<Ros, ConvertError> {
    let bad = |what: &str| ConvertError::Shape(format!("YARP image: {what}"));
    let mut items = b.into_items();
    if items.len() != 4 || items[0] != Value::Vocab32(Vocab32::encode("mat")) {
        return Err(bad("not [mat] [code] (params) {pixels}"));
    }
    let code = items[1].as_vocab().ok_or_else(|| bad("no pixel code"))?;
    let (_, encoding, depth) = ENCODINGS
        .iter()
        .find(|(c, ..)| Vocab32::encode(c) == code)
        .ok_or_else(|| {
            bad(&format!(
                "pixel code [{}] has no ROS encoding",
                code.as_string()
            ))
        })?;
    let params: Vec<i64> = items[2]
        .as_list()
        .map(|l| l.iter().filter_map(Value::as_i64).collect())
        .unwrap_or_default();
    let [d, size, q, w, h] = params[..] else {
        return Err(bad("parameters are not 5 integers"));
    };
    let (quantum, bottom_up) = (q & 0xffff, (q >> 16) & 0xffff == 1);
    let (w, h) = (
        usize::try_from(w).map_err(|_| bad("negative width"))?,
        usize::try_from(h).map_err(|_| bad("negative height"))?,
    );
    if d != *depth as i64 {
        return Err(bad(&format!("depth {d} for {encoding}")));
    }
    let row = w * depth;
    let step = if quantum > 1 {
        row.div_ceil(quantum as usize) * quantum as usize
    } else {
        row
    };
    let Some(Value::Blob(mut pixels)) = items.pop() else {
        return Err(bad("pixels are not a blob"));
    };
    if pixels.len() != step * h || size != pixels.len() as i64 {
        return Err(bad(&format!(
            "{} pixel bytes for {w}x{h}, step {step} (header says {size})",
            pixels.len()
        )));
    }
    if bottom_up && step > 0 {
        // Rows swap in place: no second image-sized buffer.
        for i in 0..h / 2 {
            let (top, bottom) = pixels.split_at_mut((h - 1 - i) * step);
            top[i * step..(i + 1) * step].swap_with_slice(&mut bottom[..step]);
        }
    }
    Ok(Ros::Struct(vec![
        header(stamp_ns, frame_id),
        Ros::U32(h as u32),
        Ros::U32(w as u32),
        Ros::Str((*encoding).to_string()),
        Ros::U8(0),
        Ros::U32(step as u32),
        Ros::Bytes(pixels),
    ]))
}

/// Converts a device's image (`yarp_proto::image::Image`, e.g. from `IFrameGrabberImage`
/// or `IRGBDSensor`) into a `sensor_msgs/msg/Image`.
pub fn from_image(
    img: &yarp_proto::image::Image,
    frame_id: &str,
    stamp_ns: u64,
) -> Result<Ros, ConvertError> {
    to_ros(img.to_bottle(), frame_id, stamp_ns)
}

/// Converts a `sensor_msgs/msg/Image` into a device image (rows packed, quantum 1): the
/// encodings of [`to_ros`] and `16UC1` (as `mono16`). Rows of `step` bytes may carry
/// padding after the pixels, which is dropped.
pub fn to_image(m: &Ros) -> Result<yarp_proto::image::Image, ConvertError> {
    use yarp_proto::image::{Image, PixelCode};
    let bad = |what: String| ConvertError::Shape(format!("ROS image: {what}"));
    let f = m.fields().ok_or_else(|| bad("not a message".into()))?;
    let (
        Some(Ros::U32(h)),
        Some(Ros::U32(w)),
        Some(Ros::Str(enc)),
        Some(Ros::U32(step)),
        Some(Ros::Bytes(data)),
    ) = (f.get(1), f.get(2), f.get(3), f.get(5), f.get(6))
    else {
        return Err(bad("not a sensor_msgs/Image".into()));
    };
    let enc = if enc == "16UC1" {
        "mono16"
    } else {
        enc.as_str()
    };
    let (code, _, depth) = ENCODINGS
        .iter()
        .find(|(_, e, _)| *e == enc)
        .ok_or_else(|| bad(format!("encoding {enc} has no YARP pixel code")))?;
    let (w, h, step) = (*w as usize, *h as usize, *step as usize);
    let row = w * depth;
    if step < row || data.len() < step * h.saturating_sub(1) + row {
        return Err(bad(format!(
            "{} bytes for {w}x{h} {enc}, step {step}",
            data.len()
        )));
    }
    let code = PixelCode(Vocab32::encode(code).0);
    let mut img = Image::with_layout(code, w, h, 1, true).map_err(|e| bad(e.to_string()))?;
    for y in 0..h {
        img.row_mut(y)
            .copy_from_slice(&data[y * step..y * step + row]);
    }
    Ok(img)
}

/// Builds the YARP image Bottle for `pixels` (rows of `width * depth` bytes, quantum 1),
/// as C++ writes it (tests, tools).
pub fn yarp_image(
    code: &str,
    depth: usize,
    width: usize,
    height: usize,
    pixels: Vec<u8>,
) -> Bottle {
    let mut params = Bottle::new();
    for v in [depth, pixels.len(), 1, width, height] {
        params.push(v as i32);
    }
    let mut b = Bottle::new();
    b.add_vocab("mat").add_vocab(code);
    b.push(params);
    b.push(Value::Blob(pixels));
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_image_with_its_layout() {
        let px: Vec<u8> = (0..2 * 3 * 3).map(|i| i as u8).collect();
        let b = yarp_image("rgb", 3, 3, 2, px.clone());
        // the Bottle's binary form starts like C++'s ImageNetworkHeader
        let wire = b.encode();
        assert_eq!(&wire[..8], &[0, 1, 0, 0, 4, 0, 0, 0], "list tag, 4 items");
        let m = to_ros(b, "cam", 5).unwrap();
        assert!(m.conforms_to("sensor_msgs/msg/Image"));
        let f = m.fields().unwrap();
        assert_eq!(
            f[1..6],
            [
                Ros::U32(2),
                Ros::U32(3),
                Ros::Str("rgb8".into()),
                Ros::U8(0),
                Ros::U32(9)
            ]
        );
        assert_eq!(f[6], Ros::Bytes(px));
    }

    #[test]
    fn padded_rows_and_bottom_up_images() {
        // mono 3x2 with quantum 4: rows of 4 bytes; high half of the quantum int = 1
        let mut params = Bottle::new();
        for v in [1, 8, 4 | (1 << 16), 3, 2] {
            params.push(v);
        }
        let mut b = Bottle::new();
        b.add_vocab("mat").add_vocab("mono");
        b.push(params);
        b.push(Value::Blob(vec![1, 2, 3, 0, 4, 5, 6, 0]));
        let m = to_ros(b, "", 0).unwrap();
        let f = m.fields().unwrap();
        assert_eq!(f[5], Ros::U32(4));
        assert_eq!(f[6], Ros::Bytes(vec![4, 5, 6, 0, 1, 2, 3, 0]));

        // an odd number of rows: the middle one stays
        let mut params = Bottle::new();
        for v in [1, 3, 1 | (1 << 16), 1, 3] {
            params.push(v);
        }
        let mut b = Bottle::new();
        b.add_vocab("mat").add_vocab("mono");
        b.push(params);
        b.push(Value::Blob(vec![1, 2, 3]));
        let m = to_ros(b, "", 0).unwrap();
        assert_eq!(m.fields().unwrap()[6], Ros::Bytes(vec![3, 2, 1]));
    }

    #[test]
    fn device_images_with_row_padding_and_float_depth() {
        use yarp_proto::image::{Image, PixelCode};
        let mut depth = Image::new(PixelCode::MONO_FLOAT, 3, 2).unwrap();
        depth.pixel_mut(2, 1).copy_from_slice(&1.5f32.to_ne_bytes());
        let m = from_image(&depth, "depth", 7).unwrap();
        assert!(m.conforms_to("sensor_msgs/msg/Image"));
        let f = m.fields().unwrap();
        assert_eq!(f[3], Ros::Str("32FC1".into()));
        let (Ros::U32(step), Ros::Bytes(px)) = (&f[5], &f[6]) else {
            panic!("{f:?}")
        };
        assert_eq!(px.len(), *step as usize * 2);
        let at = *step as usize + 8;
        assert_eq!(px[at..at + 4], 1.5f32.to_ne_bytes());
    }

    #[test]
    fn ros_images_back_to_device_images() {
        use yarp_proto::image::PixelCode;
        let px: Vec<u8> = (0..2 * 4).map(|i| i as u8).collect();
        // mono 3x2 with rows padded to 4 bytes
        let mut m = Ros::zero("sensor_msgs/msg/Image").unwrap();
        if let Ros::Struct(f) = &mut m {
            f[1] = Ros::U32(2);
            f[2] = Ros::U32(3);
            f[3] = Ros::Str("mono8".into());
            f[5] = Ros::U32(4);
            f[6] = Ros::Bytes(px);
        }
        let img = to_image(&m).unwrap();
        assert_eq!(
            (img.width(), img.height(), img.pixel_code()),
            (3, 2, PixelCode::MONO)
        );
        assert_eq!(
            (img.row(0), img.row(1)),
            (&[0u8, 1, 2][..], &[4u8, 5, 6][..])
        );
        let back = from_image(&img, "", 0).unwrap();
        assert_eq!(
            back.fields().unwrap()[6],
            Ros::Bytes(vec![0, 1, 2, 4, 5, 6])
        );
        if let Ros::Struct(f) = &mut m {
            f[3] = Ros::Str("yuv422".into());
        }
        assert!(to_image(&m).is_err());
    }

    #[test]
    fn inconsistent_images_are_errors() {
        let short = yarp_image("rgb", 3, 3, 2, vec![0; 17]);
        assert!(matches!(to_ros(short, "", 0), Err(ConvertError::Shape(_))));
        let odd = yarp_image("yuv", 3, 1, 1, vec![0; 3]);
        assert!(matches!(to_ros(odd, "", 0), Err(ConvertError::Shape(_))));
        let depth = yarp_image("mono", 3, 1, 1, vec![0; 3]);
        assert!(matches!(to_ros(depth, "", 0), Err(ConvertError::Shape(_))));
        assert!(to_ros(Bottle::from_text("1 2 3 4"), "", 0).is_err());
    }
}
