//! Streaming commands on `/<name>/command:i` (C++ `StreamingMessagesParser`), as pure
//! functions: the message codec and `handle_command`.
//!
//! A command is C++ `CommandMessage` = `PortablePair<Bottle, Vector>`: a list of two, the
//! head (`[vmo] 0`, `[vmos]`, `[dtq] 0`, `[icur] [ref] 0` ...) and a float64 vector of
//! values (`(5.0)`, `(1.0 2.0 3.0 4.0)`). No reply is sent.
//!
//! Served heads: `[poss]`; velocity `[vmo] j`, `[vmos]`, `[vmog] n (joints)`; position
//! direct `[dpo] j`, `[dpos]`, `[dpog] n (joints)`; torque `[dtq] j`, `[dtqs]`,
//! `[dtqg] n (joints)`; current `[icur] [ref] j`, `[icur] [refs]`, `[icur] [refg] n
//! (joints)`; duty cycle `[ipwm] [ref] j`, `[ipwm] [refs]`.

use crate::driver::DeviceDriver;
use crate::error::DeviceError;
use crate::vocabs::{
    CURRENT_IFACE, POSITION_DIRECT, POSITION_DIRECTS, POSITION_DIRECT_GROUP, POSITION_MOVES,
    PWM_IFACE, REF, REFS, REF_GROUP, VELOCITY_MOVE, VELOCITY_MOVES, VELOCITY_MOVE_GROUP,
};
use yarp_proto::{Bottle, Value, Vocab32};

const fn v(s: &str) -> i32 {
    Vocab32::new(s).0
}
const TORQUES_DIRECT: i32 = v("dtq");
const TORQUES_DIRECTS: i32 = v("dtqs");
const TORQUES_DIRECT_GROUP: i32 = v("dtqg");

/// One streaming command: the head Bottle and the values.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandMessage {
    pub head: Bottle,
    pub body: Vec<f64>,
}

/// Why a streaming command was not applied (C++ logs these and carries on).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandError {
    #[error("not a command message (a pair `(head) (values)`): `{0}`")]
    NotAPair(String),
    #[error("{got} values for a board of {axes} axes")]
    TooManyValues { got: usize, axes: usize },
    #[error("malformed command head `{0}`")]
    BadHead(String),
    #[error("command `{0}` carries too few values")]
    MissingValues(String),
    #[error("unrecognized streaming command `{0}`")]
    Unknown(String),
    #[error("`{command}` needs an interface the device lacks: {interface}")]
    NoInterface {
        command: String,
        interface: &'static str,
    },
    #[error("the device refused `{command}`: {source}")]
    Device {
        command: String,
        source: DeviceError,
    },
}

impl CommandMessage {
    pub fn new(head: Bottle, body: Vec<f64>) -> CommandMessage {
        CommandMessage { head, body }
    }

    /// The Bottle form that travels.
    pub fn to_bottle(&self) -> Bottle {
        let mut b = Bottle::with_capacity(2);
        b.push(Value::List(self.head.clone()));
        b.push(Value::List(self.body.iter().copied().collect()));
        b
    }

    /// Reads a received message.
    pub fn from_bottle(b: &Bottle) -> Result<CommandMessage, CommandError> {
        let not_pair = || CommandError::NotAPair(b.to_string());
        if b.len() != 2 {
            return Err(not_pair());
        }
        let head = b[0].as_list().ok_or_else(not_pair)?.clone();
        let body = b[1]
            .as_list()
            .ok_or_else(not_pair)?
            .iter()
            .map(Value::as_f64)
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(not_pair)?;
        Ok(CommandMessage { head, body })
    }
}

fn vocab_at(b: &Bottle, i: usize) -> i32 {
    match b.get(i) {
        Some(Value::Vocab32(x)) => x.0,
        _ => 0,
    }
}

