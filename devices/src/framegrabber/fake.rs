//! `fakeFrameGrabber`: a camera that draws test patterns (C++ `FakeFrameGrabber`).
//!
//! Parameters as in C++ 3.12: `width` (320), `height` (240), `period` / `freq` (frame
//! rate; neither means a new frame at every `get_image`), `mode` (`line`, `ball`, `grid`,
//! `size`, `rand`, `none`, `time`; also accepted as `[line]`...), `syncro`, `topIsLow`,
//! `mirror`, `add_timestamp`, `add_noise`, `snr`, `horizontalFov`, `verticalFov` and the
//! intrinsic parameters (`physFocalLength`, `focalLengthX`... `k1`..`t2`,
//! `distortionModel`, `rectificationMatrix`).
//!
//! Frames follow the clock as the C++ producer thread does: frame `n` is the one due
//! at `open + n * period`, and `get_image` returns the latest one due. The pattern
//! state (`Patterns`) is pure, so a test can step it frame by frame.

use super::image::{Image, PixelCode};
use super::IFrameGrabberControlsDC1394;
use super::{CameraConfig, CameraDescriptor, IFrameGrabberControls, IFrameGrabberImage};
use super::{IRgbVisualParams, MODE_UNKNOWN};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use yarp_proto::{Bottle, Property, Stamp, Value};

const NAME: &str = "fakeFrameGrabber";

crate::device_params! {
    /// What `fakeFrameGrabber` reads (C++ `FakeFrameGrabber_params.md`, and C++'s
    /// `topIsLow`; no background image, bayer or mono images here).
    pub struct FakeFrameGrabberParams for "fakeFrameGrabber" {
        /// desired width of test image
        width: usize = 320; in 1..=32768,
        /// desired height of test image
        height: usize = 240; in 1..=32768,
        /// desired horizontal fov of test image
        "horizontalFov" horizontal_fov: f64 = 1.0,
        /// desired vertical fov of test image
        "verticalFov" vertical_fov: f64 = 2.0,
        /// rpc port for the fakeFrameGrabber (accepted; a frameGrabber_nws_yarp serves it)
        "fakeFrameGrabber_rpc_port" rpc_port: String = "/fakeFrameGrabber/rpc",
        /// mirror height of test image
        mirror: bool = false,
        /// synchronize producer and consumer, so that all images are used once and only once
        syncro: bool = false,
        /// Physical focal length
        "physFocalLength" phys_focal_length: f64 = 3.0,
        /// Horizontal component of the focal length
        "focalLengthX" focal_length_x: f64 = 4.0,
        /// Vertical component of the focal length
        "focalLengthY" focal_length_y: f64 = 5.0,
        /// X coordinate of the principal point
        "principalPointX" principal_point_x: f64 = 6.0,
        /// Y coordinate of the principal point
        "principalPointY" principal_point_y: f64 = 7.0,
        /// Reference to group of parameters describing the distortion model of the camera
        "distortionModel" distortion_model: String = "FishEye",
        /// Radial distortion coefficient of the lens(fake)
        k1: f64 = 8.0,
        /// Radial distortion coefficient of the lens(fake)
        k2: f64 = 9.0,
        /// Radial distortion coefficient of the lens(fake)
        k3: f64 = 10.0,
        /// Tangential distortion of the lens(fake)
        t1: f64 = 11.0,
        /// Tangential distortion of the lens(fake)
        t2: f64 = 12.0,
        /// rate of test images in Hz
        freq: f64 = 0.0; "Hz",
        /// period of test images in seconds
        period: f64 = 0.0; "s",
        /// ball, line, grid, size, rand, none, time
        mode: String = "line",
        /// should write the timestamp in the first bytes of the image
        add_timestamp: bool = false,
        /// should add noise to the image (uses snr parameter)
        add_noise: bool = false,
        /// Signal noise ratio ([0.0-1.0]
        snr: f64 = 0.5,
        /// Matrix that describes the lens' distortion
        "rectificationMatrix" rectification_matrix: Vec<f64> = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        /// the image's first row is its top
        "topIsLow" top_is_low: bool = true,
        /// background image to use, if any (accepted; the patterns are drawn on black)
        src: String = optional,
        /// should emit bayer test image (accepted; the image stays RGB)
        bayer: bool = false,
        /// should emit a monochrome image (accepted; the image stays RGB)
        mono: bool = false,
    }
}

