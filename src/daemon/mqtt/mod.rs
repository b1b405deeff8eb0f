//! The MQTT sink (`[publish] mqtt`): the published lines, and the stand's status, on a
//! broker's topics `propid/<stand>/...` ([`topics`]; docs/mqtt.md), and the fleet page's
//! subscriber ([`fleet`]).
//!
//! - **Never in the daemon's way.** The client is `rumqttc` (its synchronous `Client` and
//!   `Connection`; no protocol code here). Its connection runs on its own thread
//!   (`propid-mqtt`), which reconnects with a back-off. [`MqttSink::send`], on the worker's
//!   thread like every sink, only offers a message to the client's bounded queue
//!   (`try_publish`): a broker that is down, slow or restarted never blocks the worker, and the
//!   sampler never sees the sink. While the broker is away, up to `mqtt_queue_messages`
//!   messages wait (sent when it returns); more are dropped and counted (`mqtt_dropped`).
//!   Live samples are not queued while it is away (dropped and counted: stale on return).
//! - **At least once.** Models, events, warnings, the stats line and the status are QoS 1, in a
//!   persistent session (`clean_session = false`, client id `propid-<stand>`): a message the
//!   broker has not acknowledged is sent again after a reconnect, so a subscriber may see a
//!   model twice (its `t_s` and `first_sample` tell), never zero times while the daemon lives.
//! - **Status.** `online` (retained) at every connection; the will `offline` (retained) for an
//!   unclean end; `offline` published at a clean one ([`MqttSink::close`]).
//! - **Schedule.** Each model also goes, retained, to `propid/<stand>/schedule/<level>`: the
//!   last model of each operating point. The sink keeps them and sends them again at every
//!   connection, with the last stats line, so a broker restarted without persistence has them
//!   again.
//! - **Samples** (`mqtt_samples = true` only): the web page's `samples` lines, batched (one
//!   message holds the lines of at least [`SAMPLES_PERIOD`], newline-separated), QoS 0.

pub mod fleet;
pub mod options;
pub use propid_session::topics;

use crossbeam_channel::{bounded, Receiver};
use rumqttc::{Client, Event, Incoming, LastWill, Outgoing, QoS};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::config::mqtt::MqttConfig;
use super::line::Line;
use super::stats::MqttStats;
use super::DaemonError;
use topics::StandTopics;

/// At most one samples message per this long (10 per second).
pub const SAMPLES_PERIOD: Duration = Duration::from_millis(100);

/// Largest samples message, bytes: lines beyond it are dropped and counted.
pub const SAMPLES_BATCH_BYTES: usize = 512 * 1024;

/// How long [`MqttSink::close`] waits for the queue to empty and the `offline` status to be
/// acknowledged, at most.
const CLOSE_WAIT: Duration = Duration::from_secs(3);

/// Longest wait between two connection attempts.
const BACKOFF_MAX: Duration = Duration::from_secs(2);

/// Counters shared with the connection thread.
#[derive(Default)]
struct Counters {
    connected: AtomicBool,
    closing: AtomicBool,
    /// Messages handed to the client.
    accepted: AtomicU64,
    /// Messages done: QoS 0 written, QoS 1 acknowledged.
    done: AtomicU64,
    dropped: AtomicU64,
    reconnects: AtomicU64,
}

/// What is sent again at every connection (retained topics).
#[derive(Default)]
struct Retained {
    /// Per operating point number, its last model line.
    schedule: Vec<(u32, Arc<str>)>,
    /// The last stats line.
    stats: Option<Arc<str>>,
}

/// The MQTT sink of a [`super::Publisher`].
pub struct MqttSink {
    client: Client,
    topics: StandTopics,
    counters: Arc<Counters>,
    retained: Arc<Mutex<Retained>>,
    samples: Option<Batch>,
    broker: String,
    ended: Receiver<()>,
}

/// Samples lines waiting for their message.
struct Batch {
    text: String,
    last_sent: Instant,
}

