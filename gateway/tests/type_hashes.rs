//! The gateway's REP-2016 hashes against rclpy's: every catalog type against the
//! `type_hashes` the wheels ship, and a few against what rclpy reports for its own live
//! endpoints. Domain indices used here: 0, 1, 4, 5.

mod common;

use yarp_ros2_gateway::{hash::rihs01, interfaces, types::MESSAGES};

/// The project's copy of a definition as `venv`'s distro ships it, where that release
/// differs from the built-in one (`gateway/msg/<distro>/`: Jazzy's control_msgs).
fn distro_release(venv: &common::Distro, pkg: &str, kind: &str, name: &str) -> std::path::PathBuf {
    common::gateway_dir().join(format!("msg/{}/{pkg}/{kind}/{name}.{kind}", venv.name))
}

#[test]
fn every_catalog_type_matches_the_installed_type_descriptions() {
    for d in common::distros("every_catalog_type_matches_the_installed_type_descriptions") {
        every_catalog_type_matches_the_installed_type_descriptions_on(&d);
    }
}

fn every_catalog_type_matches_the_installed_type_descriptions_on(venv: &common::Distro) {
    let (mut checked, mut absent) = (0, std::collections::BTreeSet::new());
    for t in MESSAGES {
        // `pkg/srv/Name_Request` lives in `share/pkg/srv/Name.json`.
        let (pkg, kind, name) = yarp_ros2_gateway::types::split_name(t.name).unwrap();
        // Packages with no PyPI wheel (yarp_control_msgs) are checked by their own tests.
        if !venv.join(format!("share/{pkg}")).is_dir() {
            absent.insert(pkg);
            continue;
        }
        let file_stem = name.split('_').next().unwrap();
        // Another release in this distro (Jazzy's control_msgs): checked with every
        // installed definition.
        if distro_release(venv, pkg, kind, file_stem).exists() {
            continue;
        }
        let path = venv.join(format!("share/{pkg}/{kind}/{file_stem}.json"));
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let want = json["type_hashes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|h| h["type_name"] == t.name)
            .unwrap_or_else(|| panic!("{} not in {}", t.name, path.display()))["hash_string"]
            .as_str()
            .unwrap()
            .to_string();
        assert_eq!(rihs01(t.name).unwrap(), want, "{}", t.name);
        checked += 1;
    }
    eprintln!(
        "[{}] {checked} catalog types checked; not installed: {absent:?}",
        venv.name
    );
    assert!(checked > 40, "{checked}");
}

/// Every built-in definition (`gateway/msg/`) is the one the wheels install (same
/// structures once parsed, defaults and constants included) and each of its structures
/// hashes as rosidl's `.json` beside it says; yarp_control_msgs, which has no wheel, is
/// checked against rosidl by gateway/ros2-devices/tests/type_hashes.rs.
#[test]
fn every_built_in_definition_is_the_installed_one() {
    for d in common::distros("every_built_in_definition_is_the_installed_one") {
        every_built_in_definition_is_the_installed_one_on(&d);
    }
}

fn every_built_in_definition_is_the_installed_one_on(venv: &common::Distro) {
    use yarp_ros2_gateway::types::{parse_definition, DEFINITIONS};
    let (mut same, mut hashed, mut unchecked) = (0, 0, std::collections::BTreeSet::new());
    for &def in DEFINITIONS {
        let (pkg, kind, name, _) = def;
        let structures = parse_definition(def).unwrap();
        let file = venv.join(format!("share/{pkg}/{kind}/{name}.{kind}"));
        // A distro that ships another release of the package (Jazzy's control_msgs): the
        // installed file is the project's copy of that release; its hashes are checked
        // with every installed definition's.
        let variant = distro_release(venv, pkg, kind, name);
        if let Ok(ours) = std::fs::read_to_string(&variant) {
            let text = std::fs::read_to_string(&file).unwrap();
            assert_eq!(
                parse_definition((pkg, kind, name, &ours)).unwrap(),
                parse_definition((pkg, kind, name, &text)).unwrap(),
                "{}",
                file.display()
            );
            same += 1;
            continue;
        }
        if let Ok(text) = std::fs::read_to_string(&file) {
            let installed = parse_definition((pkg, kind, name, &text)).unwrap();
            assert_eq!(structures, installed, "{}", file.display());
            same += 1;
        }
        let Ok(text) = std::fs::read_to_string(file.with_extension("json")) else {
            unchecked.insert(pkg);
            continue;
        };
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        for s in &structures {
            let want = json["type_hashes"]
                .as_array()
                .unwrap()
                .iter()
                .find(|h| h["type_name"] == s.name.as_str())
                .unwrap_or_else(|| panic!("{} not in {}", s.name, file.display()))["hash_string"]
                .as_str()
                .unwrap();
            assert_eq!(rihs01(&s.name).unwrap(), want, "{}", s.name);
            hashed += 1;
        }
    }
    eprintln!(
        "[{}] {same} built-in definitions as installed, {hashed} structures hashed as rosidl",
        venv.name
    );
    assert_eq!(
        unchecked.into_iter().collect::<Vec<_>>(),
        ["yarp_control_msgs"]
    );
    // all but tf2_msgs (no wheel; only its hashes are generated into the venv) and
    // yarp_control_msgs
    assert_eq!(same, DEFINITIONS.len() - 10);
}

/// Every message, service and action definition the wheels install
/// (`share/<pkg>/msg/*.msg`, `srv/*.srv`, `action/*.action`; nav_msgs, visualization_msgs
/// and test_msgs' Fibonacci among them), read at run time, hashes as rosidl hashed it
/// (the `type_hashes` of the `.json` beside each file), every structure rosidl derives
/// from an action included.
#[test]
fn every_installed_definition_hashes_as_rosidl() {
    for d in common::distros("every_installed_definition_hashes_as_rosidl") {
        every_installed_definition_hashes_as_rosidl_on(&d);
    }
}

fn every_installed_definition_hashes_as_rosidl_on(venv: &common::Distro) {
    assert!(interfaces::add_dir(venv) > 100, "{}", venv.display());
    let (mut checked, mut mismatched, mut actions) = (0, Vec::new(), 0);
    let share = venv.join("share");
    for pkg in std::fs::read_dir(&share).unwrap().flatten() {
        for kind in ["msg", "srv", "action"] {
            let Ok(files) = std::fs::read_dir(pkg.path().join(kind)) else {
                continue;
            };
            for f in files.flatten() {
                let p = f.path();
                if p.extension().is_none_or(|e| e != "json") || !p.with_extension(kind).exists() {
                    continue;
                }
                let json: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
                for h in json["type_hashes"].as_array().unwrap() {
                    let name = h["type_name"].as_str().unwrap();
                    if !name.contains(&format!("/{kind}/")) {
                        continue; // a referenced type of another kind
                    }
                    let got = interfaces::lookup(name)
                        .map(|_| rihs01(name).unwrap_or_else(|e| e.to_string()))
                        .unwrap_or_else(|| {
                            format!("no definition: {:?}", interfaces::problem(name))
                        });
                    if got != h["hash_string"].as_str().unwrap() {
                        mismatched.push(format!("{name}: {got}"));
                    }
                    checked += 1;
                    actions += usize::from(kind == "action");
                }
            }
        }
    }
    assert!(mismatched.is_empty(), "{mismatched:#?}");
    for t in ["nav_msgs/msg/Odometry", "visualization_msgs/msg/Marker"] {
        assert!(
            interfaces::lookup(t).is_some(),
            "{t} not installed in {}",
            venv.display()
        );
    }
    eprintln!(
        "[{}] {checked} installed types hash as rosidl ({actions} of actions)",
        venv.name
    );
    assert!(checked > 150, "{checked}");
    // test_msgs' Fibonacci and NestedMessage: 13 structures each.
    assert!(actions >= 26, "{actions} action structures checked");
}

/// The `.idl` files rosidl generated from every installed `.msg`/`.srv` describe the same
/// structures as those, read by the gateway's IDL reader (the one used for packages that
/// ship `.idl` only): same fields, types, shapes, bounds and constants, so same hashes.
#[test]
fn every_installed_idl_reads_as_its_msg() {
    for d in common::distros("every_installed_idl_reads_as_its_msg") {
        every_installed_idl_reads_as_its_msg_on(&d);
    }
}

fn every_installed_idl_reads_as_its_msg_on(venv: &common::Distro) {
    use yarp_ros2_gateway::{idl, msgdef};
    let mut checked = 0;
    for pkg in std::fs::read_dir(venv.join("share")).unwrap().flatten() {
        let name = pkg.file_name().to_string_lossy().into_owned();
        for kind in ["msg", "srv"] {
            let Ok(files) = std::fs::read_dir(pkg.path().join(kind)) else {
                continue;
            };
            for f in files.flatten() {
                let p = f.path();
                let def = p.with_extension(kind);
                if p.extension().is_none_or(|e| e != "idl") || !def.exists() {
                    continue;
                }
                let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
                let text = std::fs::read_to_string(&def).unwrap();
                let mut want = if kind == "msg" {
                    vec![msgdef::parse_msg(&name, &stem, &text).unwrap()]
                } else {
                    msgdef::parse_srv(&name, &stem, &text).unwrap()
                };
                let mut got = idl::parse(&std::fs::read_to_string(&p).unwrap())
                    .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
                // Defaults are written differently (`FALSE`, `false`); compare the rest.
                for d in want.iter_mut().chain(got.iter_mut()) {
                    d.fields.iter_mut().for_each(|f| f.default = None);
                    d.constants.iter_mut().for_each(|c| c.value.clear());
                }
                assert_eq!(got, want, "{}", p.display());
                checked += 1;
            }
        }
    }
    eprintln!(
        "[{}] {checked} .idl files read as their .msg/.srv",
        venv.name
    );
    assert!(checked > 100, "{checked}");
}

#[test]
fn rclpy_reports_the_same_hash_for_its_own_endpoints() {
    for d in common::distros("rclpy_reports_the_same_hash_for_its_own_endpoints") {
        rclpy_reports_the_same_hash_for_its_own_endpoints_on(&d);
    }
}

fn rclpy_reports_the_same_hash_for_its_own_endpoints_on(venv: &common::Distro) {
    for (i, ty) in ["geometry_msgs/msg/Twist", "sensor_msgs/msg/JointState"]
        .into_iter()
        .enumerate()
    {
        let peer = common::Peer::start(venv, venv.domain(i as u16), &["hash", ty]);
        assert_eq!(peer.expect("HASH", common::T), rihs01(ty).unwrap(), "{ty}");
        assert!(peer.finish(common::T));
    }
}

/// What rclpy reports for the gateway's own endpoints: `(pubs, subs)` JSON of one topic.
async fn gateway_endpoints_seen_by_rclpy(
    venv: &common::Distro,
    index: u16,
) -> (serde_json::Value, String) {
    let domain = venv.domain(index);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "twist"
direction = "both"
yarp_port = "/gw/twist"
ros_topic = "/gw_twist"
ros_type = "geometry_msgs/msg/Twist"
"#,
        &ns,
        domain,
    )
    .await;
    let peer = common::Peer::start(
        venv,
        domain,
        &[
            "info",
            "/gw_twist",
            "--pubs",
            "1",
            "--subs",
            "1",
            "--named",
            "--timeout",
            "10",
        ],
    );
    let info: serde_json::Value =
        serde_json::from_str(&peer.expect_async("INFO", common::T).await).unwrap();
    assert!(peer.finish(common::T));
    gw.shutdown().await;
    stop.shutdown();
    (info, rihs01("geometry_msgs/msg/Twist").unwrap())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rclpy_discovers_the_gateway_endpoints_with_their_types() {
    for d in common::distros("rclpy_discovers_the_gateway_endpoints_with_their_types") {
        let (info, want) = gateway_endpoints_seen_by_rclpy(&d, 4).await;
        for side in ["pubs", "subs"] {
            let e = &info[side][0];
            assert_eq!(e["type"], "geometry_msgs/msg/Twist", "{info}");
            assert_eq!(e["node"], "yarp_ros2_gateway", "{info}");
            eprintln!(
                "[{}] rclpy sees the gateway's {side} with {} (correct: {want})",
                d.name, e["hash"]
            );
        }
    }
}

/// The acceptance check for REP-2016 hashes on the wire: rclpy reads `typehash=…;` from
/// the USER_DATA the gateway's endpoints announce (third_party/README.md), for topics in
/// both directions and for both service directions (a service's request and reply topics
/// carry the hash of the service type, as rmw announces them).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rclpy_sees_the_correct_type_hash_on_gateway_endpoints() {
    for d in common::distros("rclpy_sees_the_correct_type_hash_on_gateway_endpoints") {
        rclpy_sees_the_correct_type_hash_on_gateway_endpoints_on(&d).await;
    }
}

