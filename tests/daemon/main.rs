//! The daemon end to end: the real binary against the simulated stand on a pty, recordings replayed, faults forced.

mod browser;
mod daemon_csv_placement;
mod daemon_e2e;
mod daemon_e2e_gaps;
mod daemon_http;
mod daemon_live;
mod daemon_mqtt;
mod daemon_proc;
mod daemon_rate;
mod daemon_replay;
mod demo_http;
mod host_faults;
mod http_hostile;
mod kinds;
mod limits;
mod link_faults;
mod lying_stand;
mod mqtt_broker;
