//! Variable identifiers (`eOprotID32_t`) and the layout of every network variable: for
//! each endpoint/entity the size of the whole entity item and, for each tag, the offset
//! and size of the variable inside it (as `EoProtocol{MN,MC,AS,SK}_rom.c` declare them:
//! `sizeof(eoprot_xx_rom_yy_defaultvalue.field)` at that field's offset).

use std::fmt;

/// `eOprotID32_t`: `endpoint<<24 | entity<<16 | index<<8 | tag` (`EOPROT_ID_GET`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Id32(pub u32);

impl Id32 {
    pub const fn new(endpoint: u8, entity: u8, index: u8, tag: u8) -> Self {
        Self((endpoint as u32) << 24 | (entity as u32) << 16 | (index as u32) << 8 | tag as u32)
    }
    pub const fn endpoint(self) -> u8 {
        (self.0 >> 24) as u8
    }
    pub const fn entity(self) -> u8 {
        (self.0 >> 16) as u8
    }
    pub const fn index(self) -> u8 {
        (self.0 >> 8) as u8
    }
    pub const fn tag(self) -> u8 {
        self.0 as u8
    }
    /// The same variable of another instance.
    pub const fn with_index(self, index: u8) -> Self {
        Self::new(self.endpoint(), self.entity(), index, self.tag())
    }
    /// Where the variable lives in its entity item, if the protocol defines it.
    pub fn layout(self) -> Option<TagLayout> {
        tag_layout(self.endpoint(), self.entity(), self.tag())
    }
    /// `sizeof` the variable, if the protocol defines it.
    pub fn size(self) -> Option<usize> {
        self.layout().map(|l| l.size)
    }
}

impl fmt::Debug for Id32 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Id32({:#010x} ep {} ent {} idx {} tag {})",
            self.0,
            self.endpoint(),
            self.entity(),
            self.index(),
            self.tag()
        )
    }
}

impl fmt::Display for Id32 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:#010x} ({}, entity {}, index {}, tag {})",
            self.0,
            endpoint_name(self.endpoint()),
            self.entity(),
            self.index(),
            self.tag()
        )
    }
}

/// `eOprot_endpoint_t`.
pub mod endpoint {
    pub const MANAGEMENT: u8 = 0;
    pub const MOTION_CONTROL: u8 = 1;
    pub const ANALOG_SENSORS: u8 = 2;
    pub const SKIN: u8 = 3;
    /// `eoprot_endpoint_all`.
    pub const ALL: u8 = 254;
}

/// The C name of an endpoint (`eoprot_EP2string`).
pub fn endpoint_name(ep: u8) -> &'static str {
    match ep {
        endpoint::MANAGEMENT => "eoprot_endpoint_management",
        endpoint::MOTION_CONTROL => "eoprot_endpoint_motioncontrol",
        endpoint::ANALOG_SENSORS => "eoprot_endpoint_analogsensors",
        endpoint::SKIN => "eoprot_endpoint_skin",
        _ => "eoprot_endpoint_unknown",
    }
}

/// Entities (`eOmn_entity_t`, `eOmc_entity_t`, `eOas_entity_t`, `eOsk_entity_t`).
pub mod entity {
    pub const MN_COMM: u8 = 0;
    pub const MN_APPL: u8 = 1;
    pub const MN_INFO: u8 = 2;
    pub const MN_SERVICE: u8 = 3;
    pub const MC_JOINT: u8 = 0;
    pub const MC_MOTOR: u8 = 1;
    pub const MC_CONTROLLER: u8 = 2;
    pub const AS_STRAIN: u8 = 0;
    pub const AS_MAIS: u8 = 1;
    pub const AS_TEMPERATURE: u8 = 2;
    pub const AS_INERTIAL3: u8 = 3;
    pub const AS_PSC: u8 = 4;
    pub const AS_POS: u8 = 5;
    pub const AS_FT: u8 = 6;
    pub const AS_BATTERY: u8 = 7;
    pub const SK_SKIN: u8 = 0;
}

