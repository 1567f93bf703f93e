//! Wavefront OBJ loading: positions and faces only, every error located to its line.
//!
//! The parser is a small streaming line scanner of its own rather than `tobj`: `tobj` hands back
//! per-object vertex arrays compacted to the referenced vertices in order of first use, which
//! would renumber the file's vertices, drop unreferenced ones and lose the line of every
//! problem. Here vertex `i` of the mesh is always the `i`-th `v` line of the file.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

use glam::Vec3;

use super::{MeshError, TriMesh};

/// Statements that carry no surface triangles and are skipped: texture coordinates, normals,
/// parameter-space vertices, points and lines, grouping, smoothing, materials, free-form
/// geometry and rendering attributes.
const IGNORED: &[&[u8]] = &[
    b"vt",
    b"vn",
    b"vp",
    b"p",
    b"l",
    b"o",
    b"g",
    b"s",
    b"mg",
    b"mtllib",
    b"usemtl",
    b"maplib",
    b"usemap",
    b"cstype",
    b"deg",
    b"bmat",
    b"step",
    b"curv",
    b"curv2",
    b"surf",
    b"parm",
    b"trim",
    b"hole",
    b"scrv",
    b"sp",
    b"end",
    b"con",
    b"bevel",
    b"c_interp",
    b"d_interp",
    b"lod",
    b"shadow_obj",
    b"trace_obj",
    b"ctech",
    b"stech",
    b"call",
    b"csh",
];

impl TriMesh {
    /// Loads the triangles of a Wavefront OBJ file.
    ///
    /// Reads the `v` (position) and `f` (face) statements; all objects and groups go into one
    /// mesh. Faces may be written `f a b c`, `f a/t …`, `f a//n …` or `f a/t/n …` (only the
    /// position index is used) with absolute (1-based) or relative (negative) indices, and
    /// faces with more than three vertices are split into a fan `(a, b, c), (a, c, d), …`.
    /// Vertex `i` of the mesh is the `i`-th `v` line of the file, unreferenced vertices
    /// included; a `w` weight or vertex colour after the three coordinates is ignored.
    /// Texture coordinates, normals, points, lines, groups, smoothing groups, materials
    /// (`mtllib` files are never opened) and other statements are skipped, as is everything
    /// after a `#`. Lines may be continued with a trailing `\`.
    ///
    /// # Errors
    /// [`MeshError::Io`] if the file cannot be read (missing, a directory, no permission);
    /// [`MeshError::Malformed`], naming the file and the 1-based line, for a `v` statement
    /// without three numbers or with a NaN / infinite (or `f32`-overflowing) coordinate, a face
    /// with fewer than three vertices, an unparsable index, index 0, an index beyond the
    /// vertices, binary data, or a statement longer than 1 MiB (input is read line by line, so
    /// memory stays bounded whatever the file); [`MeshError::Malformed`] with line 0 for a file
    /// without faces. Never panics, whatever the content.
    ///
    /// # Example
    /// ```no_run
    /// use stochastic_collision::mesh::TriMesh;
    /// let mesh = TriMesh::from_obj("bunny.obj")?;
    /// println!("{} triangles", mesh.triangle_count());
    /// # Ok::<(), stochastic_collision::mesh::MeshError>(())
    /// ```
    pub fn from_obj(path: impl AsRef<Path>) -> Result<TriMesh, MeshError> {
        let path = path.as_ref();
        let io_error = |e: std::io::Error| MeshError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let file = File::open(path).map_err(io_error)?;
        if file.metadata().map_err(io_error)?.is_dir() {
            return Err(MeshError::Io {
                path: path.to_path_buf(),
                message: "is a directory, not a file".to_owned(),
            });
        }
        Self::from_obj_reader(BufReader::new(file), path)
    }

    /// Loads the triangles of Wavefront OBJ text from `reader` (a file already open, or text in
    /// memory); `name` stands for the source in error messages.
    ///
    /// Accepts and refuses exactly what [`TriMesh::from_obj`] does.
    ///
    /// # Errors
    /// As [`TriMesh::from_obj`]: [`MeshError::Io`] if reading fails, [`MeshError::Malformed`]
    /// with `name` and the line for bad content.
    ///
    /// # Example
    /// ```
    /// use std::path::Path;
    /// use stochastic_collision::mesh::{MeshError, TriMesh};
    ///
    /// let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    /// let quad = TriMesh::from_obj_reader(text.as_bytes(), Path::new("quad.obj"))?;
    /// assert_eq!(quad.triangles(), &[[0, 1, 2], [0, 2, 3]]);
    ///
    /// let err = TriMesh::from_obj_reader("v 0 0 0\nf 1 2 3\n".as_bytes(), Path::new("bad.obj"));
    /// assert!(matches!(err, Err(MeshError::Malformed { line: 2, .. })));
    /// # Ok::<(), MeshError>(())
    /// ```
    pub fn from_obj_reader(reader: impl BufRead, name: &Path) -> Result<TriMesh, MeshError> {
        Parser::new(name).parse(reader)
    }

