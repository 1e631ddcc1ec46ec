//! The `mjpeg` carrier (C++ YARP's `mjpeg` plug-in, `src/carriers/mjpeg_carrier`): a
//! *pull* connection, the HTTP "motion JPEG" a web camera serves. The reading port (or a
//! web browser) connects to the writing one and asks for the stream; the writer answers
//! once, then sends each image compressed as a JPEG part of a multipart stream:
//!
//! ```text
//! reader  GET /?action=stream\n\n HTTP/1.1\nHost: 127.0.0.1\r\n\n   (C++'s exact bytes)
//! writer  HTTP/1.0 200 OK\r\n ... Content-Type: multipart/x-mixed-replace;boundary=boundarydonotcross\r\n
//!         \r\n--boundarydonotcross\r\n
//! writer  Content-Type: image/jpeg\r\nContent-Length: 5123\r\n\r\n<JPEG>\r\n--boundarydonotcross\r\n
//! ```
//!
//! The header's first 8 bytes, `GET /?ac`, pick the carrier (the http carrier leaves them
//! alone). An image's envelope travels as the JPEG's comment (`COM`) marker: the
//! envelope's text with its terminating NUL. Images are compressed as libjpeg does by
//! default (quality 75); the reader gets RGB images, or mono ones for grayscale JPEGs.
//!
//! Sans-I/O: [`RequestReader`] consumes the request on the writing side, [`StreamDecoder`]
//! turns the reader's received bytes into JPEG frames, [`encode_jpeg`]/[`decode_jpeg`]
//! convert YARP images.

use crate::image::{Image, PixelCode};
use crate::Stamp;

/// The carrier's 8 header bytes.
pub const HEADER: [u8; 8] = *b"GET /?ac";
/// The boundary between parts.
pub const BOUNDARY: &str = "boundarydonotcross";
/// What the writer answers to the request, boundary included (C++'s bytes).
pub const RESPONSE: &str = "HTTP/1.0 200 OK\r\n\
Connection: close\r\n\
Server: yarp/mjpeg_carrier/0.1\r\n\
Cache-Control: no-store, no-cache, must-revalidate, pre-check=0, post-check=0, max-age=0\r\n\
Pragma: no-cache\r\n\
Expires: Mon, 3 Jan 2000 12:34:56 GMT\r\n\
Content-Type: multipart/x-mixed-replace;boundary=boundarydonotcross\r\n\
\r\n\
--boundarydonotcross\r\n";
/// The largest JPEG part a reader accepts.
pub const MAX_FRAME: usize = 64 << 20;
/// The longest header line a reader keeps (longer ones are cut, as they carry nothing
/// the reader needs).
const MAX_LINE: usize = 4096;

/// Why a stream or an image could not be handled.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MjpegError {
    #[error("mjpeg part of {0} bytes is larger than the {MAX_FRAME} accepted")]
    TooLarge(usize),
    #[error("mjpeg cannot send pixel code {0}: only mono, rgb, rgba, bgra and bgr images")]
    UnsupportedPixel(String),
    #[error("image of {0}x{1} pixels is too large for a JPEG")]
    TooWide(usize, usize),
    #[error("not an image: {0}")]
    NotAnImage(String),
    #[error("JPEG encoding failed: {0}")]
    Encode(String),
    #[error("JPEG decoding failed: {0}")]
    Decode(String),
}

/// The request a reading port sends when it connects (C++ `MjpegCarrier::sendHeader`,
/// byte for byte, odd line breaks included): `path` is the carrier's `path` modifier.
pub fn request(path: Option<&str>, host: &str) -> Vec<u8> {
    let mut out = match path {
        Some(p) if !p.is_empty() => format!("GET /{p}"),
        _ => "GET /?action=stream\n\n".to_string(),
    };
    out.push_str(" HTTP/1.1\n");
    if !host.is_empty() {
        out.push_str("Host: ");
        out.push_str(host);
        out.push_str("\r\n");
    }
    out.push('\n');
    out.into_bytes()
}

/// The bytes around one JPEG part: what goes before it and after it.
pub fn part_framing(jpeg_len: usize) -> (String, String) {
    (
        format!("Content-Type: image/jpeg\r\nContent-Length: {jpeg_len}\r\n\r\n"),
        format!("\r\n--{BOUNDARY}\r\n"),
    )
}

/// Line splitting as YARP's `InputStream::readLine`: up to `\n`, `\r` dropped.
#[derive(Debug, Default)]
struct Lines {
    buf: Vec<u8>,
}