/// Tags (`eOprot_tag_xx_yy_t` of `EoProtocol{MN,MC,AS,SK}.h`).
pub mod tag {
    pub const MN_COMM_WHOLEITEM: u8 = 0;
    pub const MN_COMM_STATUS: u8 = 1;
    pub const MN_COMM_STATUS_MANAGEMENTPROTOCOLVERSION: u8 = 2;
    pub const MN_COMM_CMMNDS_COMMAND_QUERYNUMOF: u8 = 3;
    pub const MN_COMM_CMMNDS_COMMAND_QUERYARRAY: u8 = 4;
    pub const MN_COMM_CMMNDS_COMMAND_REPLYNUMOF: u8 = 5;
    pub const MN_COMM_CMMNDS_COMMAND_REPLYARRAY: u8 = 6;
    pub const MN_COMM_CMMNDS_COMMAND_CONFIG: u8 = 7;
    pub const MN_APPL_WHOLEITEM: u8 = 0;
    pub const MN_APPL_CONFIG: u8 = 1;
    pub const MN_APPL_CONFIG_TXRATEDIVIDER: u8 = 2;
    pub const MN_APPL_STATUS: u8 = 3;
    pub const MN_APPL_CMMNDS_GO2STATE: u8 = 4;
    pub const MN_APPL_CMMNDS_TIMESET: u8 = 5;
    pub const MN_INFO_WHOLEITEM: u8 = 0;
    pub const MN_INFO_CONFIG: u8 = 1;
    pub const MN_INFO_CONFIG_ENABLED: u8 = 2;
    pub const MN_INFO_STATUS: u8 = 3;
    pub const MN_INFO_STATUS_BASIC: u8 = 4;
    pub const MN_SERVICE_WHOLEITEM: u8 = 0;
    pub const MN_SERVICE_STATUS_COMMANDRESULT: u8 = 1;
    pub const MN_SERVICE_CMMNDS_COMMAND: u8 = 2;

    pub const MC_JOINT_WHOLEITEM: u8 = 0;
    pub const MC_JOINT_CONFIG: u8 = 1;
    pub const MC_JOINT_CONFIG_PIDPOSITION: u8 = 2;
    pub const MC_JOINT_CONFIG_PIDTRAJECTORY: u8 = 2;
    pub const MC_JOINT_CONFIG_PIDVELOCITY: u8 = 3;
    pub const MC_JOINT_CONFIG_PIDDIRECT: u8 = 3;
    pub const MC_JOINT_CONFIG_PIDTORQUE: u8 = 4;
    pub const MC_JOINT_CONFIG_USERLIMITS: u8 = 5;
    pub const MC_JOINT_CONFIG_IMPEDANCE: u8 = 6;
    pub const MC_JOINT_CONFIG_MOTOR_PARAMS: u8 = 7;
    pub const MC_JOINT_CONFIG_TCFILTERTYPE: u8 = 8;
    pub const MC_JOINT_STATUS: u8 = 9;
    pub const MC_JOINT_STATUS_CORE: u8 = 10;
    pub const MC_JOINT_STATUS_TARGET: u8 = 11;
    pub const MC_JOINT_STATUS_CORE_MODES_CONTROLMODESTATUS: u8 = 12;
    pub const MC_JOINT_STATUS_CORE_MODES_INTERACTIONMODESTATUS: u8 = 13;
    pub const MC_JOINT_STATUS_CORE_MODES_ISMOTIONDONE: u8 = 14;
    pub const MC_JOINT_STATUS_ADDINFO_MULTIENC: u8 = 15;
    pub const MC_JOINT_STATUS_DEBUG: u8 = 16;
    pub const MC_JOINT_INPUTS: u8 = 17;
    pub const MC_JOINT_INPUTS_EXTERNALLYMEASUREDTORQUE: u8 = 18;
    pub const MC_JOINT_CMMNDS_CALIBRATION: u8 = 19;
    pub const MC_JOINT_CMMNDS_SETPOINT: u8 = 20;
    pub const MC_JOINT_CMMNDS_STOPTRAJECTORY: u8 = 21;
    pub const MC_JOINT_CMMNDS_CONTROLMODE: u8 = 22;
    pub const MC_JOINT_CMMNDS_INTERACTIONMODE: u8 = 23;
    pub const MC_MOTOR_WHOLEITEM: u8 = 0;
    pub const MC_MOTOR_CONFIG: u8 = 1;
    pub const MC_MOTOR_CONFIG_CURRENTLIMITS: u8 = 2;
    pub const MC_MOTOR_CONFIG_GEARBOX_M2J: u8 = 3;
    pub const MC_MOTOR_CONFIG_ROTORENCODER: u8 = 4;
    pub const MC_MOTOR_CONFIG_PWMLIMIT: u8 = 5;
    pub const MC_MOTOR_CONFIG_TEMPERATURELIMIT: u8 = 6;
    pub const MC_MOTOR_CONFIG_PIDCURRENT: u8 = 7;
    pub const MC_MOTOR_CONFIG_PIDSPEED: u8 = 8;
    pub const MC_MOTOR_STATUS: u8 = 9;
    pub const MC_MOTOR_STATUS_BASIC: u8 = 10;
    pub const MC_CONTROLLER_WHOLEITEM: u8 = 0;
    pub const MC_CONTROLLER_CONFIG: u8 = 1;
    pub const MC_CONTROLLER_STATUS: u8 = 2;

