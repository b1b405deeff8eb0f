//! Run statistics: what the final `"stats"` line reports.
//!
//! The sampler owns the link-side counters (frames, drops by kind, samples, gaps, overflows,
//! reconnects); the worker owns the identification counters. Both are plain structs moved back
//! to the thread that publishes the final line, so no counter is shared or locked while running.

use serde::Serialize;
use std::collections::BTreeMap;

/// Link-side counters, kept by the sampler.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LinkStats {
    /// Wire format of the link: `"tsp"`, `"csv"` or `"undecided"` (no byte arrived).
    pub wire: String,
    /// Frames that decoded (lines, for a CSV link).
    pub frames_ok: u64,
    /// Frames dropped, one count per kind of drop (names from the protocol decoder).
    pub frames_dropped: BTreeMap<String, u64>,
    /// Empty frames (two 0x00 delimiters in a row; a stream of zero bytes is all of them):
    /// ignored by the protocol, published when there is one.
    #[serde(skip_serializing_if = "is_zero")]
    pub empty_frames: u64,
    /// Bytes received.
    pub bytes: u64,
    /// SAMPLE frames received.
    pub samples: u64,
    /// Samples the device took but we never received (from `sample_index` jumps, any cause).
    pub samples_lost: u64,
    /// Gaps (index jumps) seen.
    pub gaps: u64,
    /// Of those, gaps longer than the largest one masked (ingest's `max_gap_samples`): each
    /// ended its segment instead of being bridged.
    pub large_gaps: u64,
    /// Items the sampler could not queue to the worker (queue full).
    pub overflows: u64,
    /// Successful reconnects after a disconnection or a stall.
    pub reconnects: u64,
    /// Stalls: the link open but silent (no data, no ACK) for `device.stall_timeout_ms`, each
    /// a `link_stalled` warning (published when there was one).
    #[serde(skip_serializing_if = "is_zero")]
    pub stalls: u64,
    /// Times the 32-bit device clock wrapped.
    pub clock_wraps: u64,
    /// SAMPLE frames dropped as duplicates (same `sample_index` as the previous one).
    pub duplicates: u64,
    /// Bytes of the raw recording the OS accepted, over every file (only with a recording:
    /// below `bytes` after a write failure).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record_bytes_written: Option<u64>,
    /// Bytes received that the recording dropped because it fell behind (a pipe whose reader
    /// stalled, a slow disk: [`super::recorder`]), or that it had not written when the run
    /// ended (only with a recording).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record_bytes_dropped: Option<u64>,
}

/// For `skip_serializing_if`: counters published only when they counted something.
fn is_zero(v: &u64) -> bool {
    *v == 0
}

/// Worker-side counters.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct WorkStats {
    /// Models published.
    pub models: u64,
    /// Identifications that failed (each published as a warning).
    pub identify_errors: u64,
    /// Models that failed the quality checks ([`super::quality`]), published as
    /// `model_unreliable` warnings instead of models.
    pub models_unreliable: u64,
    /// Pulses seen (EVENT IMPULSE_START).
    pub pulses: u64,
    /// `segment` lines published: device segments as the sampler's tracker announces them
    /// ([`super::tracker`], "Announcing": each boot's HELLO, else the first sample after the
    /// index went back or a gap too long to mask, or of a stream without HELLO), counted where
    /// the line is published so that the two always agree (a reset with no sample after it
    /// included; an item lost to a full queue is in neither, but in `overflows`).
    pub segments: u64,
    /// Windows a device reset (a new segment) closed before their K pulses, each a
    /// `window_interrupted` warning (published when there was one).
    #[serde(skip_serializing_if = "is_zero")]
    pub windows_interrupted: u64,
    /// `clock_jump` warnings (present when there was one).
    #[serde(skip_serializing_if = "is_zero")]
    pub clock_jumps: u64,
}

/// The final `"stats"` line (its `"type"` is written by [`super::line::Line::Stats`]).
#[derive(Debug, Clone, Serialize)]
pub struct StatsLine<'a> {
    /// Link counters, flattened into the line.
    #[serde(flatten)]
    pub link: &'a LinkStats,
    /// Worker counters, flattened into the line.
    #[serde(flatten)]
    pub work: &'a WorkStats,
    /// Socket clients dropped for falling behind.
    pub dropped_clients: u64,
    /// Socket and web-page clients refused: `publish.max_clients` were connected, or (web
    /// page) its connection cap was reached (only with a socket or a web page).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clients_refused: Option<u64>,
    /// The MQTT sink's counters (only with `[publish] mqtt`).
    #[serde(flatten)]
    pub mqtt: Option<MqttStats>,
    /// Wall-clock duration of the run, seconds.
    pub elapsed_s: f64,
    /// Latency from a window's last sample to its published model line.
    pub latency_s: Latency,
}