/// Applies one streaming command to `dev`, which has `axes` joints.
pub fn handle_command(
    msg: &CommandMessage,
    dev: &mut dyn DeviceDriver,
    axes: usize,
) -> Result<(), CommandError> {
    let head = &msg.head;
    let body = &msg.body;
    let command = || format!("({head}) ({} values)", body.len());
    if body.len() > axes {
        return Err(CommandError::TooManyValues {
            got: body.len(),
            axes,
        });
    }
    let int_at = |i: usize| -> Result<i64, CommandError> {
        head.get(i)
            .filter(|v| v.is_int())
            .and_then(Value::as_i64)
            .ok_or_else(|| CommandError::BadHead(head.to_string()))
    };
    let joint_at = |i: usize| -> Result<usize, CommandError> {
        usize::try_from(int_at(i)?).map_err(|_| CommandError::BadHead(head.to_string()))
    };
    let first = || -> Result<f64, CommandError> {
        body.first()
            .copied()
            .ok_or_else(|| CommandError::MissingValues(head.to_string()))
    };
    // `n (joints...)` starting at `i`, with one value per joint
    let group = |i: usize| -> Result<Vec<usize>, CommandError> {
        let n = usize::try_from(int_at(i)?).map_err(|_| CommandError::BadHead(head.to_string()))?;
        let joints = head
            .get(i + 1)
            .and_then(Value::as_list)
            .ok_or_else(|| CommandError::BadHead(head.to_string()))?
            .iter()
            .map(|v| v.as_i64().and_then(|x| usize::try_from(x).ok()))
            .collect::<Option<Vec<usize>>>()
            .ok_or_else(|| CommandError::BadHead(head.to_string()))?;
        if joints.len() != n || body.len() != n {
            return Err(CommandError::MissingValues(head.to_string()));
        }
        Ok(joints)
    };
    let missing = |interface: &'static str| CommandError::NoInterface {
        command: command(),
        interface,
    };
    let refused = |source: DeviceError| CommandError::Device {
        command: command(),
        source,
    };
    match vocab_at(head, 0) {
        POSITION_MOVES => dev
            .as_position_control()
            .ok_or_else(|| missing("IPositionControl"))?
            .position_moves(body),
        VELOCITY_MOVE => {
            let (j, x) = (joint_at(1)?, first()?);
            dev.as_velocity_control()
                .ok_or_else(|| missing("IVelocityControl"))?
                .velocity_move(j, x)
        }
        VELOCITY_MOVES => dev
            .as_velocity_control()
            .ok_or_else(|| missing("IVelocityControl"))?
            .velocity_moves(body),
        VELOCITY_MOVE_GROUP => {
            let joints = group(1)?;
            dev.as_velocity_control()
                .ok_or_else(|| missing("IVelocityControl"))?
                .velocity_move_group(&joints, body)
        }
        TORQUES_DIRECT => {
            let (j, x) = (joint_at(1)?, first()?);
            dev.as_torque_control()
                .ok_or_else(|| missing("ITorqueControl"))?
                .set_ref_torque(j, x)
        }
        TORQUES_DIRECTS | TORQUES_DIRECT_GROUP => {
            let joints: Vec<usize> = if vocab_at(head, 0) == TORQUES_DIRECTS {
                (0..body.len()).collect()
            } else {
                group(1)?
            };
            let t = dev
                .as_torque_control()
                .ok_or_else(|| missing("ITorqueControl"))?;
            joints
                .iter()
                .zip(body)
                .try_for_each(|(j, x)| t.set_ref_torque(*j, *x))
        }
        POSITION_DIRECT => {
            let (j, x) = (joint_at(1)?, first()?);
            dev.as_position_direct()
                .ok_or_else(|| missing("IPositionDirect"))?
                .set_position(j, x)
        }
        POSITION_DIRECTS => dev
            .as_position_direct()
            .ok_or_else(|| missing("IPositionDirect"))?
            .set_positions(body),
        POSITION_DIRECT_GROUP => {
            let joints = group(1)?;
            dev.as_position_direct()
                .ok_or_else(|| missing("IPositionDirect"))?
                .set_positions_group(&joints, body)
        }
        PWM_IFACE if vocab_at(head, 1) == REF => {
            let (j, x) = (joint_at(2)?, first()?);
            dev.as_pwm_control()
                .ok_or_else(|| missing("IPWMControl"))?
                .set_ref_duty_cycle(j, x)
        }
        PWM_IFACE if vocab_at(head, 1) == REFS => dev
            .as_pwm_control()
            .ok_or_else(|| missing("IPWMControl"))?
            .set_ref_duty_cycles(body),
        CURRENT_IFACE if vocab_at(head, 1) == REF => {
            let (j, x) = (joint_at(2)?, first()?);
            dev.as_current_control()
                .ok_or_else(|| missing("ICurrentControl"))?
                .set_ref_current(j, x)
        }
        CURRENT_IFACE if vocab_at(head, 1) == REFS => dev
            .as_current_control()
            .ok_or_else(|| missing("ICurrentControl"))?
            .set_ref_currents(body),
        CURRENT_IFACE if vocab_at(head, 1) == REF_GROUP => {
            let joints = group(2)?;
            dev.as_current_control()
                .ok_or_else(|| missing("ICurrentControl"))?
                .set_ref_current_group(&joints, body)
        }
        _ => return Err(CommandError::Unknown(head.to_string())),
    }
    .map_err(refused)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interfaces::IVelocityControl;
    use crate::FakeMotionControl;

    fn msg(text: &str) -> CommandMessage {
        CommandMessage::from_bottle(&Bottle::from_text(text)).unwrap()
    }

    #[test]
    fn velocity_commands_reach_the_device() {
        let mut dev = FakeMotionControl::with_joints(4);
        handle_command(&msg("([vmo] 1) (5.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_velocity(1).unwrap(), 5.0);
        handle_command(&msg("([vmos]) (1.0 2.0 3.0 4.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_velocity(3).unwrap(), 4.0);
        handle_command(&msg("([vmog] 2 (0 2)) (7.0 8.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_velocity(2).unwrap(), 8.0);
    }

    #[test]
    fn position_direct_current_and_pwm_commands_reach_the_device() {
        use crate::interfaces::{ICurrentControl, IPositionDirect, IPwmControl};
        let mut dev = FakeMotionControl::with_joints(4);
        handle_command(&msg("([dpo] 0) (1.5)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_position(0).unwrap(), 1.5);
        handle_command(&msg("([dpos]) (1.0 2.0 3.0 4.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_positions().unwrap(), [1.0, 2.0, 3.0, 4.0]);
        handle_command(&msg("([dpog] 2 (1 3)) (7.0 8.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_positions().unwrap(), [1.0, 7.0, 3.0, 8.0]);
        handle_command(&msg("([icur] [ref] 0) (0.5)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_current(0).unwrap(), 0.5);
        handle_command(&msg("([icur] [refs]) (1.0 2.0 3.0 4.0)"), &mut dev, 4).unwrap();
        handle_command(&msg("([icur] [refg] 1 (2)) (9.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_current(2).unwrap(), 9.0);
        assert_eq!(dev.get_ref_current(3).unwrap(), 4.0);
        handle_command(&msg("([ipwm] [ref] 0) (10.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_ref_duty_cycle(0).unwrap(), 10.0);
        assert_eq!(dev.get_duty_cycle(0).unwrap(), 10.0);
        handle_command(&msg("([ipwm] [refs]) (1.0 2.0 3.0 4.0)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_duty_cycle(3).unwrap(), 4.0);
    }

    #[test]
    fn bad_commands_are_errors_not_panics() {
        let mut dev = FakeMotionControl::with_joints(2);
        for (text, want) in [
            ("([vmo]) (5.0)", "malformed"),
            ("([vmo] 0) ()", "too few"),
            ("([vmos]) (1.0 2.0 3.0)", "3 values"),
            ("([zzz] 0) (1.0)", "unrecognized"),
            ("([vmog] 2 (0)) (1.0 2.0)", "too few"),
            ("([dpo]) (1.0)", "malformed"),
            ("([icur] [ref]) (1.0)", "malformed"),
            ("([vmo] 9) (1.0)", "refused"),
        ] {
            let e = handle_command(&msg(text), &mut dev, 2).unwrap_err();
            assert!(e.to_string().contains(want), "{text}: {e}");
        }
        assert!(CommandMessage::from_bottle(&Bottle::from_text("[vmo] 0 5.0")).is_err());
        assert!(CommandMessage::from_bottle(&Bottle::from_text("([vmo] 0) (a)")).is_err());
    }
}
