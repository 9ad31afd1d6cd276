//! The voxel grid of a surface (SPEC A.4, "BVH vs voxels"): uniform cubic cells over the surface's
//! bounding box, each listing the triangles that overlap it by the exact triangle–box test.

use glam::{Vec3, Vec3A};
use tissue_bvh::Aabb;

use crate::tri_box::triangle_overlaps_box;
use crate::{CollideError, SurfaceView};

/// The largest number of cells a grid may have (`2²⁴`, 64 MB of cell offsets).
pub const MAX_CELLS: u64 = 1 << 24;

/// Uniform cells over a surface's bounding box, with the triangles overlapping each.
///
/// Cell `(i, j, k)` is the closed box `origin + [i, i+1]·h × [j, j+1]·h × [k, k+1]·h` (`h` the
/// cell size), numbered `i + nx·(j + ny·k)`. A triangle is listed in a cell when the exact test
/// finds them overlapping with the cell grown by a small slack (`10⁻³·h` plus a few ulps of the
/// coordinates), so rounding can add a cell to a triangle's list but never drop one it touches.
/// Both directions are stored as compressed rows, in increasing order: cell → triangles and
/// triangle → cells.
///
/// [`VoxelGrid::update`] re-bins the moved surface into the same arrays: after the first few steps
/// (once the arrays have grown to the largest size needed) it does not allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelGrid {
    cell_size: f32,
    slack: f32,
    origin: Vec3,
    dims: [u32; 3],
    cell_start: Vec<u32>,
    cell_triangles: Vec<u32>,
    triangle_start: Vec<u32>,
    triangle_cells: Vec<u32>,
    /// The box (with the slack) of each entry of `triangle_cells`.
    triangle_cell_boxes: Vec<Aabb>,
    occupied: Vec<u32>,
    cursor: Vec<u32>,
}

impl VoxelGrid {
    /// Bins `view`'s triangles into cells of edge `cell_size` (cm).
    ///
    /// # Errors
    /// [`CollideError::InvalidParameter`] for a cell size that is not finite and positive,
    /// [`CollideError::NonFinitePosition`], [`CollideError::TooManyCells`].
    pub fn new(view: &SurfaceView<'_>, cell_size: f32) -> Result<VoxelGrid, CollideError> {
        if !(cell_size.is_finite() && cell_size > 0.0) {
            return Err(CollideError::InvalidParameter {
                name: "cell_size",
                value: cell_size,
                expected: "finite and positive (cm)",
            });
        }
        let mut grid = VoxelGrid {
            cell_size,
            slack: 0.0,
            origin: Vec3::ZERO,
            dims: [1; 3],
            cell_start: Vec::new(),
            cell_triangles: Vec::new(),
            triangle_start: Vec::new(),
            triangle_cells: Vec::new(),
            triangle_cell_boxes: Vec::new(),
            occupied: Vec::new(),
            cursor: Vec::new(),
        };
        grid.update(view)?;
        Ok(grid)
    }

    /// A cell size for `view`: twice its mean edge length, so that a cell holds a handful of
    /// triangles.
    pub fn suggested_cell_size(view: &SurfaceView<'_>) -> f32 {
        let edges = view.surface().edges();
        let pos = view.positions();
        let sum: f64 = edges
            .iter()
            .map(|&[a, b]| f64::from((pos[a as usize] - pos[b as usize]).length()))
            .sum();
        let mean = (sum / edges.len().max(1) as f64) as f32;
        if mean.is_finite() && mean > 0.0 {
            2.0 * mean
        } else {
            1.0
        }
    }

