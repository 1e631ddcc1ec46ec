//! Property readers against files: includes, directories, search paths, and real iCub
//! configuration files.

// Wrapped in a module so that `cargo test property` selects these tests by name.
mod property {
    use std::fs;
    use std::path::{Path, PathBuf};
    use std::sync::atomic::{AtomicUsize, Ordering};
    use yarp_proto::error::ParseError;
    use yarp_proto::property::ConfigOptions;
    use yarp_proto::{Bottle, Property, Value};

    /// A fresh directory under the system temp dir, removed on drop.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(tag: &str) -> TempDir {
            static COUNTER: AtomicUsize = AtomicUsize::new(0);
            let dir = std::env::temp_dir().join(format!(
                "yarp-proto-property-{tag}-{}-{}",
                std::process::id(),
                COUNTER.fetch_add(1, Ordering::Relaxed)
            ));
            let _ = fs::remove_dir_all(&dir);
            fs::create_dir_all(&dir).expect("create temp dir");
            TempDir(dir)
        }

        fn write(&self, name: &str, content: &str) -> PathBuf {
            let path = self.0.join(name);
            if let Some(parent) = path.parent() {
                fs::create_dir_all(parent).expect("create parent dir");
            }
            fs::write(&path, content).expect("write test file");
            path
        }

        fn path(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    fn opts() -> ConfigOptions {
        ConfigOptions::new().process_env(false)
    }

    fn load(path: &Path) -> Property {
        match Property::from_config_file_with(path, &opts()) {
            Ok(p) => p,
            Err(e) => panic!("{}: {e}", path.display()),
        }
    }

    fn int(v: Option<&Value>) -> Option<i64> {
        v.and_then(Value::as_i64)
    }

    fn text(v: Option<&Value>) -> String {
        v.map(|v| String::from_utf8_lossy(&v.to_text_bare()).into_owned())
            .unwrap_or_default()
    }

    fn sub<'a>(p: &'a Property, group: &str, key: &str) -> Option<&'a Value> {
        p.find_group(group).and_then(|g| g.find(key))
    }

    #[test]
    fn include_at_top_level() {
        let d = TempDir::new("inc");
        d.write("one.ini", "x 1\n");
        let root = d.write("root.ini", "[include one.ini]\ny 2\n");
        let p = load(&root);
        assert_eq!(int(p.find("x")), Some(1));
        assert_eq!(int(p.find("y")), Some(2));
    }

    #[test]
    fn include_into_section() {
        let d = TempDir::new("incsec");
        d.write("one.ini", "x 1\n");
        let root = d.write("root.ini", "[include base one.ini]\ny 2\n");
        let p = load(&root);
        assert_eq!(int(sub(&p, "base", "x")), Some(1));
        assert_eq!(
            int(p.find("y")),
            Some(2),
            "lines after an include are top level"
        );
        assert_eq!(
            p.find_group("base").map(|g| g.to_string()),
            Some("base (x 1)".into())
        );

        // earlier content of the section is kept and merged
        let root = d.write(
            "root2.ini",
            "[base]\nw 4\n[base]\nz 3\n[include base one.ini]\ny 2\n",
        );
        let p = load(&root);
        assert_eq!(int(sub(&p, "base", "x")), Some(1));
        assert_eq!(int(sub(&p, "base", "z")), Some(3));
        assert_eq!(int(sub(&p, "base", "w")), Some(4));
        assert_eq!(int(p.find("y")), Some(2));
    }

    #[test]
    fn include_with_list() {
        let d = TempDir::new("inclist");
        d.write("one.ini", "x 1\n");
        let root = d.write(
            "root.ini",
            "[b1]\nz 3\n[include base b1 one.ini]\n[include base b2 one.ini]\ny 2\n",
        );
        let p = load(&root);
        assert_eq!(int(sub(&p, "b1", "x")), Some(1));
        assert_eq!(int(sub(&p, "b1", "z")), Some(3));
        assert_eq!(int(sub(&p, "b2", "x")), Some(1));
        assert_eq!(
            p.find_group("base").map(|g| g.to_string()),
            Some("base b1 b2".into())
        );
    }

    #[test]
    fn included_sections_and_following_groups() {
        // C++ regression for robotology/yarp#459
        let d = TempDir::new("i459");
        d.write(
            "one.ini",
            "[include_one]\nincl_param1   red\nincl_param2   green\nincl_param3   blue\n",
        );
        d.write(
            "two.ini",
            "[include_two]\nincl2_paramA   car\nincl2_paramB   table\n",
        );
        let root = d.write(
            "root.ini",
            "[include \"one.ini\"]\n   \n[include \"two.ini\"]  \n[root_group]   \n\
             ciao hello\nbau 10\n\n[end_group]\nlili  lolo\ncici  bubu\n",
        );
        let check = d.write(
            "check.ini",
            "[include \"one.ini\"]\n\n[root_group]\nciao hello\nbau 10\n\n\
             [include \"two.ini\"]  \n\n[end_group]\nlili  lolo\ncici  bubu\n",
        );
        for file in [root, check] {
            let p = load(&file);
            assert_eq!(int(sub(&p, "root_group", "bau")), Some(10), "{p}");
            assert_eq!(text(sub(&p, "include_one", "incl_param2")), "green");
            assert_eq!(text(sub(&p, "include_two", "incl2_paramB")), "table");
            assert_eq!(text(sub(&p, "end_group", "cici")), "bubu");
        }
    }

    #[test]
    fn includes_resolve_against_the_including_file() {
        let d = TempDir::new("relpath");
        d.write("conf/sub/leaf.ini", "leaf yes\n");
        d.write("conf/mid.ini", "[include sub/leaf.ini]\nmid yes\n");
        // found through the root's directory, which joins CONFIG_PATH
        d.write("conf/root.ini", "[include mid.ini]\nroot yes\n");
        let p = load(&d.path().join("conf/root.ini"));
        assert_eq!(p.to_string(), "(leaf yes) (mid yes) (root yes)");

        // CONFIG_PATH given by the caller
        let other = TempDir::new("relpath2");
        let root = other.write("root.ini", "[include mid.ini]\n");
        let options = opts().search_path(d.path().join("conf"));
        let p = Property::from_config_file_with(&root, &options).expect("load with search path");
        assert!(p.check("mid") && p.check("leaf"), "{p}");
    }

    #[test]
    fn variables_from_earlier_keys_and_options() {
        let d = TempDir::new("vars");
        d.write("part.ini", "robot $robot\nport /${robot}/${part}\n");
        let root = d.write("root.ini", "robot icub\n[include part.ini]\n");
        let options = opts().var("part", "left_arm");
        let p = Property::from_config_file_with(&root, &options).expect("load");
        assert_eq!(text(p.find("port")), "/icub/left_arm");
        assert_eq!(text(p.find("robot")), "icub");
    }

    #[test]
    fn missing_include_is_an_error_naming_the_line() {
        let d = TempDir::new("missing");
        let root = d.write("root.ini", "a 1\n\n[include nowhere.ini]\nb 2\n");
        match Property::from_config_file_with(&root, &opts()) {
            Err(ParseError::Include { line: 3, path, .. }) => assert_eq!(path, "nowhere.ini"),
            other => panic!("expected include error at line 3, got {other:?}"),
        }
        match Property::from_config_file_with(d.path().join("absent.ini"), &opts()) {
            Err(ParseError::Include { line: 0, .. }) => {}
            other => panic!("expected include error at line 0, got {other:?}"),
        }
        // an error inside an included file is reported through the include line
        d.write("bad.ini", "ok 1\nbroken \"quote\n");
        let root = d.write("root2.ini", "[include bad.ini]\n");
        match Property::from_config_file_with(&root, &opts()) {
            Err(ParseError::Include {
                line: 1, reason, ..
            }) => {
                assert!(reason.contains("line 2"), "{reason}")
            }
            other => panic!("expected include error, got {other:?}"),
        }
    }

    #[test]
    fn include_cycles_and_depth_are_bounded() {
        let d = TempDir::new("cycle");
        let me = d.write("self.ini", "a 1\n[include self.ini]\n");
        let e = Property::from_config_file_with(&me, &opts());
        assert!(
            matches!(e, Err(ParseError::Include { ref reason, .. }) if reason.contains("cycle")),
            "{e:?}"
        );
        d.write("ping.ini", "[include pong.ini]\n");
        let pong = d.write("pong.ini", "[include sec ping.ini]\n");
        assert!(Property::from_config_file_with(&pong, &opts()).is_err());

        // a long chain of distinct files hits the depth limit
        let n = yarp_proto::property::MAX_INCLUDE_DEPTH + 2;
        for i in 0..n {
            d.write(
                &format!("chain{i}.ini"),
                &format!("k{i} {i}\n[include chain{}.ini]\n", i + 1),
            );
        }
        d.write(&format!("chain{n}.ini"), "end 1\n");
        let e = Property::from_config_file_with(d.path().join("chain0.ini"), &opts());
        assert!(
            matches!(e, Err(ParseError::Include { ref reason, .. }) if reason.contains("deeper")),
            "{e:?}"
        );
        // a short chain is fine
        let p = load(&d.path().join(format!("chain{}.ini", n - 3)));
        assert!(p.check("end"));
    }

    #[test]
    fn directory_scanning() {
        let d = TempDir::new("dir");
        d.write("t1.ini", "x 3\n[nesttest]\nz 14\n");
        d.write("t2.ini", "y 4\n");
        d.write("skip.txt", "w 5\n");
        let p = load(d.path());
        assert_eq!(int(p.find("x")), Some(3));
        assert_eq!(int(p.find("y")), Some(4), "t2's keys are top level again");
        assert_eq!(int(sub(&p, "nesttest", "z")), Some(14));
        assert!(!p.check("w"));

        let p = Property::from_config_dir(d.path(), "files").expect("config dir");
        let files = p.find_group("files").expect("file list");
        assert_eq!(files.len(), 3, "{p}");
        let first = text(files.get(1));
        assert!(first.ends_with("/t1.ini"), "{first}");
        assert_eq!(int(sub(&p, &first, "x")), Some(3));
    }

    #[test]
    fn command_line_overrides_config() {
        let mut p =
            Property::from_config_text_with("period 10\nname base\n[arm]\ngain 1\n", &opts())
                .expect("config");
        p.merge_args(["--period", "20", "--arm::gain", "5"]);
        assert_eq!(int(p.find("period")), Some(20));
        assert_eq!(text(p.find("name")), "base");
        assert_eq!(int(sub(&p, "arm", "gain")), Some(5));
    }

    // ---- real iCub configuration --------------------------------------------------------------

    fn icub_dir() -> PathBuf {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/robots-configuration/iCubGenova01");
        assert!(
            dir.is_dir(),
            "iCub configuration directory missing: {} (the tests need /work/shared/robots-configuration)",
            dir.display()
        );
        dir
    }

    fn list_len(v: Option<&Value>) -> Option<usize> {
        v.and_then(Value::as_list).map(Bottle::len)
    }

    #[test]
    fn icub_eyes_calibration() {
        let p = load(&icub_dir().join("icubEyes.ini"));
        let left = p
            .find_group("CAMERA_CALIBRATION_LEFT")
            .expect("left camera");
        assert_eq!(left.find("fx"), Some(&Value::Float64(234.88)));
        assert_eq!(left.find("w"), Some(&Value::Int32(320)));
        assert_eq!(
            left.find("projection").and_then(Value::as_str),
            Some("pinhole")
        );
        assert_eq!(
            sub(&p, "CAMERA_CALIBRATION_RIGHT", "k1"),
            Some(&Value::Float64(-0.425792))
        );
        assert_eq!(
            int(sub(&p, "STEREO_CALIBRATION_CONFIGURATION", "numberOfPairs")),
            Some(30)
        );
        let disparity = p.find_group("STEREO_DISPARITY").expect("disparity");
        assert_eq!(list_len(disparity.find("HN")), Some(16));
        assert_eq!(
            list_len(disparity.find("QL")),
            Some(8),
            "tabs separate list items"
        );

        let p = load(&icub_dir().join("iKinGazeCtrl.ini"));
        assert_eq!(text(p.find("head_version")), "v2.0");
        assert_eq!(text(sub(&p, "cameras", "context")), "cameraCalibration");
        assert_eq!(text(sub(&p, "cameras", "file")), "icubEyes.ini");
        assert_eq!(text(sub(&p, "imu", "source_port_name")), "/imuFilter");
    }

    #[test]
    fn icub_skin_manager_continued_lines() {
        let p = load(&icub_dir().join("skinManAll.ini"));
        let inputs = p
            .find("inputPorts")
            .and_then(Value::as_list)
            .expect("inputPorts");
        assert_eq!(inputs.len(), 7, "{inputs}");
        assert_eq!(text(inputs.get(0)), "/icub/skin/left_hand");
        assert_eq!(text(inputs.get(6)), "/icub/skin/torso");
        assert_eq!(list_len(p.find("outputPorts")), Some(7));
        assert_eq!(int(p.find("period")), Some(20));
        assert_eq!(
            p.find("zeroUpRawData").and_then(Value::as_bool),
            Some(false)
        );
        assert_eq!(p.find("compensationGain"), Some(&Value::Float64(0.2)));
        let events = p.find_group("SKIN_EVENTS").expect("SKIN_EVENTS");
        assert_eq!(list_len(events.find("skinParts")), Some(7));
        assert_eq!(list_len(events.find("taxelPositionFiles")), Some(7));
        assert_eq!(events.find("maxNeighborDist"), Some(&Value::Float64(0.015)));
        // `%` starts no comment in YARP: C++ keeps those lines as groups keyed "%"
        assert!(events.check("%"));
    }

    #[test]
    fn icub_cartesian_solver_sections() {
        let p = load(&icub_dir().join("cartesianSolver.ini"));
        assert_eq!(p.keys().count(), 4, "{p}");
        assert_eq!(list_len(sub(&p, "left_arm", "dof")), Some(10));
        assert_eq!(text(sub(&p, "right_leg", "type")), "right");
        assert_eq!(sub(&p, "right_arm", "tol"), Some(&Value::Float64(0.001)));
        assert_eq!(
            text(sub(&p, "left_arm", "name")),
            "cartesianSolver/left_arm"
        );
    }

    #[test]
    fn icub_hash_comments_and_repeated_keys() {
        let dir = icub_dir();
        let p = load(&dir.join("pf3dTracker.ini"));
        assert_eq!(text(p.find("name")), "/pf3dTracker");
        assert_eq!(int(p.find("nParticles")), Some(700));
        assert_eq!(int(p.find("accelStDev")), Some(30));
        assert_eq!(
            text(p.find("saveImagesWithOpencvDir")),
            "./graphical_results/"
        );
        assert!(!p.check("#") && !p.check("#nParticles"));

        let p = load(&dir.join("firmwareupdater.ini"));
        let drivers = p.find_group("DRIVERS").expect("DRIVERS");
        assert_eq!(drivers.len(), 11, "repeated keys in a section are all kept");
        assert_eq!(text(drivers.find("CFW2")), "0", "find sees the first");

        let p = load(&dir.join("camera/dragonfly2_config_left_bayer_320_240.ini"));
        assert_eq!(text(p.find("guid")), "00b09d01009b56fe");
        assert!(p.check("stamp") && p.find("stamp").is_none());
        assert_eq!(p.find_group("white_balance").map(Bottle::len), Some(3));
    }

    #[test]
    fn every_icub_ini_file_loads() {
        let mut stack = vec![icub_dir()];
        let mut count = 0;
        while let Some(dir) = stack.pop() {
            for entry in fs::read_dir(&dir).expect("read dir") {
                let path = entry.expect("dir entry").path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "ini") {
                    let p = load(&path);
                    assert!(!p.is_empty(), "{} read as empty", path.display());
                    // printing and reading back gives the same Property
                    assert_eq!(Property::from_text(p.to_text()), p, "{}", path.display());
                    count += 1;
                }
            }
        }
        assert!(count >= 10, "only {count} .ini files found");
    }
}
