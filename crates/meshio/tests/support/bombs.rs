//! Hostile and honest `.vtu` files built in the test, shared by the `it` binary (which checks
//! the errors) and `peak_memory` (which measures the memory that reading them takes).
//!
//! The bombs are zlib blocks of zeros as `vtkZLibDataCompressor` writes them: 1 MiB of zeros
//! compresses to about 1 KiB, within the reader's 1100:1 check per block, so 400 blocks make a
//! file of about 400 KiB whose arrays claim 400 MiB.
#![allow(clippy::unwrap_used)]

use std::io::Write;

use base64::Engine as _;
use flate2::write::ZlibEncoder;
use flate2::Compression;

/// Blocks of a bomb array, and their size: 400 MiB of zeros.
pub const BOMB_BLOCKS: usize = 400;
/// One block of a bomb: 1 MiB.
pub const BOMB_BLOCK: usize = 1 << 20;

/// How a file stores its binary arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// `<AppendedData encoding="raw">`.
    AppendedRaw,
    /// `<AppendedData encoding="base64">`: each array's header and data base64-encoded
    /// separately; offsets count characters.
    AppendedBase64,
    /// Inline `format="binary"`: the header and the data base64-encoded separately, as VTK and
    /// meshio write them.
    InlineBase64,
}

/// One binary `DataArray`: where it goes, its attributes, and its encoded header and data.
pub struct Array {
    /// `Points`, `Cells` or `PointData`.
    pub parent: &'static str,
    /// `Name`.
    pub name: &'static str,
    /// `type`, e.g. `Float64`.
    pub ty: &'static str,
    /// `NumberOfComponents`.
    pub components: usize,
    /// The byte-count header (for compressed data, the block table).
    pub header: Vec<u8>,
    /// The data after the header, as stored.
    pub data: Vec<u8>,
}

fn int(v: u64, header64: bool) -> Vec<u8> {
    if header64 {
        v.to_le_bytes().to_vec()
    } else {
        u32::try_from(v).unwrap().to_le_bytes().to_vec()
    }
}

fn compress(data: &[u8]) -> Vec<u8> {
    let mut e = ZlibEncoder::new(Vec::new(), Compression::best());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

/// `blocks` blocks of `block` zero bytes, compressed: the header and the compressed data. Only
/// one block is ever compressed (they are all the same), so building a bomb costs little.
pub fn zlib_zeros(blocks: usize, block: usize, header64: bool) -> (Vec<u8>, Vec<u8>) {
    let one = compress(&vec![0u8; block]);
    let mut header = int(blocks as u64, header64);
    header.extend(int(block as u64, header64));
    header.extend(int(block as u64, header64)); // the last block is full
    for _ in 0..blocks {
        header.extend(int(one.len() as u64, header64));
    }
    (header, one.repeat(blocks))
}

/// `data` compressed in blocks of `block` bytes, as `vtkZLibDataCompressor` writes it.
pub fn zlib(data: &[u8], block: usize, header64: bool) -> (Vec<u8>, Vec<u8>) {
    let chunks: Vec<&[u8]> = data.chunks(block).collect();
    let last = chunks.last().map_or(0, |c| c.len());
    let mut header = int(chunks.len() as u64, header64);
    header.extend(int(block as u64, header64));
    // VTK writes 0 when the last block is full, meshio its size; the reader takes both.
    header.extend(int(if last == block { 0 } else { last as u64 }, header64));
    let mut payload = Vec::new();
    for c in chunks {
        let z = compress(c);
        header.extend(int(z.len() as u64, header64));
        payload.extend(z);
    }
    (header, payload)
}

/// Uncompressed data: its byte-count header and the bytes.
pub fn plain(data: &[u8], header64: bool) -> (Vec<u8>, Vec<u8>) {
    (int(data.len() as u64, header64), data.to_vec())
}

impl Array {
    pub fn new(
        parent: &'static str,
        name: &'static str,
        ty: &'static str,
        components: usize,
        (header, data): (Vec<u8>, Vec<u8>),
    ) -> Self {
        Array {
            parent,
            name,
            ty,
            components,
            header,
            data,
        }
    }
}

/// A `.vtu` file with one piece holding `arrays`.
pub fn vtu(
    header64: bool,
    compressed: bool,
    encoding: Encoding,
    points: u64,
    cells: u64,
    arrays: &[Array],
) -> Vec<u8> {
    let b64 = base64::engine::general_purpose::STANDARD;
    let mut appended = Vec::new();
    let mut xml = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"{}\"{}>\n<UnstructuredGrid>\n\
         <Piece NumberOfPoints=\"{points}\" NumberOfCells=\"{cells}\">\n",
        if header64 { "UInt64" } else { "UInt32" },
        if compressed {
            " compressor=\"vtkZLibDataCompressor\""
        } else {
            ""
        }
    );
    for parent in ["Points", "Cells", "PointData"] {
        xml += &format!("<{parent}>\n");
        for a in arrays.iter().filter(|a| a.parent == parent) {
            let head = format!(
                "<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"",
                a.ty, a.name, a.components
            );
            match encoding {
                Encoding::AppendedRaw => {
                    xml += &format!(
                        "{head} format=\"appended\" offset=\"{}\"/>\n",
                        appended.len()
                    );
                    appended.extend_from_slice(&a.header);
                    appended.extend_from_slice(&a.data);
                }
                Encoding::AppendedBase64 => {
                    xml += &format!(
                        "{head} format=\"appended\" offset=\"{}\"/>\n",
                        appended.len()
                    );
                    appended.extend(b64.encode(&a.header).bytes());
                    appended.extend(b64.encode(&a.data).bytes());
                }
                Encoding::InlineBase64 => {
                    xml += &format!(
                        "{head} format=\"binary\">\n{}{}\n</DataArray>\n",
                        b64.encode(&a.header),
                        b64.encode(&a.data)
                    );
                }
            }
        }
        xml += &format!("</{parent}>\n");
    }
    xml += "</Piece>\n</UnstructuredGrid>\n";
    let mut bytes = xml.into_bytes();
    if encoding != Encoding::InlineBase64 {
        let name = if encoding == Encoding::AppendedRaw {
            "raw"
        } else {
            "base64"
        };
        bytes.extend_from_slice(format!("<AppendedData encoding=\"{name}\">\n_").as_bytes());
        bytes.extend_from_slice(&appended);
        bytes.extend_from_slice(b"\n</AppendedData>\n");
    }
    bytes.extend_from_slice(b"</VTKFile>\n");
    bytes
}

