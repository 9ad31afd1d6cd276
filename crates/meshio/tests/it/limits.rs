//! Hostile inputs: every reader bounds the work a file can cause (the studio's uploads reach them from the network). The
//! `.vtu` bombs come from `support/bombs.rs`; the memory they cost is measured by the
//! `peak_memory` binary, their errors here.

// Test code: a failed unwrap is a failed test.
#![allow(clippy::unwrap_used)]

use std::fmt::Write as _;

use tissue_meshio::{parse_msh, parse_vtu, MeshIoError, MAX_DEPTH};

use crate::bombs::{self, Encoding};

#[test]
fn vtu_bombs_are_refused_naming_the_array() {
    let all = bombs::bombs();
    assert_eq!(all.len(), 2 * 3 * 6 + 1);
    for bomb in all {
        let result = parse_vtu(&bomb.bytes, "bomb.vtu");
        match (&bomb.refused_with, result) {
            (None, Ok(d)) => assert_eq!(d.tets, vec![[0, 1, 2, 3]], "{}", bomb.name),
            (Some(parts), Err(e)) => {
                assert!(matches!(e, MeshIoError::Parse { .. }), "{}: {e}", bomb.name);
                let msg = e.to_string();
                assert!(msg.starts_with("bomb.vtu, line "), "{}: {msg}", bomb.name);
                for part in parts {
                    assert!(
                        msg.contains(part.as_str()),
                        "{}: {msg}\nlacks {part}",
                        bomb.name
                    );
                }
            }
            (want, got) => panic!("{}: expected {want:?}, got {got:?}", bomb.name),
        }
    }
}

#[test]
fn a_legitimate_compressed_vtu_still_reads() {
    let n = 12;
    let (points, tets) = bombs::tet_grid(n);
    for header64 in [false, true] {
        for encoding in [
            Encoding::AppendedRaw,
            Encoding::AppendedBase64,
            Encoding::InlineBase64,
        ] {
            let bytes = bombs::grid_vtu(n, header64, encoding);
            let d = parse_vtu(&bytes, "grid.vtu")
                .unwrap_or_else(|e| panic!("{encoding:?} {header64}: {e}"));
            assert_eq!(d.positions.len(), points.len());
            for (p, q) in d.positions.iter().zip(&points) {
                assert_eq!(p.to_array(), q.map(|x| x as f32));
            }
            let want: Vec<[u32; 4]> = tets.iter().map(|t| t.map(|i| i as u32)).collect();
            assert_eq!(d.tets, want, "{encoding:?} {header64}");
        }
    }
}

#[test]
fn vtu_piece_counts_beyond_the_absolute_cap_are_refused() {
    let (points, tets) = bombs::tet_grid(1);
    let bytes = bombs::grid_vtu(1, false, Encoding::AppendedRaw);
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let from = format!("NumberOfPoints=\"{}\"", points.len());
    let e = parse_vtu(
        text.replacen(&from, "NumberOfPoints=\"1000000000000\"", 1)
            .as_bytes(),
        "big.vtu",
    )
    .unwrap_err();
    assert!(matches!(e, MeshIoError::Parse { line: 4, .. }), "{e}");
    assert!(
        e.to_string()
            .contains("NumberOfPoints=\"1000000000000\" is more than"),
        "{e}"
    );
    let from = format!("NumberOfCells=\"{}\"", tets.len());
    let e = parse_vtu(
        text.replacen(&from, "NumberOfCells=\"18446744073709551615\"", 1)
            .as_bytes(),
        "big.vtu",
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("NumberOfCells=\"18446744073709551615\" is more than"),
        "{e}"
    );
}

/// A file whose cells (or elements) each have a type of their own: counting them for the "no
/// tetrahedra" message used to take time quadratic in their number and write every type into
/// the message.
#[test]
fn many_distinct_cell_types_cost_linear_time_and_a_short_message() {
    let cells = 200_000usize;
    // VTU: cells without points (all offsets 0), Int64 types 1000, 1001, ...
    let offsets = vec![0u8; 8 * cells];
    let types: Vec<u8> = (0..cells as i64)
        .flat_map(|t| (1000 + t).to_le_bytes())
        .collect();
    let arrays = [
        bombs::Array::new(
            "Cells",
            "connectivity",
            "Int64",
            1,
            bombs::plain(&[], false),
        ),
        bombs::Array::new(
            "Cells",
            "offsets",
            "Int64",
            1,
            bombs::plain(&offsets, false),
        ),
        bombs::Array::new("Cells", "types", "Int64", 1, bombs::plain(&types, false)),
    ];
    let bytes = bombs::vtu(
        false,
        false,
        Encoding::AppendedRaw,
        0,
        cells as u64,
        &arrays,
    );
    let e = parse_vtu(&bytes, "types.vtu").unwrap_err().to_string();
    assert!(e.contains("no tetrahedra"), "{e}");
    assert!(
        e.contains(&format!("{} cells of other types", cells - 16)),
        "{e}"
    );
    assert!(e.len() < 1500, "{} bytes: {}", e.len(), &e[..1500]);

    // MSH 2: `tag type 0` lines, types 1000, 1001, ...
    let mut text =
        String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n");
    writeln!(text, "$Elements\n{cells}").unwrap();
    for c in 0..cells {
        writeln!(text, "{} {} 0", c + 1, 1000 + c).unwrap();
    }
    text += "$EndElements\n";
    let e = parse_msh(text.as_bytes(), "types.msh")
        .unwrap_err()
        .to_string();
    assert!(e.contains("no 4-node tetrahedra"), "{e}");
    assert!(
        e.contains(&format!("{} elements of other types", cells - 16)),
        "{e}"
    );
    assert!(e.len() < 1500, "{} bytes: {}", e.len(), &e[..1500]);
}

#[test]
fn vtu_nesting_is_bounded() {
    let mut text = String::from("<VTKFile type=\"UnstructuredGrid\">\n");
    for _ in 0..10 * MAX_DEPTH {
        text += "<a>";
    }
    let e = parse_vtu(text.as_bytes(), "deep.vtu").unwrap_err();
    assert!(matches!(e, MeshIoError::Parse { line: 2, .. }), "{e}");
    assert!(
        e.to_string()
            .contains(&format!("more than {MAX_DEPTH} deep")),
        "{e}"
    );
}
