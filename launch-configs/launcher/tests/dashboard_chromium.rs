//! The dashboard in a real browser: headless Chromium (Debian `chromium`, installed by
//! `tests/peers/install-chromium.sh`) loads the page of a running `yarp-launch demo.toml`,
//! takes a screenshot (checked to be a non-blank PNG) and dumps the DOM (checked to hold
//! the port graph's nodes and edge, and a drawn plot). Skips loudly without Chromium.

mod common;

use common::browser::{check_not_blank, chromium, run_chromium};
use common::*;
use std::path::PathBuf;
use std::time::Duration;

/// Runs `config` with a dashboard, waits for plot samples, then checks a screenshot
/// (saved as `<CARGO_TARGET_TMPDIR>/<shot>.png`) and that the DOM holds every needle.
fn check_dashboard(config: &str, extra: &[&str], up_line: &str, shot: &str, needles: &[&str]) {
    let Some(browser) = chromium() else { return };
    let mut args = vec!["--dashboard", "127.0.0.1:0"];
    args.extend_from_slice(extra);
    let mut l = Launch::start(&configs_dir().join(config), &args);
    let url = l.dashboard_url();
    l.wait_line(up_line, Duration::from_secs(60));
    // Let the plot gather samples before the browser looks.
    let ok = eventually(Duration::from_secs(15), || {
        let p = get_json(&format!("{url}api/plot"));
        (p["t"].as_array().map_or(0, Vec::len) >= 20).then_some(())
    });
    assert!(ok.is_some(), "no plot samples");

    let work = tempfile::tempdir().unwrap();
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let png_path = tmp.join(format!("{shot}.png"));
    let _ = std::fs::remove_file(&png_path);
    run_chromium(
        &browser,
        &work.path().join("profile1"),
        &[format!("--screenshot={}", png_path.display()), url.clone()],
        Duration::from_secs(60),
    );
    let (w, h, colours, share) = check_not_blank(&png_path);
    eprintln!(
        "screenshot {}: {w}x{h}, {colours} colours, {:.1}% non-background",
        png_path.display(),
        share * 100.0
    );
    assert_eq!((w, h), (1280, 900));
    assert!(colours >= 20, "only {colours} colours: blank page?");
    assert!(share > 0.05, "only {:.1}% non-background", share * 100.0);

    let dom = run_chromium(
        &browser,
        &work.path().join("profile2"),
        &["--dump-dom".to_string(), url.clone()],
        Duration::from_secs(60),
    );
    std::fs::write(tmp.join(format!("{shot}.html")), &dom).ok();
    for needle in [
        r#"id="port-graph""#,
        r#"id="joint-plot""#,
        r#"class="series""#,
    ]
    .iter()
    .chain(needles)
    {
        assert!(dom.contains(needle), "DOM lacks {needle}:\n{dom}");
    }
    assert_eq!(l.stop(Signal::SIGTERM, Duration::from_secs(40)), Some(0));
}

#[test]
fn dashboard_renders_graph_and_plot_in_headless_chromium() {
    check_dashboard(
        "demo.toml",
        &[],
        "demo is up in",
        "dashboard-demo",
        &[
            r#"data-port="/demo/writer""#,
            r#"data-port="/demo/reader""#,
            r#"data-from="/demo/writer" data-to="/demo/reader" data-carrier="tcp""#,
            "<td>writer</td>",
        ],
    );
}

#[test]
fn dashboard_shows_arm_camera_and_bridge_of_fake_devices() {
    // A ROS domain of its own (201..=230): other tests run DDS in this namespace.
    let domain = (201 + std::process::id() % 30).to_string();
    check_dashboard(
        "fake-devices.toml",
        &[
            "--set",
            &format!("module.gateway.env={{ NO_COLOR = \"1\", ROS_DOMAIN_ID = \"{domain}\" }}"),
            "--set",
            "module.wave.enabled=true",
        ],
        "fake-devices is up in",
        "dashboard-fake-devices",
        &[
            r#"data-port="/icub/left_arm/state:o""#,
            r#"data-port="/icub/cam/left""#,
            r#"data-port="/yarp_ros2_gateway/left_arm/state:i""#,
            "/icub/cam/left 320x240",
            "<td>left_arm_joints</td>",
        ],
    );
}
