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
    /// Successful reconnects after a disconnection.
    pub reconnects: u64,
    /// Device boots seen (distinct `boot_id`s in a row).
    pub segments: u64,
    /// Times the 32-bit device clock wrapped.
    pub clock_wraps: u64,
    /// SAMPLE frames dropped as duplicates (same `sample_index` as the previous one).
    pub duplicates: u64,
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
}

/// The final `"stats"` line.
#[derive(Debug, Clone, Serialize)]
pub struct StatsLine<'a> {
    /// Always `"stats"`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// Link counters, flattened into the line.
    #[serde(flatten)]
    pub link: &'a LinkStats,
    /// Worker counters, flattened into the line.
    #[serde(flatten)]
    pub work: &'a WorkStats,
    /// Socket clients dropped for falling behind.
    pub dropped_clients: u64,
    /// Wall-clock duration of the run, seconds.
    pub elapsed_s: f64,
}

impl<'a> StatsLine<'a> {
    /// The line for these counters.
    pub fn new(
        link: &'a LinkStats,
        work: &'a WorkStats,
        dropped_clients: u64,
        elapsed_s: f64,
    ) -> Self {
        StatsLine {
            kind: "stats",
            link,
            work,
            dropped_clients,
            elapsed_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let v: serde_json::Value =
            serde_json::to_value(StatsLine::new(&link, &work, 0, 1.5)).unwrap();
        assert_eq!(v["type"], "stats");
        assert_eq!(v["frames_ok"], 10);
        assert_eq!(v["frames_dropped"]["crc_error"], 4);
        assert_eq!(v["samples"], 8);
        assert_eq!(v["samples_lost"], 2);
        assert_eq!(v["overflows"], 1);
        assert_eq!(v["reconnects"], 3);
        assert_eq!(v["large_gaps"], 1);
    }
}
