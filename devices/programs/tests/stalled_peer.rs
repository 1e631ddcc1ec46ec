//! A robot process whose far peer stalls keeps serving (issue: no wait without a bound).
//! `yarprobotinterface` runs a chain NWS -> NWC -> (NWS -> device in another process):
//! `controlBoard_nws_yarp` `/mid` attached to a `remote_controlboard` of `/far` (a `yarpdev`
//! of its own), and beside it `/other`, a `controlBoard_nws_yarp` of a local fake. The far
//! process is stopped (SIGSTOP) while clients wait on `/mid`: each of those calls ends
//! with an error within the client's RPC timeout, and meanwhile `/other` answers at once
//! and its `state:o` keeps streaming. After SIGCONT `/mid` works again. Run under
//! ../shared/netns-run.

use std::time::{Duration, Instant};
use yarp_interop_tests::{run_fed, Proc, YarpNet, STEP};

fn robot_xml(dir: &std::path::Path) -> std::path::PathBuf {
    let xml = r#"<?xml version="1.0" encoding="UTF-8" ?>
<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">
<robot name="stall" build="1" portprefix="/stall">
<devices>
<device name="far_client" type="remote_controlboard">
  <param name="remote">/far</param>
  <param name="local">/stall/far_client</param>
</device>
<device name="mid_nws" type="controlBoard_nws_yarp">
  <param name="name">/mid</param>
  <param name="period">0.01</param>
  <action phase="startup" level="5" type="attach"><param name="device">far_client</param></action>
  <action phase="shutdown" level="5" type="detach" />
</device>
<device name="other_motor" type="fakeMotionControl" />
<device name="other_nws" type="controlBoard_nws_yarp">
  <param name="name">/other</param>
  <param name="period">0.01</param>
  <action phase="startup" level="5" type="attach"><param name="device">other_motor</param></action>
  <action phase="shutdown" level="5" type="detach" />
</device>
</devices>
</robot>
"#;
    let path = dir.join("stall.xml");
    std::fs::write(&path, xml).expect("robot file");
    path
}

fn signal(pid: u32, sig: &str) {
    let ok = std::process::Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "kill {sig} {pid}");
}

fn rpc_within(net: &YarpNet, port: &str, input: &str, limit: Duration) -> String {
    let mut c = net.yarp();
    c.args(["rpc", port]);
    run_fed("yarp rpc", c, input, limit)
}

#[test]
fn a_stalled_far_peer_stalls_only_the_calls_that_need_it() {
    let net = YarpNet::new();
    let _server = net.server();
    let mut far = Proc::spawn("far yarpdev", {
        let mut c = net.cmd("yarpdev", "yarp-device-programs");
        c.args(["--device", "fakeMotionControl", "--name", "/far"]);
        c
    });
    net.wait_registered("/far/rpc:i");
    let xml = robot_xml(net.dir.path());
    let mut robot = Proc::spawn("yarprobotinterface", {
        let mut c = net.cmd("yarprobotinterface", "yarp-device-programs");
        c.arg("--config").arg(&xml).current_dir(net.dir.path());
        c
    });
    robot.wait_line("running happily", STEP);
    assert!(net
        .rpc("/mid/rpc:i", "get llim 0\n")
        .contains("Response: [is] llim"));
    let mut reader = Proc::spawn("yarp read", {
        let mut c = net.yarp();
        c.args(["read", "/stall/reader", "/other/state:o"]);
        c
    });
    reader.wait_line(".", STEP);

    signal(far.pid(), "-STOP");
    // Three clients wait on /mid, whose device waits on the stopped far end.
    let waiting: Vec<_> = (0..3)
        .map(|_| {
            let mut c = net.yarp();
            c.args(["rpc", "/mid/rpc:i"]);
            std::thread::spawn(move || {
                let t = Instant::now();
                let out = run_fed("yarp rpc /mid", c, "get llim 0\n", Duration::from_secs(40));
                (out, t.elapsed())
            })
        })
        .collect();
    std::thread::sleep(Duration::from_millis(500));
    // Everything else in the process goes on.
    for _ in 0..5 {
        let t = Instant::now();
        let out = rpc_within(&net, "/other/rpc:i", "get axes\n", Duration::from_secs(10));
        assert!(
            out.contains("Response: [is] axes"),
            "/other during the stall: {out}"
        );
        assert!(
            t.elapsed() < Duration::from_secs(3),
            "/other took {:?}",
            t.elapsed()
        );
        let _ = reader.drain();
        reader.wait_line(".", Duration::from_secs(3));
    }
    for w in waiting {
        let (out, took) = w.join().expect("client thread");
        assert!(
            out.contains("Response:"),
            "a call to /mid got no answer: {out}"
        );
        assert!(
            took < Duration::from_secs(35),
            "a call to /mid took {took:?}"
        );
    }

    signal(far.pid(), "-CONT");
    assert!(
        yarp_interop_tests::eventually(STEP, || net
            .rpc("/mid/rpc:i", "get llim 0\n")
            .contains("Response: [is] llim")),
        "/mid after the far end came back"
    );
    far.kill();
}
