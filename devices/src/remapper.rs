//! `controlboardremapper`: several control boards joined into one virtual part, each of
//! its joints delegated to a joint of one attached board (C++ `ControlBoardRemapper`).
//!
//! Two configurations, as in C++ (exactly one of them):
//! * `axesNames (n0 n1 ...)`: the part's joints, found by name among the axes of the
//!   devices given to `attach_all` (each needs encoders and axis info);
//! * `networks (net1 net2 ...)`, `joints N`, and per network
//!   `net1 (partFirst partLast boardFirst boardLast)` (or the four numbers without
//!   parentheses): joints `partFirst..=partLast` of the part are joints
//!   `boardFirst..=boardLast` of the device attached under the key `net1`.
//!
//! The mapping is computed by the pure [`Layout::resolve`]; the device then forwards every
//! interface call to the owning board.

use crate::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::interfaces::*;
use parking_lot::MutexGuard;
use std::collections::HashMap;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use yarp_proto::{Bottle, Property, Value, Vocab32};

/// The C++ device name.
pub const NAME: &str = "controlboardremapper";

crate::device_params! {
    /// What `controlboardremapper` reads (C++ `ControlBoardRemapper`'s documentation):
    /// either `axesNames`, or `networks` with `joints` and, for each network named, a
    /// line `NAME partFirst partLast boardFirst boardLast`.
    pub struct ControlBoardRemapperParams for "controlboardremapper" {
        /// the axes of the remapped board, by name, from the boards attached
        "axesNames" axes_names: Vec<String> = optional,
        /// the boards attached, by their key in attachAll (old-style layout)
        networks: Vec<String> = optional,
        /// number of joints of the remapped board (with networks)
        joints: usize = optional,
    }
}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, crate::driver::Factory)] =
    &[(NAME, || Box::new(ControlBoardRemapper::new()))];

/// One `networks` entry: part joints `part_first..=part_last` are board joints
/// `board_first..=board_last` of the device attached as `name`.
#[derive(Debug, Clone, PartialEq)]
pub struct Network {
    pub name: String,
    pub part_first: usize,
    pub part_last: usize,
    pub board_first: usize,
    pub board_last: usize,
}

/// How the part's joints are found among the attached boards.
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    AxesNames(Vec<String>),
    Networks {
        joints: usize,
        networks: Vec<Network>,
    },
}

/// What `resolve` needs to know about one attached board.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardInfo {
    pub key: String,
    pub axes: usize,
    /// Axis names (only needed for the `axesNames` layout).
    pub names: Vec<String>,
}

/// Where a part joint lives: index of the board in the attached list, joint on it.
pub type Lut = Vec<(usize, usize)>;

/// Why the layout cannot be built from the attached boards.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RemapError {
    #[error("axis `{0}` is on no attached board")]
    UnknownAxis(String),
    #[error("axis name `{name}` is on two boards (`{first}` and `{second}`)")]
    DuplicateAxis {
        name: String,
        first: String,
        second: String,
    },
    #[error("network `{0}` is not among the attached devices")]
    MissingNetwork(String),
    #[error("network `{name}`: board joints {first}..={last} but the board has {axes} axes")]
    BoardRange {
        name: String,
        first: usize,
        last: usize,
        axes: usize,
    },
    #[error("part joint {0} is covered by no network")]
    Uncovered(usize),
}

