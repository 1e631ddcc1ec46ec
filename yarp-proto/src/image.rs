//! Images as C++ `yarp::sig::Image` / `ImageOf<P>` keep and send them.
//!
//! In memory an image is `height` rows of `row_size` bytes, each row holding `width`
//! pixels followed by padding up to a multiple of the row *quantum* (default 8 bytes).
//! On the wire (C++ `Image::write`) it is a Bottle-compatible list of four values:
//!
//! ```text
//! [mat] [<pixel code>] (depth image_size quantum|top_is_low<<16 width height) {pixels}
//! ```
//!
//! i.e. a fixed 60-byte header (C++ `ImageNetworkHeader`, fifteen little-endian int32,
//! the fifth int of the inner list packing two int16) followed by the raw rows, padding
//! included. `encode_image` / `decode_image` are pure functions over those bytes.
//!
//! YARP 4.0 dropped `topIsLow`: its third int is the quantum alone, where 3.x packs a
//! 1 above it, which a 4.0 reader would take for part of the quantum (and then find the
//! rows' size wrong). Readers of either generation read the quantum from the low half.

use crate::tags::Generation;
use crate::{Bottle, Value, Vocab32};
use thiserror::Error;

/// Row alignment C++ uses when none is asked for (`YARP_IMAGE_ALIGN`).
pub const DEFAULT_QUANTUM: usize = 8;
/// Size of the wire header before the pixel bytes.
pub const HEADER_LEN: usize = 60;

const TAG_INT32: i32 = 1;
const TAG_VOCAB32: i32 = 9;
const TAG_BLOB: i32 = 12;
const TAG_LIST: i32 = 256;
const VOCAB_MAT: i32 = Vocab32::new("mat").0;

/// A pixel type code (C++ `YarpVocabPixelTypesEnum`): a vocab naming the layout, or a
/// negative number `-n` for anonymous pixels of `n` bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PixelCode(pub i32);

impl PixelCode {
    pub const INVALID: PixelCode = PixelCode(0);
    pub const MONO: PixelCode = PixelCode::v("mono");
    pub const MONO16: PixelCode = PixelCode::v("mo16");
    pub const RGB: PixelCode = PixelCode::v("rgb");
    pub const RGBA: PixelCode = PixelCode::v("rgba");
    pub const BGRA: PixelCode = PixelCode::v("bgra");
    pub const INT: PixelCode = PixelCode::v("int");
    pub const HSV: PixelCode = PixelCode::v("hsv");
    pub const BGR: PixelCode = PixelCode::v("bgr");
    pub const MONO_SIGNED: PixelCode = PixelCode::v("sign");
    pub const RGB_SIGNED: PixelCode = PixelCode::v("rgb-");
    pub const RGB_INT: PixelCode = PixelCode::v("rgbi");
    pub const MONO_FLOAT: PixelCode = PixelCode::v("dec");
    pub const RGB_FLOAT: PixelCode = PixelCode::v("rgb.");
    pub const HSV_FLOAT: PixelCode = PixelCode::v("hsv.");
    pub const BAYER_GRBG8: PixelCode = PixelCode::v("grbg");
    pub const BAYER_GRBG16: PixelCode = PixelCode::v("gr16");
    pub const BAYER_BGGR8: PixelCode = PixelCode::v("bggr");
    pub const BAYER_BGGR16: PixelCode = PixelCode::v("bg16");
    pub const BAYER_GBRG8: PixelCode = PixelCode::v("gbrg");
    pub const BAYER_GBRG16: PixelCode = PixelCode::v("gb16");
    pub const BAYER_RGGB8: PixelCode = PixelCode::v("rggb");
    pub const BAYER_RGGB16: PixelCode = PixelCode::v("rg16");
    pub const YUV_420: PixelCode = PixelCode::v("yuva");
    pub const YUV_444: PixelCode = PixelCode::v("yuvb");
    pub const YUV_422: PixelCode = PixelCode::v("yuvc");
    pub const YUV_411: PixelCode = PixelCode::v("yuvd");

    const fn v(s: &str) -> PixelCode {
        PixelCode(Vocab32::new(s).0)
    }

