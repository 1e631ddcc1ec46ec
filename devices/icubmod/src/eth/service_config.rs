//! The configuration a `verifyactivate` carries (`eOmn_serv_config_data_t`), built from a
//! device's `SERVICE` group and mechanicals as icub-main's `ServiceParser::parseService`
//! and `embObjMotionControl::saveCouplingsData` build it: a board checks it against the
//! hardware behind it and configures its service from it.
//!
//! Motion control: the CAN boards' version and type (`PROPERTIES/CANBOARDS`), one
//! joint-motor descriptor per `JOINTMAPPING` column (actuator, two encoders), and the
//! coupling: joint sets (`JOINTSET_CFG`), their control outputs (the `outputType` of the
//! joints' PID groups) and the `COUPLINGS` matrices in q17.14. Strings are accepted long
//! (`eomc_act_foc`) or short (`foc`), as C++ accepts them. Bytes C++ leaves
//! uninitialised are zero here.

use icub_eth::entities::boards::{BoardInfo, CanLocation, EthBoardType};
use icub_eth::entities::mn::service_type as st;
use icub_eth::entities::service::{Coupling, JomoDescriptor, JomoDescriptors, McServiceConfig};
use icub_eth::wire::Writer;
use yarp_proto::Property;

use super::config::{Node, ParamError};

/// `eObrd_cantype_t` by name (`EoBoards.c`).
pub fn can_board_type(name: &str) -> Option<u8> {
    let s = name.trim().trim_matches('"').to_ascii_lowercase();
    let s = s.strip_prefix("eobrd_").unwrap_or(&s);
    Some(match s {
        "dsp" => 0,
        "pic" => 1,
        "2dc" => 2,
        "mc4" => 3,
        "bll" => 4,
        "mtb" => 5,
        "strain" => 6,
        "mais" => 7,
        "foc" => 8,
        "6sg" => 9,
        "jog" => 10,
        "mtb4" => 11,
        "strain2" => 12,
        "rfe" => 13,
        "sg3" => 14,
        "psc" => 15,
        "mtb4w" => 16,
        "pmc" => 17,
        "amcbldc" => 18,
        "bms" => 19,
        "mtb4c" => 20,
        "amc2c" => 21,
        "strain2c" => 22,
        "bat" => 23,
        "amcfoc2c" => 24,
        "amcmj1_mot" => 25,
        _ => return None,
    })
}

/// A value of one of `EoMotionControl.c`'s string tables, long or short form.
fn lookup(table: &[(&str, u8)], prefix: &str, s: &str) -> Option<u8> {
    let s = s.trim().trim_matches('"');
    let short = s.strip_prefix(prefix).unwrap_or(s);
    table.iter().find(|(n, _)| *n == short).map(|(_, v)| *v)
}

/// `eOmc_encoder_t` of a JOINTMAPPING encoder `type` (`aea`, `eomc_enc_aea`, ...).
pub fn encoder_type(name: &str) -> Option<u8> {
    lookup(ENCODERS, "eomc_enc_", name)
}

/// `eOmc_position_t` of a JOINTMAPPING encoder `position` (`atjoint`, `eomc_pos_atjoint`, ...).
pub fn encoder_position(name: &str) -> Option<u8> {
    lookup(POSITIONS, "eomc_pos_", name)
}

const ACTUATORS: &[(&str, u8)] = &[
    ("none", 0),
    ("foc", 1),
    ("mc4", 2),
    ("pwm", 3),
    ("advfoc", 4),
];
const ENCODERS: &[(&str, u8)] = &[
    ("none", 0),
    ("aea", 1),
    ("roie", 2),
    ("absanalog", 3),
    ("mais", 4),
    ("qenc", 5),
    ("hallmotor", 6),
    ("spichainof2", 7),
    ("spichainof3", 8),
    ("amo", 9),
    ("psc", 10),
    ("pos", 11),
    ("aea3", 12),
    ("aksim2", 13),
    ("mrie", 14),
];
const POSITIONS: &[(&str, u8)] = &[("none", 0), ("atjoint", 1), ("atmotor", 2)];
const CONSTRAINTS: &[(&str, u8)] = &[
    ("none", 0),
    ("cerhand", 1),
    ("trifid", 2),
    ("cerhand2", 3),
    ("ergocubwrist", 4),
];
const MAIS_PORTS: &[(&str, u8)] = &[
    ("thumbproximal", 0),
    ("thumbdistal", 1),
    ("indexproximal", 2),
    ("indexdistal", 3),
    ("mediumproximal", 4),
    ("mediumdistal", 5),
    ("littlefingers", 6),
];
const POS_PORTS: &[(&str, u8)] = &[
    ("hand_thumb_oc", 0),
    ("hand_index_oc", 1),
    ("hand_middle_oc", 2),
    ("hand_ring_pinky_oc", 3),
    ("hand_thumb_add", 4),
    ("hand_tbd", 5),
    ("hand_index_add", 6),
];

/// Encoder types, for the emulator and tests.
pub mod encoder {
    pub const AEA: u8 = 1;
    pub const ROIE: u8 = 2;
    pub const AEA3: u8 = 12;
}

/// Port "none" (`eobrd_port_none`) and "not local" (a CAN encoder, `eobrd_port_nolocal`).
const PORT_NONE: u8 = 31;
const PORT_NOLOCAL: u8 = 29;

/// A connector of an Ethernet board -> its port (`EoBoards.c` map of ports).
fn connector_port(board: EthBoardType, conn: &str) -> Option<u8> {
    let c = conn.trim();
    let c = c.strip_prefix("eobrd_conn_").unwrap_or(c);
    if c == "none" {
        return Some(PORT_NONE);
    }
    let table: &[(&str, u8)] = match board {
        EthBoardType::Ems4 => &[
            ("P6", 0),
            ("P7", 3),
            ("P8", 1),
            ("P9", 4),
            ("P10", 2),
            ("P11", 5),
        ],
        EthBoardType::Mc4plus => &[
            ("P2", 1),
            ("P3", 0),
            ("P4", 2),
            ("P5", 3),
            ("P3P", 4),
            ("P4P", 5),
            ("P10", 0),
            ("P11", 1),
        ],
        EthBoardType::Mc2plus => &[("P2", 1), ("P3", 0), ("P10", 0), ("P11", 1)],
        EthBoardType::Amc => &[("J5_X1", 0), ("J5_X2", 1), ("J5_X3", 2)],
        EthBoardType::Amcfoc => &[("J11", 0), ("J12", 1)],
        _ => &[],
    };
    table.iter().find(|(n, _)| *n == c).map(|(_, p)| *p)
}