    /// Writes the mesh as Wavefront OBJ text (`v x y z` lines with round-tripping `f32`
    /// precision, then `f a b c` lines, 1-based), which [`TriMesh::from_obj`] reads back
    /// identically.
    ///
    /// # Errors
    /// Whatever `out` reports.
    ///
    /// # Example
    /// ```
    /// use std::path::Path;
    /// use stochastic_collision::mesh::{TriMesh, generate};
    /// let ball = generate::icosphere(1.0, 1);
    /// let mut text = Vec::new();
    /// ball.write_obj(&mut text)?;
    /// let back = TriMesh::from_obj_reader(text.as_slice(), Path::new("ball.obj")).unwrap();
    /// assert_eq!(back, ball);
    /// # Ok::<(), std::io::Error>(())
    /// ```
    pub fn write_obj(&self, out: impl std::io::Write) -> std::io::Result<()> {
        let mut out = std::io::BufWriter::new(out);
        for p in self.positions() {
            writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
        }
        for [a, b, c] in self.triangles() {
            writeln!(out, "f {} {} {}", a + 1, b + 1, c + 1)?;
        }
        out.flush()
    }
}

/// Longest statement accepted, in bytes (a line, or lines joined by `\`): 1 MiB, room for a
/// face of about 100,000 vertices. Longer is refused, so that input without line breaks
/// (binary data, a runaway continuation) is never buffered whole: memory stays bounded by this
/// plus the mesh itself.
const MAX_STATEMENT_BYTES: usize = 1 << 20;

/// A face that refers to a vertex not yet defined when it was read (allowed if the vertex
/// comes later in the file).
struct ForwardReference {
    line: usize,
    index: u64,
}

struct Parser<'a> {
    name: &'a Path,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    forward: Vec<ForwardReference>,
    face_lines: usize,
    corners: Vec<u32>,
}

impl<'a> Parser<'a> {
    fn new(name: &'a Path) -> Self {
        Self {
            name,
            positions: Vec::new(),
            triangles: Vec::new(),
            forward: Vec::new(),
            face_lines: 0,
            corners: Vec::new(),
        }
    }