    /// Bytes per pixel (C++ `Image::pixelCode2Size`); `None` for codes C++ does not know.
    pub fn pixel_size(self) -> Option<usize> {
        if self.0 < 0 {
            return usize::try_from(self.0.unsigned_abs()).ok();
        }
        let p = self;
        let size = if p == Self::MONO
            || p == Self::MONO_SIGNED
            || p == Self::BAYER_GRBG8
            || p == Self::BAYER_BGGR8
            || p == Self::BAYER_GBRG8
            || p == Self::BAYER_RGGB8
            || p == Self::YUV_420
            || p == Self::YUV_444
            || p == Self::YUV_422
            || p == Self::YUV_411
        {
            1
        } else if p == Self::MONO16
            || p == Self::BAYER_GRBG16
            || p == Self::BAYER_BGGR16
            || p == Self::BAYER_GBRG16
            || p == Self::BAYER_RGGB16
        {
            2
        } else if p == Self::RGB || p == Self::BGR || p == Self::HSV || p == Self::RGB_SIGNED {
            3
        } else if p == Self::RGBA || p == Self::BGRA || p == Self::INT || p == Self::MONO_FLOAT {
            4
        } else if p == Self::RGB_INT || p == Self::RGB_FLOAT || p == Self::HSV_FLOAT {
            12
        } else {
            return None;
        };
        Some(size)
    }

    /// The code as a vocab value (`[rgb]`).
    pub fn vocab(self) -> Vocab32 {
        Vocab32(self.0)
    }
}

/// Why image bytes (or an image Bottle) were rejected.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ImageError {
    #[error("image data too short: {got} bytes, need {need}")]
    Truncated { need: usize, got: usize },
    #[error("image header field `{field}` is {got}, expected {expected}")]
    BadHeader {
        field: &'static str,
        expected: i64,
        got: i64,
    },
    #[error("unknown pixel code {0} ({1:?})")]
    UnknownPixelCode(i32, String),
    #[error("pixel depth {depth} does not match pixel code {code:?} ({size} bytes)")]
    DepthMismatch {
        code: String,
        depth: i64,
        size: usize,
    },
    #[error("negative image dimension {width}x{height}")]
    NegativeSize { width: i64, height: i64 },
    #[error("image size {got} does not match {width}x{height}, {depth} bytes/pixel, quantum {quantum} (expected {expected})")]
    SizeMismatch {
        width: usize,
        height: usize,
        depth: usize,
        quantum: usize,
        expected: usize,
        got: i64,
    },
    #[error("image too large")]
    TooLarge,
    #[error("not an image Bottle: {0}")]
    NotAnImage(&'static str),
}

/// Bytes in a row of `width` pixels of `depth` bytes padded to `quantum`.
fn row_size(width: usize, depth: usize, quantum: usize) -> Option<usize> {
    let len = width.checked_mul(depth)?;
    let q = quantum.max(1);
    let rem = len % q;
    if rem == 0 {
        Some(len)
    } else {
        len.checked_add(q - rem)
    }
}

/// An image: pixel code, size, row layout and the raw rows (padding included).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    code: PixelCode,
    width: usize,
    height: usize,
    quantum: usize,
    top_is_low: bool,
    data: Vec<u8>,
}

impl Image {
    /// A zeroed image with the default quantum and top-left origin (C++ defaults).
    pub fn new(code: PixelCode, width: usize, height: usize) -> Result<Image, ImageError> {
        Image::with_layout(code, width, height, DEFAULT_QUANTUM, true)
    }

    /// A zeroed image with an explicit row quantum (0 means the default, as in C++) and
    /// origin.
    pub fn with_layout(
        code: PixelCode,
        width: usize,
        height: usize,
        quantum: usize,
        top_is_low: bool,
    ) -> Result<Image, ImageError> {
        let depth = code.pixel_size().ok_or_else(|| unknown_code(code.0))?;
        let quantum = if quantum == 0 {
            DEFAULT_QUANTUM
        } else {
            quantum
        };
        let size = row_size(width, depth, quantum)
            .and_then(|r| r.checked_mul(height))
            .filter(|&s| i32::try_from(s).is_ok())
            .ok_or(ImageError::TooLarge)?;
        Ok(Image {
            code,
            width,
            height,
            quantum,
            top_is_low,
            data: vec![0; size],
        })
    }