/// `CANx:a` or `CANx:a:i` (bus 1-2, address 1-14, index 0, 1, 3 or 4), as C++ `convert`.
pub fn can_location(s: &str) -> Option<CanLocation> {
    let s = s.trim().trim_matches('"');
    let rest = s.strip_prefix("CAN")?;
    let mut parts = rest.split(':');
    let bus: u8 = parts.next()?.parse().ok()?;
    let addr: u8 = parts.next()?.parse().ok()?;
    let index: u8 = match parts.next() {
        Some(i) => i.parse().ok()?,
        None => 0,
    };
    if parts.next().is_some() || !(1..=2).contains(&bus) || !(1..=14).contains(&addr) {
        return None;
    }
    if !matches!(index, 0 | 1 | 3 | 4) {
        return None;
    }
    Some(CanLocation {
        port: bus - 1,
        addr,
        inside_index: index,
    })
}

/// `eOlocation_t` of an advanced actuator: `CANx:a`, `ICCx:a` or `LOC:n` (bus:3 — can1 0,
/// can2 1, local 2, icc1 3, icc2 4 — ffu:1, adr:4).
fn location_byte(s: &str) -> Option<u8> {
    let s = s.trim().trim_matches('"');
    let (bus, adr) = if let Some(n) = s.strip_prefix("LOC:") {
        (2, n.parse::<u8>().ok()?)
    } else {
        let (head, adr) = s.split_once(':')?;
        let adr: u8 = adr.split(':').next()?.parse().ok()?;
        let bus = match head {
            "CAN1" => 0,
            "CAN2" => 1,
            "ICC1" => 3,
            "ICC2" => 4,
            _ => return None,
        };
        (bus, adr)
    };
    (adr <= 15).then_some(bus | adr << 4)
}

/// Double -> `eOq17_14_t` as `eo_common_float_to_Q17_14` does (through f32, truncating).
pub fn q17_14(x: f64) -> i32 {
    let v = f64::from((x as f32) * 16384.0f32) as i64;
    v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

/// The rows of the `JOINTMAPPING` subgroup `which`: `key` → one string per joint.
struct Mapping<'a> {
    group: Node<'a>,
    path: &'static str,
    n: usize,
}

impl<'a> Mapping<'a> {
    fn row(&self, key: &str) -> Result<Vec<String>, ParamError> {
        let v = self.group.strings(key).ok_or_else(|| {
            ParamError::missing(format!("{}/{key}", self.path), "one value per joint")
        })?;
        if v.len() != self.n {
            return Err(ParamError::bad(
                format!("{}/{key}", self.path),
                "as many values as JOINTMAPPING/ACTUATOR/type",
                v.join(" "),
            ));
        }
        Ok(v)
    }

    fn table(
        &self,
        key: &str,
        table: &[(&str, u8)],
        prefix: &str,
        what: &'static str,
    ) -> Result<Vec<u8>, ParamError> {
        self.row(key)?
            .iter()
            .map(|s| {
                lookup(table, prefix, s)
                    .ok_or_else(|| ParamError::bad(format!("{}/{key}", self.path), what, s.clone()))
            })
            .collect()
    }
}

/// The CAN boards of `PROPERTIES/CANBOARDS`: type, firmware, protocol per column.
fn can_boards(props: &Node) -> Result<Vec<BoardInfo>, ParamError> {
    // A service of PWM joints on the board itself has none.
    let Some(g) = props.group("CANBOARDS") else {
        return Ok(Vec::new());
    };
    let types = g
        .strings("type")
        .ok_or_else(|| ParamError::missing("CANBOARDS/type", "the CAN boards' types"))?;
    let n = types.len();
    let nums = |group: &'static str, key: &str| -> Result<Vec<u8>, ParamError> {
        let v = g.need_group(group)?.need_numbers(key, n)?;
        Ok(v.into_iter().map(|x| x as u8).collect())
    };
    let (fw_major, fw_minor, fw_build) = (
        nums("FIRMWARE", "major")?,
        nums("FIRMWARE", "minor")?,
        nums("FIRMWARE", "build")?,
    );
    let (pr_major, pr_minor) = (nums("PROTOCOL", "major")?, nums("PROTOCOL", "minor")?);
    types
        .iter()
        .enumerate()
        .map(|(i, t)| {
            Ok(BoardInfo {
                board_type: can_board_type(t).ok_or_else(|| {
                    ParamError::bad("CANBOARDS/type", "a CAN board type", t.clone())
                })?,
                firmware: [fw_major[i], fw_minor[i], fw_build[i]],
                protocol: [pr_major[i], pr_minor[i]],
            })
        })
        .collect()
}

fn version(b: &BoardInfo) -> [u8; 5] {
    [
        b.firmware[0],
        b.firmware[1],
        b.firmware[2],
        b.protocol[0],
        b.protocol[1],
    ]
}

/// One location of `group/location` (C++ forces the inside index to "none", 2).
fn sensor_canloc(props: &Node, group: &'static str, count: usize) -> Result<Vec<u8>, ParamError> {
    let g = props.need_group(group)?;
    let v = g
        .strings("location")
        .ok_or_else(|| ParamError::missing(format!("{group}/location"), "CAN locations"))?;
    if v.len() != count {
        return Err(ParamError::bad(
            format!("{group}/location"),
            if count == 1 {
                "one CAN location"
            } else {
                "three CAN locations"
            },
            v.join(" "),
        ));
    }
    v.iter()
        .map(|s| sensor_canloc_of(s, group).map(CanLocation::to_byte))
        .collect()
}

/// One encoder's port byte (C++ `parse_encoder_port`).
fn encoder_port(kind: u8, s: &str, board: EthBoardType) -> Option<u8> {
    let s = s.trim().trim_matches('"');
    match kind {
        0 => Some(PORT_NONE),
        4 => lookup(MAIS_PORTS, "MAIS:", s).filter(|_| s.starts_with("MAIS:")),
        10 => {
            let f = s.strip_prefix("PSC:").unwrap_or(s);
            match f {
                "finger0" => Some(0),
                "finger1" => Some(1),
                _ => None,
            }
        }
        11 => lookup(POS_PORTS, "POS:", s),
        1 | 3 | 5 | 7 | 8 | 9 | 12 | 13 => connector_port(board, s.strip_prefix("CONN:")?),
        _ => s.starts_with("CAN").then_some(PORT_NOLOCAL),
    }
}

