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

use super::v3::{Group, Wire3};
use crate::driver::DeviceDriver;
use crate::error::DeviceError;
use crate::vocabs::{
    CURRENT_IFACE, POSITION_DIRECT, POSITION_DIRECTS, POSITION_DIRECT_GROUP, POSITION_MOVES,
    PWM_IFACE, REF, REFS, REF_GROUP, VELOCITY_MOVE, VELOCITY_MOVES, VELOCITY_MOVE_GROUP,
};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value, Vocab32};

const fn v(s: &str) -> i32 {
    Vocab32::new(s).0
}
const TORQUES_DIRECT: i32 = v("dtq");
const TORQUES_DIRECTS: i32 = v("dtqs");
const TORQUES_DIRECT_GROUP: i32 = v("dtqg");
// YARP 4.0 names the interface first (`[ivel] [vmo] j`; current and PWM always did).
const IPOS: i32 = v("ipos");
const IPOD: i32 = v("ipod");
const IVEL: i32 = v("ivel");
const ITRQ: i32 = v("itrq");
const IVED: i32 = v("ived");
const VDSO: i32 = v("vdso");
const VDSA: i32 = v("vdsa");
const VDSG: i32 = v("vdsg");
// YARP 4.0 streams a PID's offset and feedforward: `[ipid] [poff] <type> j`
const IPID: i32 = v("ipid");
const POFF: i32 = v("poff");
const PFFD: i32 = v("pffd");

/// What a streaming command sets. Each has one shape of joints ([`Shape`]) and a head in
/// each generation ([`Kind::heads`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    PositionMoves,
    VelocityMove,
    VelocityMoves,
    VelocityMoveGroup,
    RefTorque,
    RefTorques,
    RefTorqueGroup,
    Position,
    Positions,
    PositionGroup,
    RefDutyCycle,
    RefDutyCycles,
    RefCurrent,
    RefCurrents,
    RefCurrentGroup,
    /// 4.0's `IVelocityDirect` (no 3.12 form).
    VelocityDirect,
    VelocitiesDirect,
    VelocitiesDirectGroup,
    /// 4.0's streamed PID offset and feedforward (no 3.12 form; 3.12 sets the offset by
    /// RPC).
    PidOffset,
    PidFeedforward,
}

/// Which joints a command addresses, after its head's vocabs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Joints {
    /// `j`: one joint, the first value.
    One(usize),
    /// nothing: every joint, one value each (fewer are accepted, as C++ does).
    All,
    /// `n (j1 j2 ...)`: these joints, one value each.
    Group(Vec<usize>),
    /// `<type> j`: joint `j`'s PID of this type (3.12's names; 4.0's on the wire).
    Pid(Vocab32, usize),
}

impl Kind {
    const ALL: [Kind; 20] = [
        Kind::PositionMoves,
        Kind::VelocityMove,
        Kind::VelocityMoves,
        Kind::VelocityMoveGroup,
        Kind::RefTorque,
        Kind::RefTorques,
        Kind::RefTorqueGroup,
        Kind::Position,
        Kind::Positions,
        Kind::PositionGroup,
        Kind::RefDutyCycle,
        Kind::RefDutyCycles,
        Kind::RefCurrent,
        Kind::RefCurrents,
        Kind::RefCurrentGroup,
        Kind::VelocityDirect,
        Kind::VelocitiesDirect,
        Kind::VelocitiesDirectGroup,
        Kind::PidOffset,
        Kind::PidFeedforward,
    ];

    /// The head's vocabs in YARP 3.12 and in 4.0.
    fn heads(self) -> (&'static [i32], &'static [i32]) {
        match self {
            Kind::PositionMoves => (&[POSITION_MOVES], &[IPOS, POSITION_MOVES]),
            Kind::VelocityMove => (&[VELOCITY_MOVE], &[IVEL, VELOCITY_MOVE]),
            Kind::VelocityMoves => (&[VELOCITY_MOVES], &[IVEL, VELOCITY_MOVES]),
            Kind::VelocityMoveGroup => (&[VELOCITY_MOVE_GROUP], &[IVEL, VELOCITY_MOVE_GROUP]),
            Kind::RefTorque => (&[TORQUES_DIRECT], &[ITRQ, TORQUES_DIRECT]),
            Kind::RefTorques => (&[TORQUES_DIRECTS], &[ITRQ, TORQUES_DIRECTS]),
            Kind::RefTorqueGroup => (&[TORQUES_DIRECT_GROUP], &[ITRQ, TORQUES_DIRECT_GROUP]),
            Kind::Position => (&[POSITION_DIRECT], &[IPOD, POSITION_DIRECT]),
            Kind::Positions => (&[POSITION_DIRECTS], &[IPOD, POSITION_DIRECTS]),
            Kind::PositionGroup => (&[POSITION_DIRECT_GROUP], &[IPOD, POSITION_DIRECT_GROUP]),
            Kind::RefDutyCycle => (&[PWM_IFACE, REF], &[PWM_IFACE, REF]),
            Kind::RefDutyCycles => (&[PWM_IFACE, REFS], &[PWM_IFACE, REFS]),
            Kind::RefCurrent => (&[CURRENT_IFACE, REF], &[CURRENT_IFACE, REF]),
            Kind::RefCurrents => (&[CURRENT_IFACE, REFS], &[CURRENT_IFACE, REFS]),
            Kind::RefCurrentGroup => (&[CURRENT_IFACE, REF_GROUP], &[CURRENT_IFACE, REF_GROUP]),
            Kind::VelocityDirect => (&[], &[IVED, VDSO]),
            Kind::VelocitiesDirect => (&[], &[IVED, VDSA]),
            Kind::VelocitiesDirectGroup => (&[], &[IVED, VDSG]),
            Kind::PidOffset => (&[], &[IPID, POFF]),
            Kind::PidFeedforward => (&[], &[IPID, PFFD]),
        }
    }

