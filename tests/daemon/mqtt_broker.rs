//! A real Mosquitto broker for the MQTT tests (Debian's `mosquitto` and `mosquitto-clients`,
//! installed by scripts/test.sh): started on a free loopback port with its own persistence
//! file, killed when dropped; subscribers are `mosquitto_sub` processes whose messages arrive
//! on a channel.

#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

use crate::daemon_proc::KillOnDrop;

/// The broker's binary (in /usr/sbin, not always on a user's PATH).
fn mosquitto() -> &'static str {
    if Path::new("/usr/sbin/mosquitto").exists() {
        "/usr/sbin/mosquitto"
    } else {
        "mosquitto"
    }
}

/// Started as root, Mosquitto drops to the user `mosquitto`, who cannot read the test's
/// private directory: it stays root (the option does nothing for another user).
const USER: &str = "user root\n";

/// A free loopback port (bound, then released for the broker).
pub fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A Mosquitto broker on `127.0.0.1:port`, persistent (its sessions and retained messages
/// survive a restart), anonymous.
pub struct Broker {
    pub port: u16,
    dir: PathBuf,
    child: Option<KillOnDrop>,
}

impl Broker {
    /// Starts a broker on a free port, its files in `dir`.
    pub fn start(dir: &Path) -> Broker {
        let mut b = Broker {
            port: free_port(),
            dir: dir.to_path_buf(),
            child: None,
        };
        b.restart();
        b
    }

    /// `mqtt://127.0.0.1:PORT`.
    pub fn url(&self) -> String {
        format!("mqtt://127.0.0.1:{}", self.port)
    }

    /// Starts the broker (again) on its port and waits until it accepts connections.
    pub fn restart(&mut self) {
        let conf = self.dir.join("mosquitto.conf");
        std::fs::write(
            &conf,
            format!(
                "{}listener {} 127.0.0.1\nallow_anonymous true\npersistence true\n\
                 persistence_location {}/\npersistence_file mosquitto.db\nlog_dest stderr\n\
                 log_type error\nlog_type warning\n",
                USER,
                self.port,
                self.dir.display()
            ),
        )
        .unwrap();
        let child = Command::new(mosquitto())
            .arg("-c")
            .arg(&conf)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| {
                panic!("cannot start mosquitto ({e}): scripts/test.sh installs Debian's mosquitto")
            });
        self.child = Some(KillOnDrop(child));
        let t = Instant::now();
        while TcpStream::connect(("127.0.0.1", self.port)).is_err() {
            assert!(
                t.elapsed() < Duration::from_secs(10),
                "mosquitto did not start"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Stops the broker as an operator would (SIGTERM: it saves its persistence file) and
    /// waits for its exit.
    pub fn stop(&mut self) {
        if let Some(mut c) = self.child.take() {
            crate::daemon_proc::signal(c.0.id(), libc::SIGTERM);
            let status = crate::daemon_proc::wait_exit(&mut c.0, 10.0);
            assert!(status.is_some(), "mosquitto did not stop");
        }
    }
}

/// One message as a subscriber got it.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    pub topic: String,
    pub payload: String,
}

/// A `mosquitto_sub` process printing `topic payload` lines.
pub struct Subscriber {
    child: KillOnDrop,
    rx: Receiver<Message>,
    /// Every message received so far (by [`Subscriber::wait_for`] and [`Subscriber::drain`]).
    pub got: Vec<Message>,
}

impl Subscriber {
    /// Subscribes to `filters` at QoS 1; `session`: a persistent session of that client id
    /// (messages published while it is away are kept for it).
    pub fn start(broker: &Broker, filters: &[&str], session: Option<&str>) -> Subscriber {
        let mut cmd = Command::new("mosquitto_sub");
        cmd.args([
            "-h",
            "127.0.0.1",
            "-p",
            &broker.port.to_string(),
            "-q",
            "1",
            "-v",
        ]);
        for f in filters {
            cmd.args(["-t", f]);
        }
        if let Some(id) = session {
            cmd.args(["-c", "-i", id]);
        }
        Subscriber::spawn(cmd)
    }

    fn spawn(mut cmd: Command) -> Subscriber {
        let mut child: Child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("mosquitto_sub (Debian's mosquitto-clients; scripts/test.sh installs it)");
        let out = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines() {
                let Ok(l) = l else { return };
                let (topic, payload) = l.split_once(' ').unwrap_or((&l, ""));
                let m = Message {
                    topic: topic.to_string(),
                    payload: payload.to_string(),
                };
                if tx.send(m).is_err() {
                    return;
                }
            }
        });
        Subscriber {
            child: KillOnDrop(child),
            rx,
            got: Vec::new(),
        }
    }

    /// Waits for a message matching `pred` (panics after `secs`).
    pub fn wait_for(&mut self, secs: f64, pred: impl Fn(&Message) -> bool) -> Message {
        let end = Instant::now() + Duration::from_secs_f64(secs);
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(m) => {
                    self.got.push(m.clone());
                    if pred(&m) {
                        return m;
                    }
                }
                Err(_) => panic!("no matching message within {secs} s; got {:#?}", self.got),
            }
        }
    }

    /// Takes what arrives until nothing has come for `quiet_s`.
    pub fn drain(&mut self, quiet_s: f64) -> &[Message] {
        while let Ok(m) = self.rx.recv_timeout(Duration::from_secs_f64(quiet_s)) {
            self.got.push(m);
        }
        &self.got
    }

    /// The process id (to stop it).
    pub fn id(&self) -> u32 {
        self.child.0.id()
    }
}