    pub const AS_STRAIN_WHOLEITEM: u8 = 0;
    pub const AS_STRAIN_CONFIG: u8 = 1;
    pub const AS_STRAIN_STATUS: u8 = 2;
    pub const AS_STRAIN_STATUS_FULLSCALE: u8 = 3;
    pub const AS_STRAIN_STATUS_CALIBRATEDVALUES: u8 = 4;
    pub const AS_STRAIN_STATUS_UNCALIBRATEDVALUES: u8 = 5;
    pub const AS_MAIS_WHOLEITEM: u8 = 0;
    pub const AS_MAIS_CONFIG: u8 = 1;
    pub const AS_MAIS_CONFIG_MODE: u8 = 2;
    pub const AS_MAIS_CONFIG_DATARATE: u8 = 3;
    pub const AS_MAIS_CONFIG_RESOLUTION: u8 = 4;
    pub const AS_MAIS_STATUS: u8 = 5;
    pub const AS_MAIS_STATUS_THE15VALUES: u8 = 6;
    /// Shared by temperature, inertial3, psc and pos.
    pub const AS_XX_WHOLEITEM: u8 = 0;
    pub const AS_XX_CONFIG: u8 = 1;
    pub const AS_XX_STATUS: u8 = 2;
    pub const AS_XX_CMMNDS_ENABLE: u8 = 3;
    pub const AS_FT_CONFIG: u8 = 0;
    pub const AS_FT_CMMNDS_ENABLE: u8 = 1;
    pub const AS_FT_STATUS: u8 = 2;
    pub const AS_FT_STATUS_TIMEDVALUE: u8 = 3;
    pub const AS_FT_STATUS_FULLSCALE: u8 = 4;
    pub const AS_BATTERY_CONFIG: u8 = 0;
    pub const AS_BATTERY_CMMNDS_ENABLE: u8 = 1;
    pub const AS_BATTERY_STATUS: u8 = 2;
    pub const AS_BATTERY_STATUS_TIMEDVALUE: u8 = 3;

    pub const SK_SKIN_WHOLEITEM: u8 = 0;
    pub const SK_SKIN_CONFIG_SIGMODE: u8 = 1;
    pub const SK_SKIN_STATUS_ARRAYOFCANDATA: u8 = 2;
    pub const SK_SKIN_CMMNDS_BOARDSCFG: u8 = 3;
    pub const SK_SKIN_CMMNDS_TRIANGLESCFG: u8 = 4;
}

/// Where a variable lives in its entity item.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TagLayout {
    pub offset: usize,
    pub size: usize,
}

const fn l(offset: usize, size: usize) -> TagLayout {
    TagLayout { offset, size }
}

/// Whole-item size and per-tag layout of each entity.
struct EntityLayout {
    item: usize,
    tags: &'static [TagLayout],
}

