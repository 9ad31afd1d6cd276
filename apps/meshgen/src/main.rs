//! `meshgen`: writes the thesis's deterministic test meshes, as `fixtures/generate.sh` runs it.
//!
//! ```text
//! meshgen grid   --n 65 --side 1 OUT.obj
//! meshgen sphere --segments 32 --rings 31 --radius 0.25 OUT.obj
//! meshgen cube   --per-edge 8 --side 2 OUT.obj
//! meshgen disc   --radial 8 --segments 32 --radius 1 OUT.obj
//! ```
//! The output format follows the extension (obj, ply, stl, vtk). Exit codes from the table every
//! tissue binary shares ([`tissue_cli::Exit`]): 2 for a bad command line or an output extension
//! no writer knows, 6 for a size out of range, 8 when the file cannot be written.
//! Only clap's help and version go to stdout; a closed stdout ends the program by SIGPIPE without
//! a message (status 141 in a shell).
#![allow(clippy::print_stderr)]

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use tissue_cli::Exit;
use tissue_mesh::{disc, grid, subdivided_cube, uv_sphere, TriMesh};
use tissue_meshio::MeshIoError;

/// Writes deterministic test meshes (the thesis's planes, spheres and cube).
#[derive(Parser, Debug)]
#[command(version, about, after_long_help = Exit::help_section(&[
    (Exit::Usage, "or an output extension other than obj, ply, stl, vtk"),
    (Exit::Parameters, "a count or size the generator refuses"),
]))]
struct Args {
    #[command(subcommand)]
    shape: Shape,
}

#[derive(Subcommand, Debug)]
enum Shape {
    /// Square plane of n×n vertices and the given side, centred at the origin in z = 0.
    Grid {
        #[arg(long)]
        n: u32,
        #[arg(long)]
        side: f32,
        out: PathBuf,
    },
    /// UV sphere: `rings` latitude circles of `segments` vertices plus two poles.
    Sphere {
        #[arg(long)]
        segments: u32,
        #[arg(long)]
        rings: u32,
        #[arg(long)]
        radius: f32,
        out: PathBuf,
    },
    /// Axis-aligned cube centred at the origin, each face split into per_edge² quads.
    Cube {
        #[arg(long)]
        per_edge: u32,
        #[arg(long)]
        side: f32,
        out: PathBuf,
    },
    /// Flat disc in z = 0: a centre vertex and `radial` rings of `segments` vertices.
    Disc {
        #[arg(long)]
        radial: u32,
        #[arg(long)]
        segments: u32,
        #[arg(long)]
        radius: f32,
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    // A closed stdout (`| head`) ends the program by SIGPIPE, silently; see tissue-cli.
    tissue_cli::reset_sigpipe();
    let args = Args::parse();
    let (mesh, out): (Result<TriMesh, _>, PathBuf) = match args.shape {
        Shape::Grid { n, side, out } => (grid(n, side), out),
        Shape::Sphere {
            segments,
            rings,
            radius,
            out,
        } => (uv_sphere(segments, rings, radius), out),
        Shape::Cube {
            per_edge,
            side,
            out,
        } => (subdivided_cube(per_edge, side), out),
        Shape::Disc {
            radial,
            segments,
            radius,
            out,
        } => (disc(radial, segments, radius), out),
    };
    let mesh = match mesh {
        Ok(m) => m,
        Err(e) => {
            eprintln!("meshgen: {e}");
            return Exit::Parameters.into();
        }
    };
    if let Err(e) = tissue_meshio::write_surface(&out, &mesh) {
        eprintln!("meshgen: {e}");
        return match e {
            MeshIoError::UnsupportedFormat { .. } => Exit::Usage,
            _ => Exit::Output,
        }
        .into();
    }
    ExitCode::SUCCESS
}