/// The test patterns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// A red line scrolling down one row per frame.
    Line,
    /// A green/cyan ball wandering around the centre.
    Ball,
    /// A colour gradient with a blue scrolling row.
    Grid,
    /// The grid, changing size every 100 frames.
    Size,
    /// Random-walk colours.
    Rand,
    /// Black.
    None,
    /// The elapsed time drawn in digits.
    Time,
}

impl Mode {
    /// Parses `line` or `[line]` (C++ keeps the brackets in its default).
    pub fn parse(s: &str) -> Option<Mode> {
        let s = s.trim_start_matches('[').trim_end_matches(']');
        Some(match s.to_ascii_lowercase().as_str() {
            "line" => Mode::Line,
            "ball" => Mode::Ball,
            "grid" => Mode::Grid,
            "size" => Mode::Size,
            "rand" => Mode::Rand,
            "none" => Mode::None,
            "time" => Mode::Time,
            _ => return None,
        })
    }
}

/// Pattern state, advanced one frame at a time (C++ `createTestImage`).
#[derive(Debug, Clone)]
pub struct Patterns {
    pub mode: Mode,
    /// The scrolling row.
    ct: usize,
    bx: i64,
    by: i64,
    rnd: u32,
    rgb: [u8; 3],
    size_count: u32,
    start_time: Option<f64>,
    noise: u64,
}

impl Patterns {
    pub fn new(mode: Mode, width: usize, height: usize) -> Patterns {
        Patterns {
            mode,
            ct: 0,
            bx: (width / 2) as i64,
            by: (height / 2) as i64,
            rnd: 0,
            rgb: [128; 3],
            size_count: 0,
            start_time: None,
            noise: 0x9e37_79b9_7f4a_7c15,
        }
    }

    fn next_rand(&mut self) -> u64 {
        // xorshift: cheap, deterministic noise is all a test pattern needs
        let mut x = self.noise;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.noise = x;
        x
    }

    /// Draws the next frame into `img` (resizing it to `width` x `height` first, except
    /// in `size` mode, which picks its own size) and advances the state.
    pub fn draw(&mut self, img: &mut Image, width: usize, height: usize, time: f64) {
        let (mut w, mut h) = (width, height);
        if self.mode == Mode::Size {
            self.size_count += 1;
            match self.size_count {
                100 => (w, h) = (100, 100),
                200 => (w, h) = (200, 100),
                300 => {
                    (w, h) = (300, 50);
                    self.size_count = 0;
                }
                _ => (w, h) = (img.width().max(1), img.height().max(1)),
            }
            if img.width() == 0 {
                (w, h) = (width, height);
            }
        }
        if img.width() != w || img.height() != h || img.pixel_code() != PixelCode::RGB {
            *img =
                Image::new(PixelCode::RGB, w, h).unwrap_or_else(|_| Image::empty(PixelCode::RGB));
        }
        match self.mode {
            Mode::Line => {
                img.zero();
                if self.ct < img.height() {
                    for x in 0..img.width() {
                        img.pixel_mut(x, self.ct)[0] = 255;
                    }
                }
            }
            Mode::Ball => {
                img.zero();
                circle(img, [0, 255, 0], self.bx, self.by, 15);
                circle(img, [0, 255, 255], self.bx, self.by, 8);
                self.move_ball(img.width(), img.height());
            }
            Mode::Grid | Mode::Size => self.grid(img),
            Mode::Rand => {
                for y in 0..img.height() {
                    for x in 0..img.width() {
                        for c in 0..3 {
                            let step = (self.next_rand() % 3) as u8;
                            self.rgb[c] = self.rgb[c].wrapping_add(step).wrapping_sub(1);
                        }
                        img.pixel_mut(x, y).copy_from_slice(&self.rgb);
                    }
                }
            }
            Mode::None => img.zero(),
            Mode::Time => {
                img.zero();
                let start = *self.start_time.get_or_insert(time);
                draw_text(img, &format!("{:.3}", time - start));
            }
        }
        self.advance(img.width(), img.height());
    }

