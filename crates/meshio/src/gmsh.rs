//! Gmsh `.msh` tetrahedral meshes (read only): MSH 1 (`$NOD`/`$ELM`, as SOFA ships its meshes),
//! MSH 2 (`$MeshFormat` 2.x: 2.0, 2.1, 2.2; ASCII and binary) and MSH 4.1 (ASCII and binary).
//!
//! Nodes may carry any tags (gaps, any order): they are numbered 0, 1, ... in the order the file
//! lists them, and elements' node tags are mapped through that. Elements of type 4 (the 4-node
//! tetrahedron) are kept, in file order with their nodes as stored; every other element type
//! (points, lines, triangles, quadrangles, hexahedra, second-order elements, ...) is skipped, and
//! a file without a single 4-node tetrahedron is an error that says what it holds. Physical and
//! elementary tags, `$PhysicalNames`, `$Entities`, `$NodeData` and other sections are ignored.
//!
//! Binary files: either byte order (told by the `1` that follows the format line), `double`
//! coordinates, 4-byte `int`s and (MSH 4.1) `size_t`s of the declared data size, 4 or 8 bytes.
//! MSH 4.1 nodes with parametric coordinates are read (the parametric part is skipped). MSH 3 and
//! 4.0 are refused with an error that says how to re-save the file.
//!
//! Errors name the file and the line (text) or the node or element (binary data), and say how to
//! fix the file where they can.

use std::collections::HashMap;
use std::path::Path;
use std::str::FromStr;

use glam::Vec3;

use crate::atomic::read_file;
use crate::tally::TypeCounts;
use crate::text::{capacity, shorten};
use crate::{MeshIoError, TetData};

/// Gmsh's element type number of the 4-node tetrahedron.
const GMSH_TET: i64 = 4;

/// Reads the tetrahedra of a Gmsh `.msh` file (the subset described in the module docs).
pub fn read_msh(path: impl AsRef<Path>) -> Result<TetData, MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("read_msh", path = %path.display()).entered();
    parse_msh(&read_file(path)?, path)
}

/// Parses Gmsh `.msh` bytes held in memory; `name` stands for the file in error messages.
pub fn parse_msh(bytes: &[u8], name: impl AsRef<Path>) -> Result<TetData, MeshIoError> {
    let path = name.as_ref();
    let mut c = Cursor {
        bytes,
        pos: 0,
        line: 1,
        path,
        terminated: true,
    };
    let mut m = Msh {
        version: Version::V1,
        binary: None,
        nodes: Nodes::default(),
        tets: Vec::new(),
        skipped: TypeCounts::default(),
        seen_nodes: false,
        seen_elements: false,
    };
    let mut seen_format = false;
    while let Some((line, text)) = c.next_line() {
        let word = String::from_utf8_lossy(text.trim_ascii()).into_owned();
        if word.is_empty() {
            continue;
        }
        if !word.starts_with('$') {
            return Err(MeshIoError::parse(
                path,
                line,
                format!(
                    "expected a section such as `$MeshFormat`, `$Nodes` or `$NOD`, found `{}`: is this a Gmsh .msh file?",
                    shorten(&word)
                ),
            ));
        }
        match word.as_str() {
            "$MeshFormat" => {
                m.read_format(&mut c)?;
                seen_format = true;
            }
            "$NOD" | "$NOE" if !seen_format => {
                m.read_v1_nodes(&mut c)?;
            }
            "$ELM" if !seen_format => {
                m.need_nodes(path, line, "$ELM", "$NOD")?;
                m.read_v1_elements(&mut c)?;
            }
            "$Nodes" if seen_format => m.read_nodes(&mut c)?,
            "$Elements" if seen_format => {
                m.need_nodes(path, line, "$Elements", "$Nodes")?;
                m.read_elements(&mut c)?;
            }
            _ => {
                let name = word.trim_start_matches('$');
                let end = format!("$End{name}");
                c.skip_to(&end, line, name)?;
            }
        }
        if m.seen_elements {
            break;
        }
    }
    if !m.seen_nodes || !m.seen_elements {
        let (nodes, elements) = if seen_format {
            ("$Nodes", "$Elements")
        } else {
            ("$NOD", "$ELM")
        };
        let missing = if m.seen_nodes { elements } else { nodes };
        return Err(MeshIoError::parse(
            path,
            c.line,
            format!("the file has no {missing} section: is it truncated, or not a Gmsh mesh?"),
        ));
    }
    if m.tets.is_empty() {
        return Err(MeshIoError::parse(
            path,
            c.line,
            format!(
                "no 4-node tetrahedra (element type 4) in the file: it holds {}. tissue needs a \
                 first-order tetrahedral volume mesh: mesh the volume in Gmsh (Mesh > 3D, or \
                 `gmsh -3 -order 1`)",
                m.skipped.describe("elements", element_name)
            ),
        ));
    }
    if !m.skipped.is_empty() {
        tracing::debug!(
            skipped = %m.skipped.describe("elements", element_name),
            "msh: elements other than tetrahedra skipped"
        );
    }
    Ok(TetData {
        positions: m.nodes.positions,
        tets: m.tets,
    })
}

