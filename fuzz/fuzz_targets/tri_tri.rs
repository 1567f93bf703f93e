//! Triangle–triangle intersection and closest points on arbitrary floats, NaN and infinity
//! included (see `tests/fuzz_checks` for the properties checked).
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

libfuzzer_sys::fuzz_target!(|input: fuzz_checks::TriTriInput| fuzz_checks::tri_tri(&input));
