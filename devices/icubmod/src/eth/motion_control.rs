//! `embObjMotionControl` (icub-main): the joints of one Ethernet motor-control board
//! (EMS4 + 2FOC, MC4plus, MC2plus, AMC, ...) behind the YARP motor interfaces.
//!
//! `open`, as C++: the board's `ETH_BOARD`/`PC104` groups and the motion-control
//! parameters ([`McParams`]); the board is brought up (once per board); the MC endpoint's
//! protocol version is verified; the service (`SERVICE/type`) is verified and activated;
//! every joint is set idle, its status (`joint status core`, `addinfo multienc`, `motor
//! status`) is made regular, its `joint config` and `motor config` are set and checked;
//! the service is started. Any step that fails names the board (IP and name) and why.
//!
//! Units, as icub-main's `measureConverter`: positions and velocities are sent in
//! encoder units (`Encoder` per degree), currents in `ampsToSensor` units per A, PWM in
//! `fullscalePWM` counts per 100 %, torques in µN·m (`newtonsToSensor` 1e6), stiffness
//! and damping in µN·m per encoder unit, PID gains as [`McParams::pid_factors`] gives
//! them; motor temperatures through the motor's sensor ([`TemperatureSensor`], NaN
//! without one). Readings come from the regulars the board streams;
//! `checkMotionDone` and `calibrationDone` ask the board, as C++ does. A board silent for
//! longer than its `MONITOR_ITS_PRESENCE` timeout makes every reading fail, naming it.

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::service_config::mc_config;
use icub_eth::entities::mc::{
    control_mode as cm, Calibrator, ControllerStatus, CurrentLimits, Impedance, JointConfig,
    JointStatusCore, MotorConfig, MotorParams, MotorStatus, Pid as EoPid, PositionLimits, Pwm,
    Setpoint,
};
use icub_eth::entities::mn::{category, ServiceCommand};
use icub_eth::host::Startup;
use icub_eth::id::{endpoint as ep, entity as en, ids, tag};
use icub_eth::{Entity, Id32, Retry};
use yarp_devices::interfaces::*;
use yarp_devices::sensors::virtual_analog::{IVirtualAnalogSensor, VasStatus};
use yarp_devices::vocabs::*;
use yarp_devices::{DevResult, DeviceDriver, DeviceError};
use yarp_proto::{Property, Value, Vocab32};

use super::manager::{Board, EthError, EthManager};
use super::mc_params::{
    s16, s32, McParams, PidKind, PidParams, TemperatureSensor, NEWTONS_TO_SENSOR,
};
use super::params::{read_eth_board, read_pc104};
use super::service;

pub const NAME: &str = "embObjMotionControl";

/// How long an `ask` of a joint variable may take (`theNVmanager`'s default).
const ASK_TIMEOUT: Duration = Duration::from_millis(500);

/// Whether the board runs joint `c`'s torque PID: torque control, or position control
/// with compliant interaction (C++ reads the `ofpid` torque fields only then).
fn torque_pid_active(c: &JointStatusCore) -> bool {
    c.control_mode == cm::TORQUE
        || (c.control_mode == cm::POSITION
            && c.interaction_mode == icub_eth::entities::mc::interaction_mode::COMPLIANT)
}

/// The YARP vocab of a board control-mode status.
pub fn mode_vocab(m: u8) -> Vocab32 {
    match m {
        cm::IDLE => CM_IDLE,
        cm::POSITION => CM_POSITION,
        cm::VELOCITY => CM_VELOCITY,
        cm::TORQUE => CM_TORQUE,
        cm::IMPEDANCE_POS => CM_IMPEDANCE_POS,
        cm::IMPEDANCE_VEL => CM_IMPEDANCE_VEL,
        cm::CURRENT => CM_CURRENT,
        // icub-main's eomcUtils: "they are the same"
        cm::MIXED | cm::VELOCITY_POS => CM_MIXED,
        cm::DIRECT => CM_POSITION_DIRECT,
        cm::OPENLOOP => CM_PWM,
        cm::HW_FAULT => CM_HW_FAULT,
        cm::NOT_CONFIGURED => CM_NOT_CONFIGURED,
        cm::CONFIGURED => CM_CONFIGURED,
        cm::CALIB => CM_CALIBRATING,
        _ => CM_UNKNOWN,
    }
}

/// The board command for a YARP control mode a client may ask for.
pub fn vocab_mode(v: Vocab32) -> Option<u8> {
    Some(match v {
        _ if v == CM_IDLE => cm::IDLE,
        _ if v == CM_FORCE_IDLE => cm::FORCE_IDLE,
        _ if v == CM_POSITION => cm::POSITION,
        _ if v == CM_VELOCITY => cm::VELOCITY,
        _ if v == CM_TORQUE => cm::TORQUE,
        _ if v == CM_CURRENT => cm::CURRENT,
        _ if v == CM_MIXED => cm::MIXED,
        _ if v == CM_POSITION_DIRECT => cm::DIRECT,
        _ if v == CM_PWM => cm::OPENLOOP,
        _ if v == CM_IMPEDANCE_POS => cm::IMPEDANCE_POS,
        _ if v == CM_IMPEDANCE_VEL => cm::IMPEDANCE_VEL,
        _ => return None,
    })
}

/// `eOmc_calibrator32_t`'s parameter words for a calibration (C++
/// `setCalibrationParametersRaw`: each type's union member, fields at their C offsets;
/// `zero` already in encoder units).
pub fn calibrator(params: &CalibrationParameters, zero: i32) -> Option<Calibrator> {
    let i = |v: f64| v.round() as i32;
    let lo16 = |v: f64| i32::from(v.round() as i16) & 0xffff;
    let p = match params.kind {
        0 | 2 => [lo16(params.param1), i(params.param2), zero, 0, 0, 0],
        1 => [i(params.param1), i(params.param2), zero, 0, 0, 0],
        3 | 4 => [
            i(params.param1),
            i(params.param2),
            i(params.param3),
            zero,
            0,
            0,
        ],
        5 => [i(params.param1), i(params.param2), zero, 0, 0, 0],
        6 => [
            i(params.param1),
            i(params.param2),
            i(params.param4),
            i(params.param5),
            zero,
            lo16(params.param3),
        ],
        7 => [
            i(params.param1),
            i(params.param2),
            i(params.param4),
            i(params.param5),
            zero,
            0,
        ],
        8 | 9 => [
            i(params.param1),
            i(params.param2),
            i(params.param_zero),
            0,
            0,
            0,
        ],
        10 => [i(params.param1), zero, 0, 0, 0, 0],
        11 => [
            i(params.param1),
            i(params.param2),
            i(params.param3),
            i(params.param4),
            i(params.param5),
            0,
        ],
        12 => [i(params.param1), zero, 0, 0, 0, 0],
        13 => [
            i(params.param1),
            i(params.param2),
            i(params.param3),
            i(params.param4),
            0,
            0,
        ],
        14 => {
            let invert = params.param3.round() as i64;
            if invert != 0 && invert != 1 {
                return None;
            }
            [
                i(params.param1),
                i(params.param2),
                invert as i32,
                i(params.param4),
                i(params.param5),
                zero,
            ]
        }
        _ => return None,
    };
    Some(Calibrator {
        calibration_type: params.kind as u8,
        params: p,
    })
}

