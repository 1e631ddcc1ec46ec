//! `yarp::dev::ICartesianControl`: a limb driven in the operational space (its end
//! effector's pose), as icub-main's `cartesiancontrollerclient` (crate `icub-cartesian`)
//! offers it. Positions in metres, orientations as a unit axis and an angle in radians
//! (`ax ay az theta`), joints in degrees, as C++.

use crate::error::DevResult;

/// A pose: position and axis-angle orientation.
pub type Pose = ([f64; 3], [f64; 4]);

/// What a solver would answer for a target (`askForPose`): the pose it reaches and the
/// joints of the whole chain \[deg\].
#[derive(Debug, Clone, PartialEq)]
pub struct Solved {
    pub x: [f64; 3],
    pub o: [f64; 4],
    pub q: Vec<f64>,
}

/// An event of the controller (`cartesianEventVariables`).
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianEvent {
    /// `motion-onset`, `motion-ongoing`, `motion-done`, `closing`.
    pub kind: String,
    pub time: f64,
    /// The path fraction of a `motion-ongoing` event.
    pub checkpoint: Option<f64>,
}

/// `yarp::dev::ICartesianControl`, method by method.
pub trait ICartesianControl {
    fn set_tracking_mode(&mut self, on: bool) -> DevResult<()>;
    fn get_tracking_mode(&mut self) -> DevResult<bool>;
    fn set_reference_mode(&mut self, on: bool) -> DevResult<()>;
    fn get_reference_mode(&mut self) -> DevResult<bool>;
    /// `"position"` or `"orientation"`.
    fn set_pose_priority(&mut self, priority: &str) -> DevResult<()>;
    fn get_pose_priority(&mut self) -> DevResult<String>;
    /// The end effector's pose from the state stream, with its time.
    fn get_pose(&mut self) -> DevResult<(Pose, f64)>;
    /// The pose of the frame of link `axis`.
    fn get_link_pose(&mut self, axis: usize) -> DevResult<Pose>;
    fn go_to_pose(&mut self, x: &[f64; 3], o: &[f64; 4], t: f64) -> DevResult<()>;
    fn go_to_position(&mut self, x: &[f64; 3], t: f64) -> DevResult<()>;
    fn go_to_pose_sync(&mut self, x: &[f64; 3], o: &[f64; 4], t: f64) -> DevResult<()>;
    fn go_to_position_sync(&mut self, x: &[f64; 3], t: f64) -> DevResult<()>;
    /// The solver's last answer: pose and joints \[deg\].
    fn get_desired(&mut self) -> DevResult<Solved>;
    /// What the solver would do for a pose, from joints `q0` \[deg\] or the current ones.
    fn ask_for_pose(&mut self, x: &[f64; 3], o: &[f64; 4], q0: Option<&[f64]>)
        -> DevResult<Solved>;
    fn ask_for_position(&mut self, x: &[f64; 3], q0: Option<&[f64]>) -> DevResult<Solved>;
    /// Links released (1) or blocked (0).
    fn get_dof(&mut self) -> DevResult<Vec<i32>>;
    /// 0 blocks, 1 releases, 2 leaves; returns the DOF now.
    fn set_dof(&mut self, dof: &[i32]) -> DevResult<Vec<i32>>;
    fn get_rest_pos(&mut self) -> DevResult<Vec<f64>>;
    fn set_rest_pos(&mut self, rest: &[f64]) -> DevResult<Vec<f64>>;
    fn get_rest_weights(&mut self) -> DevResult<Vec<f64>>;
    fn set_rest_weights(&mut self, weights: &[f64]) -> DevResult<Vec<f64>>;
    fn get_limits(&mut self, axis: usize) -> DevResult<(f64, f64)>;
    fn set_limits(&mut self, axis: usize, min: f64, max: f64) -> DevResult<()>;
    fn get_traj_time(&mut self) -> DevResult<f64>;
    fn set_traj_time(&mut self, t: f64) -> DevResult<()>;
    fn get_in_target_tol(&mut self) -> DevResult<f64>;
    fn set_in_target_tol(&mut self, tol: f64) -> DevResult<()>;
    /// The joints' commanded velocities \[deg/s\].
    fn get_joints_velocities(&mut self) -> DevResult<Vec<f64>>;
    /// The end effector's velocity: linear and (axis, speed).
    fn get_task_velocities(&mut self) -> DevResult<([f64; 3], [f64; 4])>;
    fn set_task_velocities(&mut self, xdot: &[f64; 3], odot: &[f64; 4]) -> DevResult<()>;
    fn attach_tip_frame(&mut self, x: &[f64; 3], o: &[f64; 4]) -> DevResult<()>;
    fn get_tip_frame(&mut self) -> DevResult<Pose>;
    fn remove_tip_frame(&mut self) -> DevResult<()> {
        self.attach_tip_frame(&[0.0; 3], &[0.0; 4])
    }
    fn check_motion_done(&mut self) -> DevResult<bool>;
    /// Polls [`ICartesianControl::check_motion_done`] every `period` s; false after
    /// `timeout` s (0: no limit).
    fn wait_motion_done(&mut self, period: f64, timeout: f64) -> DevResult<bool>;
    fn stop_control(&mut self) -> DevResult<()>;
    fn store_context(&mut self) -> DevResult<i32>;
    fn restore_context(&mut self, id: i32) -> DevResult<()>;
    fn delete_context(&mut self, id: i32) -> DevResult<()>;
    /// The server's `[get] [info]` list.
    fn get_info(&mut self) -> DevResult<yarp_proto::Bottle>;
    /// Asks for `motion-ongoing` events at a path fraction.
    fn register_ongoing_checkpoint(&mut self, checkpoint: f64) -> DevResult<()>;
    fn unregister_ongoing_checkpoint(&mut self, checkpoint: f64) -> DevResult<()>;
    /// The events received since the last call.
    fn take_events(&mut self) -> Vec<CartesianEvent>;
}