    /// Moves to the next frame without drawing (frames nobody asked for).
    pub fn skip(&mut self, width: usize, height: usize) {
        if self.mode == Mode::Ball {
            self.move_ball(width, height);
        }
        self.advance(width, height);
    }

    fn advance(&mut self, width: usize, height: usize) {
        self.ct += 1;
        if self.ct >= height {
            self.ct = 0;
        }
        if self.by >= height as i64 {
            self.by = height as i64 - 1;
        }
        if self.bx >= width as i64 {
            self.bx = width as i64 - 1;
        }
    }

    fn move_ball(&mut self, width: usize, height: usize) {
        if !self.ct.is_multiple_of(5) {
            self.rnd = self.rnd.wrapping_mul(65537).wrapping_add(17);
            self.bx += i64::from(self.rnd % 5) - 2;
            self.rnd = self.rnd.wrapping_mul(65537).wrapping_add(17);
            self.by += i64::from(self.rnd % 5) - 2;
        } else {
            self.bx += (width as i64 / 2 - self.bx).signum();
            self.by += (height as i64 / 2 - self.by).signum();
        }
    }

    fn grid(&self, img: &mut Image) {
        let (w, h) = (img.width(), img.height());
        if w < 2 || h < 2 {
            return;
        }
        for y in 0..h {
            for x in 0..w {
                let r = (0.5 + 255.0 * x as f64 / (w - 1) as f64) as u8;
                let g = (0.5 + 255.0 * y as f64 / (h - 1) as f64) as u8;
                let b = if y == self.ct { 255 } else { 0 };
                img.pixel_mut(x, y).copy_from_slice(&[r, g, b]);
            }
        }
    }
}

/// A filled circle clipped to the image (C++ `addCircle`).
fn circle(img: &mut Image, rgb: [u8; 3], cx: i64, cy: i64, r: i64) {
    for y in cy - r..=cy + r {
        for x in cx - r..=cx + r {
            let inside = (x - cx).pow(2) + (y - cy).pow(2) <= r * r;
            if inside
                && x >= 0
                && y >= 0
                && (x as usize) < img.width()
                && (y as usize) < img.height()
            {
                img.pixel_mut(x as usize, y as usize).copy_from_slice(&rgb);
            }
        }
    }
}

/// 3x5 glyphs for `0-9`, space and `.` (C++ `num`), drawn 5x scaled in blue.
fn draw_text(img: &mut Image, text: &str) {
    const GLYPHS: [&[u8; 15]; 12] = [
        b"**** ** ** ****",
        b" *  *  *  *  * ",
        b"***  *****  ***",
        b"***  ****  ****",
        b"* ** ****  *  *",
        b"****  ***  ****",
        b"****  **** ****",
        b"***  *  *  *  *",
        b"**** ***** ****",
        b"**** ****  ****",
        b"               ",
        b"          ** **",
    ];
    const SCALE: usize = 5;
    for (i, ch) in text.chars().enumerate() {
        let glyph = match ch {
            '0'..='9' => GLYPHS[ch as usize - '0' as usize],
            '.' => GLYPHS[11],
            _ => GLYPHS[10],
        };
        let x0 = i * (3 * SCALE + 5);
        for gy in 0..5 {
            for gx in 0..3 {
                if glyph[gy * 3 + gx] != b'*' {
                    continue;
                }
                for y in gy * SCALE..(gy + 1) * SCALE {
                    for x in x0 + gx * SCALE..x0 + (gx + 1) * SCALE {
                        if x < img.width() && y < img.height() {
                            img.pixel_mut(x, y).copy_from_slice(&[0, 0, 255]);
                        }
                    }
                }
            }
        }
    }
}

/// C++ stamps fake images `NNN.NNN42`: the time cut to milliseconds, plus 0.00042.
pub fn fake_timestamp(now: f64) -> f64 {
    (now * 1000.0).trunc() / 1000.0 + 0.00042
}

