//! Legacy VTK, ASCII: surfaces and tetrahedral meshes with per-vertex fields, out and back in.
//!
//! Written: `# vtk DataFile Version 3.0`, `DATASET POLYDATA` with `POLYGONS` (surfaces) or
//! `DATASET UNSTRUCTURED_GRID` with `CELLS` / `CELL_TYPES` 10 = `VTK_TETRA` (tets), then
//! `POINT_DATA` with one `SCALARS name float 1` or `VECTORS name float` block per field.
//! ParaView opens these. A tet `a b c d` is stored as given; VTK's orientation (`a b c` seen
//! counter-clockwise from `d`) is our positive volume.
//!
//! Read: the same subset. `POINTS` of any numeric type, `POLYGONS` (polygons fan-triangulated),
//! `CELLS` of type 5 (triangle) or 10 (tetra), not mixed, and `POINT_DATA` `SCALARS` (one
//! component, optional `LOOKUP_TABLE`) and `VECTORS`. Anything else (binary files, VTK 5
//! `OFFSETS`/`CONNECTIVITY`, `CELL_DATA`, lines, strips, other cell types) is an error that says
//! so and names the line. Keywords are matched case-insensitively.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use glam::Vec3;
use tissue_mesh::{TetMesh, TriMesh};

use crate::atomic::{read_file, write_atomic};
use crate::obj::fan;
use crate::text::{capacity, parse_number, shorten, utf8, Tokens, F};
use crate::{MeshIoError, SurfaceData, TetData};

/// One per-vertex field to write with a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexField<'a> {
    /// The name ParaView shows; non-empty, without whitespace.
    pub name: &'a str,
    /// One value per vertex.
    pub values: FieldValues<'a>,
}

/// The values of a [`VertexField`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FieldValues<'a> {
    /// One number per vertex (e.g. a stress measure).
    Scalars(&'a [f32]),
    /// One vector per vertex (e.g. a displacement in cm).
    Vectors(&'a [Vec3]),
}

impl FieldValues<'_> {
    fn len(&self) -> usize {
        match self {
            FieldValues::Scalars(v) => v.len(),
            FieldValues::Vectors(v) => v.len(),
        }
    }
}

/// A per-vertex field read from a VTK file.
#[derive(Debug, Clone, PartialEq)]
pub struct PointField {
    /// The field's name.
    pub name: String,
    /// One value per vertex.
    pub values: PointValues,
}

impl PointField {
    /// The field as a [`VertexField`], to write it again.
    pub fn as_vertex_field(&self) -> VertexField<'_> {
        VertexField {
            name: &self.name,
            values: match &self.values {
                PointValues::Scalars(v) => FieldValues::Scalars(v),
                PointValues::Vectors(v) => FieldValues::Vectors(v),
            },
        }
    }
}

/// The values of a [`PointField`].
#[derive(Debug, Clone, PartialEq)]
pub enum PointValues {
    /// One number per vertex.
    Scalars(Vec<f32>),
    /// One vector per vertex.
    Vectors(Vec<Vec3>),
}

/// What a VTK file holds.
#[derive(Debug, Clone, PartialEq)]
pub enum VtkMesh {
    /// A triangle surface (`POLYDATA`, or an `UNSTRUCTURED_GRID` of triangles).
    Surface(SurfaceData),
    /// A tetrahedral mesh (an `UNSTRUCTURED_GRID` of tetrahedra).
    Tets(TetData),
}

/// A VTK file's mesh and per-vertex fields, unvalidated.
#[derive(Debug, Clone, PartialEq)]
pub struct VtkData {
    /// The mesh.
    pub mesh: VtkMesh,
    /// The `POINT_DATA` fields, in file order.
    pub fields: Vec<PointField>,
}

/// Reads a legacy ASCII VTK file (the subset described in the module docs).
pub fn read_vtk(path: impl AsRef<Path>) -> Result<VtkData, MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("read_vtk", path = %path.display()).entered();
    parse_vtk(&read_file(path)?, path)
}

