//! VTK XML unstructured grids (`.vtu`), tetrahedra only (read only).
//!
//! Read: `<VTKFile type="UnstructuredGrid">` with one or more `<Piece>`s (concatenated), each
//! with `<Points>` (one `DataArray` of 3 components, any numeric type) and `<Cells>` with the
//! `connectivity`, `offsets` and `types` `DataArray`s (any integer type). Cells of type 10
//! (`VTK_TETRA`) are kept, in file order and with their corners as stored; every other cell type
//! (vertices, lines, triangles, quadratic cells, ...) is skipped, and a file without a single
//! tetrahedron is an error that lists what it holds. `PointData`, `CellData` and `FieldData` are
//! ignored.
//!
//! Data encodings: `format="ascii"`; `format="binary"` (inline base64 of a byte-count header and
//! the data, the header and data encoded together or separately as VTK and meshio do); and
//! `format="appended"` with `<AppendedData encoding="raw">` or `encoding="base64"`. The header's
//! integers are `UInt32` or `UInt64` (`header_type`, default `UInt32`), in `byte_order`
//! (`LittleEndian` or `BigEndian`). Compressed data: `compressor="vtkZLibDataCompressor"` (what
//! meshio writes by default) is read; LZ4 and LZMA are refused with an error that says to save
//! the file uncompressed or with zlib.
//!
//! Errors name the file and the line of the XML element at fault (for a `DataArray`, the line of
//! its tag, and the array's name).
//!
//! # Limits: what a file can make the reader do
//!
//! A `.vtu` may come from anyone (the studio reads uploads), and zlib data can claim up to about
//! 1000 times their size. So no count or size in a file is trusted before it is checked:
//! - **Every array's size is known before it is decoded.** `Points` must hold
//!   3 × `NumberOfPoints` values, `offsets` and `types` `NumberOfCells` values, and
//!   `connectivity` exactly as many as the last offset says (the offsets are read first). A
//!   binary array whose byte-count header (for compressed data: block size × (blocks − 1) + last
//!   block size) declares anything else is refused before a byte of it is decompressed or
//!   copied, with an error naming the array; an ASCII array stops at the first value too many.
//!   Nothing is widened to `f64`/`i64` beyond the expected count.
//! - **The decoded total is capped per file.** Every array read is charged 8 bytes per value
//!   (its size once widened, never less than its inflated size) before it is decoded, and the
//!   sum may not exceed [`MAX_INFLATION_RATIO`] × the file's size (but at least 1 MiB), nor
//!   [`MAX_INFLATED`] in any case. A compressed bomb therefore costs at most that much memory,
//!   and one of 400 KiB claiming 400 MiB is refused having allocated at most the size of its
//!   own text (`tests/peak_memory.rs`).
//! - **`NumberOfPoints` and `NumberOfCells`** are checked against [`MAX_INFLATED`] when the
//!   `<Piece>` is read: compressed data can make a small file legitimately large, so the bound is
//!   the absolute cap, not the file's size (which the per-file cap then applies).
//! - Arrays the reader does not use (`PointData`, `CellData`, `FieldData`, other `Cells` arrays)
//!   are never decoded, inflated or copied.
//! - Compressed blocks: each block's declared size must be within zlib's ratio of its
//!   compressed size (1100:1), and each block inflates at most its declared size.
//! - XML: elements nested more than [`MAX_DEPTH`] deep are refused; lines are counted as the
//!   parser goes and attributes are looked up without quick-xml's duplicate check (both were
//!   quadratic in the number of elements or attributes); the number of skipped cell types kept
//!   apart for the "no tetrahedra" message is bounded.

use std::borrow::Cow;
use std::cell::Cell;
use std::io::Read;
use std::path::Path;

use base64::Engine as _;
use glam::Vec3;
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

use crate::atomic::read_file;
use crate::tally::TypeCounts;
use crate::text::{capacity, line_of_offset, shorten};
use crate::{MeshIoError, TetData};

/// VTK's cell type number of a linear tetrahedron.
const VTK_TETRA: i64 = 10;

/// The most bytes the arrays of one `.vtu` file may decode to, whatever its size: 1 GiB.
///
/// Each value read counts 8 bytes (its size as `f64`/`i64`), so this bounds both the inflated
/// data and the decoded values. A 1.6-million-tetrahedron mesh, larger than anything tissue
/// simulates, decodes to about 80 MiB (0.3 M points: 7 MiB; 6.4 M connectivity values: 49 MiB;
/// 1.6 M offsets and types: 24 MiB), so 1 GiB leaves a factor of 12 and still refuses a bomb
/// long before it could exhaust a server's memory. Point and cell data are not read and do not
/// count.
pub const MAX_INFLATED: u64 = 1 << 30;

/// The most bytes the arrays of a `.vtu` file may decode to, per byte of the file (but at least
/// 1 MiB, so that small files are never refused for their compression ratio).
///
/// zlib alone allows about 1032:1. Real meshes compress far less: a regular grid of
/// tetrahedra, the most compressible mesh there is (round coordinates, regular connectivity,
/// every type 10), decodes to about 9 times the size of its zlib-compressed `.vtu` (counted as
/// [`MAX_INFLATED`] counts), and an unstructured mesh to about 5 times. 64 leaves a factor of 7
/// over the regular grid and caps what a 400 KiB upload can make the reader allocate at 25 MiB.
pub const MAX_INFLATION_RATIO: u64 = 64;

/// What any file may decode to, however small: 1 MiB.
const MIN_INFLATION_BUDGET: u64 = 1 << 20;

/// How deep XML elements may nest: a `.vtu` needs 7 levels (`VTKFile`, `UnstructuredGrid`,
/// `Piece`, `PointData`, `DataArray`, `InformationKey`, `Value`); anything near this bound is
/// not a `.vtu` file, and each level costs memory.
pub const MAX_DEPTH: usize = 64;

/// The decoding budget of a file of `len` bytes (see [`MAX_INFLATION_RATIO`]).
fn inflation_limit(len: usize) -> u64 {
    // `clamp` cannot panic: its bounds are in order (checked at compile time below).
    (len as u64)
        .saturating_mul(MAX_INFLATION_RATIO)
        .clamp(MIN_INFLATION_BUDGET, MAX_INFLATED)
}

const _: () = assert!(MIN_INFLATION_BUDGET <= MAX_INFLATED);

/// Reads the tetrahedra of a `.vtu` file (the subset described in the module docs).
///
/// Limits, for files from anyone: every array must hold exactly what the `<Piece>` says
/// (3 × `NumberOfPoints` point coordinates; `NumberOfCells` offsets and types; as many
/// connectivity values as the last offset), and a binary array whose header declares another
/// size is refused before it is decompressed, with an error naming the array. The arrays of a
/// file may decode to at most [`MAX_INFLATION_RATIO`] times the file's size (but at least
/// 1 MiB), and never to more than [`MAX_INFLATED`], counting 8 bytes a value; point and cell
/// data are never decoded. Elements may nest at most [`MAX_DEPTH`] deep.
pub fn read_vtu(path: impl AsRef<Path>) -> Result<TetData, MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("read_vtu", path = %path.display()).entered();
    parse_vtu(&read_file(path)?, path)
}

