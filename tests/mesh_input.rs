//! Mesh input: `TriMesh::new` validation and OBJ loading, good and bad.
mod common;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use stochastic_collision::mesh::{MeshError, TriMesh};

fn load(text: &str) -> Result<TriMesh, MeshError> {
    TriMesh::from_obj_reader(text.as_bytes(), Path::new("mesh.obj"))
}

/// Expects a `Malformed` error for `mesh.obj` at `line` whose message contains every one of
/// `words`; returns the displayed error.
#[track_caller]
fn expect_malformed(result: Result<TriMesh, MeshError>, line: usize, words: &[&str]) -> String {
    let err = result.expect_err("the input should be refused");
    let MeshError::Malformed {
        path,
        line: got,
        message,
    } = &err
    else {
        panic!("expected MeshError::Malformed, got {err:?}");
    };
    assert_eq!(path, Path::new("mesh.obj"), "{err}");
    assert_eq!(*got, line, "wrong line in: {err}");
    for w in words {
        assert!(message.contains(w), "message lacks {w:?}: {err}");
    }
    let shown = err.to_string();
    let prefix = if line == 0 {
        "mesh.obj: ".to_string()
    } else {
        format!("mesh.obj:{line}: ")
    };
    assert!(shown.starts_with(&prefix), "{shown}");
    shown
}

/// A file under the temporary directory, removed on drop.
struct TempFile(PathBuf);

impl TempFile {
    fn new(content: &[u8]) -> Self {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let path = std::env::temp_dir().join(format!(
            "stochastic_collision_mesh_input_{}_{}.obj",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::write(&path, content).unwrap();
        Self(path)
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

// ---------------------------------------------------------------- TriMesh::new

#[test]
fn new_refuses_empty_meshes() {
    assert_eq!(
        TriMesh::new(vec![], vec![]),
        Err(MeshError::Empty {
            vertices: 0,
            triangles: 0
        })
    );
    assert_eq!(
        TriMesh::new(vec![Vec3::ZERO; 3], vec![]),
        Err(MeshError::Empty {
            vertices: 3,
            triangles: 0
        })
    );
}

#[test]
fn new_refuses_out_of_range_indices() {
    let err = TriMesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 2], [2, 1, 3]]).unwrap_err();
    assert_eq!(
        err,
        MeshError::IndexOutOfRange {
            triangle: 1,
            index: 3,
            vertices: 3
        }
    );
}

#[test]
fn new_refuses_nan_and_infinity() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, bad, 0.0)];
        match TriMesh::new(positions, vec![[0, 1, 2]]) {
            Err(MeshError::NonFinite { vertex: 2, .. }) => {}
            other => panic!("{bad}: {other:?}"),
        }
    }
}

#[test]
fn set_positions_refuses_bad_input_and_leaves_the_mesh_unchanged() {
    let mut mesh = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
    let before = mesh.clone();
    assert_eq!(
        mesh.set_positions(&[Vec3::ZERO; 2]),
        Err(MeshError::PositionCount {
            expected: 3,
            got: 2
        })
    );
    assert_eq!(mesh, before);
    let nan = [Vec3::Z, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE];
    assert!(matches!(
        mesh.set_positions(&nan),
        Err(MeshError::NonFinite { vertex: 1, .. })
    ));
    assert_eq!(mesh, before);
    let inf = [Vec3::Z, Vec3::X, Vec3::splat(f32::INFINITY)];
    assert!(mesh.set_positions(&inf).is_err());
    assert_eq!(mesh, before);
    mesh.set_positions(&[Vec3::Z, Vec3::X, Vec3::ONE]).unwrap();
    assert_eq!(mesh.positions(), &[Vec3::Z, Vec3::X, Vec3::ONE]);
}

// ---------------------------------------------------------------- bad OBJ input

#[test]
fn empty_file_is_refused_naming_the_file() {
    let shown = expect_malformed(load(""), 0, &["no faces"]);
    assert!(shown.contains("mesh.obj"));
    expect_malformed(load("# just a comment\n\n   \n"), 0, &["no faces"]);
}