/// The `embObjMotionControl` device.
#[derive(Default)]
pub struct EmbObjMotionControl {
    id: String,
    p: Option<McParams>,
    board: Option<Arc<Board>>,
    jconfig: Vec<JointConfig>,
    mconfig: Vec<MotorConfig>,
    ref_speed: Vec<f64>,
    /// Encoder units/s² (C++ `_ref_accs`, saturated at ±1e6).
    ref_acc_raw: Vec<f64>,
    targets: Vec<f64>,
    /// Whether `targets[j]` is the goal of a position move made in the joint's current
    /// control mode (a relative move starts from it; else from the encoder).
    target_valid: Vec<bool>,
    ref_velocity: Vec<f64>,
    ref_position: Vec<f64>,
    ref_current: Vec<f64>,
    ref_pwm: Vec<f64>,
    vel_limits: Vec<(f64, f64)>,
    mode_set_at: Vec<Option<Instant>>,
    /// `MAINTENANCE/skipRecalibration`: an idle joint counts as calibrated.
    skip_recalibration: bool,
    /// When a command skipped for its control mode was last reported (at most once a
    /// second, as C++'s event downsampler).
    last_skip_report: Option<Instant>,
}

impl EmbObjMotionControl {
    pub fn new() -> Self {
        Self::default()
    }

    /// The board behind the device (to check its presence, counters, ...).
    pub fn board(&self) -> Option<&Arc<Board>> {
        self.board.as_ref()
    }

    fn p(&self) -> DevResult<&McParams> {
        self.p.as_ref().ok_or(DeviceError::NotOpen)
    }

    fn b(&self) -> DevResult<&Board> {
        self.board.as_deref().ok_or(DeviceError::NotOpen)
    }

    fn fail(&self, e: EthError) -> DeviceError {
        DeviceError::failed(&self.id, e)
    }

    /// Whether joint `j` is in one of `modes` (as C++ checks before a setpoint); if not,
    /// `what` is reported (downsampled) and the caller skips the command.
    fn in_mode(&mut self, j: usize, modes: &[Vocab32], what: &str) -> DevResult<bool> {
        let now = mode_vocab(self.core(j)?.control_mode);
        if modes.contains(&now) {
            return Ok(true);
        }
        if self
            .last_skip_report
            .is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
        {
            self.last_skip_report = Some(Instant::now());
            tracing::error!(device = %self.id, joint = j, "{what}: skipping command because the joint is in control mode {now}");
        }
        Ok(false)
    }

    /// An error when joint `j` has no torque control (`CONTROLS/torqueControl none`), as
    /// C++ refuses torque mode and compliant interaction then.
    fn need_torque_control(&self, j: usize, what: &str) -> DevResult<()> {
        self.phys(j)?;
        if self.p()?.trq_pids.get(j).is_some_and(Option::is_some) {
            return Ok(());
        }
        Err(DeviceError::failed(
            &self.id,
            format!("joint {j}: {what} needs a torque PID (CONTROLS/torqueControl is none)"),
        ))
    }

    fn axes(&self) -> DevResult<usize> {
        Ok(self.p()?.joints)
    }

    /// The board joint of logical joint `j` (checked).
    fn phys(&self, j: usize) -> DevResult<u8> {
        let p = self.p()?;
        if j >= p.joints {
            return Err(DeviceError::InvalidJoint {
                joint: j as i64,
                axes: p.joints,
            });
        }
        Ok(p.axis_map[j] as u8)
    }

    fn a2e(&self, j: usize) -> f64 {
        self.p.as_ref().map_or(1.0, |p| p.a2e(j))
    }

    fn joint_id(&self, j: usize, t: u8) -> DevResult<Id32> {
        Ok(ids::joint(self.phys(j)?, t))
    }

    fn motor_id(&self, j: usize, t: u8) -> DevResult<Id32> {
        Ok(ids::motor(self.phys(j)?, t))
    }

    fn core(&self, j: usize) -> DevResult<JointStatusCore> {
        let id = self.joint_id(j, tag::MC_JOINT_STATUS_CORE)?;
        self.b()?.read(id).map_err(|e| self.fail(e))
    }

    fn motor_status(&self, j: usize) -> DevResult<MotorStatus> {
        let id = self.motor_id(j, tag::MC_MOTOR_STATUS)?;
        self.b()?.read(id).map_err(|e| self.fail(e))
    }

    fn set<T: Entity>(&self, id: Id32, v: &T) -> DevResult<()> {
        self.b()?.set_value(id, v).map_err(|e| self.fail(e))
    }

    fn setpoint(&self, j: usize, sp: Setpoint) -> DevResult<()> {
        let id = self.joint_id(j, tag::MC_JOINT_CMMNDS_SETPOINT)?;
        self.set(id, &sp)
    }

    /// An ask of the board (C++ `askRemoteValue`), as [`Retry::DEVICE_ASK`].
    fn retried<T>(&self, ask: impl Fn(&Board, Duration) -> Result<T, EthError>) -> DevResult<T> {
        let b = self.b()?;
        Retry::DEVICE_ASK
            .run(|timeout| ask(b, timeout))
            .map_err(|e| self.fail(e))
    }

    /// Asks a board variable of a known type.
    fn ask<T: Entity>(&self, id: Id32) -> DevResult<T> {
        self.retried(|b, timeout| b.ask_value(id, timeout))
    }

    /// Asks a one-byte joint variable (as C++).
    fn ask_u8(&self, j: usize, t: u8) -> DevResult<u8> {
        let id = self.joint_id(j, t)?;
        self.retried(|b, timeout| b.ask(id, timeout).map(|v| v.first().copied().unwrap_or(0)))
    }

    /// Motor `m`'s current limits as the board has them (C++ asks them each time).
    fn current_limits(&self, m: usize) -> DevResult<CurrentLimits> {
        self.phys(m)?;
        self.ask(self.motor_id(m, tag::MC_MOTOR_CONFIG_CURRENTLIMITS)?)
    }

    /// C++ `set{Max,Nominal,Peak}CurrentRaw`: asks the limits, changes one (A to the
    /// board's mA through `ampsToSensor`, `S_16`) and sets them back.
    fn change_current_limits(
        &mut self,
        m: usize,
        change: fn(&mut CurrentLimits, i16),
        amps: f64,
    ) -> DevResult<()> {
        let mut limits = self.current_limits(m)?;
        let raw = s16(amps * self.p()?.amps_to_sensor[m]);
        change(&mut limits, raw);
        self.set(
            self.motor_id(m, tag::MC_MOTOR_CONFIG_CURRENTLIMITS)?,
            &limits,
        )?;
        self.mconfig[m].current_limits = limits;
        Ok(())
    }

    /// Joint `j`'s impedance as the board has it (C++ `getWholeImpedanceRaw` asks it and
    /// keeps it as the cache that later sets start from).
    fn board_impedance(&mut self, j: usize) -> DevResult<Impedance> {
        self.phys(j)?;
        let i: Impedance = self.ask(self.joint_id(j, tag::MC_JOINT_CONFIG_IMPEDANCE)?)?;
        self.jconfig[j].impedance = i;
        Ok(i)
    }

