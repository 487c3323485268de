//! libFuzzer on `droidctl::fuzzing::session_core`: what it checks and the input's layout are
//! documented there (the same harness runs on stable in its unit test).

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| droidctl::fuzzing::session_core::run_input(data));