/// Parses `.vtu` bytes held in memory; `name` stands for the file in error messages. The
/// limits of [`read_vtu`] apply, with `bytes.len()` as the file's size.
pub fn parse_vtu(bytes: &[u8], name: impl AsRef<Path>) -> Result<TetData, MeshIoError> {
    let path = name.as_ref();
    let appended = find_appended(bytes, path)?;
    let xml = bytes
        .get(..appended.as_ref().map_or(bytes.len(), |a| a.tag_start))
        .unwrap_or(bytes);
    let doc = parse_xml(xml, path)?;
    let file = File {
        path,
        bytes,
        header: doc.header,
        big_endian: doc.big_endian,
        compressed: doc.compressed,
        appended,
        limit: inflation_limit(bytes.len()),
        decoded: Cell::new(0),
    };
    let mut data = TetData::default();
    let mut skipped = TypeCounts::default();
    for piece in &doc.pieces {
        file.add_piece(piece, &mut data, &mut skipped)?;
    }
    if doc.pieces.is_empty() {
        return Err(MeshIoError::parse(
            path,
            doc.grid_line,
            "the UnstructuredGrid has no <Piece>: the file holds no mesh",
        ));
    }
    if data.tets.is_empty() {
        return Err(MeshIoError::parse(
            path,
            doc.grid_line,
            format!(
                "no tetrahedra (VTK cell type 10) in the file: it holds {}. tissue needs a \
                 tetrahedral volume mesh: tetrahedralise the shape first (e.g. with Gmsh or \
                 TetGen), or give a surface as a surface",
                skipped.describe("cells", vtk_cell_name)
            ),
        ));
    }
    if !skipped.is_empty() {
        tracing::debug!(
            skipped = %skipped.describe("cells", vtk_cell_name),
            "vtu: cells other than tetrahedra skipped"
        );
    }
    Ok(data)
}

fn vtk_cell_name(ty: i64) -> &'static str {
    match ty {
        1 => "vertices",
        2 => "poly-vertices",
        3 => "lines",
        4 => "polylines",
        5 => "triangles",
        6 => "triangle strips",
        7 => "polygons",
        8 => "pixels",
        9 => "quads",
        11 => "voxels",
        12 => "hexahedra",
        13 => "wedges",
        14 => "pyramids",
        21 => "quadratic edges",
        22 => "quadratic triangles",
        23 => "quadratic quads",
        24 => "quadratic tetrahedra",
        25 => "quadratic hexahedra",
        42 => "polyhedra",
        _ => "cells",
    }
}

/// The integers of the byte-count headers of binary data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HeaderType {
    U32,
    U64,
}

impl HeaderType {
    fn size(self) -> usize {
        match self {
            HeaderType::U32 => 4,
            HeaderType::U64 => 8,
        }
    }
}

/// A `DataArray`'s element type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NumType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl NumType {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "Int8" | "Char" => NumType::I8,
            "UInt8" | "UChar" => NumType::U8,
            "Int16" => NumType::I16,
            "UInt16" => NumType::U16,
            "Int32" => NumType::I32,
            "UInt32" => NumType::U32,
            "Int64" => NumType::I64,
            "UInt64" => NumType::U64,
            "Float32" => NumType::F32,
            "Float64" => NumType::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            NumType::I8 | NumType::U8 => 1,
            NumType::I16 | NumType::U16 => 2,
            NumType::I32 | NumType::U32 | NumType::F32 => 4,
            NumType::I64 | NumType::U64 | NumType::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, NumType::F32 | NumType::F64)
    }

    /// VTK's name of the type, for messages.
    fn name(self) -> &'static str {
        match self {
            NumType::I8 => "Int8",
            NumType::U8 => "UInt8",
            NumType::I16 => "Int16",
            NumType::U16 => "UInt16",
            NumType::I32 => "Int32",
            NumType::U32 => "UInt32",
            NumType::I64 => "Int64",
            NumType::U64 => "UInt64",
            NumType::F32 => "Float32",
            NumType::F64 => "Float64",
        }
    }

    /// "48 bytes of Float32".
    fn bytes(self, n: usize) -> String {
        let s = if n == 1 { "" } else { "s" };
        format!("{n} byte{s} of {}", self.name())
    }
}

/// How a `DataArray` stores its values.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Format {
    Ascii,
    /// Inline base64; the text without whitespace.
    Binary,
    /// In `<AppendedData>`, at this offset.
    Appended(usize),
}

/// One `DataArray` the reader needs.
#[derive(Debug, Clone)]
struct Array {
    /// `Name`, or what the array is (`"Points"`) for messages.
    name: String,
    ty: NumType,
    components: usize,
    format: Format,
    /// Inline text (ascii or base64).
    text: Vec<u8>,
    /// Line of the `<DataArray` tag.
    line: usize,
}

/// A `<Piece>`. The arrays are boxed so that a file of many empty pieces costs about as much
/// memory as its text.
#[derive(Debug, Default)]
struct Piece {
    points: usize,
    cells: usize,
    line: usize,
    positions: Option<Box<Array>>,
    connectivity: Option<Box<Array>>,
    offsets: Option<Box<Array>>,
    types: Option<Box<Array>>,
}

struct Doc {
    header: HeaderType,
    big_endian: bool,
    compressed: bool,
    grid_line: usize,
    pieces: Vec<Piece>,
}

/// Where `<AppendedData>` is and what it holds.
struct Appended {
    /// Byte offset of `<AppendedData` (the XML before it is parsed as XML).
    tag_start: usize,
    /// Line of the tag.
    line: usize,
    raw: bool,
    /// Byte offset of the first data byte (after the `_`).
    data_start: usize,
    /// Byte offset where the data end (`</AppendedData>`, or the end of the file).
    data_end: usize,
}

const APPENDED_TAG: &[u8] = b"<AppendedData";

fn find(haystack: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    haystack
        .get(from..)?
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|k| k + from)
}

/// Finds `<AppendedData encoding="...">_`, whose raw bytes are not XML and so are never given to
/// the XML parser.
fn find_appended(bytes: &[u8], path: &Path) -> Result<Option<Appended>, MeshIoError> {
    let Some(tag_start) = find(bytes, APPENDED_TAG, 0) else {
        return Ok(None);
    };
    let line = line_of_offset(bytes, tag_start);
    let err = |m: &str| MeshIoError::parse(path, line, m.to_string());
    let gt = bytes
        .get(tag_start..)
        .and_then(|r| r.iter().position(|&b| b == b'>'))
        .map(|k| k + tag_start)
        .ok_or_else(|| err("the <AppendedData> tag is not closed: is the file truncated?"))?;
    let tag = bytes.get(tag_start..=gt).unwrap_or_default();
    let mut reader = Reader::from_reader(tag);
    let encoding = match reader.read_event() {
        Ok(Event::Start(e) | Event::Empty(e)) => attr(&e, "encoding").map(|v| v.into_owned()),
        _ => return Err(err("cannot read the <AppendedData> tag")),
    };
    let raw = match encoding.as_deref() {
        Some("raw") => true,
        Some("base64") => false,
        Some(other) => {
            return Err(err(&format!(
                "<AppendedData encoding=\"{}\">: expected \"raw\" or \"base64\"",
                shorten(other)
            )))
        }
        None => {
            return Err(err(
                "<AppendedData> has no encoding (\"raw\" or \"base64\")",
            ))
        }
    };
    let mut k = gt + 1;
    while bytes.get(k).is_some_and(u8::is_ascii_whitespace) {
        k += 1;
    }
    if bytes.get(k) != Some(&b'_') {
        return Err(err(
            "the appended data must start with `_` after the <AppendedData> tag",
        ));
    }
    let data_start = k + 1;
    let data_end = if raw {
        bytes.len()
    } else {
        find(bytes, b"</AppendedData>", data_start).unwrap_or(bytes.len())
    };
    Ok(Some(Appended {
        tag_start,
        line,
        raw,
        data_start,
        data_end,
    }))
}