impl Layout {
    /// Reads the layout from the device configuration (C++ parameter names).
    pub fn from_config(config: &Property) -> DevResult<Layout> {
        let p = ControlBoardRemapperParams::read(config)?;
        let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
            device: NAME.into(),
            param: param.into(),
            expected,
            got,
        };
        match (p.axes_names, p.networks) {
            (Some(_), Some(_)) => Err(bad(
                "networks",
                "absent when axesNames is given (use one of them)",
                "both".into(),
            )),
            (None, None) => Err(DeviceError::MissingParam {
                device: NAME.into(),
                param: "axesNames".into(),
            }),
            (Some(names), None) => Ok(Layout::AxesNames(names)),
            (None, Some(nets)) => {
                let joints = p.joints.ok_or_else(|| DeviceError::MissingParam {
                    device: NAME.into(),
                    param: "joints".into(),
                })?;
                let networks = nets
                    .iter()
                    .map(|name| network(config, name))
                    .collect::<DevResult<Vec<_>>>()?;
                for n in &networks {
                    if n.part_last >= joints {
                        return Err(bad(
                            &n.name,
                            "part joints below `joints`",
                            format!("{}..={} with joints {joints}", n.part_first, n.part_last),
                        ));
                    }
                }
                Ok(Layout::Networks { joints, networks })
            }
        }
    }

    /// Maps every part joint to (board index, board joint) for the boards attached.
    pub fn resolve(&self, boards: &[BoardInfo]) -> Result<Lut, RemapError> {
        match self {
            Layout::AxesNames(names) => {
                let mut at: HashMap<&str, (usize, usize)> = HashMap::new();
                for (b, info) in boards.iter().enumerate() {
                    for (j, name) in info.names.iter().enumerate() {
                        if let Some((b0, _)) = at.insert(name, (b, j)) {
                            return Err(RemapError::DuplicateAxis {
                                name: name.clone(),
                                first: boards[b0].key.clone(),
                                second: info.key.clone(),
                            });
                        }
                    }
                }
                names
                    .iter()
                    .map(|n| {
                        at.get(n.as_str())
                            .copied()
                            .ok_or_else(|| RemapError::UnknownAxis(n.clone()))
                    })
                    .collect()
            }
            Layout::Networks { joints, networks } => {
                let mut lut: Vec<Option<(usize, usize)>> = vec![None; *joints];
                for n in networks {
                    let b = boards
                        .iter()
                        .position(|i| i.key == n.name)
                        .ok_or_else(|| RemapError::MissingNetwork(n.name.clone()))?;
                    if n.board_last >= boards[b].axes {
                        return Err(RemapError::BoardRange {
                            name: n.name.clone(),
                            first: n.board_first,
                            last: n.board_last,
                            axes: boards[b].axes,
                        });
                    }
                    for (k, slot) in lut[n.part_first..=n.part_last].iter_mut().enumerate() {
                        *slot = Some((b, n.board_first + k));
                    }
                }
                lut.into_iter()
                    .enumerate()
                    .map(|(j, s)| s.ok_or(RemapError::Uncovered(j)))
                    .collect()
            }
        }
    }
}

/// Reads `name (a b c d)` or `name a b c d` from the configuration.
fn network(config: &Property, name: &str) -> DevResult<Network> {
    let bad = |got: String| DeviceError::BadParam {
        device: NAME.into(),
        param: name.into(),
        expected: "four joint indices (partFirst partLast boardFirst boardLast), with equal spans",
        got,
    };
    let line = config
        .find_group(name)
        .ok_or_else(|| DeviceError::MissingParam {
            device: NAME.into(),
            param: name.into(),
        })?;
    let numbers: Vec<Value> = match line.len() {
        2 => match &line[1] {
            Value::List(l) => l.iter().cloned().collect(),
            v => match v.as_str() {
                Some(text) => Bottle::from_text(text).into_items(),
                None => return Err(bad(line.to_string())),
            },
        },
        5 => line.iter().skip(1).cloned().collect(),
        _ => return Err(bad(line.to_string())),
    };
    let n: Vec<usize> = numbers
        .iter()
        .map(|v| {
            v.as_i64()
                .filter(|_| v.is_int())
                .and_then(|x| usize::try_from(x).ok())
        })
        .collect::<Option<Vec<_>>>()
        .filter(|n| n.len() == 4)
        .ok_or_else(|| bad(line.to_string()))?;
    if n[1] < n[0] || n[3] < n[2] || n[1] - n[0] != n[3] - n[2] {
        return Err(bad(line.to_string()));
    }
    Ok(Network {
        name: name.to_string(),
        part_first: n[0],
        part_last: n[1],
        board_first: n[2],
        board_last: n[3],
    })
}

/// The remapper device.
#[derive(Default)]
pub struct ControlBoardRemapper {
    layout: Option<Layout>,
    boards: Vec<SharedDevice>,
    lut: Lut,
    /// The part's calibrator device (C++ `IRemoteCalibrator::setCalibratorDevice`).
    calibrator: Option<SharedDevice>,
    /// Its quit flag, taken when it was set: a quit must reach it while it is busy.
    calibrator_quit: Option<Arc<AtomicBool>>,
}

