//! Headless Chromium for the dashboard tests: installing it (bounded), running it with the
//! flags that keep it on this machine, and checking a screenshot is not blank.

use super::Signal;
use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Installs Chromium if needed; None (after saying why) when it cannot be had.
pub fn chromium() -> Option<PathBuf> {
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
        yarp_interop_tests::peer_missing(
            "dashboard in a browser",
            "headless Chromium",
            &format!("{} did not give /usr/bin/chromium", script.display()),
            yarp_interop_tests::CHROMIUM_INSTALL,
        );
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
pub fn run_chromium(bin: &Path, profile: &Path, args: &[String], limit: Duration) -> String {
    for attempt in 0..2 {
        let dir = profile.with_extension(attempt.to_string());
        if let Some(out) = run_chromium_once(bin, &dir, args, limit) {
            return out;
        }
    }
    panic!("chromium did not finish within {limit:?}, twice");
}

/// Decodes a PNG and says whether it shows something: several colours and a fair share
/// of non-background pixels.
pub fn check_not_blank(png_path: &Path) -> (u32, u32, usize, f64) {
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
