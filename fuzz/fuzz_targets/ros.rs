//! libFuzzer on `droidctl::fuzzing::ros`: what it checks and the input's layout are
//! documented there (the same harness runs on stable in `tests/it/fuzz_smoke.rs`).

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| droidctl::fuzzing::ros::run_input(data));
