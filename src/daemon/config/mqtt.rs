//! `[publish] mqtt` and its keys, validated: the broker's URL, the stand's name, TLS files and
//! the credentials (docs/mqtt.md). Only paths are kept here; the files are read when the
//! connection starts ([`crate::daemon::mqtt`]), and a file that cannot be read is refused then
//! with its key named, as a configuration error.

use std::path::PathBuf;
use std::time::Duration;

use super::ConfigError;

/// A broker address from `mqtt://HOST[:PORT]` or `mqtts://HOST[:PORT]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BrokerUrl {
    /// Host name or address (an IPv6 address without its brackets).
    pub host: String,
    /// TCP port (1883 for `mqtt://`, 8883 for `mqtts://` when not written).
    pub port: u16,
    /// `mqtts://`: TLS.
    pub tls: bool,
}

impl BrokerUrl {
    /// Parses `mqtt://HOST[:PORT][/]` or `mqtts://...`; no user, password, path or query
    /// (credentials go in `mqtt_username` and `mqtt_password_file`).
    pub fn parse(text: &str) -> Option<BrokerUrl> {
        let (tls, rest) = if let Some(r) = text.strip_prefix("mqtt://") {
            (false, r)
        } else if let Some(r) = text.strip_prefix("mqtts://") {
            (true, r)
        } else {
            return None;
        };
        let rest = rest.strip_suffix('/').unwrap_or(rest);
        if rest.is_empty() || rest.contains(['@', '/', '?', '#', ' ']) {
            return None;
        }
        let default_port = if tls { 8883 } else { 1883 };
        let (host, port) = if let Some(v6) = rest.strip_prefix('[') {
            let (h, after) = v6.split_once(']')?;
            match after {
                "" => (h, None),
                p => (h, Some(p.strip_prefix(':')?)),
            }
        } else {
            match rest.rsplit_once(':') {
                Some((h, p)) if !h.contains(':') => (h, Some(p)),
                Some(_) => return None, // an IPv6 address needs brackets
                None => (rest, None),
            }
        };
        if host.is_empty() {
            return None;
        }
        let port = match port {
            None => default_port,
            Some(p) => p.parse::<u16>().ok().filter(|&p| p > 0)?,
        };
        Some(BrokerUrl {
            host: host.to_string(),
            port,
            tls,
        })
    }

    /// `mqtt://HOST:PORT` (for messages).
    pub fn display(&self) -> String {
        let scheme = if self.tls { "mqtts" } else { "mqtt" };
        if self.host.contains(':') {
            format!("{scheme}://[{}]:{}", self.host, self.port)
        } else {
            format!("{scheme}://{}:{}", self.host, self.port)
        }
    }
}

/// The validated MQTT settings (`[publish] mqtt` and the `mqtt_*` keys, `stand`).
#[derive(Debug, Clone, PartialEq)]
pub struct MqttConfig {
    /// The broker.
    pub broker: BrokerUrl,
    /// The stand's name: the topic level `propid/<stand>/...`.
    pub stand: String,
    /// CA certificate (PEM) the broker's certificate must chain to (`mqtts://` only, needed).
    pub ca: Option<PathBuf>,
    /// Client certificate and key (PEM), both or neither (`mqtts://` only).
    pub client_auth: Option<(PathBuf, PathBuf)>,
    /// User name given to the broker.
    pub username: Option<String>,
    /// File whose first line is the password (needs `username`).
    pub password_file: Option<PathBuf>,
    /// Publish the live samples, batched, on `propid/<stand>/samples` (QoS 0).
    pub samples: bool,
    /// MQTT keep-alive: the broker declares the daemon gone (its will: `offline`) after 1.5×
    /// this without a packet.
    pub keep_alive: Duration,
    /// Messages queued while the broker is away (or slow); more are dropped and counted.
    pub queue_messages: usize,
}

impl MqttConfig {
    /// A plain broker with every default (`propid fleet --mqtt URL` without a file); the
    /// stand's name is unused there.
    pub fn plain(broker: BrokerUrl) -> MqttConfig {
        MqttConfig {
            broker,
            stand: "fleet".into(),
            ca: None,
            client_auth: None,
            username: None,
            password_file: None,
            samples: false,
            keep_alive: Duration::from_secs(10),
            queue_messages: 4_096,
        }
    }

