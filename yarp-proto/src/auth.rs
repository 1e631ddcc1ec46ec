//! YARP port authentication (C++ `AuthHMAC`), sans I/O: when `auth.conf` holds a key, every
//! TCP connection opens with a three-way HMAC-SHA256 exchange before its carrier header.
//!
//! The side that accepted the connection ("source" in C++) speaks first; each message is an
//! 8-byte nonce and a 32-byte MAC:
//!
//! ```text
//! acceptor  -> connector   n1, HMAC(key, n1)
//! connector -> acceptor    n2, HMAC(key, n1 n2)
//! acceptor  -> connector   n3, HMAC(key, n1 n2 n3)
//! ```
//!
//! Each side checks the other's MAC, so both prove they hold the key; a side that fails a
//! check closes the connection. The key is the `key` of the file's `[AUTH]` group, as bytes.

use crate::Property;
use hmac::{Hmac, Mac};
use sha2::Sha256;

/// Bytes of a nonce (C++ `NONCE_LEN`).
pub const NONCE_LEN: usize = 8;
/// Bytes of a MAC (`SHA256_DIGEST_SIZE`).
pub const DIGEST_LEN: usize = 32;
/// Bytes of one message of the exchange.
pub const MESSAGE_LEN: usize = NONCE_LEN + DIGEST_LEN;

/// One message: a nonce and its MAC.
pub type Message = [u8; MESSAGE_LEN];
/// A nonce: the caller draws it from a good random source.
pub type Nonce = [u8; NONCE_LEN];

/// The shared key of a YARP network.
#[derive(Clone)]
pub struct AuthKey(Vec<u8>);

impl std::fmt::Debug for AuthKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("AuthKey(..)")
    }
}

/// Why an `auth.conf` gives no key (C++ then runs without authentication, and says so).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AuthConfError {
    #[error("No \"AUTH\" group found in auth.conf file. Authentication disabled.")]
    NoGroup,
    #[error("No \"key\" found in \"AUTH\" group in auth.conf file. Authentication disabled.")]
    NoKey,
}

/// The other side did not prove it holds the key.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("authentication failed: the peer's digest does not match the key")]
pub struct AuthFailed;

impl AuthKey {
    pub fn new(key: impl Into<Vec<u8>>) -> AuthKey {
        AuthKey(key.into())
    }

    /// The key of an `auth.conf` file's text, as C++ reads it (`[AUTH]`, `key`).
    pub fn from_conf(text: &str) -> Result<AuthKey, AuthConfError> {
        let conf = Property::from_config_text(text).map_err(|_| AuthConfError::NoGroup)?;
        let group = conf.find_group("AUTH").ok_or(AuthConfError::NoGroup)?;
        // C++ `asString()`: a key that reads as a number is no string, hence no key.
        let key = group
            .find("key")
            .and_then(|v| v.as_str())
            .filter(|k| !k.is_empty())
            .ok_or(AuthConfError::NoKey)?;
        Ok(AuthKey::new(key.as_bytes().to_vec()))
    }

    fn mac(&self, nonces: &[&Nonce]) -> [u8; DIGEST_LEN] {
        let mut mac =
            <Hmac<Sha256> as Mac>::new_from_slice(&self.0).expect("HMAC takes any key length");
        for n in nonces {
            mac.update(&n[..]);
        }
        mac.finalize().into_bytes().into()
    }

    fn message(&self, nonce: &Nonce, over: &[&Nonce]) -> Message {
        let mut m = [0u8; MESSAGE_LEN];
        m[..NONCE_LEN].copy_from_slice(nonce);
        m[NONCE_LEN..].copy_from_slice(&self.mac(over));
        m
    }

    fn check(&self, msg: &Message, over: &[&Nonce]) -> Result<(), AuthFailed> {
        let mut mac =
            <Hmac<Sha256> as Mac>::new_from_slice(&self.0).expect("HMAC takes any key length");
        for n in over {
            mac.update(&n[..]);
        }
        // Constant time, so a prober learns nothing from how long a refusal takes.
        mac.verify_slice(&msg[NONCE_LEN..]).map_err(|_| AuthFailed)
    }
}

fn nonce_of(msg: &Message) -> Nonce {
    let mut n = [0u8; NONCE_LEN];
    n.copy_from_slice(&msg[..NONCE_LEN]);
    n
}

