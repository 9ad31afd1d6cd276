//! Stanford PLY: ASCII and binary (little and big endian) in, binary little endian out.
//!
//! Read: element `vertex` with scalar properties `x`, `y`, `z` (any numeric type; `double` is
//! rounded to `f32`), and optionally element `face` with an integer list property
//! `vertex_indices` (or `vertex_index`); polygons are fan-triangulated. Other elements and
//! properties (normals, colours, `edge`, ...) are read past and ignored. Elements may come in any
//! order. A file without `face` gives a surface without triangles.
//!
//! The header and the element records are parsed by `ply-rs` 0.1.3, but this module drives it
//! one element at a time so that errors name the element (and, for ASCII, the line), and guards
//! the two inputs that would make it panic or hang:
//! - a number in the header with more digits than fit in a `u64` (its grammar `unwrap`s the
//!   parse; checked by [`check_header`] before ply-rs sees the header);
//! - a huge element count for an element without properties (it would loop that many times
//!   reading nothing; such elements carry no data, so they are skipped for binary files and
//!   bounded by the remaining lines for ASCII ones);
//! - long element and property names: ply-rs copies every property's name for every record it
//!   reads, so a 1 MiB name on a 1-byte property would cost 1 MiB of copying per byte of the
//!   body. Names longer than [`MAX_NAME`] bytes are refused (checked by the same scan).
//!
//! Every other read consumes at least one byte or one line per element, so a corrupt count ends
//! in an error at the end of the data instead of a long loop. The vertex capacity reserved for
//! the declared count is bounded by what the body can hold at the smallest record size the
//! header allows (so by about the body's size for binary files, twice it for ASCII), and an
//! ASCII body is read line by line, never split into a list of lines first.

use std::io::{Cursor, Write};
use std::path::Path;

use glam::Vec3;
use ply_rs::parser::Parser;
use ply_rs::ply::{ElementDef, Encoding, Property, PropertyAccess, PropertyType, ScalarType};
use tissue_mesh::TriMesh;

use crate::atomic::{read_file, write_atomic};
use crate::obj::fan;
use crate::text::{capacity, line_of_offset, shorten};
use crate::{MeshIoError, SurfaceData};

/// Reads a PLY file's positions and triangles (see the module docs for what is kept).
pub fn read_ply(path: impl AsRef<Path>) -> Result<SurfaceData, MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("read_ply", path = %path.display()).entered();
    parse_ply(&read_file(path)?, path)
}

/// One element record as read by ply-rs: only the properties we use are kept.
#[derive(Default)]
struct Row {
    xyz: [f64; 3],
    indices: Vec<i64>,
}

impl PropertyAccess for Row {
    fn new() -> Self {
        Row::default()
    }

    fn set_property(&mut self, name: String, property: Property) {
        let axis = match name.as_str() {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            "vertex_indices" | "vertex_index" => {
                self.indices = int_list(property);
                return;
            }
            _ => return,
        };
        if let Some(v) = self.xyz.get_mut(axis) {
            *v = scalar(&property);
        }
    }
}

fn scalar(p: &Property) -> f64 {
    match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        // The header check admits only scalar coordinates.
        _ => f64::NAN,
    }
}

fn int_list(p: Property) -> Vec<i64> {
    fn widen<T: Copy + Into<i64>>(v: Vec<T>) -> Vec<i64> {
        v.into_iter().map(Into::into).collect()
    }
    match p {
        Property::ListChar(v) => widen(v),
        Property::ListUChar(v) => widen(v),
        Property::ListShort(v) => widen(v),
        Property::ListUShort(v) => widen(v),
        Property::ListInt(v) => widen(v),
        Property::ListUInt(v) => widen(v),
        // The header check admits only integer index lists.
        _ => Vec::new(),
    }
}

fn is_int(t: &ScalarType) -> bool {
    !matches!(t, ScalarType::Float | ScalarType::Double)
}

/// What an element is to us.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Vertex,
    Face,
    Other,
}