    /// These settings with another broker (`--mqtt` over `publish.mqtt`), checked again: an
    /// `mqtts://` broker needs `mqtt_ca`, TLS files need one.
    pub fn with_broker(self, broker: BrokerUrl) -> Result<MqttConfig, ConfigError> {
        if broker.tls && self.ca.is_none() {
            return Err(refuse(
                "publish.mqtt_ca",
                "",
                "the CA certificate (PEM file) of the mqtts:// broker given by --mqtt",
            ));
        }
        if !broker.tls && (self.ca.is_some() || self.client_auth.is_some()) {
            return Err(refuse(
                "publish.mqtt_ca",
                "set",
                "only with an mqtts:// broker (--mqtt gave mqtt://)",
            ));
        }
        Ok(MqttConfig { broker, ..self })
    }
}

/// The `[publish]` keys of MQTT as written (fields of [`super::RawPublish`]).
#[derive(Debug, Default)]
pub struct RawMqtt {
    /// `mqtt`.
    pub url: Option<String>,
    /// `stand`.
    pub stand: Option<String>,
    /// `mqtt_ca`.
    pub ca: Option<String>,
    /// `mqtt_cert`.
    pub cert: Option<String>,
    /// `mqtt_key`.
    pub key: Option<String>,
    /// `mqtt_username`.
    pub username: Option<String>,
    /// `mqtt_password_file`.
    pub password_file: Option<String>,
    /// `mqtt_samples`.
    pub samples: Option<bool>,
    /// `mqtt_keep_alive_s`.
    pub keep_alive_s: Option<u64>,
    /// `mqtt_queue_messages`.
    pub queue_messages: Option<usize>,
}

/// Longest stand name, characters.
pub const STAND_MAX: usize = 64;

/// Whether `name` is a stand name: 1..=64 of `A-Z a-z 0-9 _ . -` (a topic level without
/// wildcards or separators, and a path segment of the fleet page as it is).
pub fn is_stand_name(name: &str) -> bool {
    (1..=STAND_MAX).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'.' | b'-'))
}

/// The host's name, when it is a stand name (the default `stand`).
fn host_name() -> Option<String> {
    let mut buf = [0 as libc::c_char; 256];
    // SAFETY: the buffer is live and its length given; the result is NUL-terminated on success
    let r = unsafe { libc::gethostname(buf.as_mut_ptr(), buf.len() - 1) };
    if r != 0 {
        return None;
    }
    // SAFETY: NUL-terminated (the last byte was never written)
    let name = unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) };
    let name = name.to_str().ok()?.to_string();
    is_stand_name(&name).then_some(name)
}

fn refuse(key: &'static str, value: &str, expected: &'static str) -> ConfigError {
    ConfigError::OutOfRange {
        key,
        value: format!("{value:?}"),
        expected,
    }
}

/// A key that needs `publish.mqtt`.
fn needs_url(raw: &RawMqtt) -> Option<&'static str> {
    [
        ("publish.mqtt_ca", raw.ca.is_some()),
        ("publish.mqtt_cert", raw.cert.is_some()),
        ("publish.mqtt_key", raw.key.is_some()),
        ("publish.mqtt_username", raw.username.is_some()),
        ("publish.mqtt_password_file", raw.password_file.is_some()),
        ("publish.mqtt_samples", raw.samples.is_some()),
        ("publish.mqtt_keep_alive_s", raw.keep_alive_s.is_some()),
        ("publish.mqtt_queue_messages", raw.queue_messages.is_some()),
    ]
    .into_iter()
    .find(|k| k.1)
    .map(|k| k.0)
}

