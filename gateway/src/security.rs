//! SROS2: whether and how a DDS participant is secured, read from the environment as rcl
//! (`rcl/security.c`) and rmw (`rmw_dds_common::get_security_files`) read it.
//!
//! - `ROS_SECURITY_ENABLE=true` (exactly) turns security on; anything else leaves it off.
//! - `ROS_SECURITY_STRATEGY=Enforce` (exactly) refuses to run unsecured when the enclave
//!   cannot be found or is incomplete; anything else (rmw's "permissive") runs unsecured,
//!   saying why.
//! - The enclave's directory is `$ROS_SECURITY_KEYSTORE/enclaves/<enclave>`, the enclave
//!   being `$ROS_SECURITY_ENCLAVE_OVERRIDE` if set, else `--ros-args --enclave`, else `/`
//!   (`enclaves/` itself), as `ros2 security create_enclave` lays it out.
//! - The directory must hold the six files SROS2 writes there (below); DDS Security's
//!   builtin plugins (RustDDS's `security` feature: PKI-DH authentication, signed
//!   governance and permissions, AES-GCM-GMAC) then secure the participant.

use std::path::{Path, PathBuf};

/// The files an enclave holds, by the names rmw looks for (the CRL is optional, and
/// RustDDS does not read one).
pub const ENCLAVE_FILES: [&str; 6] = [
    "identity_ca.cert.pem",
    "cert.pem",
    "key.pem",
    "permissions_ca.cert.pem",
    "governance.p7s",
    "permissions.p7s",
];

/// Why a participant that must be secured could not be.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SecurityError {
    /// `Enforce` without `ROS_SECURITY_KEYSTORE`.
    #[error(
        "ROS_SECURITY_ENABLE=true with ROS_SECURITY_STRATEGY=Enforce, but ROS_SECURITY_KEYSTORE \
         is not set: refusing to join the graph unsecured"
    )]
    NoKeystore,
    /// `Enforce` and the enclave's directory is missing (rcl's message).
    #[error("SECURITY ERROR: directory '{}' does not exist.", .0.display())]
    NoEnclave(PathBuf),
    /// `Enforce` and the enclave lacks some of [`ENCLAVE_FILES`] (rmw's message, naming them).
    #[error("couldn't find all security files in '{}': missing {}", .dir.display(), .missing.join(", "))]
    Incomplete { dir: PathBuf, missing: Vec<String> },
}

/// How this process joins the graph.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Security {
    /// Unsecured (security off, or permissive without a usable enclave).
    Off,
    /// Secured with the enclave in this directory (holding every [`ENCLAVE_FILES`]).
    Enclave(PathBuf),
}

static ENCLAVE: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Sets this process's enclave (`--ros-args --enclave`), once, before any participant.
pub fn set_enclave(enclave: &str) {
    let _ = ENCLAVE.set(enclave.to_string());
}

/// This process's enclave: `--ros-args --enclave`, else `/`.
pub fn enclave() -> &'static str {
    ENCLAVE.get().map(String::as_str).unwrap_or("/")
}

/// What the environment asks for (`env` reads a variable), for `enclave`.
pub fn from_env(
    env: &dyn Fn(&str) -> Option<String>,
    enclave: &str,
) -> Result<Security, SecurityError> {
    if env("ROS_SECURITY_ENABLE").as_deref() != Some("true") {
        return Ok(Security::Off);
    }
    let enforce = env("ROS_SECURITY_STRATEGY").as_deref() == Some("Enforce");
    // Permissive: what rmw does without a usable enclave is run unsecured; we say so.
    let permissive = |why: SecurityError| {
        if enforce {
            Err(why)
        } else {
            tracing::warn!("{why}; running unsecured (ROS_SECURITY_STRATEGY is not Enforce)");
            Ok(Security::Off)
        }
    };
    let Some(keystore) = env("ROS_SECURITY_KEYSTORE").filter(|k| !k.is_empty()) else {
        return permissive(SecurityError::NoKeystore);
    };
    let name = env("ROS_SECURITY_ENCLAVE_OVERRIDE")
        .filter(|o| !o.is_empty())
        .unwrap_or_else(|| enclave.to_string());
    let dir = enclave_dir(Path::new(&keystore), &name);
    if !dir.is_dir() {
        return permissive(SecurityError::NoEnclave(dir));
    }
    let missing: Vec<String> = ENCLAVE_FILES
        .iter()
        .filter(|f| !dir.join(f).is_file())
        .map(|f| f.to_string())
        .collect();
    if !missing.is_empty() {
        return permissive(SecurityError::Incomplete { dir, missing });
    }
    tracing::info!("Found security directory: {}", dir.display());
    Ok(Security::Enclave(dir))
}