/// Parses legacy ASCII VTK text held in memory; `name` stands for the file in error messages.
pub fn parse_vtk(bytes: &[u8], name: impl AsRef<Path>) -> Result<VtkData, MeshIoError> {
    let path = name.as_ref();
    let text = utf8(bytes, path, "legacy ASCII VTK")?;
    let first = text.lines().next().unwrap_or_default();
    if !first.trim_start().starts_with("# vtk DataFile") {
        return Err(MeshIoError::parse(
            path,
            1,
            "not a legacy VTK file: the first line must be `# vtk DataFile Version x.y`",
        ));
    }
    // Line 2 is a free-text title.
    let mut t = Tokens::after_lines(text, 2);
    let err = |t: &Tokens<'_>, message: String| MeshIoError::parse(path, t.line(), message);
    let encoding = t.need(path, "`ASCII`")?;
    if encoding.eq_ignore_ascii_case("BINARY") {
        return Err(err(
            &t,
            "binary legacy VTK is not supported: save the file as ASCII".into(),
        ));
    }
    if !encoding.eq_ignore_ascii_case("ASCII") {
        return Err(err(
            &t,
            format!("expected `ASCII`, found `{}`", shorten(encoding)),
        ));
    }
    t.expect(path, "DATASET")?;
    let dataset = t.need(path, "the dataset type")?;
    let polydata = if dataset.eq_ignore_ascii_case("POLYDATA") {
        true
    } else if dataset.eq_ignore_ascii_case("UNSTRUCTURED_GRID") {
        false
    } else {
        return Err(err(
            &t,
            format!(
                "dataset type `{}` is not supported: expected POLYDATA or UNSTRUCTURED_GRID",
                shorten(dataset)
            ),
        ));
    };

    let mut points: Option<Vec<Vec3>> = None;
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut tets: Vec<[u32; 4]> = Vec::new();
    let mut fields = Vec::new();
    let mut polygon = Vec::new();
    while let Some(section) = t.next_token() {
        let upper = section.to_ascii_uppercase();
        match upper.as_str() {
            "POINTS" => {
                if points.is_some() {
                    return Err(err(&t, "a second POINTS section".into()));
                }
                let n: usize = t.number(path, "the number of points")?;
                t.need(path, "the point data type (e.g. `float`)")?;
                if n >= u32::MAX as usize {
                    return Err(err(&t, format!("{n} points: at most 2^32 - 2 are supported")));
                }
                let mut p = Vec::with_capacity(capacity(n, text.len(), 6));
                for i in 0..n {
                    let mut xyz = [0.0f32; 3];
                    for (axis, v) in ["x", "y", "z"].iter().zip(xyz.iter_mut()) {
                        *v = t.number(path, &format!("the {axis} coordinate of point {i}"))?;
                    }
                    p.push(Vec3::from_array(xyz));
                }
                points = Some(p);
            }
            "POLYGONS" if polydata => {
                let n_points = points.as_ref().map_or(0, Vec::len);
                let cells: usize = t.number(path, "the number of polygons")?;
                let size: usize = t.number(path, "the size of the polygon list")?;
                if t.peek().is_some_and(|w| w.eq_ignore_ascii_case("OFFSETS")) {
                    t.next_token();
                    return Err(err(&t, "the VTK 5 OFFSETS/CONNECTIVITY layout is not supported: save as legacy VTK 4.2 or earlier".into()));
                }
                let mut total = 0usize;
                for c in 0..cells {
                    let k: usize = t.number(path, &format!("the vertex count of polygon {c}"))?;
                    polygon.clear();
                    for _ in 0..k {
                        polygon.push(point_index(&mut t, path, n_points, "polygon", c)?);
                    }
                    if k < 3 {
                        return Err(err(&t, format!("polygon {c} has {k} vertices: at least 3 are needed")));
                    }
                    fan(&polygon, &mut triangles);
                    total = total.saturating_add(k.saturating_add(1));
                }
                if total != size {
                    return Err(err(&t, format!("POLYGONS declares a list size of {size}, but its cells use {total} numbers")));
                }
            }
            "CELLS" if !polydata => {
                let n_points = points.as_ref().map_or(0, Vec::len);
                let cells: usize = t.number(path, "the number of cells")?;
                let size: usize = t.number(path, "the size of the cell list")?;
                if t.peek().is_some_and(|w| w.eq_ignore_ascii_case("OFFSETS")) {
                    t.next_token();
                    return Err(err(&t, "the VTK 5 OFFSETS/CONNECTIVITY layout is not supported: save as legacy VTK 4.2 or earlier".into()));
                }
                // (first index in `connectivity`, vertex count) per cell.
                let mut spans = Vec::with_capacity(capacity(cells, text.len(), 4));
                let mut connectivity = Vec::with_capacity(capacity(size, text.len(), 2));
                let mut total = 0usize;
                for c in 0..cells {
                    let k: usize = t.number(path, &format!("the vertex count of cell {c}"))?;
                    spans.push((connectivity.len(), k));
                    for _ in 0..k {
                        connectivity.push(point_index(&mut t, path, n_points, "cell", c)?);
                    }
                    total = total.saturating_add(k.saturating_add(1));
                }
                if total != size {
                    return Err(err(&t, format!("CELLS declares a list size of {size}, but its cells use {total} numbers")));
                }
                t.expect(path, "CELL_TYPES")?;
                let n_types: usize = t.number(path, "the number of cell types")?;
                if n_types != cells {
                    return Err(err(&t, format!("CELL_TYPES has {n_types} entries, but CELLS has {cells}")));
                }
                for (c, &(start, k)) in spans.iter().enumerate() {
                    let kind: u32 = t.number(path, &format!("the type of cell {c}"))?;
                    let ids = connectivity.get(start..start.saturating_add(k)).unwrap_or_default();
                    match (kind, ids) {
                        (10, &[a, b, cc, d]) => tets.push([a, b, cc, d]),
                        (5, &[a, b, cc]) => triangles.push([a, b, cc]),
                        (10 | 5, _) => {
                            return Err(err(&t, format!(
                                "cell {c} has type {kind} ({}) but {k} vertices",
                                if kind == 10 { "tetra, 4 vertices" } else { "triangle, 3 vertices" }
                            )))
                        }
                        _ => {
                            return Err(err(&t, format!(
                                "cell {c} has VTK cell type {kind}: only 5 (triangle) and 10 (tetra) are supported"
                            )))
                        }
                    }
                }
                if !tets.is_empty() && !triangles.is_empty() {
                    return Err(err(&t, "the grid mixes tetrahedra and triangles: write them to separate files".into()));
                }
            }
            "POINT_DATA" => {
                let n_points = points.as_ref().map_or(0, Vec::len);
                let n: usize = t.number(path, "the number of point values")?;
                if n != n_points {
                    return Err(err(&t, format!("POINT_DATA is for {n} points, but the file has {n_points}")));
                }
                read_point_data(&mut t, path, n, text.len(), &mut fields)?;
            }
            _ => {
                return Err(err(
                    &t,
                    format!(
                        "unsupported section `{}`: this reader knows POINTS, {}, POINT_DATA (SCALARS, VECTORS)",
                        shorten(section),
                        if polydata { "POLYGONS" } else { "CELLS, CELL_TYPES" }
                    ),
                ))
            }
        }
    }
    let Some(positions) = points else {
        return Err(MeshIoError::parse(
            path,
            t.line(),
            "the file has no POINTS section",
        ));
    };
    let mesh = if polydata || (tets.is_empty() && !triangles.is_empty()) {
        VtkMesh::Surface(SurfaceData {
            positions,
            triangles,
        })
    } else {
        VtkMesh::Tets(TetData { positions, tets })
    };
    Ok(VtkData { mesh, fields })
}

