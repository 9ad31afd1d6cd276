//! `meshinfo FILE [--json]`: what a user should know about a mesh before planning on it.
//!
//! Prints counts, bounding box, area, volume (closed surfaces), boundary loops with their lengths,
//! components, Euler characteristic and every defect found. Exit codes from the table every
//! tissue binary shares ([`tissue_cli::Exit`]): 0 when the mesh loads (warnings allowed), 3 when
//! the file is missing, unreadable or of an unsupported type, 4 when it is malformed or has hard
//! defects. A closed stdout (`meshinfo FILE | head`) ends it by SIGPIPE without a message
//! (status 141 in a shell).
#![allow(clippy::print_stdout, clippy::print_stderr)]

mod report;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use tissue_cli::Exit;
use tissue_meshio::MeshIoError;

/// Counts, measures, topology and defects of a mesh file (OBJ, PLY, STL, VTK, VTK XML .vtu, Gmsh
/// .msh, TetGen .node/.ele).
#[derive(Parser, Debug)]
#[command(version, about, after_long_help = Exit::help_section(&[
    (Exit::Input, "the file"),
    (Exit::Mesh, "a malformed file, or hard defects (listed)"),
]))]
struct Args {
    /// The mesh file: a surface (.obj, .ply, .stl, .vtk) or a tetrahedral mesh (.vtu, .msh as
    /// Gmsh 1, 2.2 or 4.1, a .vtk tet grid, or a TetGen .node/.ele pair: give either file); of a
    /// .vtu or .msh only the tetrahedra are read.
    file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    // A closed stdout (`| head`) ends the program by SIGPIPE, silently; see tissue-cli.
    tissue_cli::reset_sigpipe();
    let args = Args::parse();
    let report = match report::inspect(&args.file) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("meshinfo: {e}");
            return read_failure(&e).into();
        }
    };
    if args.json {
        match serde_json::to_string_pretty(&report) {
            Ok(s) => println!("{s}"),
            Err(e) => {
                eprintln!("meshinfo: cannot write JSON: {e}");
                return Exit::Output.into();
            }
        }
    } else {
        print!("{}", report.to_text());
    }
    if report.loaded {
        ExitCode::SUCCESS
    } else {
        eprintln!(
            "meshinfo: {} was read but rejected: {} hard defect(s); the first: {}",
            args.file.display(),
            report.hard_defect_count(),
            report.first_hard_defect().unwrap_or("?")
        );
        Exit::Mesh.into()
    }
}

/// The exit code of a file that could not be read: missing, unreadable or of an unsupported
/// type is the input's fault, anything read but malformed the mesh's.
fn read_failure(e: &MeshIoError) -> Exit {
    match e {
        MeshIoError::Io { .. } | MeshIoError::UnsupportedFormat { .. } => Exit::Input,
        _ => Exit::Mesh,
    }
}