/// `<keystore>/enclaves/<enclave without its leading />` (`/` is `enclaves` itself).
pub fn enclave_dir(keystore: &Path, enclave: &str) -> PathBuf {
    let enclaves = keystore.join("enclaves");
    match enclave.trim_start_matches('/') {
        "" => enclaves,
        rel => enclaves.join(rel),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            vars.iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    /// A keystore holding enclave `/robot` complete and `/half` without its permissions.
    fn keystore() -> tempfile::TempDir {
        let ks = tempfile::tempdir().unwrap();
        for (enclave, files) in [("robot", &ENCLAVE_FILES[..]), ("half", &ENCLAVE_FILES[..5])] {
            let d = ks.path().join("enclaves").join(enclave);
            std::fs::create_dir_all(&d).unwrap();
            for f in files {
                std::fs::write(d.join(f), "x").unwrap();
            }
        }
        ks
    }

    #[test]
    fn off_unless_enable_is_exactly_true() {
        for v in [
            &[][..],
            &[("ROS_SECURITY_ENABLE", "1")],
            &[("ROS_SECURITY_ENABLE", "True")],
        ] {
            assert_eq!(from_env(&env(v), "/"), Ok(Security::Off));
        }
    }

    #[test]
    fn the_enclave_is_found_as_rcl_finds_it() {
        let ks = keystore();
        let k = ks.path().to_str().unwrap();
        let on = [
            ("ROS_SECURITY_ENABLE", "true"),
            ("ROS_SECURITY_KEYSTORE", k),
        ];
        let robot = ks.path().join("enclaves/robot");
        assert_eq!(
            from_env(&env(&on), "/robot"),
            Ok(Security::Enclave(robot.clone()))
        );
        let over = [&on[..], &[("ROS_SECURITY_ENCLAVE_OVERRIDE", "/robot")]].concat();
        assert_eq!(from_env(&env(&over), "/"), Ok(Security::Enclave(robot)));
        assert_eq!(enclave_dir(ks.path(), "/"), ks.path().join("enclaves"));
    }

    #[test]
    fn enforce_refuses_what_permissive_runs_unsecured() {
        let ks = keystore();
        let k = ks.path().to_str().unwrap();
        let permissive = [
            ("ROS_SECURITY_ENABLE", "true"),
            ("ROS_SECURITY_KEYSTORE", k),
        ];
        let enforce = [&permissive[..], &[("ROS_SECURITY_STRATEGY", "Enforce")]].concat();
        for enclave in ["/nobody", "/half"] {
            assert_eq!(from_env(&env(&permissive), enclave), Ok(Security::Off));
        }
        assert_eq!(
            from_env(&env(&enforce), "/nobody"),
            Err(SecurityError::NoEnclave(ks.path().join("enclaves/nobody")))
        );
        assert_eq!(
            from_env(&env(&enforce), "/half"),
            Err(SecurityError::Incomplete {
                dir: ks.path().join("enclaves/half"),
                missing: vec!["permissions.p7s".into()]
            })
        );
        assert_eq!(
            from_env(
                &env(&[
                    ("ROS_SECURITY_ENABLE", "true"),
                    ("ROS_SECURITY_STRATEGY", "Enforce")
                ]),
                "/"
            ),
            Err(SecurityError::NoKeystore)
        );
    }
}
