//! `remote_controlboard` over real sockets (run under netns-run): against our
//! `controlBoard_nws_yarp` (udp and tcp streaming), and against raw servers replaying
//! the recorded C++ 3.12 server side, checking every byte our client sends when it opens.

mod controlboard_common;

use controlboard_common::{hex, name_client, read_message, records, run, wait_for};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, UdpSocket};
use yarp_devices::vocabs::{
    CM_POSITION, CM_POSITION_DIRECT, CM_VELOCITY, IM_COMPLIANT, PIDTYPE_POSITION,
};
use yarp_devices::{DeviceDriver, DeviceError, Pid, PolyDriver};
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::Property;

fn open(text: &str) -> PolyDriver {
    PolyDriver::open(&Property::from_config_text(text).unwrap()).expect("open device")
}

fn registered(port: &str) -> bool {
    let ns = name_client();
    let port = port.to_string();
    run(async move { ns.query(&port).await.unwrap().is_some() })
}

fn exercise(remote: &mut PolyDriver) {
    let d = remote.device();
    assert_eq!(d.as_encoders().unwrap().get_axes().unwrap(), 4);
    let q = wait_for("streamed encoders", || {
        d.as_encoders().unwrap().get_encoders().ok()
    });
    assert_eq!(q.len(), 4);
    let (_, t) = d.as_encoders().unwrap().get_encoders_timed().unwrap();
    assert!(t.iter().all(|t| *t > 1.5e9), "{t:?}");

    // position control over RPC, observed through the stream
    let p = d.as_position_control().unwrap();
    p.position_move(1, 30.0).unwrap();
    assert_eq!(p.get_target_position(1).unwrap(), 30.0);
    p.set_ref_speed(0, 10.0).unwrap();
    assert_eq!(p.get_ref_speed(0).unwrap(), 10.0);
    p.position_move_group(&[2, 3], &[11.0, 33.0]).unwrap();
    assert_eq!(p.get_target_positions().unwrap()[2..], [11.0, 33.0]);
    wait_for("joint 1 at 30", || {
        let e = d.as_encoders().unwrap().get_encoder(1).ok()?;
        (e == 30.0).then_some(())
    });

    // streaming commands over command:o
    d.as_control_mode()
        .unwrap()
        .set_control_mode(0, CM_VELOCITY)
        .unwrap();
    wait_for("velocity mode streamed back", || {
        let m = d.as_control_mode().unwrap().get_control_mode(0).ok()?;
        (m == CM_VELOCITY).then_some(())
    });
    d.as_velocity_control()
        .unwrap()
        .velocity_move(0, 5.0)
        .unwrap();
    wait_for("velocity reference", || {
        let v = d.as_velocity_control().unwrap().get_ref_velocity(0).ok()?;
        (v == 5.0).then_some(())
    });
    d.as_velocity_control()
        .unwrap()
        .velocity_moves(&[1.0, 2.0, 3.0, 4.0])
        .unwrap();
    wait_for("velocity references", || {
        let v = d.as_velocity_control().unwrap().get_ref_velocities().ok()?;
        (v == [1.0, 2.0, 3.0, 4.0]).then_some(())
    });
    d.as_torque_control()
        .unwrap()
        .set_ref_torque(1, 1.5)
        .unwrap();
    wait_for("torque reference", || {
        let v = d.as_torque_control().unwrap().get_ref_torque(1).ok()?;
        (v == 1.5).then_some(())
    });
    d.as_control_mode()
        .unwrap()
        .set_control_modes(&[CM_POSITION; 4])
        .unwrap();
    d.as_interaction_mode()
        .unwrap()
        .set_interaction_mode(0, IM_COMPLIANT)
        .unwrap();
    wait_for("interaction mode streamed back", || {
        let m = d
            .as_interaction_mode()
            .unwrap()
            .get_interaction_mode(0)
            .ok()?;
        (m == IM_COMPLIANT).then_some(())
    });

    // the rest of the RPC surface
    assert_eq!(
        d.as_axis_info().unwrap().get_axis_name(0).unwrap(),
        "joint0"
    );
    // the fake, as C++ 3.12.3's, accepts limits and keeps its configured ones
    d.as_control_limits()
        .unwrap()
        .set_limits(0, -90.0, 90.0)
        .unwrap();
    assert_eq!(
        d.as_control_limits().unwrap().get_limits(0).unwrap(),
        (0.0, 100.0)
    );
    let pid = Pid::from_slice(&[1.5, 0.25, 0.125, 100.0, 100.0]);
    let pc = d.as_pid_control().unwrap();
    pc.set_pid(PIDTYPE_POSITION, 0, pid).unwrap();
    assert_eq!(pc.get_pid(PIDTYPE_POSITION, 0).unwrap(), pid);
    pc.enable_pid(PIDTYPE_POSITION, 1).unwrap();
    assert!(pc.is_pid_enabled(PIDTYPE_POSITION, 1).unwrap());
    assert_eq!(
        d.as_motor_encoders()
            .unwrap()
            .get_num_of_motor_encoders()
            .unwrap(),
        4
    );
    assert_eq!(
        d.as_amplifier_control()
            .unwrap()
            .get_amp_statuses()
            .unwrap(),
        [0; 4]
    );
    assert_eq!(d.as_motor().unwrap().get_temperature(0).unwrap(), 37.5);
    assert_eq!(d.as_motor().unwrap().get_number_of_motors().unwrap(), 4);
    assert_eq!(d.as_motor().unwrap().get_gearbox_ratio(1).unwrap(), 0.0);
    let pc = d.as_pid_control().unwrap();
    assert_eq!(pc.get_pid_error(PIDTYPE_POSITION, 0).unwrap(), 0.1);
    assert_eq!(pc.get_pid_output(PIDTYPE_POSITION, 1).unwrap(), 11.1);
    pc.reset_pid(PIDTYPE_POSITION, 0).unwrap();
    assert_eq!(
        d.as_torque_control().unwrap().get_torque_range(0).unwrap(),
        (0.0, 0.0)
    );

    // position direct, current and PWM references over command:o; readings streamed back
    d.as_control_mode()
        .unwrap()
        .set_control_modes(&[CM_POSITION_DIRECT; 4])
        .unwrap();
    // (one command at a time: a message sent while the previous one is in flight is
    // dropped, as in C++ without writeStrict)
    d.as_position_direct()
        .unwrap()
        .set_positions(&[5.0, 6.0, 7.0, 8.0])
        .unwrap();
    wait_for("position-direct references (all)", || {
        let r = d.as_position_direct().unwrap().get_ref_positions().ok()?;
        (r == [5.0, 6.0, 7.0, 8.0]).then_some(())
    });
    d.as_position_direct()
        .unwrap()
        .set_position(0, 1.5)
        .unwrap();
    wait_for("position-direct references", || {
        let r = d.as_position_direct().unwrap().get_ref_positions().ok()?;
        (r == [1.5, 6.0, 7.0, 8.0]).then_some(())
    });
    wait_for("joints at the position-direct references", || {
        let q = d.as_encoders().unwrap().get_encoders().ok()?;
        (q == [1.5, 6.0, 7.0, 8.0]).then_some(())
    });
    assert_eq!(
        d.as_position_direct().unwrap().get_ref_position(1).unwrap(),
        6.0
    );
    d.as_position_direct()
        .unwrap()
        .set_positions_group(&[2], &[9.0])
        .unwrap();
    wait_for("position-direct group", || {
        let r = d
            .as_position_direct()
            .unwrap()
            .get_ref_positions_group(&[2, 3])
            .ok()?;
        (r == [9.0, 8.0]).then_some(())
    });
    d.as_pwm_control()
        .unwrap()
        .set_ref_duty_cycle(1, 10.0)
        .unwrap();
    wait_for("measured duty cycle streamed back", || {
        let v = d.as_pwm_control().unwrap().get_duty_cycle(1).ok()?;
        (v == 10.0).then_some(())
    });
    d.as_current_control()
        .unwrap()
        .set_ref_current(2, 0.5)
        .unwrap();
    wait_for("current reference", || {
        let v = d.as_current_control().unwrap().get_ref_current(2).ok()?;
        (v == 0.5).then_some(())
    });
    // currents follow the reference in the fake (half of it), through stateExt
    wait_for("current streamed back", || {
        let v = d.as_amplifier_control().unwrap().get_current(2).ok()?;
        (v == 0.25).then_some(())
    });
    let me = d.as_motor_encoders().unwrap();
    assert_eq!(me.get_motor_encoder_speeds().unwrap(), [0.0; 4]);
    assert_eq!(me.get_motor_encoder_acceleration(3).unwrap(), 0.0);
    d.as_control_mode()
        .unwrap()
        .set_control_modes(&[CM_POSITION; 4])
        .unwrap();

    // errors: a joint out of range is refused locally or by the server, never a hang
    assert!(matches!(
        d.as_encoders().unwrap().get_encoder(9),
        Err(DeviceError::InvalidJoint { joint: 9, axes: 4 })
    ));
    assert!(d
        .as_position_control()
        .unwrap()
        .position_move(9, 1.0)
        .is_err());
    assert!(d
        .as_position_control()
        .unwrap()
        .position_moves(&[1.0])
        .is_err());
}

