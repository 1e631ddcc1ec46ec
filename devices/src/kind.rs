//! What a device is, read from the interfaces its driver offers: their C++ names (for
//! `yarpdev --list`) and a [`Kind`] (motor control, sensor, camera, network wrapper,
//! calibrator); and which known devices to suggest for an unknown name, so that a name
//! that asks for a motor gets motor devices rather than whatever is spelled alike.

use crate::driver::INTERFACES;

/// What a device is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Joints: encoders, position/velocity/torque control (boards, their clients, remappers).
    Motor,
    /// IMUs, force/torque, skin, analog sensors (devices and their clients).
    Sensor,
    /// Frame grabbers.
    Camera,
    /// Network wrappers (servers) and other devices that serve attached devices.
    Wrapper,
    /// Calibrators.
    Calibrator,
    Other,
}

impl Kind {
    /// How `yarpdev --list` and the unknown-device error name the kind.
    pub fn label(self) -> &'static str {
        match self {
            Kind::Motor => "motor",
            Kind::Sensor => "sensor",
            Kind::Camera => "camera",
            Kind::Wrapper => "network wrapper",
            Kind::Calibrator => "calibrator",
            Kind::Other => "other",
        }
    }
}

/// The kind a device's interfaces make it. What it offers comes first: a remapper that
/// attaches boards (`IMultipleWrapper`) is a motor device; a server that only attaches
/// (`controlBoard_nws_yarp`) is a network wrapper.
pub fn kind_of(interfaces: &[&str]) -> Kind {
    let offers = |kind: Kind| {
        INTERFACES
            .iter()
            .any(|(name, k)| *k == kind && interfaces.contains(name))
    };
    [
        Kind::Motor,
        Kind::Camera,
        Kind::Sensor,
        Kind::Calibrator,
        Kind::Wrapper,
    ]
    .into_iter()
    .find(|k| offers(*k))
    .unwrap_or(Kind::Other)
}

