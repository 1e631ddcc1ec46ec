//! YARP images (as a frame grabber sends them) to PNG, for the dashboard's camera view.
//!
//! Wire form (C++ `yarp::sig::Image`, Bottle-compatible): a list of 4 —
//! `[mat]`, the pixel code vocab (`[rgb]`, `[bgr]`, `[rgba]`, `[bgra]`, `[mono]`, `[mo16]`),
//! `(depth image_size quantum|origin<<16 width height)` and a blob of pixels, rows of
//! `image_size / height` bytes (padded to the quantum). Rows are shown in the order sent
//! (top first): the origin flag is ignored, as C++ 3.12 sends the same flag for every
//! ordinary image (see the framegrabber section of the yarp-vectors README).
//! The PNG is written uncompressed (stored deflate blocks): simple, and fast enough for a
//! few frames a second on localhost.

use yarp_proto::{Bottle, Value, Vocab32};

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ImageError {
    #[error("not a YARP image: {0}")]
    NotImage(&'static str),
    #[error("unsupported pixel code [{0}]")]
    PixelCode(String),
    #[error("image {width}x{height}: {why}")]
    BadSize {
        width: i64,
        height: i64,
        why: String,
    },
}

/// Pixels ready for PNG: 8-bit RGB or gray, top row first, no padding.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// 1 (gray) or 3 (RGB) bytes per pixel.
    pub channels: u8,
    pub pixels: Vec<u8>,
}

/// The largest image accepted (guards against absurd headers).
const MAX_PIXELS: i64 = 8192 * 8192;

/// Decodes an image Bottle into a [`Frame`].
pub fn decode(b: &Bottle) -> Result<Frame, ImageError> {
    let items: Vec<&Value> = (0..b.len()).filter_map(|i| b.get(i)).collect();
    if items.len() != 4 || items[0].as_vocab() != Some(Vocab32::encode("mat")) {
        return Err(ImageError::NotImage("expected [mat] code (header) pixels"));
    }
    let code = items[1]
        .as_vocab()
        .ok_or(ImageError::NotImage("pixel code is not a vocab"))?
        .as_string();
    let header = items[2]
        .as_list()
        .ok_or(ImageError::NotImage("header is not a list"))?;
    let h = |i: usize| header.get(i).and_then(Value::as_i64).unwrap_or(-1);
    let (depth, size, width, height) = (h(0), h(1), h(3), h(4));
    let data = items[3]
        .as_bytes()
        .ok_or(ImageError::NotImage("pixels are not a blob"))?;
    let bad = |why: String| ImageError::BadSize { width, height, why };
    if width <= 0 || height <= 0 || width * height > MAX_PIXELS {
        return Err(bad("size out of range".into()));
    }
    let (in_bpp, out_ch): (i64, u8) = match code.trim() {
        "rgb" | "bgr" => (3, 3),
        "rgba" | "bgra" => (4, 3),
        "mono" => (1, 1),
        "mo16" => (2, 1),
        other => return Err(ImageError::PixelCode(other.to_string())),
    };
    if depth != in_bpp {
        return Err(bad(format!("depth {depth} does not match [{code}]")));
    }
    let row = width * in_bpp;
    let stride = if size > 0 { size / height } else { row };
    if stride < row || (data.len() as i64) < stride * height {
        return Err(bad(format!(
            "{} pixel bytes, need {} rows of {row}",
            data.len(),
            height
        )));
    }
    let (w, hgt) = (width as usize, height as usize);
    let mut pixels = Vec::with_capacity(w * hgt * out_ch as usize);
    for y in 0..hgt {
        let start = y * stride as usize;
        let r = &data[start..start + row as usize];
        match code.trim() {
            "rgb" => pixels.extend_from_slice(r),
            "bgr" => r
                .chunks_exact(3)
                .for_each(|p| pixels.extend([p[2], p[1], p[0]])),
            "rgba" => r.chunks_exact(4).for_each(|p| pixels.extend(&p[..3])),
            "bgra" => r
                .chunks_exact(4)
                .for_each(|p| pixels.extend([p[2], p[1], p[0]])),
            "mono" => pixels.extend_from_slice(r),
            // Little-endian 16-bit: keep the high byte.
            _ => r.chunks_exact(2).for_each(|p| pixels.push(p[1])),
        }
    }
    Ok(Frame {
        width: width as u32,
        height: height as u32,
        channels: out_ch,
        pixels,
    })
}