    /// An empty (0x0) image of the given pixel type, as a fresh C++ `ImageOf<P>`.
    pub fn empty(code: PixelCode) -> Image {
        Image {
            code,
            width: 0,
            height: 0,
            quantum: DEFAULT_QUANTUM,
            top_is_low: true,
            data: Vec::new(),
        }
    }

    pub fn pixel_code(&self) -> PixelCode {
        self.code
    }
    pub fn width(&self) -> usize {
        self.width
    }
    pub fn height(&self) -> usize {
        self.height
    }
    /// Bytes per pixel.
    pub fn pixel_size(&self) -> usize {
        self.code.pixel_size().unwrap_or(0)
    }
    /// Row alignment in bytes.
    pub fn quantum(&self) -> usize {
        self.quantum
    }
    /// Bytes per row, padding included.
    pub fn row_size(&self) -> usize {
        row_size(self.width, self.pixel_size(), self.quantum).unwrap_or(0)
    }
    /// Padding bytes at the end of each row.
    pub fn padding(&self) -> usize {
        self.row_size() - self.width * self.pixel_size()
    }
    /// Whether row 0 is the top of the picture (C++ `topIsLowIndex`).
    pub fn top_is_low(&self) -> bool {
        self.top_is_low
    }
    pub fn set_top_is_low(&mut self, on: bool) {
        self.top_is_low = on;
    }
    /// The raw rows, padding included (C++ `getRawImage`, `getRawImageSize` bytes).
    pub fn data(&self) -> &[u8] {
        &self.data
    }
    pub fn data_mut(&mut self) -> &mut [u8] {
        &mut self.data
    }
    /// The pixel bytes of row `y` (without padding). Like slice indexing, the pixel
    /// accessors panic when the coordinates are outside the image.
    pub fn row(&self, y: usize) -> &[u8] {
        let start = y * self.row_size();
        &self.data[start..start + self.width * self.pixel_size()]
    }
    pub fn row_mut(&mut self, y: usize) -> &mut [u8] {
        let start = y * self.row_size();
        let len = self.width * self.pixel_size();
        &mut self.data[start..start + len]
    }
    /// The bytes of pixel (x, y).
    pub fn pixel(&self, x: usize, y: usize) -> &[u8] {
        let d = self.pixel_size();
        &self.row(y)[x * d..(x + 1) * d]
    }
    pub fn pixel_mut(&mut self, x: usize, y: usize) -> &mut [u8] {
        let d = self.pixel_size();
        &mut self.row_mut(y)[x * d..(x + 1) * d]
    }
    /// Sets every byte to 0.
    pub fn zero(&mut self) {
        self.data.fill(0);
    }

    /// The image as the Bottle it travels as (what C++ `copyPortable(image, bottle)`
    /// gives, e.g. inside an `[fgi] [imgr]` reply).
    pub fn to_bottle(&self) -> Bottle {
        self.to_bottle_as(Generation::V3)
    }

    /// [`Image::to_bottle`] for a reader of `generation`.
    pub fn to_bottle_as(&self, generation: Generation) -> Bottle {
        let mut params = Bottle::with_capacity(5);
        let [d, s, q, w, h] = self.header_ints(generation);
        params.push(d).push(s).push(q).push(w).push(h);
        let mut b = Bottle::with_capacity(4);
        b.push(Vocab32(VOCAB_MAT))
            .push(self.code.vocab())
            .push(Value::List(params))
            .push(Value::Blob(self.data.clone()));
        b
    }

    /// Reads an image from its Bottle form, with the checks of [`decode_image`].
    pub fn from_bottle(b: &Bottle) -> Result<Image, ImageError> {
        if b.len() != 4 {
            return Err(ImageError::NotAnImage("expected 4 elements"));
        }
        if b.get(0).and_then(Value::as_vocab).map(|v| v.0) != Some(VOCAB_MAT) {
            return Err(ImageError::NotAnImage("first element is not [mat]"));
        }
        let code = match b.get(1) {
            Some(Value::Vocab32(v)) => v.0,
            Some(Value::Int32(i)) => *i,
            _ => return Err(ImageError::NotAnImage("second element is not a pixel code")),
        };
        let params = b
            .get(2)
            .and_then(Value::as_list)
            .filter(|l| l.len() == 5)
            .ok_or(ImageError::NotAnImage(
                "third element is not a list of 5 ints",
            ))?;
        let mut ints = [0i32; 5];
        for (slot, v) in ints.iter_mut().zip(params.iter()) {
            *slot = match v {
                Value::Int32(i) => *i,
                _ => return Err(ImageError::NotAnImage("image parameters must be int32")),
            };
        }
        let blob = match b.get(3) {
            Some(Value::Blob(d)) => d,
            _ => return Err(ImageError::NotAnImage("fourth element is not a blob")),
        };
        let h = Header::from_ints(code, ints, blob.len() as i64);
        h.build(blob)
    }

