//! `propid fleet --mqtt URL [--config F] [--http ADDR]`: one page listing every stand that
//! publishes to the broker (`propid/+/...`, [`crate::daemon::mqtt::topics`]), online or
//! offline, with its phase, latest model, gain schedule and warnings; each stand opens the
//! single-stand page (`/stand/NAME/`) fed from the broker.
//!
//! The broker's TLS files and credentials come from `--config`'s `[publish]` keys (never from
//! the command line); `--mqtt` overrides `publish.mqtt`. The page is served on the loopback
//! unless another interface is written out, as the live page ([`super::http_arg`]). Runs until
//! Ctrl-C / SIGTERM.

use crossbeam_channel::{bounded, RecvTimeoutError};
use rumqttc::{Client, Event, Incoming, QoS};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use super::CliError;
use crate::daemon::config::mqtt::{BrokerUrl, MqttConfig};
use crate::daemon::config::ConfigError;
use crate::daemon::http::assets::{self, Asset};
use crate::daemon::http::site::Site;
use crate::daemon::http::{HttpSink, Kind};
use crate::daemon::mqtt::fleet::Fleet;
use crate::daemon::mqtt::{options, topics};
use crate::daemon::Shutdown;

/// Arguments of `propid fleet`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The broker: mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (overrides `publish.mqtt`).
    #[arg(long, value_name = "URL", value_parser = broker_arg)]
    pub mqtt: Option<BrokerUrl>,
    /// Configuration file whose `[publish]` mqtt keys give the broker, its CA, the client
    /// certificate and key, the user name and the password file.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Serve the page on ADDR (a port or `:PORT`: 127.0.0.1 only; another interface only when
    /// its address is given, e.g. `0.0.0.0:8080`; port 0: any free port, printed).
    #[arg(long, value_name = "ADDR", value_parser = super::http_arg, default_value = "8080")]
    pub http: std::net::SocketAddr,
}

fn broker_arg(text: &str) -> Result<BrokerUrl, String> {
    BrokerUrl::parse(text).ok_or_else(|| {
        format!("{text:?}: mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (no credentials in the URL)")
    })
}

/// The fleet page's line is sent at most this often.
const SUMMARY_EVERY: Duration = Duration::from_millis(250);

/// Lines queued per browser of a stand's page (samples come at 10 batches a second).
const QUEUE_LINES: usize = 1_024;

/// Browsers per stream.
const MAX_CLIENTS: usize = 64;

/// The fleet page's files: its own page at `/`, the live page at `/stand/NAME/`, their
/// scripts and styles.
fn asset(path: &str) -> Option<Asset> {
    const HTML: &str = "text/html; charset=utf-8";
    let own = |content_type, body| Some(Asset { content_type, body });
    match path {
        "/" | "/index.html" => own(HTML, include_bytes!("../../assets/web/fleet.html")),
        "/fleet.js" => own(
            "text/javascript; charset=utf-8",
            include_bytes!("../../assets/web/fleet.js"),
        ),
        "/fleet.css" => own(
            "text/css; charset=utf-8",
            include_bytes!("../../assets/web/fleet.css"),
        ),
        p => match stand_page(p) {
            Some(_) => assets::get("/"),
            None => assets::get(p),
        },
    }
}

/// `/stand/NAME/` → NAME.
fn stand_page(path: &str) -> Option<&str> {
    path.strip_prefix("/stand/")?
        .strip_suffix('/')
        .filter(|n| !n.contains('/'))
}

/// `/stand/NAME/events` → NAME.
fn stand_stream(path: &str) -> Option<&str> {
    path.strip_prefix("/stand/")?
        .strip_suffix("/events")
        .filter(|n| !n.contains('/'))
}

/// The fleet page's site.
pub const SITE: Site = Site {
    asset,
    stream: stand_stream,
};