#[test]
fn vertices_without_faces_are_refused() {
    expect_malformed(load(SQUARE), 0, &["no faces", "4 vertices"]);
}

#[test]
fn short_vertex_is_refused_with_its_line() {
    expect_malformed(load("v 0 0 0\nv 1 2\nf 1 2 3\n"), 2, &["vertex 2", "z"]);
    expect_malformed(load("v\n"), 1, &["x"]);
}

#[test]
fn unparsable_vertex_is_refused_with_its_line() {
    expect_malformed(load("# c\nv a b c\n"), 2, &["`a`", "not a number"]);
    expect_malformed(load("v 0 0 0\nv 1 0 0,5\n"), 2, &["0,5"]);
}

#[test]
fn short_face_is_refused_with_its_line() {
    expect_malformed(
        load(&format!("{SQUARE}f 1 2 3\nf 1 2\n")),
        6,
        &["2 vertices", "at least 3"],
    );
    expect_malformed(load(&format!("{SQUARE}f\n")), 5, &["0 vertices"]);
}

#[test]
fn out_of_range_face_is_refused_with_its_line() {
    let shown = expect_malformed(load(&format!("{SQUARE}\nf 1 2 99\n")), 6, &[]);
    assert_eq!(
        shown,
        "mesh.obj:6: face refers to vertex 99, but only 4 vertices are defined"
    );
    // A forward reference to a vertex defined later is fine; one that never comes is not.
    assert!(load("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n").is_ok());
    expect_malformed(
        load("v 0 0 0\nf 1 2 4\nv 1 0 0\nv 0 1 0\n"),
        2,
        &["vertex 4", "3 vertices"],
    );
    // Huge indices do not overflow.
    expect_malformed(
        load(&format!("{SQUARE}f 1 2 99999999999\n")),
        5,
        &["99999999999"],
    );
    expect_malformed(
        load(&format!("{SQUARE}f 1 2 999999999999999999999999\n")),
        5,
        &["not an integer"],
    );
}

#[test]
fn index_zero_is_refused_with_its_line() {
    expect_malformed(
        load(&format!("{SQUARE}f 0 1 2\n")),
        5,
        &["vertex 0", "start at 1"],
    );
}

#[test]
fn relative_index_before_the_first_vertex_is_refused() {
    expect_malformed(load(&format!("{SQUARE}f -1 -2 -5\n")), 5, &["-5"]);
}

#[test]
fn unparsable_face_index_is_refused_with_its_line() {
    expect_malformed(load(&format!("{SQUARE}f 1 2 x\n")), 5, &["`x`"]);
    expect_malformed(load(&format!("{SQUARE}f 1 2 3/a\n")), 5, &["`a`"]);
    expect_malformed(
        load(&format!("{SQUARE}f 1 2 /3\n")),
        5,
        &["no position index"],
    );
    expect_malformed(load(&format!("{SQUARE}f 1 2 3/1/1/1\n")), 5, &["3/1/1/1"]);
    expect_malformed(load(&format!("{SQUARE}f 1 2 1.5\n")), 5, &["1.5"]);
}

