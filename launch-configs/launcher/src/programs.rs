//! Finding the program a module names.
//!
//! A name with a `/` is a path (relative to the config's directory). A bare name is looked
//! up, first match wins, in: `$YARP_BIN_DIR`; the directory of the running `yarp-launch`
//! (cargo puts every workspace binary there); `$CARGO_TARGET_DIR/debug` and `/release`;
//! the workspace's `target/debug` and `target/release`; then `$PATH`.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
#[error("program {name:?} not found (looked in: {looked}); build it with `cargo build -p {package}` or set YARP_BIN_DIR")]
pub struct NotFound {
    pub name: String,
    pub looked: String,
    pub package: String,
}

/// The cargo package that builds a workspace program, for the hint in [`NotFound`].
pub fn package_of(program: &str) -> &'static str {
    match program {
        "yarp" => "yarp-cli",
        "yarpserver" => "yarp-net",
        "yarpdev" | "yarprobotinterface" => "yarp-device-programs",
        "yarp-ros2-gateway" => "yarp-ros2-gateway",
        "icub-board-emulator" | "icub-eth-emulator" | "icub-robot-emulator" => "icub-emulators",
        "iKinCartesianSolver" | "iKinGazeCtrl" => "icub-cartesian",
        "yarp-launch" => "yarp-launch",
        _ => "<package>",
    }
}

/// Directories searched for bare names, in order (existing or not).
pub fn search_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("YARP_BIN_DIR") {
        dirs.push(PathBuf::from(d));
    }
    if let Some(d) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        dirs.push(d.clone());
        // Test binaries live in target/debug/deps; the programs one level up.
        if d.ends_with("deps") {
            if let Some(p) = d.parent() {
                dirs.push(p.to_path_buf());
            }
        }
    }
    if let Some(t) = std::env::var_os("CARGO_TARGET_DIR") {
        let t = PathBuf::from(t);
        dirs.push(t.join("debug"));
        dirs.push(t.join("release"));
    }
    let ws = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target");
    dirs.push(ws.join("debug"));
    dirs.push(ws.join("release"));
    if let Some(path) = std::env::var_os("PATH") {
        dirs.extend(std::env::split_paths(&path));
    }
    dirs
}

fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    p.metadata()
        .map(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
        .unwrap_or(false)
}

/// Resolves `program` as the module doc says; `base` is the config's directory.
pub fn resolve(program: &str, base: &Path) -> Result<PathBuf, NotFound> {
    if program.contains('/') {
        let p = base.join(program);
        if is_executable(&p) {
            return Ok(p);
        }
        return Err(NotFound {
            name: program.into(),
            looked: p.display().to_string(),
            package: package_of(program).into(),
        });
    }
    let dirs = search_dirs();
    for d in &dirs {
        let p = d.join(program);
        if is_executable(&p) {
            return Ok(p);
        }
    }
    Err(NotFound {
        name: program.into(),
        looked: "YARP_BIN_DIR, the launcher's directory, the cargo target dirs, PATH".into(),
        package: package_of(program).into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_programs_on_path_and_by_path() {
        assert!(resolve("sh", Path::new("/")).is_ok());
        assert!(resolve("/bin/sh", Path::new("/nonexistent")).is_ok());
        let e = resolve("no-such-program-xyz", Path::new("/")).unwrap_err();
        assert!(e.to_string().contains("no-such-program-xyz"));
        let e = resolve("yarpdev-missing/x", Path::new("/")).unwrap_err();
        assert!(e.to_string().contains("not found"));
        assert_eq!(package_of("yarpdev"), "yarp-device-programs");
        assert_eq!(package_of("icub-board-emulator"), "icub-emulators");
    }
}