/// Parses PLY data held in memory; `name` stands for the file in error messages.
pub fn parse_ply(bytes: &[u8], name: impl AsRef<Path>) -> Result<SurfaceData, MeshIoError> {
    let path = name.as_ref();
    let element_lines = check_header(bytes, path)?;
    let header_line = |element: &str| {
        element_lines
            .iter()
            .find(|(n, _)| n == element)
            .map_or(1, |&(_, l)| l)
    };
    let mut cursor = Cursor::new(bytes);
    let parser = Parser::<Row>::new();
    let header = parser.read_header(&mut cursor).map_err(|e| {
        let pos = usize::try_from(cursor.position()).unwrap_or(bytes.len());
        let line = failed_line(bytes, pos);
        let text = bytes.split(|&b| b == b'\n').nth(line.saturating_sub(1)).unwrap_or_default();
        MeshIoError::parse(
            path,
            line,
            format!(
                "not a valid PLY header line `{}`: {} (a header is `ply`, `format ascii|binary_little_endian|binary_big_endian 1.0`, then `element NAME COUNT` lines each followed by `property TYPE NAME` or `property list COUNT_TYPE TYPE NAME` lines, and `end_header`)",
                shorten(String::from_utf8_lossy(text).trim()),
                reason(&e)
            ),
        )
    })?;
    let body = usize::try_from(cursor.position()).unwrap_or(bytes.len());

    let vertex = header.elements.get("vertex").ok_or_else(|| {
        MeshIoError::parse(
            path,
            1,
            "the header declares no `element vertex`: a PLY mesh needs one with properties x, y, z",
        )
    })?;
    for axis in ["x", "y", "z"] {
        match vertex.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(PropertyType::List(..)) => {
                return Err(MeshIoError::parse(
                    path,
                    header_line("vertex"),
                    format!(
                        "vertex property `{axis}` is a list: declare it as `property float {axis}`"
                    ),
                ))
            }
            None => {
                return Err(MeshIoError::parse(
                    path,
                    header_line("vertex"),
                    format!("element vertex has no property `{axis}`: add `property float {axis}`"),
                ))
            }
        }
    }
    let vertex_count = vertex.count;
    if vertex_count >= u32::MAX as usize {
        return Err(MeshIoError::parse(
            path,
            header_line("vertex"),
            format!("{vertex_count} vertices: at most 2^32 - 2 are supported"),
        ));
    }
    if let Some(face) = header.elements.get("face") {
        let list = ["vertex_indices", "vertex_index"]
            .iter()
            .find_map(|n| face.properties.get(*n));
        match list.map(|p| &p.data_type) {
            Some(PropertyType::List(count, item)) if is_int(count) && is_int(item) => {}
            Some(_) => {
                return Err(MeshIoError::parse(
                    path,
                    header_line("face"),
                    "the face index list must be a list of integers, e.g. `property list uchar int vertex_indices`",
                ))
            }
            None => {
                return Err(MeshIoError::parse(
                    path,
                    header_line("face"),
                    "element face has no `vertex_indices` (or `vertex_index`) list property",
                ))
            }
        }
    }

    let rest = bytes.get(body..).unwrap_or_default();
    let ascii = header.encoding == Encoding::Ascii;
    let mut out = SurfaceData {
        positions: Vec::with_capacity(capacity(
            vertex_count,
            rest.len(),
            min_record_bytes(vertex, ascii),
        )),
        triangles: Vec::new(),
    };
    let mut polygon = Vec::new();
    let kind_of = |name: &str| match name {
        "vertex" => Kind::Vertex,
        "face" => Kind::Face,
        _ => Kind::Other,
    };

    match header.encoding {
        Encoding::Ascii => {
            let mut line = line_of_offset(bytes, body);
            // Lines are taken one at a time, never collected: a list of every line would cost
            // 16 bytes per line, 16 times the size of a file of empty lines. The newline ending
            // the last line starts no new one, and an empty body has no lines.
            let body_lines = rest.strip_suffix(b"\n").unwrap_or(rest);
            let mut lines = (!rest.is_empty())
                .then(|| body_lines.split(|&b| b == b'\n'))
                .into_iter()
                .flatten();
            for (name, def) in &header.elements {
                let kind = kind_of(name);
                for index in 0..def.count {
                    let Some(raw) = lines.next() else {
                        return Err(MeshIoError::parse(
                            path,
                            line,
                            format!(
                                "the file ends after {index} of the {} `{name}` elements the header declares: it is truncated, or the count is wrong",
                                def.count
                            ),
                        ));
                    };
                    let at = |message: String| {
                        MeshIoError::parse(path, line, format!("{name} {index}: {message}"))
                    };
                    let text = std::str::from_utf8(raw)
                        .map_err(|_| at("not text (not UTF-8): is the file binary?".into()))?;
                    let row = parser.read_ascii_element(text, def).map_err(|e| {
                        let names: Vec<&str> = def.properties.keys().map(String::as_str).collect();
                        at(format!(
                            "cannot read `{}` as numbers for the properties the header declares ({}): {}",
                            shorten(text.trim()),
                            names.join(" "),
                            reason(&e)
                        ))
                    })?;
                    take(kind, &row, vertex_count, &mut out, &mut polygon).map_err(at)?;
                    line += 1;
                }
            }
        }
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            let little = header.encoding == Encoding::BinaryLittleEndian;
            if fast_binary(rest, &header, little, vertex_count, &mut out, &mut polygon).is_some() {
                return Ok(out);
            }
            out.positions.clear();
            out.triangles.clear();
            for (name, def) in &header.elements {
                if def.properties.is_empty() {
                    continue; // nothing stored, whatever the count
                }
                let kind = kind_of(name);
                for index in 0..def.count {
                    let start = cursor.position();
                    let at = |message: String| {
                        MeshIoError::binary(path, name.as_str(), Some(index), message)
                    };
                    let row = read_binary(&parser, &mut cursor, def, little).map_err(|e| {
                        let why = if e.kind() == std::io::ErrorKind::UnexpectedEof
                            || e.to_string().contains("Couldn't find a list element")
                        {
                            "the file ends inside it".to_string()
                        } else {
                            reason(&e)
                        };
                        at(format!(
                            "cannot read it at byte {start} of {}: {why}; the file is truncated, or the header does not match the data",
                            bytes.len()
                        ))
                    })?;
                    take(kind, &row, vertex_count, &mut out, &mut polygon).map_err(at)?;
                }
            }
        }
    }
    Ok(out)
}

