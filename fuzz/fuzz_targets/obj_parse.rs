//! OBJ parsing on arbitrary bytes: never panics; an accepted mesh is valid and round-trips
//! through `write_obj`; a refusal is `Malformed` with a line inside the input.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use stochastic_collision::mesh::{MeshError, TriMesh};

fuzz_target!(|data: &[u8]| {
    let name = Path::new("fuzz.obj");
    match TriMesh::from_obj_reader(data, name) {
        Ok(mesh) => {
            assert!(mesh.triangle_count() > 0);
            let n = mesh.vertex_count();
            assert!(mesh.triangles().iter().flatten().all(|&i| (i as usize) < n));
            assert!(mesh.positions().iter().all(|p| p.is_finite()));
            let mut text = Vec::new();
            mesh.write_obj(&mut text).unwrap();
            let back = TriMesh::from_obj_reader(text.as_slice(), name).unwrap();
            assert_eq!(back, mesh);
        }
        Err(MeshError::Malformed {
            path,
            line,
            message,
        }) => {
            assert_eq!(path, name);
            let lines = data.split(|&b| b == b'\n').count();
            assert!(line <= lines, "line {line} of {lines}: {message}");
            assert!(!message.is_empty());
        }
        Err(other) => panic!("in-memory input gave {other:?}"),
    }
});
