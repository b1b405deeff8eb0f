//! The application library without the binary: file ingest, diagnosis on generated cases, the simulator and the reader agreeing.

mod diagnose_detection;
mod diagnose_record;
mod diagnose_verdict;
mod ingest_csv_files;
mod protocol_ingest;
mod protocol_ingest_sim;
mod sim_interop;