    fn head(self, generation: Generation) -> &'static [i32] {
        match generation {
            Generation::V3 => self.heads().0,
            Generation::V4 => self.heads().1,
        }
    }
}

/// A streaming command's head: what it sets and on which joints.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Stream {
    pub kind: Kind,
    pub joints: Joints,
}

impl Stream {
    /// Whether the command has a form in `generation` (4.0's IVelocityDirect has none
    /// in 3.12).
    pub fn has_form(&self, generation: Generation) -> bool {
        !self.kind.head(generation).is_empty()
    }

    /// The head Bottle for a server of `generation`.
    pub fn head(&self, generation: Generation) -> Bottle {
        let mut b: Bottle = self
            .kind
            .head(generation)
            .iter()
            .map(|v| Vocab32(*v))
            .collect();
        match &self.joints {
            Joints::One(j) => j.put(&mut b),
            Joints::All => {}
            Joints::Group(js) => Group(js.clone()).put(&mut b),
            Joints::Pid(ty, j) => {
                b.push(super::v3::PidType(*ty).to_v4());
                j.put(&mut b);
            }
        }
        b
    }

    /// Reads a received head, in either generation's form: the command, and which
    /// generation's form it had (icur and ipwm heads read as 3.12's: both are the same).
    pub fn decode(head: &Bottle) -> Result<(Stream, Generation), CommandError> {
        let items = head.items();
        // an empty head: no form in that generation
        let starts = |h: &[i32]| {
            !h.is_empty()
                && items.len() >= h.len()
                && h.iter()
                    .zip(items)
                    .all(|(h, v)| v.as_vocab().map(|x| x.0) == Some(*h))
        };
        let found = Kind::ALL.iter().find_map(|&k| {
            let (v3, v4) = k.heads();
            [(Generation::V3, v3), (Generation::V4, v4)]
                .into_iter()
                .find(|(_, h)| starts(h))
                .map(|(g, h)| (k, g, h.len()))
        });
        let Some((kind, generation, at)) = found else {
            return Err(CommandError::Unknown(head.to_string()));
        };
        let bad = || CommandError::BadHead(head.to_string());
        // the joints are ints, strictly: a head C++ cannot read is refused
        let int = |i: usize| items.get(i).filter(|v| v.is_int()).and_then(Value::as_i64);
        let joint = |i: usize| int(i).and_then(|j| usize::try_from(j).ok()).ok_or_else(bad);
        let joints = match kind {
            Kind::PositionMoves
            | Kind::VelocityMoves
            | Kind::RefTorques
            | Kind::Positions
            | Kind::RefDutyCycles
            | Kind::RefCurrents
            | Kind::VelocitiesDirect => Joints::All,
            Kind::VelocityMove
            | Kind::RefTorque
            | Kind::Position
            | Kind::RefDutyCycle
            | Kind::RefCurrent
            | Kind::VelocityDirect => Joints::One(joint(at)?),
            Kind::PidOffset | Kind::PidFeedforward => {
                let ty = items.get(at).and_then(Value::as_vocab).ok_or_else(bad)?;
                Joints::Pid(super::v3::PidType::from_v4(ty).0, joint(at + 1)?)
            }
            Kind::VelocityMoveGroup
            | Kind::RefTorqueGroup
            | Kind::PositionGroup
            | Kind::RefCurrentGroup
            | Kind::VelocitiesDirectGroup => {
                let n = joint(at)?;
                let js = items
                    .get(at + 1)
                    .and_then(Value::as_list)
                    .ok_or_else(bad)?
                    .iter()
                    .map(|v| v.as_i64().and_then(|x| usize::try_from(x).ok()))
                    .collect::<Option<Vec<usize>>>()
                    .ok_or_else(bad)?;
                if js.len() != n {
                    return Err(CommandError::MissingValues(head.to_string()));
                }
                Joints::Group(js)
            }
        };
        Ok((Stream { kind, joints }, generation))
    }
}

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