    /// The inner int list: depth, size, quantum (|top_is_low<<16 in 3.x), width, height.
    fn header_ints(&self, generation: Generation) -> [i32; 5] {
        // the wire field is 0 for "top is low" (YARP 3.4 compatibility); 4.0 has none
        let til: i32 = match (generation, self.top_is_low) {
            (Generation::V3, false) => 1,
            _ => 0,
        };
        let q = (self.quantum as i32) & 0xffff;
        [
            self.pixel_size() as i32,
            self.data.len() as i32,
            q | (til << 16),
            self.width as i32,
            self.height as i32,
        ]
    }
}

fn unknown_code(code: i32) -> ImageError {
    ImageError::UnknownPixelCode(code, Vocab32(code).as_string())
}

/// Encodes an image exactly as C++ `Image::write` puts it on the wire (header + rows).
pub fn encode_image(img: &Image) -> Vec<u8> {
    encode_image_as(img, Generation::V3)
}

/// [`encode_image`] as C++ YARP of `generation` writes it.
pub fn encode_image_as(img: &Image, generation: Generation) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_LEN + img.data.len());
    let [d, s, q, w, h] = img.header_ints(generation);
    for v in [
        TAG_LIST,
        4,
        TAG_VOCAB32,
        VOCAB_MAT,
        TAG_VOCAB32,
        img.code.0,
        TAG_LIST | TAG_INT32,
        5,
        d,
        s,
        q,
        w,
        h,
        TAG_BLOB,
        s,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&img.data);
    out
}

/// The parsed header fields, before validation.
struct Header {
    code: i32,
    depth: i32,
    size: i32,
    quantum_field: i32,
    width: i32,
    height: i32,
    blob_len: i64,
}

impl Header {
    fn from_ints(
        code: i32,
        [depth, size, quantum_field, width, height]: [i32; 5],
        blob_len: i64,
    ) -> Header {
        Header {
            code,
            depth,
            size,
            quantum_field,
            width,
            height,
            blob_len,
        }
    }

    /// Checks the header against the pixel bytes that follow and builds the image.
    fn build(&self, pixels: &[u8]) -> Result<Image, ImageError> {
        if self.width < 0 || self.height < 0 {
            return Err(ImageError::NegativeSize {
                width: self.width.into(),
                height: self.height.into(),
            });
        }
        let code = PixelCode(self.code);
        let depth = code.pixel_size().ok_or_else(|| unknown_code(self.code))?;
        if i64::from(self.depth) != depth as i64 {
            return Err(ImageError::DepthMismatch {
                code: Vocab32(self.code).as_string(),
                depth: self.depth.into(),
                size: depth,
            });
        }
        // low half: quantum; high half: 0 = top is low
        let quantum = (self.quantum_field & 0xffff) as usize;
        let top_is_low = (self.quantum_field >> 16) & 0xffff == 0;
        let quantum = if quantum == 0 {
            DEFAULT_QUANTUM
        } else {
            quantum
        };
        let (width, height) = (self.width as usize, self.height as usize);
        let expected = row_size(width, depth, quantum)
            .and_then(|r| r.checked_mul(height))
            .ok_or(ImageError::TooLarge)?;
        if i64::from(self.size) != expected as i64 {
            return Err(ImageError::SizeMismatch {
                width,
                height,
                depth,
                quantum,
                expected,
                got: self.size.into(),
            });
        }
        if self.blob_len != expected as i64 {
            return Err(ImageError::BadHeader {
                field: "blob length",
                expected: expected as i64,
                got: self.blob_len,
            });
        }
        if pixels.len() < expected {
            return Err(ImageError::Truncated {
                need: HEADER_LEN + expected,
                got: HEADER_LEN + pixels.len(),
            });
        }
        Ok(Image {
            code,
            width,
            height,
            quantum,
            top_is_low,
            data: pixels[..expected].to_vec(),
        })
    }
}