/// The retained messages of `filters` as a subscriber that connects now gets them
/// (`mosquitto_sub --retained-only`, ended after a second without messages).
pub fn retained(broker: &Broker, filters: &[&str]) -> Vec<Message> {
    let mut cmd = Command::new("mosquitto_sub");
    cmd.args([
        "-h",
        "127.0.0.1",
        "-p",
        &broker.port.to_string(),
        "-q",
        "1",
        "-v",
        "--retained-only",
        "-W",
        "2",
    ]);
    for f in filters {
        cmd.args(["-t", f]);
    }
    let mut s = Subscriber::spawn(cmd);
    s.drain(2.5).to_vec()
}

/// Files of a throw-away PKI made with `openssl`: a CA, a server certificate for 127.0.0.1
/// and a client certificate, each key beside it (PEM, P-256).
pub struct Pki {
    pub ca: PathBuf,
    pub server: (PathBuf, PathBuf),
    pub client: (PathBuf, PathBuf),
}

fn openssl(dir: &Path, args: &[&str]) {
    let out = Command::new("openssl")
        .args(args)
        .current_dir(dir)
        .output()
        .expect("openssl");
    assert!(
        out.status.success(),
        "openssl {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Makes the PKI in `dir`.
pub fn pki(dir: &Path) -> Pki {
    let ec = [
        "-newkey",
        "ec",
        "-pkeyopt",
        "ec_paramgen_curve:P-256",
        "-nodes",
    ];
    let mut a = vec!["req", "-x509"];
    a.extend(ec);
    a.extend([
        "-keyout",
        "ca.key",
        "-out",
        "ca.pem",
        "-days",
        "2",
        "-subj",
        "/CN=propid test CA",
    ]);
    openssl(dir, &a);
    for (name, ext) in [
        ("server", "subjectAltName=IP:127.0.0.1\n"),
        ("client", "extendedKeyUsage=clientAuth\n"),
    ] {
        let mut a = vec!["req"];
        a.extend(ec);
        let (key, csr, pem, extf) = (
            format!("{name}.key"),
            format!("{name}.csr"),
            format!("{name}.pem"),
            format!("{name}.ext"),
        );
        std::fs::write(dir.join(&extf), ext).unwrap();
        let subj = format!("/CN={name}");
        a.extend(["-keyout", &key, "-out", &csr, "-subj", &subj]);
        openssl(dir, &a);
        openssl(
            dir,
            &[
                "x509",
                "-req",
                "-in",
                &csr,
                "-CA",
                "ca.pem",
                "-CAkey",
                "ca.key",
                "-CAcreateserial",
                "-out",
                &pem,
                "-days",
                "2",
                "-extfile",
                &extf,
            ],
        );
    }
    Pki {
        ca: dir.join("ca.pem"),
        server: (dir.join("server.pem"), dir.join("server.key")),
        client: (dir.join("client.pem"), dir.join("client.key")),
    }
}

impl Broker {
    /// A broker with a plain listener (for the test's subscribers) and a TLS one on
    /// `tls_port` that requires a client certificate of `pki`'s CA.
    pub fn start_tls(dir: &Path, pki: &Pki) -> (Broker, u16) {
        let port = free_port();
        let tls_port = free_port();
        let conf = dir.join("mosquitto.conf");
        std::fs::write(
            &conf,
            format!(
                "{USER}per_listener_settings false\nallow_anonymous true\n\
                 listener {port} 127.0.0.1\n\
                 listener {tls_port} 127.0.0.1\ncafile {}\ncertfile {}\nkeyfile {}\n\
                 require_certificate true\n",
                pki.ca.display(),
                pki.server.0.display(),
                pki.server.1.display()
            ),
        )
        .unwrap();
        let child = Command::new(mosquitto())
            .arg("-c")
            .arg(&conf)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("mosquitto");
        let b = Broker {
            port,
            dir: dir.to_path_buf(),
            child: Some(KillOnDrop(child)),
        };
        let t = Instant::now();
        while TcpStream::connect(("127.0.0.1", tls_port)).is_err()
            || TcpStream::connect(("127.0.0.1", port)).is_err()
        {
            assert!(
                t.elapsed() < Duration::from_secs(10),
                "mosquitto did not start"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        (b, tls_port)
    }
}
