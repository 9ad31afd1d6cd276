//! What reading a hostile file costs in memory: a counting global allocator records the peak of
//! live heap bytes while a reader runs, and each reader must stay far below what the file
//! claims. The bombs are in `support/bombs.rs` (the `it` binary checks their errors).
//!
//! A binary of its own, because the global allocator counts every allocation of the process;
//! the tests take a lock so that only one of them measures at a time.
//!
//! The one place in the crate with `unsafe`: the counting allocator must implement the `unsafe`
//! trait `GlobalAlloc`. It only forwards to `System`.
#![allow(unsafe_code, clippy::unwrap_used, clippy::print_stderr)]

#[path = "support/bombs.rs"]
mod bombs;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Counts live heap bytes and their peak, on every thread.
struct Counting;
static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(bytes: usize) {
    let now = LIVE.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        grew(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        grew(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // Counted as if the old and the new block were both live for a moment, as they are
        // when the system allocator has to move the data.
        grew(new_size);
        // SAFETY: same contract as the caller's.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        p
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// One test at a time: each holds this from its start, also while it builds its inputs, since
/// the counters see the allocations of every thread.
static MEASURING: Mutex<()> = Mutex::new(());

fn alone() -> MutexGuard<'static, ()> {
    MEASURING.lock().unwrap_or_else(|e| e.into_inner())
}

/// The peak of live heap bytes while `f` runs, above what was live when it started.
fn peak_of<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let out = f();
    (out, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

const MIB: usize = 1 << 20;
/// What a read of a few MiB may take on a busy machine; the quadratic cases took minutes.
const SLOW: Duration = Duration::from_secs(5);
/// What any of these reads may take: a few times the largest input, nowhere near the hundreds
/// of MiB the bombs claim.
const LIMIT: usize = 16 * MIB;

#[test]
fn vtu_bombs_are_refused_before_they_are_decompressed() {
    let _alone = alone();
    let mut report = Vec::new();
    for bomb in bombs::bombs() {
        let (result, peak) = peak_of(|| tissue_meshio::parse_vtu(&bomb.bytes, "bomb.vtu"));
        report.push(format!(
            "{:>8} KiB file, peak {:>9} KiB: {} ({})",
            bomb.bytes.len() >> 10,
            peak >> 10,
            bomb.name,
            match &result {
                Ok(_) => "read".to_string(),
                Err(e) => e.to_string(),
            }
        ));
        match (&bomb.refused_with, &result) {
            (None, Ok(d)) => assert_eq!(d.tets.len(), 1, "{}", bomb.name),
            (Some(_), Err(_)) => {}
            _ => panic!("{}: {:?}", bomb.name, result.map(|d| d.tets.len())),
        }
        assert!(
            peak < LIMIT,
            "{}: peak {} KiB\n{}",
            bomb.name,
            peak >> 10,
            report.join("\n")
        );
    }
    // Shown with --nocapture: the measurements behind the report of issue 29.
    eprintln!("{}", report.join("\n"));
}

/// Reads `input` with `read` and checks that the peak stays below `limit` bytes; returns what
/// `read` gave, for the caller's checks, and prints the peak.
fn bounded<T>(what: &str, input: &[u8], limit: usize, read: impl FnOnce(&[u8]) -> T) -> T {
    let (out, peak) = peak_of(|| read(input));
    eprintln!(
        "{what}: {} KiB input, peak {} KiB",
        input.len() >> 10,
        peak >> 10
    );
    assert!(
        peak < limit,
        "{what}: peak {} KiB, limit {} KiB",
        peak >> 10,
        limit >> 10
    );
    out
}

#[test]
fn ascii_ply_lines_are_read_one_at_a_time() {
    let _alone = alone();
    // 8 MiB of empty lines, each an element without properties: a list of all lines would
    // take 16 bytes each, 128 MiB.
    let lines = 8 * MIB;
    let mut bytes = format!(
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n\
         property float z\nelement blank {lines}\nend_header\n"
    )
    .into_bytes();
    bytes.resize(bytes.len() + lines, b'\n');
    let result = bounded("PLY, 8 Mi empty lines", &bytes, MIB, |b| {
        tissue_meshio::parse_ply(b, "lines.ply")
    });
    assert!(result.unwrap().positions.is_empty());
}

#[test]
fn ply_vertex_capacity_is_what_the_body_can_hold() {
    let _alone = alone();
    // 8 Mi vertices declared, the body cut after 8 MiB. At 12 bytes a binary record (float
    // x y z) the body holds 0.7 Mi vertices, 8 MiB of `Vec3`; at the 3 bytes a vertex could
    // take at least (three `char`s), 32 MiB would be reserved.
    let declared = 8 * MIB;
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {declared}\nproperty float x\n\
         property float y\nproperty float z\nend_header\n"
    )
    .into_bytes();
    let body = 8 * MIB;
    bytes.resize(bytes.len() + body, 0);
    let result = bounded(
        "PLY binary, 8 Mi vertices declared, 8 MiB body",
        &bytes,
        body + MIB,
        |b| tissue_meshio::parse_ply(b, "cut.ply"),
    );
    assert!(result.unwrap_err().to_string().contains("truncated"));
}

#[test]
fn vtu_empty_pieces_cost_about_their_text() {
    let _alone = alone();
    // About 90,000 pieces in 4 MiB.
    let piece = "<Piece NumberOfPoints=\"0\" NumberOfCells=\"0\"/>\n";
    let mut text = String::from("<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>\n");
    while text.len() < 4 * MIB {
        text += piece;
    }
    text += "</UnstructuredGrid></VTKFile>\n";
    let start = Instant::now();
    let result = bounded(
        "VTU, 4 MiB of empty pieces",
        text.as_bytes(),
        3 * text.len(),
        |b| tissue_meshio::parse_vtu(b, "pieces.vtu"),
    );
    let e = result.unwrap_err().to_string();
    assert!(e.contains("no tetrahedra"), "{e}");
    // Finding each element's line by counting from the start took over a minute.
    assert!(start.elapsed() < SLOW, "{:?}", start.elapsed());
}

#[test]
fn vtu_attributes_cost_linear_time() {
    let _alone = alone();
    // 50,000 attributes, then 50,000 repeats of the last: quick-xml's duplicate check compares
    // each repeat with every name before it.
    let mut text = String::from("<VTKFile");
    for k in 0..50_000 {
        text += &format!(" a{k}=\"\"");
    }
    text += &" a49999=\"\"".repeat(50_000);
    text += " type=\"UnstructuredGrid\"><UnstructuredGrid/></VTKFile>";
    let start = Instant::now();
    let result = bounded("VTU, 100,000 attributes", text.as_bytes(), MIB, |b| {
        tissue_meshio::parse_vtu(b, "attributes.vtu")
    });
    assert!(result.unwrap_err().to_string().contains("no <Piece>"));
    assert!(start.elapsed() < SLOW, "{:?}", start.elapsed());
}

#[test]
fn vtu_deep_nesting_is_refused_early() {
    let _alone = alone();
    let mut text = String::from("<VTKFile type=\"UnstructuredGrid\">\n");
    while text.len() < 4 * MIB {
        text += "<a>";
    }
    let result = bounded("VTU, 4 MiB of nested elements", text.as_bytes(), MIB, |b| {
        tissue_meshio::parse_vtu(b, "deep.vtu")
    });
    assert!(result.is_err());
}

#[test]
fn a_legitimate_compressed_vtu_reads_in_a_few_times_its_decoded_size() {
    let _alone = alone();
    let n = 30;
    let (points, tets) = bombs::tet_grid(n);
    // What the reader decodes, at 8 bytes a value: 3 per point, 6 per tetrahedron.
    let decoded = 8 * (3 * points.len() + 6 * tets.len());
    for encoding in [bombs::Encoding::AppendedRaw, bombs::Encoding::InlineBase64] {
        let bytes = bombs::grid_vtu(n, true, encoding);
        let d = bounded(
            &format!("VTU, {} tets, zlib, {encoding:?}", tets.len()),
            &bytes,
            3 * decoded,
            |b| tissue_meshio::parse_vtu(b, "grid.vtu"),
        )
        .unwrap();
        assert_eq!(d.tets.len(), tets.len());
    }
}
