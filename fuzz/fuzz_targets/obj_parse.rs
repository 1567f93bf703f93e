//! OBJ parsing on arbitrary bytes (see `tests/fuzz_checks` for the properties checked).
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzz_checks::obj_parse(data));
