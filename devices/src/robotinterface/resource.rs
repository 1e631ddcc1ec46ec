//! Where `yarpdev --from` and `yarprobotinterface --config` find their files: the
//! subset of C++ `ResourceFinder` search paths these programs rely on.
//!
//! In order: the name as given (relative to the working directory), then for each data
//! directory (`YARP_DATA_HOME`, then each entry of `YARP_DATA_DIRS`, `:`-separated) the
//! context directory `contexts/<context>/` (when a context is given) and the robot
//! directory `robots/$YARP_ROBOT_NAME/` (when the variable is set). An installed
//! robots-configuration is found this way: `YARP_ROBOT_NAME=iCubGenova01
//! yarprobotinterface` reads `robots/iCubGenova01/yarprobotinterface.ini`.

use std::path::{Path, PathBuf};

/// The candidate paths for `name`, in search order.
pub fn candidates(
    name: &str,
    context: Option<&str>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Vec<PathBuf> {
    let mut out = vec![PathBuf::from(name)];
    if Path::new(name).is_absolute() {
        return out;
    }
    let mut data_dirs: Vec<PathBuf> = Vec::new();
    if let Some(home) = env("YARP_DATA_HOME").filter(|s| !s.is_empty()) {
        data_dirs.push(home.into());
    }
    if let Some(dirs) = env("YARP_DATA_DIRS") {
        data_dirs.extend(dirs.split(':').filter(|s| !s.is_empty()).map(PathBuf::from));
    }
    let robot = env("YARP_ROBOT_NAME").filter(|s| !s.is_empty());
    for dir in &data_dirs {
        if let Some(ctx) = context {
            out.push(dir.join("contexts").join(ctx).join(name));
        }
        if let Some(robot) = &robot {
            out.push(dir.join("robots").join(robot).join(name));
        }
    }
    out
}

/// The first existing candidate for `name` (see [`candidates`]), from the process
/// environment.
pub fn find_file(name: &str, context: Option<&str>) -> Option<PathBuf> {
    candidates(name, context, &|k| std::env::var(k).ok())
        .into_iter()
        .find(|p| p.is_file())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn search_order() {
        let env = |k: &str| match k {
            "YARP_DATA_HOME" => Some("/home/u/.local/share/yarp".to_string()),
            "YARP_DATA_DIRS" => Some("/opt/a:/opt/b".to_string()),
            "YARP_ROBOT_NAME" => Some("iCubGenova01".to_string()),
            _ => None,
        };
        let c = candidates("robot.ini", Some("ctx"), &env);
        let c: Vec<String> = c.iter().map(|p| p.display().to_string()).collect();
        assert_eq!(
            c,
            [
                "robot.ini",
                "/home/u/.local/share/yarp/contexts/ctx/robot.ini",
                "/home/u/.local/share/yarp/robots/iCubGenova01/robot.ini",
                "/opt/a/contexts/ctx/robot.ini",
                "/opt/a/robots/iCubGenova01/robot.ini",
                "/opt/b/contexts/ctx/robot.ini",
                "/opt/b/robots/iCubGenova01/robot.ini",
            ]
        );
        assert_eq!(candidates("/abs.ini", Some("ctx"), &env).len(), 1);
        assert_eq!(candidates("x.ini", None, &|_| None).len(), 1);
    }
}