/// The honest arrays of one tetrahedron (points `0..4`), compressed or not.
fn one_tet(header64: bool, compressed: bool, skip: &str) -> Vec<Array> {
    let pack = |data: &[u8]| {
        if compressed {
            zlib(data, 32 << 10, header64)
        } else {
            plain(data, header64)
        }
    };
    let points: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let conn: Vec<u8> = [0i64, 1, 2, 3]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    [
        Array::new("Points", "Points", "Float32", 3, pack(&points)),
        Array::new("Cells", "connectivity", "Int64", 1, pack(&conn)),
        Array::new("Cells", "offsets", "Int64", 1, pack(&4i64.to_le_bytes())),
        Array::new("Cells", "types", "UInt8", 1, pack(&[10])),
    ]
    .into_iter()
    .filter(|a| a.name != skip)
    .collect()
}

/// A bomb and what reading it must give.
pub struct Bomb {
    /// What it is, for assertion messages.
    pub name: String,
    /// The file.
    pub bytes: Vec<u8>,
    /// `None`: it must read (one tetrahedron); `Some(parts)`: it must be refused with an
    /// error whose message contains every part.
    pub refused_with: Option<Vec<String>>,
}

/// Every bomb, each about 400 KiB, in every encoding and header type.
pub fn bombs() -> Vec<Bomb> {
    let mut out = Vec::new();
    let corrupt = "the file is corrupt or not what it claims".to_string();
    for header64 in [false, true] {
        for encoding in [
            Encoding::AppendedRaw,
            Encoding::AppendedBase64,
            Encoding::InlineBase64,
        ] {
            let tag = format!("{encoding:?} header64={header64}");
            let zeros = || zlib_zeros(BOMB_BLOCKS, BOMB_BLOCK, header64);
            // The probe's bomb: NumberOfPoints="4", but Points claims 400 MiB.
            let mut arrays = one_tet(header64, true, "Points");
            arrays.push(Array::new("Points", "Points", "Float32", 3, zeros()));
            out.push(Bomb {
                name: format!("Points, NumberOfPoints=4, {tag}"),
                bytes: vtu(header64, true, encoding, 4, 1, &arrays),
                refused_with: Some(vec![
                    "DataArray `Points`".into(),
                    "NumberOfPoints=\"4\" needs 12 values".into(),
                    corrupt.clone(),
                ]),
            });
            // The same with a NumberOfPoints that matches the 400 MiB: the file's
            // decoding budget refuses it.
            let points = (BOMB_BLOCKS * BOMB_BLOCK / 12) as u64;
            let mut arrays = one_tet(header64, true, "Points");
            arrays.push(Array::new("Points", "Points", "Float32", 3, zeros()));
            out.push(Bomb {
                name: format!("Points, NumberOfPoints matching, {tag}"),
                bytes: vtu(header64, true, encoding, points, 1, &arrays),
                refused_with: Some(vec![
                    "DataArray `Points`".into(),
                    "64 times its size".into(),
                    corrupt.clone(),
                ]),
            });
            // Each cell array in turn.
            for (name, ty, why) in [
                ("connectivity", "Int64", "the offsets need 4 values"),
                ("offsets", "Int64", "NumberOfCells=\"1\" needs 1 value"),
                ("types", "UInt8", "NumberOfCells=\"1\" needs 1 value"),
            ] {
                let mut arrays = one_tet(header64, true, name);
                arrays.push(Array::new("Cells", name, ty, 1, zeros()));
                out.push(Bomb {
                    name: format!("{name}, {tag}"),
                    bytes: vtu(header64, true, encoding, 4, 1, &arrays),
                    refused_with: Some(vec![
                        format!("DataArray `{name}`"),
                        why.into(),
                        corrupt.clone(),
                    ]),
                });
            }
            // Point data the reader does not use: never decompressed, so the file reads.
            let mut arrays = one_tet(header64, true, "");
            arrays.push(Array::new("PointData", "junk", "Float64", 1, zeros()));
            out.push(Bomb {
                name: format!("unused PointData, {tag}"),
                bytes: vtu(header64, true, encoding, 4, 1, &arrays),
                refused_with: None,
            });
        }
    }
    // Uncompressed: a byte count that claims 400 MiB over 48 bytes of data.
    let mut arrays = one_tet(false, false, "Points");
    let mut lie = plain(&[0; 48], false);
    lie.0 = ((BOMB_BLOCKS * BOMB_BLOCK) as u32).to_le_bytes().to_vec();
    arrays.push(Array::new("Points", "Points", "Float32", 3, lie));
    out.push(Bomb {
        name: "uncompressed Points with a lying byte count".into(),
        bytes: vtu(false, false, Encoding::AppendedRaw, 4, 1, &arrays),
        refused_with: Some(vec![
            "DataArray `Points`".into(),
            "NumberOfPoints=\"4\" needs 12 values".into(),
        ]),
    });
    out
}