/// The joint-motor descriptors of `JOINTMAPPING` (not for mc4 and advfoc).
/// The `ACTUATOR`, `ENCODER1` and `ENCODER2` rows of `JOINTMAPPING`, as many columns as
/// `ACTUATOR/type` has.
fn joint_mapping<'a>(map: &Node<'a>) -> Result<[Mapping<'a>; 3], ParamError> {
    let n = map
        .need_group("ACTUATOR")?
        .strings("type")
        .ok_or_else(|| ParamError::missing("JOINTMAPPING/ACTUATOR/type", "one actuator per joint"))?
        .len();
    let m = |group: &'static str, path: &'static str| -> Result<Mapping<'a>, ParamError> {
        Ok(Mapping {
            group: map.need_group(group)?,
            path,
            n,
        })
    };
    Ok([
        m("ACTUATOR", "JOINTMAPPING/ACTUATOR")?,
        m("ENCODER1", "JOINTMAPPING/ENCODER1")?,
        m("ENCODER2", "JOINTMAPPING/ENCODER2")?,
    ])
}

/// Each joint's encoder of one `ENCODER` row: (type, port, position).
fn encoders(e: &Mapping, board: EthBoardType) -> Result<Vec<(u8, u8, u8)>, ParamError> {
    let kinds = e.table("type", ENCODERS, "eomc_enc_", "an encoder type")?;
    let pos = e.table(
        "position",
        POSITIONS,
        "eomc_pos_",
        "a position (atjoint, atmotor, none)",
    )?;
    let ports = e.row("port")?;
    kinds
        .iter()
        .zip(&pos)
        .zip(&ports)
        .map(|((k, p), s)| {
            let port = encoder_port(*k, s, board).ok_or_else(|| {
                ParamError::bad(
                    format!("{}/port", e.path),
                    "a port of this encoder type and board",
                    s.clone(),
                )
            })?;
            Ok((*k, port, *p))
        })
        .collect()
}

fn jomos(map: &Node, board: EthBoardType, stype: u8) -> Result<Vec<JomoDescriptor>, ParamError> {
    let [act, e1, e2] = joint_mapping(map)?;
    let n = act.n;
    let act_types = act.table("type", ACTUATORS, "eomc_act_", "an actuator type")?;
    let act_ports = act.row("port")?;
    let (enc1, enc2) = (encoders(&e1, board)?, encoders(&e2, board)?);
    (0..n)
        .map(|j| {
            let port = &act_ports[j];
            let actuator = match act_types[j] {
                0 => PORT_NONE,
                1 if stype == st::MC_FOC => can_location(port)
                    .map(|l| {
                        CanLocation {
                            inside_index: 0,
                            ..l
                        }
                        .to_byte()
                    })
                    .ok_or_else(|| {
                        ParamError::bad("JOINTMAPPING/ACTUATOR/port", "CANx:a[:i]", port.clone())
                    })?,
                3 => port
                    .trim()
                    .strip_prefix("CONN:")
                    .and_then(|c| connector_port(board, c))
                    .ok_or_else(|| {
                        ParamError::bad(
                            "JOINTMAPPING/ACTUATOR/port",
                            "CONN:<connector of the board>",
                            port.clone(),
                        )
                    })?,
                _ => {
                    return Err(ParamError::bad(
                        "JOINTMAPPING/ACTUATOR/type",
                        "an actuator this service drives",
                        format!("{} for {}", act.row("type")?[j], st_name(stype)),
                    ))
                }
            };
            Ok(JomoDescriptor {
                actuator,
                encoder1: enc1[j],
                encoder2: enc2[j],
            })
        })
        .collect()
}

fn st_name(stype: u8) -> &'static str {
    match stype {
        st::MC_FOC => "eomn_serv_MC_foc",
        st::MC_MC4 => "eomn_serv_MC_mc4",
        st::MC_MC4PLUS => "eomn_serv_MC_mc4plus",
        st::MC_MC4PLUSMAIS => "eomn_serv_MC_mc4plusmais",
        st::MC_MC2PLUSPSC => "eomn_serv_MC_mc2pluspsc",
        st::MC_MC4PLUSFAPS => "eomn_serv_MC_mc4plusfaps",
        st::MC_ADVFOC => "eomn_serv_MC_advfoc",
        _ => "this service",
    }
}

/// `outputType` of a PID group (`pwm` 1, `velocity` 2, `current` 3).
fn output_type(root: &Node, group: &str) -> u8 {
    let group = group.trim().trim_matches('"');
    if group.eq_ignore_ascii_case("none") {
        return 0;
    }
    let Some(g) = root.group(group) else { return 0 };
    match g.string("outputType").as_deref().map(str::trim) {
        Some("pwm") => 1,
        Some("velocity") => 2,
        Some("current") => 3,
        _ => 0,
    }
}

