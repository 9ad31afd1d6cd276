//! TetGen `.node` / `.ele` tetrahedral meshes (read only).
//!
//! `.node`: a header `<#nodes> [<dim = 3> [<#attributes> [<boundary marker 0|1>]]]`, then one
//! line per node `<index> <x> <y> <z> [attributes...] [marker]`. `.ele`: a header
//! `<#tets> [<nodes per tet 4|10> [<region attribute 0|1>]]`, then `<index> <n1> ... <n4>
//! [n5 ... n10] [region]`; of a 10-node (quadratic) tet only the 4 corners are kept. `#` starts
//! a comment anywhere; blank lines are skipped; lines after the declared records are ignored.
//!
//! Numbering: the first node's index (0 or 1) sets the base of the whole mesh, nodes must then
//! be numbered consecutively, and `.ele` node references are shifted by the same base, so the
//! data come back 0-based either way. Errors name the file (`.node` or `.ele`) and the line.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::atomic::read_file;
use crate::text::{capacity, parse_number};
use crate::{MeshIoError, TetData};

/// Reads a TetGen mesh. `path` may name the `.node` file, the `.ele` file, or their common stem
/// (`bunny` or `bunny.1` for `bunny.1.node` + `bunny.1.ele`); the other file is found beside it.
pub fn read_tetgen(path: impl AsRef<Path>) -> Result<TetData, MeshIoError> {
    let (node, ele) = tetgen_paths(path.as_ref());
    let _span = tracing::debug_span!("read_tetgen", node = %node.display()).entered();
    let node_bytes = read_file(&node)?;
    let ele_bytes = read_file(&ele)?;
    parse_tetgen(&node_bytes, &node, &ele_bytes, &ele)
}

/// The `.node` and `.ele` paths for a `.node`, `.ele` or stem path.
pub(crate) fn tetgen_paths(path: &Path) -> (PathBuf, PathBuf) {
    let is_tetgen = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("node") || e.eq_ignore_ascii_case("ele"));
    let stem = if is_tetgen {
        path.with_extension("")
    } else {
        path.to_path_buf()
    };
    let with = |ext: &str| {
        let mut s: OsString = stem.clone().into_os_string();
        s.push(ext);
        PathBuf::from(s)
    };
    (with(".node"), with(".ele"))
}

/// Parses TetGen `.node` and `.ele` text held in memory; the names stand for the files in error
/// messages.
pub fn parse_tetgen(
    node: &[u8],
    node_name: impl AsRef<Path>,
    ele: &[u8],
    ele_name: impl AsRef<Path>,
) -> Result<TetData, MeshIoError> {
    let (positions, base) = parse_node(node, node_name.as_ref())?;
    let tets = parse_ele(ele, ele_name.as_ref(), base, positions.len())?;
    Ok(TetData { positions, tets })
}

/// Non-blank, comment-free lines split into words, with 1-based line numbers.
struct Records<'a> {
    bytes: &'a [u8],
    /// Start of the next line in `bytes`.
    offset: usize,
    path: &'a Path,
    /// Line of the last record returned (or of the end of the file).
    line: usize,
}

impl<'a> Records<'a> {
    fn new(bytes: &'a [u8], path: &'a Path) -> Self {
        Records {
            bytes,
            offset: 0,
            path,
            line: 0,
        }
    }