/// The accepting side's exchange (C++ `authSource`, in `TcpFace::read`).
pub struct Acceptor {
    key: AuthKey,
    n1: Nonce,
}

impl Acceptor {
    /// Starts the exchange: the first message to send.
    pub fn start(key: &AuthKey, n1: Nonce) -> (Acceptor, Message) {
        let first = key.message(&n1, &[&n1]);
        (
            Acceptor {
                key: key.clone(),
                n1,
            },
            first,
        )
    }

    /// Checks the connector's answer; on success, the third and last message to send.
    pub fn on_answer(self, answer: &Message, n3: Nonce) -> Result<Message, AuthFailed> {
        let n2 = nonce_of(answer);
        self.key.check(answer, &[&self.n1, &n2])?;
        Ok(self.key.message(&n3, &[&self.n1, &n2, &n3]))
    }
}

/// The connecting side's exchange (C++ `authDest`, in `TcpFace::write`).
pub struct Connector {
    key: AuthKey,
    n1: Nonce,
    n2: Nonce,
}

impl Connector {
    /// Checks the acceptor's first message; on success, the answer to send.
    pub fn on_first(
        key: &AuthKey,
        first: &Message,
        n2: Nonce,
    ) -> Result<(Connector, Message), AuthFailed> {
        let n1 = nonce_of(first);
        key.check(first, &[&n1])?;
        let answer = key.message(&n2, &[&n1, &n2]);
        Ok((
            Connector {
                key: key.clone(),
                n1,
                n2,
            },
            answer,
        ))
    }

    /// Checks the acceptor's last message: the connection is then authenticated.
    pub fn on_last(self, last: &Message) -> Result<(), AuthFailed> {
        let n3 = nonce_of(last);
        self.key.check(last, &[&self.n1, &self.n2, &n3])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_sides_with_one_key_agree() {
        let key = AuthKey::new(b"secret".to_vec());
        let (acc, m1) = Acceptor::start(&key, [1; 8]);
        let (con, m2) = Connector::on_first(&key, &m1, [2; 8]).unwrap();
        let m3 = acc.on_answer(&m2, [3; 8]).unwrap();
        con.on_last(&m3).unwrap();
    }

    #[test]
    fn a_wrong_key_is_refused_at_the_first_check_on_either_side() {
        let (k, wrong) = (
            AuthKey::new(b"secret".to_vec()),
            AuthKey::new(b"guess".to_vec()),
        );
        let (_, m1) = Acceptor::start(&k, [1; 8]);
        assert_eq!(
            Connector::on_first(&wrong, &m1, [2; 8]).err(),
            Some(AuthFailed)
        );
        // A connector with the wrong key that answers anyway is refused by the acceptor.
        let (acc, m1) = Acceptor::start(&k, [1; 8]);
        let mut forged = wrong.message(&[2; 8], &[&nonce_of(&m1), &[2; 8]]);
        assert_eq!(acc.on_answer(&forged, [3; 8]).err(), Some(AuthFailed));
        forged[0] ^= 1;
        let (acc, _) = Acceptor::start(&k, [1; 8]);
        assert!(acc.on_answer(&forged, [3; 8]).is_err());
    }

    #[test]
    fn the_mac_is_rfc_4231_hmac_sha256() {
        // RFC 4231 test case 2: key "Jefe", data "what do ya want for nothing?".
        let key = AuthKey::new(b"Jefe".to_vec());
        let mut mac = <Hmac<Sha256> as Mac>::new_from_slice(&key.0).unwrap();
        mac.update(b"what do ya want for nothing?");
        assert_eq!(
            hex::encode(mac.finalize().into_bytes()),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"
        );
    }

    #[test]
    fn the_key_is_read_as_cpp_reads_auth_conf() {
        let k = AuthKey::from_conf("[AUTH]\nkey mysecret\n").unwrap();
        assert_eq!(k.0, b"mysecret");
        assert_eq!(
            AuthKey::from_conf("key x\n").err(),
            Some(AuthConfError::NoGroup)
        );
        assert_eq!(
            AuthKey::from_conf("[AUTH]\nother 1\n").err(),
            Some(AuthConfError::NoKey)
        );
    }
}
