//! Vocab codes used by the control-board interfaces and protocol (as in C++ YARP).
#![allow(missing_docs)]

use yarp_proto::Vocab32;

const fn v(s: &str) -> i32 {
    Vocab32::new(s).0
}

// generic
pub const SET: i32 = v("set");
pub const GET: i32 = v("get");
pub const IS: i32 = v("is");
pub const OK: i32 = v("ok");
pub const FAILED: i32 = v("fail");
pub const NAK: i32 = v("nak");
pub const TIMESTAMP: i32 = v("tsta");
pub const PROTOCOL_VERSION: i32 = v("prot");

// remote variables (IRemoteVariables)
pub const REMOTE_VARIABLE_IFACE: i32 = v("ivar");
pub const VARIABLE: i32 = v("mvar");
pub const VARIABLE_LIST: i32 = v("lvar");

// joint faults (IJointFault)
pub const JOINT_FAULT_IFACE: i32 = v("ijfl");
pub const GET_JOINT_FAULT: i32 = v("jhfl");

// encoders
pub const AXES: i32 = v("axes");
pub const ENCODER: i32 = v("enc");
pub const ENCODERS: i32 = v("encs");
pub const ENCODER_SPEED: i32 = v("esp");
pub const ENCODER_SPEEDS: i32 = v("esps");
pub const ENCODER_ACCELERATION: i32 = v("eac");
pub const ENCODER_ACCELERATIONS: i32 = v("eacs");
pub const E_RESET: i32 = v("ere");
pub const E_RESETS: i32 = v("eres");

// position / velocity control
pub const POSITION_MOVE: i32 = v("pos");
pub const POSITION_MOVES: i32 = v("poss");
pub const POSITION_MOVE_GROUP: i32 = v("posg");
pub const RELATIVE_MOVE: i32 = v("rel");
pub const RELATIVE_MOVES: i32 = v("rels");
pub const RELATIVE_MOVE_GROUP: i32 = v("relg");
pub const MOTION_DONE: i32 = v("don");
pub const MOTION_DONES: i32 = v("dons");
pub const MOTION_DONE_GROUP: i32 = v("dong");
pub const REF_SPEED: i32 = v("vel");
pub const REF_SPEEDS: i32 = v("vels");
pub const REF_SPEED_GROUP: i32 = v("velg");
pub const REF_ACCELERATION: i32 = v("acc");
pub const REF_ACCELERATIONS: i32 = v("accs");
pub const REF_ACCELERATION_GROUP: i32 = v("accg");
pub const STOP: i32 = v("sto");
pub const STOPS: i32 = v("stos");
pub const STOP_GROUP: i32 = v("stog");
pub const VELOCITY_MOVE: i32 = v("vmo");
pub const VELOCITY_MOVES: i32 = v("vmos");
pub const VELOCITY_MOVE_GROUP: i32 = v("vmog");
pub const POSITION_DIRECT: i32 = v("dpo");
pub const POSITION_DIRECTS: i32 = v("dpos");
pub const POSITION_DIRECT_GROUP: i32 = v("dpog");

// limits / info
pub const LIMITS: i32 = v("llim");
pub const VEL_LIMITS: i32 = v("vlim");
pub const INFO_NAME: i32 = v("name");
pub const INFO_TYPE: i32 = v("type");

// motor encoders, amplifiers, motors
pub const MOTOR_ENCODER_NUMBER: i32 = v("mnum");
pub const MOTOR_ENCODER: i32 = v("mnc");
pub const MOTOR_ENCODERS: i32 = v("mncs");
pub const MOTOR_E_RESET: i32 = v("mre");
pub const MOTOR_E_RESETS: i32 = v("mres");
pub const AMP_ENABLE: i32 = v("aen");
pub const AMP_DISABLE: i32 = v("adi");
pub const AMP_STATUS: i32 = v("asta");
pub const AMP_CURRENT: i32 = v("acu");
pub const AMP_MAXCURRENT: i32 = v("maxc");
pub const AMP_CURRENTS: i32 = v("acus");
pub const AMP_STATUS_SINGLE: i32 = v("asts");
pub const AMP_NOMINAL_CURRENT: i32 = v("acno");
pub const AMP_PEAK_CURRENT: i32 = v("acpk");
pub const AMP_PWM: i32 = v("pwm");
pub const AMP_PWM_LIMIT: i32 = v("pwml");
pub const AMP_VOLTAGE_SUPPLY: i32 = v("avsu");
pub const TEMPERATURE: i32 = v("tmp");
pub const TEMPERATURES: i32 = v("tmps");
pub const TEMPERATURE_LIMIT: i32 = v("tmpl");
pub const MOTOR_ENCODER_SPEED: i32 = v("msp");
pub const MOTOR_ENCODER_SPEEDS: i32 = v("msps");
pub const MOTOR_ENCODER_ACCELERATION: i32 = v("mac");
pub const MOTOR_ENCODER_ACCELERATIONS: i32 = v("macs");
pub const MOTORS_NUMBER: i32 = v("mtnm");
pub const GEARBOX_RATIO: i32 = v("gbxr");