impl MqttSink {
    /// Starts the client and its connection thread (the files of the configuration are read
    /// now; the broker need not be up).
    pub fn start(cfg: &MqttConfig) -> Result<MqttSink, DaemonError> {
        let topics = StandTopics::new(&cfg.stand);
        let mut opts = options::client_options(cfg, &format!("propid-{}", cfg.stand))?;
        opts.set_clean_session(false);
        opts.set_last_will(LastWill::new(
            &topics.status,
            topics::OFFLINE,
            QoS::AtLeastOnce,
            true,
        ));
        let (client, connection) = Client::new(opts, cfg.queue_messages);
        let counters = Arc::new(Counters::default());
        let retained = Arc::new(Mutex::new(Retained::default()));
        let (done_tx, ended) = bounded(1);
        let pump = Pump {
            client: client.clone(),
            topics: topics.clone(),
            counters: counters.clone(),
            retained: retained.clone(),
            broker: cfg.broker.display(),
        };
        std::thread::Builder::new()
            .name("propid-mqtt".into())
            .spawn(move || {
                pump.run(connection);
                let _ = done_tx.send(());
            })
            .map_err(|e| DaemonError::io("spawn the mqtt thread", e))?;
        Ok(MqttSink {
            client,
            topics,
            counters,
            retained,
            samples: cfg.samples.then(|| Batch {
                text: String::new(),
                last_sent: Instant::now(),
            }),
            broker: cfg.broker.display(),
            ended,
        })
    }

    /// The broker, as `mqtt://HOST:PORT`.
    pub fn broker(&self) -> &str {
        &self.broker
    }

    /// Whether live samples are published (the worker then builds them).
    pub fn wants_samples(&self) -> bool {
        self.samples.is_some()
    }

    /// Offers `line` (serialised as `text`) to the broker's topics; never waits.
    pub fn send(&mut self, line: &Line<'_>, text: &str) {
        match line {
            Line::Model(m) => {
                self.offer(&self.topics.model, QoS::AtLeastOnce, false, text);
                let level = m.window.level;
                let topic = self.topics.schedule(level);
                self.offer(&topic, QoS::AtLeastOnce, true, text);
                if let Ok(mut r) = self.retained.lock() {
                    let text: Arc<str> = Arc::from(text);
                    match r.schedule.iter_mut().find(|e| e.0 == level) {
                        Some(e) => e.1 = text,
                        None => r.schedule.push((level, text)),
                    }
                }
            }
            // an experiment kind's results go with the events (no topic of their own yet)
            Line::Event(_) | Line::Warning(_) | Line::Kind(_) => {
                self.offer(&self.topics.event, QoS::AtLeastOnce, false, text)
            }
            Line::Stats(_) => {
                self.offer(&self.topics.stats, QoS::AtLeastOnce, true, text);
                if let Ok(mut r) = self.retained.lock() {
                    r.stats = Some(Arc::from(text));
                }
            }
            Line::Samples(_) => self.batch_samples(text),
            // the final schedule is on the retained schedule topics; the rest is the web page's
            Line::Schedule(_) | Line::LiveStats(_) | Line::Response(_) | Line::Stabilization(_) => {
            }
        }
    }

    fn batch_samples(&mut self, text: &str) {
        let connected = self.counters.connected.load(Ordering::Relaxed);
        let Some(b) = self.samples.as_mut() else {
            return;
        };
        if !connected || b.text.len() + text.len() + 1 > SAMPLES_BATCH_BYTES {
            self.counters.dropped.fetch_add(1, Ordering::Relaxed);
            return;
        }
        if !b.text.is_empty() {
            b.text.push('\n');
        }
        b.text.push_str(text);
        if b.last_sent.elapsed() >= SAMPLES_PERIOD {
            self.flush_samples();
        }
    }

    fn flush_samples(&mut self) {
        let Some(b) = self.samples.as_mut() else {
            return;
        };
        if b.text.is_empty() {
            return;
        }
        b.last_sent = Instant::now();
        let text = std::mem::take(&mut b.text);
        let topic = self.topics.samples.clone();
        self.offer(&topic, QoS::AtMostOnce, false, &text);
    }

    fn offer(&self, topic: &str, qos: QoS, retain: bool, text: &str) {
        match self
            .client
            .try_publish(topic, qos, retain, text.as_bytes().to_vec())
        {
            Ok(()) => self.counters.accepted.fetch_add(1, Ordering::Relaxed),
            Err(_) => self.counters.dropped.fetch_add(1, Ordering::Relaxed),
        };
    }

    /// The counters for the stats line.
    pub fn stats(&self) -> MqttStats {
        let c = &self.counters;
        let accepted = c.accepted.load(Ordering::Relaxed);
        MqttStats {
            mqtt_published: accepted,
            mqtt_queued: accepted.saturating_sub(c.done.load(Ordering::Relaxed)),
            mqtt_dropped: c.dropped.load(Ordering::Relaxed),
            mqtt_reconnects: c.reconnects.load(Ordering::Relaxed),
        }
    }