const NOT_ATTACHED: &str = "controlboardremapper: no boards attached yet";

fn lock(d: &SharedDevice) -> MutexGuard<'_, crate::driver::PolyDriver> {
    d.lock()
}

impl ControlBoardRemapper {
    pub fn new() -> Self {
        Self::default()
    }

    /// The (board index, board joint) of every part joint, once attached.
    pub fn lut(&self) -> &[(usize, usize)] {
        &self.lut
    }

    fn axes(&self) -> DevResult<usize> {
        if self.boards.is_empty() {
            return Err(DeviceError::Unsupported(NOT_ATTACHED));
        }
        Ok(self.lut.len())
    }

    /// Sets (or clears) the calibrator device that `IRemoteCalibrator` calls go to; it
    /// must offer `IRemoteCalibrator` and must not lock this remapper while serving them.
    pub fn set_calibrator_device(&mut self, calibrator: Option<SharedDevice>) {
        self.calibrator_quit = calibrator.as_ref().and_then(|c| {
            lock(c)
                .device()
                .as_remote_calibrator()
                .and_then(|rc| rc.quit_signal())
        });
        self.calibrator = calibrator;
    }

    /// Runs `f` on the calibrator device's `IRemoteCalibrator`, if one is set. A
    /// calibrator that is busy (its own calibrate or park holds it, and may be waiting
    /// for this remapper) answers an error instead of deadlocking.
    fn on_calibrator<R>(
        &self,
        f: impl FnOnce(&mut dyn IRemoteCalibrator) -> DevResult<R>,
    ) -> Option<DevResult<R>> {
        let c = self.calibrator.as_ref()?;
        let mut pd = match c.try_lock() {
            Some(pd) => pd,
            None => {
                return Some(Err(DeviceError::Unsupported(
                    "the calibrator device is busy calibrating or parking",
                )))
            }
        };
        Some(match pd.device().as_remote_calibrator() {
            Some(rc) => f(rc),
            None => Err(DeviceError::Unsupported(
                "the remapper's calibrator device lacks IRemoteCalibrator",
            )),
        })
    }

    /// Without a calibrator device, C++ asks every board's own `IRemoteCalibrator`.
    fn on_every_board(
        &self,
        f: impl Fn(&mut dyn IRemoteCalibrator) -> DevResult<()>,
    ) -> DevResult<()> {
        self.axes()?;
        for b in &self.boards {
            let mut pd = lock(b);
            let rc = pd
                .device()
                .as_remote_calibrator()
                .ok_or(DeviceError::Unsupported(
                    "a board of the remapper lacks IRemoteCalibrator",
                ))?;
            f(rc)?;
        }
        Ok(())
    }

    /// Runs `f` on the board owning part joint `j`, with the board's joint index.
    fn on<R>(
        &self,
        j: usize,
        f: impl FnOnce(&mut dyn DeviceDriver, usize) -> DevResult<R>,
    ) -> DevResult<R> {
        let axes = self.axes()?;
        let (b, local) = *self.lut.get(j).ok_or(DeviceError::InvalidJoint {
            joint: j as i64,
            axes,
        })?;
        let mut pd = lock(&self.boards[b]);
        f(pd.device(), local)
    }
}

/// The interface `$view` of the board owning joint `$j`, as `$i` with board joint `$l`.
macro_rules! on {
    ($self:ident, $j:expr, $view:ident, |$i:ident, $l:ident| $body:expr) => {
        $self.on($j, |d, $l| {
            let $i = d.$view().ok_or(DeviceError::Unsupported(concat!(
                "a board of the remapper lacks the interface of ",
                stringify!($view)
            )))?;
            $body
        })
    };
}

/// Trait methods that hand joint `j` to the same method of the board that has it, as that
/// board's joint: `fn name(j, args) -> Reply => as_view;` (C++'s remapper does this by
/// hand, method by method).
macro_rules! joint_calls {
    ($(fn $name:ident($j:ident $(, $arg:ident: $ty:ty)*) -> $ret:ty => $view:ident;)*) => {
        $(
            fn $name(&mut self, $j: usize $(, $arg: $ty)*) -> DevResult<$ret> {
                on!(self, $j, $view, |d, l| d.$name(l $(, $arg)*))
            }
        )*
    };
}