    /// Re-bins the surface at its current positions (same cell size; the box, and so the number
    /// of cells, follows the surface).
    ///
    /// # Errors
    /// [`CollideError::NonFinitePosition`], [`CollideError::TooManyCells`]. On error the grid is
    /// left empty (no cell lists a triangle) until an update succeeds.
    pub fn update(&mut self, view: &SurfaceView<'_>) -> Result<(), CollideError> {
        let _span =
            tracing::trace_span!("voxel_update", triangles = view.surface().triangle_count())
                .entered();
        self.cell_start.clear();
        self.cell_start.push(0);
        self.cell_triangles.clear();
        self.triangle_start.clear();
        self.triangle_cells.clear();
        self.triangle_cell_boxes.clear();
        self.occupied.clear();
        self.dims = [1; 3];
        let positions = view.positions();
        let mut lo = Vec3A::splat(f32::INFINITY);
        let mut hi = Vec3A::splat(f32::NEG_INFINITY);
        for (i, &p) in positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(CollideError::NonFinitePosition {
                    side: view.side(),
                    particle: i as u32,
                    position: p.to_array(),
                });
            }
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let h = self.cell_size;
        let extent = hi - lo;
        let dims = [0, 1, 2].map(|k| (extent[k] / h).floor() as u64 + 1);
        let cells = dims[0].saturating_mul(dims[1]).saturating_mul(dims[2]);
        if cells > MAX_CELLS {
            return Err(CollideError::TooManyCells {
                cell_size: h,
                extent: extent.to_array(),
                cells,
                max: MAX_CELLS,
            });
        }
        self.dims = dims.map(|d| d as u32);
        self.origin = lo.into();
        let scale = lo.abs().max(hi.abs()).max_element();
        self.slack = 1e-3 * h + 4.0 * f32::EPSILON * scale;
        let cells = cells as usize;
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        self.triangle_start.push(0);
        let [nx, ny, _] = self.dims;
        for t in 0..view.surface().triangle_count() as u32 {
            let [a, b, c] = view.corners(t);
            let tb = Aabb::from_triangle(a, b, c).expanded(self.slack);
            let i0 = self.cell_coords(tb.min.into());
            let i1 = self.cell_coords(tb.max.into());
            for z in i0[2]..=i1[2] {
                for y in i0[1]..=i1[1] {
                    for x in i0[0]..=i1[0] {
                        let cell = x + nx * (y + ny * z);
                        let cell_box = self.cell_box_at([x, y, z]).expanded(self.slack);
                        if triangle_overlaps_box(a, b, c, &cell_box) {
                            self.triangle_cells.push(cell);
                            self.triangle_cell_boxes.push(cell_box);
                            self.cell_start[cell as usize + 1] += 1;
                        }
                    }
                }
            }
            self.triangle_start.push(self.triangle_cells.len() as u32);
        }
        for c in 0..cells {
            if self.cell_start[c + 1] > 0 {
                self.occupied.push(c as u32);
            }
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.cell_start[..cells]);
        self.cell_triangles.resize(self.triangle_cells.len(), 0);
        for t in 0..view.surface().triangle_count() {
            let range = self.triangle_start[t] as usize..self.triangle_start[t + 1] as usize;
            for &cell in &self.triangle_cells[range] {
                let slot = &mut self.cursor[cell as usize];
                self.cell_triangles[*slot as usize] = t as u32;
                *slot += 1;
            }
        }
        Ok(())
    }

    /// The cell containing `p` (clamped into the grid), as `[i, j, k]`.
    #[inline]
    fn cell_coords(&self, p: Vec3A) -> [u32; 3] {
        let rel = (p - Vec3A::from(self.origin)) / self.cell_size;
        [0, 1, 2].map(|k| {
            let i = rel[k].floor();
            if i >= 0.0 {
                (i as u32).min(self.dims[k] - 1)
            } else {
                0
            }
        })
    }

    /// Cell edge length (cm).
    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    /// How much each cell is grown for the overlap tests (cm).
    pub fn slack(&self) -> f32 {
        self.slack
    }

    /// Number of cells along x, y, z.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// The minimum corner of cell 0.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Number of triangles binned.
    pub fn triangle_count(&self) -> usize {
        self.triangle_start.len().saturating_sub(1)
    }

    /// The closed box of `cell`.
    #[inline]
    pub fn cell_box(&self, cell: u32) -> Aabb {
        let [nx, ny, _] = self.dims;
        self.cell_box_at([cell % nx, (cell / nx) % ny, cell / (nx * ny)])
    }

    /// The closed box of the cell at `[i, j, k]`.
    #[inline]
    fn cell_box_at(&self, [x, y, z]: [u32; 3]) -> Aabb {
        let i = Vec3::new(x as f32, y as f32, z as f32);
        Aabb::new(
            self.origin + i * self.cell_size,
            self.origin + (i + Vec3::ONE) * self.cell_size,
        )
    }

    /// The box of `cell` grown by [`VoxelGrid::slack`]: what the overlap tests use.
    #[inline]
    pub fn cell_box_with_slack(&self, cell: u32) -> Aabb {
        self.cell_box(cell).expanded(self.slack)
    }

    /// Triangles overlapping `cell`, increasing (empty for a cell index out of range).
    #[inline]
    pub fn cell_triangles(&self, cell: u32) -> &[u32] {
        let c = cell as usize;
        match (self.cell_start.get(c), self.cell_start.get(c + 1)) {
            (Some(&a), Some(&b)) => &self.cell_triangles[a as usize..b as usize],
            _ => &[],
        }
    }

    /// Cells triangle `t` overlaps, increasing (empty for a triangle index out of range).
    #[inline]
    pub fn triangle_cells(&self, t: u32) -> &[u32] {
        let i = t as usize;
        match (self.triangle_start.get(i), self.triangle_start.get(i + 1)) {
            (Some(&a), Some(&b)) => &self.triangle_cells[a as usize..b as usize],
            _ => &[],
        }
    }

    /// The first cell in triangle `t`'s list whose box (with the slack) overlaps `aabb` grown by
    /// `gap`: the one cell in which BVH-vs-voxel detection tests a triangle pair.
    #[inline]
    pub fn first_cell_overlapping(&self, t: u32, aabb: &Aabb, gap: f32) -> Option<u32> {
        let i = t as usize;
        let (Some(&lo), Some(&hi)) = (self.triangle_start.get(i), self.triangle_start.get(i + 1))
        else {
            return None;
        };
        (lo as usize..hi as usize)
            .find(|&k| self.triangle_cell_boxes[k].overlaps(aabb, gap))
            .map(|k| self.triangle_cells[k])
    }

    /// The cells that list at least one triangle, increasing.
    pub fn occupied_cells(&self) -> &[u32] {
        &self.occupied
    }

    /// Checks the grid against `view` (the positions it was last updated with): every vertex lies
    /// in the grid; each triangle lists, in increasing order, every cell it touches and only cells
    /// that pass the exact test with the slack; the cell lists are the transpose of the triangle
    /// lists. `O(triangles × cells)`: for tests.
    ///
    /// # Panics
    /// With a message naming the triangle or cell at fault.
    pub fn assert_well_formed(&self, view: &SurfaceView<'_>) {
        let n = view.surface().triangle_count();
        assert_eq!(self.triangle_count(), n, "voxel grid: triangle count");
        let domain = Aabb::new(
            self.origin,
            self.origin + Vec3::from(self.dims.map(|d| d as f32)) * self.cell_size,
        );
        for (i, &p) in view.positions().iter().enumerate() {
            assert!(
                domain.contains_point(p),
                "voxel grid: vertex {i} at {p} outside {domain:?}"
            );
        }
        let cells = self.dims.iter().map(|&d| d as usize).product::<usize>();
        let mut transposed = vec![Vec::new(); cells];
        for t in 0..n as u32 {
            let [a, b, c] = view.corners(t);
            let listed = self.triangle_cells(t);
            assert!(!listed.is_empty(), "voxel grid: triangle {t} is in no cell");
            assert!(
                listed.windows(2).all(|w| w[0] < w[1]),
                "voxel grid: cells of triangle {t} not increasing"
            );
            for &cell in listed {
                assert!(
                    triangle_overlaps_box(a, b, c, &self.cell_box_with_slack(cell)),
                    "voxel grid: triangle {t} listed in cell {cell} it does not overlap"
                );
                transposed[cell as usize].push(t);
            }
            for cell in 0..cells as u32 {
                if triangle_overlaps_box(a, b, c, &self.cell_box(cell)) {
                    assert!(
                        listed.contains(&cell),
                        "voxel grid: triangle {t} touches cell {cell} but is not listed there"
                    );
                }
            }
        }
        for (cell, tris) in transposed.iter().enumerate() {
            assert_eq!(
                self.cell_triangles(cell as u32),
                tris.as_slice(),
                "voxel grid: cell {cell}"
            );
        }
        let occupied: Vec<u32> = (0..cells as u32)
            .filter(|&c| !transposed[c as usize].is_empty())
            .collect();
        assert_eq!(
            self.occupied_cells(),
            occupied.as_slice(),
            "voxel grid: occupied cells"
        );
    }
}