fn element_name(ty: i64) -> &'static str {
    match ty {
        1 | 8 | 26..=28 => "lines",
        2 | 9 | 20..=25 => "triangles",
        3 | 10 | 16 => "quadrangles",
        5 | 12 | 17 | 92 | 93 => "hexahedra",
        6 | 13 | 18 => "prisms",
        7 | 14 | 19 => "pyramids",
        11 | 29..=31 => "higher-order tetrahedra",
        15 => "points",
        _ => "elements",
    }
}

/// Nodes per element of a Gmsh element type, for binary files (whose records have no length).
fn nodes_per_element(ty: i64) -> Option<usize> {
    Some(match ty {
        1 => 2,
        2 => 3,
        3 | 4 => 4,
        5 => 8,
        6 => 6,
        7 => 5,
        8 => 3,
        9 => 6,
        10 => 9,
        11 => 10,
        12 => 27,
        13 => 18,
        14 => 14,
        15 => 1,
        16 => 8,
        17 => 20,
        18 => 15,
        19 => 13,
        20 => 9,
        21 => 10,
        22 => 12,
        23 | 24 => 15,
        25 => 21,
        26 => 4,
        27 => 5,
        28 => 6,
        29 => 20,
        30 => 35,
        31 => 56,
        92 => 64,
        93 => 125,
        _ => return None,
    })
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Version {
    V1,
    V2,
    V41,
}

/// A binary file's layout.
#[derive(Clone, Copy)]
struct Binary {
    little: bool,
    /// `size_t` bytes (MSH 4.1).
    size_t: usize,
}

#[derive(Default)]
struct Nodes {
    positions: Vec<Vec3>,
    /// Tag → 0-based index.
    index: HashMap<u64, u32>,
}

struct Msh {
    version: Version,
    binary: Option<Binary>,
    nodes: Nodes,
    tets: Vec<[u32; 4]>,
    /// Skipped elements by type.
    skipped: TypeCounts,
    seen_nodes: bool,
    seen_elements: bool,
}

/// Lines and binary blocks of a file, with the line number of the next byte.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    path: &'a Path,
    /// Whether the last line read ended with a line break (not at the end of the file).
    terminated: bool,
}

impl<'a> Cursor<'a> {
    /// The next line (without `\r\n`) and its number.
    fn next_line(&mut self) -> Option<(usize, &'a [u8])> {
        let rest = self.bytes.get(self.pos..).filter(|r| !r.is_empty())?;
        let line = self.line;
        let raw = match rest.iter().position(|&b| b == b'\n') {
            Some(k) => {
                self.pos += k + 1;
                self.line += 1;
                self.terminated = true;
                rest.get(..k).unwrap_or_default()
            }
            None => {
                self.pos = self.bytes.len();
                self.terminated = false;
                rest
            }
        };
        Some((line, raw.strip_suffix(b"\r").unwrap_or(raw)))
    }

    /// The next non-blank line as words; `what` names it in the error at the end of the file.
    /// A record is always followed by more (at least an `$End...` line), so a last line without
    /// a line break is a truncated file.
    fn words(&mut self, what: &str) -> Result<(usize, Vec<&'a str>), MeshIoError> {
        let (line, words) = self.any_words(what)?;
        if !self.terminated {
            return Err(MeshIoError::parse(
                self.path,
                line,
                format!("the file ends inside {what}: is it truncated?"),
            ));
        }
        Ok((line, words))
    }

    /// [`Cursor::words`], also for the last line of the file.
    fn any_words(&mut self, what: &str) -> Result<(usize, Vec<&'a str>), MeshIoError> {
        loop {
            let Some((line, raw)) = self.next_line() else {
                return Err(MeshIoError::parse(
                    self.path,
                    self.line,
                    format!("the file ends where {what} was expected: is it truncated?"),
                ));
            };
            let text = std::str::from_utf8(raw).map_err(|_| {
                MeshIoError::parse(
                    self.path,
                    line,
                    format!("expected {what} as text, found binary bytes: is the file corrupt or its $MeshFormat line wrong?"),
                )
            })?;
            let words: Vec<&str> = text.split_whitespace().collect();
            if !words.is_empty() {
                return Ok((line, words));
            }
        }
    }

