//! Ropframes, ROPs and entities built byte by byte from the layouts of icub-firmware-shared
//! (`EOropframe_hid.h`, `EOrop.h`, `EoProtocol.h`, `EoManagement.h`, `EoMotionControl.h`,
//! `EoAnalogSensors.h`, `EoSkin.h`): sizes, offsets and values are named in each test.

use icub_eth::entities::analog::{BatteryStatus, FtStatus, Inertial3Status, StrainStatus};
use icub_eth::entities::mc::{
    control_mode, Calibrator, JointConfig, JointStatus, JointStatusCore, MotorConfig, MotorStatus,
    Pid, Setpoint,
};
use icub_eth::entities::mn::{
    category, ApplConfig, ApplStatus, CommStatus, ReplyArray, ServiceCommand, ServiceCommandResult,
    ServiceOperation, ServiceStatus, Version,
};
use icub_eth::entities::skin::{SkinCanData, SkinStatus};
use icub_eth::frame::{FrameBuilder, RopsError, EMPTY_FRAME_SIZE};
use icub_eth::id::{ids, tag, Id32};
use icub_eth::rop::{ConfInfo, RopCtrl};
use icub_eth::{decode_datagram, Entity, Frame, FrameError, NvStore, Rop, RopCode, RopError};

fn le32(v: u32) -> [u8; 4] {
    v.to_le_bytes()
}

/// A ropframe by hand: EOropframeHeader_t (24 bytes), the ROPs, EOropframeFooter_t (4).
fn frame_bytes(rops: &[u8], count: u16, age: u64, seq: u64) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(&le32(0x1234_5678)); // offset 0: startofframe
    b.extend_from_slice(&(rops.len() as u16).to_le_bytes()); // offset 4: ropssizeof
    b.extend_from_slice(&count.to_le_bytes()); // offset 6: ropsnumberof
    b.extend_from_slice(&age.to_le_bytes()); // offset 8: ageofframe (µs)
    b.extend_from_slice(&seq.to_le_bytes()); // offset 16: sequencenumber
    assert_eq!(b.len(), 24, "EOropframeHeader_t is 24 bytes");
    b.extend_from_slice(rops);
    b.extend_from_slice(&le32(0x8765_4321)); // endoframe
    b
}

#[test]
fn id32_is_endpoint_entity_index_tag() {
    // EOPROT_ID_GET(ep 1 = motioncontrol, entity 0 = joint, index 3, tag 20 = cmmnds.setpoint)
    let id = ids::joint(3, tag::MC_JOINT_CMMNDS_SETPOINT);
    assert_eq!(id.0, 0x0100_0314);
    assert_eq!(
        (id.endpoint(), id.entity(), id.index(), id.tag()),
        (1, 0, 3, 20)
    );
    // On the wire the id32 is a little-endian u32: tag first.
    assert_eq!(id.0.to_le_bytes(), [0x14, 0x03, 0x00, 0x01]);
    // The management protocol version: ep 0, entity comm 0, index 0, tag 2.
    assert_eq!(ids::COMM_MANAGEMENT_PROTOCOL_VERSION.0, 0x0000_0002);
    assert_eq!(ids::SERVICE_COMMAND.0, 0x0003_0002);
}

#[test]
fn empty_ropframe_is_28_bytes() {
    let b = frame_bytes(&[], 0, 7, 1);
    assert_eq!(b.len(), EMPTY_FRAME_SIZE);
    assert_eq!(b.len(), 28, "eo_ropframe_sizeforZEROrops");
    let f = Frame::decode(&b).unwrap();
    assert_eq!(f.header.rops_size, 0);
    assert_eq!(f.header.rops_count, 0);
    assert_eq!(f.header.age, 7);
    assert_eq!(f.header.sequence, 1);
    assert_eq!(FrameBuilder::new(768).finish(1, 7), b);
}