/// `eOmc_4jomo_coupling_t` (EMC `saveCouplingsData`).
fn coupling(root: &Node, joints: usize) -> Result<Coupling, ParamError> {
    let mut c = Coupling {
        joint2set: [0; 4],
        jointset_config: [[0; 16]; 4],
        joint2motor: [[0; 4]; 4],
        motor2joint: [[0; 4]; 4],
        encoder2joint: [[0; 6]; 4],
    };
    for (j, s) in c.joint2set.iter_mut().enumerate() {
        if j >= joints {
            *s = 0xFF;
        }
    }
    let cpl = root.need_group("COUPLINGS")?;
    let j2m = cpl.need_numbers("matrixJ2M", 16)?;
    let m2j = cpl.need_numbers("matrixM2J", 16)?;
    let e2j = cpl.need_numbers("matrixE2J", 24)?;
    for r in 0..4 {
        for k in 0..4 {
            c.joint2motor[r][k] = q17_14(j2m[4 * r + k]);
            c.motor2joint[r][k] = q17_14(m2j[4 * r + k]);
        }
        for k in 0..6 {
            c.encoder2joint[r][k] = q17_14(e2j[6 * r + k]);
        }
    }
    let general = root.need_group("GENERAL")?;
    let speed_fbk = general
        .numbers("useMotorSpeedFbk", joints)?
        .unwrap_or_else(|| vec![0.0; joints]);
    let controls = root.group("CONTROLS");
    let pid_of = |key: &str, j: usize| -> String {
        controls
            .and_then(|c| c.strings(key))
            .and_then(|v| v.get(j).cloned())
            .unwrap_or_else(|| "none".into())
    };
    let sets_group = root.need_group("JOINTSET_CFG")?;
    let sets = sets_group.number("numberofsets")?.ok_or_else(|| {
        ParamError::missing("JOINTSET_CFG/numberofsets", "the number of joint sets")
    })? as usize;
    if sets == 0 || sets > joints.min(4) {
        return Err(ParamError::bad(
            "JOINTSET_CFG/numberofsets",
            "1 to the number of joints",
            sets.to_string(),
        ));
    }
    for s in 0..sets {
        let name = format!("JOINTSET_{s}");
        let g = sets_group.need_group(&name)?;
        let list: Vec<usize> = g
            .strings("listofjoints")
            .unwrap_or_default()
            .iter()
            .map(|x| x.parse::<usize>())
            .collect::<Result<_, _>>()
            .ok()
            .filter(|l: &Vec<usize>| !l.is_empty() && l.iter().all(|j| *j < joints.min(4)))
            .ok_or_else(|| {
                ParamError::bad(
                    format!("{name}/listofjoints"),
                    "joints of this board",
                    g.strings("listofjoints").unwrap_or_default().join(" "),
                )
            })?;
        for &j in &list {
            c.joint2set[j] = s as u8;
        }
        let first = list[0];
        let fbk = list.iter().all(|j| speed_fbk[*j] != 0.0);
        let pos = output_type(root, &pid_of("positionControl", first));
        let trq = output_type(root, &pid_of("torqueControl", first));
        let cur = if pid_of("currentPid", first)
            .trim()
            .eq_ignore_ascii_case("none")
        {
            0
        } else {
            3
        };
        let constraint = g.string("constraint").unwrap_or_else(|| "none".into());
        let constraint =
            lookup(CONSTRAINTS, "eomc_jsetconstraint_", &constraint).ok_or_else(|| {
                ParamError::bad(
                    format!("{name}/constraint"),
                    "a joint-set constraint",
                    constraint.clone(),
                )
            })?;
        let param = |k: &str| -> Result<f32, ParamError> { Ok(g.number(k)?.unwrap_or(0.0) as f32) };
        let mut w = Writer::with_capacity(16);
        w.u8(u8::from(fbk) << 1);
        w.u8(trq | pos << 2 | pos << 4 | pos << 6);
        w.u8(pos | pos << 2 | 1 << 4 | cur << 6);
        w.u8(0);
        w.u8(constraint);
        w.zeros(3);
        w.bytes(&param("param1")?.to_le_bytes());
        w.bytes(&param("param2")?.to_le_bytes());
        c.jointset_config[s].copy_from_slice(&w.into_inner());
    }
    Ok(c)
}

/// The advanced descriptors and coupling of `eomn_serv_MC_advfoc` (332 bytes).
fn advfoc(
    map: &Node,
    boards: &[BoardInfo],
    eth: EthBoardType,
    c: &Coupling,
) -> Result<Vec<u8>, ParamError> {
    let [act, e1, e2] = joint_mapping(map)?;
    let n = act.n;
    let types = act.table("type", ACTUATORS, "eomc_act_", "an actuator type")?;
    if types.iter().any(|t| *t != 4) {
        return Err(ParamError::bad(
            "JOINTMAPPING/ACTUATOR/type",
            "advfoc for every joint",
            act.row("type")?.join(" "),
        ));
    }
    let ports = act.row("port")?;
    let onboard = act.row("onboard")?;
    let mut w = Writer::with_capacity(332);
    w.bytes(&[4, 16, n.min(4) as u8, 0]);
    // eOmc_encoder_descriptor_t of an advanced joint: type, port | pos << 5, 2 free bytes
    let enc = |e: &Mapping| -> Result<Vec<[u8; 4]>, ParamError> {
        Ok(encoders(e, eth)?
            .into_iter()
            .map(|(k, port, p)| [k, (port & 0x1f) | (p & 7) << 5, 0, 0])
            .collect())
    };
    let (enc1, enc2) = (enc(&e1)?, enc(&e2)?);
    for j in 0..4 {
        if j >= n {
            w.zeros(16);
            continue;
        }
        let loc = location_byte(&ports[j]).ok_or_else(|| {
            ParamError::bad(
                "JOINTMAPPING/ACTUATOR/port",
                "CANx:a, ICCx:a or LOC:n",
                ports[j].clone(),
            )
        })?;
        let kind = can_board_type(&onboard[j]).ok_or_else(|| {
            ParamError::bad(
                "JOINTMAPPING/ACTUATOR/onboard",
                "a CAN board type",
                onboard[j].clone(),
            )
        })?;
        let board = boards
            .iter()
            .find(|b| b.board_type == kind)
            .ok_or_else(|| {
                ParamError::bad(
                    "JOINTMAPPING/ACTUATOR/onboard",
                    "a type CANBOARDS/type lists",
                    onboard[j].clone(),
                )
            })?;
        w.u8(4);
        w.u8(loc);
        w.entity(&BoardInfo {
            board_type: kind,
            ..*board
        });
        w.bytes(&enc1[j]);
        w.bytes(&enc2[j]);
    }
    // eOmc_adv4jomo_coupling_t: type traditional4x4 (0), filler, then as the 4-jomo one
    // with the first four columns of encoder2joint.
    w.u8(0);
    w.zeros(3);
    w.bytes(&c.joint2set);
    for cfg in &c.jointset_config {
        w.bytes(cfg);
    }
    for row in c.joint2motor.iter().chain(&c.motor2joint) {
        for v in row {
            w.i32(*v);
        }
    }
    for row in &c.encoder2joint {
        for v in &row[..4] {
            w.i32(*v);
        }
    }
    Ok(w.into_inner())
}