/// The fewest bytes one record of `def` can take in the file: the sizes of its scalars and list
/// counts (binary), or a character and a separator per property (ASCII). Bounds the capacity
/// reserved for a declared count by what the body can hold.
fn min_record_bytes(def: &ElementDef, ascii: bool) -> usize {
    if ascii {
        return 2 * def.properties.len();
    }
    def.properties
        .values()
        .map(|p| match &p.data_type {
            PropertyType::Scalar(t) | PropertyType::List(t, _) => scalar_size(t),
        })
        .sum()
}

fn scalar_size(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

fn read_binary(
    parser: &Parser<Row>,
    cursor: &mut Cursor<&[u8]>,
    def: &ElementDef,
    little: bool,
) -> std::io::Result<Row> {
    if little {
        parser.read_little_endian_element(cursor, def)
    } else {
        parser.read_big_endian_element(cursor, def)
    }
}

/// The binary body read straight from the bytes, without ply-rs's per-record maps and strings
/// (a fine scan has millions of records) into `out`: what reading the records one by one gives, or `None`
/// at the first thing that is not plainly right (the file ends, an index is out of range, a
/// face has fewer than 3 vertices), where the record-by-record reading then says what.
fn fast_binary(
    rest: &[u8],
    header: &ply_rs::ply::Header,
    little: bool,
    vertex_count: usize,
    out: &mut SurfaceData,
    polygon: &mut Vec<u32>,
) -> Option<()> {
    let mut row = Row::default();
    let mut at = 0usize;
    for (name, def) in &header.elements {
        if def.properties.is_empty() {
            continue;
        }
        let kind = match name.as_str() {
            "vertex" => Kind::Vertex,
            "face" => Kind::Face,
            _ => Kind::Other,
        };
        // What each property is to us: an axis (0–2), the index list (3) or nothing (4).
        let properties: Vec<(usize, &PropertyType)> = def
            .properties
            .iter()
            .map(|(name, p)| {
                let role = match name.as_str() {
                    "x" => 0,
                    "y" => 1,
                    "z" => 2,
                    "vertex_indices" | "vertex_index" => 3,
                    _ => 4,
                };
                (role, &p.data_type)
            })
            .collect();
        for _ in 0..def.count {
            for &(role, data_type) in &properties {
                match data_type {
                    PropertyType::Scalar(t) => {
                        let v = binary_scalar(rest, &mut at, t, little)?;
                        if let Some(axis) = row.xyz.get_mut(role) {
                            *axis = v;
                        }
                    }
                    PropertyType::List(count_type, item) => {
                        let count = binary_scalar(rest, &mut at, count_type, little)?;
                        if !(count >= 0.0 && count.fract() == 0.0) {
                            return None;
                        }
                        let count = count as usize;
                        if role == 3 {
                            row.indices.clear();
                            for _ in 0..count {
                                let i = binary_scalar(rest, &mut at, item, little)?;
                                row.indices.push(i as i64);
                            }
                        } else {
                            at = at.checked_add(count.checked_mul(scalar_size(item))?)?;
                            if at > rest.len() {
                                return None;
                            }
                        }
                    }
                }
            }
            take(kind, &row, vertex_count, out, polygon).ok()?;
        }
    }
    Some(())
}

/// One binary scalar at `*at` (which moves past it), widened to `f64` (exact for every PLY
/// integer type); `None` past the end.
fn binary_scalar(bytes: &[u8], at: &mut usize, t: &ScalarType, little: bool) -> Option<f64> {
    fn take_n<const N: usize>(bytes: &[u8], at: &mut usize, little: bool) -> Option<[u8; N]> {
        let mut raw: [u8; N] = bytes.get(*at..at.checked_add(N)?)?.try_into().ok()?;
        *at += N;
        if !little {
            raw.reverse();
        }
        Some(raw)
    }
    Some(match t {
        ScalarType::Char => f64::from(i8::from_le_bytes(take_n(bytes, at, little)?)),
        ScalarType::UChar => f64::from(u8::from_le_bytes(take_n(bytes, at, little)?)),
        ScalarType::Short => f64::from(i16::from_le_bytes(take_n(bytes, at, little)?)),
        ScalarType::UShort => f64::from(u16::from_le_bytes(take_n(bytes, at, little)?)),
        ScalarType::Int => f64::from(i32::from_le_bytes(take_n(bytes, at, little)?)),
        ScalarType::UInt => f64::from(u32::from_le_bytes(take_n(bytes, at, little)?)),
        ScalarType::Float => f64::from(f32::from_le_bytes(take_n(bytes, at, little)?)),
        ScalarType::Double => f64::from_le_bytes(take_n(bytes, at, little)?),
    })
}

/// Stores one element record; an error says what is wrong with it.
fn take(
    kind: Kind,
    row: &Row,
    vertex_count: usize,
    out: &mut SurfaceData,
    polygon: &mut Vec<u32>,
) -> Result<(), String> {
    match kind {
        Kind::Vertex => {
            let [x, y, z] = row.xyz;
            out.positions.push(Vec3::new(x as f32, y as f32, z as f32));
        }
        Kind::Face => {
            polygon.clear();
            for &i in &row.indices {
                match u32::try_from(i) {
                    Ok(v) if (v as usize) < vertex_count => polygon.push(v),
                    _ => {
                        return Err(format!(
                            "refers to vertex {i}, but the header declares {vertex_count} vertices (indices count from 0)"
                        ))
                    }
                }
            }
            if polygon.len() < 3 {
                return Err(format!(
                    "a face needs at least 3 vertices, this one has {}",
                    polygon.len()
                ));
            }
            fan(polygon, &mut out.triangles);
        }
        Kind::Other => {}
    }
    Ok(())
}

/// The longest element or property name a PLY header may use. PLY writers use short names
/// (`vertex_indices`, `scalar_intensity`); ply-rs copies each property's name once per record,
/// so this bounds that copying to a small multiple of the body's size.
const MAX_NAME: usize = 255;

/// Rejects header numbers that do not fit in a `u64`: ply-rs 0.1.3's header grammar parses
/// every digit run of `element` and `format` lines with `unwrap()`, so one would panic. Checks
/// every header line except comments (a false alarm on a property name with 20 digits is the
/// price of not re-implementing its grammar). Also rejects `element` and `property` names
/// longer than [`MAX_NAME`]. Returns each `element` line's name and line number, for error
/// messages.
fn check_header(bytes: &[u8], path: &Path) -> Result<Vec<(String, usize)>, MeshIoError> {
    let mut elements = Vec::new();
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let text = String::from_utf8_lossy(raw);
        let text = text.trim_end();
        let mut words = text.split_whitespace();
        let first = words.next();
        if matches!(first, Some("comment" | "obj_info")) {
            continue;
        }
        // The name is the second word of an `element` line and the last of a `property` line.
        let name = match first {
            Some("element") => words.next(),
            Some("property") => words.last(),
            _ => None,
        };
        if let Some(name) = name.filter(|n| n.len() > MAX_NAME) {
            return Err(MeshIoError::parse(
                path,
                line,
                format!(
                    "the name `{}` is {} bytes long: this reader takes names of at most {MAX_NAME} bytes",
                    shorten(name),
                    name.len()
                ),
            ));
        }
        if first == Some("element") {
            if let Some(name) = name {
                elements.push((name.to_string(), line));
            }
        }
        for run in text
            .split(|c: char| !c.is_ascii_digit())
            .filter(|r| !r.is_empty())
        {
            if run.parse::<u64>().is_err() {
                return Err(MeshIoError::parse(
                    path,
                    line,
                    format!(
                        "the number `{}` in the header is too large (more than 64 bits)",
                        shorten(run)
                    ),
                ));
            }
        }
        if text == "end_header" {
            break;
        }
    }
    Ok(elements)
}