/// The value of attribute `key` (the first, if the tag repeats it).
///
/// Without quick-xml's duplicate check: a tag of N attributes, most of them repeating the last
/// new name, makes that check scan every earlier name for each, N² in all.
fn attr<'a>(e: &'a BytesStart<'_>, key: &str) -> Option<Cow<'a, str>> {
    let mut attributes = e.attributes();
    attributes.with_checks(false);
    attributes
        .flatten()
        .find(|a| a.key.as_ref() == key.as_bytes())
        .map(|a| match a.value {
            Cow::Borrowed(b) => String::from_utf8_lossy(b),
            Cow::Owned(v) => Cow::Owned(String::from_utf8_lossy(&v).into_owned()),
        })
}

/// Which `DataArray` the parser is inside, and what it is for.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Positions,
    Connectivity,
    Offsets,
    Types,
}

/// The lines of offsets that only grow, counted as they go: finding each element's line by
/// counting from the start of the file would take time quadratic in the number of elements.
struct LineCounter<'a> {
    text: &'a [u8],
    /// The offset counted up to, and its line.
    pos: usize,
    line: usize,
}

impl LineCounter<'_> {
    /// The 1-based line of byte `offset`.
    fn at(&mut self, offset: usize) -> usize {
        if offset < self.pos {
            // Never happens (events come in file order); recount rather than be wrong.
            self.pos = 0;
            self.line = 1;
        }
        let upto = offset.min(self.text.len());
        let between = self.text.get(self.pos..upto).unwrap_or_default();
        self.line += between.iter().filter(|&&b| b == b'\n').count();
        self.pos = upto;
        self.line
    }
}