impl DeviceDriver for ControlBoardRemapper {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        ControlBoardRemapperParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.layout = Some(Layout::from_config(config)?);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.detach_all()
    }

    crate::views!(as_multiple_wrapper);

    crate::motor_control_views!();

    crate::views!(
        as_remote_calibrator,
        as_velocity_direct,
        as_joint_brake,
        as_joint_fault,
        as_remote_variables
    );
}

/// As C++'s remapper (3.12 and 4.0, which warns "not properly implemented"): a variable is
/// every board's values one after the other, set with one list per board; the keys are
/// those of the board owning joint 0. A board without the interface fails the call.
impl IRemoteVariables for ControlBoardRemapper {
    fn get_remote_variable(&mut self, key: &str) -> DevResult<Bottle> {
        self.axes()?;
        let mut all = Bottle::new();
        let mut failed = None;
        for b in &self.boards {
            let mut pd = lock(b);
            let vars = pd.device().as_remote_variables().ok_or(NO_VARIABLES)?;
            match vars.get_remote_variable(key) {
                Ok(v) => all.extend(v.into_items()),
                Err(e) => failed = failed.or(Some(e)),
            }
        }
        failed.map_or(Ok(all), Err)
    }
    fn set_remote_variable(&mut self, key: &str, value: &Bottle) -> DevResult<()> {
        self.axes()?;
        if value.len() != self.boards.len() {
            return Err(DeviceError::WrongSize {
                expected: self.boards.len(),
                got: value.len(),
            });
        }
        let mut failed = None;
        for (b, v) in self.boards.iter().zip(value.iter()) {
            let part = v.as_list().ok_or_else(|| DeviceError::Failed {
                device: NAME.into(),
                reason: format!("setRemoteVariable {key}: one list per board, got `{v}`"),
            })?;
            let mut pd = lock(b);
            let vars = pd.device().as_remote_variables().ok_or(NO_VARIABLES)?;
            if let Err(e) = vars.set_remote_variable(key, part) {
                failed = failed.or(Some(e));
            }
        }
        failed.map_or(Ok(()), Err)
    }
    fn get_remote_variables_list(&mut self) -> DevResult<Bottle> {
        self.on(0, |d, _| {
            d.as_remote_variables()
                .ok_or(NO_VARIABLES)?
                .get_remote_variables_list()
        })
    }
}

const NO_VARIABLES: DeviceError =
    DeviceError::Unsupported("a board of the remapper lacks IRemoteVariables");

/// What the layout needs to know about an attached device.
fn board_info(key: &str, dev: &SharedDevice, with_names: bool) -> DevResult<BoardInfo> {
    let mut pd = lock(dev);
    let d = pd.device();
    let axes = d
        .as_encoders()
        .ok_or(DeviceError::Unsupported(
            "controlboardremapper: an attached device has no encoders",
        ))?
        .get_axes()?;
    let names = if with_names {
        let info = d.as_axis_info().ok_or(DeviceError::Unsupported(
            "controlboardremapper: axesNames needs devices with axis info",
        ))?;
        (0..axes)
            .map(|j| info.get_axis_name(j))
            .collect::<DevResult<Vec<_>>>()?
    } else {
        Vec::new()
    };
    Ok(BoardInfo {
        key: key.to_string(),
        axes,
        names,
    })
}

impl IMultipleWrapper for ControlBoardRemapper {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        if self.layout.is_none() {
            return Err(DeviceError::NotOpen);
        }
        // as C++, a device keyed "calibrator" is not a board but the calibrator device
        if let Some((_, c)) = devices
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case("calibrator"))
        {
            self.set_calibrator_device(Some(c.clone()));
        }
        let layout = self.layout.as_ref().ok_or(DeviceError::NotOpen)?;
        let with_names = matches!(layout, Layout::AxesNames(_));
        let boards: Vec<&(String, SharedDevice)> = devices
            .iter()
            .filter(|(k, _)| !k.eq_ignore_ascii_case("calibrator"))
            .collect();
        let infos = boards
            .iter()
            .map(|(k, d)| board_info(k, d, with_names))
            .collect::<DevResult<Vec<_>>>()?;
        let lut = layout.resolve(&infos).map_err(|e| DeviceError::BadParam {
            device: NAME.into(),
            param: if with_names { "axesNames" } else { "networks" }.into(),
            expected: "a layout the attached boards provide",
            got: e.to_string(),
        })?;
        self.boards = boards.into_iter().map(|(_, d)| d.clone()).collect();
        self.lut = lut;
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.boards.clear();
        self.lut.clear();
        Ok(())
    }
}