/// Applies one streaming command to `dev`, which has `axes` joints.
pub fn handle_command(
    msg: &CommandMessage,
    dev: &mut dyn DeviceDriver,
    axes: usize,
) -> Result<(), CommandError> {
    let (head, body) = (&msg.head, msg.body.as_slice());
    let command = || format!("({head}) ({} values)", body.len());
    if body.len() > axes {
        return Err(CommandError::TooManyValues {
            got: body.len(),
            axes,
        });
    }
    let (Stream { kind, joints }, _) = Stream::decode(head)?;
    let too_few = || CommandError::MissingValues(head.to_string());
    // the one value, or the group's values (one per joint)
    let (one, group) = match &joints {
        Joints::One(j) | Joints::Pid(_, j) => {
            (Some((*j, *body.first().ok_or_else(too_few)?)), &[][..])
        }
        Joints::Group(js) if js.len() != body.len() => return Err(too_few()),
        Joints::Group(js) => (None, js.as_slice()),
        Joints::All => (None, &[][..]),
    };
    let (j, x) = one.unwrap_or_default();
    macro_rules! via {
        ($as:ident, $name:literal) => {
            dev.$as().ok_or_else(|| CommandError::NoInterface {
                command: command(),
                interface: $name,
            })?
        };
    }
    match kind {
        Kind::PositionMoves => via!(as_position_control, "IPositionControl").position_moves(body),
        Kind::VelocityMove => via!(as_velocity_control, "IVelocityControl").velocity_move(j, x),
        Kind::VelocityMoves => via!(as_velocity_control, "IVelocityControl").velocity_moves(body),
        Kind::VelocityMoveGroup => {
            via!(as_velocity_control, "IVelocityControl").velocity_move_group(group, body)
        }
        Kind::RefTorque => via!(as_torque_control, "ITorqueControl").set_ref_torque(j, x),
        Kind::RefTorques | Kind::RefTorqueGroup => {
            let t = via!(as_torque_control, "ITorqueControl");
            let all: Vec<usize> = (0..body.len()).collect();
            let js = if kind == Kind::RefTorques {
                &all[..]
            } else {
                group
            };
            js.iter()
                .zip(body)
                .try_for_each(|(j, x)| t.set_ref_torque(*j, *x))
        }
        Kind::Position => via!(as_position_direct, "IPositionDirect").set_position(j, x),
        Kind::Positions => via!(as_position_direct, "IPositionDirect").set_positions(body),
        Kind::PositionGroup => {
            via!(as_position_direct, "IPositionDirect").set_positions_group(group, body)
        }
        Kind::RefDutyCycle => via!(as_pwm_control, "IPWMControl").set_ref_duty_cycle(j, x),
        Kind::RefDutyCycles => via!(as_pwm_control, "IPWMControl").set_ref_duty_cycles(body),
        Kind::RefCurrent => via!(as_current_control, "ICurrentControl").set_ref_current(j, x),
        Kind::RefCurrents => via!(as_current_control, "ICurrentControl").set_ref_currents(body),
        Kind::RefCurrentGroup => {
            via!(as_current_control, "ICurrentControl").set_ref_current_group(group, body)
        }
        Kind::VelocityDirect => {
            via!(as_velocity_direct, "IVelocityDirect").set_ref_velocity_direct(j, x)
        }
        Kind::VelocitiesDirect => {
            via!(as_velocity_direct, "IVelocityDirect").set_ref_velocities_direct(body)
        }
        Kind::VelocitiesDirectGroup => {
            via!(as_velocity_direct, "IVelocityDirect").set_ref_velocities_direct_group(group, body)
        }
        Kind::PidOffset | Kind::PidFeedforward => {
            let Joints::Pid(ty, _) = joints else {
                return Err(CommandError::BadHead(head.to_string()));
            };
            let p = via!(as_pid_control, "IPidControl");
            if kind == Kind::PidOffset {
                p.set_pid_offset(ty, j, x)
            } else {
                p.set_pid_feedforward(ty, j, x)
            }
        }
    }
    .map_err(|source| CommandError::Device {
        command: command(),
        source,
    })
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
    fn four_streams_pid_offsets_and_feedforwards() {
        use crate::interfaces::IPidControl;
        let mut dev = FakeMotionControl::with_joints(4);
        let pos = Vocab32::new("pos");
        // 4.0's numbered type on the wire, 3.12's name in the device
        handle_command(&msg("([ipid] [poff] [pos1] 2) (1.5)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_pid(pos, 2).unwrap().offset, 1.5);
        handle_command(&msg("([ipid] [pffd] [pos1] 1) (0.5)"), &mut dev, 4).unwrap();
        assert_eq!(dev.get_pid_feedforward(pos, 1).unwrap(), 0.5);
        let s = Stream {
            kind: Kind::PidOffset,
            joints: Joints::Pid(pos, 2),
        };
        assert_eq!(s.head(Generation::V4).to_string(), "[ipid] [poff] [pos1] 2");
        assert!(!s.has_form(Generation::V3));
        assert_eq!(
            Stream::decode(&s.head(Generation::V4)),
            Ok((s, Generation::V4))
        );
        assert!(handle_command(&msg("([ipid] [poff] 2) (1.5)"), &mut dev, 4).is_err());
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