/// Decodes image bytes as C++ `Image::read` accepts them; malformed input (wrong tags,
/// unknown pixel code, sizes that disagree, missing pixels) is an error, never a panic.
/// Bytes after the image are ignored, as C++ does.
pub fn decode_image(bytes: &[u8]) -> Result<Image, ImageError> {
    if bytes.len() < HEADER_LEN {
        return Err(ImageError::Truncated {
            need: HEADER_LEN,
            got: bytes.len(),
        });
    }
    let mut f = [0i32; 15];
    for (i, slot) in f.iter_mut().enumerate() {
        let mut word = [0u8; 4];
        word.copy_from_slice(&bytes[i * 4..i * 4 + 4]);
        *slot = i32::from_le_bytes(word);
    }
    let fixed: [(&'static str, usize, i32); 8] = [
        ("list tag", 0, TAG_LIST),
        ("list length", 1, 4),
        ("name tag", 2, TAG_VOCAB32),
        ("name", 3, VOCAB_MAT),
        ("pixel code tag", 4, TAG_VOCAB32),
        ("parameter list tag", 6, TAG_LIST | TAG_INT32),
        ("parameter count", 7, 5),
        ("blob tag", 13, TAG_BLOB),
    ];
    for (field, i, want) in fixed {
        if f[i] != want {
            return Err(ImageError::BadHeader {
                field,
                expected: want.into(),
                got: f[i].into(),
            });
        }
    }
    let h = Header::from_ints(f[5], [f[8], f[9], f[10], f[11], f[12]], f[14].into());
    h.build(&bytes[HEADER_LEN..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padding_follows_quantum() {
        let img = Image::new(PixelCode::RGB, 3, 2).unwrap();
        assert_eq!(img.row_size(), 16);
        assert_eq!(img.padding(), 7);
        assert_eq!(img.data().len(), 32);
        let img = Image::with_layout(PixelCode::MONO, 5, 1, 1, true).unwrap();
        assert_eq!(img.row_size(), 5);
    }

    #[test]
    fn round_trip_with_padding() {
        let mut img = Image::new(PixelCode::BGR, 3, 2).unwrap();
        img.pixel_mut(2, 1).copy_from_slice(&[1, 2, 3]);
        img.set_top_is_low(false);
        let bytes = encode_image(&img);
        assert_eq!(bytes.len(), HEADER_LEN + 32);
        assert_eq!(decode_image(&bytes).unwrap(), img);
        let b = Bottle::decode(&bytes).unwrap();
        assert_eq!(b.encode(), bytes);
        assert_eq!(Image::from_bottle(&b).unwrap(), img);
        assert_eq!(img.to_bottle(), b);
    }

    #[test]
    fn pixel_sizes() {
        assert_eq!(PixelCode::RGB.0, 0x626772);
        assert_eq!(PixelCode::MONO16.pixel_size(), Some(2));
        assert_eq!(PixelCode::RGB_FLOAT.pixel_size(), Some(12));
        assert_eq!(PixelCode(-5).pixel_size(), Some(5));
        assert_eq!(PixelCode(7).pixel_size(), None);
    }

    #[test]
    fn malformed_rejected() {
        let img = Image::new(PixelCode::RGB, 4, 4).unwrap();
        let good = encode_image(&img);
        assert!(matches!(
            decode_image(&good[..10]),
            Err(ImageError::Truncated { .. })
        ));
        assert!(matches!(
            decode_image(&good[..good.len() - 1]),
            Err(ImageError::Truncated { .. })
        ));
        let mut bad = good.clone();
        bad[20..24].copy_from_slice(&7i32.to_le_bytes());
        assert!(matches!(
            decode_image(&bad),
            Err(ImageError::UnknownPixelCode(7, _))
        ));
        let mut bad = good.clone();
        bad[36..40].copy_from_slice(&1000i32.to_le_bytes());
        assert!(matches!(
            decode_image(&bad),
            Err(ImageError::SizeMismatch { .. })
        ));
        let mut bad = good.clone();
        bad[44..48].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(decode_image(&bad).is_err());
        let mut bad = good;
        bad[48..52].copy_from_slice(&(-1i32).to_le_bytes());
        assert!(matches!(
            decode_image(&bad),
            Err(ImageError::NegativeSize { .. })
        ));
    }
}