#[test]
fn ask_with_signature_and_time_is_20_bytes() {
    // The host's ask (HostTransceiver::addROPask): ctrl plustime (bit 2) + plussign (bit 3)
    // = 0x0C, ropc 1 (ask), dsiz 0, id32, no data, signature (4), time (8).
    let id = ids::COMM_MANAGEMENT_PROTOCOL_VERSION;
    let mut rop = vec![0x0C, 0x01, 0x00, 0x00];
    rop.extend_from_slice(&le32(id.0));
    rop.extend_from_slice(&le32(42)); // signature
    rop.extend_from_slice(&1_000_000u64.to_le_bytes()); // time, µs
    assert_eq!(rop.len(), 20);
    let built = Rop::ask(id).with_signature(42).with_time(1_000_000);
    assert_eq!(built.encode().unwrap(), rop);
    assert_eq!(built.wire_size(), 20);

    let frame = frame_bytes(&rop, 1, 5, 9);
    let (h, rops, err) = decode_datagram(&frame).unwrap();
    assert_eq!(err, None);
    assert_eq!(
        (h.rops_size, h.rops_count, h.age, h.sequence),
        (20, 1, 5, 9)
    );
    assert_eq!(rops, vec![built.clone()]);
    let mut fb = FrameBuilder::new(768);
    fb.push(&built).unwrap();
    assert_eq!(fb.finish(9, 5), frame);
}

#[test]
fn data_is_padded_to_four_bytes() {
    // set<joint 2 cmmnds controlmode> = position (1 byte): dsiz 1, data 1 + 3 padding.
    let id = ids::joint(2, tag::MC_JOINT_CMMNDS_CONTROLMODE);
    let mut rop = vec![0x00, 0x03, 0x01, 0x00];
    rop.extend_from_slice(&le32(id.0));
    rop.extend_from_slice(&[control_mode::POSITION, 0, 0, 0]);
    assert_eq!(rop.len(), 12);
    let r = Rop::set(id, vec![control_mode::POSITION]);
    assert_eq!(r.encode().unwrap(), rop);
    let (back, n) = Rop::decode(&rop).unwrap();
    assert_eq!(n, 12);
    assert_eq!(back.data, vec![control_mode::POSITION]);

    // say<comm status managementprotocolversion> = 2.25: dsiz 2, data [2, 25, 0, 0],
    // signature echoed (the board copies plussign and the signature).
    let v = ids::COMM_MANAGEMENT_PROTOCOL_VERSION;
    let mut say = vec![0x08, 0x02, 0x02, 0x00];
    say.extend_from_slice(&le32(v.0));
    say.extend_from_slice(&[2, 25, 0, 0]);
    say.extend_from_slice(&le32(42));
    let (back, n) = Rop::decode(&say).unwrap();
    assert_eq!(n, 16);
    assert_eq!(back.code, RopCode::Say);
    assert_eq!(
        Version::from_bytes(&back.data).unwrap(),
        Version::new(2, 25)
    );
    assert_eq!(back.signature, Some(42));
}

#[test]
fn confirmations_carry_no_data() {
    // An ack (confinfo 2) of a set: the data field is not required (eo_rop_datafield_is_required),
    // so even a non-zero dsiz is not followed by data.
    let id = ids::APPL_CONFIG;
    let mut ack = vec![0x02, 0x03, 0x10, 0x00];
    ack.extend_from_slice(&le32(id.0));
    let (r, n) = Rop::decode(&ack).unwrap();
    assert_eq!(n, 8);
    assert_eq!(r.ctrl.confinfo, ConfInfo::Ack);
    assert!(r.data.is_empty());
    let ctrl = RopCtrl::from_byte(0x29).unwrap(); // rqstconf (bit 5) | plussign (bit 3) | nak (1)
    assert!(ctrl.rqstconf && ctrl.plussign && !ctrl.plustime);
    assert_eq!(ctrl.confinfo, ConfInfo::Nak);
    assert_eq!(ctrl.to_byte(), 0x29);
}