impl IEncoders for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn get_encoder(j) -> f64 => as_encoders;
        fn get_encoder_speed(j) -> f64 => as_encoders;
        fn get_encoder_acceleration(j) -> f64 => as_encoders;
        fn get_encoder_timed(j) -> (f64, f64) => as_encoders;
        fn set_encoder(j, value: f64) -> () => as_encoders;
        fn reset_encoder(j) -> () => as_encoders;
    }
}

impl IPositionControl for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn position_move(j, target: f64) -> () => as_position_control;
        fn relative_move(j, delta: f64) -> () => as_position_control;
        fn check_motion_done(j) -> bool => as_position_control;
        fn set_ref_speed(j, speed: f64) -> () => as_position_control;
        fn set_ref_acceleration(j, acc: f64) -> () => as_position_control;
        fn get_ref_speed(j) -> f64 => as_position_control;
        fn get_ref_acceleration(j) -> f64 => as_position_control;
        fn stop(j) -> () => as_position_control;
        fn get_target_position(j) -> f64 => as_position_control;
    }
}

impl IVelocityControl for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn velocity_move(j, speed: f64) -> () => as_velocity_control;
        fn get_ref_velocity(j) -> f64 => as_velocity_control;
    }
}

impl IVelocityDirect for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn set_ref_velocity_direct(j, v: f64) -> () => as_velocity_direct;
        fn get_ref_velocity_direct(j) -> f64 => as_velocity_direct;
    }
}

impl IJointFault for ControlBoardRemapper {
    joint_calls! {
        fn get_last_joint_fault(j) -> (i32, String) => as_joint_fault;
    }
}

impl IJointBrake for ControlBoardRemapper {
    joint_calls! {
        fn is_joint_braked(j) -> bool => as_joint_brake;
        fn set_manual_brake_active(j, active: bool) -> () => as_joint_brake;
        fn set_auto_brake_enabled(j, enabled: bool) -> () => as_joint_brake;
        fn get_auto_brake_enabled(j) -> bool => as_joint_brake;
    }
}

impl IControlMode for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn get_available_control_modes(j) -> Vec<Vocab32> => as_control_mode;
        fn get_control_mode(j) -> Vocab32 => as_control_mode;
        fn set_control_mode(j, mode: Vocab32) -> () => as_control_mode;
    }
}

impl IInteractionMode for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn get_interaction_mode(j) -> Vocab32 => as_interaction_mode;
        fn set_interaction_mode(j, mode: Vocab32) -> () => as_interaction_mode;
    }
}

impl IAxisInfo for ControlBoardRemapper {
    joint_calls! {
        fn get_axis_name(j) -> String => as_axis_info;
        fn get_joint_type(j) -> Vocab32 => as_axis_info;
    }
}

impl IControlLimits for ControlBoardRemapper {
    joint_calls! {
        fn set_limits(j, min: f64, max: f64) -> () => as_control_limits;
        fn get_limits(j) -> (f64, f64) => as_control_limits;
        fn set_vel_limits(j, min: f64, max: f64) -> () => as_control_limits;
        fn get_vel_limits(j) -> (f64, f64) => as_control_limits;
    }
}

impl ITorqueControl for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn get_motor_torque_params(j) -> [f64; 9] => as_torque_control;
        fn set_motor_torque_params(j, p: [f64; 9]) -> () => as_torque_control;
        fn get_torque(j) -> f64 => as_torque_control;
        fn set_ref_torque(j, v: f64) -> () => as_torque_control;
        fn get_ref_torque(j) -> f64 => as_torque_control;
        fn get_torque_range(j) -> (f64, f64) => as_torque_control;
    }
}