#[test]
fn remote_drives_our_wrapper_over_udp() {
    name_client();
    let _server = open(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /srv\nperiod 0.01\n\
         [GENERAL]\njoints 4\n",
    );
    let mut remote = open("device remote_controlboard\nremote /srv\nlocal /cli\n");
    exercise(&mut remote);
    remote.close().unwrap();
    for p in ["/cli/rpc:o", "/cli/command:o", "/cli/stateExt:i"] {
        assert!(!registered(p), "{p} still registered after close");
    }
}

#[test]
fn remote_drives_our_wrapper_over_tcp() {
    name_client();
    let _server = open(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /srvt\nperiod 0.01\n\
         [GENERAL]\njoints 4\n",
    );
    let mut remote = open("device remote_controlboard\nremote /srvt\nlocal /clit\ncarrier tcp\n");
    exercise(&mut remote);
}

/// A wrapper opened before its board is attached (a robot starting up) answers `get axes`
/// with a failure: the open fails, and a second open with the same local ports, once the
/// board is there, succeeds (iKinCartesianSolver's `waitPart` retries so).
#[test]
fn a_retried_open_succeeds_once_the_wrapper_has_its_board() {
    name_client();
    let mut server = open("device controlBoard_nws_yarp\nname /late\nperiod 0.01\n");
    let cfg =
        Property::from_config_text("device remote_controlboard\nremote /late\nlocal /retry\n")
            .unwrap();
    let err = PolyDriver::open(&cfg)
        .err()
        .expect("no board behind the wrapper yet");
    assert!(err.to_string().contains("/late"), "{err}");
    let board =
        yarp_devices::driver::shared(open("device fakeMotionControl\n[GENERAL]\njoints 4\n"));
    server
        .device()
        .as_wrapper()
        .unwrap()
        .attach(board)
        .expect("attach");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(
            PolyDriver::open(&cfg)
                .map(|_| ())
                .map_err(|e| e.to_string()),
        );
    });
    let second = rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("the second open hangs");
    assert!(second.is_ok(), "{second:?}");
}

