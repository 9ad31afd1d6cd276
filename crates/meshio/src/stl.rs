//! STL: binary and ASCII in, binary out.
//!
//! STL stores every triangle with its own three corners. Reading welds corners whose positions
//! are bitwise equal (so `0.0` and `-0.0` stay apart) into one vertex, numbered in order of first
//! appearance: deterministic, and a closed surface written as STL comes back closed. Stored
//! normals are ignored (they follow from the winding).
//!
//! Which kind: a file whose size is exactly `84 + 50·n` for the triangle count `n` in bytes
//! 80..84 is binary (even if its header starts with `solid`, as some exporters write); otherwise
//! one that starts with `solid` is ASCII; otherwise it is a binary file of the wrong size, and the
//! error names the first incomplete triangle.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use glam::Vec3;
use tissue_mesh::TriMesh;

use crate::atomic::{read_file, write_atomic};
use crate::text::{shorten, utf8, Tokens};
use crate::{MeshIoError, SurfaceData};

const HEADER: usize = 80;
const RECORD: usize = 50;

/// Reads an STL file (binary or ASCII), welding bitwise-equal corners.
pub fn read_stl(path: impl AsRef<Path>) -> Result<SurfaceData, MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("read_stl", path = %path.display()).entered();
    parse_stl(&read_file(path)?, path)
}

/// Parses STL data held in memory; `name` stands for the file in error messages.
pub fn parse_stl(bytes: &[u8], name: impl AsRef<Path>) -> Result<SurfaceData, MeshIoError> {
    let path = name.as_ref();
    let count = binary_count(bytes);
    if let Some(n) = count {
        if (bytes.len() as u64).checked_sub(HEADER as u64 + 4) == Some(n * RECORD as u64) {
            return parse_binary(bytes, path);
        }
    }
    let starts_solid = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .and_then(|s| bytes.get(s..s + 5))
        .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
    if starts_solid {
        let ascii = parse_ascii(bytes, path);
        // A binary file of the wrong size whose header happens to start with `solid`: the
        // binary explanation helps more than an ASCII parse error at some garbage byte.
        let looks_binary = count.is_some() && bytes.iter().any(|&b| b == 0 || b >= 0x80);
        return match ascii {
            Err(_) if looks_binary => Err(binary_size_error(bytes, path)),
            other => other,
        };
    }
    Err(binary_size_error(bytes, path))
}

/// The triangle count in a binary header, if the file is long enough to have one.
fn binary_count(bytes: &[u8]) -> Option<u64> {
    let b: [u8; 4] = bytes.get(HEADER..HEADER + 4)?.try_into().ok()?;
    Some(u64::from(u32::from_le_bytes(b)))
}

fn binary_size_error(bytes: &[u8], path: &Path) -> MeshIoError {
    let Some(n) = binary_count(bytes) else {
        return MeshIoError::binary(
            path,
            "header",
            None,
            format!(
                "the file has {} bytes: too short for a binary STL (at least 84) and it does not start with `solid` as an ASCII STL does",
                bytes.len()
            ),
        );
    };
    let expected = HEADER as u64 + 4 + n * RECORD as u64;
    let have = bytes.len() as u64;
    let body = have - (HEADER as u64 + 4);
    if have < expected {
        MeshIoError::binary(
            path,
            "triangle",
            usize::try_from(body / RECORD as u64).ok(),
            format!(
                "the header declares {n} triangles ({expected} bytes), but the file has {have} bytes, so this triangle is incomplete: the file is truncated"
            ),
        )
    } else {
        MeshIoError::binary(
            path,
            "header",
            None,
            format!(
                "the header declares {n} triangles ({expected} bytes), but the file has {have} bytes: the count is wrong, or data follows the last triangle (and it does not start with `solid`, so it is not ASCII STL)"
            ),
        )
    }
}

