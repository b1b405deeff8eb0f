//! The client options of a connection to the broker, from [`MqttConfig`]: TLS files, the
//! credentials, keep-alive, packet sizes. The files are read here, once, at start-up; one that
//! cannot be read, or is not what its key needs, is a configuration error naming the key.

use rumqttc::{MqttOptions, TlsConfiguration, Transport};
use std::path::Path;

use crate::daemon::config::mqtt::MqttConfig;
use crate::daemon::config::ConfigError;

/// Largest MQTT packet sent or received, bytes (a model line is a few KiB; a samples batch
/// up to [`super::SAMPLES_BATCH_BYTES`]).
pub const MAX_PACKET: usize = 1 << 20;

/// A file of the configuration that cannot be used.
fn bad_file(key: &'static str, path: &Path, why: String) -> ConfigError {
    ConfigError::File {
        key,
        path: path.to_path_buf(),
        reason: why,
    }
}

/// Reads a PEM file whose blocks include `label` (`CERTIFICATE`, `PRIVATE KEY`).
fn pem(key: &'static str, path: &Path, label: &str) -> Result<Vec<u8>, ConfigError> {
    let bytes =
        std::fs::read(path).map_err(|e| bad_file(key, path, format!("cannot read: {e}")))?;
    let text = String::from_utf8_lossy(&bytes);
    let found = text
        .lines()
        .any(|l| l.starts_with("-----BEGIN ") && l.contains(label) && l.ends_with("-----"));
    if !found {
        return Err(bad_file(
            key,
            path,
            format!("a PEM file with a {label} block"),
        ));
    }
    Ok(bytes)
}

/// The password: the first line of the file, which others may not read.
fn password(path: &Path) -> Result<String, ConfigError> {
    use std::os::unix::fs::PermissionsExt;
    let key = "publish.mqtt_password_file";
    let meta =
        std::fs::metadata(path).map_err(|e| bad_file(key, path, format!("cannot read: {e}")))?;
    if meta.permissions().mode() & 0o007 != 0 {
        return Err(bad_file(
            key,
            path,
            "a file others cannot read or write (chmod o-rwx)".into(),
        ));
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| bad_file(key, path, format!("cannot read: {e}")))?;
    let line = text.lines().next().unwrap_or("");
    if line.is_empty() {
        return Err(bad_file(
            key,
            path,
            "a file whose first line is the password".into(),
        ));
    }
    Ok(line.to_string())
}

/// The options of a client `client_id` for `cfg`'s broker (files read now).
pub fn client_options(cfg: &MqttConfig, client_id: &str) -> Result<MqttOptions, ConfigError> {
    let mut o = MqttOptions::new(client_id, cfg.broker.host.clone(), cfg.broker.port);
    o.set_keep_alive(cfg.keep_alive);
    o.set_max_packet_size(MAX_PACKET, MAX_PACKET);
    if cfg.broker.tls {
        let ca = match &cfg.ca {
            Some(p) => pem("publish.mqtt_ca", p, "CERTIFICATE")?,
            None => Vec::new(),
        };
        let client_auth = match &cfg.client_auth {
            Some((cert, key)) => Some((
                pem("publish.mqtt_cert", cert, "CERTIFICATE")?,
                pem("publish.mqtt_key", key, "PRIVATE KEY")?,
            )),
            None => None,
        };
        o.set_transport(Transport::Tls(TlsConfiguration::Simple {
            ca,
            alpn: None,
            client_auth,
        }));
    }
    if let Some(user) = &cfg.username {
        let pw = match &cfg.password_file {
            Some(p) => password(p)?,
            None => String::new(),
        };
        o.set_credentials(user.clone(), pw);
    }
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::Config;
    use std::os::unix::fs::PermissionsExt;

    fn cfg(extra: &str) -> MqttConfig {
        Config::parse(
            &format!("[publish]\nmqtt = \"mqtts://127.0.0.1:8884\"\nstand = \"s\"\n{extra}"),
            "t",
        )
        .unwrap()
        .publish
        .mqtt
        .unwrap()
    }

    #[test]
    fn files_are_read_and_refused_by_key() {
        let dir = tempfile::tempdir().unwrap();
        let ca = dir.path().join("ca.pem");
        let e = client_options(&cfg(&format!("mqtt_ca = {:?}\n", ca)), "c").unwrap_err();
        assert!(e.to_string().contains("publish.mqtt_ca") && e.to_string().contains("cannot read"));
        std::fs::write(&ca, "not a certificate\n").unwrap();
        let e = client_options(&cfg(&format!("mqtt_ca = {:?}\n", ca)), "c").unwrap_err();
        assert!(e.to_string().contains("CERTIFICATE block"), "{e}");
        std::fs::write(
            &ca,
            "-----BEGIN CERTIFICATE-----\nAAAA\n-----END CERTIFICATE-----\n",
        )
        .unwrap();
        assert!(client_options(&cfg(&format!("mqtt_ca = {:?}\n", ca)), "c").is_ok());
        let key = dir.path().join("key.pem");
        std::fs::write(&key, "-----BEGIN CERTIFICATE-----\n").unwrap();
        let e = client_options(
            &cfg(&format!(
                "mqtt_ca = {ca:?}\nmqtt_cert = {ca:?}\nmqtt_key = {key:?}\n"
            )),
            "c",
        )
        .unwrap_err();
        assert!(e.to_string().contains("publish.mqtt_key"), "{e}");
    }

    #[test]
    fn the_password_file_is_private_and_its_first_line_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let pw = dir.path().join("pw");
        std::fs::write(&pw, "s3cret\nignored\n").unwrap();
        std::fs::set_permissions(&pw, std::fs::Permissions::from_mode(0o644)).unwrap();
        let ca = dir.path().join("ca.pem");
        std::fs::write(&ca, "-----BEGIN CERTIFICATE-----\n").unwrap();
        let c = cfg(&format!(
            "mqtt_ca = {ca:?}\nmqtt_username = \"u\"\nmqtt_password_file = {pw:?}\n"
        ));
        let e = client_options(&c, "c").unwrap_err();
        assert!(e.to_string().contains("publish.mqtt_password_file"), "{e}");
        std::fs::set_permissions(&pw, std::fs::Permissions::from_mode(0o600)).unwrap();
        let o = client_options(&c, "c").unwrap();
        let login = o.credentials().unwrap();
        assert_eq!(
            (login.username.as_str(), login.password.as_str()),
            ("u", "s3cret")
        );
    }
}