/// MC4 boards behind an EMS (`eomn_serv_MC_mc4`).
fn mc4(props: &Node, map: &Node, boards: &[BoardInfo]) -> Result<McServiceConfig, ParamError> {
    let of = |t: u8| {
        boards
            .iter()
            .find(|b| b.board_type == t)
            .map(version)
            .unwrap_or_default()
    };
    let shifts = props.need_group("MC4")?.need_group("SHIFTS")?;
    let sh = |k: &str| -> Result<u8, ParamError> {
        let v = shifts
            .number(k)?
            .ok_or_else(|| ParamError::missing(format!("MC4/SHIFTS/{k}"), "a shift"))?;
        Ok(v as u8)
    };
    let (ejv, eja, emv, ema) = (
        sh("estimJointVelocity")?,
        sh("estimJointAcceleration")?,
        sh("estimMotorVelocity")?,
        sh("estimMotorAcceleration")?,
    );
    if [ejv, eja, emv, ema].iter().any(|v| *v > 15) {
        return Err(ParamError::bad(
            "MC4/SHIFTS",
            "estimation shifts up to 15",
            format!("{ejv} {eja} {emv} {ema}"),
        ));
    }
    let flags = props
        .need_group("MC4")?
        .group("BROADCASTPOLICY")
        .and_then(|b| b.strings("enable"))
        .unwrap_or_default()
        .iter()
        // short (`position`) or full (`eomc_mc4broadcast_position`), as C++ accepts them
        .map(
            |s| match s.strip_prefix("eomc_mc4broadcast_").unwrap_or(s) {
                "position" => 1u16 << 1,
                "pidvalues" => 1 << 2,
                "status" => 1 << 3,
                "print" => 1 << 6,
                "motorposition" => 1 << 10,
                // C++ leaves out what it does not know
                "none" => 0,
                other => {
                    tracing::warn!(
                        "MC4/BROADCASTPOLICY/enable: `{other}` is no broadcast: left out"
                    );
                    0
                }
            },
        )
        .fold(0u16, |acc, bit| acc | bit);
    let ports = map.need_group("ACTUATOR")?.strings("port").ok_or_else(|| {
        ParamError::missing("JOINTMAPPING/ACTUATOR/port", "one MC4 location per joint")
    })?;
    let mut joints = [0u8; 12];
    for (slot, p) in joints.iter_mut().zip(&ports) {
        *slot = can_location(p)
            .filter(|_| p.matches(':').count() == 2)
            .ok_or_else(|| ParamError::bad("JOINTMAPPING/ACTUATOR/port", "CANx:a:i", p.clone()))?
            .to_byte();
    }
    // C++ leaves the MAIS location of this type unset; the group is there: use it.
    let mais_loc = match props.group("MAIS") {
        Some(_) => sensor_canloc(props, "MAIS", 1)?[0],
        None => 0,
    };
    let mut mais = [0u8; 6];
    mais[..5].copy_from_slice(&of(7));
    mais[5] = mais_loc;
    Ok(McServiceConfig::Mc4 {
        version: of(3),
        shifts: [sh("velocity")?, ejv | eja << 4, emv | ema << 4],
        joints,
        mais,
        broadcast_flags: flags,
    })
}

/// The `verifyactivate` data of a motion-control service: its 340 bytes.
pub fn mc_config(config: &Property, stype: u8, joints: usize) -> Result<Vec<u8>, ParamError> {
    let root = Node::root(config);
    let props = root.need_group("SERVICE")?.need_group("PROPERTIES")?;
    let eth_name = props
        .need_group("ETHBOARD")?
        .need_string("type", "the Ethernet board's type")?;
    let eth = EthBoardType::from_name(eth_name.trim()).ok_or_else(|| {
        ParamError::bad("ETHBOARD/type", "an Ethernet board type", eth_name.clone())
    })?;
    let boards = can_boards(&props)?;
    let map = props.need_group("JOINTMAPPING")?;
    let first = || {
        boards
            .first()
            .copied()
            .ok_or_else(|| ParamError::missing("CANBOARDS/type", "a CAN board"))
    };
    let cfg = match stype {
        st::MC_MC4 => mc4(&props, &map, &boards)?,
        st::MC_ADVFOC => {
            let c = coupling(&root, joints)?;
            let bytes = advfoc(&map, &boards, eth, &c)?;
            let mut descriptors = [0u8; 68];
            let mut coupling = [0u8; 264];
            descriptors.copy_from_slice(&bytes[..68]);
            coupling.copy_from_slice(&bytes[68..332]);
            McServiceConfig::AdvFoc {
                descriptors,
                coupling,
            }
        }
        _ => {
            let jomos = JomoDescriptors(jomos(&map, eth, stype)?);
            let coupling = coupling(&root, joints)?;
            match stype {
                st::MC_FOC => {
                    let b = first()?;
                    McServiceConfig::Foc {
                        version: version(&b),
                        board_type: b.board_type,
                        jomos,
                        coupling,
                    }
                }
                st::MC_MC4PLUS => McServiceConfig::Mc4plus { jomos, coupling },
                st::MC_MC4PLUSMAIS => {
                    let mut mais = [0u8; 6];
                    mais[..5].copy_from_slice(&version(&first()?));
                    mais[5] = sensor_canloc(&props, "MAIS", 1)?[0];
                    McServiceConfig::Mc4plusMais { mais, jomos, coupling }
                }
                st::MC_MC2PLUSPSC => {
                    let mut psc = [0u8; 8];
                    psc[..5].copy_from_slice(&version(&first()?));
                    psc[5..].copy_from_slice(&sensor_canloc(&props, "PSC", 3)?);
                    McServiceConfig::Mc2plusPsc {
                        psc,
                        jomos,
                        coupling,
                        stop_switches: [0; 4],
                    }
                }
                st::MC_MC4PLUSFAPS => {
                    let b = first()?;
                    let mut w = Writer::with_capacity(24);
                    w.entity(&b);
                    let loc = sensor_canloc(&props, "POS", 1)?[0] & 0x1f;
                    w.u8(loc);
                    w.u8(0);
                    // C++ describes four sensors, whatever POS/SENSORS says: type 0,
                    // connector and port s, enabled, no offset.
                    for s in 0..4u16 {
                        w.u16(s << 4 | s << 8 | 1 << 12);
                        w.u16(0);
                    }
                    let mut pos = [0u8; 24];
                    pos.copy_from_slice(&w.into_inner());
                    McServiceConfig::Mc4plusFaps { pos, jomos, coupling }
                }
                _ => {
                    return Err(ParamError::bad(
                        "SERVICE/type",
                        "a motion-control service the host drives (eomn_serv_MC_mc2plus is refused, as by C++)",
                        st_name(stype),
                    ))
                }
            }
        }
    };
    Ok(cfg.to_bytes())
}

// ---- analog sensors and skin (`ServiceParser::check_analog`, `parseService`) ----

/// `eOas_sensor_t` by its long name (`eoas_string2sensor`).
fn sensor_type(s: &str) -> Option<u8> {
    let s = s.trim().trim_matches('"');
    let s = s.strip_prefix("eoas_").unwrap_or(s);
    Some(match s {
        "strain" => 0,
        "mais" => 1,
        "accel_mtb_int" => 2,
        "accel_mtb_ext" => 3,
        "gyros_mtb_ext" => 4,
        "accel_st_lis3x" => 5,
        "gyros_st_l3g4200d" => 6,
        "imu_acc" => 7,
        "imu_mag" => 8,
        "imu_gyr" => 9,
        "imu_eul" => 10,
        "imu_qua" => 11,
        "imu_lia" => 12,
        "imu_grv" => 13,
        "imu_status" => 14,
        "temperature" => 15,
        "psc_angle" => 16,
        "pos_angle" => 17,
        "ft" => 18,
        "battery" => 19,
        _ => return None,
    })
}

