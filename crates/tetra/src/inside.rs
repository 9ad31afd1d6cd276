//! Inside/outside queries for a closed surface: ray parity along +x, exact and tie-free.
//!
//! A point is inside when a ray from it along +x crosses the surface an odd number of times.
//! Crossings are found in a uniform grid over the surface's projection onto the yz-plane (each
//! triangle listed in every cell its projected bounding box touches; a query reads one cell).
//! Whether the ray's foot lies in a projected triangle is decided with exact `orient2d`; when it
//! lies exactly on a projected edge or vertex the query point is taken as moved by `(δ, δ²)` in
//! `(y, z)` (Simulation of Simplicity), so a ray through a shared edge or vertex counts exactly
//! one of the triangles around it and parity stays right. Triangles seen edge-on are skipped.
//! Only a point lying exactly on the surface can get either answer.
//!
//! The same grid answers "how far is the nearest surface triangle, up to a radius" for the
//! lattice filter, through [`SurfaceGrid`].

use robust::Coord;

use crate::predicates::P3;

/// Ray-parity point-in-surface test.
pub(crate) struct RayCaster {
    tris: Vec<[P3; 3]>,
    lo: [f64; 2],
    inv_cell: [f64; 2],
    dims: [usize; 2],
    start: Vec<u32>,
    items: Vec<u32>,
}

#[inline]
fn yz(p: &P3) -> Coord<f64> {
    Coord { x: p[1], y: p[2] }
}

/// Sign of `orient2d(a, b, p)` in the (y, z) projection, never 0 unless `a` and `b` project to
/// the same point: a zero is resolved by moving `p` by `(δ, δ²)`.
#[inline]
fn edge_sign(a: &P3, b: &P3, p: &P3) -> i8 {
    let o = robust::orient2d(yz(a), yz(b), yz(p));
    if o > 0.0 {
        1
    } else if o < 0.0 {
        -1
    } else {
        // d/dp_y orient = −(b_z − a_z); d/dp_z orient = (b_y − a_y).
        let dz = b[2] - a[2];
        let dy = b[1] - a[1];
        if dz != 0.0 {
            if dz < 0.0 {
                1
            } else {
                -1
            }
        } else if dy > 0.0 {
            1
        } else if dy < 0.0 {
            -1
        } else {
            0
        }
    }
}

impl RayCaster {
    pub fn new(tris: Vec<[P3; 3]>) -> Self {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for t in &tris {
            for p in t {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k + 1]);
                    hi[k] = hi[k].max(p[k + 1]);
                }
            }
        }
        let extent = [hi[0] - lo[0], hi[1] - lo[1]];
        // About one cell per triangle.
        let cells = (tris.len() as f64).max(1.0);
        let area = (extent[0] * extent[1]).max(f64::MIN_POSITIVE);
        let cell = (area / cells).sqrt().max(1e-12 * (extent[0] + extent[1]));
        let dims = [0, 1].map(|k| ((extent[k] / cell).ceil() as usize).clamp(1, 4096));
        let inv_cell = [0, 1].map(|k| {
            if extent[k] > 0.0 {
                dims[k] as f64 / extent[k]
            } else {
                0.0
            }
        });
        let mut grid = RayCaster {
            tris,
            lo,
            inv_cell,
            dims,
            start: Vec::new(),
            items: Vec::new(),
        };
        let ranges: Vec<[usize; 4]> = grid
            .tris
            .iter()
            .map(|t| {
                let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
                for p in t {
                    for k in 0..2 {
                        a[k] = a[k].min(p[k + 1]);
                        b[k] = b[k].max(p[k + 1]);
                    }
                }
                let (i0, j0) = grid.cell_of(a);
                let (i1, j1) = grid.cell_of(b);
                [i0, i1, j0, j1]
            })
            .collect();
        let ncell = dims[0] * dims[1];
        let mut count = vec![0u32; ncell + 1];
        for r in &ranges {
            for i in r[0]..=r[1] {
                for j in r[2]..=r[3] {
                    count[i * dims[1] + j + 1] += 1;
                }
            }
        }
        for c in 1..=ncell {
            count[c] += count[c - 1];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[ncell] as usize];
        for (t, r) in ranges.iter().enumerate() {
            for i in r[0]..=r[1] {
                for j in r[2]..=r[3] {
                    let c = i * dims[1] + j;
                    items[fill[c] as usize] = t as u32;
                    fill[c] += 1;
                }
            }
        }
        grid.start = count;
        grid.items = items;
        grid
    }

    #[inline]
    fn cell_of(&self, q: [f64; 2]) -> (usize, usize) {
        let i = ((q[0] - self.lo[0]) * self.inv_cell[0]).floor();
        let j = ((q[1] - self.lo[1]) * self.inv_cell[1]).floor();
        let i = (i.max(0.0) as usize).min(self.dims[0] - 1);
        let j = (j.max(0.0) as usize).min(self.dims[1] - 1);
        (i, j)
    }

    /// `true` when `p` is inside the surface (odd number of crossings along +x).
    pub fn is_inside(&self, p: &P3) -> bool {
        let q = [p[1], p[2]];
        let (lo, inv) = (self.lo, self.inv_cell);
        // Outside the grid's box in (y, z): no triangle can be hit.
        for k in 0..2 {
            let u = (q[k] - lo[k]) * inv[k];
            if !(u >= 0.0 && u <= self.dims[k] as f64) {
                return false;
            }
        }
        let (i, j) = self.cell_of(q);
        let c = i * self.dims[1] + j;
        let mut crossings = 0u32;
        for &t in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
            let [a, b, cc] = &self.tris[t as usize];
            let area = robust::orient2d(yz(a), yz(b), yz(cc));
            if area == 0.0 {
                continue; // seen edge-on
            }
            let s = if area > 0.0 { 1 } else { -1 };
            let (sa, sb, sc) = (edge_sign(b, cc, p), edge_sign(cc, a, p), edge_sign(a, b, p));
            if sa != s || sb != s || sc != s {
                continue;
            }
            // Where the ray meets the triangle's plane (barycentric in the projection).
            let la = robust::orient2d(yz(b), yz(cc), yz(p)) / area;
            let lb = robust::orient2d(yz(cc), yz(a), yz(p)) / area;
            let lc = 1.0 - la - lb;
            let x = la * a[0] + lb * b[0] + lc * cc[0];
            if x > p[0] {
                crossings += 1;
            }
        }
        crossings % 2 == 1
    }
}

