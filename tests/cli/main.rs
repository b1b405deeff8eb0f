//! The propid binary's subcommands run as a user runs them: identify, diagnose, demo, sim, walkthrough.

mod demo_cli;
mod diagnose_cli;
mod diagnose_injected;
mod diagnose_input_lead;
mod diagnose_model_keys;
mod diagnose_outliers;
mod diagnose_rejected;
mod diagnose_sim;
mod diagnose_staircase;
mod host_faults_cli;
mod identify_cli;
mod identify_dialects;
mod identify_encodings;
mod identify_gain;
mod identify_held;
mod identify_interpolated;
mod identify_quality;
mod identify_real_data;
mod identify_sim_recording;
mod identify_slow_logs;
mod identify_square_hankel;
mod identify_stabilization;
mod identify_units;
mod sim_cli;
mod support;
mod walkthrough_cli;