    /// The board's joint and motor configuration of joint `j` (C++ `init()`): PIDs as
    /// YARP's `convert_pid_to_machine` ([`McParams::pid_factors`]; `piddirect` left
    /// zero, as C++), stiffness and damping in µN·m per encoder unit, `ktau` and `bemf`
    /// in the firmware's units, the encoders at the joint and at the motor, the dead zone
    /// in encoder units, the motor group's flags, poles, `Kbemf` and the hardware
    /// temperature limit as the sensor's raw reading.
    pub fn configs(p: &McParams, j: usize) -> (JointConfig, MotorConfig) {
        let a2e = p.a2e(j);
        let pos = |deg: f64| s32(deg * a2e);
        let pid = |kind: PidKind, v: &Option<PidParams>| {
            let (fbk, out) = p.pid_factors(kind, j);
            v.unwrap_or_default().to_eo(fbk, out)
        };
        let trq = p.trq_pids[j].unwrap_or_default();
        let (jenc, menc) = (p.joint_encoder[j], p.rotor_encoder[j]);
        let jc = JointConfig {
            pid_trajectory: pid(PidKind::Position, &p.pos_pids[j]),
            pid_direct: Default::default(),
            pid_torque: pid(PidKind::Torque, &p.trq_pids[j]),
            user_limits: PositionLimits {
                min: pos(p.pos_min[j]),
                max: pos(p.pos_max[j]),
            },
            hardware_limits: PositionLimits {
                min: pos(p.hw_pos_min[j]),
                max: pos(p.hw_pos_max[j]),
            },
            impedance: Impedance {
                stiffness: p.imp_to_raw(j, p.stiffness[j]) as f32,
                damping: p.imp_to_raw(j, p.damping[j]) as f32,
                offset: 0.0,
            },
            max_velocity_of_joint: pos(p.vel_max[j]),
            jnt_encoder_resolution: jenc.resolution,
            motor_params: MotorParams {
                bemf_value: (trq.kbemf * p.bemf_to_raw(j)) as f32,
                ktau_value: (trq.ktau * p.ktau_to_raw(j)) as f32,
                // YARP's friction conversion factors are 1 (C++ gives none)
                friction: [
                    trq.viscous_pos as f32,
                    trq.viscous_neg as f32,
                    trq.coulomb_pos as f32,
                    trq.coulomb_neg as f32,
                    trq.velocity_thres as f32,
                ],
                ..Default::default()
            },
            velocity_setpoint_timeout: p.velocity_timeout[j] as u16,
            current_setpoint_timeout: p.current_timeout[j] as u16,
            openloop_setpoint_timeout: p.pwm_timeout[j] as u16,
            torque_setpoint_timeout: p.torque_timeout[j] as u16,
            torque_feedback_timeout: p.torque_fbk_timeout[j] as u16,
            tc_filter_type: trq.filter_type as u8,
            jnt_encoder_type: jenc.kind,
            jnt_enc_tolerance: jenc.tolerance as f32,
            gearbox_e2j: p.gearbox_e2j[j] as f32,
            deadzone: (p.deadzone[j] * a2e) as f32,
            kalman: p.kalman[j],
        };
        let flags = u8::from(p.has_hall_sensor[j])
            | u8::from(p.has_temp_sensor[j]) << 1
            | u8::from(p.has_rotor_encoder[j]) << 2
            | u8::from(p.has_rotor_encoder_index[j]) << 3
            | u8::from(p.has_speed_encoder[j]) << 4
            | u8::from(p.motor_verbose[j]) << 6;
        let mc = MotorConfig {
            pid_current: pid(PidKind::Current, &p.cur_pids[j]),
            pid_speed: pid(PidKind::Velocity, &p.spd_pids[j]),
            gearbox_m2j: p.gearbox_m2j[j] as f32,
            rotor_encoder_resolution: menc.resolution,
            current_limits: CurrentLimits {
                nominal: p.nominal_current[j] as i16,
                peak: p.peak_current[j] as i16,
                overload: p.overload_current[j] as i16,
            },
            rotor_index_offset: p.rotor_index_offset[j] as i16,
            motor_poles: p.motor_poles[j] as u8,
            flags,
            rotor_encoder_type: menc.kind,
            rot_enc_tolerance: menc.tolerance as f32,
            kbemf: p.motor_kbemf[j] as f32,
            pwm_limit: p.pwm_limit[j] as i16,
            temperature_limit: p.temperature_limit_raw(j),
            limits_of_rotor: PositionLimits {
                min: pos(p.rotor_min[j]),
                max: pos(p.rotor_max[j]),
            },
            lugre: p.lugre[j],
            ..Default::default()
        };
        (jc, mc)
    }

    /// C++ `open()` after the parameters: verify, activate (with the service's
    /// configuration, `service`), `init()`, start.
    fn bring_up(
        &mut self,
        board: &Arc<Board>,
        p: &McParams,
        service: &[u8],
    ) -> Result<(), EthError> {
        let mut steps = Startup::steps();
        service::verify_endpoint(board, &mut steps, service::endpoint_of(category::MC));
        steps.verify_activate(&ServiceCommand::verify_activate(
            category::MC,
            p.service.service_type,
            0,
            0,
            service,
        ));
        for j in 0..p.joints {
            let f = p.axis_map[j] as u8;
            steps.set(ids::joint(f, tag::MC_JOINT_CMMNDS_CONTROLMODE), &[cm::IDLE]);
        }
        steps.pause(Duration::from_millis(10));
        let mut regulars = Vec::new();
        for f in 0..p.joints as u8 {
            regulars.push(ids::joint(f, tag::MC_JOINT_STATUS_CORE));
            regulars.push(ids::joint(f, tag::MC_JOINT_STATUS_ADDINFO_MULTIENC));
            regulars.push(ids::motor(f, tag::MC_MOTOR_STATUS));
        }
        steps.set_regulars(category::MC, &regulars);
        steps.pause(Duration::from_millis(5));
        for j in 0..p.joints {
            let f = p.axis_map[j] as u8;
            steps.setcheck(
                ids::joint(f, tag::MC_JOINT_CONFIG),
                &self.jconfig[j].to_bytes(),
            );
        }
        for j in 0..p.joints {
            let f = p.axis_map[j] as u8;
            steps.setcheck(
                ids::motor(f, tag::MC_MOTOR_CONFIG),
                &self.mconfig[j].to_bytes(),
            );
        }
        // eOmc_controller_config_t: the control loop's duration (the board's cycle, µs)
        // and whether the board may skip recalibration (MAINTENANCE/skipRecalibration)
        let mut controller = u32::from(board.params().appl.cycletime)
            .to_le_bytes()
            .to_vec();
        controller.extend_from_slice(&[u8::from(self.skip_recalibration), 0, 0, 0]);
        steps.setcheck(
            Id32::new(
                ep::MOTION_CONTROL,
                en::MC_CONTROLLER,
                0,
                tag::MC_CONTROLLER_CONFIG,
            ),
            &controller,
        );
        steps.start(category::MC);
        board.run(&mut steps)
    }

    /// The PID kind of a YARP PID type.
    fn pid_kind(t: Vocab32) -> DevResult<PidKind> {
        Ok(match t {
            _ if t == PIDTYPE_POSITION => PidKind::Position,
            _ if t == PIDTYPE_TORQUE => PidKind::Torque,
            _ if t == PIDTYPE_CURRENT => PidKind::Current,
            _ if t == PIDTYPE_VELOCITY => PidKind::Velocity,
            _ => return Err(DeviceError::Unsupported("unknown PID type")),
        })
    }