    /// The next `n` bytes of binary data, about `element` `index`.
    fn take(&mut self, n: usize, element: &str, index: usize) -> Result<&'a [u8], MeshIoError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(MeshIoError::binary(
                self.path,
                element,
                Some(index),
                "the file ends inside its data: is it truncated?",
            ));
        };
        let b = self.bytes.get(self.pos..end).unwrap_or_default();
        self.line += b.iter().filter(|&&x| x == b'\n').count();
        self.pos = end;
        Ok(b)
    }

    /// Reads up to the line `end` (e.g. `$EndNodes`), which must come next (blank lines and the
    /// line break after binary data aside).
    fn expect_end(&mut self, end: &str, hint: &str) -> Result<(), MeshIoError> {
        let (line, words) = self.any_words(&format!("`{end}`"))?;
        if words.len() == 1 && words[0].eq_ignore_ascii_case(end) {
            return Ok(());
        }
        Err(MeshIoError::parse(
            self.path,
            line,
            format!(
                "expected `{end}`, found `{}`: {hint}",
                shorten(&words.join(" "))
            ),
        ))
    }

    /// Skips a section this reader does not need, up to its `$End...` line.
    fn skip_to(&mut self, end: &str, start_line: usize, name: &str) -> Result<(), MeshIoError> {
        while let Some((_, raw)) = self.next_line() {
            if raw.trim_ascii().eq_ignore_ascii_case(end.as_bytes()) {
                return Ok(());
            }
        }
        Err(MeshIoError::parse(
            self.path,
            start_line,
            format!(
                "section `${}` is never closed by `{end}`: is the file truncated?",
                shorten(name)
            ),
        ))
    }

    fn err(&self, line: usize, message: String) -> MeshIoError {
        MeshIoError::parse(self.path, line, message)
    }
}

/// Word `k` parsed as a `T`.
fn word<T: FromStr>(
    c: &Cursor<'_>,
    line: usize,
    words: &[&str],
    k: usize,
    what: &str,
) -> Result<T, MeshIoError> {
    let w = words.get(k).copied().unwrap_or_default();
    w.parse().map_err(|_| {
        if w.is_empty() {
            c.err(
                line,
                format!("the line ends where {what} was expected: is the file truncated?"),
            )
        } else {
            c.err(line, format!("expected {what}, found `{}`", shorten(w)))
        }
    })
}

impl Msh {
    fn need_nodes(
        &self,
        path: &Path,
        line: usize,
        elements: &str,
        nodes: &str,
    ) -> Result<(), MeshIoError> {
        if self.seen_nodes {
            Ok(())
        } else {
            Err(MeshIoError::parse(
                path,
                line,
                format!("{elements} comes before {nodes}: the nodes must come first"),
            ))
        }
    }

    fn read_format(&mut self, c: &mut Cursor<'_>) -> Result<(), MeshIoError> {
        let (line, words) = c.words("the format line `<version> <0|1 binary> <data size>`")?;
        let version = words.first().copied().unwrap_or_default();
        let file_type: u32 = word(c, line, &words, 1, "the file type (0 ASCII, 1 binary)")?;
        let data_size: usize = word(c, line, &words, 2, "the data size")?;
        self.version = match version {
            "4.1" => Version::V41,
            v if v.starts_with("2.") || v == "2" => Version::V2,
            "4" | "4.0" | "3" | "3.0" => {
                return Err(c.err(
                    line,
                    format!(
                        "MSH version {version} is not supported: save the mesh as MSH 4.1 or 2.2 \
                         (Gmsh: File > Export, or `gmsh mesh.msh -save -format msh41`)"
                    ),
                ))
            }
            _ => {
                return Err(c.err(
                    line,
                    format!(
                        "unknown MSH version `{}`: supported are 1, 2.x and 4.1",
                        shorten(version)
                    ),
                ))
            }
        };
        match file_type {
            0 => self.binary = None,
            1 => {
                let size_ok = match self.version {
                    Version::V41 => data_size == 4 || data_size == 8,
                    _ => data_size == 8,
                };
                if !size_ok {
                    return Err(c.err(line, format!("binary data size {data_size}: expected 8 (or 4 for a 32-bit size_t in MSH 4.1)")));
                }
                let one = c.take(4, "header", 0).map_err(|_| {
                    c.err(
                        line,
                        "the file ends after the format line: is it truncated?".into(),
                    )
                })?;
                let little = match one {
                    [1, 0, 0, 0] => true,
                    [0, 0, 0, 1] => false,
                    _ => {
                        return Err(c.err(
                            line + 1,
                            "a binary .msh has the integer 1 after the format line, to tell its byte order; it is missing: was the file converted as text (line ends changed)?".into(),
                        ))
                    }
                };
                self.binary = Some(Binary {
                    little,
                    size_t: data_size,
                });
            }
            _ => {
                return Err(c.err(
                    line,
                    format!("file type {file_type}: expected 0 (ASCII) or 1 (binary)"),
                ))
            }
        }
        c.expect_end("$EndMeshFormat", "the format section has one line")
    }