    fn error(&self, line: usize, message: impl Into<String>) -> MeshError {
        MeshError::Malformed {
            path: self.name.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    fn parse(mut self, mut reader: impl BufRead) -> Result<TriMesh, MeshError> {
        let mut raw = Vec::new();
        let mut statement: Vec<u8> = Vec::new();
        let mut line_no = 0usize;
        // Line where the statement being accumulated (over `\` continuations) started.
        let mut start_line = 1usize;
        loop {
            raw.clear();
            let read = Read::take(&mut reader, MAX_STATEMENT_BYTES as u64 + 1)
                .read_until(b'\n', &mut raw)
                .map_err(|e| MeshError::Io {
                    path: self.name.to_path_buf(),
                    message: e.to_string(),
                })?;
            if read == 0 {
                break;
            }
            line_no += 1;
            if statement.is_empty() {
                start_line = line_no;
            }
            let content = raw.len() - usize::from(raw.last() == Some(&b'\n'));
            if content + statement.len() > MAX_STATEMENT_BYTES {
                return Err(self.error(
                    start_line,
                    format!(
                        "statement longer than {} MiB; this does not look like OBJ text",
                        MAX_STATEMENT_BYTES >> 20
                    ),
                ));
            }
            let mut line = raw.as_slice();
            if line_no == 1 {
                line = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(line);
            }
            while let [rest @ .., b'\n' | b'\r'] = line {
                line = rest;
            }
            if let [rest @ .., b'\\'] = line {
                statement.extend_from_slice(rest);
                statement.push(b' ');
                continue;
            }
            statement.extend_from_slice(line);
            self.statement(&statement, start_line)?;
            statement.clear();
        }
        if !statement.is_empty() {
            self.statement(&statement, start_line)?;
        }
        self.finish()
    }

    fn finish(self) -> Result<TriMesh, MeshError> {
        let n = self.positions.len() as u64;
        if let Some(f) = self.forward.iter().find(|f| f.index > n) {
            return Err(self.error(f.line, out_of_range_message(f.index, n)));
        }
        if self.triangles.is_empty() {
            let message = if self.face_lines == 0 {
                format!(
                    "no faces: {} vertices and no `f` statement; a mesh needs at least one triangle",
                    self.positions.len()
                )
            } else {
                format!(
                    "no triangles: {} vertices and {} `f` statements, none with 3 or more vertices",
                    self.positions.len(),
                    self.face_lines
                )
            };
            return Err(self.error(0, message));
        }
        TriMesh::new(self.positions, self.triangles)
    }

    /// Handles one statement (a line, or lines joined by `\`), `line` being where it starts.
    fn statement(&mut self, text: &[u8], line: usize) -> Result<(), MeshError> {
        let text = match text.iter().position(|&b| b == b'#') {
            Some(hash) => &text[..hash],
            None => text,
        };
        if let Some(&bad) = text
            .iter()
            .find(|&&b| b.is_ascii_control() && !b.is_ascii_whitespace())
        {
            return Err(self.error(
                line,
                format!("binary data (byte 0x{bad:02X}); this is not OBJ text"),
            ));
        }
        let mut words = text
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        match keyword {
            b"v" => self.vertex(words, line),
            b"f" | b"fo" => self.face(words, line),
            k if IGNORED.contains(&k) => Ok(()),
            k if is_identifier(k) => Ok(()), // unknown extension statement: skipped
            k => Err(self.error(
                line,
                format!(
                    "unrecognised statement `{}`; this does not look like OBJ text",
                    shown(k)
                ),
            )),
        }
    }

    fn vertex<'w>(
        &mut self,
        mut words: impl Iterator<Item = &'w [u8]>,
        line: usize,
    ) -> Result<(), MeshError> {
        let vertex = self.positions.len() + 1;
        let mut xyz = [0.0f32; 3];
        for (axis, value) in ["x", "y", "z"].into_iter().zip(&mut xyz) {
            let Some(word) = words.next() else {
                return Err(self.error(
                    line,
                    format!(
                        "vertex {vertex} has no {axis} coordinate (a `v` statement needs 3 numbers)"
                    ),
                ));
            };
            let Some(parsed) = std::str::from_utf8(word)
                .ok()
                .and_then(|s| s.parse::<f32>().ok())
            else {
                return Err(self.error(
                    line,
                    format!(
                        "vertex {vertex}: {axis} coordinate `{}` is not a number",
                        shown(word)
                    ),
                ));
            };
            if !parsed.is_finite() {
                let why = if parsed.is_nan() {
                    "NaN"
                } else if word.iter().any(u8::is_ascii_digit) {
                    "too large for f32"
                } else {
                    "infinite"
                };
                return Err(self.error(
                    line,
                    format!(
                        "vertex {vertex}: {axis} coordinate `{}` is {why}; coordinates must be finite",
                        shown(word)
                    ),
                ));
            }
            *value = parsed;
        }
        // Anything after x y z (a `w` weight, or a vertex colour) is ignored.
        self.positions.push(Vec3::from_array(xyz));
        Ok(())
    }

    fn face<'w>(
        &mut self,
        words: impl Iterator<Item = &'w [u8]>,
        line: usize,
    ) -> Result<(), MeshError> {
        self.face_lines += 1;
        let defined = self.positions.len() as u64;
        let mut corners = std::mem::take(&mut self.corners);
        corners.clear();
        for word in words {
            let index = self.face_index(word, line, defined)?;
            corners.push(index);
        }
        if corners.len() < 3 {
            self.corners = corners;
            return Err(self.error(
                line,
                format!(
                    "face has {} vertices; at least 3 are needed",
                    self.corners.len()
                ),
            ));
        }
        let a = corners[0];
        for pair in corners[1..].windows(2) {
            self.triangles.push([a, pair[0], pair[1]]);
        }
        self.corners = corners;
        Ok(())
    }

