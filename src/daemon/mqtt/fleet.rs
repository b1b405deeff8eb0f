//! What `propid fleet` knows of every stand, from the broker's messages ([`super::topics`]):
//! status, phase, latest model, gain schedule, recent warnings, last stats. No I/O: each
//! message goes through [`Fleet::apply`], which says what the stand's own page gets; the
//! fleet page's line is [`Fleet::summary`].
//!
//! The phase is read from the event lines as the live page reads it (`assets/web/app.js`):
//! `connected` → handshake done, `arm_acknowledged` → armed, `level_reached` / `level_done`,
//! `plan_finished`, a STOP acknowledged → stopped. The gain-schedule rows a stand's page
//! draws are the model lines' fields of [`crate::daemon::line::ScheduleRow`], picked from the
//! retained `schedule/<level>` models.

use serde_json::{json, Map, Value};
use std::collections::{BTreeMap, VecDeque};

use super::topics::{self, Topic};
use crate::daemon::config::mqtt::is_stand_name;
use crate::daemon::http::Kind;

/// Most stands followed; messages of more are ignored and counted.
pub const MAX_STANDS: usize = 1_024;

/// Warning lines kept per stand.
pub const WARNINGS_KEPT: usize = 8;

/// The fields of a schedule row, as the model line has them ([`crate::daemon::line::ScheduleRow`]).
const ROW_FIELDS: [&str; 8] = [
    "operating_point",
    "order",
    "fn_hz",
    "zeta",
    "dc_gain",
    "time_constants_s",
    "pulses",
    "uncertainty",
];

/// One stand, as its messages tell.
#[derive(Debug, Default)]
struct Stand {
    /// `online`, `offline`, or empty before its status arrived.
    status: String,
    phase: String,
    model: Option<Value>,
    /// Per operating point number, its retained last model.
    schedule: BTreeMap<u64, Value>,
    warnings: VecDeque<Value>,
    stats: Option<Value>,
    /// Model messages received.
    models: u64,
}

/// Every stand seen.
#[derive(Debug, Default)]
pub struct Fleet {
    stands: BTreeMap<String, Stand>,
    /// Messages ignored: not JSON where a line is due, a bad stand name, past [`MAX_STANDS`].
    pub ignored: u64,
}

/// What one message changes: the stand, and the lines its page gets.
#[derive(Debug, PartialEq)]
pub struct Applied {
    /// The stand's name.
    pub stand: String,
    /// Lines for the stand's page, with how its history keeps them.
    pub lines: Vec<(Kind, String)>,
}

impl Fleet {
    /// Takes one message of topic `topic`.
    pub fn apply(&mut self, topic: &str, payload: &[u8]) -> Option<Applied> {
        let Some((name, kind)) = topics::parse(topic) else {
            self.ignored += 1;
            return None;
        };
        if !is_stand_name(name)
            || (!self.stands.contains_key(name) && self.stands.len() >= MAX_STANDS)
        {
            self.ignored += 1;
            return None;
        }
        let Ok(text) = std::str::from_utf8(payload) else {
            self.ignored += 1;
            return None;
        };
        let stand = self.stands.entry(name.to_string()).or_default();
        let mut lines = Vec::new();
        match kind {
            Topic::Status => {
                if text != topics::ONLINE && text != topics::OFFLINE {
                    self.ignored += 1;
                    return None;
                }
                if text == topics::ONLINE && stand.status == topics::OFFLINE {
                    stand.phase.clear(); // a new run
                }
                stand.status = text.to_string();
            }
            Topic::Samples => {
                for l in text.lines().filter(|l| !l.is_empty()) {
                    lines.push((Kind::Samples, l.to_string()));
                }
            }
            _ => {
                let Ok(v) = serde_json::from_str::<Value>(text) else {
                    self.ignored += 1;
                    return None;
                };
                match kind {
                    Topic::Model => {
                        stand.models += 1;
                        stand.model = Some(v);
                        lines.push((Kind::State("model"), text.to_string()));
                    }
                    Topic::Event => {
                        if v["type"] == "warning" {
                            if stand.warnings.len() == WARNINGS_KEPT {
                                stand.warnings.pop_front();
                            }
                            stand.warnings.push_back(v.clone());
                        } else if let Some(p) = phase(&v) {
                            stand.phase = p;
                        }
                        lines.push((Kind::Log, text.to_string()));
                    }
                    Topic::Stats => {
                        stand.stats = Some(v);
                        lines.push((Kind::State("stats"), text.to_string()));
                    }
                    Topic::Schedule(level) => {
                        let Ok(level) = level.parse::<u64>() else {
                            self.ignored += 1;
                            return None;
                        };
                        stand.schedule.insert(level, v);
                        let line = json!({"type": "schedule", "models": rows(stand)});
                        lines.push((Kind::State("schedule"), line.to_string()));
                    }
                    Topic::Status | Topic::Samples => {}
                }
            }
        }
        Some(Applied {
            stand: name.to_string(),
            lines,
        })
    }

    /// The fleet page's line: `{"type":"fleet","stands":[{"stand","status","phase","model",
    /// "schedule","warnings","models","stats"}, ...]}`, stands by name.
    pub fn summary(&self) -> Value {
        let stands: Vec<Value> = self
            .stands
            .iter()
            .map(|(name, s)| {
                json!({
                    "stand": name,
                    "status": if s.status.is_empty() { "unknown" } else { s.status.as_str() },
                    "phase": s.phase,
                    "model": s.model,
                    "schedule": rows(s),
                    "warnings": s.warnings,
                    "models": s.models,
                    "stats": s.stats,
                })
            })
            .collect();
        json!({"type": "fleet", "stands": stands, "ignored": self.ignored})
    }