    fn add_node(
        &mut self,
        c: &Cursor<'_>,
        line: usize,
        tag: u64,
        p: Vec3,
    ) -> Result<(), MeshIoError> {
        let n = self.nodes.positions.len();
        if n >= u32::MAX as usize - 1 {
            return Err(c.err(line, "more than 2^32 - 2 nodes are not supported".into()));
        }
        if self.nodes.index.insert(tag, n as u32).is_some() {
            return Err(c.err(
                line,
                format!("node tag {tag} appears twice: node tags must be unique"),
            ));
        }
        self.nodes.positions.push(p);
        Ok(())
    }

    fn add_node_binary(
        &mut self,
        c: &Cursor<'_>,
        i: usize,
        tag: u64,
        p: Vec3,
    ) -> Result<(), MeshIoError> {
        let n = self.nodes.positions.len();
        if n >= u32::MAX as usize - 1 {
            return Err(MeshIoError::binary(
                c.path,
                "node",
                Some(i),
                "more than 2^32 - 2 nodes are not supported",
            ));
        }
        if self.nodes.index.insert(tag, n as u32).is_some() {
            return Err(MeshIoError::binary(
                c.path,
                "node",
                Some(i),
                format!("node tag {tag} appears twice: node tags must be unique"),
            ));
        }
        self.nodes.positions.push(p);
        Ok(())
    }

    fn skip(&mut self, ty: i64) {
        self.skipped.add(ty);
    }

    /// Node tags of a tetrahedron → indices; `at` reports an unknown tag.
    fn tet(
        &self,
        tags: [u64; 4],
        at: impl Fn(String) -> MeshIoError,
    ) -> Result<[u32; 4], MeshIoError> {
        let mut tet = [0u32; 4];
        for (slot, tag) in tet.iter_mut().zip(tags) {
            *slot = *self.nodes.index.get(&tag).ok_or_else(|| {
                at(format!(
                    "refers to node tag {tag}, which the nodes section does not define"
                ))
            })?;
        }
        Ok(tet)
    }

    // ---------------------------------------------------------------- MSH 1 and 2 (ASCII)

    fn read_v1_nodes(&mut self, c: &mut Cursor<'_>) -> Result<(), MeshIoError> {
        self.read_text_nodes(c, "$ENDNOD")
    }

    /// `n`, then `n` lines `tag x y z` (MSH 1 and ASCII MSH 2).
    fn read_text_nodes(&mut self, c: &mut Cursor<'_>, end: &str) -> Result<(), MeshIoError> {
        let (line, words) = c.words("the number of nodes")?;
        let count: usize = word(c, line, &words, 0, "the number of nodes")?;
        self.nodes
            .positions
            .reserve(capacity(count, c.bytes.len(), 8));
        for i in 0..count {
            let (line, words) = c.words(&format!("node {} of {count}", i + 1))?;
            let tag: u64 = word(c, line, &words, 0, "a node tag (a positive integer)")?;
            let x: f64 = word(c, line, &words, 1, "the node's x coordinate")?;
            let y: f64 = word(c, line, &words, 2, "the node's y coordinate")?;
            let z: f64 = word(c, line, &words, 3, "the node's z coordinate")?;
            self.add_node(c, line, tag, Vec3::new(x as f32, y as f32, z as f32))?;
        }
        self.seen_nodes = true;
        c.expect_end(end, "the node count does not match the node lines")
    }

    fn read_v1_elements(&mut self, c: &mut Cursor<'_>) -> Result<(), MeshIoError> {
        // `tag type physical elementary n-nodes nodes...`
        self.read_text_elements(c, "$ENDELM", |c, line, words| {
            let n: usize = word(c, line, words, 4, "the number of nodes of the element")?;
            if words.len().checked_sub(5) != Some(n) {
                return Err(c.err(line, format!("the element says it has {n} nodes, but the line has {} after the 5 leading numbers", words.len().saturating_sub(5))));
            }
            Ok(5)
        })
    }