/// Words of a device name, lowercase: split at `_`, `-`, digits and camelCase
/// (`fakeFTs` -> `fake`, `fts`; `controlBoard_nws_yarp` -> `control`, `board`, `nws`, `yarp`).
fn words(name: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut prev_lower = false;
    for c in name.chars() {
        if !c.is_ascii_alphabetic() {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            prev_lower = false;
            continue;
        }
        if c.is_ascii_uppercase() && prev_lower && !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
        prev_lower = c.is_ascii_lowercase();
        cur.push(c.to_ascii_lowercase());
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// The kind a name asks for, from its words: whole short words (`mc`, `ft`, `imu`, plural
/// `s` allowed) or stems anywhere in the name (`motor`, `grabber`, `calib`, ...).
pub fn kind_asked_for(name: &str) -> Option<Kind> {
    let lower = name.to_ascii_lowercase();
    let ws = words(name);
    let word = |keys: &[&str]| {
        ws.iter().any(|w| {
            keys.iter()
                .any(|k| w == k || w.strip_suffix('s') == Some(k))
        })
    };
    let stem = |keys: &[&str]| keys.iter().any(|k| lower.contains(k));
    // order matters: `controlboard_nws_ros` wants a wrapper, `ftSensor` a sensor
    if word(&["nws", "server", "wrapper"]) || stem(&["wrapper"]) {
        Some(Kind::Wrapper)
    } else if word(&["cam", "image", "video", "frame", "grabber"]) || stem(&["camera", "grabber"]) {
        Some(Kind::Camera)
    } else if word(&[
        "imu", "ft", "skin", "sensor", "gyro", "mtb", "xsens", "force", "tactile",
    ]) || stem(&[
        "inertial",
        "accelero",
        "magneto",
        "analog",
        "sensor",
        "gyro",
        "temperature",
    ]) {
        Some(Kind::Sensor)
    } else if word(&[
        "mc", "arm", "leg", "torso", "joint", "axis", "axes", "servo", "encoder", "board",
    ]) || stem(&["motor", "motion", "controlboard", "actuator", "servo"])
    {
        Some(Kind::Motor)
    } else if stem(&["calib"]) {
        Some(Kind::Calibrator)
    } else {
        None
    }
}

/// Levenshtein distance, case-insensitive.
pub fn distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.to_lowercase().chars().collect();
    let b: Vec<char> = b.to_lowercase().chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur.push(sub.min(prev[j + 1] + 1).min(cur[j] + 1));
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Length of the longest run of letters two names share, case-insensitive
/// (`fake_motor` and `fakeMotionControl` share `fakemot`).
fn common_run(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.to_lowercase().chars().collect();
    let b: Vec<char> = b.to_lowercase().chars().collect();
    let mut best = 0;
    let mut prev = vec![0usize; b.len() + 1];
    for ca in &a {
        let mut cur = vec![0usize; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            if ca == cb {
                cur[j + 1] = prev[j] + 1;
                best = best.max(cur[j + 1]);
            }
        }
        prev = cur;
    }
    best
}

/// How many words two names share (a plural `s` ignored: `ftSensor` and `fakeFTs` share
/// `ft`).
fn shared_words(a: &str, b: &str) -> usize {
    let stem = |w: &String| w.strip_suffix('s').unwrap_or(w).to_string();
    let b: Vec<String> = words(b).iter().map(stem).collect();
    words(a).iter().filter(|w| b.contains(&stem(w))).count()
}

/// How many devices a suggestion names at most.
pub const MAX_SUGGESTIONS: usize = 5;

/// What to suggest for an unknown device name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Suggestions {
    /// Known names, best first: misspellings of the name, then devices of the kind it
    /// asks for (closest spelling first).
    pub names: Vec<String>,
    /// The kind the name asks for, when its words say.
    pub kind: Option<Kind>,
}

/// The known devices (`(name, kind)`) to suggest for `name`. A near spelling (at most a
/// quarter of the name's letters, or 2, differ) always comes first; a name that asks for
/// a kind then gets devices of that kind, those sharing the most words, then the longest
/// run of letters with it first; a name that says nothing gets the three closest spellings.
pub fn suggest(name: &str, known: &[(&str, Kind)]) -> Suggestions {
    let mut scored: Vec<(usize, &str, Kind)> = known
        .iter()
        .map(|(n, k)| (distance(name, n), *n, *k))
        .collect();
    scored.sort_by_key(|(d, n, _)| (*d, n.to_lowercase()));
    let typo = (name.chars().count() / 4).max(2);
    let mut names: Vec<String> = scored
        .iter()
        .filter(|(d, ..)| *d <= typo)
        .map(|(_, n, _)| n.to_string())
        .collect();
    let kind = kind_asked_for(name);
    match kind {
        Some(wanted) => {
            let mut of_kind: Vec<(usize, usize, usize, &str)> = scored
                .iter()
                .filter(|(_, n, k)| *k == wanted && !names.iter().any(|x| x == n))
                .map(|(d, n, _)| (shared_words(name, n), common_run(name, n), *d, *n))
                .collect();
            of_kind.sort_by(|a, b| (b.0, b.1).cmp(&(a.0, a.1)).then(a.2.cmp(&b.2)));
            names.extend(of_kind.into_iter().map(|(.., n)| n.to_string()));
        }
        None if names.is_empty() => {
            let limit = name.chars().count().max(3) * 2 / 3 + 1;
            names = scored
                .iter()
                .filter(|(d, ..)| *d <= limit)
                .take(3)
                .map(|(_, n, _)| n.to_string())
                .collect();
            if names.is_empty() {
                names = scored
                    .iter()
                    .take(3)
                    .map(|(_, n, _)| n.to_string())
                    .collect();
            }
        }
        None => {}
    }
    names.truncate(MAX_SUGGESTIONS);
    Suggestions { names, kind }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KNOWN: &[(&str, Kind)] = &[
        ("fakeMotionControl", Kind::Motor),
        ("test_motor", Kind::Motor),
        ("remote_controlboard", Kind::Motor),
        ("controlboardremapper", Kind::Motor),
        ("canmotioncontrol", Kind::Motor),
        ("controlBoard_nws_yarp", Kind::Wrapper),
        ("imuFilter", Kind::Sensor),
        ("xsensmtx", Kind::Sensor),
        ("fakeFTs", Kind::Sensor),
        ("fakeIMU", Kind::Sensor),
        ("fakeFrameGrabber", Kind::Camera),
        ("frameGrabber_nws_yarp", Kind::Wrapper),
        ("parametricCalibrator", Kind::Calibrator),
    ];

    #[test]
    fn words_of_names() {
        assert_eq!(words("fakeFTs"), ["fake", "fts"]);
        assert_eq!(
            words("controlBoard_nws_yarp"),
            ["control", "board", "nws", "yarp"]
        );
        assert_eq!(words("test_motor2"), ["test", "motor"]);
    }

    #[test]
    fn kinds_asked_for() {
        for (name, kind) in [
            ("fake_motor", Some(Kind::Motor)),
            ("motors", Some(Kind::Motor)),
            ("left_arm", Some(Kind::Motor)),
            ("embObjMotionControl", Some(Kind::Motor)),
            ("ftSensor", Some(Kind::Sensor)),
            ("inertial", Some(Kind::Sensor)),
            ("usbCamera", Some(Kind::Camera)),
            ("controlBoard_nws_ros2", Some(Kind::Wrapper)),
            ("parametricCalib", Some(Kind::Calibrator)),
            ("left", None),
            ("foo", None),
        ] {
            assert_eq!(kind_asked_for(name), kind, "{name}");
        }
    }

    #[test]
    fn a_motor_name_gets_motor_devices() {
        let s = suggest("fake_motor", KNOWN);
        assert_eq!(s.kind, Some(Kind::Motor));
        assert_eq!(s.names.len(), 5);
        assert!(s
            .names
            .iter()
            .all(|n| KNOWN.iter().any(|(k, kind)| k == n && *kind == Kind::Motor)));
        let mut first_two = s.names[..2].to_vec();
        first_two.sort();
        assert_eq!(first_two, ["fakeMotionControl", "test_motor"], "{s:?}");
        let s = suggest("ftSensor", KNOWN);
        assert_eq!(
            (s.names[0].as_str(), s.kind),
            ("fakeFTs", Some(Kind::Sensor))
        );
    }

    #[test]
    fn misspellings_come_first() {
        let s = suggest("fakeMotionControll", KNOWN);
        assert_eq!(s.names[0], "fakeMotionControl");
        let s = suggest("tset_motor", KNOWN);
        assert_eq!(s.names[0], "test_motor");
        // a name that says nothing still gets the closest spellings
        let s = suggest("fakeIMUU", KNOWN);
        assert_eq!((s.names[0].as_str(), s.kind), ("fakeIMU", None));
        let s = suggest("xyz", KNOWN);
        assert_eq!((s.names.len(), s.kind), (3, None));
    }

    #[test]
    fn kinds_from_interfaces() {
        assert_eq!(
            kind_of(&["IEncodersTimed", "IPositionControl"]),
            Kind::Motor
        );
        assert_eq!(kind_of(&["IWrapper", "IMultipleWrapper"]), Kind::Wrapper);
        assert_eq!(
            kind_of(&["IEncodersTimed", "IMultipleWrapper"]),
            Kind::Motor
        );
        assert_eq!(
            kind_of(&["IRemoteCalibrator", "ICalibrator"]),
            Kind::Calibrator
        );
        assert_eq!(kind_of(&["IFrameGrabberImage"]), Kind::Camera);
        assert_eq!(kind_of(&["IOrientationSensors"]), Kind::Sensor);
        assert_eq!(kind_of(&[]), Kind::Other);
    }
}