impl Lines {
    /// The next whole line in `input` (consumed from it), if there is one.
    fn next(&mut self, input: &mut Vec<u8>) -> Option<String> {
        let end = input.iter().position(|&b| b == b'\n');
        let take = end.map_or(input.len(), |e| e + 1);
        for &b in &input[..take] {
            if b != b'\n' && b != b'\r' && self.buf.len() < MAX_LINE {
                self.buf.push(b);
            }
        }
        input.drain(..take);
        end.map(|_| String::from_utf8_lossy(&std::mem::take(&mut self.buf)).into_owned())
    }
}

/// The writing side's view of a new connection after its 8 header bytes: the rest of the
/// request, read line by line until an empty one (C++ `expectExtraHeader`). Whatever the
/// reader sends after that is ignored.
#[derive(Debug, Default)]
pub struct RequestReader {
    lines: Lines,
    done: bool,
}

impl RequestReader {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds received bytes; true once the request has ended.
    pub fn feed(&mut self, bytes: &[u8]) -> bool {
        let mut input = bytes.to_vec();
        while !self.done {
            match self.lines.next(&mut input) {
                Some(line) if line.is_empty() => self.done = true,
                Some(_) => {}
                None => break,
            }
        }
        self.done
    }
}

/// What the reading side gets from its stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StreamEvent {
    /// One JPEG image.
    Frame(Vec<u8>),
    /// A part that is not a JPEG, skipped (as C++ skips it with a warning).
    Skipped(String),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// The writer's HTTP answer, until an empty line.
    Reply,
    /// Until a boundary line (starting with `-`).
    Boundary,
    ContentType,
    ContentLength,
    /// Further part headers, until an empty line.
    PartHeaders(usize),
    Body(usize),
}

/// The reading side of an mjpeg stream (C++ `expectReplyToHeader` and `MjpegStream`).
#[derive(Debug)]
pub struct StreamDecoder {
    phase: Phase,
    input: Vec<u8>,
    lines: Lines,
}

impl Default for StreamDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl StreamDecoder {
    pub fn new() -> Self {
        StreamDecoder {
            phase: Phase::Reply,
            input: Vec::new(),
            lines: Lines::default(),
        }
    }

    pub fn feed(&mut self, bytes: &[u8]) {
        self.input.extend_from_slice(bytes);
    }

    /// The next event from what was fed; `Ok(None)` when more bytes are needed.
    pub fn poll(&mut self) -> Result<Option<StreamEvent>, MjpegError> {
        loop {
            if let Phase::Body(n) = self.phase {
                if self.input.len() < n {
                    return Ok(None);
                }
                let rest = self.input.split_off(n);
                let jpeg = std::mem::replace(&mut self.input, rest);
                self.phase = Phase::Boundary;
                return Ok(Some(StreamEvent::Frame(jpeg)));
            }
            let Some(line) = self.lines.next(&mut self.input) else {
                return Ok(None);
            };
            match self.phase {
                Phase::Reply if line.is_empty() => self.phase = Phase::Boundary,
                Phase::Reply => {}
                // the answer's last line is the first boundary
                Phase::Boundary if line.starts_with('-') => self.phase = Phase::ContentType,
                Phase::Boundary => {}
                Phase::ContentType if line == "Content-Type: image/jpeg" => {
                    self.phase = Phase::ContentLength
                }
                Phase::ContentType => {
                    self.phase = Phase::Boundary;
                    return Ok(Some(StreamEvent::Skipped(format!(
                        "unknown content type \"{line}\""
                    ))));
                }
                Phase::ContentLength => {
                    let mut words = line.split_whitespace();
                    let len = match (words.next(), words.next().map(str::parse::<usize>)) {
                        (Some("Content-Length:"), Some(Ok(n))) => n,
                        _ => {
                            self.phase = Phase::Boundary;
                            return Ok(Some(StreamEvent::Skipped(format!(
                                "expected Content-Length:, got \"{line}\""
                            ))));
                        }
                    };
                    if len > MAX_FRAME {
                        return Err(MjpegError::TooLarge(len));
                    }
                    self.phase = Phase::PartHeaders(len);
                }
                Phase::PartHeaders(n) if line.is_empty() => self.phase = Phase::Body(n),
                Phase::PartHeaders(_) => {}
                Phase::Body(_) => unreachable!("handled above"),
            }
        }
    }
}