#[test]
fn malformed_frames_are_typed_errors() {
    let good = frame_bytes(&[], 0, 0, 1);
    assert_eq!(
        Frame::decode(&good[..27]).unwrap_err(),
        FrameError::TooShort(27)
    );
    let mut b = good.clone();
    b[0] = 0;
    assert!(matches!(Frame::decode(&b), Err(FrameError::StartCode(_))));
    let mut b = good.clone();
    b[27] = 0;
    assert!(matches!(Frame::decode(&b), Err(FrameError::EndCode(_))));
    let mut b = good.clone();
    b[4] = 8; // ropssizeof 8 in a 28-byte datagram
    assert_eq!(
        Frame::decode(&b).unwrap_err(),
        FrameError::RopsSize {
            rops_size: 8,
            len: 28
        }
    );
    let mut b = good.clone();
    b.push(0);
    assert_eq!(Frame::decode(&b).unwrap_err(), FrameError::TrailingBytes(1));
}

#[test]
fn malformed_rops_are_typed_errors() {
    let id = ids::APPL_STATUS.0.to_le_bytes();
    let head = |ctrl: u8, ropc: u8, dsiz: u16| {
        let mut v = vec![ctrl, ropc];
        v.extend_from_slice(&dsiz.to_le_bytes());
        v.extend_from_slice(&id);
        v
    };
    assert_eq!(
        Rop::decode(&[0; 7]).unwrap_err(),
        RopError::Truncated {
            needed: 8,
            available: 7
        }
    );
    assert_eq!(
        Rop::decode(&head(0x40, 1, 0)).unwrap_err(),
        RopError::Version(1)
    );
    assert_eq!(
        Rop::decode(&head(0, 0, 0)).unwrap_err(),
        RopError::RopCode(0)
    );
    assert_eq!(
        Rop::decode(&head(0, 6, 0)).unwrap_err(),
        RopError::RopCode(6)
    );
    assert_eq!(
        Rop::decode(&head(3, 1, 0)).unwrap_err(),
        RopError::ConfInfo(3)
    );
    assert_eq!(
        Rop::decode(&head(0, 3, 0)).unwrap_err(),
        RopError::MissingData(RopCode::Set)
    );
    // set of 5 bytes needs 8 + 8 bytes.
    assert_eq!(
        Rop::decode(&head(0, 3, 5)).unwrap_err(),
        RopError::Truncated {
            needed: 16,
            available: 8
        }
    );
    // plustime without the 8 bytes.
    assert_eq!(
        Rop::decode(&head(0x04, 1, 0)).unwrap_err(),
        RopError::Truncated {
            needed: 16,
            available: 8
        }
    );

    // In a frame: the ROPs before a bad one are kept; a count that does not match is reported.
    let mut rops = Rop::ask(ids::APPL_STATUS).encode().unwrap();
    rops.extend_from_slice(&head(0, 9, 0));
    let f = frame_bytes(&rops, 2, 0, 1);
    let (_, parsed, err) = decode_datagram(&f).unwrap();
    assert_eq!(parsed.len(), 1);
    assert_eq!(
        err,
        Some(RopsError::Rop {
            index: 1,
            error: RopError::RopCode(9)
        })
    );
    let f = frame_bytes(&Rop::ask(ids::APPL_STATUS).encode().unwrap(), 3, 0, 1);
    let (_, parsed, err) = decode_datagram(&f).unwrap();
    assert_eq!(parsed.len(), 1);
    assert_eq!(
        err,
        Some(RopsError::Count {
            declared: 3,
            parsed: 1,
            unparsed_bytes: 0
        })
    );
}

#[test]
fn frame_builder_respects_capacity() {
    // maxSizeRXpacket 768 leaves 740 bytes of ROPs; a set<service command> is 8 + 348.
    let mut fb = FrameBuilder::new(768);
    let cmd = ServiceCommand::bare(ServiceOperation::Start, category::MC).to_bytes();
    let rop = Rop::set(ids::SERVICE_COMMAND, cmd);
    assert_eq!(rop.wire_size(), 356);
    fb.push(&rop).unwrap();
    fb.push(&rop).unwrap();
    assert_eq!(fb.room(), 740 - 712);
    assert!(fb.push(&rop).is_err());
    assert_eq!(fb.finish(1, 0).len(), 28 + 712);
}