/// `eObrd_location_t` (1 byte, `ServiceParser::convert`): `CANb:a` (place can 1: port
/// bit 2, address bits 3-6), `CANb:a:i` (place extcan 3: index bit 7, 3 stored as 1 and
/// 4 as 0), `ETH:n` (place eth 2: id bits 2-7), `LOC:...` (nothing set).
fn location(s: &str) -> Option<u8> {
    let s = s.trim().trim_matches('"');
    if let Some(n) = s.strip_prefix("ETH:") {
        let id: u8 = n.parse().ok()?;
        return (id < 64).then_some(2 | id << 2);
    }
    if s.starts_with("LOC:") {
        return Some(0);
    }
    let l = can_location(s)?;
    let extended = s.matches(':').count() == 2;
    let base = l.port << 2 | l.addr << 3;
    Some(if extended {
        3 | base | (l.inside_index & 1) << 7
    } else {
        1 | base
    })
}

/// A `SENSORS` column per sensor, and which of them are enabled.
struct Sensors<'a> {
    group: Node<'a>,
    ids: Vec<String>,
    on: Vec<usize>,
}

impl<'a> Sensors<'a> {
    fn of(service: &Node<'a>) -> Result<Sensors<'a>, ParamError> {
        let group = service.need_group("PROPERTIES")?.need_group("SENSORS")?;
        let ids = group
            .strings("id")
            .ok_or_else(|| ParamError::missing("SENSORS/id", "the sensors' ids"))?;
        let wanted = service
            .need_group("SETTINGS")?
            .strings("enabledSensors")
            .ok_or_else(|| {
                ParamError::missing("SETTINGS/enabledSensors", "the enabled sensors' ids")
            })?;
        if wanted.len() > ids.len() {
            return Err(ParamError::bad(
                "SETTINGS/enabledSensors",
                "no more sensors than SENSORS lists",
                wanted.join(" "),
            ));
        }
        let on: Vec<usize> = wanted
            .iter()
            .filter_map(|w| ids.iter().position(|i| i == w))
            .collect();
        if on.is_empty() {
            return Err(ParamError::bad(
                "SETTINGS/enabledSensors",
                "ids of SENSORS/id",
                wanted.join(" "),
            ));
        }
        Ok(Sensors { group, ids, on })
    }

    /// Column `key` (one value per sensor).
    fn column(&self, key: &str) -> Result<Vec<String>, ParamError> {
        let v = self
            .group
            .strings(key)
            .ok_or_else(|| ParamError::missing(format!("SENSORS/{key}"), "one value per sensor"))?;
        if v.len() != self.ids.len() {
            return Err(ParamError::bad(
                format!("SENSORS/{key}"),
                "as many values as SENSORS/id",
                v.join(" "),
            ));
        }
        Ok(v)
    }
}

fn can_board_named(s: &str, path: &'static str) -> Result<u8, ParamError> {
    can_board_type(s).ok_or_else(|| ParamError::bad(path, "a CAN board type", s))
}

/// The CAN location of a sensor's `location` with inside index "none" (2).
fn sensor_canloc_of(s: &str, group: &str) -> Result<CanLocation, ParamError> {
    can_location(s)
        .map(|l| CanLocation {
            inside_index: 2,
            ..l
        })
        .ok_or_else(|| ParamError::bad(format!("{group}/location"), "CANx:a", s))
}

fn strain_config(service: &Node, boards: &[BoardInfo]) -> Result<Vec<u8>, ParamError> {
    let b = boards
        .first()
        .copied()
        .filter(|b| matches!(b.board_type, 6 | 12 | 22))
        .ok_or_else(|| ParamError::missing("CANBOARDS/type", "strain, strain2 or strain2c"))?;
    let s = Sensors::of(service)?;
    let loc = sensor_canloc_of(&s.column("location")?[s.on[0]], "SENSORS")?;
    let mut w = Writer::with_capacity(7);
    w.entity(&b);
    w.u8(loc.to_byte());
    Ok(w.into_inner())
}

/// `eOmn_serv_config_data_as_temperature_t` of a strain board's temperature sensor, as
/// icub-main's `eo_ftsens_privData::fillTemperatureEthServiceInfo` builds it from the
/// strain service: the board's info in its slot of the set (mtb4, strain2, mtb4c,
/// strain2c; the others `none`), then one descriptor (board type, CAN place, port and
/// address, `eoas_temperature_t1`) in an array of capacity 7. A plain `strain` has no
/// temperature sensor: C++ then fails to open, and so does this.
pub fn strain_temperature_config(root: &Node) -> Result<Vec<u8>, ParamError> {
    let service = root.need_group("SERVICE")?;
    let boards = can_boards(&service.need_group("PROPERTIES")?)?;
    let b = boards
        .first()
        .copied()
        .ok_or_else(|| ParamError::missing("CANBOARDS/type", "the strain's board"))?;
    let slot =
        match b.board_type {
            11 => 0,
            12 => 1,
            20 => 2,
            22 => 3,
            other => return Err(ParamError::bad(
                "SETTINGS/temperature-acquisitionRate",
                "a board with a temperature sensor (strain2, strain2c, mtb4, mtb4c) when above 0",
                format!("CANBOARDS/type of eObrd_cantype_t {other}"),
            )),
        };
    let s = Sensors::of(&service)?;
    let loc = sensor_canloc_of(&s.column("location")?[s.on[0]], "SENSORS")?;
    let mut infos = [BoardInfo {
        board_type: 0xFE,
        ..Default::default()
    }; 4];
    infos[slot] = b;
    let mut w = Writer::with_capacity(56);
    for i in &infos {
        w.entity(i);
    }
    // eOas_temperature_arrayof_descriptors_t: head (capacity 7, item 4 bytes, 1 item)
    w.bytes(&[7, 4, 1, 0]);
    let on = 1 | loc.port << 2 | loc.addr << 3; // eObrd_location_t, place can
    w.bytes(&[b.board_type, on, 15, 0]);
    w.bytes(&[0; 6 * 4]);
    Ok(w.into_inner())
}

fn mais_config(service: &Node, boards: &[BoardInfo]) -> Result<Vec<u8>, ParamError> {
    let b = boards
        .iter()
        .find(|b| b.board_type == 7)
        .copied()
        .ok_or_else(|| ParamError::missing("CANBOARDS/type", "mais"))?;
    let s = Sensors::of(service)?;
    let loc = sensor_canloc_of(&s.column("location")?[s.on[0]], "SENSORS")?;
    let mut w = Writer::with_capacity(6);
    w.bytes(&version(&b));
    w.u8(loc.to_byte());
    Ok(w.into_inner())
}

/// `eOmn_serv_config_data_as_inertial3_t`: the board infos by slot (mtb, mtb4, strain2,
/// rfe, mtb4c, strain2c), then the enabled sensors' descriptors.
fn inertials3_config(service: &Node, boards: &[BoardInfo]) -> Result<Vec<u8>, ParamError> {
    let s = Sensors::of(service)?;
    let (types, locs, board_types) = (
        s.column("type")?,
        s.column("location")?,
        s.column("boardType")?,
    );
    let mut infos = [BoardInfo {
        board_type: 0xFE,
        ..Default::default()
    }; 6];
    let mut descriptors = Vec::new();
    for &k in &s.on {
        let Some(kind) = sensor_type(&types[k]).filter(|t| matches!(t, 2..=4 | 6..=14)) else {
            tracing::warn!("SENSORS/type {}: not an inertial sensor, dropped", types[k]);
            continue;
        };
        let board = match EthBoardType::from_name(board_types[k].trim()) {
            Some(eth) => eth as u8,
            None => can_board_named(&board_types[k], "SENSORS/boardType")?,
        };
        let slot = match board {
            5 => Some(0),
            11 => Some(1),
            12 => Some(2),
            13 => Some(3),
            20 => Some(4),
            22 => Some(5),
            _ => None,
        };
        if let Some(slot) = slot {
            if infos[slot].board_type == 0xFE {
                infos[slot] = boards
                    .iter()
                    .find(|b| b.board_type == board)
                    .copied()
                    .ok_or_else(|| {
                        ParamError::bad(
                            "SENSORS/boardType",
                            "a board CANBOARDS/type lists",
                            board_types[k].clone(),
                        )
                    })?;
            }
        }
        let on = location(&locs[k]).ok_or_else(|| {
            ParamError::bad(
                "SENSORS/location",
                "CANx:a, CANx:a:i or ETH:n",
                locs[k].clone(),
            )
        })?;
        descriptors.push([board, on, kind, 0]);
    }
    let mut w = Writer::with_capacity(168);
    for i in &infos {
        w.entity(i);
    }
    w.bytes(&[32, 4, descriptors.len().min(32) as u8, 0]);
    for d in descriptors.iter().take(32) {
        w.bytes(d);
    }
    Ok(w.into_inner())
}

/// A connector of a CAN board to its port (`eoboards_connector2port`).
fn can_connector_port(board: u8, conn: &str) -> Option<u8> {
    let c = conn.trim().trim_matches('"');
    let c = c.strip_prefix("CONN:").unwrap_or(c);
    let c = c.strip_prefix("eobrd_conn_").unwrap_or(c);
    let n = |prefix: &str| -> Option<u8> { c.strip_prefix(prefix)?.parse::<u8>().ok() };
    match board {
        11 | 20 => n("J3_SDA")
            .filter(|p| *p < 4)
            .or_else(|| n("J2").filter(|p| *p < 4))
            .or_else(|| n("J3").filter(|p| *p < 4)),
        17 => n("J").and_then(|j| (4..=7).contains(&j).then(|| j - 4)),
        _ => None,
    }
}

/// `eOmn_serv_config_data_as_pos_t` (one board, up to four sensors).
fn pos_config(service: &Node, boards: &[BoardInfo]) -> Result<Vec<u8>, ParamError> {
    let s = Sensors::of(service)?;
    let (locs, board_types, ports, conns) = (
        s.column("location")?,
        s.column("boardType")?,
        s.column("port")?,
        s.column("connector")?,
    );
    let first = s.on[0];
    let kind = can_board_named(&board_types[first], "SENSORS/boardType")?;
    if !matches!(kind, 11 | 17 | 20) {
        return Err(ParamError::bad(
            "SENSORS/boardType",
            "mtb4, mtb4c or pmc",
            board_types[first].clone(),
        ));
    }
    let b = boards.first().copied().unwrap_or_default();
    let loc = can_location(&locs[first])
        .ok_or_else(|| ParamError::bad("SENSORS/location", "CANx:a", locs[first].clone()))?;
    let mut w = Writer::with_capacity(24);
    w.entity(&BoardInfo {
        board_type: kind,
        ..b
    });
    w.u8(CanLocation {
        inside_index: 0,
        ..loc
    }
    .to_byte());
    w.u8(0);
    let calib = service
        .group("PROPERTIES")
        .and_then(|p| p.group("SENSORS"))
        .and_then(|g| g.group("CALIBRATION"));
    for (n, &k) in s.on.iter().take(4).enumerate() {
        let port = lookup(POS_PORTS, "POS:", &ports[k])
            .ok_or_else(|| ParamError::bad("SENSORS/port", "POS:hand_...", ports[k].clone()))?;
        let conn = can_connector_port(kind, &conns[k]).ok_or_else(|| {
            ParamError::bad(
                "SENSORS/connector",
                "a connector of the board",
                conns[k].clone(),
            )
        })?;
        let (rotation, invert, offset) = match &calib {
            Some(c) => {
                let at = |key: &str| c.strings(key).and_then(|v| v.get(n).cloned());
                let rot = match at("rotation")
                    .as_deref()
                    .map(|r| r.trim_start_matches("ROT:"))
                {
                    None | Some("zero") => 0,
                    Some("plus180") => 1,
                    Some("plus090") => 2,
                    Some("minus090") => 3,
                    Some(other) => {
                        return Err(ParamError::bad(
                            "CALIBRATION/rotation",
                            "ROT:zero, plus180, plus090, minus090",
                            other,
                        ))
                    }
                };
                let inv = at("invertDirection").is_some_and(|v| v == "true" || v == "1");
                let off = at("offset")
                    .and_then(|v| v.parse::<f64>().ok())
                    .unwrap_or(0.0);
                (rot, inv, off)
            }
            None => (0, false, 0.0),
        };
        let word = u16::from(conn & 0xF) << 4
            | u16::from(port & 0xF) << 8
            | 1 << 12
            | u16::from(invert) << 13
            | (rotation & 3) << 14;
        w.u16(word);
        w.i16((10.0 * offset) as i16);
    }
    w.zeros(24 - w.len());
    Ok(w.into_inner())
}

/// The FT and battery parsers' location (`CANb:a`, no range checks).
fn ft_canloc(s: &str) -> Result<CanLocation, ParamError> {
    let t = s.trim().trim_matches('"');
    let bus = t.get(3..4).and_then(|b| b.parse::<u8>().ok());
    let addr = t.get(5..).and_then(|a| a.parse::<u8>().ok());
    match (bus, addr) {
        (Some(b @ 1..=2), Some(a)) if t.starts_with("CAN") => Ok(CanLocation {
            port: b - 1,
            addr: a,
            inside_index: 2,
        }),
        _ => Err(ParamError::bad("SENSORS/location", "CAN1:a or CAN2:a", s)),
    }
}

/// The CAN sensors of an FT or battery service, each with the version of the
/// `CANBOARDS` entry of its board type (zero when none is of that type, as C++).
fn can_sensor(board: &str, loc: &str, boards: &[BoardInfo]) -> Result<[u8; 8], ParamError> {
    let kind = can_board_named(board, "SENSORS/board")?;
    let b = boards
        .iter()
        .find(|b| b.board_type == kind)
        .copied()
        .unwrap_or(BoardInfo {
            board_type: kind,
            ..Default::default()
        });
    let mut w = Writer::with_capacity(8);
    w.entity(&b);
    w.u8(ft_canloc(loc)?.to_byte());
    w.u8(0);
    Ok(w.into_inner().try_into().unwrap_or([0; 8]))
}

/// `eOmn_serv_config_data_as_ft_t`: the CAN monitor, then the enabled sensors in the
/// order of their ids (C++ keeps them in a `std::map`).
fn ft_config(service: &Node, boards: &[BoardInfo]) -> Result<Vec<u8>, ParamError> {
    let s = Sensors::of(service)?;
    let (board, locs) = (s.column("board")?, s.column("location")?);
    let mut on = s.on.clone();
    on.sort_by(|a, b| s.ids[*a].cmp(&s.ids[*b]));
    let mon = service.group("CANMONITOR");
    let num = |k: &str| mon.and_then(|m| m.number(k).ok().flatten()).unwrap_or(0.0);
    let mode = match mon.and_then(|m| m.string("reportMode")).as_deref() {
        None | Some("NEVER") => 0,
        Some("justLOSTjustFOUND") => 1,
        Some("justLOSTjustFOUNDstillLOST") => 2,
        Some("ALL") => 3,
        Some(other) => {
            return Err(ParamError::bad(
                "CANMONITOR/reportMode",
                "NEVER, justLOSTjustFOUND, justLOSTjustFOUNDstillLOST or ALL",
                other,
            ))
        }
    };
    let mut w = Writer::with_capacity(40);
    w.u8(num("checkPeriod").clamp(0.0, 254.0) as u8);
    w.u8(mode);
    w.u16(num("ratePeriod").clamp(0.0, 65535.0) as u16);
    w.bytes(&[4, 8, on.len().min(4) as u8, 0]);
    for &k in on.iter().take(4) {
        w.bytes(&can_sensor(&board[k], &locs[k], boards)?);
    }
    w.zeros(40 - w.len());
    Ok(w.into_inner())
}

/// `eOmn_serv_config_data_as_battery_t`: one sensor (the CAN monitor is not set by C++).
fn battery_config(service: &Node, boards: &[BoardInfo]) -> Result<Vec<u8>, ParamError> {
    let s = Sensors::of(service)?;
    let (board, locs) = (s.column("board")?, s.column("location")?);
    let k = s.on[0];
    let mut w = Writer::with_capacity(16);
    w.zeros(4);
    w.bytes(&[1, 8, 1, 0]);
    w.bytes(&can_sensor(&board[k], &locs[k], boards)?);
    Ok(w.into_inner())
}

/// `eOmn_serv_config_data_sk_skin_t` (`EmbObjSkin::fromConfig`): the board from
/// `SERVICE/PROPERTIES/CANBOARDS` (an MTB with no version without it), the patches of
/// `patches/skinCanAddrsPatch1` (on CAN1) and `skinCanAddrsPatch2` (on CAN2).
pub fn skin_config(root: &Node) -> Result<Vec<u8>, ParamError> {
    let props = root.group("SERVICE").and_then(|s| s.group("PROPERTIES"));
    let board = match props {
        Some(p) => can_boards(&p)?
            .first()
            .copied()
            .filter(|b| matches!(b.board_type, 5 | 11 | 15 | 20))
            .unwrap_or(BoardInfo {
                board_type: 5,
                ..Default::default()
            }),
        None => BoardInfo {
            board_type: 5,
            ..Default::default()
        },
    };
    let patches = root.group("patches");
    let mut map = [[0u16; 2]; 4];
    let mut n = 0usize;
    for (bus, key) in ["skinCanAddrsPatch1", "skinCanAddrsPatch2"]
        .iter()
        .enumerate()
    {
        let Some(addrs) = patches.and_then(|p| p.strings(key)) else {
            continue;
        };
        for a in addrs.iter().filter_map(|a| a.parse::<u16>().ok()) {
            if (1..=14).contains(&a) {
                map[n][bus] |= 1 << a;
            }
        }
        n += 1;
    }
    let mut w = Writer::with_capacity(24);
    w.entity(&board);
    w.u8(n as u8);
    w.u8(0);
    for p in &map {
        w.u16(p[0]);
        w.u16(p[1]);
    }
    Ok(w.into_inner())
}

/// The `verifyactivate` data of an analog-sensor service of type `stype`.
pub fn sensor_config(root: &Node, stype: u8) -> Result<Vec<u8>, ParamError> {
    if stype == st::SK_SKIN {
        return skin_config(root);
    }
    let service = root.need_group("SERVICE")?;
    let boards = can_boards(&service.need_group("PROPERTIES")?)?;
    match stype {
        st::AS_STRAIN => strain_config(&service, &boards),
        st::AS_MAIS => mais_config(&service, &boards),
        st::AS_INERTIALS3 => inertials3_config(&service, &boards),
        st::AS_POS => pos_config(&service, &boards),
        st::AS_FT => ft_config(&service, &boards),
        st::AS_BATTERY => battery_config(&service, &boards),
        st::SK_SKIN => skin_config(root),
        _ => Ok(Vec::new()),
    }
}