impl IMotorEncoders for ControlBoardRemapper {
    fn get_num_of_motor_encoders(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn get_motor_encoder_timed(m) -> (f64, f64) => as_motor_encoders;
        fn set_motor_encoder(m, v: f64) -> () => as_motor_encoders;
        fn reset_motor_encoder(m) -> () => as_motor_encoders;
        fn get_motor_encoder(m) -> f64 => as_motor_encoders;
        fn get_motor_encoder_speed(m) -> f64 => as_motor_encoders;
        fn get_motor_encoder_acceleration(m) -> f64 => as_motor_encoders;
    }
}

impl IAmplifierControl for ControlBoardRemapper {
    joint_calls! {
        fn enable_amp(j) -> () => as_amplifier_control;
        fn disable_amp(j) -> () => as_amplifier_control;
    }
    fn get_amp_statuses(&mut self) -> DevResult<Vec<i32>> {
        (0..self.axes()?)
            .map(|j| {
                on!(self, j, as_amplifier_control, |a, l| a
                    .get_amp_statuses()?
                    .get(l)
                    .copied()
                    .ok_or(DeviceError::Unsupported(
                        "a board of the remapper reported too few amplifier statuses"
                    )))
            })
            .collect()
    }
    joint_calls! {
        fn get_current(j) -> f64 => as_amplifier_control;
        fn get_max_current(j) -> f64 => as_amplifier_control;
        fn set_max_current(j, v: f64) -> () => as_amplifier_control;
        fn get_nominal_current(j) -> f64 => as_amplifier_control;
        fn set_nominal_current(j, v: f64) -> () => as_amplifier_control;
        fn get_peak_current(j) -> f64 => as_amplifier_control;
        fn set_peak_current(j, v: f64) -> () => as_amplifier_control;
        fn get_pwm(j) -> f64 => as_amplifier_control;
        fn get_pwm_limit(j) -> f64 => as_amplifier_control;
        fn set_pwm_limit(j, v: f64) -> () => as_amplifier_control;
        fn get_power_supply_voltage(j) -> f64 => as_amplifier_control;
        fn get_amp_status(j) -> i32 => as_amplifier_control;
    }
}

impl IMotor for ControlBoardRemapper {
    joint_calls! {
        fn get_temperature(m) -> f64 => as_motor;
    }
    fn get_number_of_motors(&mut self) -> DevResult<usize> {
        // one motor per joint of the part, as C++ (motors and joints are remapped alike)
        self.axes()
    }
    joint_calls! {
        fn get_gearbox_ratio(m) -> f64 => as_motor;
        fn set_gearbox_ratio(m, v: f64) -> () => as_motor;
        fn get_temperature_limit(m) -> f64 => as_motor;
        fn set_temperature_limit(m, v: f64) -> () => as_motor;
    }
}

impl IPidControl for ControlBoardRemapper {
    fn get_pid(&mut self, ty: Vocab32, j: usize) -> DevResult<Pid> {
        on!(self, j, as_pid_control, |p, l| p.get_pid(ty, l))
    }
    joint_calls! {
        fn get_available_pids(j) -> Vec<Vocab32> => as_pid_control;
    }
    fn set_pid_feedforward(&mut self, ty: Vocab32, j: usize, v: f64) -> DevResult<()> {
        on!(self, j, as_pid_control, |p, l| p
            .set_pid_feedforward(ty, l, v))
    }
    fn get_pid_feedforward(&mut self, ty: Vocab32, j: usize) -> DevResult<f64> {
        on!(self, j, as_pid_control, |p, l| p.get_pid_feedforward(ty, l))
    }
    fn get_pid_extra_info(&mut self, ty: Vocab32, j: usize) -> DevResult<PidExtraInfo> {
        on!(self, j, as_pid_control, |p, l| p.get_pid_extra_info(ty, l))
    }
    fn set_pid(&mut self, ty: Vocab32, j: usize, pid: Pid) -> DevResult<()> {
        on!(self, j, as_pid_control, |p, l| p.set_pid(ty, l, pid))
    }
    fn enable_pid(&mut self, ty: Vocab32, j: usize) -> DevResult<()> {
        on!(self, j, as_pid_control, |p, l| p.enable_pid(ty, l))
    }
    fn disable_pid(&mut self, ty: Vocab32, j: usize) -> DevResult<()> {
        on!(self, j, as_pid_control, |p, l| p.disable_pid(ty, l))
    }
    fn is_pid_enabled(&mut self, ty: Vocab32, j: usize) -> DevResult<bool> {
        on!(self, j, as_pid_control, |p, l| p.is_pid_enabled(ty, l))
    }
    fn set_pid_reference(&mut self, ty: Vocab32, j: usize, r: f64) -> DevResult<()> {
        on!(self, j, as_pid_control, |p, l| p
            .set_pid_reference(ty, l, r))
    }
    fn get_pid_reference(&mut self, ty: Vocab32, j: usize) -> DevResult<f64> {
        on!(self, j, as_pid_control, |p, l| p.get_pid_reference(ty, l))
    }
    fn get_pid_error(&mut self, ty: Vocab32, j: usize) -> DevResult<f64> {
        on!(self, j, as_pid_control, |p, l| p.get_pid_error(ty, l))
    }
    fn get_pid_output(&mut self, ty: Vocab32, j: usize) -> DevResult<f64> {
        on!(self, j, as_pid_control, |p, l| p.get_pid_output(ty, l))
    }
    fn reset_pid(&mut self, ty: Vocab32, j: usize) -> DevResult<()> {
        on!(self, j, as_pid_control, |p, l| p.reset_pid(ty, l))
    }
}