fn crc32(chunks: &[&[u8]]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for data in chunks {
        for &b in *data {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
    }
    !crc
}

fn adler32(data: &[u8]) -> u32 {
    let (mut a, mut b) = (1u32, 0u32);
    for chunk in data.chunks(5552) {
        for &x in chunk {
            a += x as u32;
            b += a;
        }
        a %= 65521;
        b %= 65521;
    }
    (b << 16) | a
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend((data.len() as u32).to_be_bytes());
    out.extend(kind);
    out.extend(data);
    out.extend(crc32(&[kind, data]).to_be_bytes());
}

/// Encodes a frame as a PNG file (8-bit gray or RGB, stored deflate).
pub fn to_png(f: &Frame) -> Vec<u8> {
    let row = f.width as usize * f.channels as usize;
    let mut raw = Vec::with_capacity((row + 1) * f.height as usize);
    for r in f.pixels.chunks_exact(row.max(1)).take(f.height as usize) {
        raw.push(0); // filter: none
        raw.extend_from_slice(r);
    }
    let mut z = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = raw.chunks(65535).collect();
    for (i, b) in blocks.iter().enumerate() {
        z.push(u8::from(i + 1 == blocks.len()));
        z.extend((b.len() as u16).to_le_bytes());
        z.extend((!(b.len() as u16)).to_le_bytes());
        z.extend_from_slice(b);
    }
    if blocks.is_empty() {
        z.extend([1, 0, 0, 0xff, 0xff]);
    }
    z.extend(adler32(&raw).to_be_bytes());
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend(f.width.to_be_bytes());
    ihdr.extend(f.height.to_be_bytes());
    ihdr.extend([8, if f.channels == 1 { 0 } else { 2 }, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", &z);
    chunk(&mut out, b"IEND", &[]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(code: &str, depth: i32, w: i32, h: i32, top: bool, data: Vec<u8>) -> Bottle {
        let mut b = Bottle::new();
        b.add_vocab("mat");
        b.add_vocab(code);
        let hd = b.add_list();
        let packed = 8 | if top { 1 << 16 } else { 0 };
        for v in [depth, data.len() as i32, packed, w, h] {
            hd.push(v);
        }
        b.push(Value::Blob(data));
        b
    }

    #[test]
    fn rgb_bgr_mono() {
        let px: Vec<u8> = (0..2 * 2 * 3).collect();
        let f = decode(&image("rgb", 3, 2, 2, true, px.clone())).unwrap();
        assert_eq!(f.pixels, px);
        let f = decode(&image("bgr", 3, 2, 2, true, px.clone())).unwrap();
        assert_eq!(&f.pixels[..3], &[2, 1, 0]);
        let f = decode(&image("mono", 1, 2, 2, false, vec![1, 2, 3, 4])).unwrap();
        assert_eq!(f.pixels, [1, 2, 3, 4]);
        let f = decode(&image("mo16", 2, 1, 1, true, vec![0x34, 0x12])).unwrap();
        assert_eq!(f.pixels, [0x12]);
    }

    #[test]
    fn padded_rows() {
        // 1x2 rgb padded to 8 bytes per row.
        let mut data = vec![9, 9, 9, 0, 0, 0, 0, 0, 7, 7, 7, 0, 0, 0, 0, 0];
        let f = decode(&image("rgb", 3, 1, 2, true, std::mem::take(&mut data))).unwrap();
        assert_eq!(f.pixels, [9, 9, 9, 7, 7, 7]);
    }

    #[test]
    fn bad_images() {
        assert!(decode(&Bottle::from_text("1 2 3")).is_err());
        assert!(matches!(
            decode(&image("yuv", 3, 1, 1, true, vec![0; 3])),
            Err(ImageError::PixelCode(_))
        ));
        assert!(matches!(
            decode(&image("rgb", 3, 4, 4, true, vec![0; 3])),
            Err(ImageError::BadSize { .. })
        ));
        assert!(decode(&image("rgb", 1, 1, 1, true, vec![0; 3])).is_err());
    }

    #[test]
    fn png_layout() {
        let f = Frame {
            width: 2,
            height: 1,
            channels: 3,
            pixels: vec![255, 0, 0, 0, 255, 0],
        };
        let png = to_png(&f);
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(&png[12..16], b"IHDR");
        assert!(png.ends_with(&[0xae, 0x42, 0x60, 0x82]), "IEND crc");
        assert_eq!(adler32(b"Wikipedia"), 0x11E6_0398);
        assert_eq!(crc32(&[b"123456789"]), 0xCBF4_3926);
    }
}