    fn next_record(&mut self) -> Result<Option<Vec<&'a str>>, MeshIoError> {
        while let Some(rest) = self.bytes.get(self.offset..).filter(|r| !r.is_empty()) {
            self.line += 1;
            let raw = match rest.iter().position(|&b| b == b'\n') {
                Some(k) => {
                    self.offset += k + 1;
                    rest.get(..k).unwrap_or_default()
                }
                None => {
                    self.offset = self.bytes.len();
                    rest
                }
            };
            let content = match raw.iter().position(|&b| b == b'#') {
                Some(hash) => raw.get(..hash).unwrap_or_default(),
                None => raw,
            };
            let text = std::str::from_utf8(content).map_err(|_| {
                MeshIoError::parse(
                    self.path,
                    self.line,
                    "not text (not UTF-8): is this a binary file?",
                )
            })?;
            let words: Vec<&str> = text.split_whitespace().collect();
            if !words.is_empty() {
                return Ok(Some(words));
            }
        }
        self.line = self.line.max(1);
        Ok(None)
    }

    /// The next record, which must exist: `what` names it in the error.
    fn need(&mut self, what: &str) -> Result<Vec<&'a str>, MeshIoError> {
        self.next_record()?.ok_or_else(|| {
            MeshIoError::parse(
                self.path,
                self.line,
                format!("the file ends where {what} was expected: is it truncated?"),
            )
        })
    }

    fn err(&self, message: String) -> MeshIoError {
        MeshIoError::parse(self.path, self.line, message)
    }

    /// Word `k` of a record parsed as a `T`.
    fn word<T: std::str::FromStr>(
        &self,
        words: &[&str],
        k: usize,
        what: &str,
    ) -> Result<T, MeshIoError> {
        let w = words.get(k).copied().unwrap_or_default();
        parse_number(w, self.path, self.line, what)
    }

    /// Optional header word `k`, `default` when absent.
    fn header_word(
        &self,
        words: &[&str],
        k: usize,
        default: usize,
        what: &str,
    ) -> Result<usize, MeshIoError> {
        if words.len() > k {
            self.word(words, k, what)
        } else {
            Ok(default)
        }
    }
}

fn parse_node(bytes: &[u8], path: &Path) -> Result<(Vec<Vec3>, u32), MeshIoError> {
    let mut rec = Records::new(bytes, path);
    let header = rec.need("the header `<#nodes> 3 <#attributes> <#markers>`")?;
    let count: usize = rec.word(&header, 0, "the number of nodes")?;
    let dim = rec.header_word(&header, 1, 3, "the dimension (3)")?;
    let attributes = rec.header_word(&header, 2, 0, "the number of attributes")?;
    let markers = rec.header_word(&header, 3, 0, "the boundary-marker flag (0 or 1)")?;
    if dim != 3 {
        return Err(rec.err(format!("dimension {dim}: only 3-D meshes can be read")));
    }
    if markers > 1 {
        return Err(rec.err(format!("boundary-marker flag {markers}: it must be 0 or 1")));
    }
    let width = 4usize.saturating_add(attributes).saturating_add(markers);
    if count >= u32::MAX as usize {
        return Err(rec.err(format!("{count} nodes: at most 2^32 - 2 are supported")));
    }
    let mut positions = Vec::with_capacity(capacity(count, bytes.len(), 8));
    let mut base = 0u32;
    for i in 0..count {
        let words = rec.need(&format!("node {} of {count}", i + 1))?;
        if words.len() < width {
            return Err(rec.err(format!(
                "a node line needs its index, x, y, z, {attributes} attribute(s) and {markers} marker(s): {width} values, found {}",
                words.len()
            )));
        }
        let index: i64 = rec.word(&words, 0, "a node index (an integer)")?;
        if i == 0 {
            base = match index {
                0 => 0,
                1 => 1,
                _ => {
                    return Err(rec.err(format!(
                        "the first node is numbered {index}: TetGen numbers nodes from 0 or from 1"
                    )))
                }
            };
        } else if index != i as i64 + i64::from(base) {
            return Err(rec.err(format!(
                "node numbered {index}, expected {}: nodes must be numbered consecutively",
                i as i64 + i64::from(base)
            )));
        }
        let x = rec.word(&words, 1, "the node's x coordinate")?;
        let y = rec.word(&words, 2, "the node's y coordinate")?;
        let z = rec.word(&words, 3, "the node's z coordinate")?;
        positions.push(Vec3::new(x, y, z));
    }
    Ok((positions, base))
}

