//! The bridge key: the one secret both bridges of a run hold, so that no third peer can join, read samples or send
//! a command. It is a small private certificate authority used once: `silrig-bridge keygen` makes a CA, signs one
//! certificate with it for the bridges, and throws the CA's private key away, so the file holds the CA's
//! certificate (what a peer must chain to), the bridges' certificate and its private key, and nobody can ever
//! issue another certificate under that CA. Both bridges present that certificate and require the other's to chain
//! to the CA (Zenoh's TLS transport with mutual authentication, TLS 1.3), so the link is also encrypted.
//!
//! Owns: making the key ([`BridgeKey::generate`], [`write_new`]), reading it back from an owner-only file
//! ([`BridgeKey::read`]: a file its group or others can read is refused), its fingerprint for people to compare
//! across hosts, and the Zenoh settings that use it ([`BridgeKey::zenoh_settings`]).

use super::error::BridgeError;
use std::io::Write;
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::Path;

/// The PEM labels of the file's three blocks, in order.
const BLOCKS: [&str; 3] = ["CERTIFICATE", "CERTIFICATE", "PRIVATE KEY"];

/// A bridge key as read from its file.
#[derive(Clone, PartialEq, Eq)]
pub struct BridgeKey {
    /// The CA's certificate, PEM: the one trust anchor.
    ca_pem: String,
    /// The bridges' certificate, PEM.
    cert_pem: String,
    /// Its private key, PKCS#8 PEM.
    key_pem: String,
}

// Never the private key in a debug print.
impl std::fmt::Debug for BridgeKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BridgeKey({})", self.fingerprint())
    }
}

impl BridgeKey {
    /// A new key: a CA used once to sign the bridges' certificate (ECDSA P-256), its own private key dropped.
    pub fn generate() -> Result<Self, String> {
        use rcgen::{
            BasicConstraints, CertificateParams, DnType, ExtendedKeyUsagePurpose, IsCa, Issuer, KeyPair,
            KeyUsagePurpose,
        };
        let words = |e: rcgen::Error| format!("making the bridge key: {e}");
        let ca_key = KeyPair::generate().map_err(words)?;
        let mut ca = CertificateParams::new(Vec::<String>::new()).map_err(words)?;
        ca.is_ca = IsCa::Ca(BasicConstraints::Constrained(0));
        ca.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::DigitalSignature];
        ca.distinguished_name.push(DnType::CommonName, "silrig bridge key authority");
        let ca_pem = ca.self_signed(&ca_key).map_err(words)?.pem();
        let key = KeyPair::generate().map_err(words)?;
        // The name is never checked (bridges connect by address); both purposes, as each bridge is TLS server
        // and client alike.
        let mut cert = CertificateParams::new(vec!["silrig-bridge".to_string()]).map_err(words)?;
        cert.distinguished_name.push(DnType::CommonName, "silrig-bridge");
        cert.key_usages = vec![KeyUsagePurpose::DigitalSignature];
        cert.extended_key_usages = vec![ExtendedKeyUsagePurpose::ServerAuth, ExtendedKeyUsagePurpose::ClientAuth];
        let issuer = Issuer::new(ca, ca_key);
        let cert_pem = cert.signed_by(&key, &issuer).map_err(words)?.pem();
        Self::from_text(&Self { ca_pem, cert_pem, key_pem: key.serialize_pem() }.to_text())
    }

    /// The file's text: a comment saying what it is, then the three PEM blocks.
    pub fn to_text(&self) -> String {
        format!(
            "# silrig bridge key {}: both bridges of a run hold this same file (silrig-bridge keygen).\n# It is a \
             secret: whoever has it can join the run. Copy it to the other host over a channel you trust (scp -p)\n\
             # and keep it readable by its owner only (chmod 600).\n{}{}{}",
            self.fingerprint(),
            self.ca_pem,
            self.cert_pem,
            self.key_pem
        )
    }

    /// A key from a file's text: exactly a CA certificate, a certificate and a private key, in that order.
    pub fn from_text(text: &str) -> Result<Self, String> {
        let blocks = pem::parse_many(text).map_err(|e| format!("not a bridge key: {e}"))?;
        let tags: Vec<&str> = blocks.iter().map(|b| b.tag()).collect();
        if tags != BLOCKS {
            return Err(format!(
                "not a bridge key: it holds the PEM blocks {tags:?}, where `silrig-bridge keygen` writes {BLOCKS:?}"
            ));
        }
        // One form whatever wrote the file (rcgen, an editor: line endings differ), so equal keys compare equal.
        let lf = pem::EncodeConfig::new().set_line_ending(pem::LineEnding::LF);
        let [ca, cert, key] = [0, 1, 2].map(|i| pem::encode_config(&blocks[i], lf));
        Ok(Self { ca_pem: ca, cert_pem: cert, key_pem: key })
    }

    /// Read the key from `path`, refused unless only its owner can read it.
    pub fn read(path: &Path) -> Result<Self, BridgeError> {
        let shown = path.display();
        let meta = std::fs::metadata(path)
            .map_err(|e| BridgeError::Key(format!("bridge key {shown}: {e} (make one with `silrig-bridge keygen`)")))?;
        check_owner_only(path, meta.mode())?;
        let text = std::fs::read_to_string(path).map_err(|e| BridgeError::Key(format!("bridge key {shown}: {e}")))?;
        Self::from_text(&text).map_err(|e| BridgeError::Key(format!("bridge key {shown}: {e}")))
    }

    /// The first 8 bytes of the SHA-256 of the bridges' certificate, in hex: equal on both hosts when they hold
    /// the same key (each bridge prints it when it starts).
    pub fn fingerprint(&self) -> String {
        let der = pem::parse(&self.cert_pem).map(|p| p.into_contents()).unwrap_or_default();
        let digest = ring::digest::digest(&ring::digest::SHA256, &der);
        digest.as_ref()[..8].iter().map(|b| format!("{b:02x}")).collect()
    }

    /// Zenoh's settings for mutual TLS with this key, as (key, JSON5 value): the CA as the only anchor of our
    /// own (Zenoh's client adds the web's public roots; see the architecture page), the certificate and key for
    /// both listening and connecting, mutual authentication on, and no check of the peer's name against its
    /// address, which the certificate cannot know.
    pub fn zenoh_settings(&self) -> Vec<(&'static str, String)> {
        use base64::Engine;
        let b64 = |pem: &str| format!("\"{}\"", base64::engine::general_purpose::STANDARD.encode(pem));
        vec![
            ("transport/link/tls/root_ca_certificate_base64", b64(&self.ca_pem)),
            ("transport/link/tls/listen_certificate_base64", b64(&self.cert_pem)),
            ("transport/link/tls/listen_private_key_base64", b64(&self.key_pem)),
            ("transport/link/tls/connect_certificate_base64", b64(&self.cert_pem)),
            ("transport/link/tls/connect_private_key_base64", b64(&self.key_pem)),
            ("transport/link/tls/enable_mtls", "true".into()),
            ("transport/link/tls/verify_name_on_connect", "false".into()),
        ]
    }
}