// interface families (second element of the command)
pub const ICONTROLMODE: i32 = v("icmd");
pub const CM_CONTROL_MODE: i32 = v("cmod");
pub const CM_CONTROL_MODES: i32 = v("cmds");
pub const CM_CONTROL_MODE_GROUP: i32 = v("cmog");
pub const INTERACTION_MODE_IFACE: i32 = v("intm");
pub const INTERACTION_MODE: i32 = v("mode");
pub const INTERACTION_MODES: i32 = v("mods");
pub const INTERACTION_MODE_GROUP: i32 = v("mobg");
pub const TORQUE: i32 = v("torq");
pub const TRQ: i32 = v("trq");
pub const TRQS: i32 = v("trqs");
pub const REF: i32 = v("ref");
pub const PID: i32 = v("pid");
pub const PID_ENABLE: i32 = v("ena");
pub const PID_DISABLE: i32 = v("dis");
pub const PID_ERROR: i32 = v("err");
pub const PID_OUTPUT: i32 = v("out");
pub const PID_RESET: i32 = v("res");
pub const RANGE: i32 = v("rng");
pub const RANGES: i32 = v("rngs");
pub const PIDS: i32 = v("pids");
pub const PID_ERROR_LIMIT: i32 = v("lim");
pub const PID_ERROR_LIMITS: i32 = v("lims");
pub const PID_ERRORS: i32 = v("errs");
pub const PID_OUTPUTS: i32 = v("outs");
pub const PID_OFFSET: i32 = v("off");
pub const MOTOR_PARAMS: i32 = v("mtps");
pub const MOTOR_CPR: i32 = v("mcpr");
pub const REFS: i32 = v("refs");
pub const REF_GROUP: i32 = v("refg");
pub const PWM_OUTPUT: i32 = v("pwm");
pub const PWM_OUTPUTS: i32 = v("pwms");
pub const CURRENT_IFACE: i32 = v("icur");
pub const PWM_IFACE: i32 = v("ipwm");

// impedance (C++ `VOCAB_IMPEDANCE` is "iimp"; 3.12 asks the limits with `VOCAB_LIMITS`
// "llim", later releases with "ilim")
pub const IMPEDANCE: i32 = v("iimp");
pub const IMP_PARAM: i32 = v("ipr");
pub const IMP_OFFSET: i32 = v("iof");

// IControlCalibration: commands without an interface vocab (`[calj] j ...`)
pub const CALIBRATE_JOINT: i32 = v("calj");
pub const CALIBRATE_JOINT_PARAMS: i32 = v("cljp");
pub const CALIBRATE: i32 = v("cal");
pub const CALIBRATE_DONE: i32 = v("cald");
pub const ABORTCALIB: i32 = v("abca");
pub const ABORTPARK: i32 = v("abpa");
pub const PARK: i32 = v("park");

// IRemoteCalibrator (C++ `CalibratorVocabs.h`)
pub const REMOTE_CALIBRATOR_IFACE: i32 = v("reca");
pub const IS_CALIBRATOR_PRESENT: i32 = v("isca");
pub const CALIBRATE_SINGLE_JOINT: i32 = v("cal");
pub const CALIBRATE_WHOLE_PART: i32 = v("cals");
pub const HOMING_SINGLE_JOINT: i32 = v("hom");
pub const HOMING_WHOLE_PART: i32 = v("homs");
pub const PARK_SINGLE_JOINT: i32 = v("par");
pub const PARK_WHOLE_PART: i32 = v("pars");
pub const QUIT_CALIBRATE: i32 = v("quca");
pub const QUIT_PARK: i32 = v("qupa");

// control mode values
pub const CM_IDLE: Vocab32 = Vocab32::new("idl");
pub const CM_POSITION: Vocab32 = Vocab32::new("pos");
pub const CM_POSITION_DIRECT: Vocab32 = Vocab32::new("posd");
pub const CM_VELOCITY: Vocab32 = Vocab32::new("vel");
pub const CM_TORQUE: Vocab32 = Vocab32::new("torq");
pub const CM_CURRENT: Vocab32 = Vocab32::new("icur");
pub const CM_PWM: Vocab32 = Vocab32::new("ipwm");
pub const CM_MIXED: Vocab32 = Vocab32::new("mix");
pub const CM_HW_FAULT: Vocab32 = Vocab32::new("hwfa");
pub const CM_FORCE_IDLE: Vocab32 = Vocab32::new("fidl");
/// Deprecated in YARP, still reported by boards.
pub const CM_IMPEDANCE_POS: Vocab32 = Vocab32::new("impo");
/// Deprecated in YARP, still reported by boards.
pub const CM_IMPEDANCE_VEL: Vocab32 = Vocab32::new("imve");
pub const CM_CALIBRATING: Vocab32 = Vocab32::new("cal");
pub const CM_CALIB_DONE: Vocab32 = Vocab32::new("cald");
pub const CM_NOT_CONFIGURED: Vocab32 = Vocab32::new("cfgn");
pub const CM_CONFIGURED: Vocab32 = Vocab32::new("cfgy");
pub const CM_UNKNOWN: Vocab32 = Vocab32::new("unkw");

// interaction mode values
pub const IM_STIFF: Vocab32 = Vocab32::new("stif");
pub const IM_COMPLIANT: Vocab32 = Vocab32::new("comp");
pub const IM_UNKNOWN: Vocab32 = Vocab32(0);

// joint types (C++ `JointTypeEnum`; the recorded fake answers 1987212385 = "atrv")
pub const JOINTTYPE_REVOLUTE: Vocab32 = Vocab32::new("atrv");
pub const JOINTTYPE_PRISMATIC: Vocab32 = Vocab32::new("atpr");
pub const JOINTTYPE_UNKNOWN: Vocab32 = Vocab32::new("unkn");

// PID types
pub const PIDTYPE_POSITION: Vocab32 = Vocab32::new("pos");
pub const PIDTYPE_VELOCITY: Vocab32 = Vocab32::new("vel");
pub const PIDTYPE_TORQUE: Vocab32 = Vocab32::new("trq");
pub const PIDTYPE_CURRENT: Vocab32 = Vocab32::new("cur");