/// The JPEG of an image, as C++ compresses it (libjpeg defaults: quality 75), with the
/// envelope's text (and its NUL) as the comment marker.
pub fn encode_jpeg(img: &Image, envelope: Option<&Stamp>) -> Result<Vec<u8>, MjpegError> {
    use jpeg_encoder::ColorType;
    let code = img.pixel_code();
    let (color, channels) = match code {
        c if c == PixelCode::MONO => (ColorType::Luma, 1),
        c if c == PixelCode::RGB => (ColorType::Rgb, 3),
        c if c == PixelCode::RGBA => (ColorType::Rgba, 4),
        c if c == PixelCode::BGRA => (ColorType::Bgra, 4),
        c if c == PixelCode::BGR => (ColorType::Bgr, 3),
        c => return Err(MjpegError::UnsupportedPixel(c.vocab().as_string())),
    };
    let (w, h) = (img.width(), img.height());
    let (Ok(w16), Ok(h16)) = (u16::try_from(w), u16::try_from(h)) else {
        return Err(MjpegError::TooWide(w, h));
    };
    if w == 0 || h == 0 {
        return Err(MjpegError::TooWide(w, h));
    }
    // the rows without their padding
    let row = w * channels;
    let mut pixels = Vec::with_capacity(row * h);
    for y in 0..h {
        pixels.extend_from_slice(&img.row(y)[..row]);
    }
    let mut out = Vec::with_capacity(row * h / 8 + 1024);
    jpeg_encoder::Encoder::new(&mut out, 75)
        .encode(&pixels, w16, h16, color)
        .map_err(|e| MjpegError::Encode(e.to_string()))?;
    if let Some(stamp) = envelope {
        let mut text = stamp.to_text().into_bytes();
        text.push(0);
        insert_comment(&mut out, &text);
    }
    Ok(out)
}

/// Puts a comment (`FF FE`) segment after the JFIF header, where libjpeg writes the
/// markers of `jpeg_write_marker`.
fn insert_comment(jpeg: &mut Vec<u8>, text: &[u8]) {
    let text = &text[..text.len().min(65533)];
    let mut at = 2; // after SOI
    if jpeg.get(2..4) == Some(&[0xFF, 0xE0]) {
        let len = jpeg
            .get(4..6)
            .map_or(0, |l| u16::from_be_bytes([l[0], l[1]]) as usize);
        at = (4 + len).min(jpeg.len());
    }
    let len = (text.len() + 2) as u16;
    let mut seg = vec![0xFF, 0xFE];
    seg.extend_from_slice(&len.to_be_bytes());
    seg.extend_from_slice(text);
    jpeg.splice(at..at, seg);
}

/// The first comment marker of a JPEG (before its image data), without trailing NULs.
fn comment(jpeg: &[u8]) -> Option<&[u8]> {
    let mut at = 2;
    while at + 4 <= jpeg.len() && jpeg[at] == 0xFF {
        let marker = jpeg[at + 1];
        if marker == 0xDA || marker == 0xD9 {
            return None; // start of scan / end of image: no comment before the data
        }
        let len = u16::from_be_bytes([jpeg[at + 2], jpeg[at + 3]]) as usize;
        let body = jpeg.get(at + 4..at + 2 + len.max(2))?;
        if marker == 0xFE {
            let end = body.iter().rposition(|&b| b != 0).map_or(0, |e| e + 1);
            return Some(&body[..end]);
        }
        at += 2 + len;
    }
    None
}