    /// Where joint `j`'s PID of a kind lives on the board: the joint's `pidtrajectory` or
    /// `pidtorque`, the motor's `pidcurrent` or `pidspeed`.
    fn pid_id(&self, kind: PidKind, j: usize) -> DevResult<Id32> {
        match kind {
            PidKind::Position => self.joint_id(j, tag::MC_JOINT_CONFIG_PIDTRAJECTORY),
            PidKind::Torque => self.joint_id(j, tag::MC_JOINT_CONFIG_PIDTORQUE),
            PidKind::Current => self.motor_id(j, tag::MC_MOTOR_CONFIG_PIDCURRENT),
            PidKind::Velocity => self.motor_id(j, tag::MC_MOTOR_CONFIG_PIDSPEED),
        }
    }

    /// The host's copy of that PID (as last sent or asked); `j` checked by the caller.
    fn pid_slot(&mut self, kind: PidKind, j: usize) -> &mut EoPid {
        match kind {
            PidKind::Position => &mut self.jconfig[j].pid_trajectory,
            PidKind::Torque => &mut self.jconfig[j].pid_torque,
            PidKind::Current => &mut self.mconfig[j].pid_current,
            PidKind::Velocity => &mut self.mconfig[j].pid_speed,
        }
    }

    /// Joint `j`'s PID of a type asked of the board (C++ `helper_get*PidRaw`), in user
    /// units. What the board answers becomes the copy later sets start from.
    fn board_pid(&mut self, t: Vocab32, j: usize) -> DevResult<PidParams> {
        self.phys(j)?;
        let kind = Self::pid_kind(t)?;
        let eo: EoPid = self.ask(self.pid_id(kind, j)?)?;
        *self.pid_slot(kind, j) = eo;
        let (fbk, out) = self.p()?.pid_factors(kind, j);
        Ok(PidParams::from_eo(&eo, fbk, out))
    }
}

impl DeviceDriver for EmbObjMotionControl {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        super::tables::of(NAME)
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        super::tables::help_if_asked(NAME, config);
        self.close()?;
        self.id = config
            .find("id")
            .map_or_else(|| NAME.to_string(), Value::to_string_bare);
        let id = self.id.clone();
        let pc104 = read_pc104(config).map_err(|e| e.for_device(&id))?;
        let eth = read_eth_board(config).map_err(|e| e.for_device(&id))?;
        let p = McParams::read(config).map_err(|e| e.for_device(&id))?;
        let service =
            mc_config(config, p.service.service_type, p.joints).map_err(|e| e.for_device(&id))?;
        let n = p.joints;
        let (jc, mc): (Vec<_>, Vec<_>) = (0..n).map(|j| Self::configs(&p, j)).unzip();
        self.jconfig = jc;
        self.mconfig = mc;
        self.ref_speed = vec![10.0; n];
        self.ref_acc_raw = vec![0.0; n];
        self.targets = vec![0.0; n];
        self.target_valid = vec![false; n];
        self.ref_velocity = vec![0.0; n];
        self.ref_position = vec![0.0; n];
        self.ref_current = vec![0.0; n];
        self.ref_pwm = vec![0.0; n];
        self.vel_limits = p.vel_max.iter().map(|v| (0.0, *v)).collect();
        self.mode_set_at = vec![None; n];
        self.skip_recalibration = super::config::Node::root(config)
            .group("MAINTENANCE")
            .and_then(|m| m.boolean("skipRecalibration"))
            .unwrap_or(false);
        let mgr = EthManager::instance(&pc104).map_err(|e| DeviceError::failed(&id, e))?;
        let board = mgr.board(&eth);
        if let Err(e) = self.bring_up(&board, &p, &service) {
            tracing::error!(device = %id, "embObjMotionControl::open() fails for BOARD {}: {e}", board.who());
            return Err(DeviceError::failed(&id, e));
        }
        tracing::info!(device = %id, board = %board.who(), joints = n, "embObjMotionControl open");
        self.p = Some(p);
        self.board = Some(board);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let (Some(b), Some(p)) = (self.board.take(), self.p.take()) {
            for f in 0..p.joints as u8 {
                let _ = b.set(ids::joint(f, tag::MC_JOINT_CMMNDS_CONTROLMODE), &[cm::IDLE]);
            }
        }
        Ok(())
    }

    yarp_devices::motor_control_views!();
    yarp_devices::views!(as_virtual_analog_sensor, as_raw_values_publisher);
}

/// The one key of icub-main's embObjMotionControl as `IRawValuesPublisher`: the name of
/// the ROP tag its values come from.
pub const RAW_VALUES_KEY: &str = "eoprot_tag_mc_joint_status_addinfo_multienc";
/// What each joint's three raw values are, after its name.
const RAW_VALUE_SUFFIXES: [&str; 3] = [
    "_primary_encoder_raw_value",
    "_secondary_encoder_raw_value",
    "_primary_encoder_diagnostic",
];

/// C++ `embObjMotionControl` as `IRawValuesPublisher`: per joint, the three words of its
/// `status addinfo multienc` (a regular), raw as the board sends them, joint after joint.
impl yarp_devices::raw_values::IRawValuesPublisher for EmbObjMotionControl {
    fn get_raw_data_map(&mut self) -> DevResult<std::collections::BTreeMap<String, Vec<i32>>> {
        let mut values = Vec::new();
        for j in 0..self.axes()? {
            let id = self.joint_id(j, tag::MC_JOINT_STATUS_ADDINFO_MULTIENC)?;
            let m: icub_eth::entities::mc::MultiEncoders =
                self.b()?.read(id).map_err(|e| self.fail(e))?;
            values.extend(m.0);
        }
        Ok(std::collections::BTreeMap::from([(
            RAW_VALUES_KEY.to_string(),
            values,
        )]))
    }

    fn get_metadata_map(
        &mut self,
    ) -> DevResult<std::collections::BTreeMap<String, yarp_devices::raw_values::RawValuesKeyMetadata>>
    {
        let names = &self.p()?.axis_names;
        let raw_value_names = names
            .iter()
            .flat_map(|n| RAW_VALUE_SUFFIXES.map(|s| format!("{n}{s}")))
            .collect();
        let m = yarp_devices::raw_values::RawValuesKeyMetadata {
            raw_value_names,
            axes_names: names.clone(),
            size: i32::try_from(3 * names.len()).unwrap_or(i32::MAX),
        };
        Ok(std::collections::BTreeMap::from([(
            RAW_VALUES_KEY.to_string(),
            m,
        )]))
    }
}