/// Triangles binned in a uniform 3D grid, each listed in every cell that its bounding box grown
/// by `reach` touches: a query at a point reads one cell and sees every triangle within `reach`.
pub(crate) struct SurfaceGrid {
    lo: P3,
    inv_cell: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl SurfaceGrid {
    /// `reach_of(t)` is how far from triangle `t`'s bounding box a query must still see it.
    pub fn new(tris: &[[P3; 3]], cell: f64, reach_of: impl Fn(usize) -> f64) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let boxes: Vec<(P3, P3)> = tris
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let r = reach_of(t);
                let mut a = [f64::INFINITY; 3];
                let mut b = [f64::NEG_INFINITY; 3];
                for p in tri {
                    for k in 0..3 {
                        a[k] = a[k].min(p[k] - r);
                        b[k] = b[k].max(p[k] + r);
                    }
                }
                for k in 0..3 {
                    lo[k] = lo[k].min(a[k]);
                    hi[k] = hi[k].max(b[k]);
                }
                (a, b)
            })
            .collect();
        // Keep the grid to a few million cells whatever `cell` asks for.
        let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let cell = cell.max(extent / 160.0).max(f64::MIN_POSITIVE);
        let dims = [0, 1, 2].map(|k| (((hi[k] - lo[k]) / cell).ceil() as usize).max(1));
        let mut grid = SurfaceGrid {
            lo,
            inv_cell: 1.0 / cell,
            dims,
            start: Vec::new(),
            items: Vec::new(),
        };
        let ranges: Vec<([usize; 3], [usize; 3])> = boxes
            .iter()
            .map(|(a, b)| (grid.cell_of(a), grid.cell_of(b)))
            .collect();
        let ncell = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; ncell + 1];
        let each = |r: &([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
            for i in r.0[0]..=r.1[0] {
                for j in r.0[1]..=r.1[1] {
                    for k in r.0[2]..=r.1[2] {
                        f((i * dims[1] + j) * dims[2] + k);
                    }
                }
            }
        };
        for r in &ranges {
            each(r, &mut |c| count[c + 1] += 1);
        }
        for c in 1..=ncell {
            count[c] += count[c - 1];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[ncell] as usize];
        for (t, r) in ranges.iter().enumerate() {
            each(r, &mut |c| {
                items[fill[c] as usize] = t as u32;
                fill[c] += 1;
            });
        }
        grid.start = count;
        grid.items = items;
        grid
    }

    #[inline]
    fn cell_of(&self, p: &P3) -> [usize; 3] {
        [0, 1, 2].map(|k| {
            let u = ((p[k] - self.lo[k]) * self.inv_cell).floor();
            (u.max(0.0) as usize).min(self.dims[k] - 1)
        })
    }

    /// The triangles listed where `p` is (empty outside the grid).
    pub fn near(&self, p: &P3) -> &[u32] {
        let outside = (0..3).any(|k| {
            let u = (p[k] - self.lo[k]) * self.inv_cell;
            !(u >= 0.0 && u < self.dims[k] as f64)
        });
        if outside {
            return &[];
        }
        let [i, j, k] = self.cell_of(p);
        let c = (i * self.dims[1] + j) * self.dims[2] + k;
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

#[inline]
fn sub(a: &P3, b: &P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn dot(a: &P3, b: &P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Squared distance from `p` to triangle `abc` (closest point by Voronoi regions of the
/// triangle's vertices, edges and face).
pub(crate) fn distance_sq_to_triangle(p: &P3, [a, b, c]: &[P3; 3]) -> f64 {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(&ab, &ap);
    let d2 = dot(&ac, &ap);
    let at = |s: f64, t: f64| -> f64 {
        let q = [
            a[0] + s * ab[0] + t * ac[0],
            a[1] + s * ab[1] + t * ac[1],
            a[2] + s * ab[2] + t * ac[2],
        ];
        let d = sub(p, &q);
        dot(&d, &d)
    };
    if d1 <= 0.0 && d2 <= 0.0 {
        return at(0.0, 0.0);
    }
    let bp = sub(p, b);
    let d3 = dot(&ab, &bp);
    let d4 = dot(&ac, &bp);
    if d3 >= 0.0 && d4 <= d3 {
        return at(1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return at(d1 / (d1 - d3), 0.0);
    }
    let cp = sub(p, c);
    let d5 = dot(&ab, &cp);
    let d6 = dot(&ac, &cp);
    if d6 >= 0.0 && d5 <= d6 {
        return at(0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return at(0.0, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return at(1.0 - w, w);
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        return at(0.0, 0.0).min(at(1.0, 0.0)).min(at(0.0, 1.0));
    }
    at(vb / denom, vc / denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit cube's surface, 12 triangles, outward.
    fn cube() -> Vec<[P3; 3]> {
        let v: Vec<P3> = (0..8)
            .map(|i| {
                [
                    f64::from(i & 1),
                    f64::from((i >> 1) & 1),
                    f64::from((i >> 2) & 1),
                ]
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut t = Vec::new();
        for q in quads {
            t.push([v[q[0]], v[q[1]], v[q[2]]]);
            t.push([v[q[0]], v[q[2]], v[q[3]]]);
        }
        t
    }

    #[test]
    fn cube_parity_with_rays_through_diagonal_edges() {
        let r = RayCaster::new(cube());
        // y == z: the ray meets the x = 1 face on its diagonal edge.
        for p in [
            [0.5, 0.5, 0.5],
            [0.2, 0.3, 0.3],
            [0.7, 0.25, 0.25],
            [0.2, 0.3, 0.6],
        ] {
            assert!(r.is_inside(&p), "{p:?}");
        }
        for p in [
            [1.5, 0.5, 0.5],
            [-0.5, 0.5, 0.5],
            [0.5, 1.5, 0.5],
            [0.5, 0.5, -1e-9],
        ] {
            assert!(!r.is_inside(&p), "{p:?}");
        }
    }

    #[test]
    fn octahedron_parity_with_rays_through_vertices() {
        let v = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let mut tris = Vec::new();
        for x in [0, 1] {
            for y in [2, 3] {
                for z in [4, 5] {
                    tris.push([v[x], v[y], v[z]]);
                }
            }
        }
        let r = RayCaster::new(tris);
        // Along the x axis the ray passes through the vertices (±1, 0, 0), where 4 triangles meet.
        assert!(r.is_inside(&[0.0, 0.0, 0.0]));
        assert!(r.is_inside(&[0.5, 0.0, 0.0]));
        assert!(r.is_inside(&[-0.9, 0.0, 0.0]));
        assert!(!r.is_inside(&[-2.0, 0.0, 0.0]));
        assert!(!r.is_inside(&[1.5, 0.0, 0.0]));
        // Through the edge (1,0,0)–(0,1,0) region and the edge at z = 0.
        assert!(r.is_inside(&[0.0, 0.5, 0.0]));
        assert!(!r.is_inside(&[-3.0, 0.5, 0.0]));
    }

    #[test]
    fn distance_to_triangle_regions() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!((distance_sq_to_triangle(&[0.2, 0.2, 2.0], &t) - 4.0).abs() < 1e-12);
        assert!((distance_sq_to_triangle(&[-1.0, -1.0, 0.0], &t) - 2.0).abs() < 1e-12);
        assert!((distance_sq_to_triangle(&[1.0, 1.0, 0.0], &t) - 0.5).abs() < 1e-12);
        assert!((distance_sq_to_triangle(&[0.5, -2.0, 0.0], &t) - 4.0).abs() < 1e-12);
    }
}