    /// Parses one face vertex (`v`, `v/t`, `v//n` or `v/t/n`) into a 0-based position index.
    fn face_index(&mut self, word: &[u8], line: usize, defined: u64) -> Result<u32, MeshError> {
        let mut fields = word.split(|&b| b == b'/');
        let first = fields.next().unwrap_or_default();
        for (i, field) in fields.enumerate() {
            if i >= 2 {
                return Err(self.error(
                    line,
                    format!(
                        "face vertex `{}` has more than 3 `/`-separated fields",
                        shown(word)
                    ),
                ));
            }
            if !field.is_empty() && parse_int(field).is_none() {
                return Err(self.error(
                    line,
                    format!(
                        "face vertex `{}`: `{}` is not an integer index",
                        shown(word),
                        shown(field)
                    ),
                ));
            }
        }
        if first.is_empty() {
            return Err(self.error(
                line,
                format!("face vertex `{}` has no position index", shown(word)),
            ));
        }
        let Some(index) = parse_int(first) else {
            return Err(self.error(
                line,
                format!(
                    "face vertex `{}`: `{}` is not an integer index",
                    shown(word),
                    shown(first)
                ),
            ));
        };
        // 1-based absolute index into the vertices.
        let one_based: u64 = if index > 0 {
            index as u64
        } else if index == 0 {
            return Err(self.error(
                line,
                "face refers to vertex 0, but OBJ indices start at 1 (or are negative, relative)",
            ));
        } else {
            let back = index.unsigned_abs();
            if back > defined {
                return Err(self.error(
                    line,
                    format!(
                        "face refers to vertex {index} (relative), but only {defined} vertices are defined before this line"
                    ),
                ));
            }
            defined - back + 1
        };
        if one_based > u64::from(u32::MAX) {
            return Err(self.error(line, out_of_range_message(one_based, defined)));
        }
        if one_based > defined {
            // Possibly defined further down; checked once the whole file is read.
            if self.forward.last().is_none_or(|f| f.line != line) {
                self.forward.push(ForwardReference {
                    line,
                    index: one_based,
                });
            } else if let Some(f) = self.forward.last_mut() {
                f.index = f.index.max(one_based);
            }
        }
        Ok((one_based - 1) as u32)
    }
}

fn out_of_range_message(index: u64, vertices: u64) -> String {
    match vertices {
        0 => format!("face refers to vertex {index}, but no vertices are defined"),
        1 => format!("face refers to vertex {index}, but only 1 vertex is defined"),
        n => format!("face refers to vertex {index}, but only {n} vertices are defined"),
    }
}

/// Parses a signed decimal integer (no overflow: `None` past `i64`).
fn parse_int(word: &[u8]) -> Option<i64> {
    std::str::from_utf8(word).ok()?.parse::<i64>().ok()
}

fn is_identifier(word: &[u8]) -> bool {
    word.first().is_some_and(u8::is_ascii_alphabetic)
        && word.iter().all(|&b| b.is_ascii_alphanumeric() || b == b'_')
}

/// A word for an error message: lossy UTF-8, shortened if long.
fn shown(word: &[u8]) -> String {
    const MAX: usize = 40;
    let text = String::from_utf8_lossy(word);
    if text.chars().count() > MAX {
        let head: String = text.chars().take(MAX).collect();
        format!("{head}…")
    } else {
        text.into_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<TriMesh, MeshError> {
        TriMesh::from_obj_reader(text.as_bytes(), Path::new("t.obj"))
    }

    fn line_of(r: Result<TriMesh, MeshError>) -> (usize, String) {
        match r {
            Err(MeshError::Malformed { line, message, .. }) => (line, message),
            other => panic!("expected Malformed, got {other:?}"),
        }
    }

    #[test]
    fn fan_and_forms() {
        let m = load("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1/1 2//3 3/4/5 -2 -1  \n")
            .unwrap();
        assert_eq!(m.triangles(), &[[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn errors_have_lines() {
        assert_eq!(line_of(load("v 0 0 0\nv 1 2\n")).0, 2);
        assert_eq!(line_of(load("v 0 0 0\n\nf 1 1 9\n")).0, 3);
        let (line, message) = line_of(load("v 1e39 0 0\n"));
        assert_eq!(line, 1);
        assert!(message.contains("too large"), "{message}");
        assert_eq!(line_of(load("# nothing\n")).0, 0);
        assert_eq!(line_of(load("\u{0}\u{1}garbage")).0, 1);
    }

    #[test]
    fn continuation_and_comments() {
        let m =
            load("v 0 0 0 # origin\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 3\nf 1 2 3 # again\n").unwrap();
        assert_eq!(m.triangle_count(), 2);
    }
}