/// C++ `embObjMotionControl` as `IVirtualAnalogSensor`: the joint torques estimated by
/// the host (wholeBodyDynamics through `virtualAnalogServer`) go to the boards as
/// `joint inputs externallymeasuredtorque`, in µN·m rounded to an integer.
impl IVirtualAnalogSensor for EmbObjMotionControl {
    fn get_virtual_analog_sensor_status(&mut self, ch: usize) -> VasStatus {
        match (self.phys(ch), self.b()) {
            (Ok(_), Ok(b)) if !b.is_lost() => VasStatus::Ok,
            (Ok(_), Ok(_)) => VasStatus::Timeout,
            _ => VasStatus::Error,
        }
    }
    fn get_virtual_analog_sensor_channels(&mut self) -> usize {
        self.axes().unwrap_or(0)
    }
    fn update_virtual_analog_sensor_measure(&mut self, measure: &[f64]) -> DevResult<()> {
        for (j, v) in measure.iter().enumerate().take(self.axes()?) {
            self.update_virtual_analog_sensor_channel(j, *v)?;
        }
        Ok(())
    }
    fn update_virtual_analog_sensor_channel(&mut self, ch: usize, measure: f64) -> DevResult<()> {
        let id = self.joint_id(ch, tag::MC_JOINT_INPUTS_EXTERNALLYMEASUREDTORQUE)?;
        // C++: (eOmeas_torque_t) S_32(trqN2S(fTorque)), µN·m
        let raw = s32(measure * NEWTONS_TO_SENSOR) as f32;
        let mut bytes = raw.to_le_bytes().to_vec();
        bytes.resize(id.size().unwrap_or(4), 0);
        self.b()?.set(id, &bytes).map_err(|e| self.fail(e))
    }
}

impl IEncoders for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_encoder(&mut self, j: usize) -> DevResult<f64> {
        Ok(f64::from(self.core(j)?.position) / self.a2e(j))
    }
    fn get_encoder_speed(&mut self, j: usize) -> DevResult<f64> {
        Ok(f64::from(self.core(j)?.velocity) / self.a2e(j))
    }
    fn get_encoder_acceleration(&mut self, j: usize) -> DevResult<f64> {
        Ok(f64::from(self.core(j)?.acceleration) / self.a2e(j))
    }
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)> {
        Ok((self.get_encoder(j)?, wall_time()))
    }
    fn set_encoder(&mut self, _j: usize, _value: f64) -> DevResult<()> {
        Err(DeviceError::Unsupported(
            "setEncoder: not available on embObj boards",
        ))
    }
}

fn wall_time() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

impl IPositionControl for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// As C++ `positionMoveRaw`: sent in position, mixed, impedance-position or idle
    /// mode; in another mode the command is skipped (logged), not an error.
    fn position_move(&mut self, j: usize, target: f64) -> DevResult<()> {
        if !self.in_mode(
            j,
            &[CM_POSITION, CM_MIXED, CM_IMPEDANCE_POS, CM_IDLE],
            "positionMove",
        )? {
            return Ok(());
        }
        let a2e = self.a2e(j);
        let sp = Setpoint::Position {
            value: (target * a2e).round() as i32,
            velocity: (self.ref_speed.get(j).copied().unwrap_or(10.0) * a2e).round() as i32,
        };
        self.setpoint(j, sp)?;
        self.targets[j] = target;
        self.target_valid[j] = true;
        Ok(())
    }
    /// From the goal of the last position move in this control mode, else from where
    /// the joint is (C++ leaves relativeMove unimplemented; a move relative to a stale
    /// or never-set goal would be a large unintended motion).
    fn relative_move(&mut self, j: usize, delta: f64) -> DevResult<()> {
        self.phys(j)?;
        let from = if self.target_valid[j] {
            self.targets[j]
        } else {
            self.get_encoder(j)?
        };
        self.position_move(j, from + delta)
    }
    fn check_motion_done(&mut self, j: usize) -> DevResult<bool> {
        Ok(self.ask_u8(j, tag::MC_JOINT_STATUS_CORE_MODES_ISMOTIONDONE)? != 0)
    }
    fn set_ref_speed(&mut self, j: usize, speed: f64) -> DevResult<()> {
        self.phys(j)?;
        self.ref_speed[j] = speed.abs();
        Ok(())
    }
    /// As C++ (`accA2E_abs` then `setRefAccelerationRaw`): kept in encoder units,
    /// saturated at ±1e6; sent with the next velocity move.
    fn set_ref_acceleration(&mut self, j: usize, acc: f64) -> DevResult<()> {
        self.phys(j)?;
        self.ref_acc_raw[j] = (acc * self.a2e(j).abs()).clamp(-1e6, 1e6);
        Ok(())
    }
    fn get_ref_speed(&mut self, j: usize) -> DevResult<f64> {
        self.phys(j)?;
        Ok(self.ref_speed[j])
    }
    fn get_ref_acceleration(&mut self, j: usize) -> DevResult<f64> {
        self.phys(j)?;
        Ok(self.ref_acc_raw[j] / self.a2e(j).abs())
    }
    fn stop(&mut self, j: usize) -> DevResult<()> {
        let id = self.joint_id(j, tag::MC_JOINT_CMMNDS_STOPTRAJECTORY)?;
        self.b()?.set(id, &[1]).map_err(|e| self.fail(e))
    }
    fn get_target_position(&mut self, j: usize) -> DevResult<f64> {
        self.phys(j)?;
        Ok(self.targets[j])
    }
}

impl IVelocityControl for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// As C++ `velocityMoveRaw`: sent in velocity, mixed, impedance-velocity or idle mode,
    /// skipped (logged) in another.
    fn velocity_move(&mut self, j: usize, speed: f64) -> DevResult<()> {
        if !self.in_mode(
            j,
            &[CM_VELOCITY, CM_MIXED, CM_IMPEDANCE_VEL, CM_IDLE],
            "velocityMove",
        )? {
            return Ok(());
        }
        let a2e = self.a2e(j);
        let sp = Setpoint::Velocity {
            value: (speed * a2e).round() as i32,
            acceleration: s32(self.ref_acc_raw.get(j).copied().unwrap_or(0.0)),
        };
        self.setpoint(j, sp)?;
        self.ref_velocity[j] = speed;
        Ok(())
    }
    fn get_ref_velocity(&mut self, j: usize) -> DevResult<f64> {
        self.phys(j)?;
        Ok(self.ref_velocity[j])
    }
}

impl IControlMode for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_control_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        Ok(mode_vocab(self.core(j)?.control_mode))
    }
    /// Sends the command, then asks the board's control mode until it is the one asked
    /// (C++ `checkRemoteControlModeStatus`: up to 25 asks 10 ms apart within 250 ms;
    /// idle answers a forced idle, and a joint in hardware fault answers the call).
    fn set_control_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        const TIMEOUT: Duration = Duration::from_millis(250);
        const ATTEMPTS: usize = 25;
        const GAP: Duration = Duration::from_millis(10);
        let m = vocab_mode(mode).ok_or(DeviceError::Unsupported(
            "control mode not available on embObj boards",
        ))?;
        if m == cm::TORQUE {
            self.need_torque_control(j, "torque control mode")?;
        }
        let id = self.joint_id(j, tag::MC_JOINT_CMMNDS_CONTROLMODE)?;
        self.b()?.set(id, &[m]).map_err(|e| self.fail(e))?;
        self.mode_set_at[j] = Some(Instant::now());
        self.target_valid[j] = false;
        let want = match m {
            cm::FORCE_IDLE => cm::IDLE,
            m => m,
        };
        let start = Instant::now();
        let mut now = cm::UNKNOWN_ERROR;
        for _ in 0..ATTEMPTS {
            now = self.ask_u8(j, tag::MC_JOINT_STATUS_CORE_MODES_CONTROLMODESTATUS)?;
            if now == want {
                return Ok(());
            }
            if now == cm::HW_FAULT {
                if m != cm::FORCE_IDLE {
                    tracing::error!(device = %self.id, joint = j, "asked control mode {mode}, the joint is in hardware fault");
                }
                return Ok(());
            }
            if start.elapsed() > TIMEOUT {
                break;
            }
            std::thread::sleep(GAP);
        }
        Err(DeviceError::failed(
            &self.id,
            format!(
                "joint {j}: asked control mode {mode}, the board reports {} after {:.2} s",
                mode_vocab(now),
                start.elapsed().as_secs_f64()
            ),
        ))
    }
}

