//! The MQTT topics of a stand: the one place their names are spelled (the daemon publishes
//! them, `propid fleet` subscribes to them). docs/mqtt.md lists them with their QoS and
//! retain flags.

/// Every topic starts with this level.
pub const ROOT: &str = "propid";

/// The `status` payload while the daemon is connected (retained).
pub const ONLINE: &str = "online";

/// The `status` payload after it ended, cleanly or not (retained; the will).
pub const OFFLINE: &str = "offline";

/// One stand's topic of a kind, parsed from a topic name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Topic<'a> {
    /// `propid/<stand>/status`: `online` / `offline`.
    Status,
    /// `propid/<stand>/model`: each model line.
    Model,
    /// `propid/<stand>/event`: each event and warning line.
    Event,
    /// `propid/<stand>/stats`: the stats line at the end of a run.
    Stats,
    /// `propid/<stand>/samples`: batches of live samples lines.
    Samples,
    /// `propid/<stand>/schedule/<level>`: the last model line of an operating point.
    Schedule(&'a str),
}

/// The topic names of one stand.
#[derive(Debug, Clone)]
pub struct StandTopics {
    /// `propid/<stand>/status`.
    pub status: String,
    /// `propid/<stand>/model`.
    pub model: String,
    /// `propid/<stand>/event`.
    pub event: String,
    /// `propid/<stand>/stats`.
    pub stats: String,
    /// `propid/<stand>/samples`.
    pub samples: String,
    prefix: String,
}

impl StandTopics {
    /// The topics of `stand` (a valid stand name).
    pub fn new(stand: &str) -> StandTopics {
        let prefix = format!("{ROOT}/{stand}/");
        StandTopics {
            status: format!("{prefix}status"),
            model: format!("{prefix}model"),
            event: format!("{prefix}event"),
            stats: format!("{prefix}stats"),
            samples: format!("{prefix}samples"),
            prefix,
        }
    }

    /// `propid/<stand>/schedule/<level>`.
    pub fn schedule(&self, level: u32) -> String {
        format!("{}schedule/{level}", self.prefix)
    }
}

/// The subscriptions of `propid fleet`: every stand's topics (`+` is any stand).
pub fn fleet_filters() -> [&'static str; 6] {
    [
        "propid/+/status",
        "propid/+/model",
        "propid/+/event",
        "propid/+/stats",
        "propid/+/samples",
        "propid/+/schedule/+",
    ]
}

/// The stand and the kind of a topic name, when it is one of a stand's.
pub fn parse(topic: &str) -> Option<(&str, Topic<'_>)> {
    let rest = topic.strip_prefix(ROOT)?.strip_prefix('/')?;
    let (stand, kind) = rest.split_once('/')?;
    if stand.is_empty() {
        return None;
    }
    let kind = match kind {
        "status" => Topic::Status,
        "model" => Topic::Model,
        "event" => Topic::Event,
        "stats" => Topic::Stats,
        "samples" => Topic::Samples,
        k => {
            let level = k.strip_prefix("schedule/")?;
            if level.is_empty() || !level.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            Topic::Schedule(level)
        }
    };
    Some((stand, kind))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_their_parse() {
        let t = StandTopics::new("bench-1");
        assert_eq!(t.status, "propid/bench-1/status");
        assert_eq!(t.model, "propid/bench-1/model");
        assert_eq!(t.event, "propid/bench-1/event");
        assert_eq!(t.stats, "propid/bench-1/stats");
        assert_eq!(t.samples, "propid/bench-1/samples");
        assert_eq!(t.schedule(2), "propid/bench-1/schedule/2");
        assert_eq!(parse(&t.model), Some(("bench-1", Topic::Model)));
        assert_eq!(
            parse(&t.schedule(12)),
            Some(("bench-1", Topic::Schedule("12")))
        );
        assert_eq!(parse(&t.status), Some(("bench-1", Topic::Status)));
        for bad in [
            "propid",
            "propid//model",
            "other/a/model",
            "propid/a/what",
            "propid/a/schedule/",
            "propid/a/schedule/x",
            "propid/a/model/x",
        ] {
            assert_eq!(parse(bad), None, "{bad}");
        }
    }
}