/// The broker settings: `--config`'s, with `--mqtt`'s broker.
fn mqtt_config(args: &Args) -> Result<MqttConfig, CliError> {
    let from_file = match &args.config {
        Some(p) => crate::daemon::Config::load(p)?.publish.mqtt,
        None => None,
    };
    let cfg = match (from_file, &args.mqtt) {
        (Some(m), None) => m,
        (Some(m), Some(url)) => m.with_broker(url.clone())?,
        (None, Some(url)) => MqttConfig::plain(url.clone()),
        (None, None) => {
            return Err(ConfigError::OutOfRange {
                key: "publish.mqtt",
                value: "\"\"".into(),
                expected: "a broker for propid fleet (or --mqtt URL)",
            }
            .into())
        }
    };
    Ok(cfg)
}

/// Runs `propid fleet`.
pub fn run(args: Args) -> Result<(), CliError> {
    let cfg = mqtt_config(&args)?;
    let shutdown = Shutdown::install()?;
    let mut opts = options::client_options(&cfg, &format!("propid-fleet-{}", std::process::id()))?;
    opts.set_clean_session(true);
    let sink = HttpSink::bind_site(args.http, QUEUE_LINES, MAX_CLIENTS, SITE)?;
    eprintln!(
        "propid: the fleet page of {} is at {}",
        cfg.broker.display(),
        sink.url()
    );
    let (client, mut connection) = Client::new(opts, 64);
    let (tx, rx) = bounded::<(String, Vec<u8>)>(4_096);
    let broker = cfg.broker.display();
    std::thread::Builder::new()
        .name("propid-fleet-mqtt".into())
        .spawn(move || {
            let mut reported = false;
            for event in connection.iter() {
                match event {
                    Ok(Event::Incoming(Incoming::ConnAck(_))) => {
                        reported = false;
                        for f in topics::fleet_filters() {
                            let qos = if f.ends_with("/samples") {
                                QoS::AtMostOnce
                            } else {
                                QoS::AtLeastOnce
                            };
                            let _ = client.try_subscribe(f, qos);
                        }
                    }
                    Ok(Event::Incoming(Incoming::Publish(p))) => {
                        if tx.send((p.topic, p.payload.to_vec())).is_err() {
                            return;
                        }
                    }
                    Ok(_) => {}
                    Err(e) => {
                        if !reported {
                            eprintln!("propid: mqtt: {broker}: {e}; retrying");
                            reported = true;
                        }
                        std::thread::sleep(Duration::from_millis(500));
                    }
                }
            }
        })
        .map_err(|e| CliError::io("spawn the mqtt thread", e))?;
    let mut fleet = Fleet::default();
    let mut dirty = true;
    let mut last_summary = Instant::now() - SUMMARY_EVERY;
    while !shutdown.requested() {
        match rx.recv_timeout(Duration::from_millis(50)) {
            Ok((topic, payload)) => {
                if let Some(a) = fleet.apply(&topic, &payload) {
                    for (kind, line) in &a.lines {
                        sink.send_to(&a.stand, *kind, line);
                    }
                    dirty = true;
                }
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
        if dirty && last_summary.elapsed() >= SUMMARY_EVERY {
            sink.send(Kind::State("fleet"), &fleet.summary().to_string());
            dirty = false;
            last_summary = Instant::now();
        }
    }
    sink.close();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_site_maps_stand_pages_and_streams() {
        assert!(asset("/").unwrap().body.starts_with(b"<!doctype html>"));
        let live = assets::get("/").unwrap().body;
        assert_eq!(asset("/stand/bench-1/").unwrap().body, live);
        assert!(asset("/app.js").is_some() && asset("/fleet.js").is_some());
        assert!(asset("/stand/a/b/").is_none());
        assert!(asset("/stand/a").is_none());
        assert_eq!(stand_stream("/stand/bench-1/events"), Some("bench-1"));
        assert_eq!(stand_stream("/stand/a/b/events"), None);
        assert_eq!(stand_stream("/events"), None);
    }
}