fn parse_binary(bytes: &[u8], path: &Path) -> Result<SurfaceData, MeshIoError> {
    let body = bytes.get(HEADER + 4..).unwrap_or_default();
    let mut weld = Welder::with_capacity(body.len() / RECORD);
    for (t, record) in body.chunks_exact(RECORD).enumerate() {
        // Bytes 0..12 are the normal, 12..48 the corners, 48..50 the attribute count.
        let mut f = [0.0f32; 9];
        let corner_bytes = record.get(12..48).unwrap_or_default().chunks_exact(4);
        for (slot, b) in f.iter_mut().zip(corner_bytes) {
            *slot = f32::from_le_bytes(b.try_into().unwrap_or_default());
        }
        let [ax, ay, az, bx, by, bz, cx, cy, cz] = f;
        let corners = [
            Vec3::new(ax, ay, az),
            Vec3::new(bx, by, bz),
            Vec3::new(cx, cy, cz),
        ];
        weld.triangle(corners)
            .map_err(|m| MeshIoError::binary(path, "triangle", Some(t), m))?;
    }
    Ok(weld.finish())
}

fn parse_ascii(bytes: &[u8], path: &Path) -> Result<SurfaceData, MeshIoError> {
    let text = utf8(bytes, path, "ASCII STL")?;
    let mut tokens = Tokens::new(text);
    let mut weld = Welder::with_capacity(text.len() / 200);
    let mut polygon: Vec<Vec3> = Vec::new();
    let err =
        |tokens: &Tokens<'_>, message: String| MeshIoError::parse(path, tokens.line(), message);
    // One or more `solid NAME ... endsolid [NAME]` blocks.
    while tokens.peek().is_some() {
        tokens.expect(path, "solid")?;
        tokens.rest_of_line(); // the name
        loop {
            let word = tokens.need(path, "`facet` or `endsolid`")?;
            if word.eq_ignore_ascii_case("endsolid") {
                tokens.rest_of_line();
                break;
            }
            if !word.eq_ignore_ascii_case("facet") {
                return Err(err(
                    &tokens,
                    format!("expected `facet` or `endsolid`, found `{}`", shorten(word)),
                ));
            }
            tokens.expect(path, "normal")?;
            for _ in 0..3 {
                tokens.number::<f32>(path, "a normal component (a number)")?;
            }
            tokens.expect(path, "outer")?;
            tokens.expect(path, "loop")?;
            polygon.clear();
            while tokens
                .peek()
                .is_some_and(|w| w.eq_ignore_ascii_case("vertex"))
            {
                tokens.next_token();
                let mut p = [0.0f32; 3];
                for (axis, v) in ["x", "y", "z"].iter().zip(p.iter_mut()) {
                    *v = tokens.number(path, &format!("the {axis} coordinate of a vertex"))?;
                }
                polygon.push(Vec3::from_array(p));
            }
            if polygon.len() < 3 {
                tokens.next_token();
                return Err(err(
                    &tokens,
                    format!(
                        "a facet needs 3 `vertex` lines before `endloop`, this one has {}",
                        polygon.len()
                    ),
                ));
            }
            tokens.expect(path, "endloop")?;
            tokens.expect(path, "endfacet")?;
            let line = tokens.line();
            // More than 3 vertices in a loop: not standard, but harmless to fan-triangulate.
            if let Some((&first, rest)) = polygon.split_first() {
                for pair in rest.windows(2) {
                    if let [b, c] = *pair {
                        weld.triangle([first, b, c])
                            .map_err(|m| MeshIoError::parse(path, line, m))?;
                    }
                }
            }
        }
    }
    Ok(weld.finish())
}

