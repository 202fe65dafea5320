//! A real DVL installation as a user calibrates it, one test binary: known answers of
//! the installation model, the study end to end (sharded, resumed, swept, compared), the
//! operator's `calibrate` and `correct`, the clock found again on each dive, the
//! intervals' coverage, the learned DCNets and the A-KIT recordings. One module a topic;
//! the helpers, and the synthetic recordings of a known installation
//! (`common::installed`), in `tests/common/`.

#[path = "../common/mod.rs"]
mod common;

mod acceptance;
mod blackout;
mod browser;
mod bags;
mod bag_fixes;
mod between_dives;
mod coverage;
mod dive_clock;
mod dvl_logs;
mod fix_coverage;
mod fix_joint;
mod fix_latency;
mod fixes;
mod installation;
mod installation_compare;
mod installation_study;
mod installation_sweep;
mod learned;
mod operator;
mod nmea_reference;
mod paired_recordings;
mod report;