// eOmn_comm_t (120): config 8, status 32 at 8, cmmnds.command at 40 (a union: all the
// query/reply/config variables start there).
const MN_COMM: EntityLayout = EntityLayout {
    item: 120,
    tags: &[
        l(0, 120),
        l(8, 32),
        l(8, 2),
        l(40, 4),
        l(40, 4),
        l(40, 4),
        l(40, 72),
        l(40, 76),
    ],
};
// eOmn_appl_t (64): config 16 (txratedivider at 10), status 32 at 16, go2state at 48,
// timeset (u64) at 56.
const MN_APPL: EntityLayout = EntityLayout {
    item: 64,
    tags: &[l(0, 64), l(0, 16), l(10, 1), l(16, 32), l(48, 1), l(56, 8)],
};
// eOmn_info_t (80): config 8, status 72 at 8 (basic 24 first).
const MN_INFO: EntityLayout = EntityLayout {
    item: 80,
    tags: &[l(0, 80), l(0, 8), l(0, 1), l(8, 72), l(8, 24)],
};
// eOmn_service_t (396): status 48 (commandresult 32 at 16), cmmnds.command 348 at 48.
const MN_SERVICE: EntityLayout = EntityLayout {
    item: 396,
    tags: &[l(0, 396), l(16, 32), l(48, 348)],
};
// eOmc_joint_t (392): config 248, status 96 at 248 (core 40, target 28 at 288, multienc
// 12 at 316, debug 16 at 328), inputs 4 at 344, cmmnds 44 at 348.
const MC_JOINT: EntityLayout = EntityLayout {
    item: 392,
    tags: &[
        l(0, 392),  // wholeitem
        l(0, 248),  // config
        l(0, 40),   // config.pidtrajectory
        l(40, 40),  // config.piddirect
        l(80, 40),  // config.pidtorque
        l(120, 8),  // config.userlimits
        l(136, 12), // config.impedance
        l(156, 32), // config.motor_params
        l(198, 1),  // config.tcfiltertype
        l(248, 96), // status
        l(248, 40), // status.core
        l(288, 28), // status.target
        l(284, 1),  // status.core.modes.controlmodestatus
        l(285, 1),  // status.core.modes.interactionmodestatus
        l(286, 1),  // status.core.modes.ismotiondone
        l(316, 12), // status.addinfo.multienc
        l(328, 16), // status.debug
        l(344, 4),  // inputs
        l(344, 4),  // inputs.externallymeasuredtorque
        l(348, 28), // cmmnds.calibration
        l(376, 12), // cmmnds.setpoint
        l(388, 1),  // cmmnds.stoptrajectory
        l(389, 1),  // cmmnds.controlmode
        l(390, 1),  // cmmnds.interactionmode
    ],
};
// eOmc_motor_t (184): config 160, status 24 at 160.
const MC_MOTOR: EntityLayout = EntityLayout {
    item: 184,
    tags: &[
        l(0, 184),  // wholeitem
        l(0, 160),  // config
        l(92, 6),   // config.currentLimits
        l(80, 4),   // config.gearbox_M2J
        l(84, 4),   // config.rotorEncoderResolution
        l(112, 2),  // config.pwmLimit
        l(114, 2),  // config.temperatureLimit
        l(0, 40),   // config.pidcurrent
        l(40, 40),  // config.pidspeed
        l(160, 24), // status
        l(160, 20), // status.basic
    ],
};
// eOmc_controller_t (24): config 8, status 16.
const MC_CONTROLLER: EntityLayout = EntityLayout {
    item: 24,
    tags: &[l(0, 24), l(0, 8), l(8, 16)],
};
// eOas_strain_t (56): config 4, inputs 4, status 48 (three 16-byte arrays).
const AS_STRAIN: EntityLayout = EntityLayout {
    item: 56,
    tags: &[l(0, 56), l(0, 4), l(8, 48), l(8, 16), l(24, 16), l(40, 16)],
};
// eOas_mais_t (48): config 4 (mode, datarate, resolution), inputs 4, status 40.
const AS_MAIS: EntityLayout = EntityLayout {
    item: 48,
    tags: &[
        l(0, 48),
        l(0, 4),
        l(0, 1),
        l(1, 1),
        l(2, 1),
        l(8, 40),
        l(8, 40),
    ],
};
// eOas_temperature_t (28): config 4, status 20, cmmnds.enable.
const AS_TEMPERATURE: EntityLayout = EntityLayout {
    item: 28,
    tags: &[l(0, 28), l(0, 4), l(4, 20), l(24, 1)],
};
// eOas_inertial3_t (80): config 8, status 68, cmmnds.enable.
const AS_INERTIAL3: EntityLayout = EntityLayout {
    item: 80,
    tags: &[l(0, 80), l(0, 8), l(8, 68), l(76, 1)],
};
// eOas_psc_t (24): config 4, status 16, cmmnds.enable.
const AS_PSC: EntityLayout = EntityLayout {
    item: 24,
    tags: &[l(0, 24), l(0, 4), l(4, 16), l(20, 1)],
};
// eOas_pos_t (40): config 4, status 32, cmmnds.enable.
const AS_POS: EntityLayout = EntityLayout {
    item: 40,
    tags: &[l(0, 40), l(0, 4), l(4, 32), l(36, 1)],
};
// eOas_ft_t (64): config 4, cmmnds 4, status 56 (timedvalue 40, fullscale 12). No
// wholeitem tag: tag 0 is the config.
const AS_FT: EntityLayout = EntityLayout {
    item: 64,
    tags: &[l(0, 4), l(4, 1), l(8, 56), l(8, 40), l(48, 12)],
};
// eOas_battery_t (40): config 4, cmmnds 4, status 32.
const AS_BATTERY: EntityLayout = EntityLayout {
    item: 40,
    tags: &[l(0, 4), l(4, 1), l(8, 32), l(8, 32)],
};
// eOsk_skin_t (280): config 8, status 248 (arrayofcandata 244), cmmnds 24.
const SK_SKIN: EntityLayout = EntityLayout {
    item: 280,
    tags: &[l(0, 280), l(0, 1), l(8, 244), l(256, 8), l(264, 16)],
};

