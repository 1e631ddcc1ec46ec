//! `yarp::dev::IGazeControl`: where a robot's eyes look, as icub-main's
//! `gazecontrollerclient` (crate `icub-cartesian`) offers it. Points in metres in the
//! robot's root frame, angles in degrees (azimuth right, elevation up, vergence).

use crate::cartesian_control::CartesianEvent;
use crate::error::DevResult;

/// `yarp::dev::IGazeControl`, the calls of its everyday use.
pub trait IGazeControl {
    fn set_tracking_mode(&mut self, on: bool) -> DevResult<()>;
    fn get_tracking_mode(&mut self) -> DevResult<bool>;
    /// Gaze stabilisation (the head countering the IMU's rotation while idle).
    fn set_stabilization_mode(&mut self, on: bool) -> DevResult<()>;
    fn get_stabilization_mode(&mut self) -> DevResult<bool>;
    /// The vestibulo-ocular reflex's gain (the eyes countering the IMU's rotation).
    fn set_vor_gain(&mut self, gain: f64) -> DevResult<()>;
    fn get_vor_gain(&mut self) -> DevResult<f64>;
    /// The oculo-collic reflex's gain (the eyes countering the neck's motion).
    fn set_ocr_gain(&mut self, gain: f64) -> DevResult<()>;
    fn get_ocr_gain(&mut self) -> DevResult<f64>;
    /// The fixation point from the `x:o` stream, with its time.
    fn get_fixation_point(&mut self) -> DevResult<([f64; 3], f64)>;
    /// The absolute angles of the fixation point from the `angles:o` stream.
    fn get_angles(&mut self) -> DevResult<[f64; 3]>;
    fn look_at_fixation_point(&mut self, x: &[f64; 3]) -> DevResult<()>;
    /// Returns once the motion has started (as C++'s).
    fn look_at_fixation_point_sync(&mut self, x: &[f64; 3]) -> DevResult<()>;
    fn look_at_abs_angles(&mut self, ang: &[f64; 3]) -> DevResult<()>;
    fn look_at_rel_angles(&mut self, ang: &[f64; 3]) -> DevResult<()>;
    fn look_at_abs_angles_sync(&mut self, ang: &[f64; 3]) -> DevResult<()>;
    /// The pixel of point `x` in camera `cam` (0 left, 1 right).
    fn get_2d_pixel(&mut self, cam: usize, x: &[f64; 3]) -> DevResult<[f64; 2]>;
    /// The point at depth `z` along pixel `px` of camera `cam`.
    fn get_3d_point(&mut self, cam: usize, px: &[f64; 2], z: f64) -> DevResult<[f64; 3]>;
    /// The point seen at pixel `pl` of the left camera and `pr` of the right one.
    fn triangulate_3d_point(&mut self, pl: &[f64; 2], pr: &[f64; 2]) -> DevResult<[f64; 3]>;
    fn look_at_mono_pixel_sync(&mut self, cam: usize, px: &[f64; 2], z: f64) -> DevResult<()>;
    fn look_at_stereo_pixels_sync(&mut self, pl: &[f64; 2], pr: &[f64; 2]) -> DevResult<()>;
    fn get_neck_traj_time(&mut self) -> DevResult<f64>;
    fn set_neck_traj_time(&mut self, t: f64) -> DevResult<()>;
    fn get_eyes_traj_time(&mut self) -> DevResult<f64>;
    fn set_eyes_traj_time(&mut self, t: f64) -> DevResult<()>;
    /// The head's desired joints \[deg\].
    fn get_joints_desired(&mut self) -> DevResult<Vec<f64>>;
    fn check_motion_done(&mut self) -> DevResult<bool>;
    /// Polls every `period` s; false after `timeout` s (0: no limit).
    fn wait_motion_done(&mut self, period: f64, timeout: f64) -> DevResult<bool>;
    fn stop_control(&mut self) -> DevResult<()>;
    fn store_context(&mut self) -> DevResult<i32>;
    fn restore_context(&mut self, id: i32) -> DevResult<()>;
    fn delete_context(&mut self, id: i32) -> DevResult<()>;
    /// The server's `get info` list.
    fn get_info(&mut self) -> DevResult<yarp_proto::Bottle>;
    /// The events received since the last call.
    fn take_events(&mut self) -> Vec<CartesianEvent>;
}