fn parse_ele(
    bytes: &[u8],
    path: &Path,
    base: u32,
    nodes: usize,
) -> Result<Vec<[u32; 4]>, MeshIoError> {
    let mut rec = Records::new(bytes, path);
    let header = rec.need("the header `<#tetrahedra> <4|10> <0|1>`")?;
    let count: usize = rec.word(&header, 0, "the number of tetrahedra")?;
    let per_tet = rec.header_word(&header, 1, 4, "the nodes per tetrahedron (4 or 10)")?;
    let region = rec.header_word(&header, 2, 0, "the region-attribute flag (0 or 1)")?;
    if per_tet != 4 && per_tet != 10 {
        return Err(rec.err(format!(
            "{per_tet} nodes per tetrahedron: TetGen writes 4 (linear) or 10 (quadratic)"
        )));
    }
    if region > 1 {
        return Err(rec.err(format!("region-attribute flag {region}: it must be 0 or 1")));
    }
    let width = 1 + per_tet + region;
    let mut tets = Vec::with_capacity(capacity(count, bytes.len(), 10));
    let first = i64::from(base);
    let last = first + nodes as i64 - 1;
    for t in 0..count {
        let words = rec.need(&format!("tetrahedron {} of {count}", t + 1))?;
        if words.len() < width {
            return Err(rec.err(format!(
                "a tetrahedron line needs its index, {per_tet} node numbers and {region} region attribute(s): {width} values, found {}",
                words.len()
            )));
        }
        rec.word::<i64>(&words, 0, "a tetrahedron index (an integer)")?;
        let mut tet = [0u32; 4];
        for (k, slot) in tet.iter_mut().enumerate() {
            let n: i64 = rec.word(&words, k + 1, "a node number (an integer)")?;
            if n < first || n > last {
                return Err(rec.err(format!(
                    "tetrahedron {t} refers to node {n}, but the .node file has nodes {first}..={last}"
                )));
            }
            // In range 0..nodes < 2^32 - 1 by the two checks above.
            *slot = u32::try_from(n - first).unwrap_or(u32::MAX);
        }
        tets.push(tet);
    }
    Ok(tets)
}

#[cfg(test)]
mod tests {
    use super::*;

    const NODE1: &str =
        "# one-based\n4 3 1 1\n1 0 0 0 7.5 1\n2 1 0 0 7.5 1\n\n3 0 1 0 7.5 1 # c\n4 0 0 1 7.5 1\n";
    const ELE1: &str = "1 4 1\n  1 1 2 3 4 9\n# Generated by hand\n";

    #[test]
    fn one_based_with_attributes_and_markers() {
        let d = parse_tetgen(NODE1.as_bytes(), "m.node", ELE1.as_bytes(), "m.ele").unwrap();
        assert_eq!(d.positions.len(), 4);
        assert_eq!(d.positions[3], Vec3::Z);
        assert_eq!(d.tets, vec![[0, 1, 2, 3]]);
    }

    #[test]
    fn errors_name_file_and_line() {
        let bad = NODE1.replace("3 0 1 0", "3 0 x 0");
        let e = parse_tetgen(bad.as_bytes(), "m.node", ELE1.as_bytes(), "m.ele").unwrap_err();
        assert!(
            matches!(&e, MeshIoError::Parse { line: 6, path, .. } if path.ends_with("m.node")),
            "{e}"
        );
        let bad = ELE1.replace("1 2 3 4 9", "1 2 3 5 9");
        let e = parse_tetgen(NODE1.as_bytes(), "m.node", bad.as_bytes(), "m.ele").unwrap_err();
        assert!(
            matches!(&e, MeshIoError::Parse { line: 2, path, .. } if path.ends_with("m.ele")),
            "{e}"
        );
        let e =
            parse_tetgen(NODE1.as_bytes(), "m.node", b"2 4 0\n0 1 2 3 4\n", "m.ele").unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
        let bad = NODE1.replace("\n3 0 1", "\n5 0 1");
        let e = parse_tetgen(bad.as_bytes(), "m.node", ELE1.as_bytes(), "m.ele").unwrap_err();
        assert!(e.to_string().contains("consecutively"), "{e}");
    }

    #[test]
    fn paths_from_node_ele_or_stem() {
        let want = (PathBuf::from("d/b.1.node"), PathBuf::from("d/b.1.ele"));
        assert_eq!(tetgen_paths(Path::new("d/b.1.node")), want);
        assert_eq!(tetgen_paths(Path::new("d/b.1.ELE")), want);
        assert_eq!(tetgen_paths(Path::new("d/b.1")), want);
    }
}