fn parse_xml(xml: &[u8], path: &Path) -> Result<Doc, MeshIoError> {
    let mut reader = Reader::from_reader(xml);
    let mut lines = LineCounter {
        text: xml,
        pos: 0,
        line: 1,
    };
    let mut doc = Doc {
        header: HeaderType::U32,
        big_endian: false,
        compressed: false,
        grid_line: 1,
        pieces: Vec::new(),
    };
    let mut seen_root = false;
    // Element names from the root down.
    let mut stack: Vec<Vec<u8>> = Vec::new();
    // The DataArray being read, if it is one we need.
    let mut current: Option<(Role, Array)> = None;
    loop {
        let before = usize::try_from(reader.buffer_position()).unwrap_or(usize::MAX);
        let event = reader.read_event().map_err(|e| {
            let at = usize::try_from(reader.error_position()).unwrap_or(before);
            MeshIoError::parse(
                path,
                line_of_offset(xml, at),
                format!("not well-formed XML ({e}): is this a .vtu file, and is it whole?"),
            )
        })?;
        // Line of the start of this event (skip the whitespace before a tag).
        let mut line = || {
            let mut k = before;
            while xml.get(k).is_some_and(u8::is_ascii_whitespace) {
                k += 1;
            }
            lines.at(k)
        };
        match event {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let empty = matches!(event, Event::Empty(_));
                let name = e.name().as_ref().to_vec();
                let l = line();
                if !seen_root {
                    seen_root = true;
                    root(e, path, l, &mut doc)?;
                } else {
                    element(e, &name, &stack, path, l, &mut doc, &mut current)?;
                }
                if !empty {
                    if stack.len() >= MAX_DEPTH {
                        return Err(MeshIoError::parse(
                            path,
                            l,
                            format!(
                                "XML elements nested more than {MAX_DEPTH} deep: a .vtu file needs 7 levels; the file is corrupt or not what it claims"
                            ),
                        ));
                    }
                    stack.push(name);
                } else if name == b"DataArray" {
                    finish_array(&mut current, &mut doc);
                }
            }
            Event::End(e) => {
                if e.name().as_ref() == b"DataArray" {
                    finish_array(&mut current, &mut doc);
                }
                stack.pop();
            }
            Event::Text(t) => {
                if let Some((_, array)) = current.as_mut() {
                    array.text.extend_from_slice(&t);
                }
            }
            Event::CData(_) | Event::GeneralRef(_) => {
                if let Some((_, array)) = current.as_ref() {
                    return Err(MeshIoError::parse(
                        path,
                        array.line,
                        format!(
                            "DataArray `{}` holds CDATA or an entity: expected numbers or base64",
                            array.name
                        ),
                    ));
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !seen_root {
        return Err(MeshIoError::parse(
            path,
            1,
            "no XML element in the file: a .vtu file starts with <VTKFile type=\"UnstructuredGrid\">",
        ));
    }
    Ok(doc)
}

fn root(e: &BytesStart<'_>, path: &Path, line: usize, doc: &mut Doc) -> Result<(), MeshIoError> {
    let err = |m: String| MeshIoError::parse(path, line, m);
    if e.name().as_ref() != b"VTKFile" {
        return Err(err(format!(
            "the root element is <{}>, expected <VTKFile type=\"UnstructuredGrid\">: is this a .vtu file?",
            shorten(&String::from_utf8_lossy(e.name().as_ref()))
        )));
    }
    match attr(e, "type").as_deref() {
        Some("UnstructuredGrid") => {}
        Some(other) => {
            return Err(err(format!(
                "a VTK `{}` file: only UnstructuredGrid (.vtu) holds tetrahedra; save the mesh as an unstructured grid",
                shorten(other)
            )))
        }
        None => return Err(err("<VTKFile> has no type: expected type=\"UnstructuredGrid\"".into())),
    }
    doc.big_endian = match attr(e, "byte_order").as_deref() {
        None | Some("LittleEndian") => false,
        Some("BigEndian") => true,
        Some(other) => {
            return Err(err(format!(
                "byte_order=\"{}\": expected LittleEndian or BigEndian",
                shorten(other)
            )))
        }
    };
    doc.header = match attr(e, "header_type").as_deref() {
        None | Some("UInt32") => HeaderType::U32,
        Some("UInt64") => HeaderType::U64,
        Some(other) => {
            return Err(err(format!(
                "header_type=\"{}\": expected UInt32 or UInt64",
                shorten(other)
            )))
        }
    };
    doc.compressed = match attr(e, "compressor").as_deref() {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(other) => {
            return Err(err(format!(
                "compressor=\"{}\" is not supported: save the file uncompressed or with zlib \
                 (in ParaView: Data Mode Binary or Ascii, Compressor None or ZLib; in meshio: \
                 compression=None or \"zlib\")",
                shorten(other)
            )))
        }
    };
    Ok(())
}

/// A `<Piece>`'s `key` count. `values` is how many values each counted item needs at least
/// (3 coordinates a point; an offset and a type a cell): at 8 bytes each once decoded, the
/// count may not need more than [`MAX_INFLATED`] bytes, whatever the file's size.
fn parse_count(
    e: &BytesStart<'_>,
    key: &str,
    values: u64,
    path: &Path,
    line: usize,
) -> Result<usize, MeshIoError> {
    let v = attr(e, key)
        .ok_or_else(|| MeshIoError::parse(path, line, format!("<Piece> has no {key} attribute")))?;
    let n: u64 = v.trim().parse().map_err(|_| {
        MeshIoError::parse(
            path,
            line,
            format!("{key}=\"{}\": expected a count", shorten(&v)),
        )
    })?;
    let most = MAX_INFLATED / (8 * values);
    usize::try_from(n).ok().filter(|_| n <= most).ok_or_else(|| {
        MeshIoError::parse(
            path,
            line,
            format!(
                "{key}=\"{n}\" is more than this reader takes (at most {most}, whose data alone decode to {MAX_INFLATED} bytes): the file is corrupt or not what it claims"
            ),
        )
    })
}

#[allow(clippy::too_many_arguments)]
fn element(
    e: &BytesStart<'_>,
    name: &[u8],
    stack: &[Vec<u8>],
    path: &Path,
    line: usize,
    doc: &mut Doc,
    current: &mut Option<(Role, Array)>,
) -> Result<(), MeshIoError> {
    let parent = stack.last().map(Vec::as_slice);
    match name {
        b"UnstructuredGrid" => doc.grid_line = line,
        b"Piece" if parent == Some(b"UnstructuredGrid") => {
            let points = parse_count(e, "NumberOfPoints", 3, path, line)?;
            let cells = parse_count(e, "NumberOfCells", 2, path, line)?;
            doc.pieces.push(Piece {
                points,
                cells,
                line,
                ..Piece::default()
            });
        }
        b"DataArray" => {
            let role = match parent {
                Some(b"Points") => Role::Positions,
                Some(b"Cells") => match attr(e, "Name").as_deref() {
                    Some("connectivity") => Role::Connectivity,
                    Some("offsets") => Role::Offsets,
                    Some("types") => Role::Types,
                    _ => return Ok(()),
                },
                _ => return Ok(()),
            };
            let array_name = match role {
                Role::Positions => {
                    attr(e, "Name").map_or_else(|| "Points".into(), |n| n.into_owned())
                }
                Role::Connectivity => "connectivity".into(),
                Role::Offsets => "offsets".into(),
                Role::Types => "types".into(),
            };
            let err = |m: String| {
                MeshIoError::parse(path, line, format!("DataArray `{array_name}`: {m}"))
            };
            let ty_name = attr(e, "type").ok_or_else(|| err("no type attribute".into()))?;
            let ty = NumType::from_name(&ty_name).ok_or_else(|| {
                err(format!(
                    "type \"{}\" is not a VTK number type (Int8 ... UInt64, Float32, Float64)",
                    shorten(&ty_name)
                ))
            })?;
            if role != Role::Positions && ty.is_float() {
                return Err(err(format!("type {ty_name}: cell data must be integers")));
            }
            let components = match attr(e, "NumberOfComponents") {
                None => 1,
                Some(c) => c.trim().parse().map_err(|_| {
                    err(format!(
                        "NumberOfComponents=\"{}\": expected a count",
                        shorten(&c)
                    ))
                })?,
            };
            let format = match attr(e, "format").as_deref() {
                Some("ascii") => Format::Ascii,
                Some("binary") => Format::Binary,
                Some("appended") => {
                    let off = attr(e, "offset")
                        .ok_or_else(|| err("format=\"appended\" without an offset".into()))?;
                    Format::Appended(off.trim().parse().map_err(|_| {
                        err(format!(
                            "offset=\"{}\": expected a byte offset",
                            shorten(&off)
                        ))
                    })?)
                }
                Some(other) => {
                    return Err(err(format!(
                        "format=\"{}\": expected ascii, binary or appended",
                        shorten(other)
                    )))
                }
                None => return Err(err("no format attribute (ascii, binary or appended)".into())),
            };
            *current = Some((
                role,
                Array {
                    name: array_name.clone(),
                    ty,
                    components,
                    format,
                    text: Vec::new(),
                    line,
                },
            ));
        }
        _ => {}
    }
    Ok(())
}

fn finish_array(current: &mut Option<(Role, Array)>, doc: &mut Doc) {
    let Some((role, array)) = current.take() else {
        return;
    };
    let Some(piece) = doc.pieces.last_mut() else {
        return;
    };
    let slot = match role {
        Role::Positions => &mut piece.positions,
        Role::Connectivity => &mut piece.connectivity,
        Role::Offsets => &mut piece.offsets,
        Role::Types => &mut piece.types,
    };
    if slot.is_none() {
        *slot = Some(Box::new(array));
    }
}

/// Values of one array, as floats (positions) or integers (cells).
enum Values {
    Float(Vec<f64>),
    Int(Vec<i64>),
}

/// How many values an array must hold, and what says so (for messages), e.g.
/// `NumberOfPoints="4" needs 12 values`.
struct Expected {
    values: usize,
    why: String,
}

impl Expected {
    fn new(values: usize, source: &str, verb: &str) -> Self {
        let s = if values == 1 { "" } else { "s" };
        Expected {
            values,
            why: format!("{source} {verb} {values} value{s}"),
        }
    }
}

struct File<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    header: HeaderType,
    big_endian: bool,
    compressed: bool,
    appended: Option<Appended>,
    /// What the arrays of this file may decode to in all (see [`MAX_INFLATION_RATIO`]).
    limit: u64,
    /// What the arrays read so far are charged (8 bytes a value).
    decoded: Cell<u64>,
}

impl File<'_> {
    fn add_piece(
        &self,
        piece: &Piece,
        data: &mut TetData,
        skipped: &mut TypeCounts,
    ) -> Result<(), MeshIoError> {
        let path = self.path;
        let missing = |what: &str| {
            MeshIoError::parse(
                path,
                piece.line,
                format!("the <Piece> has no {what}: a .vtu mesh needs <Points> and <Cells> with connectivity, offsets and types"),
            )
        };
        let base = data.positions.len();
        if piece.points > 0 {
            let arr = piece
                .positions
                .as_ref()
                .ok_or_else(|| missing("<Points> DataArray"))?;
            let err = |m: String| {
                MeshIoError::parse(path, arr.line, format!("DataArray `{}`: {m}", arr.name))
            };
            if arr.components != 3 {
                return Err(err(format!(
                    "NumberOfComponents is {}: points need 3 (x y z)",
                    arr.components
                )));
            }
            if base + piece.points >= u32::MAX as usize {
                return Err(err("more than 2^32 - 2 points are not supported".into()));
            }
            let need = Expected::new(
                3 * piece.points,
                &format!("NumberOfPoints=\"{}\"", piece.points),
                "needs",
            );
            // `values` holds exactly `need.values` values.
            let values = match self.values(arr, &need)? {
                Values::Float(v) => v,
                Values::Int(v) => v.into_iter().map(|x| x as f64).collect(),
            };
            data.positions.reserve(piece.points);
            for p in values.chunks_exact(3) {
                data.positions
                    .push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32));
            }
        }
        if piece.cells == 0 {
            return Ok(());
        }
        let conn_arr = piece
            .connectivity
            .as_ref()
            .ok_or_else(|| missing("`connectivity` DataArray"))?;
        let off_arr = piece
            .offsets
            .as_ref()
            .ok_or_else(|| missing("`offsets` DataArray"))?;
        let types_arr = piece
            .types
            .as_ref()
            .ok_or_else(|| missing("`types` DataArray"))?;
        let ints = |arr: &Array, need: &Expected| -> Result<Vec<i64>, MeshIoError> {
            match self.values(arr, need)? {
                Values::Int(v) => Ok(v),
                Values::Float(_) => Err(MeshIoError::parse(
                    path,
                    arr.line,
                    format!("DataArray `{}`: expected integers", arr.name),
                )),
            }
        };
        let per_cell = Expected::new(
            piece.cells,
            &format!("NumberOfCells=\"{}\"", piece.cells),
            "needs",
        );
        let offsets = ints(off_arr, &per_cell)?;
        let types = ints(types_arr, &per_cell)?;
        // The offsets first: their last value is the length of `connectivity`, which is then
        // known before a byte of it is decoded.
        let mut end_of_last = 0i64;
        for (c, &end) in offsets.iter().enumerate() {
            if end < end_of_last {
                return Err(MeshIoError::parse(
                    path,
                    off_arr.line,
                    format!(
                        "DataArray `offsets`: cell {c} ends at {end}, before the previous cell's end {end_of_last}: offsets must grow"
                    ),
                ));
            }
            end_of_last = end;
        }
        let conn_len = usize::try_from(end_of_last).unwrap_or(usize::MAX);
        let conn = ints(conn_arr, &Expected::new(conn_len, "the offsets", "need"))?;
        let mut start = 0i64;
        for (c, (&end, &ty)) in offsets.iter().zip(&types).enumerate() {
            // Every cell's points are checked, also those of cells that are skipped: a bad
            // index anywhere means a corrupt file. (`start..end` lies within `conn`: the
            // offsets grow and the last one is its length.)
            let cell = conn.get(start as usize..end as usize).unwrap_or_default();
            if let Some(&i) = cell.iter().find(|&&i| i < 0 || i >= piece.points as i64) {
                return Err(MeshIoError::parse(
                    path,
                    conn_arr.line,
                    format!(
                        "DataArray `connectivity`: cell {c} (type {ty}) refers to point {i}, but the piece has points 0..{}",
                        piece.points
                    ),
                ));
            }
            if ty == VTK_TETRA {
                if end - start != 4 {
                    return Err(MeshIoError::parse(
                        path,
                        off_arr.line,
                        format!(
                            "cell {c} is a tetrahedron (type 10) with {} points: it needs 4",
                            end - start
                        ),
                    ));
                }
                let mut tet = [0u32; 4];
                for (k, slot) in tet.iter_mut().enumerate() {
                    let i = cell.get(k).copied().unwrap_or(0);
                    // Below NumberOfPoints, and base + NumberOfPoints < 2^32 - 1 (checked above).
                    *slot = u32::try_from(i as usize + base).unwrap_or(u32::MAX);
                }
                data.tets.push(tet);
            } else {
                skipped.add(ty);
            }
            start = end;
        }
        Ok(())
    }

    /// Charges the file's decoding budget for an array of `values` values (8 bytes each), or
    /// says why the file may not decode that much.
    fn charge(&self, values: usize) -> Result<(), String> {
        let need = (values as u64).saturating_mul(8);
        let before = self.decoded.get();
        let total = before.saturating_add(need);
        if total > self.limit {
            let with_the_rest = if before > 0 {
                format!(" ({total} with the arrays read before it)")
            } else {
                String::new()
            };
            return Err(format!(
                "its {values} values take {need} bytes decoded{with_the_rest}: more than the {limit} bytes a .vtu file of {len} bytes may decode to ({MAX_INFLATION_RATIO} times its size, but at least {MIN_INFLATION_BUDGET} and at most {MAX_INFLATED}): the file is corrupt or not what it claims",
                limit = self.limit,
                len = self.bytes.len(),
            ));
        }
        self.decoded.set(total);
        Ok(())
    }

    /// The values of an array, decoded; exactly `need.values` of them, or an error. Nothing is
    /// decoded before the file's budget has been charged for them, and a binary array whose
    /// header declares another size is refused before its data are touched.
    fn values(&self, arr: &Array, need: &Expected) -> Result<Values, MeshIoError> {
        let err = |m: String| {
            MeshIoError::parse(
                self.path,
                arr.line,
                format!("DataArray `{}`: {m}", arr.name),
            )
        };
        self.charge(need.values).map_err(err)?;
        // Within the budget, so far below usize::MAX.
        let want = Want {
            bytes: need.values.saturating_mul(arr.ty.size()),
            ty: arr.ty,
            need,
        };
        let text = arr.text.as_slice();
        let raw: Vec<u8> = match &arr.format {
            Format::Ascii => return ascii_values(text, arr.ty, need).map_err(err),
            Format::Binary => self.decode_base64(text, &want).map_err(err)?,
            Format::Appended(offset) => {
                let app = self.appended.as_ref().ok_or_else(|| {
                    err(
                        "format=\"appended\", but the file has no <AppendedData>: is it truncated?"
                            .into(),
                    )
                })?;
                let data = self
                    .bytes
                    .get(app.data_start..app.data_end)
                    .unwrap_or_default();
                let at = data.get(*offset..).ok_or_else(|| {
                    err(format!(
                        "offset {offset} is past the end of the appended data ({} bytes, from line {}): is the file truncated?",
                        data.len(),
                        app.line
                    ))
                })?;
                if app.raw {
                    self.decode_raw(at, &want).map_err(err)?
                } else {
                    self.decode_base64(at, &want).map_err(err)?
                }
            }
        };
        // The decoders give exactly the declared size, which was checked to be `want.bytes`;
        // checked again here, so that nothing larger is ever widened.
        if raw.len() != want.bytes {
            return Err(err(format!(
                "{} bytes of data, but {} ({}): the file is corrupt",
                raw.len(),
                need.why,
                arr.ty.bytes(want.bytes),
            )));
        }
        binary_values(&raw, arr.ty, self.big_endian).map_err(err)
    }

    fn header_value(&self, bytes: &[u8], k: usize) -> u64 {
        let s = self.header.size();
        let b = bytes.get(k * s..(k + 1) * s).unwrap_or_default();
        let mut v = 0u64;
        if self.big_endian {
            for &x in b {
                v = (v << 8) | u64::from(x);
            }
        } else {
            for &x in b.iter().rev() {
                v = (v << 8) | u64::from(x);
            }
        }
        v
    }

    /// The number of header items, from the first bytes of the header (for compressed data,
    /// the block count is its first item).
    fn header_items(&self, first: &[u8]) -> Result<usize, String> {
        if !self.compressed {
            return Ok(1);
        }
        let blocks = self.header_value(first, 0);
        // Each block costs at least one header item in the file.
        let blocks = usize::try_from(blocks)
            .ok()
            .filter(|&b| b <= self.bytes.len())
            .ok_or_else(|| {
                format!("the compression header claims {blocks} blocks: the file is corrupt")
            })?;
        Ok(3 + blocks)
    }

    /// Checks a full header against what the array must hold, before any data are read, and
    /// returns the number of payload bytes (as stored in the file) that follow it.
    ///
    /// The size the header declares (uncompressed: its one item; compressed: block size ×
    /// (blocks − 1) + last block size) must be exactly `want.bytes`: a larger one is refused
    /// here, before anything is decompressed or copied.
    fn payload_len(&self, header: &[u8], items: usize, want: &Want<'_>) -> Result<usize, String> {
        let declared = if self.compressed {
            self.inflated_size(header, items)?
        } else {
            self.header_value(header, 0)
        };
        if declared != want.bytes as u64 {
            let (what, verdict) = match (self.compressed, declared > want.bytes as u64) {
                (true, true) => (
                    "the compression header declares",
                    "the file is corrupt or not what it claims (refused before decompressing)",
                ),
                (false, true) => (
                    "the data header declares",
                    "the file is corrupt or not what it claims",
                ),
                (_, false) => (
                    if self.compressed {
                        "the compression header declares"
                    } else {
                        "the data header declares"
                    },
                    "is the file truncated or corrupt?",
                ),
            };
            return Err(format!(
                "{what} {declared} bytes, but {} ({}): {verdict}",
                want.need.why,
                want.ty.bytes(want.bytes)
            ));
        }
        let stored = if self.compressed {
            (3..items).try_fold(0u64, |acc, k| acc.checked_add(self.header_value(header, k)))
        } else {
            Some(declared)
        };
        stored
            .and_then(|t| usize::try_from(t).ok())
            .filter(|&t| t <= self.bytes.len())
            .ok_or_else(|| "the byte count in the data header is larger than the file: is it truncated or corrupt?".to_string())
    }

    /// The uncompressed size a compression header declares: block size × (blocks − 1) + the
    /// last block's size (0 meaning a full block, as VTK writes it).
    fn inflated_size(&self, header: &[u8], items: usize) -> Result<u64, String> {
        let blocks = (items - 3) as u64;
        let block_size = self.header_value(header, 1);
        let last_size = self.header_value(header, 2);
        if blocks == 0 {
            return Ok(0);
        }
        if last_size > block_size {
            return Err(format!(
                "the compression header's last block ({last_size} bytes) is larger than its block size ({block_size}): the file is corrupt"
            ));
        }
        let last = if last_size == 0 {
            block_size
        } else {
            last_size
        };
        block_size
            .checked_mul(blocks - 1)
            .and_then(|b| b.checked_add(last))
            .ok_or_else(|| {
                format!(
                    "the compression header declares {blocks} blocks of {block_size} bytes: the file is corrupt or not what it claims"
                )
            })
    }

    /// Raw appended data: header, then payload, straight from the file.
    fn decode_raw(&self, at: &[u8], want: &Want<'_>) -> Result<Vec<u8>, String> {
        let s = self.header.size();
        let truncated =
            || "the appended data end inside this array: is the file truncated?".to_string();
        let first = at.get(..s).ok_or_else(truncated)?;
        let items = self.header_items(first)?;
        let header = at.get(..items * s).ok_or_else(truncated)?;
        let len = self.payload_len(header, items, want)?;
        let payload = at.get(items * s..items * s + len).ok_or_else(truncated)?;
        self.finish(header, items, payload, want.bytes)
    }

    /// Base64 data (inline or appended): a header and a payload, encoded together or (as VTK
    /// and meshio write them) separately, each with its own padding. Only as much text as the
    /// header, and then the checked payload, needs is copied.
    fn decode_base64(&self, text: &[u8], want: &Want<'_>) -> Result<Vec<u8>, String> {
        let s = self.header.size();
        let chars = |bytes: usize| bytes.div_ceil(3).saturating_mul(4);
        let decode = |text: &[u8]| {
            base64::engine::general_purpose::STANDARD
                .decode(text)
                .map_err(|e| format!("bad base64 ({e}): is the file corrupt?"))
        };
        let truncated = || "the base64 data end early: is the file truncated?".to_string();
        let prefix = |n: usize| base64_prefix(text, n).ok_or_else(truncated);
        // The first item(s): 3 items (12 or 24 bytes) decode cleanly on their own.
        let first_items = if self.compressed { 3 } else { 1 };
        let first = decode(&prefix(chars(first_items * s))?)?;
        let items = self.header_items(&first)?;
        let header_len = items * s;
        let header_chars = chars(header_len);
        let mut header = decode(&prefix(header_chars)?)?;
        // Encoded on its own, the header decodes to exactly its length; encoded together with
        // the payload, its last group also holds payload bytes (when its length is not a
        // multiple of 3; when it is, both readings agree).
        let separate = header.len() == header_len;
        header.truncate(header_len);
        let len = self.payload_len(&header, items, want)?;
        let payload = if separate {
            let all = prefix(header_chars.saturating_add(chars(len)))?;
            decode(all.get(header_chars..).unwrap_or_default())?
        } else {
            let all = decode(&prefix(chars(header_len + len))?)?;
            all.get(header_len..).unwrap_or_default().to_vec()
        };
        if payload.len() < len {
            return Err(truncated());
        }
        self.finish(
            &header,
            items,
            payload.get(..len).unwrap_or_default(),
            want.bytes,
        )
    }

    /// The uncompressed data of a header and its payload; `total` is the size the header
    /// declares, already checked against the array's expected size and the file's budget.
    fn finish(
        &self,
        header: &[u8],
        items: usize,
        payload: &[u8],
        total: usize,
    ) -> Result<Vec<u8>, String> {
        if !self.compressed {
            return Ok(payload.to_vec());
        }
        let blocks = items - 3;
        let block_size = self.header_value(header, 1);
        let last_size = self.header_value(header, 2);
        let mut out = Vec::with_capacity(total);
        let mut at = 0usize;
        for b in 0..blocks {
            let comp = usize::try_from(self.header_value(header, 3 + b)).unwrap_or(usize::MAX);
            let chunk = payload.get(at..at.saturating_add(comp)).ok_or_else(|| {
                format!("compressed block {b} runs past the data: is the file truncated?")
            })?;
            at += comp;
            let want = if b + 1 == blocks && last_size != 0 {
                last_size
            } else {
                block_size
            };
            // Before each block: the blocks add up to `total` (checked with the header), so
            // this only guards that sum.
            if (out.len() as u64).saturating_add(want) > total as u64 {
                return Err(format!(
                    "compressed block {b} would take the data past the {total} bytes the header declares: the file is corrupt"
                ));
            }
            // zlib expands at most ~1032:1, so a claimed size beyond that is corrupt.
            if want > (comp as u64).saturating_mul(1100).saturating_add(64) {
                return Err(format!(
                    "compressed block {b} claims {want} bytes from {comp}: the file is corrupt"
                ));
            }
            let start = out.len();
            flate2::read::ZlibDecoder::new(chunk)
                .take(want)
                .read_to_end(&mut out)
                .map_err(|e| format!("compressed block {b} is not valid zlib data ({e})"))?;
            if (out.len() - start) as u64 != want {
                return Err(format!(
                    "compressed block {b} holds {} bytes, its header says {want}: the file is corrupt",
                    out.len() - start
                ));
            }
        }
        Ok(out)
    }
}

