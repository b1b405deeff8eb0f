//! The wire crate's integration tests, one binary: the TSP/1 decoder and the CSV dialect.

mod protocol_csv;
mod protocol_decoder;