#[test]
fn entity_sizes_are_the_c_sizes() {
    // EO_VERIFYsizeof of each C type, and the size the protocol's ROM gives the tag.
    let cases: &[(usize, usize, Option<Id32>)] = &[
        (
            Version::SIZE,
            2,
            Some(ids::COMM_MANAGEMENT_PROTOCOL_VERSION),
        ),
        (CommStatus::SIZE, 32, Some(ids::COMM_STATUS)),
        (ApplConfig::SIZE, 16, Some(ids::APPL_CONFIG)),
        (ApplStatus::SIZE, 32, Some(ids::APPL_STATUS)),
        (ReplyArray::SIZE, 72, Some(ids::COMM_REPLY_ARRAY)),
        (ServiceCommand::SIZE, 348, Some(ids::SERVICE_COMMAND)),
        (
            ServiceCommandResult::SIZE,
            32,
            Some(ids::SERVICE_COMMAND_RESULT),
        ),
        (ServiceStatus::SIZE, 48, None),
        (
            Pid::SIZE,
            40,
            Some(ids::joint(0, tag::MC_JOINT_CONFIG_PIDTRAJECTORY)),
        ),
        (
            JointConfig::SIZE,
            248,
            Some(ids::joint(0, tag::MC_JOINT_CONFIG)),
        ),
        (
            JointStatusCore::SIZE,
            40,
            Some(ids::joint(0, tag::MC_JOINT_STATUS_CORE)),
        ),
        (
            JointStatus::SIZE,
            96,
            Some(ids::joint(0, tag::MC_JOINT_STATUS)),
        ),
        (
            Calibrator::SIZE,
            28,
            Some(ids::joint(0, tag::MC_JOINT_CMMNDS_CALIBRATION)),
        ),
        (
            Setpoint::SIZE,
            12,
            Some(ids::joint(0, tag::MC_JOINT_CMMNDS_SETPOINT)),
        ),
        (
            MotorConfig::SIZE,
            160,
            Some(ids::motor(0, tag::MC_MOTOR_CONFIG)),
        ),
        (
            MotorStatus::SIZE,
            24,
            Some(ids::motor(0, tag::MC_MOTOR_STATUS)),
        ),
        (
            StrainStatus::SIZE,
            48,
            Some(ids::analog(0, 0, tag::AS_STRAIN_STATUS)),
        ),
        (
            Inertial3Status::SIZE,
            68,
            Some(ids::analog(3, 0, tag::AS_XX_STATUS)),
        ),
        (
            FtStatus::SIZE,
            56,
            Some(ids::analog(6, 0, tag::AS_FT_STATUS)),
        ),
        (
            BatteryStatus::SIZE,
            32,
            Some(ids::analog(7, 0, tag::AS_BATTERY_STATUS)),
        ),
        (
            SkinStatus::SIZE,
            244,
            Some(ids::skin(0, tag::SK_SKIN_STATUS_ARRAYOFCANDATA)),
        ),
    ];
    for (size, c_size, id) in cases {
        assert_eq!(size, c_size);
        if let Some(id) = id {
            assert_eq!(id.size(), Some(*c_size), "{id}");
        }
    }
    // Whole items: eOmc_joint_t 392, eOmc_motor_t 184, eOmn_service_t 396, eOsk_skin_t 280.
    assert_eq!(ids::joint(0, tag::MC_JOINT_WHOLEITEM).size(), Some(392));
    assert_eq!(ids::motor(0, tag::MC_MOTOR_WHOLEITEM).size(), Some(184));
    assert_eq!(Id32::new(0, 3, 0, 0).size(), Some(396));
    assert_eq!(ids::skin(0, tag::SK_SKIN_WHOLEITEM).size(), Some(280));
    // Every typed value encodes to exactly its size.
    assert_eq!(JointConfig::default().to_bytes().len(), 248);
    assert_eq!(MotorConfig::default().to_bytes().len(), 160);
    assert_eq!(ApplStatus::default().to_bytes().len(), 32);
}