    /// `n`, then `n` element lines; `first_node` says where a line's node tags start.
    fn read_text_elements(
        &mut self,
        c: &mut Cursor<'_>,
        end: &str,
        first_node: impl Fn(&Cursor<'_>, usize, &[&str]) -> Result<usize, MeshIoError>,
    ) -> Result<(), MeshIoError> {
        let (line, words) = c.words("the number of elements")?;
        let count: usize = word(c, line, &words, 0, "the number of elements")?;
        self.tets.reserve(capacity(count, c.bytes.len(), 20));
        for i in 0..count {
            let (line, words) = c.words(&format!("element {} of {count}", i + 1))?;
            let tag: i64 = word(c, line, &words, 0, "an element tag (an integer)")?;
            let ty: i64 = word(c, line, &words, 1, "an element type (an integer)")?;
            let k = first_node(c, line, &words)?;
            if ty != GMSH_TET {
                self.skip(ty);
                continue;
            }
            // `k` comes from the file (2^64 - 1 tags is a count like any other): no `k + 4`.
            if words.len().checked_sub(k) != Some(4) {
                return Err(c.err(
                    line,
                    format!(
                        "element {tag} is a tetrahedron (type 4) with {} nodes: it needs 4",
                        words.len().saturating_sub(k)
                    ),
                ));
            }
            let mut tags = [0u64; 4];
            for (j, t) in tags.iter_mut().enumerate() {
                *t = word(c, line, &words, k + j, "a node tag (a positive integer)")?;
            }
            let tet = self.tet(tags, |m| c.err(line, format!("element {tag} {m}")))?;
            self.tets.push(tet);
        }
        self.seen_elements = true;
        c.expect_end(end, "the element count does not match the element lines")
    }

    // ---------------------------------------------------------------- MSH 2 and 4.1

    fn read_nodes(&mut self, c: &mut Cursor<'_>) -> Result<(), MeshIoError> {
        match (self.version, self.binary) {
            (Version::V41, None) => self.read_v41_text_nodes(c),
            (Version::V41, Some(b)) => self.read_v41_binary_nodes(c, b),
            (_, None) => self.read_text_nodes(c, "$EndNodes"),
            (_, Some(b)) => self.read_v2_binary_nodes(c, b),
        }
    }

    fn read_elements(&mut self, c: &mut Cursor<'_>) -> Result<(), MeshIoError> {
        match (self.version, self.binary) {
            (Version::V41, None) => self.read_v41_text_elements(c),
            (Version::V41, Some(b)) => self.read_v41_binary_elements(c, b),
            // `tag type n-tags tags... nodes...`
            (_, None) => self.read_text_elements(c, "$EndElements", |c, line, words| {
                let n: usize = word(c, line, words, 2, "the number of tags of the element")?;
                Ok(3usize.saturating_add(n))
            }),
            (_, Some(b)) => self.read_v2_binary_elements(c, b),
        }
    }

    fn read_v2_binary_nodes(&mut self, c: &mut Cursor<'_>, b: Binary) -> Result<(), MeshIoError> {
        let (line, words) = c.words("the number of nodes")?;
        let count: usize = word(c, line, &words, 0, "the number of nodes")?;
        self.nodes
            .positions
            .reserve(capacity(count, c.bytes.len(), 28));
        for i in 0..count {
            let rec = c.take(28, "node", i)?;
            let tag = int(rec, 0, b);
            let tag = u64::try_from(tag).map_err(|_| {
                MeshIoError::binary(
                    c.path,
                    "node",
                    Some(i),
                    format!("node tag {tag}: tags must be positive"),
                )
            })?;
            let p = Vec3::new(
                f64_at(rec, 4, b) as f32,
                f64_at(rec, 12, b) as f32,
                f64_at(rec, 20, b) as f32,
            );
            self.add_node_binary(c, i, tag, p)?;
        }
        self.seen_nodes = true;
        c.expect_end("$EndNodes", "the node count does not match the node data")
    }

    fn read_v2_binary_elements(
        &mut self,
        c: &mut Cursor<'_>,
        b: Binary,
    ) -> Result<(), MeshIoError> {
        let (line, words) = c.words("the number of elements")?;
        let count: usize = word(c, line, &words, 0, "the number of elements")?;
        let mut done = 0usize;
        while done < count {
            let head = c.take(12, "element", done)?;
            let ty = i64::from(int(head, 0, b));
            let follow = int(head, 4, b);
            let tags = int(head, 8, b);
            let bad = |m: String| MeshIoError::binary(c.path, "element", Some(done), m);
            let follow = usize::try_from(follow).ok().filter(|&f| f >= 1 && f <= count - done).ok_or_else(|| {
                bad(format!("a block of {follow} elements, but {} remain of {count}: the file is corrupt", count - done))
            })?;
            let tags = usize::try_from(tags)
                .ok()
                .filter(|&t| t < 1024)
                .ok_or_else(|| bad(format!("{tags} tags per element: the file is corrupt")))?;
            let nodes = nodes_per_element(ty).ok_or_else(|| {
                bad(format!("element type {ty} is not known to this reader, so its size is unknown: save the mesh as ASCII (Gmsh: -format msh22 without -bin)"))
            })?;
            let width = 4 * (1 + tags + nodes);
            for k in 0..follow {
                let rec = c.take(width, "element", done + k)?;
                if ty == GMSH_TET {
                    let id = int(rec, 0, b);
                    let mut t = [0u64; 4];
                    for (j, slot) in t.iter_mut().enumerate() {
                        *slot = u64::try_from(int(rec, 4 * (1 + tags + j), b)).unwrap_or(u64::MAX);
                    }
                    let i = done + k;
                    let tet = self.tet(t, |m| {
                        MeshIoError::binary(c.path, "element", Some(i), format!("(tag {id}) {m}"))
                    })?;
                    self.tets.push(tet);
                } else {
                    self.skip(ty);
                }
            }
            done += follow;
        }
        self.seen_elements = true;
        c.expect_end(
            "$EndElements",
            "the element count does not match the element data",
        )
    }

    fn read_v41_text_nodes(&mut self, c: &mut Cursor<'_>) -> Result<(), MeshIoError> {
        let what = "the header `<blocks> <nodes> <min tag> <max tag>`";
        let (line, words) = c.words(what)?;
        let blocks: usize = word(c, line, &words, 0, "the number of entity blocks")?;
        let count: usize = word(c, line, &words, 1, "the number of nodes")?;
        self.nodes
            .positions
            .reserve(capacity(count, c.bytes.len(), 8));
        for blk in 0..blocks {
            let (line, words) =
                c.words(&format!("the header of node block {} of {blocks}", blk + 1))?;
            let dim: usize = word(c, line, &words, 0, "the entity dimension (0 to 3)")?;
            let parametric: u32 = word(c, line, &words, 2, "the parametric flag (0 or 1)")?;
            let n: usize = word(c, line, &words, 3, "the number of nodes in the block")?;
            if dim > 3 || parametric > 1 {
                return Err(c.err(line, format!("entity dimension {dim} / parametric flag {parametric}: expected 0..=3 and 0 or 1")));
            }
            let mut tags = Vec::with_capacity(capacity(n, c.bytes.len(), 2));
            for _ in 0..n {
                let (line, words) = c.words("a node tag")?;
                tags.push(word::<u64>(
                    c,
                    line,
                    &words,
                    0,
                    "a node tag (a positive integer)",
                )?);
            }
            for tag in tags {
                let (line, words) = c.words(&format!("the coordinates of node {tag}"))?;
                let x: f64 = word(c, line, &words, 0, "the node's x coordinate")?;
                let y: f64 = word(c, line, &words, 1, "the node's y coordinate")?;
                let z: f64 = word(c, line, &words, 2, "the node's z coordinate")?;
                self.add_node(c, line, tag, Vec3::new(x as f32, y as f32, z as f32))?;
            }
        }
        if self.nodes.positions.len() != count {
            return Err(c.err(
                line,
                format!(
                    "the header says {count} nodes, but the blocks hold {}",
                    self.nodes.positions.len()
                ),
            ));
        }
        self.seen_nodes = true;
        c.expect_end("$EndNodes", "the block sizes do not match the node lines")
    }

    fn read_v41_text_elements(&mut self, c: &mut Cursor<'_>) -> Result<(), MeshIoError> {
        let what = "the header `<blocks> <elements> <min tag> <max tag>`";
        let (line, words) = c.words(what)?;
        let blocks: usize = word(c, line, &words, 0, "the number of entity blocks")?;
        let count: usize = word(c, line, &words, 1, "the number of elements")?;
        self.tets.reserve(capacity(count, c.bytes.len(), 20));
        let mut total = 0usize;
        for blk in 0..blocks {
            let (line, words) = c.words(&format!(
                "the header of element block {} of {blocks}",
                blk + 1
            ))?;
            let ty: i64 = word(c, line, &words, 2, "the element type (an integer)")?;
            let n: usize = word(c, line, &words, 3, "the number of elements in the block")?;
            for _ in 0..n {
                let (line, words) = c.words("an element line `<tag> <node tags...>`")?;
                let tag: u64 = word(c, line, &words, 0, "an element tag (a positive integer)")?;
                total += 1;
                if ty != GMSH_TET {
                    self.skip(ty);
                    continue;
                }
                if words.len() != 5 {
                    return Err(c.err(
                        line,
                        format!(
                            "element {tag} is a tetrahedron (type 4) with {} nodes: it needs 4",
                            words.len() - 1
                        ),
                    ));
                }
                let mut tags = [0u64; 4];
                for (j, t) in tags.iter_mut().enumerate() {
                    *t = word(c, line, &words, 1 + j, "a node tag (a positive integer)")?;
                }
                let tet = self.tet(tags, |m| c.err(line, format!("element {tag} {m}")))?;
                self.tets.push(tet);
            }
        }
        if total != count {
            return Err(c.err(
                line,
                format!("the header says {count} elements, but the blocks hold {total}"),
            ));
        }
        self.seen_elements = true;
        c.expect_end(
            "$EndElements",
            "the block sizes do not match the element lines",
        )
    }

    fn read_v41_binary_nodes(&mut self, c: &mut Cursor<'_>, b: Binary) -> Result<(), MeshIoError> {
        let s = b.size_t;
        let head = c.take(4 * s, "node block", 0)?;
        let blocks = size(head, 0, b);
        let count = size(head, s, b);
        let bad = |i: usize, m: String| MeshIoError::binary(c.path, "node block", Some(i), m);
        let blocks = usize::try_from(blocks)
            .ok()
            .filter(|&n| n <= c.bytes.len())
            .ok_or_else(|| bad(0, format!("{blocks} node blocks: the file is corrupt")))?;
        let count = usize::try_from(count).unwrap_or(usize::MAX);
        self.nodes
            .positions
            .reserve(capacity(count, c.bytes.len(), 24 + s));
        let mut node = 0usize;
        for blk in 0..blocks {
            let h = c.take(12 + s, "node block", blk)?;
            let dim = int(h, 0, b);
            let parametric = int(h, 8, b);
            let n = size(h, 12, b);
            if !(0..=3).contains(&dim) || !(0..=1).contains(&parametric) {
                return Err(MeshIoError::binary(c.path, "node block", Some(blk), format!("entity dimension {dim} / parametric flag {parametric}: the file is corrupt")));
            }
            let n = usize::try_from(n)
                .ok()
                .filter(|&n| n.saturating_mul(s) <= c.bytes.len())
                .ok_or_else(|| {
                    MeshIoError::binary(
                        c.path,
                        "node block",
                        Some(blk),
                        format!("{n} nodes: more than the file holds, is it truncated?"),
                    )
                })?;
            let tags = c.take(n * s, "node", node)?;
            let width = 8 * (3 + if parametric == 1 { dim as usize } else { 0 });
            for k in 0..n {
                let rec = c.take(width, "node", node + k)?;
                let tag = size(tags, k * s, b);
                let p = Vec3::new(
                    f64_at(rec, 0, b) as f32,
                    f64_at(rec, 8, b) as f32,
                    f64_at(rec, 16, b) as f32,
                );
                self.add_node_binary(c, node + k, tag, p)?;
            }
            node += n;
        }
        if node != count {
            return Err(MeshIoError::binary(
                c.path,
                "node block",
                None,
                format!("the header says {count} nodes, but the blocks hold {node}"),
            ));
        }
        self.seen_nodes = true;
        c.expect_end("$EndNodes", "the block sizes do not match the node data")
    }

    fn read_v41_binary_elements(
        &mut self,
        c: &mut Cursor<'_>,
        b: Binary,
    ) -> Result<(), MeshIoError> {
        let s = b.size_t;
        let head = c.take(4 * s, "element block", 0)?;
        let blocks = size(head, 0, b);
        let count = size(head, s, b);
        let blocks = usize::try_from(blocks)
            .ok()
            .filter(|&n| n <= c.bytes.len())
            .ok_or_else(|| {
                MeshIoError::binary(
                    c.path,
                    "element block",
                    Some(0),
                    format!("{blocks} element blocks: the file is corrupt"),
                )
            })?;
        let count = usize::try_from(count).unwrap_or(usize::MAX);
        let mut element = 0usize;
        for blk in 0..blocks {
            let h = c.take(12 + s, "element block", blk)?;
            let ty = i64::from(int(h, 8, b));
            let n = size(h, 12, b);
            let bad = |m: String| MeshIoError::binary(c.path, "element block", Some(blk), m);
            let nodes = nodes_per_element(ty).ok_or_else(|| {
                bad(format!("element type {ty} is not known to this reader, so its size is unknown: save the mesh as ASCII MSH 4.1"))
            })?;
            let width = s * (1 + nodes);
            let n = usize::try_from(n)
                .ok()
                .filter(|&n| n.saturating_mul(width) <= c.bytes.len())
                .ok_or_else(|| {
                    bad(format!(
                        "{n} elements: more than the file holds, is it truncated?"
                    ))
                })?;
            for k in 0..n {
                let rec = c.take(width, "element", element + k)?;
                if ty == GMSH_TET {
                    let id = size(rec, 0, b);
                    let mut t = [0u64; 4];
                    for (j, slot) in t.iter_mut().enumerate() {
                        *slot = size(rec, s * (1 + j), b);
                    }
                    let i = element + k;
                    let tet = self.tet(t, |m| {
                        MeshIoError::binary(c.path, "element", Some(i), format!("(tag {id}) {m}"))
                    })?;
                    self.tets.push(tet);
                } else {
                    self.skip(ty);
                }
            }
            element += n;
        }
        if element != count {
            return Err(MeshIoError::binary(
                c.path,
                "element block",
                None,
                format!("the header says {count} elements, but the blocks hold {element}"),
            ));
        }
        self.seen_elements = true;
        c.expect_end(
            "$EndElements",
            "the block sizes do not match the element data",
        )
    }
}

fn bytes_at<const N: usize>(rec: &[u8], at: usize, b: Binary) -> [u8; N] {
    let mut out = [0u8; N];
    if let Some(src) = rec.get(at..at + N) {
        out.copy_from_slice(src);
    }
    if !b.little {
        out.reverse();
    }
    out
}

/// A 4-byte `int` at byte `at` of a record.
fn int(rec: &[u8], at: usize, b: Binary) -> i32 {
    i32::from_le_bytes(bytes_at(rec, at, b))
}

/// A `size_t` (4 or 8 bytes) at byte `at` of a record.
fn size(rec: &[u8], at: usize, b: Binary) -> u64 {
    if b.size_t == 4 {
        u64::from(u32::from_le_bytes(bytes_at(rec, at, b)))
    } else {
        u64::from_le_bytes(bytes_at(rec, at, b))
    }
}

/// A `double` at byte `at` of a record.
fn f64_at(rec: &[u8], at: usize, b: Binary) -> f64 {
    f64::from_le_bytes(bytes_at(rec, at, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    const V2: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"body\"\n$EndPhysicalNames\n$Nodes\n5\n10 0 0 0\n20 1 0 0\n30 0 1 0\n7 0 0 1\n99 1 1 1\n$EndNodes\n$Elements\n3\n1 15 2 0 1 10\n2 2 2 0 1 10 20 30\n3 4 2 1 1 10 20 30 7\n$EndElements\n";

    #[test]
    fn v2_ascii_with_sparse_tags() {
        let d = parse_msh(V2.as_bytes(), "a.msh").unwrap();
        assert_eq!(d.positions.len(), 5);
        assert_eq!(d.tets, vec![[0, 1, 2, 3]]);
    }

    #[test]
    fn v1_as_sofa_ships_it() {
        let text = "$NOD\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$ENDNOD\n$ELM\n2\n1 4 1 1 4 1 2 3 4\n2 2 1 1 3 1 2 3\n$ENDELM\n";
        let d = parse_msh(text.as_bytes(), "s.msh").unwrap();
        assert_eq!(d.tets, vec![[0, 1, 2, 3]]);
    }

    #[test]
    fn errors_name_line_and_element() {
        let bad = V2.replace("3 4 2 1 1 10 20 30 7", "3 4 2 1 1 10 20 30 8");
        let e = parse_msh(bad.as_bytes(), "a.msh").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 20, .. }), "{e}");
        assert!(e.to_string().contains("node tag 8"), "{e}");
        let bad = V2.replace("3 4 2 1 1", "3 5 2 1 1");
        let e = parse_msh(bad.as_bytes(), "a.msh").unwrap_err();
        assert!(e.to_string().contains("no 4-node tetrahedra"), "{e}");
        let e = parse_msh(
            V2.replace("4.1", "4")
                .replace("2.2 0 8", "4 0 8")
                .as_bytes(),
            "a.msh",
        )
        .unwrap_err();
        assert!(e.to_string().contains("MSH 4.1 or 2.2"), "{e}");
        let e = parse_msh(&V2.as_bytes()[..200], "a.msh").unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
    }