impl IInteractionMode for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_interaction_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        Ok(match self.core(j)?.interaction_mode {
            0 => IM_STIFF,
            1 => IM_COMPLIANT,
            _ => IM_UNKNOWN,
        })
    }
    fn set_interaction_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        let m: u8 = match mode {
            _ if mode == IM_STIFF => 0,
            _ if mode == IM_COMPLIANT => {
                self.need_torque_control(j, "compliant interaction")?;
                1
            }
            _ => return Err(DeviceError::Unsupported("unknown interaction mode")),
        };
        let id = self.joint_id(j, tag::MC_JOINT_CMMNDS_INTERACTIONMODE)?;
        self.b()?.set(id, &[m]).map_err(|e| self.fail(e))
    }
}

impl IAxisInfo for EmbObjMotionControl {
    fn get_axis_name(&mut self, j: usize) -> DevResult<String> {
        self.phys(j)?;
        Ok(self.p()?.axis_names[j].clone())
    }
    fn get_joint_type(&mut self, j: usize) -> DevResult<Vocab32> {
        self.phys(j)?;
        Ok(match self.p()?.axis_types[j].as_str() {
            "prismatic" => JOINTTYPE_PRISMATIC,
            _ => JOINTTYPE_REVOLUTE,
        })
    }
}

impl IControlLimits for EmbObjMotionControl {
    fn set_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()> {
        let a2e = self.a2e(j);
        let lim = PositionLimits {
            min: (min * a2e).round() as i32,
            max: (max * a2e).round() as i32,
        };
        let id = self.joint_id(j, tag::MC_JOINT_CONFIG_USERLIMITS)?;
        self.set(id, &lim)?;
        self.jconfig[j].user_limits = lim;
        Ok(())
    }
    /// C++ `getLimitsRaw`: the user limits asked of the board, 2 raw units inside them
    /// (`SAFETY_THRESHOLD`).
    fn get_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        const SAFETY_THRESHOLD: f64 = 2.0;
        let l: PositionLimits = self.ask(self.joint_id(j, tag::MC_JOINT_CONFIG_USERLIMITS)?)?;
        let a2e = self.a2e(j);
        Ok((
            (f64::from(l.min) + SAFETY_THRESHOLD) / a2e,
            (f64::from(l.max) - SAFETY_THRESHOLD) / a2e,
        ))
    }
    fn set_vel_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()> {
        self.phys(j)?;
        self.vel_limits[j] = (min, max);
        Ok(())
    }
    fn get_vel_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        self.phys(j)?;
        Ok(self.vel_limits[j])
    }
}

impl ITorqueControl for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// The board's measure (µN·m) in N·m (C++ `trqS2N`).
    fn get_torque(&mut self, j: usize) -> DevResult<f64> {
        Ok(f64::from(self.core(j)?.torque) / NEWTONS_TO_SENSOR)
    }
    /// C++ `setRefTorqueRaw`: `S_32(trqN2S(t))` µN·m.
    fn set_ref_torque(&mut self, j: usize, t: f64) -> DevResult<()> {
        self.setpoint(
            j,
            Setpoint::Torque {
                value: s32(t * NEWTONS_TO_SENSOR) as f32,
            },
        )
    }
    /// C++ `getRefTorqueRaw`: the torque reference the board reports (`ofpid` reftrq) in
    /// torque control or compliant position control, 0 otherwise; in N·m.
    fn get_ref_torque(&mut self, j: usize) -> DevResult<f64> {
        let c = self.core(j)?;
        Ok(if torque_pid_active(&c) {
            f64::from(c.ofpid[1]) / NEWTONS_TO_SENSOR
        } else {
            0.0
        })
    }
}

