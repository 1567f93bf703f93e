//! Mesh queries (exact, distance, self-intersection, ADB) on arbitrary small meshes and poses
//! (see `tests/fuzz_checks` for the properties checked).
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

libfuzzer_sys::fuzz_target!(|input: fuzz_checks::MeshQueryInput| {
    fuzz_checks::mesh_query(&input)
});