/// One point index of cell `c`, checked against the number of points.
fn point_index(
    t: &mut Tokens<'_>,
    path: &Path,
    n_points: usize,
    what: &str,
    c: usize,
) -> Result<u32, MeshIoError> {
    let i: u64 = t.number(path, &format!("a point index of {what} {c}"))?;
    if i >= n_points as u64 {
        return Err(MeshIoError::parse(
            path,
            t.line(),
            format!("{what} {c} refers to point {i}, but there are {n_points} points (indices count from 0; POINTS must come first)"),
        ));
    }
    Ok(u32::try_from(i).unwrap_or(u32::MAX))
}

/// `SCALARS` / `VECTORS` blocks of a `POINT_DATA` section, until another keyword or the end.
fn read_point_data(
    t: &mut Tokens<'_>,
    path: &Path,
    n: usize,
    text_len: usize,
    fields: &mut Vec<PointField>,
) -> Result<(), MeshIoError> {
    while let Some(kind) = t.peek() {
        let scalars = kind.eq_ignore_ascii_case("SCALARS");
        if !scalars && !kind.eq_ignore_ascii_case("VECTORS") {
            if kind.eq_ignore_ascii_case("POINTS")
                || kind.eq_ignore_ascii_case("POLYGONS")
                || kind.eq_ignore_ascii_case("CELLS")
            {
                return Ok(());
            }
            t.next_token();
            return Err(MeshIoError::parse(
                path,
                t.line(),
                format!(
                    "unsupported point data `{}`: this reader knows SCALARS and VECTORS",
                    shorten(kind)
                ),
            ));
        }
        t.next_token();
        let name = t.need(path, "the field name")?.to_string();
        t.need(path, "the field's data type (e.g. `float`)")?;
        let values = if scalars {
            // The optional component count shares the SCALARS line.
            let rest = t.rest_of_line();
            if !rest.is_empty() {
                let c: u32 = parse_number(rest, path, t.line(), "the number of components (1)")?;
                if c != 1 {
                    return Err(MeshIoError::parse(
                        path,
                        t.line(),
                        format!("SCALARS `{name}` has {c} components: only 1 is supported (use VECTORS for 3)"),
                    ));
                }
            }
            if t.peek()
                .is_some_and(|w| w.eq_ignore_ascii_case("LOOKUP_TABLE"))
            {
                t.next_token();
                t.need(path, "the lookup table name")?;
            }
            let mut v = Vec::with_capacity(capacity(n, text_len, 2));
            for i in 0..n {
                v.push(t.number(path, &format!("value {i} of field `{name}`"))?);
            }
            PointValues::Scalars(v)
        } else {
            let mut v = Vec::with_capacity(capacity(n, text_len, 2));
            for i in 0..n {
                let mut xyz = [0.0f32; 3];
                for x in &mut xyz {
                    *x = t.number(path, &format!("vector {i} of field `{name}`"))?;
                }
                v.push(Vec3::from_array(xyz));
            }
            PointValues::Vectors(v)
        };
        fields.push(PointField { name, values });
    }
    Ok(())
}

