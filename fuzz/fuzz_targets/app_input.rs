//! libFuzzer on `droidctl::fuzzing::app_input`: what it checks and the input's layout are
//! documented there (the same harness runs on stable in `tests/it/fuzz_smoke.rs` and, as a
//! property test, in `tests/it/safety.rs`).

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| droidctl::fuzzing::app_input::run_input(data));