fn wall_clock() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// The DC1394 settings the fake remembers, with C++ 4.0's starting values (its
/// `m_controlsDC1394`; the Format 7 windows it leaves unset read as zeros).
#[derive(Debug, Clone)]
struct Dc1394 {
    video_mode_mask: u32,
    video_mode: u32,
    fps_mask: u32,
    fps: u32,
    iso: u32,
    color_coding: u32,
    color_coding_mask: u32,
    operation: bool,
    transmission: bool,
    bpp: u32,
}

impl Default for Dc1394 {
    fn default() -> Self {
        Dc1394 {
            video_mode_mask: 10,
            video_mode: 11,
            fps_mask: 12,
            fps: 13,
            iso: 14,
            color_coding: 15,
            color_coding_mask: 16,
            operation: false,
            transmission: false,
            bpp: 100,
        }
    }
}

/// The feature values the fake remembers (C++ 3.12 `m_controls`).
#[derive(Debug, Default, Clone)]
struct Controls {
    feature: f64,
    feature2: (f64, f64),
    active: bool,
    mode: i32,
    one_push: bool,
}

/// The `fakeFrameGrabber` device.
pub struct FakeFrameGrabber {
    width: usize,
    height: usize,
    period: f64,
    syncro: bool,
    /// Value of the header's origin flag in produced images (see `open`).
    top_is_low: bool,
    add_timestamp: bool,
    add_noise: bool,
    snr: f64,
    mirror: bool,
    fov: (f64, f64),
    intrinsic: Property,
    patterns: Patterns,
    frame: Image,
    frame_time: f64,
    /// Frames produced (or skipped) since open.
    produced: u64,
    started: Option<Instant>,
    stamp_count: i32,
    last_stamp: Option<Stamp>,
    controls: Controls,
    dc1394: Dc1394,
}

impl Default for FakeFrameGrabber {
    fn default() -> Self {
        Self::new()
    }
}

impl FakeFrameGrabber {
    /// An unopened fake with the C++ defaults.
    pub fn new() -> FakeFrameGrabber {
        FakeFrameGrabber {
            width: 320,
            height: 240,
            period: 0.0,
            syncro: false,
            top_is_low: false,
            add_timestamp: false,
            add_noise: false,
            snr: 0.5,
            mirror: false,
            fov: (1.0, 2.0),
            intrinsic: Property::new(),
            patterns: Patterns::new(Mode::Line, 320, 240),
            frame: Image::empty(PixelCode::RGB),
            frame_time: 0.0,
            produced: 0,
            started: None,
            stamp_count: 0,
            last_stamp: None,
            controls: Controls::default(),
            dc1394: Dc1394::default(),
        }
    }

    /// Draws the next frame now.
    fn produce(&mut self) {
        let t = fake_timestamp(wall_clock());
        self.patterns
            .draw(&mut self.frame, self.width, self.height, t);
        if self.add_noise {
            let nsr = 1.0 - self.snr;
            let snr = self.snr;
            let n = self.frame.width() * self.frame.height();
            for i in 0..n {
                let (x, y) = (i % self.frame.width(), i / self.frame.width());
                let r = (self.patterns.next_rand() % 1_000_000) as f64 / 1_000_000.0;
                for c in self.frame.pixel_mut(x, y) {
                    *c = (f64::from(*c) * snr + r * nsr * 255.0) as u8;
                }
            }
        }
        if self.add_timestamp && self.frame.width() >= 7 && self.frame.height() >= 1 {
            let text = format!("{t:021.10}");
            let digits: Vec<u8> = text.bytes().map(|b| b.wrapping_sub(b'0')).collect();
            for (x, rgb) in digits.chunks(3).take(7).enumerate() {
                if rgb.len() == 3 {
                    self.frame.pixel_mut(x, 0).copy_from_slice(rgb);
                }
            }
        }
        self.frame.set_top_is_low(self.top_is_low);
        self.frame_time = t;
        self.produced += 1;
    }