/// The line a line-by-line reader stopped on, when it has consumed `pos` bytes.
fn failed_line(bytes: &[u8], pos: usize) -> usize {
    let upto = bytes.get(..pos).unwrap_or(bytes);
    let newlines = upto.iter().filter(|&&b| b == b'\n').count();
    if upto.last() == Some(&b'\n') {
        newlines.max(1)
    } else {
        newlines + 1
    }
}

/// The gist of a ply-rs error: its first sentence, without its `Line N:` prefix (we give the
/// line), the echoed input and the grammar's debug dump; on one line.
fn reason(e: &std::io::Error) -> String {
    let text = e.to_string();
    let first = text.split("\n\t").next().unwrap_or_default();
    let first = match first.strip_prefix("Line ") {
        Some(rest) => rest.split_once(": ").map_or(rest, |(_, r)| r),
        None => first,
    };
    first.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Writes a surface as binary little-endian PLY, atomically: `float x y z` vertices and
/// `list uchar int vertex_indices` faces (`uint` if there are more than 2^31 - 1 vertices).
/// Positions read back bit-identically.
pub fn write_ply(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("write_ply", path = %path.display()).entered();
    let index_type = if mesh.vertex_count() > i32::MAX as usize {
        "uint"
    } else {
        "int"
    };
    write_atomic(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment tissue-meshio\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar {index_type} vertex_indices\nend_header\n",
            mesh.vertex_count(),
            mesh.triangle_count()
        )?;
        for p in mesh.positions() {
            for c in p.to_array() {
                w.write_all(&c.to_le_bytes())?;
            }
        }
        for tri in mesh.triangles() {
            w.write_all(&[3])?;
            for i in tri {
                // The same four bytes serve `int` (indices < 2^31) and `uint`.
                w.write_all(&i.to_le_bytes())?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\n\
        property float x\nproperty float y\nproperty double z\nproperty uchar red\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0 1\n1 0 0 2\n1 1 0.5 3\n0 1 0 4\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_becomes_two_triangles() {
        let d = parse_ply(ASCII.as_bytes(), "q.ply").unwrap();
        assert_eq!(d.positions.len(), 4);
        assert_eq!(d.positions[2], Vec3::new(1.0, 1.0, 0.5));
        assert_eq!(d.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn ascii_errors_name_line_and_element() {
        let bad = ASCII.replace("1 1 0.5 3", "1 1 zz 3");
        let e = parse_ply(bad.as_bytes(), "q.ply").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 14, .. }), "{e}");
        assert!(e.to_string().contains("vertex 2"), "{e}");

        let bad = ASCII.replace("4 0 1 2 3", "4 0 1 2 7");
        let e = parse_ply(bad.as_bytes(), "q.ply").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 16, .. }), "{e}");
        assert!(e.to_string().contains("face 0"), "{e}");

        let cut = &ASCII[..ASCII.len() - 10];
        let e = parse_ply(cut.as_bytes(), "q.ply").unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
    }

    #[test]
    fn huge_header_number_is_an_error_not_a_panic() {
        let bad = ASCII.replace("element vertex 4", "element vertex 99999999999999999999999");
        let e = parse_ply(bad.as_bytes(), "q.ply").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 4, .. }), "{e}");
        let bad = ASCII.replace("ascii 1.0", "ascii 1.99999999999999999999999");
        assert!(parse_ply(bad.as_bytes(), "q.ply").is_err());
    }

    #[test]
    fn huge_count_of_empty_elements_is_skipped() {
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 0\n\
            property float x\nproperty float y\nproperty float z\n\
            element nothing 18446744073709551615\nend_header\n";
        let d = parse_ply(text.as_bytes(), "e.ply").unwrap();
        assert!(d.positions.is_empty());
        let ascii = text.replace("binary_little_endian", "ascii");
        assert!(parse_ply(ascii.as_bytes(), "e.ply").is_err());
    }

    #[test]
    fn long_names_are_refused() {
        let long = "n".repeat(MAX_NAME + 1);
        let bad = ASCII.replace("property uchar red", &format!("property uchar {long}"));
        let e = parse_ply(bad.as_bytes(), "q.ply").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 8, .. }), "{e}");
        assert!(e.to_string().contains("256 bytes long"), "{e}");
        let bad = ASCII.replace("element face 1", &format!("element {long} 1"));
        assert!(parse_ply(bad.as_bytes(), "q.ply").is_err());
        // At the limit, and in comments, names of any length are fine.
        let ok = ASCII
            .replace(
                "property uchar red",
                &format!("property uchar {}", &long[1..]),
            )
            .replace("comment hi", &format!("comment {long}{long}"));
        assert_eq!(
            parse_ply(ok.as_bytes(), "q.ply").unwrap().positions.len(),
            4
        );
    }

    #[test]
    fn header_errors_name_the_line() {
        let bad = ASCII.replace("property uchar red", "property banana red");
        let e = parse_ply(bad.as_bytes(), "q.ply").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 8, .. }), "{e}");
        let bad = ASCII.replace("property double z\n", "");
        let e = parse_ply(bad.as_bytes(), "q.ply").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 4, .. }), "{e}");
        assert!(e.to_string().contains("`z`"), "{e}");
    }
}