    /// The stands' names.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.stands.keys().map(String::as_str)
    }
}

/// The schedule rows of a stand, by operating point.
fn rows(s: &Stand) -> Vec<Value> {
    let mut rows: Vec<Value> = s
        .schedule
        .values()
        .map(|m| {
            let mut row = Map::new();
            for k in ROW_FIELDS {
                row.insert(k.to_string(), m.get(k).cloned().unwrap_or(Value::Null));
            }
            Value::Object(row)
        })
        .collect();
    rows.sort_by(|a, b| {
        let op = |v: &Value| v["operating_point"].as_f64().unwrap_or(f64::NAN);
        op(a).total_cmp(&op(b))
    });
    rows
}

/// The phase an event line starts, if it starts one.
fn phase(v: &Value) -> Option<String> {
    let op = |v: &Value| {
        v["operating_point"]
            .as_f64()
            .map_or("?".to_string(), |x| format!("{x:.3}"))
    };
    Some(match v["kind"].as_str()? {
        "connected" => "handshake done".into(),
        "csv_link" => "CSV link".into(),
        "arm_acknowledged" => "armed".into(),
        "level_reached" => format!("level {} ({}): pulses", v["index"], op(v)),
        "level_done" => format!("level {} done", v["index"]),
        "plan_finished" => "plan finished".into(),
        "stop_acknowledged" | "shutdown_stop_acknowledged" => "stopped".into(),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(level: u32, op: f64, gain: f64) -> String {
        json!({"type": "model", "level": level, "operating_point": op, "order": 2,
               "fn_hz": 25.0, "zeta": 0.5, "dc_gain": gain, "time_constants_s": [],
               "pulses": 4, "uncertainty": null, "t_s": 1.0})
        .to_string()
    }

    #[test]
    fn status_phase_model_schedule_and_warnings() {
        let mut f = Fleet::default();
        assert!(f
            .apply("propid/a/status", b"online")
            .unwrap()
            .lines
            .is_empty());
        f.apply(
            "propid/a/event",
            br#"{"type":"event","kind":"level_reached","index":1,"operating_point":0.45}"#,
        )
        .unwrap();
        let a = f
            .apply("propid/a/model", model(1, 0.45, 8.0).as_bytes())
            .unwrap();
        assert_eq!(a.stand, "a");
        assert_eq!(a.lines[0].0, Kind::State("model"));
        f.apply("propid/a/schedule/1", model(1, 0.45, 8.0).as_bytes());
        let a = f
            .apply("propid/a/schedule/0", model(0, 0.3, 7.0).as_bytes())
            .unwrap();
        let sched: Value = serde_json::from_str(&a.lines[0].1).unwrap();
        assert_eq!(sched["type"], "schedule");
        assert_eq!(sched["models"][0]["dc_gain"], 7.0);
        assert_eq!(sched["models"][1]["operating_point"], 0.45);
        assert!(sched["models"][0].get("t_s").is_none());
        f.apply(
            "propid/a/event",
            br#"{"type":"warning","kind":"link_stalled","silent_ms":1000}"#,
        );
        f.apply("propid/b/status", b"offline");
        let s = f.summary();
        assert_eq!(s["type"], "fleet");
        let a = &s["stands"][0];
        assert_eq!(a["stand"], "a");
        assert_eq!(a["status"], "online");
        assert_eq!(a["phase"], "level 1 (0.450): pulses");
        assert_eq!(a["model"]["dc_gain"], 8.0);
        assert_eq!(a["models"], 1);
        assert_eq!(a["schedule"].as_array().unwrap().len(), 2);
        assert_eq!(a["warnings"][0]["kind"], "link_stalled");
        assert_eq!(s["stands"][1]["status"], "offline");
        assert_eq!(f.names().collect::<Vec<_>>(), ["a", "b"]);
    }

    #[test]
    fn samples_batches_are_split_into_lines() {
        let mut f = Fleet::default();
        let a = f
            .apply(
                "propid/a/samples",
                b"{\"type\":\"samples\",\"n\":1}\n{\"type\":\"samples\",\"n\":2}",
            )
            .unwrap();
        assert_eq!(a.lines.len(), 2);
        assert!(a.lines.iter().all(|l| l.0 == Kind::Samples));
    }

    #[test]
    fn bad_messages_are_counted_not_kept() {
        let mut f = Fleet::default();
        assert!(f.apply("propid/a/model", b"not json").is_none());
        assert!(f.apply("propid/a/status", b"maybe").is_none());
        assert!(f.apply("propid/a b/status", b"online").is_none());
        assert!(f.apply("propid/a/schedule/x", b"{}").is_none());
        assert!(f.apply("other/a/model", b"{}").is_none());
        assert_eq!(f.ignored, 5);
        // a stand was created by the first two (its name is fine), with nothing known
        assert_eq!(f.summary()["stands"][0]["status"], "unknown");
    }

    #[test]
    fn a_new_run_clears_the_phase() {
        let mut f = Fleet::default();
        f.apply("propid/a/status", b"online");
        f.apply(
            "propid/a/event",
            br#"{"type":"event","kind":"plan_finished"}"#,
        );
        f.apply("propid/a/status", b"offline");
        assert_eq!(f.summary()["stands"][0]["phase"], "plan finished");
        f.apply("propid/a/status", b"online");
        assert_eq!(f.summary()["stands"][0]["phase"], "");
    }
}
