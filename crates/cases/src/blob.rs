//! Content hashes and the binary encodings of what the library stores as blobs: a patient's
//! file-unit mesh and a single run's result on the patient.
//!
//! Both are little-endian, with an 8-byte magic, a `u32` format version and the counts, so a
//! blob of another kind, version or length is refused as [`CaseError::Damaged`] rather than
//! misread.

use glam::Vec3;
use sha2::{Digest, Sha256};
use tissue_mesh::TriMesh;
use tissue_planner::PatientResult;

use crate::CaseError;

/// A mesh blob's magic.
pub(crate) const MESH_MAGIC: &[u8; 8] = b"TSCMESH\0";
/// A result blob's magic.
pub(crate) const RESULT_MAGIC: &[u8; 8] = b"TSCRSLT\0";
/// The version of both encodings.
pub(crate) const BLOB_VERSION: u32 = 1;

/// SHA-256 of `bytes` in lowercase hex.
pub(crate) fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lowercase hex of `bytes`.
pub(crate) fn hex(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let mut s = String::with_capacity(bytes.len() * 2);
    for &b in bytes {
        s.push(char::from(DIGITS[usize::from(b >> 4)]));
        s.push(char::from(DIGITS[usize::from(b & 15)]));
    }
    s
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_vec3s(out: &mut Vec<u8>, points: &[Vec3]) {
    out.reserve(points.len() * 12);
    for p in points {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
}

fn put_f32s(out: &mut Vec<u8>, values: &[f32]) {
    out.reserve(values.len() * 4);
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

fn count(n: usize, what: &str) -> Result<u32, CaseError> {
    u32::try_from(n).map_err(|_| CaseError::Damaged {
        what: what.to_owned(),
        message: format!("{n} elements do not fit the blob format (at most 2^32 - 1)"),
    })
}

/// A patient's mesh as a blob: magic, version, vertex and triangle counts, positions (f32×3)
/// and triangles (u32×3).
pub(crate) fn encode_mesh(mesh: &TriMesh) -> Result<Vec<u8>, CaseError> {
    let nv = count(mesh.positions().len(), "patient mesh")?;
    let nt = count(mesh.triangles().len(), "patient mesh")?;
    let mut out =
        Vec::with_capacity(20 + mesh.positions().len() * 12 + mesh.triangles().len() * 12);
    out.extend_from_slice(MESH_MAGIC);
    put_u32(&mut out, BLOB_VERSION);
    put_u32(&mut out, nv);
    put_u32(&mut out, nt);
    put_vec3s(&mut out, mesh.positions());
    for t in mesh.triangles() {
        for &i in t {
            put_u32(&mut out, i);
        }
    }
    Ok(out)
}

/// A reader over a blob that names the record in its errors.
struct Reader<'a> {
    bytes: &'a [u8],
    what: &'a str,
}

impl<'a> Reader<'a> {
    fn damaged(&self, message: String) -> CaseError {
        CaseError::Damaged {
            what: self.what.to_owned(),
            message,
        }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], CaseError> {
        if self.bytes.len() < n {
            return Err(self.damaged(format!(
                "the blob ends early ({} bytes left, {n} needed)",
                self.bytes.len()
            )));
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(head)
    }

    fn u32(&mut self) -> Result<u32, CaseError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn header(&mut self, magic: &[u8; 8]) -> Result<(), CaseError> {
        let m = self.take(8)?;
        if m != magic {
            return Err(self.damaged("the blob is not of this kind (wrong magic)".to_owned()));
        }
        let version = self.u32()?;
        if version != BLOB_VERSION {
            return Err(self.damaged(format!(
                "blob format version {version}, this program reads {BLOB_VERSION}: update tissue"
            )));
        }
        Ok(())
    }

    /// Checks that exactly `n` bytes are left (the counts and the length agree).
    fn expect_len(&self, n: u64) -> Result<(), CaseError> {
        if self.bytes.len() as u64 != n {
            return Err(self.damaged(format!(
                "{} bytes after the header, the counts need {n}",
                self.bytes.len()
            )));
        }
        Ok(())
    }

    fn f32s(&mut self, n: usize) -> Result<Vec<f32>, CaseError> {
        let b = self.take(n * 4)?;
        Ok(b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    fn vec3s(&mut self, n: usize) -> Result<Vec<Vec3>, CaseError> {
        let b = self.take(n * 12)?;
        Ok(b.chunks_exact(12)
            .map(|c| {
                let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                Vec3::new(f(0), f(4), f(8))
            })
            .collect())
    }
}

/// Decodes [`encode_mesh`]'s blob into a validated mesh.
pub(crate) fn decode_mesh(bytes: &[u8], what: &str) -> Result<TriMesh, CaseError> {
    let mut r = Reader { bytes, what };
    r.header(MESH_MAGIC)?;
    let nv = r.u32()? as usize;
    let nt = r.u32()? as usize;
    r.expect_len(nv as u64 * 12 + nt as u64 * 12)?;
    let positions = r.vec3s(nv)?;
    let raw = r.take(nt * 12)?;
    let triangles: Vec<[u32; 3]> = raw
        .chunks_exact(12)
        .map(|c| {
            let u = |i: usize| u32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            [u(0), u(4), u(8)]
        })
        .collect();
    TriMesh::new(positions, triangles).map_err(|e| CaseError::Damaged {
        what: what.to_owned(),
        message: format!("the stored mesh is not a valid surface: {e}"),
    })
}

/// A single run's result as a blob: magic, version, vertex count, the positions after (scan
/// unit, f32×3), then `displacement`, `stretch` and `in_region` (f32 each).
pub(crate) fn encode_result(result: &PatientResult) -> Result<Vec<u8>, CaseError> {
    let n = result.after.positions().len();
    let nv = count(n, "plan result")?;
    for (name, len) in [
        ("displacement", result.displacement.len()),
        ("stretch", result.stretch.len()),
        ("in_region", result.in_region.len()),
    ] {
        if len != n {
            return Err(CaseError::Invalid {
                field: "result",
                message: format!(
                    "the result's {name} has {len} values for {n} vertices: the plan cannot be stored"
                ),
            });
        }
    }
    let mut out = Vec::with_capacity(16 + n * 24);
    out.extend_from_slice(RESULT_MAGIC);
    put_u32(&mut out, BLOB_VERSION);
    put_u32(&mut out, nv);
    put_vec3s(&mut out, result.after.positions());
    put_f32s(&mut out, &result.displacement);
    put_f32s(&mut out, &result.stretch);
    put_f32s(&mut out, &result.in_region);
    Ok(out)
}

/// A decoded result blob.
#[derive(Debug)]
pub(crate) struct ResultData {
    pub after: Vec<Vec3>,
    pub displacement: Vec<f32>,
    pub stretch: Vec<f32>,
    pub in_region: Vec<f32>,
}

/// Decodes [`encode_result`]'s blob, checking it holds `vertices` vertices.
pub(crate) fn decode_result(
    bytes: &[u8],
    vertices: usize,
    what: &str,
) -> Result<ResultData, CaseError> {
    let mut r = Reader { bytes, what };
    r.header(RESULT_MAGIC)?;
    let n = r.u32()? as usize;
    if n != vertices {
        return Err(r.damaged(format!(
            "the result has {n} vertices, the patient's mesh {vertices}"
        )));
    }
    r.expect_len(n as u64 * 24)?;
    Ok(ResultData {
        after: r.vec3s(n)?,
        displacement: r.f32s(n)?,
        stretch: r.f32s(n)?,
        in_region: r.f32s(n)?,
    })
}

/// The result on the patient rebuilt from its blob: `before` is the patient's file mesh,
/// `after` the stored positions, `after_cm` the positions after scaled to cm (`cm_per_unit`),
/// `scan` none.
pub(crate) fn rebuild_result(
    before: &TriMesh,
    data: ResultData,
    cm_per_unit: f32,
    what: &str,
) -> Result<PatientResult, CaseError> {
    let damaged = |e: tissue_mesh::MeshError| CaseError::Damaged {
        what: what.to_owned(),
        message: format!("the stored result does not fit the patient's mesh: {e}"),
    };
    let after_cm = if cm_per_unit == 1.0 {
        before.with_positions(data.after.clone()).map_err(damaged)?
    } else {
        // A vertex that did not move has the rest position in cm (file × scale) and a moved
        // one its position after × scale: the same product either way.
        let cm = data.after.iter().map(|&p| p * cm_per_unit).collect();
        before.with_positions(cm).map_err(damaged)?
    };
    let after = before.with_positions(data.after).map_err(damaged)?;
    Ok(PatientResult {
        before: before.clone(),
        after,
        after_cm,
        displacement: data.displacement,
        stretch: data.stretch,
        in_region: data.in_region,
        scan: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_and_sha256_match_the_known_digest() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn a_mesh_round_trips_and_a_cut_blob_is_refused() {
        let mesh = tissue_mesh::grid(5, 2.0).unwrap();
        let blob = encode_mesh(&mesh).unwrap();
        let back = decode_mesh(&blob, "m").unwrap();
        assert_eq!(back.positions(), mesh.positions());
        assert_eq!(back.triangles(), mesh.triangles());
        assert!(matches!(
            decode_mesh(&blob[..blob.len() - 1], "m"),
            Err(CaseError::Damaged { .. })
        ));
        let mut wrong = blob.clone();
        wrong[0] ^= 1;
        assert!(matches!(
            decode_mesh(&wrong, "m"),
            Err(CaseError::Damaged { .. })
        ));
        assert!(matches!(
            decode_result(&blob, 25, "m"),
            Err(CaseError::Damaged { .. })
        ));
    }
}