fn entity_layout(ep: u8, ent: u8) -> Option<&'static EntityLayout> {
    Some(match (ep, ent) {
        (endpoint::MANAGEMENT, entity::MN_COMM) => &MN_COMM,
        (endpoint::MANAGEMENT, entity::MN_APPL) => &MN_APPL,
        (endpoint::MANAGEMENT, entity::MN_INFO) => &MN_INFO,
        (endpoint::MANAGEMENT, entity::MN_SERVICE) => &MN_SERVICE,
        (endpoint::MOTION_CONTROL, entity::MC_JOINT) => &MC_JOINT,
        (endpoint::MOTION_CONTROL, entity::MC_MOTOR) => &MC_MOTOR,
        (endpoint::MOTION_CONTROL, entity::MC_CONTROLLER) => &MC_CONTROLLER,
        (endpoint::ANALOG_SENSORS, entity::AS_STRAIN) => &AS_STRAIN,
        (endpoint::ANALOG_SENSORS, entity::AS_MAIS) => &AS_MAIS,
        (endpoint::ANALOG_SENSORS, entity::AS_TEMPERATURE) => &AS_TEMPERATURE,
        (endpoint::ANALOG_SENSORS, entity::AS_INERTIAL3) => &AS_INERTIAL3,
        (endpoint::ANALOG_SENSORS, entity::AS_PSC) => &AS_PSC,
        (endpoint::ANALOG_SENSORS, entity::AS_POS) => &AS_POS,
        (endpoint::ANALOG_SENSORS, entity::AS_FT) => &AS_FT,
        (endpoint::ANALOG_SENSORS, entity::AS_BATTERY) => &AS_BATTERY,
        (endpoint::SKIN, entity::SK_SKIN) => &SK_SKIN,
        _ => return None,
    })
}

/// Offset and size of a variable in its entity item.
pub fn tag_layout(ep: u8, ent: u8, tag: u8) -> Option<TagLayout> {
    entity_layout(ep, ent)?.tags.get(usize::from(tag)).copied()
}