#[test]
fn joint_status_core_offsets() {
    // eOmc_joint_status_core_t: measures (position 0, velocity 4, acceleration 8,
    // torque f32 12), ofpid 16..36, modes (controlmodestatus 36, interactionmodestatus 37,
    // ismotiondone 38, filler 39).
    let c = JointStatusCore {
        position: 0x0102_0304,
        velocity: -2,
        acceleration: 3,
        torque: 1.5,
        ofpid: [10, 11, 12, 13, 14],
        control_mode: control_mode::CALIB,
        interaction_mode: 1,
        motion_done: true,
    };
    let b = c.to_bytes();
    assert_eq!(&b[0..4], &[4, 3, 2, 1]);
    assert_eq!(&b[4..8], &(-2i32).to_le_bytes());
    assert_eq!(&b[12..16], &1.5f32.to_le_bytes());
    assert_eq!(&b[32..36], &14i32.to_le_bytes());
    assert_eq!(&b[36..40], &[0xFE, 1, 1, 0]);
    assert_eq!(JointStatusCore::from_bytes(&b).unwrap(), c);
    // In eOmc_joint_t the core is at 248 (after the 248-byte config) and the control mode
    // status at 248 + 36 = 284.
    assert_eq!(
        ids::joint(0, tag::MC_JOINT_STATUS_CORE_MODES_CONTROLMODESTATUS)
            .layout()
            .unwrap()
            .offset,
        284
    );
}

#[test]
fn setpoint_layout() {
    // eOmc_setpoint_t: type u8 at 0, 3 fillers, union at 4: position value 4, withvelocity 8.
    let s = Setpoint::Position {
        value: 1000,
        velocity: -7,
    };
    let b = s.to_bytes();
    assert_eq!(b[0], 0);
    assert_eq!(&b[1..4], &[0, 0, 0]);
    assert_eq!(&b[4..8], &1000i32.to_le_bytes());
    assert_eq!(&b[8..12], &(-7i32).to_le_bytes());
    assert_eq!(Setpoint::from_bytes(&b).unwrap(), s);
    // torque: type 2, f32 at 4.
    let b = Setpoint::Torque { value: 0.25 }.to_bytes();
    assert_eq!(b[0], 2);
    assert_eq!(&b[4..8], &0.25f32.to_le_bytes());
    // eOmc_joint_t: cmmnds at 348, calibration 28 then setpoint at 376.
    assert_eq!(
        ids::joint(0, tag::MC_JOINT_CMMNDS_SETPOINT)
            .layout()
            .unwrap()
            .offset,
        376
    );
}

#[test]
fn service_command_layout() {
    // eOmn_service_cmmnds_command_t: operation 0, category 1, filler 2..4, parameter at 4
    // (eOmn_serv_arrayof_id32_t: EOarray head capacity 41, itemsize 4, size, internalmem,
    // then the id32s).
    let regs = [
        ids::joint(0, tag::MC_JOINT_STATUS_CORE),
        ids::motor(0, tag::MC_MOTOR_STATUS),
    ];
    let c = ServiceCommand::regsig_load(category::MC, &regs);
    let b = c.to_bytes();
    assert_eq!(b.len(), 348);
    assert_eq!(&b[0..4], &[6, 0, 0, 0]);
    assert_eq!(&b[4..8], &[41, 4, 2, 0]);
    assert_eq!(&b[8..12], &regs[0].0.to_le_bytes());
    assert_eq!(&b[12..16], &regs[1].0.to_le_bytes());
    assert_eq!(ServiceCommand::from_bytes(&b).unwrap().id32s(), regs);
    // A bare start: configuration type eomn_serv_NONE (255) at parameter offset 0.
    let b = ServiceCommand::bare(ServiceOperation::Start, category::FT).to_bytes();
    assert_eq!(&b[0..5], &[4, 8, 0, 0, 255]);
    // verifyactivate: type at 4, diagnosticsmode 5, diagnosticsparam 6..8, data at 8.
    let b = ServiceCommand::verify_activate(category::MC, 15, 2, 0x0102, &[9, 9]).to_bytes();
    assert_eq!(&b[0..10], &[3, 0, 0, 0, 15, 2, 2, 1, 9, 9]);
}