impl IMotorEncoders for EmbObjMotionControl {
    fn get_num_of_motor_encoders(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// The rotor position, in degrees at the joint side (the board's raw rotor units
    /// over the joint's encoder factor).
    fn get_motor_encoder(&mut self, m: usize) -> DevResult<f64> {
        Ok(f64::from(self.motor_status(m)?.basic.position) / self.a2e(m))
    }
    fn get_motor_encoder_speed(&mut self, m: usize) -> DevResult<f64> {
        Ok(f64::from(self.motor_status(m)?.basic.velocity) / self.a2e(m))
    }
    fn get_motor_encoder_acceleration(&mut self, m: usize) -> DevResult<f64> {
        Ok(f64::from(self.motor_status(m)?.basic.acceleration) / self.a2e(m))
    }
}

impl IAmplifierControl for EmbObjMotionControl {
    /// As C++: the boards enable their amplifiers with the control mode.
    fn enable_amp(&mut self, j: usize) -> DevResult<()> {
        self.phys(j).map(|_| ())
    }
    /// Deprecated, and a no-op in C++ (idle the joint with its control mode instead).
    fn disable_amp(&mut self, j: usize) -> DevResult<()> {
        self.phys(j).map(|_| ())
    }
    fn get_amp_statuses(&mut self) -> DevResult<Vec<i32>> {
        (0..self.axes()?)
            .map(|j| self.motor_status(j).map(|s| s.mc_fault_state as i32))
            .collect()
    }
    /// A (the motor status current over `ampsToSensor`).
    fn get_current(&mut self, j: usize) -> DevResult<f64> {
        let s = self.motor_status(j)?;
        Ok(f64::from(s.basic.current) / self.p()?.amps_to_sensor[j])
    }
    /// A: the board's overload current (C++ asks the motor's current limits).
    fn get_max_current(&mut self, j: usize) -> DevResult<f64> {
        Ok(f64::from(self.current_limits(j)?.overload) / self.p()?.amps_to_sensor[j])
    }
    /// Asks the limits, changes the overload current and sets them back (C++).
    fn set_max_current(&mut self, j: usize, amps: f64) -> DevResult<()> {
        self.change_current_limits(j, |l, raw| l.overload = raw, amps)
    }
    fn get_nominal_current(&mut self, m: usize) -> DevResult<f64> {
        Ok(f64::from(self.current_limits(m)?.nominal) / self.p()?.amps_to_sensor[m])
    }
    fn set_nominal_current(&mut self, m: usize, amps: f64) -> DevResult<()> {
        self.change_current_limits(m, |l, raw| l.nominal = raw, amps)
    }
    fn get_peak_current(&mut self, m: usize) -> DevResult<f64> {
        Ok(f64::from(self.current_limits(m)?.peak) / self.p()?.amps_to_sensor[m])
    }
    fn set_peak_current(&mut self, m: usize, amps: f64) -> DevResult<()> {
        self.change_current_limits(m, |l, raw| l.peak = raw, amps)
    }
    /// The motor's PWM as the board reports it, unconverted (YARP's `getPWM` is raw).
    fn get_pwm(&mut self, m: usize) -> DevResult<f64> {
        Ok(f64::from(self.motor_status(m)?.basic.pwm))
    }
    /// The board's supply voltage in its unit, 0.01 V, as C++ answers it (asked of the
    /// controller entity; YARP applies no factor).
    fn get_power_supply_voltage(&mut self, m: usize) -> DevResult<f64> {
        self.phys(m)?;
        let status: ControllerStatus = self.ask(ids::CONTROLLER_STATUS)?;
        Ok(f64::from(status.supply_voltage))
    }
    /// The motor config's `pwmLimit`, asked of the board (as C++).
    fn get_pwm_limit(&mut self, j: usize) -> DevResult<f64> {
        let id = self.motor_id(j, tag::MC_MOTOR_CONFIG_PWMLIMIT)?;
        let v: Pwm = self
            .b()?
            .ask_value(id, ASK_TIMEOUT)
            .map_err(|e| self.fail(e))?;
        Ok(f64::from(v.0))
    }
    /// Sets the motor config's `pwmLimit` on the board; negative limits are refused.
    fn set_pwm_limit(&mut self, j: usize, limit: f64) -> DevResult<()> {
        if !(0.0..=f64::from(i16::MAX)).contains(&limit) {
            return Err(DeviceError::BadParam {
                device: NAME.into(),
                param: "PWM limit".into(),
                expected: "0 to 32767",
                got: limit.to_string(),
            });
        }
        let id = self.motor_id(j, tag::MC_MOTOR_CONFIG_PWMLIMIT)?;
        let pwm = Pwm(limit as i16);
        self.set(id, &pwm)?;
        self.mconfig[j].pwm_limit = pwm.0;
        Ok(())
    }
}

impl IMotor for EmbObjMotionControl {
    /// °C through the motor's sensor (C++ `getTemperatureRaw`); NaN for a motor without
    /// one (`TemperatureSensorType` NONE or not given).
    fn get_temperature(&mut self, m: usize) -> DevResult<f64> {
        self.phys(m)?;
        let sensor = self.p()?.temperature_sensor[m];
        if sensor == TemperatureSensor::None {
            return Ok(f64::NAN);
        }
        let raw = self.motor_status(m)?.basic.temperature;
        Ok(sensor.raw_to_celsius(f64::from(raw)))
    }
    /// The warning limit, °C (C++ `getTemperatureLimitRaw`).
    fn get_temperature_limit(&mut self, m: usize) -> DevResult<f64> {
        self.phys(m)?;
        Ok(self.p()?.warning_temperature_limit[m])
    }
    fn get_number_of_motors(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_gearbox_ratio(&mut self, m: usize) -> DevResult<f64> {
        self.phys(m)?;
        Ok(self.p()?.gearbox_m2j[m])
    }
}

impl IPidControl for EmbObjMotionControl {
    /// Asked of the board, as C++.
    fn get_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<Pid> {
        let p = self.board_pid(pid_type, j)?;
        Ok(Pid {
            kp: p.kp,
            kd: p.kd,
            ki: p.ki,
            max_int: p.max_int,
            scale: p.scale,
            max_output: p.max_output,
            offset: p.offset,
            stiction_up: p.stiction_up,
            stiction_down: p.stiction_down,
            kff: p.kff,
        })
    }
    /// YARP's `convert_pid_to_machine`, then set on the board.
    fn set_pid(&mut self, pid_type: Vocab32, j: usize, pid: Pid) -> DevResult<()> {
        self.phys(j)?;
        let kind = Self::pid_kind(pid_type)?;
        let (fbk, out) = self.p()?.pid_factors(kind, j);
        let old = PidParams::from_eo(self.pid_slot(kind, j), fbk, out);
        let new = PidParams {
            kp: pid.kp,
            kd: pid.kd,
            ki: pid.ki,
            max_int: pid.max_int,
            max_output: pid.max_output,
            offset: pid.offset,
            scale: pid.scale,
            stiction_up: pid.stiction_up,
            stiction_down: pid.stiction_down,
            kff: pid.kff,
            ..old
        };
        let eo = new.to_eo(fbk, out);
        self.set(self.pid_id(kind, j)?, &eo)?;
        *self.pid_slot(kind, j) = eo;
        Ok(())
    }
    fn enable_pid(&mut self, _pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.phys(j).map(|_| ())
    }
    /// A no-op in C++ (`disablePidRaw`), kept so.
    fn disable_pid(&mut self, _pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.phys(j).map(|_| ())
    }
    fn is_pid_enabled(&mut self, _pid_type: Vocab32, j: usize) -> DevResult<bool> {
        let m = self.core(j)?.control_mode;
        Ok(!matches!(
            m,
            cm::IDLE | cm::FORCE_IDLE | cm::HW_FAULT | cm::NOT_CONFIGURED | cm::CONFIGURED
        ))
    }
    fn set_pid_reference(&mut self, pid_type: Vocab32, j: usize, r: f64) -> DevResult<()> {
        match pid_type {
            _ if pid_type == PIDTYPE_POSITION => self.set_position(j, r),
            _ if pid_type == PIDTYPE_TORQUE => self.set_ref_torque(j, r),
            _ if pid_type == PIDTYPE_CURRENT => self.set_ref_current(j, r),
            _ => Err(DeviceError::Unsupported("PID reference of this type")),
        }
    }
    fn get_pid_reference(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        match pid_type {
            // C++ getPidReferenceRaw: none in torque, PWM or current control
            _ if pid_type == PIDTYPE_POSITION => {
                let c = self.core(j)?;
                if matches!(c.control_mode, cm::TORQUE | cm::OPENLOOP | cm::CURRENT) {
                    return Ok(0.0);
                }
                let (fbk, _) = self.p()?.pid_factors(PidKind::Position, j);
                Ok(f64::from(c.ofpid[0]) / fbk)
            }
            _ if pid_type == PIDTYPE_TORQUE => self.get_ref_torque(j),
            _ if pid_type == PIDTYPE_CURRENT => self.get_ref_current(j),
            _ => Err(DeviceError::Unsupported("PID reference of this type")),
        }
    }
    /// C++ `getPidErrorRaw` over the feedback factor: the position error (none in
    /// torque, PWM or current control), the torque error in torque or compliant
    /// position control; 0 for the others.
    fn get_pid_error(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        let kind = Self::pid_kind(pid_type)?;
        let c = self.core(j)?;
        let raw = match kind {
            PidKind::Position
                if !matches!(c.control_mode, cm::TORQUE | cm::OPENLOOP | cm::CURRENT) =>
            {
                c.ofpid[2]
            }
            PidKind::Torque if torque_pid_active(&c) => c.ofpid[3],
            _ => 0,
        };
        let (fbk, _) = self.p()?.pid_factors(kind, j);
        Ok(f64::from(raw) / fbk)
    }
    /// C++ `getPidOutputRaw` over the output factor: the output of the position PID
    /// (none in torque or current control) or of the torque PID (in torque or compliant
    /// position control); 0 for the others.
    fn get_pid_output(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        let kind = Self::pid_kind(pid_type)?;
        let c = self.core(j)?;
        let raw = match kind {
            PidKind::Position if !matches!(c.control_mode, cm::TORQUE | cm::CURRENT) => c.ofpid[4],
            PidKind::Torque if torque_pid_active(&c) => c.ofpid[4],
            _ => 0,
        };
        let (_, out) = self.p()?.pid_factors(kind, j);
        Ok(f64::from(raw) / out)
    }
}

impl ICurrentControl for EmbObjMotionControl {
    fn get_ref_current(&mut self, j: usize) -> DevResult<f64> {
        self.phys(j)?;
        Ok(self.ref_current[j])
    }
    fn set_ref_current(&mut self, j: usize, current: f64) -> DevResult<()> {
        let raw = current * self.p()?.amps_to_sensor.get(j).copied().unwrap_or(1000.0);
        self.setpoint(
            j,
            Setpoint::Current {
                value: raw.round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16,
            },
        )?;
        self.ref_current[j] = current;
        Ok(())
    }
    fn get_current_range(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let max = IAmplifierControl::get_max_current(self, j)?;
        Ok((-max, max))
    }
}

impl IPwmControl for EmbObjMotionControl {
    fn get_ref_duty_cycle(&mut self, j: usize) -> DevResult<f64> {
        self.phys(j)?;
        Ok(self.ref_pwm[j])
    }
    fn set_ref_duty_cycle(&mut self, j: usize, duty: f64) -> DevResult<()> {
        let full = self.p()?.full_scale_pwm.get(j).copied().unwrap_or(32000.0);
        let raw = (duty / 100.0 * full).round();
        self.setpoint(
            j,
            Setpoint::OpenLoop {
                value: raw.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16,
            },
        )?;
        self.ref_pwm[j] = duty;
        Ok(())
    }
    fn get_duty_cycle(&mut self, m: usize) -> DevResult<f64> {
        let s = self.motor_status(m)?;
        let full = self.p()?.full_scale_pwm[m];
        Ok(if full != 0.0 {
            f64::from(s.basic.pwm) / full * 100.0
        } else {
            f64::from(s.basic.pwm)
        })
    }
}

impl IPositionDirect for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// As C++ `setPositionRaw`: sent in position-direct or idle mode, skipped (logged) in
    /// another.
    fn set_position(&mut self, j: usize, reference: f64) -> DevResult<()> {
        if !self.in_mode(j, &[CM_POSITION_DIRECT, CM_IDLE], "setPosition")? {
            return Ok(());
        }
        let a2e = self.a2e(j);
        self.setpoint(
            j,
            Setpoint::PositionRaw {
                value: (reference * a2e).round() as i32,
            },
        )?;
        self.ref_position[j] = reference;
        Ok(())
    }
    fn get_ref_position(&mut self, j: usize) -> DevResult<f64> {
        self.phys(j)?;
        Ok(self.ref_position[j])
    }
}

/// icub-main's `_impedance_limits` of the Ethernet boards (the same for every joint).
const IMPEDANCE_LIMITS: ImpedanceLimits = ImpedanceLimits {
    min_stiffness: 0.002,
    max_stiffness: 9.889,
    min_damping: 0.001,
    max_damping: 9.888,
};

impl IImpedanceControl for EmbObjMotionControl {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    /// The board's stiffness and damping (µN·m per encoder unit) in N·m/deg and
    /// N·m/(deg/s), as absolute values (YARP `impS2N`, `fabs`).
    fn get_impedance(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let i = self.board_impedance(j)?;
        let p = self.p()?;
        Ok((
            p.imp_from_raw(j, f64::from(i.stiffness)).abs(),
            p.imp_from_raw(j, f64::from(i.damping)).abs(),
        ))
    }
    /// Sent in µN·m per encoder unit (YARP `impN2S`: × 1e6 / `Encoder`).
    fn set_impedance(&mut self, j: usize, stiffness: f64, damping: f64) -> DevResult<()> {
        self.phys(j)?;
        let mut i = self.jconfig[j].impedance;
        let p = self.p()?;
        i.stiffness = p.imp_to_raw(j, stiffness) as f32;
        i.damping = p.imp_to_raw(j, damping) as f32;
        self.set(self.joint_id(j, tag::MC_JOINT_CONFIG_IMPEDANCE)?, &i)?;
        self.jconfig[j].impedance = i;
        Ok(())
    }
    /// N·m (the board's µN·m over 1e6, YARP `trqS2N`).
    fn get_impedance_offset(&mut self, j: usize) -> DevResult<f64> {
        let i = self.board_impedance(j)?;
        Ok(f64::from(i.offset) / NEWTONS_TO_SENSOR)
    }
    /// Sent as `S_32(trqN2S(offset))` µN·m (C++ `setImpedanceOffsetRaw`).
    fn set_impedance_offset(&mut self, j: usize, offset: f64) -> DevResult<()> {
        self.phys(j)?;
        let mut i = self.jconfig[j].impedance;
        i.offset = s32(offset * NEWTONS_TO_SENSOR) as f32;
        self.set(self.joint_id(j, tag::MC_JOINT_CONFIG_IMPEDANCE)?, &i)?;
        self.jconfig[j].impedance = i;
        Ok(())
    }
    fn get_current_impedance_limit(&mut self, j: usize) -> DevResult<ImpedanceLimits> {
        self.phys(j)?;
        Ok(IMPEDANCE_LIMITS)
    }
}

impl IControlCalibration for EmbObjMotionControl {
    /// C++ `calibrateAxisWithParamsRaw`: the same command with the three parameters.
    fn calibrate_axis_with_params(
        &mut self,
        j: usize,
        kind: u32,
        p1: f64,
        p2: f64,
        p3: f64,
    ) -> DevResult<()> {
        self.set_calibration_parameters(
            j,
            &CalibrationParameters {
                kind,
                param1: p1,
                param2: p2,
                param3: p3,
                ..Default::default()
            },
        )
    }
    /// C++ `setCalibrationParametersRaw`: `set<joint cmmnds calibration>` with the
    /// type's parameters (`paramZero` in encoder units).
    fn set_calibration_parameters(
        &mut self,
        j: usize,
        params: &CalibrationParameters,
    ) -> DevResult<()> {
        let zero = (params.param_zero * self.a2e(j)).round() as i32;
        let c = calibrator(params, zero).ok_or(DeviceError::Unsupported(
            "calibration type or parameters not accepted by embObj boards",
        ))?;
        self.set(self.joint_id(j, tag::MC_JOINT_CMMNDS_CALIBRATION)?, &c)?;
        self.mode_set_at[j] = Some(Instant::now());
        Ok(())
    }
    /// C++ `calibrationDoneRaw`: done once the joint left calibration for a working
    /// mode; idle counts only with `MAINTENANCE/skipRecalibration`, and a joint in
    /// hardware fault, not configured, configured or in error has not calibrated.
    /// The mode is the board's regular status (C++ `getLocalValue`), not asked.
    fn calibration_done(&mut self, j: usize) -> DevResult<bool> {
        let m = self.core(j)?.control_mode;
        Ok(match m {
            cm::IDLE => self.skip_recalibration,
            cm::CALIB => false,
            cm::HW_FAULT | cm::NOT_CONFIGURED | cm::CONFIGURED | cm::UNKNOWN_ERROR => {
                tracing::error!(device = %self.id, joint = j, "unable to complete calibration: the joint is {}", mode_vocab(m));
                false
            }
            _ => true,
        })
    }
}