async fn rclpy_sees_the_correct_type_hash_on_gateway_endpoints_on(venv: &common::Distro) {
    let domain = venv.domain(5);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "text"
direction = "yarp_to_ros"
yarp_port = "/gw/text:i"
ros_topic = "/h/text"
ros_type = "std_msgs/msg/String"

[[topic]]
name = "array"
direction = "ros_to_yarp"
yarp_port = "/gw/array:o"
ros_topic = "/h/array"
ros_type = "std_msgs/msg/Float64MultiArray"

[[topic]]
name = "twist"
direction = "both"
yarp_port = "/gw/twist"
ros_topic = "/h/twist"
ros_type = "geometry_msgs/msg/Twist"

[[topic]]
name = "flag"
direction = "ros_to_yarp"
yarp_port = "/gw/flag:o"
ros_topic = "/h/flag"
ros_type = "std_msgs/msg/Bool"

[[service]]
name = "home"
direction = "ros_to_yarp"
yarp_port = "/test/arm/rpc:i"
ros_service = "/h/home"
ros_type = "std_srvs/srv/Trigger"
command = "[home]"

[[service]]
name = "motors"
direction = "yarp_to_ros"
yarp_port = "/gw/motors:rpc"
ros_service = "/h/motors"
ros_type = "std_srvs/srv/SetBool"
"#,
        &ns,
        domain,
    )
    .await;
    let want = [
        ("/h/text", "std_msgs/msg/String"),
        ("/h/array", "std_msgs/msg/Float64MultiArray"),
        ("/h/twist", "geometry_msgs/msg/Twist"),
        ("/h/flag", "std_msgs/msg/Bool"),
        ("rq/h/homeRequest", "std_srvs/srv/Trigger"),
        ("rr/h/homeReply", "std_srvs/srv/Trigger"),
        ("rq/h/motorsRequest", "std_srvs/srv/SetBool"),
        ("rr/h/motorsReply", "std_srvs/srv/SetBool"),
    ];
    let mut args = vec!["info_many"];
    args.extend(want.iter().map(|(topic, _)| *topic));
    args.extend(["--timeout", "15"]);
    let peer = common::Peer::start(venv, domain, &args);
    let info: serde_json::Value =
        serde_json::from_str(&peer.expect_async("INFO", common::T).await).unwrap();
    assert!(peer.finish(common::T));
    gw.shutdown().await;
    stop.shutdown();
    let mut checked = 0;
    for (topic, ty) in want {
        let hash = rihs01(ty).unwrap();
        let endpoints = info[topic].as_array().cloned().unwrap_or_default();
        assert!(
            !endpoints.is_empty(),
            "rclpy found no endpoint on {topic}: {info}"
        );
        for e in endpoints {
            assert_eq!(e["node"], "yarp_ros2_gateway", "{topic}: {e}");
            let got = e["hash"].as_str().unwrap_or_default();
            assert!(
                got.contains(&hash[7..]),
                "{topic}: rclpy sees {got}, want {hash}"
            );
            checked += 1;
        }
    }
    // Topics in both directions, and each service's request and reply.
    assert!(checked > want.len(), "{info}");
}