#[test]
fn appl_status_layout() {
    // eOmn_appl_status_t: buildate u32 0, version 4..6, name 6..22, currstate 22, filler 23,
    // cloop_timings 24..30, txdecimationfactor 30, boardtype 31.
    let mut s = ApplStatus {
        version: Version::new(3, 80),
        current_state: 1,
        cloop_timings: [400, 300, 300],
        tx_decimation_factor: 1,
        board_type: 32,
        ..Default::default()
    };
    s.name[..4].copy_from_slice(b"ems4");
    let b = s.to_bytes();
    assert_eq!(&b[4..6], &[3, 80]);
    assert_eq!(&b[6..10], b"ems4");
    assert_eq!(b[22], 1);
    assert_eq!(&b[24..26], &400u16.to_le_bytes());
    assert_eq!((b[30], b[31]), (1, 32));
    assert_eq!(ApplStatus::from_bytes(&b).unwrap(), s);
}

#[test]
fn store_reads_tags_inside_items() {
    let mut s = NvStore::new();
    s.add_entity(1, 0, 2);
    let sp = Setpoint::Position {
        value: 5,
        velocity: 6,
    };
    s.write(ids::joint(1, tag::MC_JOINT_CMMNDS_SETPOINT), &sp)
        .unwrap();
    let whole = s.get(ids::joint(1, tag::MC_JOINT_WHOLEITEM)).unwrap();
    assert_eq!(&whole[376..388], &sp.to_bytes()[..]);
    // A set must have exactly the variable's size.
    assert!(s
        .set(ids::joint(1, tag::MC_JOINT_CMMNDS_CONTROLMODE), &[1, 0])
        .is_err());
    // Index 2 is not on this board; tag 24 is not in the protocol.
    assert!(s.get(ids::joint(2, tag::MC_JOINT_STATUS_CORE)).is_err());
    assert!(s.get(ids::joint(0, 24)).is_err());
}

#[test]
fn skin_candata_info() {
    // EOSK_CANDATA_INFO(size, idcan) = size << 12 | id (12 bits).
    let d = SkinCanData::new(0x4C0, &[1, 2, 3, 4, 5, 6, 7, 8]);
    assert_eq!(d.info, 0x84C0);
    assert_eq!(d.payload(), &[1, 2, 3, 4, 5, 6, 7, 8]);
    let st = SkinStatus { frames: vec![d; 3] };
    let b = st.to_bytes();
    assert_eq!(&b[0..4], &[24, 10, 3, 0]);
    assert_eq!(&b[4..6], &0x84C0u16.to_le_bytes());
    assert_eq!(SkinStatus::from_bytes(&b).unwrap(), st);
}

#[test]
fn hostile_bytes_never_panic() {
    // A cheap deterministic sweep (the fuzz target eth_decode does the real work).
    let base = {
        let mut rops = Rop::ask(ids::APPL_STATUS)
            .with_signature(1)
            .encode()
            .unwrap();
        rops.extend(
            Rop::set(ids::APPL_CONFIG, ApplConfig::default().to_bytes())
                .encode()
                .unwrap(),
        );
        frame_bytes(&rops, 2, 1, 1)
    };
    let mut x: u32 = 0x1234_5678;
    for _ in 0..20_000 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        let mut b = base.clone();
        let i = (x as usize) % b.len();
        b[i] = (x >> 8) as u8;
        let cut = (x as usize >> 3) % (b.len() + 1);
        let _ = decode_datagram(&b[..cut]);
        let _ = decode_datagram(&b);
        let _ = Rop::decode(&b[EMPTY_FRAME_SIZE.min(cut)..]);
    }
}