/// The image a JPEG holds (RGB, or mono for a grayscale JPEG, as C++'s reader gives it)
/// and the envelope its comment carries.
pub fn decode_jpeg(jpeg: &[u8]) -> Result<(Image, Option<Stamp>), MjpegError> {
    let mut d = jpeg_decoder::Decoder::new(jpeg);
    let pixels = d.decode().map_err(|e| MjpegError::Decode(e.to_string()))?;
    let info = d
        .info()
        .ok_or_else(|| MjpegError::Decode("no image header".into()))?;
    let (w, h) = (usize::from(info.width), usize::from(info.height));
    let (code, channels) = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => (PixelCode::MONO, 1),
        jpeg_decoder::PixelFormat::RGB24 => (PixelCode::RGB, 3),
        other => {
            return Err(MjpegError::Decode(format!(
                "{other:?} JPEGs are not read (only grayscale and colour)"
            )))
        }
    };
    if pixels.len() < w * h * channels {
        return Err(MjpegError::Decode(
            "fewer pixels than the image's size".into(),
        ));
    }
    let mut img = Image::new(code, w, h).map_err(|e| MjpegError::Decode(e.to_string()))?;
    let row = w * channels;
    for (y, src) in pixels.chunks_exact(row.max(1)).take(h).enumerate() {
        img.row_mut(y)[..row].copy_from_slice(src);
    }
    let stamp = comment(jpeg)
        .and_then(|c| std::str::from_utf8(c).ok())
        .and_then(Stamp::from_text);
    Ok((img, stamp))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient(code: PixelCode, w: usize, h: usize) -> Image {
        let mut img = Image::new(code, w, h).unwrap();
        for y in 0..h {
            for x in 0..w {
                for (c, v) in img.pixel_mut(x, y).iter_mut().enumerate() {
                    *v = ((x * 4 + y * 2 + c * 50) % 256) as u8;
                }
            }
        }
        img
    }

    #[test]
    fn the_request_is_cpps_bytes() {
        assert_eq!(
            request(None, "127.0.0.1"),
            b"GET /?action=stream\n\n HTTP/1.1\nHost: 127.0.0.1\r\n\n".to_vec()
        );
        assert_eq!(&request(None, "")[..8], &HEADER);
        assert_eq!(
            request(Some("?action=snapshot"), ""),
            b"GET /?action=snapshot HTTP/1.1\n\n".to_vec()
        );
        // the writer stops at the first empty line (C++ leaves the rest unread)
        let mut r = RequestReader::new();
        let req = request(None, "127.0.0.1");
        assert!(!r.feed(&req[8..12]));
        assert!(r.feed(&req[12..]));
    }

    #[test]
    fn a_stream_split_anywhere_gives_its_frames() {
        let mut wire = RESPONSE.as_bytes().to_vec();
        let frames: Vec<Vec<u8>> = vec![vec![0xFF, 0xD8, 1, 2, 3], (0..=255).collect(), vec![9]];
        for f in &frames {
            let (head, tail) = part_framing(f.len());
            wire.extend_from_slice(head.as_bytes());
            wire.extend_from_slice(f);
            wire.extend_from_slice(tail.as_bytes());
        }
        for chunk in [1, 7, 64, wire.len()] {
            let mut d = StreamDecoder::new();
            let mut got = Vec::new();
            for piece in wire.chunks(chunk) {
                d.feed(piece);
                while let Some(ev) = d.poll().unwrap() {
                    got.push(ev);
                }
            }
            let want: Vec<StreamEvent> = frames.iter().cloned().map(StreamEvent::Frame).collect();
            assert_eq!(got, want, "in pieces of {chunk}");
        }
    }

    #[test]
    fn parts_that_are_not_jpegs_are_skipped_and_lengths_bounded() {
        let mut d = StreamDecoder::new();
        d.feed(b"HTTP/1.0 200 OK\r\n\r\n--boundarydonotcross\r\nContent-Type: text/plain\r\n");
        assert!(matches!(d.poll(), Ok(Some(StreamEvent::Skipped(_)))));
        d.feed(b"--x\r\nContent-Type: image/jpeg\r\nContent-Length: many\r\n");
        assert!(matches!(d.poll(), Ok(Some(StreamEvent::Skipped(_)))));
        d.feed(b"--x\r\nContent-Type: image/jpeg\r\nContent-Length: 99999999999\r\n");
        assert!(matches!(d.poll(), Err(MjpegError::TooLarge(_))));
    }

    #[test]
    fn images_round_trip_with_their_envelope() {
        let stamp = Stamp::new(42, 1764234567.25);
        for code in [
            PixelCode::RGB,
            PixelCode::MONO,
            PixelCode::BGR,
            PixelCode::RGBA,
        ] {
            let img = gradient(code, 33, 17); // odd width: padded rows
            let jpeg = encode_jpeg(&img, Some(&stamp)).unwrap();
            assert_eq!(&jpeg[..2], &[0xFF, 0xD8]);
            let (back, env) = decode_jpeg(&jpeg).unwrap();
            assert_eq!(env, Some(stamp));
            assert_eq!((back.width(), back.height()), (33, 17));
            let want = if code == PixelCode::MONO {
                PixelCode::MONO
            } else {
                PixelCode::RGB
            };
            assert_eq!(back.pixel_code(), want);
            // lossy, but close: compare the first channel of a smooth region
            let a = img.pixel(10, 8)[0] as i32;
            let b = if code == PixelCode::BGR {
                back.pixel(10, 8)[2] as i32
            } else {
                back.pixel(10, 8)[0] as i32
            };
            assert!((a - b).abs() < 24, "{code:?}: {a} vs {b}");
        }
        let (_, none) =
            decode_jpeg(&encode_jpeg(&gradient(PixelCode::RGB, 8, 8), None).unwrap()).unwrap();
        assert_eq!(none, None);
    }

    #[test]
    fn what_jpeg_cannot_carry_is_an_error_never_a_panic() {
        let depth = Image::new(PixelCode::MONO_FLOAT, 4, 4).unwrap();
        assert!(matches!(
            encode_jpeg(&depth, None),
            Err(MjpegError::UnsupportedPixel(_))
        ));
        assert!(encode_jpeg(&Image::empty(PixelCode::RGB), None).is_err());
        for garbage in [
            &b""[..],
            b"\xFF\xD8",
            b"\xFF\xD8\xFF\xFE\x00",
            b"not a jpeg at all",
        ] {
            assert!(decode_jpeg(garbage).is_err());
            let _ = comment(garbage);
        }
    }
}
