//! The experiments of the DCNet paper as a user meets them, one test binary: the command
//! line, the spec's checks, the pipeline's caching, resuming, sharding and sweeps, the
//! figures and reports, and what a damaged or killed run leaves. One module a topic;
//! the helpers in `tests/common/`. A refusal's message is an insta snapshot in
//! `snapshots/` (`experiment__<module>__<name>.snap`).

#[path = "../common/mod.rs"]
mod common;

mod adversarial;
mod bad_specs;
mod calibration_time;
mod cli;
mod compare;
mod paper;
mod pipeline;
mod plots;
mod recordings;
mod replicates;
mod spec_properties;