#[test]
fn service_config_layouts() {
    use icub_eth::entities::boards::{BoardInfo, CanLocation};
    use icub_eth::entities::mn::service_type;
    use icub_eth::entities::service::{
        entities_for_service, CanSensorDescriptor, CanSensorsConfig, Coupling, JomoDescriptor,
        JomoDescriptors, McServiceConfig, SkinServiceConfig,
    };
    // eOmn_serv_config_data_mc_foc_t (324 of the 340-byte union): version 5 at 0, type at 5,
    // 2 fillers, eOmc_arrayof_4jomodescriptors_t at 8 (head: capacity 4, itemsize 5, size),
    // eOmc_4jomo_coupling_t (292) at 32.
    let jomo = JomoDescriptor {
        actuator: CanLocation {
            port: 0,
            addr: 1,
            inside_index: 0,
        }
        .to_byte(),
        encoder1: (1, 2, 1), // aea on port 2, at joint
        encoder2: (0, 0, 0),
    };
    let foc = McServiceConfig::Foc {
        version: [2, 0, 0, 2, 0],
        board_type: 8, // eobrd_foc
        jomos: JomoDescriptors(vec![jomo; 3]),
        coupling: Coupling::default(),
    };
    let b = foc.to_bytes();
    assert_eq!(b.len(), 340);
    assert_eq!(b[5], 8);
    assert_eq!(&b[8..12], &[4, 5, 3, 0]);
    assert_eq!(&b[12..17], &[0x02, 1, 2 | 1 << 5, 0, 0]);
    // coupling: joint2set at 32, jsetcfg 36..100, joint2motor at 100 (identity in q17.14).
    assert_eq!(&b[32..36], &[0, 1, 2, 3]);
    assert_eq!(&b[100..104], &(1i32 << 14).to_le_bytes());
    assert_eq!(
        McServiceConfig::parse(service_type::MC_FOC, &b),
        Some(foc.clone())
    );
    assert_eq!(foc.joints(), 3);
    assert_eq!(
        entities_for_service(category::MC, service_type::MC_FOC, &b),
        vec![(1, 0, 3), (1, 1, 3), (1, 2, 1)]
    );
    // mc4: version 5, shifts 3, mc4joints[12] at 8, mais 6 at 20, broadcastflags at 26.
    let mut joints = [0u8; 12];
    joints[..4].copy_from_slice(&[0x02, 0x22, 0x04, 0x24]);
    let mc4 = McServiceConfig::Mc4 {
        version: [0; 5],
        shifts: [8, 0x55, 0x55],
        joints,
        mais: [0; 6],
        broadcast_flags: 0x0013,
    };
    let b = mc4.to_bytes();
    assert_eq!(&b[8..12], &[0x02, 0x22, 0x04, 0x24]);
    assert_eq!(&b[26..28], &[0x13, 0]);
    assert_eq!(
        McServiceConfig::parse(service_type::MC_MC4, &b)
            .unwrap()
            .joints(),
        4
    );
    // mc4plusfaps: eOmn_serv_config_data_as_pos_t (24) first, jomos at 24.
    let faps = McServiceConfig::Mc4plusFaps {
        pos: [0; 24],
        jomos: JomoDescriptors(vec![jomo; 4]),
        coupling: Coupling::default(),
    };
    let b = faps.to_bytes();
    assert_eq!(&b[24..28], &[4, 5, 4, 0]);
    assert_eq!(
        McServiceConfig::parse(service_type::MC_MC4PLUSFAPS, &b)
            .unwrap()
            .joints(),
        4
    );
    // eOmn_serv_config_data_as_ft_t (40): canmonitor 4, EOarray head (4, 8, n) at 4, sensors at 8.
    let ft = CanSensorsConfig {
        can_monitor: [100, 1, 0, 0],
        sensors: vec![
            CanSensorDescriptor {
                board: BoardInfo {
                    board_type: 12,
                    firmware: [2, 0, 0],
                    protocol: [2, 0]
                },
                can_location: CanLocation {
                    port: 1,
                    addr: 13,
                    inside_index: 0
                },
            };
            2
        ],
    };
    let b = ft.ft_bytes();
    assert_eq!(b.len(), 40);
    assert_eq!(&b[4..8], &[4, 8, 2, 0]);
    assert_eq!(&b[8..15], &[12, 2, 0, 0, 2, 0, 1 | 13 << 1]);
    assert_eq!(CanSensorsConfig::from_ft_bytes(&b), ft);
    assert_eq!(ft.battery_bytes().len(), 16);
    assert_eq!(
        entities_for_service(category::FT, service_type::AS_FT, &b),
        vec![(2, 6, 2)]
    );
    // eOmn_serv_config_data_sk_skin_t (24): boardinfo 6, numofpatches at 6, canmapskin at 8.
    let sk = SkinServiceConfig {
        num_of_patches: 2,
        can_map: [[0x7f00, 0], [0, 0x3f00], [0; 2], [0; 2]],
        ..Default::default()
    };
    let b = sk.to_bytes();
    assert_eq!(b[6], 2);
    assert_eq!(&b[8..10], &0x7f00u16.to_le_bytes());
    assert_eq!(
        entities_for_service(category::SKIN, service_type::SK_SKIN, &b),
        vec![(3, 0, 2)]
    );
}