#[test]
fn non_finite_coordinates_are_refused_with_their_line() {
    expect_malformed(
        load("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
        2,
        &["vertex 2", "NaN"],
    );
    expect_malformed(
        load("v 0 0 0\nv 0 0 0\nv 1e39 0 0\nf 1 2 3\n"),
        3,
        &["vertex 3", "1e39"],
    );
    expect_malformed(load("v 0 inf 0\n"), 1, &["infinite"]);
    expect_malformed(load("v 0 0 -infinity\nf 1 1 1\n"), 1, &["z coordinate"]);
}

#[test]
fn binary_garbage_is_refused_without_panic() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for round in 0..200 {
        let len = 1 + round * 37 % 3000;
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 24) as u8
            })
            .collect();
        let result = TriMesh::from_obj_reader(bytes.as_slice(), Path::new("mesh.obj"));
        match result {
            Err(MeshError::Malformed { .. }) => {}
            other => panic!("random bytes gave {other:?}"),
        }
    }
    // Valid-looking statements around non-UTF-8 bytes.
    let mut text = b"v 0 0 0\nv 1 0 0\nv 0 1 \xff\xfe\nf 1 2 3\n".to_vec();
    expect_malformed(
        TriMesh::from_obj_reader(text.as_slice(), Path::new("mesh.obj")),
        3,
        &["not a number"],
    );
    text = b"\x7fELF\x02\x01\x01\x00\x00\x00".to_vec();
    expect_malformed(
        TriMesh::from_obj_reader(text.as_slice(), Path::new("mesh.obj")),
        1,
        &["binary"],
    );
    // Non-UTF-8 in a comment is harmless.
    let text = b"# caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    assert!(TriMesh::from_obj_reader(text.as_slice(), Path::new("mesh.obj")).is_ok());
}