    /// Brings the frame up to date with the clock (or makes one per call without a
    /// period, or exactly the next one in `syncro` mode, waiting for its time).
    fn update(&mut self) {
        let Some(start) = self.started else { return };
        if self.period <= 0.0 {
            self.produce();
            return;
        }
        let period = Duration::from_secs_f64(self.period);
        if self.syncro {
            let due = start + period.mul_f64(self.produced as f64);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
            self.produce();
            return;
        }
        let elapsed = start.elapsed().as_secs_f64();
        let due = (elapsed / self.period).floor() as u64 + 1;
        if due <= self.produced {
            return;
        }
        // frames nobody saw only move the pattern on
        let missed = (due - self.produced - 1).min(10_000);
        for _ in 0..missed {
            self.patterns.skip(self.width, self.height);
        }
        self.produced += missed;
        self.produce();
    }
}

impl DeviceDriver for FakeFrameGrabber {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeFrameGrabberParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeFrameGrabberParams::read(config)?;
        self.width = p.width;
        self.height = p.height;
        self.period = if p.freq > 0.0 {
            1.0 / p.freq
        } else {
            p.period.max(0.0)
        };
        let mode = Mode::parse(&p.mode).ok_or_else(|| DeviceError::BadParam {
            device: NAME.into(),
            param: "mode".into(),
            expected: "one of line, ball, grid, size, rand, none, time",
            got: p.mode.clone(),
        })?;
        self.syncro = p.syncro;
        // The recorded C++ 3.12.3 fake, with `topIsLow` at its default (true), streams
        // headers whose origin field is 1, i.e. "top is not low" in `ImageNetworkHeader`
        // terms; keep that observable behaviour.
        self.top_is_low = !p.top_is_low;
        self.mirror = p.mirror;
        self.add_timestamp = p.add_timestamp;
        self.add_noise = p.add_noise;
        self.snr = p.snr.clamp(0.0, 1.0);
        self.fov = (p.horizontal_fov, p.vertical_fov);
        let mut intr = Property::new();
        intr.put("physFocalLength", p.phys_focal_length);
        intr.put("focalLengthX", p.focal_length_x);
        intr.put("focalLengthY", p.focal_length_y);
        intr.put("principalPointX", p.principal_point_x);
        intr.put("principalPointY", p.principal_point_y);
        intr.put(
            "rectificationMatrix",
            Value::List(p.rectification_matrix.into_iter().collect::<Bottle>()),
        );
        intr.put("distortionModel", p.distortion_model.as_str());
        for (key, value) in [
            ("k1", p.k1),
            ("k2", p.k2),
            ("k3", p.k3),
            ("t1", p.t1),
            ("t2", p.t2),
        ] {
            intr.put(key, value);
        }
        self.intrinsic = intr;
        self.patterns = Patterns::new(mode, self.width, self.height);
        self.frame = Image::empty(PixelCode::RGB);
        self.produced = 0;
        self.stamp_count = 0;
        self.last_stamp = None;
        self.started = Some(Instant::now());
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.started = None;
        Ok(())
    }

    crate::views!(
        as_frame_grabber_image,
        as_frame_grabber_controls,
        as_frame_grabber_controls_dc1394
    );
}

impl IFrameGrabberImage for FakeFrameGrabber {
    fn get_image(&mut self) -> DevResult<Image> {
        if self.started.is_none() {
            return Err(DeviceError::NotOpen);
        }
        self.update();
        let stamp = Stamp::new(self.stamp_count, self.frame_time);
        self.stamp_count = self.stamp_count.wrapping_add(1);
        self.last_stamp = Some(stamp);
        Ok(self.frame.clone())
    }

    fn height(&mut self) -> usize {
        self.height
    }

    fn width(&mut self) -> usize {
        self.width
    }

    fn last_input_stamp(&mut self) -> Option<Stamp> {
        self.last_stamp
    }

    fn rgb_visual_params(&mut self) -> Option<&mut dyn IRgbVisualParams> {
        Some(self)
    }
}