impl ICurrentControl for ControlBoardRemapper {
    joint_calls! {
        fn get_ref_current(j) -> f64 => as_current_control;
        fn get_current_range(j) -> (f64, f64) => as_current_control;
        fn set_ref_current(j, current: f64) -> () => as_current_control;
    }
}

impl IPwmControl for ControlBoardRemapper {
    joint_calls! {
        fn get_ref_duty_cycle(j) -> f64 => as_pwm_control;
        fn set_ref_duty_cycle(j, duty: f64) -> () => as_pwm_control;
        fn get_duty_cycle(m) -> f64 => as_pwm_control;
    }
}

impl IImpedanceControl for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn get_impedance(j) -> (f64, f64) => as_impedance_control;
        fn set_impedance(j, stiffness: f64, damping: f64) -> () => as_impedance_control;
        fn get_impedance_offset(j) -> f64 => as_impedance_control;
        fn set_impedance_offset(j, offset: f64) -> () => as_impedance_control;
        fn get_current_impedance_limit(j) -> ImpedanceLimits => as_impedance_control;
    }
}

impl IControlCalibration for ControlBoardRemapper {
    fn calibrate_axis_with_params(
        &mut self,
        j: usize,
        kind: u32,
        p1: f64,
        p2: f64,
        p3: f64,
    ) -> DevResult<()> {
        on!(self, j, as_control_calibration, |c, l| c
            .calibrate_axis_with_params(l, kind, p1, p2, p3))
    }
    fn set_calibration_parameters(
        &mut self,
        j: usize,
        params: &CalibrationParameters,
    ) -> DevResult<()> {
        on!(self, j, as_control_calibration, |c, l| c
            .set_calibration_parameters(l, params))
    }
    joint_calls! {
        fn calibration_done(j) -> bool => as_control_calibration;
    }
}

/// As C++ `ControlBoardRemapper`: calls go to the calibrator device when one is set,
/// else to the boards' own remote calibrators.
impl IRemoteCalibrator for ControlBoardRemapper {
    fn is_calibrator_device_present(&mut self) -> DevResult<bool> {
        Ok(self.calibrator.is_some())
    }
    fn set_calibrator_device(&mut self, device: Option<SharedDevice>) -> DevResult<()> {
        ControlBoardRemapper::set_calibrator_device(self, device);
        Ok(())
    }
    fn calibrator_device(&self) -> Option<SharedDevice> {
        self.calibrator.clone()
    }
    fn quit_signal(&self) -> Option<Arc<AtomicBool>> {
        self.calibrator_quit.clone()
    }
    fn calibrate_single_joint(&mut self, j: usize) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.calibrate_single_joint(j)) {
            return r;
        }
        on!(self, j, as_remote_calibrator, |c, l| c
            .calibrate_single_joint(l))
    }
    fn calibrate_whole_part(&mut self) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.calibrate_whole_part()) {
            return r;
        }
        self.on_every_board(|c| c.calibrate_whole_part())
    }
    fn homing_single_joint(&mut self, j: usize) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.homing_single_joint(j)) {
            return r;
        }
        on!(self, j, as_remote_calibrator, |c, l| c
            .homing_single_joint(l))
    }
    fn homing_whole_part(&mut self) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.homing_whole_part()) {
            return r;
        }
        self.on_every_board(|c| c.homing_whole_part())
    }
    fn park_single_joint(&mut self, j: usize, wait: bool) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.park_single_joint(j, wait)) {
            return r;
        }
        on!(self, j, as_remote_calibrator, |c, l| c
            .park_single_joint(l, wait))
    }
    fn park_whole_part(&mut self) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.park_whole_part()) {
            return r;
        }
        self.on_every_board(|c| c.park_whole_part())
    }
    fn quit_calibrate(&mut self) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.quit_calibrate()) {
            return r;
        }
        self.on_every_board(|c| c.quit_calibrate())
    }
    fn quit_park(&mut self) -> DevResult<()> {
        if let Some(r) = self.on_calibrator(|c| c.quit_park()) {
            return r;
        }
        self.on_every_board(|c| c.quit_park())
    }
}