#[test]
fn truncated_and_mangled_real_text_never_panics() {
    let text = format!(
        "{SQUARE}vt 0 0\nvn 0 0 1\ng grp\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -4 -3 -2\nf 1//1 3//1 4//1\n"
    );
    let bytes = text.as_bytes();
    for cut in 0..bytes.len() {
        let _ = TriMesh::from_obj_reader(&bytes[..cut], Path::new("mesh.obj"));
        for replacement in [b'/', b'-', b'\0', b' ', b'9', b'\n', 0xff] {
            let mut mangled = bytes.to_vec();
            mangled[cut] = replacement;
            let _ = TriMesh::from_obj_reader(mangled.as_slice(), Path::new("mesh.obj"));
        }
    }
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let path = std::env::temp_dir().join("stochastic_collision_surely_missing_file.obj");
    let err = TriMesh::from_obj(&path).unwrap_err();
    match &err {
        MeshError::Io { path: p, message } => {
            assert_eq!(p, &path);
            assert!(!message.is_empty());
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains("surely_missing_file.obj"), "{err}");
}

#[test]
fn directory_is_an_io_error() {
    let dir = std::env::temp_dir();
    match TriMesh::from_obj(&dir) {
        Err(MeshError::Io { path, message }) => {
            assert_eq!(path, dir);
            assert!(message.contains("directory"), "{message}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn file_errors_name_the_path_and_line() {
    let file = TempFile::new(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n");
    match TriMesh::from_obj(&file.0) {
        Err(MeshError::Malformed { path, line, .. }) => {
            assert_eq!(path, file.0);
            assert_eq!(line, 5);
        }
        other => panic!("{other:?}"),
    }
}

// ---------------------------------------------------------------- large input, streamed

/// OBJ text produced lazily, line by line, by `next_line(k)` for the 1-based line `k` (`None`
/// ends it, as does reaching 32 MiB); counts the bytes handed out. Nothing is ever held but the
/// current line.
struct Generated<F> {
    next_line: F,
    line: u64,
    pending: Vec<u8>,
    at: usize,
    bytes: u64,
}

impl<F: FnMut(u64) -> Option<Vec<u8>>> Generated<F> {
    fn new(next_line: F) -> Self {
        Self {
            next_line,
            line: 0,
            pending: Vec::new(),
            at: 0,
            bytes: 0,
        }
    }
}

impl<F: FnMut(u64) -> Option<Vec<u8>>> std::io::Read for Generated<F> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.bytes >= 32 * MIB {
            return Ok(0); // "endless" sources end here, so a loader that slurps fails, not hangs
        }
        if self.at == self.pending.len() {
            self.line += 1;
            match (self.next_line)(self.line) {
                Some(l) => (self.pending, self.at) = (l, 0),
                None => return Ok(0),
            }
        }
        let n = buf.len().min(self.pending.len() - self.at);
        buf[..n].copy_from_slice(&self.pending[self.at..self.at + n]);
        self.at += n;
        self.bytes += n as u64;
        Ok(n)
    }
}

const MIB: u64 = 1 << 20;

#[test]
fn a_large_file_is_read_line_by_line() {
    // 300,000 vertices on a grid, then 300,000 faces: about 9 MB of text never held whole.
    const N: u64 = 300_000;
    let mut src = Generated::new(|k| match k {
        1..=N => Some(format!("v {} {} 0\n", k % 1000, k / 1000).into_bytes()),
        _ if k <= 2 * N => {
            let i = k - N;
            Some(format!("f {} {} {}\n", i, i % N + 1, (i + 1) % N + 1).into_bytes())
        }
        _ => None,
    });
    let mesh = TriMesh::from_obj_reader(
        std::io::BufReader::with_capacity(4096, &mut src),
        Path::new("mesh.obj"),
    )
    .unwrap();
    assert_eq!(
        (mesh.vertex_count(), mesh.triangle_count()),
        (N as usize, N as usize)
    );
    assert_eq!(mesh.positions()[1234], Vec3::new(235.0, 1.0, 0.0)); // line 1235
    assert_eq!(mesh.triangles()[N as usize - 1], [N as u32 - 1, 0, 1]);
    assert!(src.bytes > 8 * MIB, "{} bytes", src.bytes);
}

#[test]
fn an_error_deep_in_an_endless_file_names_its_line_and_stops_reading() {
    // Valid vertices forever, except a NaN on line 400,000: the loader must stop there (an
    // implementation reading the whole input first would never return).
    const BAD: u64 = 400_000;
    let mut src = Generated::new(|k| {
        Some(if k == BAD {
            b"v 1 nan 2\n".to_vec()
        } else {
            format!("v {k} 0 0\n").into_bytes()
        })
    });
    let result = TriMesh::from_obj_reader(
        std::io::BufReader::with_capacity(4096, &mut src),
        Path::new("mesh.obj"),
    );
    expect_malformed(result, BAD as usize, &["vertex 400000", "NaN"]);
    assert_eq!(src.line, BAD, "read past the bad line");
}

#[test]
fn an_endless_line_is_refused_after_a_bounded_read() {
    // No line break ever (binary data, or a broken export): refused once the statement passes
    // 1 MiB, having read little more than that.
    let mut src = Generated::new(|_| Some(b"v 1 2 3 ".to_vec()));
    let result = TriMesh::from_obj_reader(std::io::BufReader::new(&mut src), Path::new("mesh.obj"));
    expect_malformed(result, 1, &["longer than 1 MiB"]);
    assert!(src.bytes <= MIB + 64 * 1024, "{} bytes read", src.bytes);

    // An endless chain of `\` continuations: refused naming the line the statement started on.
    let mut src = Generated::new(|k| {
        Some(if k < 3 {
            b"v 0 0 0\n".to_vec()
        } else {
            b"f 1 2 \\\n".to_vec()
        })
    });
    let result = TriMesh::from_obj_reader(std::io::BufReader::new(&mut src), Path::new("mesh.obj"));
    expect_malformed(result, 3, &["longer than 1 MiB"]);
    // Each 8-byte line adds 7 bytes to the statement (the `\` and line break become a space).
    assert!(
        src.bytes <= MIB * 8 / 7 + 64 * 1024,
        "{} bytes read",
        src.bytes
    );
}

#[test]
fn statements_up_to_one_mib_are_accepted() {
    let limit = MIB as usize;
    let line = |len: usize| {
        let mut l = b"v 1 2 3".to_vec();
        l.resize(len, b' ');
        l.push(b'\n');
        l
    };
    let faces = b"v 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let at_limit = [line(limit), faces.to_vec()].concat();
    let mesh = TriMesh::from_obj_reader(at_limit.as_slice(), Path::new("mesh.obj")).unwrap();
    assert_eq!(mesh.positions()[0], Vec3::new(1.0, 2.0, 3.0));
    let over = [line(limit + 1), faces.to_vec()].concat();
    expect_malformed(
        TriMesh::from_obj_reader(over.as_slice(), Path::new("mesh.obj")),
        1,
        &["longer than 1 MiB"],
    );
    // Also at the end of the input without a final line break.
    let last = [faces.to_vec(), line(limit + 1)].concat();
    let last = &last[..last.len() - 1];
    expect_malformed(
        TriMesh::from_obj_reader(last, Path::new("mesh.obj")),
        4,
        &["longer than 1 MiB"],
    );
}

// ---------------------------------------------------------------- good OBJ input

#[test]
fn loads_a_file_from_disk() {
    let file = TempFile::new(format!("{SQUARE}f 1 2 3 4\n").as_bytes());
    let mesh = TriMesh::from_obj(&file.0).unwrap();
    assert_eq!(mesh.vertex_count(), 4);
    assert_eq!(mesh.triangles(), &[[0, 1, 2], [0, 2, 3]]);
    assert_eq!(mesh.positions()[2], Vec3::new(1.0, 1.0, 0.0));
}

#[test]
fn quads_and_ngons_are_fan_triangulated() {
    let mut text = String::new();
    for i in 0..8 {
        let a = std::f32::consts::TAU * i as f32 / 8.0;
        text += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    text += "f 1 2 3\nf 1 2 3 4\nf 1 2 3 4 5\nf 1 2 3 4 5 6 7 8\n";
    let mesh = load(&text).unwrap();
    assert_eq!(mesh.triangle_count(), 1 + 2 + 3 + 6);
    assert_eq!(
        &mesh.triangles()[6..],
        &[
            [0, 1, 2],
            [0, 2, 3],
            [0, 3, 4],
            [0, 4, 5],
            [0, 5, 6],
            [0, 6, 7]
        ]
    );
}

#[test]
fn every_face_form_reads_the_position_index() {
    let head = format!("{SQUARE}vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n");
    for face in [
        "f 1 2 3",
        "f 1/1 2/2 3/3",
        "f 1//1 2//1 3//1",
        "f 1/1/1 2/2/1 3/3/1",
        "f 1/1 2//1 3/3/1",
        "  f\t1   2 3   ",
        "f 1 2 3 # comment",
        "f -4 -3 -2",
        "f -4/-3/-1 -3//-1 3/-1",
    ] {
        let mesh = load(&format!("{head}{face}\n")).unwrap_or_else(|e| panic!("{face}: {e}"));
        assert_eq!(mesh.triangles(), &[[0, 1, 2]], "{face}");
        assert_eq!(mesh.vertex_count(), 4, "{face}");
    }
}

#[test]
fn negative_indices_are_relative_to_the_vertices_so_far() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4 -1 -2\n";
    let mesh = load(text).unwrap();
    assert_eq!(mesh.triangles(), &[[0, 1, 2], [0, 3, 2]]);
}

#[test]
fn comments_groups_objects_materials_and_other_statements_are_skipped() {
    let text = "# header\r\n\
        mtllib missing.mtl\r\n\
        o first\r\n\
        v 0 0 0\r\n\
        v 1 0 0 1.0\r\n\
        v 0 1 0 0.5 0.5 0.5\r\n\
        vn 0 0 1\r\n\
        vp 0.5\r\n\
        usemtl nothing\r\n\
        s off\r\n\
        g a b\r\n\
        f 1 2 3\r\n\
        l 1 2\r\n\
        p 3\r\n\
        o second\r\n\
        v 0 0 1\r\n\
        s 1\r\n\
        f 1 2 4\r\n\
        f 2 3 \\\r\n\
        4\r\n";
    let mesh = load(text).unwrap();
    assert_eq!(mesh.vertex_count(), 4);
    assert_eq!(mesh.triangles(), &[[0, 1, 2], [0, 1, 3], [1, 2, 3]]);
    // The `w` weight and vertex colours are ignored.
    assert_eq!(mesh.positions()[1], Vec3::X);
    assert_eq!(mesh.positions()[2], Vec3::Y);
}

#[test]
fn byte_order_mark_and_missing_final_newline_are_fine() {
    let mesh = load("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3").unwrap();
    assert_eq!(mesh.triangle_count(), 1);
}

#[test]
fn unreferenced_and_degenerate_are_kept_in_file_order() {
    let text = "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 8 8 8\nf 2 3 4\nf 2 2 3\n";
    let mesh = load(text).unwrap();
    assert_eq!(mesh.vertex_count(), 5);
    assert_eq!(mesh.positions()[0], Vec3::splat(9.0));
    assert_eq!(mesh.positions()[4], Vec3::splat(8.0));
    assert_eq!(mesh.triangles(), &[[1, 2, 3], [1, 1, 2]]);
}

// ---------------------------------------------------------------- real meshes

/// (file, triangles, vertices) from the shared meshes' README table.
const SHARED: &[(&str, usize, usize)] = &[
    ("suzanne.obj", 968, 507),
    ("torus.obj", 4_608, 2_304),
    ("plane_50x50.obj", 5_000, 2_601),
    ("spot.obj", 5_856, 2_930),
    ("teapot.obj", 6_320, 3_644),
    ("bunny.obj", 6_598, 3_301),
    ("large_intestine_20k.obj", 20_000, 10_000),
    ("armadillo.obj", 29_170, 14_587),
    ("large-intestine-sf+-hf-.obj", 30_956, 15_592),
    ("dragon_50k.obj", 50_000, 25_007),
    ("stanford-bunny.obj", 69_451, 35_947),
    ("small_intestine_100k.obj", 100_000, 50_002),
    ("ogre.obj", 124_008, 62_194),
];

#[test]
fn shared_meshes_load_with_the_documented_counts() {
    for &(file, triangles, vertices) in SHARED {
        let Some(path) = common::shared_mesh(file) else {
            continue;
        };
        let mesh = TriMesh::from_obj(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(mesh.triangle_count(), triangles, "{file} triangles");
        assert_eq!(mesh.vertex_count(), vertices, "{file} vertices");
    }
}

#[test]
fn shared_mesh_bounds_match_the_readme() {
    // (file, bbox min, bbox max) from the README table, given to 5 decimals.
    let cases = [
        ("torus.obj", [-1.25, -0.25, -1.25], [1.25, 0.25, 1.25]),
        (
            "stanford-bunny.obj",
            [-0.09469, 0.03299, -0.06187],
            [0.06101, 0.18732, 0.0588],
        ),
        ("plane_50x50.obj", [-0.5, 0.0, -0.5], [0.5, 0.0, 0.5]),
    ];
    for (file, min, max) in cases {
        let Some(path) = common::shared_mesh(file) else {
            continue;
        };
        let aabb = TriMesh::from_obj(&path).unwrap().aabb();
        assert!(
            aabb.min.abs_diff_eq(Vec3::from_array(min), 1e-4),
            "{file} {aabb:?}"
        );
        assert!(
            aabb.max.abs_diff_eq(Vec3::from_array(max), 1e-4),
            "{file} {aabb:?}"
        );
    }
}

#[test]
fn ogre_degenerate_triangles_keep_their_file_indices() {
    let Some(path) = common::shared_mesh("ogre.obj") else {
        return;
    };
    let mesh = TriMesh::from_obj(&path).unwrap();
    // README: face 2074 (counting from 1) is vertices 1462/1464/1465 (1-based), zero area.
    let tri = mesh.triangles()[2073];
    let mut sorted = tri.map(|i| i + 1);
    sorted.sort_unstable();
    assert_eq!(sorted, [1462, 1464, 1465]);
    let [a, b, c] = mesh.triangle(2073);
    assert_eq!((b - a).cross(c - a), Vec3::ZERO);
}