impl IRgbVisualParams for FakeFrameGrabber {
    fn rgb_height(&mut self) -> i32 {
        self.height as i32
    }
    fn rgb_width(&mut self) -> i32 {
        self.width as i32
    }
    fn rgb_supported_configurations(&mut self) -> DevResult<Vec<CameraConfig>> {
        let conf = |w, h, fps, code| CameraConfig {
            width: w,
            height: h,
            framerate: fps,
            pixel_code: code,
        };
        Ok(vec![
            conf(128, 128, 60.0, PixelCode::RGB),
            conf(256, 256, 30.0, PixelCode::BGR),
            conf(512, 512, 15.0, PixelCode::MONO),
        ])
    }
    fn rgb_resolution(&mut self) -> DevResult<(i32, i32)> {
        Ok((self.width as i32, self.height as i32))
    }
    fn set_rgb_resolution(&mut self, width: i32, height: i32) -> DevResult<()> {
        let ok = |v: i32| v > 0 && v <= 1 << 15;
        if !ok(width) || !ok(height) {
            return Err(DeviceError::Unsupported("resolution out of range"));
        }
        self.width = width as usize;
        self.height = height as usize;
        Ok(())
    }
    fn rgb_fov(&mut self) -> DevResult<(f64, f64)> {
        Ok(self.fov)
    }
    fn set_rgb_fov(&mut self, horizontal: f64, vertical: f64) -> DevResult<()> {
        self.fov = (horizontal, vertical);
        Ok(())
    }
    fn rgb_intrinsic_param(&mut self) -> DevResult<Property> {
        Ok(self.intrinsic.clone())
    }
    fn rgb_mirroring(&mut self) -> DevResult<bool> {
        Ok(self.mirror)
    }
    fn set_rgb_mirroring(&mut self, mirror: bool) -> DevResult<()> {
        self.mirror = mirror;
        Ok(())
    }
}

impl IFrameGrabberControls for FakeFrameGrabber {
    fn camera_description(&mut self) -> DevResult<CameraDescriptor> {
        Ok(CameraDescriptor::default())
    }
    fn has_feature(&mut self, _feature: i32) -> DevResult<bool> {
        Ok(false)
    }
    fn set_feature(&mut self, _feature: i32, value: f64) -> DevResult<()> {
        self.controls.feature = value;
        Ok(())
    }
    fn get_feature(&mut self, _feature: i32) -> DevResult<f64> {
        Ok(self.controls.feature)
    }
    fn set_feature2(&mut self, _feature: i32, v1: f64, v2: f64) -> DevResult<()> {
        self.controls.feature2 = (v1, v2);
        Ok(())
    }
    fn get_feature2(&mut self, _feature: i32) -> DevResult<(f64, f64)> {
        Ok(self.controls.feature2)
    }
    fn has_on_off(&mut self, _feature: i32) -> DevResult<bool> {
        Ok(false)
    }
    fn set_active(&mut self, _feature: i32, on: bool) -> DevResult<()> {
        self.controls.active = on;
        Ok(())
    }
    fn get_active(&mut self, _feature: i32) -> DevResult<bool> {
        Ok(self.controls.active)
    }
    fn has_auto(&mut self, _feature: i32) -> DevResult<bool> {
        Ok(false)
    }
    fn has_manual(&mut self, _feature: i32) -> DevResult<bool> {
        Ok(false)
    }
    fn has_one_push(&mut self, _feature: i32) -> DevResult<bool> {
        Ok(self.controls.one_push)
    }
    fn set_mode(&mut self, _feature: i32, mode: i32) -> DevResult<()> {
        self.controls.mode = mode;
        Ok(())
    }
    fn get_mode(&mut self, _feature: i32) -> DevResult<i32> {
        Ok(if self.controls.mode == 0 {
            MODE_UNKNOWN
        } else {
            self.controls.mode
        })
    }
    fn set_one_push(&mut self, _feature: i32) -> DevResult<()> {
        self.controls.one_push = true;
        Ok(())
    }
}