#[test]
fn open_errors_name_the_parameter() {
    name_client();
    let err = PolyDriver::open(
        &Property::from_config_text("device remote_controlboard\nremote /nobody\nlocal /c\n")
            .unwrap(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(err.contains("`remote`") && err.contains("/nobody"), "{err}");
    // the local ports are released again
    assert!(!registered("/c/rpc:o"));
}

/// Replays the recorded server side of the C++ client's `open` (cb-078) on raw sockets
/// registered as `/proxyfake/...`, and checks every byte our client sends.
#[test]
fn open_sends_the_recorded_cpp_sequence() {
    let Some(recs) = records() else { return };
    let rec = recs
        .iter()
        .find(|r| r["id"] == "cb-078")
        .expect("cb-078")
        .clone();
    let units: Vec<serde_json::Value> = rec["units"].as_array().unwrap().clone();
    let of = |port: &str, dir: &str| -> Vec<serde_json::Value> {
        units
            .iter()
            .filter(|u| u["port"] == port && u["dir"] == dir)
            .cloned()
            .collect()
    };
    let rpc_c2s = of("/proxyfake/rpc:i", "c2s");
    let calls: Vec<serde_json::Value> = recs
        .iter()
        .filter(|r| r["kind"] == "cpp_client" && call_of(r["call"].as_str().unwrap()).is_some())
        .filter(|r| {
            r["units"]
                .as_array()
                .unwrap()
                .iter()
                .any(|u| u["unit"] == "message")
        })
        .cloned()
        .collect();
    let exchanges: Vec<(Vec<u8>, Vec<u8>)> = calls
        .iter()
        .map(|r| {
            let us = r["units"].as_array().unwrap();
            let m = us.iter().find(|u| u["unit"] == "message").unwrap();
            let rep = us.iter().find(|u| u["unit"] == "reply").unwrap();
            let ack = us.iter().find(|u| u["unit"] == "ack").unwrap();
            (
                [hex(&m["port_command_hex"]), hex(&m["payload_hex"])].concat(),
                [hex(&rep["payload_hex"]), hex(&ack["hex"])].concat(),
            )
        })
        .collect();
    let rpc_s2c = of("/proxyfake/rpc:i", "s2c");
    let cmd_c2s = of("/proxyfake/command:i", "c2s");
    let state_units: Vec<serde_json::Value> = units
        .iter()
        .filter(|u| u["port"] == "/proxyfake/stateExt:o")
        .cloned()
        .collect();
    let ns = name_client();
    let listeners = run(async move {
        let mut ls = Vec::new();
        for p in ["rpc:i", "command:i", "stateExt:o"] {
            let l = TcpListener::bind("127.0.0.1:0").await.unwrap();
            let port = l.local_addr().unwrap().port();
            let name = format!("/proxyfake/{p}");
            let req = RegisterRequest::explicit(&name, "tcp", "127.0.0.1", port);
            ns.register_port(&req, &["127.0.0.1"], 1).await.unwrap();
            ls.push(l.into_std().unwrap());
        }
        ls
    });
    let mut ls = listeners.into_iter();
    let (rpc_l, cmd_l, state_l) = (ls.next().unwrap(), ls.next().unwrap(), ls.next().unwrap());
    let server = yarp_devices::runtime::handle().spawn(async move {
        let rpc_l = TcpListener::from_std(rpc_l).unwrap();
        let cmd_l = TcpListener::from_std(cmd_l).unwrap();
        let state_l = TcpListener::from_std(state_l).unwrap();
        let rpc = tokio::spawn(async move {
            let (mut s, _) = rpc_l.accept().await.unwrap();
            let hello = [hex(&rpc_c2s[0]["hex"]), hex(&rpc_c2s[1]["hex"])].concat();
            let mut got = vec![0u8; hello.len()];
            s.read_exact(&mut got).await.unwrap();
            assert_eq!(
                hex::encode(&got),
                hex::encode(&hello),
                "rpc connection header"
            );
            s.write_all(&hex(&rpc_s2c[0]["hex"])).await.unwrap();
            // two requests, each answered with the recorded reply and ack
            for (k, req) in rpc_c2s[2..4].iter().enumerate() {
                let body = read_message(&mut s).await;
                let want = [hex(&req["port_command_hex"]), hex(&req["payload_hex"])].concat();
                assert_eq!(hex::encode(&body), hex::encode(&want), "rpc request {k}");
                let reply = &rpc_s2c[1 + 2 * k];
                let ack = &rpc_s2c[2 + 2 * k];
                s.write_all(&[hex(&reply["payload_hex"]), hex(&ack["hex"])].concat())
                    .await
                    .unwrap();
            }
            // then every recorded API call that used the RPC port, in order
            for (k, (req, reply)) in exchanges.into_iter().enumerate() {
                let body = read_message(&mut s).await;
                assert_eq!(hex::encode(&body), hex::encode(&req), "call {k}");
                s.write_all(&reply).await.unwrap();
            }
            s
        });
        let cmd = tokio::spawn(async move {
            let (mut s, _) = cmd_l.accept().await.unwrap();
            let hello = [hex(&cmd_c2s[0]["hex"]), hex(&cmd_c2s[1]["hex"])].concat();
            let mut got = vec![0u8; hello.len()];
            s.read_exact(&mut got).await.unwrap();
            assert_eq!(
                hex::encode(&got),
                hex::encode(&hello),
                "command:i header (udp)"
            );
            // udp: the header reply names the datagram port
            let udp = UdpSocket::bind("127.0.0.1:0").await.unwrap();
            let port = udp.local_addr().unwrap().port() as i32;
            let mut reply = b"YA".to_vec();
            reply.extend_from_slice(&port.to_le_bytes());
            reply.extend_from_slice(b"RP");
            s.write_all(&reply).await.unwrap();
            (s, udp)
        });
        // two text admin sessions on stateExt:o: [list] [out], then [add]
        for k in 0..2 {
            let (mut s, _) = state_l.accept().await.unwrap();
            let want = hex(&state_units[2 * k]["hex"]);
            let mut got = vec![0u8; want.len()];
            s.read_exact(&mut got).await.unwrap();
            assert_eq!(
                String::from_utf8_lossy(&got),
                String::from_utf8_lossy(&want),
                "admin session {k}"
            );
            s.write_all(&hex(&state_units[2 * k + 1]["hex"]))
                .await
                .unwrap();
        }
        let keep = (cmd.await.unwrap(), rpc.await.unwrap());
        keep
    });
    let mut remote = open("device remote_controlboard\nremote /proxyfake\nlocal /cbcap\n");
    let mut n = 0;
    for r in &calls {
        let name = r["call"].as_str().unwrap();
        let got = call_of(name).unwrap()(remote.device()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let want = r["result_values"].as_str().unwrap_or("");
        match got {
            Out::Nothing => {}
            Out::Nums(v) => {
                let w: Vec<f64> = want
                    .split_whitespace()
                    .map(|x| x.parse().unwrap())
                    .collect();
                assert_eq!(v, w, "{name}");
            }
            Out::Text(t) => assert_eq!(t, want, "{name}"),
        }
        n += 1;
    }
    println!("remote_controlboard: open + {n} recorded RPC calls sent byte-exact");
    let (_cmd, mut rpc) = run(async move { server.await.unwrap() });
    remote.close().unwrap();
    // at close, the rpc connection ends with the `q` port command (as cb-160)
    let close = recs.iter().find(|r| r["id"] == "cb-160").unwrap();
    let q = &close["units"][0];
    let body = run(async move { read_message(&mut rpc).await });
    assert_eq!(
        hex::encode(body),
        format!(
            "{}{}",
            q["port_command_hex"].as_str().unwrap(),
            q["port_command_text_hex"].as_str().unwrap()
        )
    );
}

/// What an API call returned, to compare with the recorded `result_values`.
enum Out {
    Nothing,
    Nums(Vec<f64>),
    Text(String),
}

type Call = fn(&mut dyn DeviceDriver) -> Result<Out, DeviceError>;

/// Our API call for a recorded C++ call (those our interfaces have).
fn call_of(name: &str) -> Option<Call> {
    use Out::*;
    Some(match name {
        "getAxes" => |d| Ok(Nums(vec![d.as_encoders().unwrap().get_axes()? as f64])),
        "resetEncoder(0)" => |d| d.as_encoders().unwrap().reset_encoder(0).map(|_| Nothing),
        "positionMove(all)" => |d| {
            let p = d.as_position_control().unwrap();
            p.position_moves(&[1.0, 2.0, 3.0, 4.0]).map(|_| Nothing)
        },
        // the recorder cut these two names at the first comma
        "positionMove(group" => |d| {
            let p = d.as_position_control().unwrap();
            p.position_move_group(&[1, 3], &[11.0, 33.0])
                .map(|_| Nothing)
        },
        "setRefSpeed(0,10.0)" => |d| {
            let p = d.as_position_control().unwrap();
            p.set_ref_speed(0, 10.0).map(|_| Nothing)
        },
        "getRefSpeed(0)" => |d| {
            Ok(Nums(vec![d
                .as_position_control()
                .unwrap()
                .get_ref_speed(0)?]))
        },
        "getRefSpeeds" => |d| Ok(Nums(d.as_position_control().unwrap().get_ref_speeds()?)),
        "getRefAcceleration(0)" => |d| {
            Ok(Nums(vec![d
                .as_position_control()
                .unwrap()
                .get_ref_acceleration(0)?]))
        },
        "getRefAccelerations" => |d| {
            Ok(Nums(
                d.as_position_control().unwrap().get_ref_accelerations()?,
            ))
        },
        "getTargetPosition(1)" => |d| {
            Ok(Nums(vec![d
                .as_position_control()
                .unwrap()
                .get_target_position(1)?]))
        },
        "getTargetPositions" => |d| {
            Ok(Nums(
                d.as_position_control().unwrap().get_target_positions()?,
            ))
        },
        "stop(all)" => |d| d.as_position_control().unwrap().stops().map(|_| Nothing),
        "getRefVelocity(0)" => |d| {
            Ok(Nums(vec![d
                .as_velocity_control()
                .unwrap()
                .get_ref_velocity(0)?]))
        },
        "getNumberOfMotorEncoders" => |d| {
            let n = d.as_motor_encoders().unwrap().get_num_of_motor_encoders()?;
            Ok(Nums(vec![n as f64]))
        },
        "setControlModes(all" => |d| {
            let c = d.as_control_mode().unwrap();
            c.set_control_modes(&[CM_POSITION; 4]).map(|_| Nothing)
        },
        "setInteractionMode(0,COMPLIANT)" => |d| {
            let i = d.as_interaction_mode().unwrap();
            i.set_interaction_mode(0, IM_COMPLIANT).map(|_| Nothing)
        },
        "getPid(POS,0)" => |d| {
            let p = d.as_pid_control().unwrap().get_pid(PIDTYPE_POSITION, 0)?;
            assert_eq!(p.kp, 1.5);
            Ok(Nothing)
        },
        "setPid(POS,0)" => |d| {
            let pid = Pid::from_slice(&[1.5, 0.25, 0.125, 100.0, 100.0]);
            let p = d.as_pid_control().unwrap();
            p.set_pid(PIDTYPE_POSITION, 0, pid).map(|_| Nothing)
        },
        "enablePid(POS,1)" => |d| {
            d.as_pid_control()
                .unwrap()
                .enable_pid(PIDTYPE_POSITION, 1)
                .map(|_| Nothing)
        },
        "disablePid(POS,1)" => |d| {
            d.as_pid_control()
                .unwrap()
                .disable_pid(PIDTYPE_POSITION, 1)
                .map(|_| Nothing)
        },
        "isPidEnabled(POS,1)" => |d| {
            let e = d
                .as_pid_control()
                .unwrap()
                .is_pid_enabled(PIDTYPE_POSITION, 1)?;
            Ok(Nums(vec![f64::from(u8::from(e))]))
        },
        "setPidReference(POS,0,2.0)" => |d| {
            let p = d.as_pid_control().unwrap();
            p.set_pid_reference(PIDTYPE_POSITION, 0, 2.0)
                .map(|_| Nothing)
        },
        "getPidReference(POS,0)" => |d| {
            let r = d
                .as_pid_control()
                .unwrap()
                .get_pid_reference(PIDTYPE_POSITION, 0)?;
            Ok(Nums(vec![r]))
        },
        "getLimits(0)" => |d| {
            let (a, b) = d.as_control_limits().unwrap().get_limits(0)?;
            Ok(Nums(vec![a, b]))
        },
        "setLimits(0,-90,90)" => |d| {
            d.as_control_limits()
                .unwrap()
                .set_limits(0, -90.0, 90.0)
                .map(|_| Nothing)
        },
        "getAxisName(0)" => |d| Ok(Text(d.as_axis_info().unwrap().get_axis_name(0)?)),
        "getJointType(0)" => |d| {
            let t = d.as_axis_info().unwrap().get_joint_type(0)?;
            Ok(Nums(vec![f64::from(t.0)]))
        },
        "getRefTorque(0)" => |d| {
            Ok(Nums(vec![d
                .as_torque_control()
                .unwrap()
                .get_ref_torque(0)?]))
        },
        "getRefCurrent(0)" => |d| {
            Ok(Nums(vec![d
                .as_current_control()
                .unwrap()
                .get_ref_current(0)?]))
        },
        "enableAmp(0)" => |d| {
            d.as_amplifier_control()
                .unwrap()
                .enable_amp(0)
                .map(|_| Nothing)
        },
        "getAmpStatus(all)" => |d| {
            let s = d.as_amplifier_control().unwrap().get_amp_statuses()?;
            Ok(Nums(s.into_iter().map(f64::from).collect()))
        },
        "getTemperature(0)" => |d| Ok(Nums(vec![d.as_motor().unwrap().get_temperature(0)?])),
        "getPidError(POS,0)" => |d| {
            let p = d.as_pid_control().unwrap();
            Ok(Nums(vec![p.get_pid_error(PIDTYPE_POSITION, 0)?]))
        },
        "getPidOutput(POS,0)" => |d| {
            let p = d.as_pid_control().unwrap();
            Ok(Nums(vec![p.get_pid_output(PIDTYPE_POSITION, 0)?]))
        },
        "resetPid(POS,0)" => |d| {
            let p = d.as_pid_control().unwrap();
            p.reset_pid(PIDTYPE_POSITION, 0).map(|_| Nothing)
        },
        "getTorqueRange(0)" => |d| {
            let (lo, hi) = d.as_torque_control().unwrap().get_torque_range(0)?;
            Ok(Nums(vec![lo, hi]))
        },
        "getNumberOfMotors(pwm)" => |d| {
            let n = d.as_motor().unwrap().get_number_of_motors()?;
            Ok(Nums(vec![n as f64]))
        },
        "getGearboxRatio(0)" => |d| Ok(Nums(vec![d.as_motor().unwrap().get_gearbox_ratio(0)?])),
        _ => return None,
    })
}

/// A wrapper serving a `remote_controlboard` (a relay): its RPC handler waits on the
/// remote's own RPC, which must not stall the device runtime.
#[test]
fn a_wrapper_can_serve_a_remote_board() {
    name_client();
    let _base = open(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /base\nperiod 0.01\n\
         [GENERAL]\njoints 4\n",
    );
    let _relay = open(
        "device controlBoard_nws_yarp\nsubdevice remote_controlboard\nname /relay\n\
         period 0.01\nremote /base\nlocal /relaycli\n",
    );
    let mut far = open("device remote_controlboard\nremote /relay\nlocal /far\n");
    let d = far.device();
    for k in 0..20 {
        assert_eq!(d.as_encoders().unwrap().get_axes().unwrap(), 4);
        let p = d.as_position_control().unwrap();
        p.position_move(0, f64::from(k)).unwrap();
        assert_eq!(p.get_target_position(0).unwrap(), f64::from(k));
    }
    let q = wait_for("state relayed twice", || {
        let q = d.as_encoders().unwrap().get_encoders().ok()?;
        (q[0] == 19.0).then_some(q)
    });
    assert_eq!(q.len(), 4);
}