/// An honest mesh: the unit cubes of an `n`³ grid, six tetrahedra each. Positions as `f64`
/// (exact in `f32`) and tetrahedra as corner indices.
pub fn tet_grid(n: usize) -> (Vec<[f64; 3]>, Vec<[i64; 4]>) {
    let idx = |i: usize, j: usize, k: usize| (i + (n + 1) * (j + (n + 1) * k)) as i64;
    let mut points = Vec::new();
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                points.push([i as f64 * 0.5, j as f64 * 0.25, k as f64]);
            }
        }
    }
    let mut tets = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let v: Vec<i64> = (0..8)
                    .map(|c| idx(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)))
                    .collect();
                for t in [
                    [0, 1, 3, 7],
                    [0, 3, 2, 7],
                    [0, 2, 6, 7],
                    [0, 6, 4, 7],
                    [0, 4, 5, 7],
                    [0, 5, 1, 7],
                ] {
                    tets.push(t.map(|c| v[c]));
                }
            }
        }
    }
    (points, tets)
}

/// The `n`³ grid as a zlib-compressed `.vtu`, with a point data array that the reader skips.
/// Blocks of 32 KiB (VTK's default) with a partial last block, except `types`, whose blocks
/// divide it, so that its last block is full (written as 0, as VTK does).
pub fn grid_vtu(n: usize, header64: bool, encoding: Encoding) -> Vec<u8> {
    let (points, tets) = tet_grid(n);
    let le = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    let flat: Vec<f64> = points.iter().flatten().copied().collect();
    let conn: Vec<u8> = tets
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let offsets: Vec<u8> = (1..=tets.len() as i64)
        .flat_map(|c| (4 * c).to_le_bytes())
        .collect();
    let types = vec![10u8; tets.len()];
    let field: Vec<f64> = (0..points.len()).map(|i| i as f64).collect();
    let block = 32 << 10;
    let arrays = [
        Array::new(
            "Points",
            "Points",
            "Float64",
            3,
            zlib(&le(&flat), block, header64),
        ),
        Array::new(
            "Cells",
            "connectivity",
            "Int64",
            1,
            zlib(&conn, block, header64),
        ),
        Array::new(
            "Cells",
            "offsets",
            "Int64",
            1,
            zlib(&offsets, block, header64),
        ),
        Array::new(
            "Cells",
            "types",
            "UInt8",
            1,
            zlib(&types, tets.len() / 3, header64),
        ),
        Array::new(
            "PointData",
            "id",
            "Float64",
            1,
            zlib(&le(&field), block, header64),
        ),
    ];
    vtu(
        header64,
        true,
        encoding,
        points.len() as u64,
        tets.len() as u64,
        &arrays,
    )
}