/// C++ 4.0's fake: every call succeeds; getters give what the setters left.
impl IFrameGrabberControlsDC1394 for FakeFrameGrabber {
    fn video_mode_mask(&mut self) -> DevResult<u32> {
        Ok(self.dc1394.video_mode_mask)
    }
    fn video_mode(&mut self) -> DevResult<u32> {
        Ok(self.dc1394.video_mode)
    }
    fn set_video_mode(&mut self, mode: i32) -> DevResult<()> {
        self.dc1394.video_mode = mode as u32;
        Ok(())
    }
    fn fps_mask(&mut self) -> DevResult<u32> {
        Ok(self.dc1394.fps_mask)
    }
    fn fps(&mut self) -> DevResult<u32> {
        Ok(self.dc1394.fps)
    }
    fn set_fps(&mut self, fps: i32) -> DevResult<()> {
        self.dc1394.fps = fps as u32;
        Ok(())
    }
    fn iso_speed(&mut self) -> DevResult<u32> {
        Ok(self.dc1394.iso)
    }
    fn set_iso_speed(&mut self, speed: i32) -> DevResult<()> {
        self.dc1394.iso = speed as u32;
        Ok(())
    }
    fn color_coding_mask(&mut self, _video_mode: u32) -> DevResult<u32> {
        Ok(self.dc1394.color_coding_mask)
    }
    fn color_coding(&mut self) -> DevResult<u32> {
        Ok(self.dc1394.color_coding)
    }
    fn set_color_coding(&mut self, coding: i32) -> DevResult<()> {
        self.dc1394.color_coding = coding as u32;
        Ok(())
    }
    fn format7_max_window(&mut self) -> DevResult<[u32; 6]> {
        Ok([0; 6])
    }
    fn format7_window(&mut self) -> DevResult<(u32, u32, i32, i32)> {
        Ok((0, 0, 0, 0))
    }
    fn set_format7_window(&mut self, _: u32, _: u32, _: i32, _: i32) -> DevResult<()> {
        Ok(())
    }
    fn operation_mode(&mut self) -> DevResult<bool> {
        Ok(self.dc1394.operation)
    }
    fn set_operation_mode(&mut self, b1394b: bool) -> DevResult<()> {
        self.dc1394.operation = b1394b;
        Ok(())
    }
    fn transmission(&mut self) -> DevResult<bool> {
        Ok(self.dc1394.transmission)
    }
    fn set_transmission(&mut self, on: bool) -> DevResult<()> {
        self.dc1394.transmission = on;
        Ok(())
    }
    fn set_broadcast(&mut self, _: bool) -> DevResult<()> {
        Ok(())
    }
    fn set_defaults(&mut self) -> DevResult<()> {
        Ok(())
    }
    fn set_reset(&mut self) -> DevResult<()> {
        Ok(())
    }
    fn set_power(&mut self, _: bool) -> DevResult<()> {
        Ok(())
    }
    fn set_capture(&mut self, _: bool) -> DevResult<()> {
        Ok(())
    }
    fn bytes_per_packet(&mut self) -> DevResult<u32> {
        Ok(self.dc1394.bpp)
    }
    fn set_bytes_per_packet(&mut self, bpp: u32) -> DevResult<()> {
        self.dc1394.bpp = bpp;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_scrolls_one_row_per_frame() {
        let mut p = Patterns::new(Mode::Line, 8, 6);
        let mut img = Image::empty(PixelCode::RGB);
        for frame in 0..8 {
            p.draw(&mut img, 8, 6, 0.0);
            for y in 0..6 {
                let red = img.row(y).chunks(3).all(|px| px == [255, 0, 0]);
                assert_eq!(red, y == frame % 6, "frame {frame} row {y}");
            }
        }
    }

    #[test]
    fn every_mode_draws_in_bounds() {
        for m in ["line", "[ball]", "grid", "size", "rand", "none", "time"] {
            let mode = Mode::parse(m).unwrap();
            let mut p = Patterns::new(mode, 40, 30);
            let mut img = Image::empty(PixelCode::RGB);
            for _ in 0..310 {
                p.draw(&mut img, 40, 30, 1.5);
            }
            assert!(img.width() > 0, "{m}");
        }
    }

    #[test]
    fn timestamps_end_in_42() {
        let t = fake_timestamp(1795298108.87311);
        assert!((t - 1795298108.87342).abs() < 1e-6, "{t}");
    }
}
