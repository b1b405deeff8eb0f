//! The CSV fallback of TSP/1 (docs/PROTOCOL.md §6), sans-IO: the one CSV dialect of the project,
//! used by the daemon's CSV link, the simulated CSV bench, recording ingest and the CSV file
//! reader.
//!
//! - [`line`]: lines (`\n`, `\r` ignored, length limit), the `*HH` checksum, comment or data,
//!   the separator and the fields;
//! - [`columns`]: the one alias table (header names of §6 and of exported logs → quantity and
//!   unit, conversion to canonical units) and the one quantity → name table;
//! - [`header`]: a header mapped onto quantities, data rows read through it;
//! - [`decoder`]: [`CsvDecoder`], bytes in, headers / rows / ACKs / comments out;
//! - [`device`]: what a bench writes (rows, `#ACK`, `#EVENT`, `# HELLO`, `# <log>`), written and
//!   read back;
//! - [`command`]: the host's commands (`PING`, `ARM`, `THR`, `IMP`, `STOP`, …), written and
//!   read back.

pub mod columns;
pub mod command;
pub mod decoder;
pub mod device;
pub mod encoding;
pub mod header;
pub mod line;

pub use command::{
    encode_csv_command, parse_csv_command, CsvCommandError, CsvCommandKind, MAX_CSV_COMMAND,
};
pub use decoder::{CsvDecoder, CsvItem, CsvOptions, CsvStats};
pub use device::{device_line, parse_ack, parse_comment, CommentFact, CsvAck};
pub use header::{CsvRow, HeaderMap, MappedColumn, RowError, UnresolvedColumn};
pub use line::{checksum, MAX_LINE};

#[cfg(test)]
mod tests;
