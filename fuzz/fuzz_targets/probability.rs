//! The ADB probability model on arbitrary counts and floats (see `tests/fuzz_checks` for the
//! properties checked).
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

libfuzzer_sys::fuzz_target!(|input: fuzz_checks::ProbabilityInput| {
    fuzz_checks::probability(&input)
});