/// A secret file must be readable by its owner alone, as ssh requires of its keys.
fn check_owner_only(path: &Path, mode: u32) -> Result<(), BridgeError> {
    if mode & 0o077 == 0 {
        return Ok(());
    }
    Err(BridgeError::Key(format!(
        "bridge key {}: its group or others may read it (mode {:o}); it is a secret: `chmod 600 {}`, and make a new \
         one with `silrig-bridge keygen` if others may have read it",
        path.display(),
        mode & 0o777,
        path.display()
    )))
}

/// Write a new key to `path`, owner-only (0600), refusing to overwrite a file there.
pub fn write_new(path: &Path) -> Result<BridgeKey, BridgeError> {
    let key = BridgeKey::generate().map_err(BridgeError::Key)?;
    let shown = path.display();
    let mut file = std::fs::OpenOptions::new().write(true).create_new(true).mode(0o600).open(path).map_err(|e| {
        let hint = if e.kind() == std::io::ErrorKind::AlreadyExists {
            ": a key is never overwritten (the other host may hold it); remove it first, or choose another name"
        } else {
            ""
        };
        BridgeError::Key(format!("writing the bridge key {shown}: {e}{hint}"))
    })?;
    file.write_all(key.to_text().as_bytes())
        .and_then(|()| file.sync_all())
        .map_err(|e| BridgeError::Key(format!("writing the bridge key {shown}: {e}")))?;
    Ok(key)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("silrig-key-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_key_is_written_owner_only_read_back_equal_and_never_overwritten() {
        let dir = temp("write");
        let path = dir.join("lab.key");
        let key = write_new(&path).unwrap();
        assert_eq!(std::fs::metadata(&path).unwrap().mode() & 0o777, 0o600);
        assert_eq!(BridgeKey::read(&path).unwrap(), key);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with(&format!("# silrig bridge key {}:", key.fingerprint())), "{text}");
        let again = write_new(&path).unwrap_err().to_string();
        assert!(again.contains("never overwritten") && again.contains("lab.key"), "{again}");
        assert_eq!(BridgeKey::read(&path).unwrap(), key, "the first key is still there");
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn a_key_others_can_read_is_refused_in_words() {
        let dir = temp("mode");
        let path = dir.join("lab.key");
        write_new(&path).unwrap();
        for mode in [0o640, 0o604, 0o644] {
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).unwrap();
            let e = BridgeKey::read(&path).unwrap_err().to_string();
            assert!(e.contains(&format!("mode {mode:o}")) && e.contains("chmod 600"), "{e}");
        }
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o400)).unwrap();
        assert!(BridgeKey::read(&path).is_ok(), "read-only for its owner is fine");
        let missing = BridgeKey::read(&dir.join("none.key")).unwrap_err().to_string();
        assert!(missing.contains("none.key") && missing.contains("silrig-bridge keygen"), "{missing}");
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn two_keys_differ_and_a_file_that_is_not_a_key_is_named() {
        let (a, b) = (BridgeKey::generate().unwrap(), BridgeKey::generate().unwrap());
        assert_ne!(a.fingerprint(), b.fingerprint());
        assert_eq!(a.fingerprint().len(), 16);
        assert_eq!(BridgeKey::from_text(&a.to_text()).unwrap(), a);
        let cert_only = BridgeKey::from_text(&a.cert_pem).unwrap_err();
        assert!(cert_only.contains("[\"CERTIFICATE\"]") && cert_only.contains("keygen"), "{cert_only}");
        assert!(BridgeKey::from_text("hello").unwrap_err().starts_with("not a bridge key"));
        assert!(!format!("{a:?}").contains("PRIVATE"), "the key stays out of debug prints");
    }

    #[test]
    fn zenoh_takes_the_key_s_settings() {
        let key = BridgeKey::generate().unwrap();
        let mut config = zenoh::Config::default();
        for (k, v) in key.zenoh_settings() {
            config.insert_json5(k, &v).unwrap_or_else(|e| panic!("{k}: {e}"));
        }
    }
}