/// What a binary array must decode to: `bytes` bytes of `ty`, because of `need`.
struct Want<'a> {
    bytes: usize,
    ty: NumType,
    need: &'a Expected,
}

/// The first `n` base64 characters of `text`, whitespace skipped, up to a `<` (the end of
/// appended data); `None` if there are fewer.
fn base64_prefix(text: &[u8], n: usize) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(n.min(text.len()));
    for &b in text {
        if out.len() == n || b == b'<' {
            break;
        }
        if !b.is_ascii_whitespace() {
            out.push(b);
        }
    }
    (out.len() == n).then_some(out)
}

/// The values of an ASCII array: exactly `need.values` of them, or an error (which comes at the
/// first value too many, without reading on).
fn ascii_values(text: &[u8], ty: NumType, need: &Expected) -> Result<Values, String> {
    let text = std::str::from_utf8(text).map_err(|_| "the values are not text".to_string())?;
    let mut words = text.split_ascii_whitespace();
    let bad = |w: &str| {
        format!(
            "expected a number of type {}, found `{}`",
            ty.name(),
            shorten(w)
        )
    };
    let cap = capacity(need.values, text.len(), 2);
    let values = if ty.is_float() {
        let mut v = Vec::with_capacity(cap);
        for w in words.by_ref().take(need.values) {
            v.push(w.parse::<f64>().map_err(|_| bad(w))?);
        }
        Values::Float(v)
    } else {
        let mut v = Vec::with_capacity(cap);
        for w in words.by_ref().take(need.values) {
            v.push(w.parse::<i64>().map_err(|_| bad(w))?);
        }
        Values::Int(v)
    };
    let n = match &values {
        Values::Float(v) => v.len(),
        Values::Int(v) => v.len(),
    };
    if words.next().is_some() {
        return Err(format!(
            "more values than {}: the file is corrupt or not what it claims",
            need.why
        ));
    }
    if n != need.values {
        return Err(format!("{n} values, but {}", need.why));
    }
    Ok(values)
}

