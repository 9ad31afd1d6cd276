//! Wavefront OBJ: `v` positions and `f` faces by position index, in and out.
//!
//! Read: `v x y z [w | r g b]` (only x y z are kept; `w` is a curve weight and colours are not
//! ours), `f` with `v`, `v/vt`, `v//vn` or `v/vt/vn` corners, 1-based or negative (relative)
//! indices, polygons fan-triangulated (`a b c d` → `a b c`, `a c d`). Only position indices
//! count, so texture and normal seams do not split vertices, and groups, objects and materials
//! do not either: all faces index one vertex list, in file order. `#` starts a comment anywhere
//! on a line; every other statement (`vt`, `vn`, `l`, `p`, `g`, `usemtl`, ...) is skipped.
//!
//! Why not `tobj`: tobj 4.0 is what the design card named, and the parser here agrees with it on
//! well-formed files (a test checks). But for a file reader that must list every defect and
//! keep the file's own numbering, tobj returns the wrong data: it renumbers vertices in order of
//! first use by a face, drops vertices no face uses (so an unreferenced-vertex defect can never
//! be reported), gives each group (`g`/`o`/`usemtl`) its own copy of shared vertices (cracking a
//! multi-group surface along group borders), and its errors carry no line number. It can also
//! panic (integer overflow in `vt * 2 + 1`) on a huge `vt`/`vn` index. Guarding all of that
//! needed a scan as long as this parser.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use tissue_mesh::TriMesh;

use crate::atomic::{read_file, write_atomic};
use crate::text::{parse_number, shorten, F};
use crate::{MeshIoError, SurfaceData};

/// Reads an OBJ file's positions and triangles (see the module docs for what is kept).
pub fn read_obj(path: impl AsRef<Path>) -> Result<SurfaceData, MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("read_obj", path = %path.display()).entered();
    parse_obj(&read_file(path)?, path)
}

/// Parses OBJ text held in memory; `name` stands for the file in error messages.
pub fn parse_obj(bytes: &[u8], name: impl AsRef<Path>) -> Result<SurfaceData, MeshIoError> {
    let path = name.as_ref();
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    // Absolute indices may point past the vertices read so far (forward references); they are
    // checked at the end, against the final count.
    let mut forward = ForwardRefs::default();
    let mut polygon: Vec<u32> = Vec::new();
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let content = match raw.iter().position(|&b| b == b'#') {
            Some(hash) => raw.get(..hash).unwrap_or_default(),
            None => raw,
        };
        let mut words = content
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => {
                let mut xyz = [0.0f32; 3];
                for (axis, value) in ["x", "y", "z"].iter().zip(xyz.iter_mut()) {
                    let what = format!("the {axis} coordinate of a vertex (`v x y z`)");
                    let word = words.next().ok_or_else(|| {
                        MeshIoError::parse(
                            path,
                            line,
                            format!("expected {what}, found the end of the line"),
                        )
                    })?;
                    *value = parse_number(&String::from_utf8_lossy(word), path, line, &what)?;
                }
                if positions.len() >= u32::MAX as usize {
                    return Err(MeshIoError::parse(
                        path,
                        line,
                        "more than 2^32 - 1 vertices: split the mesh",
                    ));
                }
                positions.push(glam::Vec3::from_array(xyz));
            }
            Some(b"f") => {
                polygon.clear();
                for word in words {
                    let index = face_corner(word, positions.len(), path, line)?;
                    if index as usize >= positions.len() {
                        forward.add(line, index);
                    }
                    polygon.push(index);
                }
                if polygon.len() < 3 {
                    return Err(MeshIoError::parse(
                        path,
                        line,
                        format!(
                            "a face needs at least 3 vertices, this one has {}: remove the line or complete it",
                            polygon.len()
                        ),
                    ));
                }
                fan(&polygon, &mut triangles);
            }
            _ => {}
        }
    }
    if let Some((line, index)) = forward.first_beyond(positions.len()) {
        return Err(MeshIoError::parse(
            path,
            line,
            format!(
                "face refers to vertex {}, but the file has only {} vertices (`v` lines): fix the index or add the vertex",
                u64::from(index) + 1,
                positions.len()
            ),
        ));
    }
    Ok(SurfaceData {
        positions,
        triangles,
    })
}

/// The forward references of a file, enough of them to name the first (in file order) that
/// is still out of range at the end.
///
/// That one refers past every index before it (those are all in range), so it is a new
/// maximum: only the references that raise the maximum so far are kept, in file order. A file
/// of `f 9 9 9` lines before its vertices keeps one entry, not one per corner.
#[derive(Default)]
struct ForwardRefs {
    /// (line, 0-based index), the indices strictly increasing.
    maxima: Vec<(usize, u32)>,
}

impl ForwardRefs {
    fn add(&mut self, line: usize, index: u32) {
        if self.maxima.last().is_none_or(|&(_, max)| index > max) {
            self.maxima.push((line, index));
        }
    }

    /// The first reference to an index `>= count`, as (line, index).
    fn first_beyond(&self, count: usize) -> Option<(usize, u32)> {
        self.maxima
            .iter()
            .find(|&&(_, index)| index as usize >= count)
            .copied()
    }
}

/// Appends the fan triangulation `p0 p(k) p(k+1)` of a polygon.
pub(crate) fn fan(polygon: &[u32], triangles: &mut Vec<[u32; 3]>) {
    if let Some((&first, rest)) = polygon.split_first() {
        for pair in rest.windows(2) {
            if let [b, c] = *pair {
                triangles.push([first, b, c]);
            }
        }
    }
}