/// `sizeof` the whole entity item (e.g. 392 for `eOmc_joint_t`).
pub fn entity_item_size(ep: u8, ent: u8) -> Option<usize> {
    entity_layout(ep, ent).map(|e| e.item)
}

/// Number of entities of an endpoint (`eoprot_entities_xx_numberof`).
pub fn entities_in_endpoint(ep: u8) -> u8 {
    match ep {
        endpoint::MANAGEMENT => 4,
        endpoint::MOTION_CONTROL => 3,
        endpoint::ANALOG_SENSORS => 8,
        endpoint::SKIN => 1,
        _ => 0,
    }
}

/// Shorthands for the identifiers the host and the board use most.
pub mod ids {
    use super::{endpoint as ep, entity as en, tag as t, Id32};
    pub const COMM_STATUS: Id32 = Id32::new(ep::MANAGEMENT, en::MN_COMM, 0, t::MN_COMM_STATUS);
    pub const COMM_MANAGEMENT_PROTOCOL_VERSION: Id32 = Id32::new(
        ep::MANAGEMENT,
        en::MN_COMM,
        0,
        t::MN_COMM_STATUS_MANAGEMENTPROTOCOLVERSION,
    );
    pub const COMM_QUERY_ARRAY: Id32 = Id32::new(
        ep::MANAGEMENT,
        en::MN_COMM,
        0,
        t::MN_COMM_CMMNDS_COMMAND_QUERYARRAY,
    );
    pub const COMM_REPLY_ARRAY: Id32 = Id32::new(
        ep::MANAGEMENT,
        en::MN_COMM,
        0,
        t::MN_COMM_CMMNDS_COMMAND_REPLYARRAY,
    );
    pub const APPL_CONFIG: Id32 = Id32::new(ep::MANAGEMENT, en::MN_APPL, 0, t::MN_APPL_CONFIG);
    pub const APPL_STATUS: Id32 = Id32::new(ep::MANAGEMENT, en::MN_APPL, 0, t::MN_APPL_STATUS);
    pub const APPL_GO2STATE: Id32 =
        Id32::new(ep::MANAGEMENT, en::MN_APPL, 0, t::MN_APPL_CMMNDS_GO2STATE);
    pub const INFO_STATUS: Id32 = Id32::new(ep::MANAGEMENT, en::MN_INFO, 0, t::MN_INFO_STATUS);
    /// The motion-control controller's status (initted joints and motors, supply voltage).
    pub const CONTROLLER_STATUS: Id32 = Id32::new(
        ep::MOTION_CONTROL,
        en::MC_CONTROLLER,
        0,
        t::MC_CONTROLLER_STATUS,
    );
    pub const SERVICE_COMMAND: Id32 = Id32::new(
        ep::MANAGEMENT,
        en::MN_SERVICE,
        0,
        t::MN_SERVICE_CMMNDS_COMMAND,
    );
    pub const SERVICE_COMMAND_RESULT: Id32 = Id32::new(
        ep::MANAGEMENT,
        en::MN_SERVICE,
        0,
        t::MN_SERVICE_STATUS_COMMANDRESULT,
    );

    /// A joint variable (`eoprot_entity_mc_joint`).
    pub const fn joint(index: u8, tag: u8) -> Id32 {
        Id32::new(ep::MOTION_CONTROL, en::MC_JOINT, index, tag)
    }
    /// A motor variable (`eoprot_entity_mc_motor`).
    pub const fn motor(index: u8, tag: u8) -> Id32 {
        Id32::new(ep::MOTION_CONTROL, en::MC_MOTOR, index, tag)
    }
    /// An analog-sensor variable.
    pub const fn analog(entity: u8, index: u8, tag: u8) -> Id32 {
        Id32::new(ep::ANALOG_SENSORS, entity, index, tag)
    }
    /// A skin variable.
    pub const fn skin(index: u8, tag: u8) -> Id32 {
        Id32::new(ep::SKIN, en::SK_SKIN, index, tag)
    }
}