/// Merges bitwise-equal corners into vertices, in order of first appearance.
struct Welder {
    index: HashMap<[u32; 3], u32>,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Welder {
    fn with_capacity(triangles: usize) -> Self {
        Welder {
            index: HashMap::with_capacity(triangles / 2),
            positions: Vec::with_capacity(triangles / 2),
            triangles: Vec::with_capacity(triangles),
        }
    }

    fn triangle(&mut self, corners: [Vec3; 3]) -> Result<(), String> {
        let mut tri = [0u32; 3];
        for (slot, p) in tri.iter_mut().zip(corners) {
            let key = p.to_array().map(f32::to_bits);
            let next = self.positions.len();
            *slot = match self.index.get(&key) {
                Some(&i) => i,
                None => {
                    let i = u32::try_from(next)
                        .ok()
                        .filter(|&i| i < u32::MAX)
                        .ok_or("more than 2^32 - 2 distinct vertices: split the mesh")?;
                    self.index.insert(key, i);
                    self.positions.push(p);
                    i
                }
            };
        }
        self.triangles.push(tri);
        Ok(())
    }

    fn finish(self) -> SurfaceData {
        SurfaceData {
            positions: self.positions,
            triangles: self.triangles,
        }
    }
}

/// Writes a surface as binary STL, atomically, with unit facet normals from the winding (zero
/// for a zero-area triangle). Corners are stored as `f32`, so positions read back
/// bit-identically; vertex numbering comes back in order of first appearance.
pub fn write_stl(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("write_stl", path = %path.display()).entered();
    let count = u32::try_from(mesh.triangle_count()).map_err(|_| {
        MeshIoError::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "binary STL holds at most 2^32 - 1 triangles",
            ),
        )
    })?;
    let positions = mesh.positions();
    let mut records = Vec::with_capacity(mesh.triangle_count());
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let mut c = [Vec3::ZERO; 3];
        for (slot, &i) in c.iter_mut().zip(tri) {
            *slot = *positions
                .get(i as usize)
                .ok_or_else(|| MeshIoError::IndexOutOfRange {
                    path: path.to_path_buf(),
                    element: "triangle",
                    index: t,
                    vertex: i,
                    vertex_count: positions.len(),
                })?;
        }
        let [a, b, cc] = c;
        let normal = (b - a).cross(cc - a).normalize_or_zero();
        records.push([normal, a, b, cc]);
    }
    write_atomic(path, |w| {
        let mut header = [b' '; HEADER];
        let label = b"binary STL written by tissue-meshio";
        for (h, l) in header.iter_mut().zip(label) {
            *h = *l;
        }
        w.write_all(&header)?;
        w.write_all(&count.to_le_bytes())?;
        for record in &records {
            for v in record {
                for c in v.to_array() {
                    w.write_all(&c.to_le_bytes())?;
                }
            }
            w.write_all(&[0, 0])?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TETRA: &str = "solid t\n facet normal 0 0 -1\n  outer loop\n   vertex 0 0 0\n   vertex 0 1 0\n   vertex 1 0 0\n  endloop\n endfacet\n\
        facet normal 0 0 0\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 0 0 1\n endloop\n endfacet\n\
        facet normal 0 0 0\n outer loop\n vertex 0 0 0\n vertex 0 0 1\n vertex 0 1 0\n endloop\n endfacet\n\
        FACET NORMAL 1 1 1\n OUTER LOOP\n VERTEX 1 0 0\n VERTEX 0 1 0\n VERTEX 0 0 1\n ENDLOOP\n ENDFACET\nendsolid t\n";

    #[test]
    fn ascii_tetrahedron_is_welded() {
        let d = parse_stl(TETRA.as_bytes(), "t.stl").unwrap();
        assert_eq!(d.positions.len(), 4);
        assert_eq!(
            d.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [2, 1, 3]]
        );
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let bad = TETRA.replacen("vertex 0 1 0", "vertex 0 one 0", 1);
        let e = parse_stl(bad.as_bytes(), "t.stl").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 5, .. }), "{e}");
        let cut = &TETRA[..TETRA.len() - 12];
        let e = parse_stl(cut.as_bytes(), "t.stl").unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
    }

    #[test]
    fn binary_with_solid_header_is_binary() {
        let mut bytes = b"solid but binary".to_vec();
        bytes.resize(80, 0);
        bytes.extend_from_slice(&1u32.to_le_bytes());
        for v in [
            [0.0f32; 3],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ] {
            for c in v {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
        let d = parse_stl(&bytes, "b.stl").unwrap();
        assert_eq!(d.triangles, vec![[0, 1, 2]]);
        // Cut short: the binary explanation wins over an ASCII parse error.
        let e = parse_stl(&bytes[..120], "b.stl").unwrap_err();
        assert!(
            matches!(&e, MeshIoError::Binary { element, index: Some(0), .. } if element == "triangle"),
            "{e}"
        );
    }

    #[test]
    fn weld_keeps_signed_zeros_apart() {
        let mut w = Welder::with_capacity(2);
        w.triangle([Vec3::ZERO, Vec3::X, Vec3::Y]).unwrap();
        w.triangle([Vec3::new(-0.0, 0.0, 0.0), Vec3::X, Vec3::Y])
            .unwrap();
        let d = w.finish();
        assert_eq!(d.positions.len(), 4);
        assert_eq!(d.triangles, vec![[0, 1, 2], [3, 1, 2]]);
    }
}
