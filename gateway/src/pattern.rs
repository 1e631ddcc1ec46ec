//! Dynamic mode helpers (pure): name-server patterns and the ROS topic of a matched port.

/// Whether `name` matches `pattern`, where `*` stands for any run of characters
/// (including `/`) and `?` for one character; everything else matches itself.
pub fn matches(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    // Iterative wildcard matching with one backtrack point (the last `*`).
    let (mut pi, mut ni) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while ni < n.len() {
        if pi < p.len() && (p[pi] == '?' || p[pi] == n[ni]) {
            pi += 1;
            ni += 1;
        } else if pi < p.len() && p[pi] == '*' {
            star = Some((pi, ni));
            pi += 1;
        } else if let Some((sp, sn)) = star {
            pi = sp + 1;
            ni = sn + 1;
            star = Some((sp, sn + 1));
        } else {
            return false;
        }
    }
    p[pi..].iter().all(|&c| c == '*')
}

/// The ROS topic for YARP port `port` under `prefix`: each `/`-separated token of the
/// port name made a valid ROS name token (other characters become `_`, a leading digit
/// gets a `_` before it). `/sensors/imu:o` under `/yarp` is `/yarp/sensors/imu_o`.
pub fn topic_for_port(prefix: &str, port: &str) -> String {
    let mut out = prefix.trim_end_matches('/').to_string();
    for tok in port.split('/').filter(|t| !t.is_empty()) {
        out.push('/');
        if tok.starts_with(|c: char| c.is_ascii_digit()) {
            out.push('_');
        }
        let mut last_underscore = false;
        for c in tok.chars() {
            let c = if c.is_ascii_alphanumeric() { c } else { '_' };
            // ROS names forbid repeated underscores.
            if c == '_' && last_underscore {
                continue;
            }
            last_underscore = c == '_';
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcards() {
        assert!(matches("/sensors/*", "/sensors/imu:o"));
        assert!(matches("/sensors/*", "/sensors/a/b"));
        assert!(matches("/*/state:o", "/icub/left_arm/state:o"));
        assert!(matches("/cam?", "/cam1"));
        assert!(matches("*", ""));
        assert!(!matches("/sensors/*", "/sensor/imu"));
        assert!(!matches("/*/state:o", "/icub/left_arm/state:i"));
        assert!(!matches("/cam?", "/cam"));
        assert!(matches("/a*b*c", "/axxbyyc"));
        assert!(!matches("/a*b*c", "/axxbyy"));
    }

    #[test]
    fn topics_from_port_names() {
        assert_eq!(
            topic_for_port("/yarp", "/sensors/imu:o"),
            "/yarp/sensors/imu_o"
        );
        assert_eq!(
            topic_for_port("/yarp/", "/icub/left_arm/state:o"),
            "/yarp/icub/left_arm/state_o"
        );
        assert_eq!(topic_for_port("/y", "/3d/cam--x"), "/y/_3d/cam_x");
    }
}