/// The 0-based position index of one face corner `v[/vt[/vn]]`; `count` is the number of
/// vertices read so far (relative indices count back from it).
fn face_corner(word: &[u8], count: usize, path: &Path, line: usize) -> Result<u32, MeshIoError> {
    let word = String::from_utf8_lossy(word);
    let bad = |why: String| MeshIoError::parse(path, line, why);
    let mut parts = word.split('/');
    let v = parts.next().unwrap_or_default();
    let what = "a vertex index (`f v1 v2 v3`, `f v1/vt1 ...` or `f v1//vn1 ...`)";
    let v: i64 = parse_number(v, path, line, what)?;
    for (k, part) in parts.enumerate() {
        if k >= 2 {
            return Err(bad(format!(
                "face corner `{}` has more than three `/`-separated indices (expected v/vt/vn)",
                shorten(&word)
            )));
        }
        if !part.is_empty() && part.parse::<i64>().is_err() {
            return Err(bad(format!(
                "expected a texture or normal index in face corner `{}`, found `{}`",
                shorten(&word),
                shorten(part)
            )));
        }
    }
    let index = match v {
        0 => {
            return Err(bad(
                "vertex index 0 in a face: OBJ indices start at 1 (or count back from -1)".into(),
            ))
        }
        v if v > 0 => v - 1,
        v => count as i64 + v,
    };
    if index < 0 {
        return Err(bad(format!(
            "relative vertex index {v} reaches before the first vertex: only {count} vertices precede this line"
        )));
    }
    u32::try_from(index)
        .ok()
        .filter(|&i| i < u32::MAX)
        .ok_or_else(|| {
            bad(format!(
                "vertex index {v} is too large (at most 2^32 - 1 vertices)"
            ))
        })
}

/// Writes a surface as OBJ (`v` and `f` lines, 1-based), atomically. Coordinates are written in
/// the shortest form that reads back to the same `f32` bits.
pub fn write_obj(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("write_obj", path = %path.display()).entered();
    write_atomic(path, |w| {
        writeln!(
            w,
            "# tissue-meshio: {} vertices, {} triangles",
            mesh.vertex_count(),
            mesh.triangle_count()
        )?;
        let mut line = String::with_capacity(64);
        for p in mesh.positions() {
            line.clear();
            // Writing to a String cannot fail.
            let _ = writeln!(line, "v {} {} {}", F(p.x), F(p.y), F(p.z));
            w.write_all(line.as_bytes())?;
        }
        for [a, b, c] in mesh.triangles() {
            writeln!(w, "f {} {} {}", a + 1, b + 1, c + 1)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<SurfaceData, MeshIoError> {
        parse_obj(text.as_bytes(), "t.obj")
    }

    #[test]
    fn corners_relative_and_slashed() {
        let d = parse("v 0 0 0\nv 1 0 0\nv 0 1 0 # c\nv 1 1 0\nf -4/1 -3//2 -2/1/1\nf 2/5/9 4 3\n")
            .unwrap();
        assert_eq!(d.triangles, vec![[0, 1, 2], [1, 3, 2]]);
        assert_eq!(d.positions.len(), 4);
    }

    #[test]
    fn quads_and_polygons_are_fans() {
        let d = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n").unwrap();
        assert_eq!(d.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn forward_references_resolve_at_the_end() {
        let d = parse("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(d.triangles, vec![[0, 1, 2]]);
        let e = parse("v 0 0 0\nf 1 2 3\nv 1 0 0\n").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 2, .. }), "{e}");
    }

    #[test]
    fn forward_references_keep_only_new_maxima() {
        let mut f = ForwardRefs::default();
        for (line, index) in [(1, 5), (1, 5), (2, 3), (3, 9), (4, 7), (5, 9), (6, 12)] {
            f.add(line, index);
        }
        assert_eq!(f.maxima, vec![(1, 5), (3, 9), (6, 12)]);
        assert_eq!(f.first_beyond(13), None);
        assert_eq!(f.first_beyond(10), Some((6, 12)));
        // Index 7 on line 4 is past 7 vertices, but line 3's 9 comes first.
        assert_eq!(f.first_beyond(7), Some((3, 9)));
        assert_eq!(f.first_beyond(0), Some((1, 5)));
        // A million references to one missing vertex keep one entry.
        let text = "f 3 3 3\n".repeat(1_000_000);
        let e = parse(&text).unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 1, .. }), "{e}");
    }

    #[test]
    fn errors_name_the_line() {
        for (text, line, needle) in [
            ("v 0 0 0\nv 1 0 x\n", 2, "z coordinate"),
            ("v 0 0\n", 1, "end of the line"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", 4, "start at 1"),
            ("v 0 0 0\nf 1 -2 1\n", 2, "before the first vertex"),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "at least 3"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n",
                4,
                "texture or normal",
            ),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", 4, "three"),
            ("v 0 0 0\nf 1 2 99999999999\n", 2, "too large"),
        ] {
            let e = parse(text).unwrap_err();
            match &e {
                MeshIoError::Parse {
                    line: l, message, ..
                } => {
                    assert_eq!(*l, line, "{e}");
                    assert!(message.contains(needle), "{e}");
                }
                other => panic!("{other}"),
            }
        }
    }
}
