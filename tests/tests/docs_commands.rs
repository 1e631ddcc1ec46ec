//! The docs test: every code block of the README and the other user-facing Markdown files,
//! one trial each (`README.md:17`), run as a reader would run it or checked as the comment
//! before it says (`yarp_interop_tests::docs`). Each block runs in a private network
//! namespace of its own (`../shared/netns-run`), so the fixed ports the documents use
//! (10000, 8080, the robots' 10.0.1.x) never meet another test's, and whatever a block
//! leaves running is killed with its namespace. The documents also name fixed paths in
//! /tmp (the emulated Xsens' pseudo-terminal link), so the trials run one at a time, in
//! the nextest group of the other tests that use them (`.config/nextest.toml`).

use libtest_mimic::{Arguments, Failed, Trial};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use yarp_interop_tests::docs;

/// Set in the child that runs one block inside its namespace: `FILE:LINE`.
const BLOCK_VAR: &str = "DOCS_TEST_BLOCK";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate is in the repository")
        .to_path_buf()
}

fn main() {
    if let Ok(spec) = std::env::var(BLOCK_VAR) {
        std::process::exit(run_here(&spec));
    }
    let args = Arguments::from_args();
    let root = root();
    let mut trials = Vec::new();
    for file in docs::user_docs(&root) {
        let rel = file
            .strip_prefix(&root)
            .unwrap_or(&file)
            .display()
            .to_string();
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        for block in docs::blocks(&text) {
            let spec = format!("{rel}:{}", block.line);
            let limit = block
                .directives
                .as_ref()
                .and_then(|d| d.as_ref().ok())
                .map_or(Duration::from_secs(90), |d| d.timeout);
            let name = spec.clone();
            trials.push(Trial::test(name, move || in_namespace(&spec, limit)));
        }
    }
    libtest_mimic::run(&args, trials).exit();
}

/// Runs one block in a fresh namespace: this program again, told which block.
fn in_namespace(spec: &str, limit: Duration) -> Result<(), Failed> {
    let netns = root().join("../shared/netns-run");
    if !netns.is_file() {
        return Err(format!(
            "{} not found (../shared beside the repository)",
            netns.display()
        )
        .into());
    }
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut child = Command::new(&netns)
        .arg(&exe)
        .env(BLOCK_VAR, spec)
        .env_remove("NETNS_RUN_INSIDE") // a namespace of its own, even inside the suite's
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start {}: {e}", netns.display()))?;
    // The child keeps its own deadline; this one only guards against it hanging.
    let guard = Instant::now() + limit + Duration::from_secs(90);
    loop {
        if let Some(_st) = child.try_wait().map_err(|e| e.to_string())? {
            break;
        }
        if Instant::now() > guard {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("{spec}: the block's runner hung past its own deadline").into());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let out = child.wait_with_output().map_err(|e| e.to_string())?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    if out.status.success() {
        print!("{text}");
        Ok(())
    } else {
        Err(format!("{spec}:\n{text}").into())
    }
}

/// Inside the namespace: runs the block and prints what happened; the exit status says
/// whether it passed.
fn run_here(spec: &str) -> i32 {
    let Some((file, line)) = spec.rsplit_once(':') else {
        eprintln!("{BLOCK_VAR}={spec}: FILE:LINE");
        return 2;
    };
    let Ok(line) = line.parse::<usize>() else {
        eprintln!("{BLOCK_VAR}={spec}: bad line");
        return 2;
    };
    let root = root();
    let text = match std::fs::read_to_string(root.join(file)) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("{file}: {e}");
            return 2;
        }
    };
    let scratch = match tempfile::tempdir() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("no scratch directory: {e}");
            return 2;
        }
    };
    let mut setting = docs::Setting::new(&root, scratch.path());
    setting.private_net = true;
    match docs::check_block(&text, line, &setting) {
        Ok(log) => {
            print!("{log}");
            0
        }
        Err(why) => {
            eprintln!("{why}");
            1
        }
    }
}
