//! The daemon's link without I/O: bytes and frames in, placed samples and frames out.
//!
//! - [`csv_link`]: a CSV bench made to look like a TSP/1 device (frames, pulse flags, ACKs).
//! - [`tracker`]: a live stream's samples placed by the wire crate's `SampleAssembler`
//!   (gaps, duplicates, boots, segments announced once).
//! - [`wire`]: the link's wire format, detected from the first bytes or configured: TSP/1
//!   frames decoded, or a CSV bench through [`csv_link`].

pub mod csv_link;
pub mod tracker;
pub mod wire;