impl IPositionDirect for ControlBoardRemapper {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    joint_calls! {
        fn set_position(j, reference: f64) -> () => as_position_direct;
        fn get_ref_position(j) -> f64 => as_position_direct;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn board(key: &str, names: &[&str]) -> BoardInfo {
        BoardInfo {
            key: key.into(),
            axes: names.len(),
            names: names.iter().map(|s| s.to_string()).collect(),
        }
    }

    fn layout(text: &str) -> DevResult<Layout> {
        Layout::from_config(&Property::from_config_text(text).unwrap())
    }

    #[test]
    fn axes_names_resolve_across_boards() {
        let l = layout("axesNames (b1 a0 a2)\n").unwrap();
        let boards = [board("a", &["a0", "a1", "a2"]), board("b", &["b0", "b1"])];
        assert_eq!(l.resolve(&boards).unwrap(), [(1, 1), (0, 0), (0, 2)]);
        let l = layout("axesNames (zz)\n").unwrap();
        assert_eq!(
            l.resolve(&boards),
            Err(RemapError::UnknownAxis("zz".into()))
        );
        let dup = [board("a", &["x"]), board("b", &["x"])];
        assert!(matches!(
            layout("axesNames (x)\n").unwrap().resolve(&dup),
            Err(RemapError::DuplicateAxis { .. })
        ));
    }

    #[test]
    fn networks_in_both_syntaxes() {
        let l = layout("networks (arm hand)\njoints 5\narm (0 2 1 3)\nhand 3 4 0 1\n").unwrap();
        let boards = [
            board("hand", &["h0", "h1"]),
            board("arm", &["a0", "a1", "a2", "a3"]),
        ];
        assert_eq!(
            l.resolve(&boards).unwrap(),
            [(1, 1), (1, 2), (1, 3), (0, 0), (0, 1)]
        );
        assert_eq!(
            l.resolve(&boards[..1]),
            Err(RemapError::MissingNetwork("arm".into()))
        );
        let gap = layout("networks (arm)\njoints 4\narm (0 2 0 2)\n").unwrap();
        assert_eq!(gap.resolve(&boards[1..]), Err(RemapError::Uncovered(3)));
        let wide = layout("networks (hand)\njoints 3\nhand (0 2 0 2)\n").unwrap();
        assert!(matches!(
            wide.resolve(&boards),
            Err(RemapError::BoardRange { .. })
        ));
    }

    #[test]
    fn bad_configurations_name_the_parameter() {
        let err = |t: &str| layout(t).unwrap_err().to_string();
        assert!(err("").contains("`axesNames`"));
        assert!(err("axesNames (a)\nnetworks (n)\n").contains("`networks`"));
        assert!(err("axesNames 3\n").contains("`axesNames`"));
        assert!(err("networks (n)\n").contains("`joints`"));
        assert!(err("networks (n)\njoints 2\n").contains("`n`"));
        assert!(err("networks (n)\njoints 2\nn (0 1 0)\n").contains("`n`"));
        assert!(err("networks (n)\njoints 2\nn (0 1 0 2)\n").contains("`n`"));
        assert!(err("networks (n)\njoints 2\nn (0 3 0 3)\n").contains("`n`"));
        assert!(err("networks (n)\njoints -1\nn (0 0 0 0)\n").contains("`joints`"));
    }
}