#[test]
fn sensor_service_config_layouts() {
    use icub_eth::entities::boards::{BoardInfo, CanLocation};
    use icub_eth::entities::service::{
        MaisServiceConfig, PosSensorConfig, PosServiceConfig, StrainServiceConfig,
    };
    // eOmn_serv_config_data_as_strain_t: eObrd_info_t (type, fw 3, proto 2) then the CAN
    // location (port:1, addr:4, insideindex:3): CAN2 address 13 -> 1 | 13 << 1 = 0x1B.
    let st = StrainServiceConfig {
        board: BoardInfo {
            board_type: 12,
            firmware: [2, 0, 7],
            protocol: [2, 0],
        },
        can_location: CanLocation {
            port: 1,
            addr: 13,
            inside_index: 0,
        },
    };
    assert_eq!(st.to_bytes(), vec![12, 2, 0, 7, 2, 0, 0x1B]);
    // eOmn_serv_config_data_as_mais_t: version 5 then CAN1 address 14 -> 0x1C.
    let m = MaisServiceConfig {
        version: [1, 0, 0, 1, 0],
        can_location: CanLocation {
            port: 0,
            addr: 14,
            inside_index: 0,
        },
    };
    assert_eq!(m.to_bytes(), vec![1, 0, 0, 1, 0, 0x1C]);
    // eoas_pos_SensorConfig_t: type 0, connector 1, port 2, enabled, rotation 1 (+180):
    // bits 0x0000 | 1 << 4 | 2 << 8 | 1 << 12 | 1 << 14 = 0x5210, then offset -30.
    let s = PosSensorConfig {
        connector: 1,
        port: 2,
        enabled: true,
        rotation: 1,
        offset: -30,
        ..Default::default()
    };
    assert_eq!(s.to_bytes(), vec![0x10, 0x52, 0xE2, 0xFF]);
    let p = PosServiceConfig {
        sensors: [s; 4],
        ..Default::default()
    };
    let b = p.to_bytes();
    assert_eq!(b.len(), 24);
    assert_eq!(&b[8..12], &[0x10, 0x52, 0xE2, 0xFF]);
    assert_eq!(PosServiceConfig::from_bytes(&b).unwrap(), p);
}
