//! The application library without the binary: file ingest, the simulator and the reader agreeing.

mod ingest_csv_files;
mod protocol_ingest;
mod protocol_ingest_sim;
mod sim_interop;