    #[test]
    fn huge_counts_in_an_element_line_are_errors_not_overflows() {
        // MSH 2: `tag type n-tags tags... nodes...`, with 2^64 - 1 tags.
        let v2 = V2.replace(
            "3 4 2 1 1 10 20 30 7",
            "3 4 18446744073709551615 1 1 10 20 30 7",
        );
        let e = parse_msh(v2.as_bytes(), "a.msh").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 20, .. }), "{e}");
        // MSH 1: `tag type physical elementary n-nodes nodes...`, with 2^64 - 1 nodes.
        let v1 =
            "$NOD\n1\n1 0 0 0\n$ENDNOD\n$ELM\n1\n1 4 1 1 18446744073709551615 1 1 1 1\n$ENDELM\n";
        let e = parse_msh(v1.as_bytes(), "s.msh").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 7, .. }), "{e}");
    }

    #[test]
    fn binary_ints_either_byte_order() {
        let le = Binary {
            little: true,
            size_t: 8,
        };
        let be = Binary {
            little: false,
            size_t: 4,
        };
        assert_eq!(int(&[2, 0, 0, 0], 0, le), 2);
        assert_eq!(int(&[0, 0, 0, 2], 0, be), 2);
        assert_eq!(size(&[0, 0, 1, 0], 0, be), 256);
        assert_eq!(f64_at(&1.5f64.to_be_bytes(), 0, be), 1.5);
    }
}
