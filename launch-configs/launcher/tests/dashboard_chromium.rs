//! The dashboard in a real browser: headless Chromium (Debian `chromium`, installed by
//! `tests/peers/install-chromium.sh`) loads the page of a running `yarp-launch demo.toml`,
//! takes a screenshot (checked to be a non-blank PNG) and dumps the DOM (checked to hold
//! the port graph's nodes and edge, and a drawn plot). Skips loudly without Chromium.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Installs Chromium if needed; None (after saying why) when it cannot be had.
fn chromium() -> Option<PathBuf> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peers/install-chromium.sh");
    // Bounded: a download that hangs must not hang the test run.
    let ok = Command::new("timeout")
        .args(["900", "bash"])
        .arg(&script)
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    let found = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .iter()
        .map(PathBuf::from)
        .find(|p| p.exists());
    if !ok || found.is_none() {
        eprintln!("==================================================================");
        eprintln!("SKIPPED: headless Chromium is not available and could not be");
        eprintln!(
            "installed ({}): the dashboard was not checked",
            script.display()
        );
        eprintln!("in a browser.");
        eprintln!("==================================================================");
        return None;
    }
    found
}

/// Runs Chromium headless with the flags that keep it on this machine; kills it after
/// `limit`. Returns its stdout, or None when it had to be killed.
fn run_chromium_once(
    bin: &Path,
    profile: &Path,
    args: &[String],
    limit: Duration,
) -> Option<String> {
    let mut child = Command::new(bin)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-dev-shm-usage",
            "--window-size=1280,900",
            "--virtual-time-budget=5000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .process_group(0)
        .spawn()
        .expect("start chromium");
    let mut out = child.stdout.take().expect("stdout");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut out, &mut s);
        s
    });
    let deadline = Instant::now() + limit;
    loop {
        if let Ok(Some(_)) = child.try_wait() {
            break;
        }
        if Instant::now() > deadline {
            // Chromium runs helper processes: kill its whole group.
            let _ = nix::sys::signal::killpg(
                nix::unistd::Pid::from_raw(child.id() as i32),
                Signal::SIGKILL,
            );
            let _ = child.wait();
            eprintln!("chromium did not finish within {limit:?}");
            return None;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    // Helpers may outlive the browser process for a moment.
    let _ = nix::sys::signal::killpg(
        nix::unistd::Pid::from_raw(child.id() as i32),
        Signal::SIGKILL,
    );
    Some(reader.join().unwrap_or_default())
}

/// [`run_chromium_once`], tried a second time (fresh profile) if the browser hangs: on a
/// loaded 2-core machine a headless Chromium occasionally never finishes its first run.
fn run_chromium(bin: &Path, profile: &Path, args: &[String], limit: Duration) -> String {
    for attempt in 0..2 {
        let dir = profile.with_extension(attempt.to_string());
        if let Some(out) = run_chromium_once(bin, &dir, args, limit) {
            return out;
        }
    }
    panic!("chromium did not finish within {limit:?}, twice");
}

use std::os::unix::process::CommandExt as _;

/// Decodes a PNG and says whether it shows something: several colours and a fair share
/// of non-background pixels.
fn check_not_blank(png_path: &Path) -> (u32, u32, usize, f64) {
    let file = std::fs::File::open(png_path).expect("screenshot exists");
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder.read_info().expect("valid PNG");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("PNG frame");
    let bpp = info.color_type.samples();
    let px = &buf[..info.buffer_size()];
    let mut colours = std::collections::HashSet::new();
    let first = &px[..bpp];
    let mut differing = 0usize;
    let n = px.len() / bpp;
    for p in px.chunks_exact(bpp) {
        if colours.len() < 10_000 {
            colours.insert(p.to_vec());
        }
        if p != first {
            differing += 1;
        }
    }
    (
        info.width,
        info.height,
        colours.len(),
        differing as f64 / n as f64,
    )
}

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
