//! droidctl's integration tests, one binary (issue 42 point 4): each area is a module here,
//! `tests/it/AREA.rs`, with the helpers they share in `common/`. One binary, not one per
//! file: each test binary links the whole library (Boa, btleplug, D-Bus, ratatui), and
//! sixty-nine of them made `cargo test` mostly linking (docs/performance.md, "Building the
//! tests"). Run one area with `cargo test --test it AREA::`.
//!
//! All of these tests are threads of one process, run in parallel: a test here must not
//! change what the process shares (environment variables, the working directory, signal
//! dispositions, the global allocator, its children as a whole): it passes what it needs to
//! the library or to the `droidctl` it starts. A test that cannot lives in a binary of its
//! own beside this one (tests/edu_engine.rs kills its own engine children by reading this
//! process's children; tests/capture_memory.rs counts allocations with its own global
//! allocator); `layout::only_the_binaries_that_need_a_process_of_their_own` keeps it to those.

mod common;

mod app_loop;
mod app_robots;
mod ble_cli;
mod ble_link;
mod ble_scan;
mod bridge_cli;
mod bridge_hostile;
mod bridge_integrators;
mod bridge_mqtt;
mod bridge_ros;
mod bridge_schema;
mod bridge_shared_broker;
mod bridge_topics;
mod capture_cli;
mod capture_replay;
mod circles;
mod cli_completions;
mod cli_config;
mod cli_errors;
mod cli_models;
mod cli_packet;
mod cli_packet_families;
mod cli_packet_stream;
mod cli_run;
mod cli_run_robi;
mod cli_run_robots;
mod cli_run_v1;
mod docs_commands;
mod e2e_pty;
mod edu_app;
mod edu_app_status;
mod edu_charger;
mod edu_field;
mod edu_infrared;
mod edu_programs;
mod edu_runtime;
mod edu_spherov2;
mod edu_twins;
mod examples;
mod exit_status;
mod failsafe;
mod fleet_app;
mod fleet_mission;
mod fuzz_smoke;
mod gamepad;
mod hints;
mod layering;
mod layout;
mod lowering;
mod man_pages;
mod monitoring;
mod monitoring_app;
mod no_bluetooth;
mod output_files;
mod picker;
mod plot_inputs;
mod realtime;
mod relay_e2e;
mod relay_protocol;
mod relay_server;
mod rsrcp;
mod rsrcp_props;
mod run_outputs;
mod safety;
mod serial;
mod serial_sdk;
mod session;
mod setup_retry;
mod shutdown;
mod sim;
mod sim_bluez;
mod sim_models;
mod sim_robi;
mod sim_v1;
mod smoke_session;
mod soak;
mod sphero_unsw;
mod spherov2_catalogue;
mod teleop_robi;
mod theme;
mod trace_json;
mod ui_context;
mod ui_program;
mod ui_robots;
mod ui_snapshots;
mod v1_props;
mod v1_vectors;
mod v2_props;
mod v2_vectors;