fn binary_values(raw: &[u8], ty: NumType, big_endian: bool) -> Result<Values, String> {
    let size = ty.size();
    if raw.len() % size != 0 {
        return Err(format!(
            "{} bytes of data is not a whole number of {} values ({size} bytes each)",
            raw.len(),
            ty.name()
        ));
    }
    let word = |c: &[u8]| -> [u8; 8] {
        let mut b = [0u8; 8];
        if big_endian {
            // Right-align, then read as big-endian below.
            b[8 - c.len()..].copy_from_slice(c);
        } else {
            b[..c.len()].copy_from_slice(c);
        }
        b
    };
    let unsigned = |c: &[u8]| -> u64 {
        let b = word(c);
        if big_endian {
            u64::from_be_bytes(b)
        } else {
            u64::from_le_bytes(b)
        }
    };
    let signed = |c: &[u8]| -> i64 {
        let u = unsigned(c);
        let shift = 64 - 8 * c.len() as u32;
        ((u << shift) as i64) >> shift
    };
    let chunks = raw.chunks_exact(size);
    Ok(match ty {
        NumType::F32 => Values::Float(
            chunks
                .map(|c| f64::from(f32::from_bits(unsigned(c) as u32)))
                .collect(),
        ),
        NumType::F64 => Values::Float(chunks.map(|c| f64::from_bits(unsigned(c))).collect()),
        NumType::U64 => {
            let mut v = Vec::with_capacity(raw.len() / size);
            for c in chunks {
                let u = unsigned(c);
                v.push(i64::try_from(u).map_err(|_| format!("value {u} is out of range"))?);
            }
            Values::Int(v)
        }
        NumType::U8 | NumType::U16 | NumType::U32 => {
            Values::Int(chunks.map(|c| unsigned(c) as i64).collect())
        }
        NumType::I8 | NumType::I16 | NumType::I32 | NumType::I64 => {
            Values::Int(chunks.map(signed).collect())
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="5" NumberOfCells="3">
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">
          0 0 0  1 0 0  0 1 0  0 0 1  1 1 1
        </DataArray>
      </Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 1 2 3 4</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">4 7 8</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10 5 1</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
"#;

    #[test]
    fn ascii_keeps_tets_and_skips_the_rest() {
        let d = parse_vtu(ASCII.as_bytes(), "a.vtu").unwrap();
        assert_eq!(d.positions.len(), 5);
        assert_eq!(d.tets, vec![[0, 1, 2, 3]]);
    }

    #[test]
    fn errors_name_the_line_and_array() {
        let bad = ASCII.replace("0 1 2 3 1 2", "0 1 2 9 1 2");
        let e = parse_vtu(bad.as_bytes(), "a.vtu").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 11, .. }), "{e}");
        assert!(e.to_string().contains("connectivity"), "{e}");
        let bad = ASCII.replace("10 5 1", "5 5 1");
        let e = parse_vtu(bad.as_bytes(), "a.vtu").unwrap_err();
        assert!(e.to_string().contains("no tetrahedra"), "{e}");
        assert!(
            e.to_string()
                .contains("2 triangles (type 5), 1 vertices (type 1)"),
            "{e}"
        );
    }

    /// Little-endian bytes of `values` with a UInt32 or UInt64 byte-count header.
    fn binary_array(header64: bool, data: &[u8], together: bool) -> String {
        let e = base64::engine::general_purpose::STANDARD;
        let n = data.len() as u64;
        let header = if header64 {
            n.to_le_bytes().to_vec()
        } else {
            (n as u32).to_le_bytes().to_vec()
        };
        if together {
            e.encode([header, data.to_vec()].concat())
        } else {
            e.encode(header) + &e.encode(data)
        }
    }

    #[test]
    fn base64_header_together_or_separate() {
        let pts: Vec<u8> = [0f64, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let conn: Vec<u8> = [0i64, 1, 2, 3]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        for header64 in [false, true] {
            for together in [false, true] {
                let arr = |ty: &str, name: &str, comps: u32, data: &[u8]| {
                    format!(
                        "<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"binary\">\n  {}\n</DataArray>",
                        binary_array(header64, data, together)
                    )
                };
                let text = format!(
                    "<VTKFile type=\"UnstructuredGrid\" header_type=\"{}\"><UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\"><Points>{}</Points><Cells>{}{}{}</Cells></Piece></UnstructuredGrid></VTKFile>",
                    if header64 { "UInt64" } else { "UInt32" },
                    arr("Float64", "Points", 3, &pts),
                    arr("Int64", "connectivity", 1, &conn),
                    arr("Int32", "offsets", 1, &4i32.to_le_bytes()),
                    arr("UInt8", "types", 1, &[10]),
                );
                let d = parse_vtu(text.as_bytes(), "b.vtu")
                    .unwrap_or_else(|e| panic!("{header64} {together}: {e}"));
                assert_eq!(d.tets, vec![[0, 1, 2, 3]]);
                assert_eq!(d.positions[3], Vec3::Z);
            }
        }
    }

    #[test]
    fn signed_and_big_endian_values() {
        let Values::Int(v) = binary_values(&[0xff, 0xfe], NumType::I16, true).unwrap() else {
            panic!()
        };
        assert_eq!(v, vec![-2]);
        let Values::Int(v) = binary_values(&[0xfe, 0xff], NumType::I16, false).unwrap() else {
            panic!()
        };
        assert_eq!(v, vec![-2]);
        let Values::Int(v) = binary_values(&[1, 0, 0, 0], NumType::U32, false).unwrap() else {
            panic!()
        };
        assert_eq!(v, vec![1]);
    }

    /// Pieces that each decode within bounds but together exceed the file's budget: all share
    /// one compressed array of zeros at offset 0 of the appended data.
    #[test]
    fn the_budget_counts_every_array_of_the_file() {
        use std::io::Write;
        let points = 20_000usize; // 480,000 bytes of Float64 each, 1,440,000 in all
        let zeros = vec![0u8; 24 * points];
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
        z.write_all(&zeros).unwrap();
        let z = z.finish().unwrap();
        let mut data = Vec::new();
        for v in [1, zeros.len(), zeros.len(), z.len()] {
            data.extend((v as u32).to_le_bytes());
        }
        data.extend(&z);
        let piece = format!(
            "<Piece NumberOfPoints=\"{points}\" NumberOfCells=\"0\"><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/></Points></Piece>\n"
        );
        let file = |pieces: usize| {
            let mut bytes = format!(
                "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkZLibDataCompressor\"><UnstructuredGrid>\n{}</UnstructuredGrid>\n<AppendedData encoding=\"raw\">_",
                piece.repeat(pieces)
            )
            .into_bytes();
            bytes.extend(&data);
            bytes.extend(b"</AppendedData></VTKFile>");
            bytes
        };
        // The file is small, so its budget is the 1 MiB floor: two pieces fit, the third does
        // not.
        let three = file(3);
        assert!(three.len() as u64 * MAX_INFLATION_RATIO < MIN_INFLATION_BUDGET);
        let e = parse_vtu(&three, "shared.vtu").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 4, .. }), "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains("1440000 with the arrays read before it"),
            "{msg}"
        );
        assert!(msg.contains("1048576 bytes a .vtu file of"), "{msg}");
        // Two pieces read (without tetrahedra, which is the error then).
        let e = parse_vtu(&file(2), "shared.vtu").unwrap_err();
        assert!(e.to_string().contains("no tetrahedra"), "{e}");
    }

    #[test]
    fn compression_headers_that_cannot_be_right_are_refused() {
        let file = File {
            path: Path::new("h.vtu"),
            bytes: &[0; 64],
            header: HeaderType::U64,
            big_endian: false,
            compressed: true,
            appended: None,
            limit: MAX_INFLATED,
            decoded: Cell::new(0),
        };
        let header =
            |items: &[u64]| -> Vec<u8> { items.iter().flat_map(|v| v.to_le_bytes()).collect() };
        // VTK's 0 for a full last block, meshio's full size, and a partial one.
        assert_eq!(
            file.inflated_size(&header(&[3, 100, 0, 1, 1, 1]), 6),
            Ok(300)
        );
        assert_eq!(
            file.inflated_size(&header(&[3, 100, 100, 1, 1, 1]), 6),
            Ok(300)
        );
        assert_eq!(
            file.inflated_size(&header(&[3, 100, 7, 1, 1, 1]), 6),
            Ok(207)
        );
        assert_eq!(file.inflated_size(&header(&[0, 100, 7]), 3), Ok(0));
        let e = file
            .inflated_size(&header(&[1, 100, 101, 1]), 4)
            .unwrap_err();
        assert!(e.contains("larger than its block size"), "{e}");
        let e = file
            .inflated_size(&header(&[3, u64::MAX / 2, 0, 1, 1, 1]), 6)
            .unwrap_err();
        assert!(e.contains("not what it claims"), "{e}");
    }

    #[test]
    fn ascii_arrays_stop_at_the_first_value_too_many() {
        let need = Expected::new(2, "NumberOfCells=\"2\"", "needs");
        let Values::Int(v) = ascii_values(b" 4\n 8 ", NumType::I32, &need).unwrap() else {
            panic!()
        };
        assert_eq!(v, vec![4, 8]);
        let e = ascii_values(b"4 8 12 not-even-read", NumType::I32, &need)
            .err()
            .unwrap();
        assert_eq!(
            e,
            "more values than NumberOfCells=\"2\" needs 2 values: the file is corrupt or not what it claims"
        );
        let e = ascii_values(b"4", NumType::I32, &need).err().unwrap();
        assert_eq!(e, "1 values, but NumberOfCells=\"2\" needs 2 values");
        // Positions: the count in the message, as before.
        let bad = ASCII.replace("1 1 1\n", "1 1 1 2 2 2\n");
        let e = parse_vtu(bad.as_bytes(), "a.vtu").unwrap_err();
        assert!(
            e.to_string().contains(
                "DataArray `Points`: more values than NumberOfPoints=\"5\" needs 15 values"
            ),
            "{e}"
        );
    }

    #[test]
    fn connectivity_must_hold_what_the_offsets_say() {
        // One value more than the last offset (8).
        let bad = ASCII.replace("0 1 2 3 1 2 3 4", "0 1 2 3 1 2 3 4 0");
        let e = parse_vtu(bad.as_bytes(), "a.vtu").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 11, .. }), "{e}");
        assert!(
            e.to_string()
                .contains("DataArray `connectivity`: more values than the offsets need 8 values"),
            "{e}"
        );
        // Offsets that shrink are refused before connectivity is read.
        let bad = ASCII.replace("4 7 8", "4 3 8");
        let e = parse_vtu(bad.as_bytes(), "a.vtu").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 12, .. }), "{e}");
        assert!(e.to_string().contains("offsets must grow"), "{e}");
    }

    #[test]
    fn base64_prefix_copies_only_what_is_asked() {
        assert_eq!(base64_prefix(b" AB\nCD EF<GH", 4), Some(b"ABCD".to_vec()));
        assert_eq!(base64_prefix(b"AB<CD", 4), None);
        assert_eq!(base64_prefix(b"", 0), Some(Vec::new()));
        let long = vec![b'A'; 1 << 20];
        assert_eq!(base64_prefix(&long, 8).map(|v| v.capacity()), Some(8));
    }
}