impl RawMqtt {
    /// Phase 2: `None` without `mqtt` (and then no other `mqtt_*` key may be set).
    pub fn validate(self) -> Result<Option<MqttConfig>, ConfigError> {
        let Some(url) = self.url.clone() else {
            if let Some(key) = needs_url(&self) {
                return Err(refuse(key, "set", "only with publish.mqtt"));
            }
            return Ok(None);
        };
        let broker = BrokerUrl::parse(&url).ok_or_else(|| {
            refuse(
                "publish.mqtt",
                &url,
                "mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (no credentials in the URL: \
                 mqtt_username, mqtt_password_file)",
            )
        })?;
        let stand = match self.stand {
            Some(s) if is_stand_name(&s) => s,
            Some(s) => {
                return Err(refuse(
                    "publish.stand",
                    &s,
                    "1..=64 characters of A-Z a-z 0-9 _ . -",
                ))
            }
            None => host_name().ok_or_else(|| {
                refuse(
                    "publish.stand",
                    "",
                    "a name (the host's name is not one: 1..=64 of A-Z a-z 0-9 _ . -)",
                )
            })?,
        };
        if !broker.tls {
            for (key, set) in [
                ("publish.mqtt_ca", self.ca.is_some()),
                ("publish.mqtt_cert", self.cert.is_some()),
                ("publish.mqtt_key", self.key.is_some()),
            ] {
                if set {
                    return Err(refuse(key, "set", "only with an mqtts:// broker"));
                }
            }
        }
        let ca = self.ca.map(PathBuf::from);
        if broker.tls && ca.is_none() {
            return Err(refuse(
                "publish.mqtt_ca",
                "",
                "the CA certificate (PEM file) the mqtts:// broker's certificate chains to",
            ));
        }
        let client_auth = match (self.cert, self.key) {
            (Some(c), Some(k)) => Some((PathBuf::from(c), PathBuf::from(k))),
            (None, None) => None,
            (Some(_), None) => {
                return Err(refuse("publish.mqtt_key", "", "set with publish.mqtt_cert"))
            }
            (None, Some(_)) => {
                return Err(refuse("publish.mqtt_cert", "", "set with publish.mqtt_key"))
            }
        };
        if self.password_file.is_some() && self.username.is_none() {
            return Err(refuse(
                "publish.mqtt_username",
                "",
                "set with publish.mqtt_password_file",
            ));
        }
        let keep_alive_s = super::range::int_in(
            "publish.mqtt_keep_alive_s",
            self.keep_alive_s.unwrap_or(10),
            5,
            3_600,
            "5..=3600 s",
        )?;
        Ok(Some(MqttConfig {
            broker,
            stand,
            ca,
            client_auth,
            username: self.username,
            password_file: self.password_file.map(PathBuf::from),
            samples: self.samples.unwrap_or(false),
            keep_alive: Duration::from_secs(keep_alive_s),
            queue_messages: super::range::int_in(
                "publish.mqtt_queue_messages",
                self.queue_messages.unwrap_or(4_096),
                16,
                1_048_576,
                "16..=1048576 messages",
            )?,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::Config;

    fn err(text: &str) -> String {
        Config::parse(text, "t").unwrap_err().to_string()
    }

    #[test]
    fn broker_urls() {
        let u = BrokerUrl::parse("mqtt://127.0.0.1:1884").unwrap();
        assert_eq!((u.host.as_str(), u.port, u.tls), ("127.0.0.1", 1884, false));
        let u = BrokerUrl::parse("mqtts://broker.lan/").unwrap();
        assert_eq!((u.host.as_str(), u.port, u.tls), ("broker.lan", 8883, true));
        let u = BrokerUrl::parse("mqtt://[::1]:1883").unwrap();
        assert_eq!((u.host.as_str(), u.port), ("::1", 1883));
        assert_eq!(u.display(), "mqtt://[::1]:1883");
        assert_eq!(BrokerUrl::parse("mqtt://h").unwrap().port, 1883);
        for bad in [
            "",
            "tcp://h:1883",
            "mqtt://",
            "mqtt://user:pw@h:1883",
            "mqtt://h:0",
            "mqtt://h:99999",
            "mqtt://h:1883/topic",
            "mqtt://::1:1883",
            "mqtt://h:x",
            "mqtt://:1883",
        ] {
            assert!(BrokerUrl::parse(bad).is_none(), "{bad}");
        }
    }

    #[test]
    fn off_by_default_and_keys_need_the_url() {
        assert_eq!(Config::default().publish.mqtt, None);
        let e = err("[publish]\nmqtt_samples = true\n");
        assert!(e.contains("publish.mqtt_samples") && e.contains("only with publish.mqtt"));
        let e = err("[publish]\nmqtt_password_file = \"/p\"\n");
        assert!(e.contains("publish.mqtt_password_file"), "{e}");
    }

    #[test]
    fn a_plain_broker_and_its_defaults() {
        let c = Config::parse(
            "[publish]\nmqtt = \"mqtt://127.0.0.1:1884\"\nstand = \"bench-2\"\n",
            "t",
        )
        .unwrap();
        let m = c.publish.mqtt.unwrap();
        assert_eq!(m.stand, "bench-2");
        assert_eq!(m.broker.port, 1884);
        assert!(!m.samples);
        assert_eq!(m.keep_alive, Duration::from_secs(10));
        assert_eq!(m.queue_messages, 4096);
        assert_eq!((m.ca, m.client_auth, m.username), (None, None, None));
    }

    #[test]
    fn bad_values_name_their_key() {
        let base = "[publish]\nmqtt = \"mqtt://h\"\n";
        for (extra, key) in [
            ("stand = \"a/b\"\n", "publish.stand"),
            ("stand = \"+\"\n", "publish.stand"),
            ("stand = \"\"\n", "publish.stand"),
            (
                "stand = \"s\"\nmqtt_keep_alive_s = 1\n",
                "publish.mqtt_keep_alive_s",
            ),
            (
                "stand = \"s\"\nmqtt_queue_messages = 1\n",
                "publish.mqtt_queue_messages",
            ),
            (
                "stand = \"s\"\nmqtt_password_file = \"/p\"\n",
                "publish.mqtt_username",
            ),
            ("stand = \"s\"\nmqtt_ca = \"/ca.pem\"\n", "publish.mqtt_ca"),
        ] {
            let e = err(&format!("{base}{extra}"));
            assert!(e.contains(key), "{extra}: {e}");
        }
        let e = err("[publish]\nmqtt = \"http://h\"\nstand = \"s\"\n");
        assert!(e.contains("publish.mqtt"), "{e}");
        let e = err("[publish]\nmqtt = \"mqtt://u:p@h\"\nstand = \"s\"\n");
        assert!(e.contains("no credentials in the URL"), "{e}");
        let e = err("[publish]\nmqtt_passwd = \"x\"\n");
        assert!(e.contains("mqtt_passwd"), "{e}");
    }

    /// `mqtts://` needs a CA; a client certificate comes with its key; the password is a file.
    #[test]
    fn tls_keys() {
        let base = "[publish]\nmqtt = \"mqtts://h:8884\"\nstand = \"s\"\n";
        let e = err(base);
        assert!(e.contains("publish.mqtt_ca"), "{e}");
        let e = err(&format!("{base}mqtt_ca = \"/ca\"\nmqtt_cert = \"/c\"\n"));
        assert!(e.contains("publish.mqtt_key"), "{e}");
        let e = err(&format!("{base}mqtt_ca = \"/ca\"\nmqtt_key = \"/k\"\n"));
        assert!(e.contains("publish.mqtt_cert"), "{e}");
        let c = Config::parse(
            &format!(
                "{base}mqtt_ca = \"/ca\"\nmqtt_cert = \"/c\"\nmqtt_key = \"/k\"\n\
                 mqtt_username = \"u\"\nmqtt_password_file = \"/pw\"\nmqtt_samples = true\n"
            ),
            "t",
        )
        .unwrap();
        let m = c.publish.mqtt.unwrap();
        assert!(m.broker.tls && m.samples);
        assert_eq!(m.ca, Some(PathBuf::from("/ca")));
        assert_eq!(
            m.client_auth,
            Some((PathBuf::from("/c"), PathBuf::from("/k")))
        );
        assert_eq!(m.username.as_deref(), Some("u"));
        assert_eq!(m.password_file, Some(PathBuf::from("/pw")));
    }

    #[test]
    fn stand_names() {
        assert!(is_stand_name("bench_2.a-b"));
        assert!(!is_stand_name(""));
        assert!(!is_stand_name("a b"));
        assert!(!is_stand_name("#"));
        assert!(!is_stand_name(&"x".repeat(65)));
    }
}
