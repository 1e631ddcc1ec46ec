//! Skin endpoint (`EoSkin.h`, `EoProtocolSK.h`): the board forwards the MTBs' CAN frames.

use crate::wire::{Entity, Reader, Writer};

/// `eOsk_sigmode_t`.
pub mod sigmode {
    pub const DONT_SIGNAL: u8 = 0;
    pub const SIGNAL_OLDWAY: u8 = 1;
    pub const SIGNAL: u8 = 2;
}

/// `eOsk_candata_t` (10 bytes): `info` = size:4 | CAN id:12, then the CAN payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SkinCanData {
    pub info: u16,
    pub data: [u8; 8],
}

impl SkinCanData {
    /// `EOSK_CANDATA_INFO(size, idcan)`.
    pub fn new(can_id: u16, payload: &[u8]) -> Self {
        let n = payload.len().min(8);
        let mut data = [0u8; 8];
        data[..n].copy_from_slice(&payload[..n]);
        Self {
            info: ((n as u16 & 0xf) << 12) | (can_id & 0x0fff),
            data,
        }
    }
    pub fn can_id(&self) -> u16 {
        self.info & 0x0fff
    }
    pub fn payload(&self) -> &[u8] {
        &self.data[..usize::from(self.info >> 12).min(8)]
    }
}

impl Entity for SkinCanData {
    const C_TYPE: &'static str = "eOsk_candata_t";
    const SIZE: usize = 10;
    fn write(&self, w: &mut Writer) {
        w.u16(self.info);
        w.bytes(&self.data);
    }
    fn read(r: &mut Reader) -> Self {
        Self {
            info: r.u16(),
            data: r.array(),
        }
    }
}

/// Capacity of `EOarray_of_skincandata_t` (`eosk_capacity_arrayof_skincandata`).
pub const SKIN_CANDATA_CAPACITY: usize = 24;

/// `EOarray_of_skincandata_t` (244 bytes): the variable `eoprot_tag_sk_skin_status_arrayofcandata`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SkinStatus {
    pub frames: Vec<SkinCanData>,
}

impl Entity for SkinStatus {
    const C_TYPE: &'static str = "EOarray_of_skincandata_t";
    const SIZE: usize = 244;
    fn write(&self, w: &mut Writer) {
        let n = self.frames.len().min(SKIN_CANDATA_CAPACITY);
        w.bytes(&[SKIN_CANDATA_CAPACITY as u8, 10, n as u8, 0]);
        for f in &self.frames[..n] {
            w.entity(f);
        }
        w.zeros((SKIN_CANDATA_CAPACITY - n) * 10);
    }
    fn read(r: &mut Reader) -> Self {
        let [_, item, size, _] = r.array();
        let n = if item == 10 {
            usize::from(size).min(SKIN_CANDATA_CAPACITY)
        } else {
            0
        };
        let frames = (0..n).map(|_| r.entity()).collect();
        r.skip((SKIN_CANDATA_CAPACITY - n) * 10);
        Self { frames }
    }
}

/// `eOsk_cmd_boardsCfg_t` (8 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SkinBoardsConfig {
    pub can_destination: [u16; 2],
    /// `eOsk_board_config_t`: skintype, period, noload.
    pub skin_type: u8,
    pub period: u8,
    pub noload: u8,
}

impl Entity for SkinBoardsConfig {
    const C_TYPE: &'static str = "eOsk_cmd_boardsCfg_t";
    const SIZE: usize = 8;
    fn write(&self, w: &mut Writer) {
        w.u16(self.can_destination[0]);
        w.u16(self.can_destination[1]);
        w.bytes(&[self.skin_type, self.period, self.noload, 0]);
    }
    fn read(r: &mut Reader) -> Self {
        let can_destination = [r.u16(), r.u16()];
        let [skin_type, period, noload, _] = r.array();
        Self {
            can_destination,
            skin_type,
            period,
            noload,
        }
    }
}

/// `eOsk_cmd_trianglesCfg_t` (16 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SkinTrianglesConfig {
    pub can_destination: [u16; 2],
    pub id_start: u8,
    pub id_end: u8,
    /// `eOsk_triangle_config_t`: enable, shift, CDCoffset.
    pub enable: u8,
    pub shift: u8,
    pub cdc_offset: u16,
}

impl Entity for SkinTrianglesConfig {
    const C_TYPE: &'static str = "eOsk_cmd_trianglesCfg_t";
    const SIZE: usize = 16;
    fn write(&self, w: &mut Writer) {
        w.u16(self.can_destination[0]);
        w.u16(self.can_destination[1]);
        w.u8(self.id_start);
        w.u8(self.id_end);
        w.zeros(6);
        w.u8(self.enable);
        w.u8(self.shift);
        w.u16(self.cdc_offset);
    }
    fn read(r: &mut Reader) -> Self {
        let can_destination = [r.u16(), r.u16()];
        let id_start = r.u8();
        let id_end = r.u8();
        r.skip(6);
        Self {
            can_destination,
            id_start,
            id_end,
            enable: r.u8(),
            shift: r.u8(),
            cdc_offset: r.u16(),
        }
    }
}