/// The cells of a dataset to write.
enum Cells<'a> {
    Triangles(&'a [[u32; 3]]),
    Tets(&'a [[u32; 4]]),
}

/// Writes a surface as legacy ASCII VTK `POLYDATA` with per-vertex fields, atomically.
/// Values are written in the shortest form that reads back to the same `f32` bits.
///
/// Every field must have one value per vertex and a non-empty name without whitespace; this is
/// checked before anything is written.
pub fn write_vtk(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    fields: &[VertexField<'_>],
) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("write_vtk", path = %path.display()).entered();
    write_dataset(
        path,
        mesh.positions(),
        Cells::Triangles(mesh.triangles()),
        fields,
    )
}

/// Writes a tetrahedral mesh as legacy ASCII VTK `UNSTRUCTURED_GRID` (`VTK_TETRA`) with
/// per-vertex fields, atomically; like [`write_vtk`] otherwise.
pub fn write_vtk_tets(
    path: impl AsRef<Path>,
    mesh: &TetMesh,
    fields: &[VertexField<'_>],
) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::debug_span!("write_vtk_tets", path = %path.display()).entered();
    write_dataset(path, mesh.positions(), Cells::Tets(mesh.tets()), fields)
}

fn write_dataset(
    path: &Path,
    positions: &[Vec3],
    cells: Cells<'_>,
    fields: &[VertexField<'_>],
) -> Result<(), MeshIoError> {
    for f in fields {
        if f.name.is_empty() || f.name.chars().any(char::is_whitespace) {
            return Err(MeshIoError::FieldName {
                path: path.to_path_buf(),
                field: f.name.to_string(),
            });
        }
        if f.values.len() != positions.len() {
            return Err(MeshIoError::FieldLength {
                path: path.to_path_buf(),
                field: f.name.to_string(),
                len: f.values.len(),
                expected: positions.len(),
            });
        }
    }
    let out_of_range = |element, index, vertex| MeshIoError::IndexOutOfRange {
        path: path.to_path_buf(),
        element,
        index,
        vertex,
        vertex_count: positions.len(),
    };
    let n = positions.len();
    match cells {
        Cells::Triangles(c) => {
            check_cells(c, n).map_err(|(i, v)| out_of_range("triangle", i, v))?
        }
        Cells::Tets(c) => check_cells(c, n).map_err(|(i, v)| out_of_range("tetrahedron", i, v))?,
    }
    write_atomic(path, |w| {
        let (title, dataset) = match cells {
            Cells::Triangles(_) => ("surface", "POLYDATA"),
            Cells::Tets(_) => ("tetrahedra", "UNSTRUCTURED_GRID"),
        };
        write!(
            w,
            "# vtk DataFile Version 3.0\ntissue-meshio {title}\nASCII\nDATASET {dataset}\nPOINTS {n} float\n"
        )?;
        let mut line = String::with_capacity(64);
        for p in positions {
            line.clear();
            let _ = writeln!(line, "{} {} {}", F(p.x), F(p.y), F(p.z));
            w.write_all(line.as_bytes())?;
        }
        match cells {
            Cells::Triangles(tris) => {
                writeln!(w, "POLYGONS {} {}", tris.len(), tris.len() * 4)?;
                for [a, b, c] in tris {
                    writeln!(w, "3 {a} {b} {c}")?;
                }
            }
            Cells::Tets(tets) => {
                writeln!(w, "CELLS {} {}", tets.len(), tets.len() * 5)?;
                for [a, b, c, d] in tets {
                    writeln!(w, "4 {a} {b} {c} {d}")?;
                }
                writeln!(w, "CELL_TYPES {}", tets.len())?;
                for _ in tets {
                    w.write_all(b"10\n")?;
                }
            }
        }
        if !fields.is_empty() {
            writeln!(w, "POINT_DATA {n}")?;
        }
        for f in fields {
            match f.values {
                FieldValues::Scalars(v) => {
                    writeln!(w, "SCALARS {} float 1\nLOOKUP_TABLE default", f.name)?;
                    for x in v {
                        writeln!(w, "{}", F(*x))?;
                    }
                }
                FieldValues::Vectors(v) => {
                    writeln!(w, "VECTORS {} float", f.name)?;
                    for p in v {
                        writeln!(w, "{} {} {}", F(p.x), F(p.y), F(p.z))?;
                    }
                }
            }
        }
        Ok(())
    })
}

/// The first (cell, vertex) whose vertex index is out of range.
fn check_cells<const K: usize>(cells: &[[u32; K]], n: usize) -> Result<(), (usize, u32)> {
    for (i, c) in cells.iter().enumerate() {
        if let Some(&v) = c.iter().find(|&&v| v as usize >= n) {
            return Err((i, v));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const SURFACE: &str = "# vtk DataFile Version 3.0\nsome title\nASCII\nDATASET POLYDATA\nPOINTS 4 double\n\
        0 0 0 1 0 0\n1 1 0\n0 1 0\nPOLYGONS 1 5\n4 0 1 2 3\nPOINT_DATA 4\nSCALARS s float\n1 2 3 4\n\
        VECTORS v float\n1 0 0 0 1 0 0 0 1 1 1 1\n";

    #[test]
    fn reads_free_layout_quads_and_fields() {
        let d = parse_vtk(SURFACE.as_bytes(), "s.vtk").unwrap();
        let VtkMesh::Surface(s) = &d.mesh else {
            panic!("{d:?}")
        };
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(d.fields.len(), 2);
        assert_eq!(
            d.fields[0].values,
            PointValues::Scalars(vec![1.0, 2.0, 3.0, 4.0])
        );
        assert_eq!(d.fields[1].name, "v");
    }

    #[test]
    fn errors_name_the_line() {
        for (from, to, line) in [
            ("4 0 1 2 3", "4 0 1 2 9", 10),
            ("POLYGONS 1 5", "POLYGONS 1 6", 10),
            ("1 1 0\n", "1 x 0\n", 7),
            ("POINT_DATA 4", "POINT_DATA 5", 11),
            ("ASCII", "BINARY", 3),
            ("VECTORS v float", "TENSORS v float", 14),
        ] {
            let bad = SURFACE.replace(from, to);
            let e = parse_vtk(bad.as_bytes(), "s.vtk").unwrap_err();
            assert!(
                matches!(e, MeshIoError::Parse { line: l, .. } if l == line),
                "{from}: {e}"
            );
        }
    }

    #[test]
    fn unstructured_grid_of_tets() {
        let text =
            "# vtk DataFile Version 2.0\n\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n\
            0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n";
        let d = parse_vtk(text.as_bytes(), "t.vtk").unwrap();
        assert_eq!(
            d.mesh,
            VtkMesh::Tets(TetData {
                positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
                tets: vec![[0, 1, 2, 3]],
            })
        );
        let bad = text.replace("\n10\n", "\n12\n");
        let e = parse_vtk(bad.as_bytes(), "t.vtk").unwrap_err();
        assert!(matches!(e, MeshIoError::Parse { line: 10, .. }), "{e}");
    }
}