/// The MQTT sink's counters ([`super::mqtt`]), in the stats line with `[publish] mqtt`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct MqttStats {
    /// Messages handed to the MQTT client (its bounded queue).
    pub mqtt_published: u64,
    /// Of those, not yet delivered when the line was made (QoS 1 not yet acknowledged, QoS 0
    /// not yet written): waiting for the broker.
    pub mqtt_queued: u64,
    /// Messages dropped: the queue was full (the broker away or slow for long), or live
    /// samples while the broker was away.
    pub mqtt_dropped: u64,
    /// Connections to the broker after the first.
    pub mqtt_reconnects: u64,
}

/// Quantiles of the latencies, s (`null` without models).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Latency {
    /// Median.
    #[serde(with = "propid_numerics::nullable::num")]
    pub p50: f64,
    /// 99th percentile.
    #[serde(with = "propid_numerics::nullable::num")]
    pub p99: f64,
}

impl<'a> StatsLine<'a> {
    /// The line for these counters and the sorted latencies.
    pub fn new(
        link: &'a LinkStats,
        work: &'a WorkStats,
        dropped_clients: u64,
        elapsed_s: f64,
        sorted_latencies_s: &[f64],
    ) -> Self {
        StatsLine {
            link,
            work,
            dropped_clients,
            clients_refused: None,
            mqtt: None,
            elapsed_s,
            latency_s: Latency {
                p50: quantile(sorted_latencies_s, 0.5),
                p99: quantile(sorted_latencies_s, 0.99),
            },
        }
    }
}

/// The `q`-quantile of sorted values (nearest rank), NaN when empty.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() as f64 - 1.0) * q.clamp(0.0, 1.0)).round() as usize;
    sorted[i]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::line::Line;

    #[test]
    fn stats_line_has_the_public_fields() {
        let mut link = LinkStats {
            frames_ok: 10,
            samples: 8,
            samples_lost: 2,
            overflows: 1,
            reconnects: 3,
            large_gaps: 1,
            ..Default::default()
        };
        link.frames_dropped.insert("crc_error".into(), 4);
        let work = WorkStats::default();
        let line = StatsLine::new(&link, &work, 0, 1.5, &[]);
        let v: serde_json::Value =
            serde_json::from_str(&Line::Stats(&line).to_json().unwrap()).unwrap();
        assert_eq!(v["type"], "stats");
        assert_eq!(v["frames_ok"], 10);
        assert_eq!(v["frames_dropped"]["crc_error"], 4);
        assert_eq!(v["samples"], 8);
        assert_eq!(v["samples_lost"], 2);
        assert_eq!(v["overflows"], 1);
        assert_eq!(v["reconnects"], 3);
        assert_eq!(v["large_gaps"], 1);
    }

    /// The bytes of the stats line as the daemon has always published them (keys sorted).
    #[test]
    fn stats_line_bytes_are_pinned() {
        let mut link = LinkStats {
            wire: "tsp".into(),
            frames_ok: 10,
            bytes: 300,
            samples: 8,
            ..Default::default()
        };
        link.frames_dropped.insert("crc_error".into(), 4);
        let work = WorkStats {
            models: 2,
            pulses: 4,
            ..Default::default()
        };
        let line = StatsLine::new(&link, &work, 1, 1.5, &[0.25, 0.5, 0.75]);
        assert_eq!(
            Line::Stats(&line).to_json().unwrap(),
            r#"{"bytes":300,"clock_wraps":0,"dropped_clients":1,"duplicates":0,"elapsed_s":1.5,"frames_dropped":{"crc_error":4},"frames_ok":10,"gaps":0,"identify_errors":0,"large_gaps":0,"latency_s":{"p50":0.5,"p99":0.75},"models":2,"models_unreliable":0,"overflows":0,"pulses":4,"reconnects":0,"samples":8,"samples_lost":0,"segments":0,"type":"stats","wire":"tsp"}"#
        );
        let none = StatsLine::new(&link, &work, 1, 1.5, &[]);
        let text = Line::Stats(&none).to_json().unwrap();
        assert!(
            text.contains(r#""latency_s":{"p50":null,"p99":null}"#),
            "{text}"
        );
    }

    /// With `[publish] mqtt`, the sink's counters join the line (absent without).
    #[test]
    fn mqtt_counters_are_flattened_in() {
        let (link, work) = (LinkStats::default(), WorkStats::default());
        let mut line = StatsLine::new(&link, &work, 0, 1.0, &[]);
        let text = Line::Stats(&line).to_json().unwrap();
        assert!(!text.contains("mqtt"), "{text}");
        line.mqtt = Some(MqttStats {
            mqtt_published: 5,
            mqtt_queued: 1,
            mqtt_dropped: 2,
            mqtt_reconnects: 3,
        });
        let v: serde_json::Value =
            serde_json::from_str(&Line::Stats(&line).to_json().unwrap()).unwrap();
        assert_eq!(
            (
                &v["mqtt_published"],
                &v["mqtt_queued"],
                &v["mqtt_dropped"],
                &v["mqtt_reconnects"]
            ),
            (&5.into(), &1.into(), &2.into(), &3.into())
        );
    }

    #[test]
    fn quantiles_by_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(quantile(&v, 0.5), 51.0);
        assert_eq!(quantile(&v, 0.99), 99.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