    /// A clean end: the samples left, `offline` (retained), then waits up to [`CLOSE_WAIT`]
    /// for the queue to be delivered, and disconnects (the will is not sent).
    pub fn close(mut self) {
        self.flush_samples();
        let topic = self.topics.status.clone();
        self.offer(&topic, QoS::AtLeastOnce, true, topics::OFFLINE);
        let end = Instant::now() + CLOSE_WAIT;
        while Instant::now() < end
            && self.counters.connected.load(Ordering::Relaxed)
            && self.stats().mqtt_queued > 0
        {
            std::thread::sleep(Duration::from_millis(10));
        }
        self.counters.closing.store(true, Ordering::Relaxed);
        let _ = self.client.try_disconnect();
        // the thread ends at the disconnect, or at its next failed attempt
        let left = end.saturating_duration_since(Instant::now());
        let _ = self
            .ended
            .recv_timeout(left.max(Duration::from_millis(200)));
    }
}

/// The connection thread's state.
struct Pump {
    client: Client,
    topics: StandTopics,
    counters: Arc<Counters>,
    retained: Arc<Mutex<Retained>>,
    broker: String,
}

impl Pump {
    /// Drives the connection until the sink closes: counts what is delivered, publishes
    /// `online` and the retained lines at every connection, waits between failed attempts.
    fn run(self, mut connection: rumqttc::Connection) {
        let mut backoff = Duration::from_millis(100);
        let mut connections = 0u64;
        let mut down_reported = false;
        for event in connection.iter() {
            let c = &self.counters;
            match event {
                Ok(Event::Incoming(Incoming::ConnAck(ack))) => {
                    if ack.code != rumqttc::ConnectReturnCode::Success {
                        eprintln!(
                            "propid: mqtt: {} refused the connection: {:?}",
                            self.broker, ack.code
                        );
                        continue;
                    }
                    c.connected.store(true, Ordering::Relaxed);
                    if connections > 0 {
                        c.reconnects.fetch_add(1, Ordering::Relaxed);
                        eprintln!("propid: mqtt: connected to {} again", self.broker);
                    }
                    connections += 1;
                    backoff = Duration::from_millis(100);
                    down_reported = false;
                    self.announce();
                }
                Ok(Event::Incoming(Incoming::PubAck(_))) => {
                    c.done.fetch_add(1, Ordering::Relaxed);
                }
                Ok(Event::Outgoing(Outgoing::Publish(0))) => {
                    // QoS 0 (packet id 0): done once written
                    c.done.fetch_add(1, Ordering::Relaxed);
                }
                Ok(Event::Outgoing(Outgoing::Disconnect)) => {
                    c.connected.store(false, Ordering::Relaxed);
                    if c.closing.load(Ordering::Relaxed) {
                        return;
                    }
                }
                Ok(_) => {}
                Err(e) => {
                    c.connected.store(false, Ordering::Relaxed);
                    if c.closing.load(Ordering::Relaxed) {
                        return;
                    }
                    if !down_reported {
                        eprintln!(
                            "propid: mqtt: {}: {e}; retrying (messages queue meanwhile)",
                            self.broker
                        );
                        down_reported = true;
                    }
                    std::thread::sleep(backoff);
                    backoff = (backoff * 2).min(BACKOFF_MAX);
                }
            }
        }
    }

    /// `online` and the retained lines, at every connection (a broker restarted without
    /// persistence has them again).
    fn announce(&self) {
        let c = &self.counters;
        let offer = |topic: &str, text: &[u8]| {
            match self
                .client
                .try_publish(topic, QoS::AtLeastOnce, true, text.to_vec())
            {
                Ok(()) => c.accepted.fetch_add(1, Ordering::Relaxed),
                Err(_) => c.dropped.fetch_add(1, Ordering::Relaxed),
            };
        };
        offer(&self.topics.status, topics::ONLINE.as_bytes());
        let Ok(r) = self.retained.lock() else {
            return;
        };
        for (level, text) in &r.schedule {
            offer(&self.topics.schedule(*level), text.as_bytes());
        }
        if let Some(s) = &r.stats {
            offer(&self.topics.stats, s.as_bytes());
        }
    }
}
