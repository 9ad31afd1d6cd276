//! Base outlines sampled counter-clockwise, and the ring grids that mesh the base and the dome
//! over them.
//!
//! Every outline is star-shaped about the origin in its own plane (a circle, a rounded
//! rectangle, or the stadium that a crescent is bent from), so the ring at parameter
//! `r ∈ (0, 1]` is the outline scaled by `r` towards the origin: ring `k` of `n` holds the same
//! `s` samples scaled, and the grid of rings is a valid triangulation of the base. A crescent
//! is then bent by [`bend`], a smooth orientation-preserving map, after the scaling.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Fewest outline samples: a rounded rectangle has eight pieces (four sides, four corners) and
/// each gets at least one sample.
pub(crate) const MIN_SEGMENTS: u32 = 12;

/// Fewest rings: one interior ring on each surface besides the centre.
pub(crate) const MIN_RINGS: u32 = 2;

/// Vertex count of a grid of `rings` rings (the rim included) and `segments` samples per ring:
/// the shared rim, `rings − 1` rings and a centre on each of the base and the dome.
pub(crate) fn vertex_count(rings: u32, segments: u32) -> u64 {
    2 + u64::from(2 * rings - 1) * u64::from(segments)
}

/// Ring count `n` and outline samples `s` whose [`vertex_count`] is closest to `budget`, with
/// `s ≈ 4n` so that cells are about as long around a ring as they are across it
/// (`n ≈ √(budget/8)`). Ties go to the `n` nearest `√(budget/8)`.
pub(crate) fn grid_size(budget: u32) -> (u32, u32) {
    let b = f64::from(budget);
    let n0 = (b / 8.0).sqrt();
    let mut candidates: Vec<u32> = ((n0.floor() as u32).saturating_sub(1).max(MIN_RINGS)
        ..=(n0.ceil() as u32 + 1).max(MIN_RINGS))
        .collect();
    candidates.sort_by(|&x, &y| {
        (f64::from(x) - n0)
            .abs()
            .total_cmp(&(f64::from(y) - n0).abs())
    });
    let mut best = (MIN_RINGS, MIN_SEGMENTS, u64::MAX);
    for n in candidates {
        let per_segment = f64::from(2 * n - 1);
        let s = ((b - 2.0) / per_segment)
            .round()
            .max(f64::from(MIN_SEGMENTS)) as u32;
        let error = vertex_count(n, s).abs_diff(u64::from(budget));
        if error < best.2 {
            best = (n, s, error);
        }
    }
    (best.0, best.1)
}

/// A piece of an outline, run counter-clockwise.
enum Piece {
    /// A straight segment from the first point to the second.
    Line([f64; 2], [f64; 2]),
    /// A quarter circle of `radius` about `centre`, from angle `start` to `start + π/2`.
    Quarter {
        centre: [f64; 2],
        radius: f64,
        start: f64,
    },
}

impl Piece {
    fn length(&self) -> f64 {
        match *self {
            Piece::Line(a, b) => (b[0] - a[0]).hypot(b[1] - a[1]),
            Piece::Quarter { radius, .. } => FRAC_PI_2 * radius,
        }
    }

    /// The point at fraction `t ∈ [0, 1)` of the piece.
    fn at(&self, t: f64) -> [f64; 2] {
        match *self {
            Piece::Line(a, b) => [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])],
            Piece::Quarter {
                centre,
                radius,
                start,
            } => {
                let phi = start + t * FRAC_PI_2;
                [
                    centre[0] + radius * phi.cos(),
                    centre[1] + radius * phi.sin(),
                ]
            }
        }
    }
}

/// `segments` points of the circle of `radius` about the origin, counter-clockwise from `+x`,
/// equally spaced.
pub(crate) fn circle(radius: f64, segments: u32) -> Vec<[f64; 2]> {
    (0..segments)
        .map(|j| {
            let phi = TAU * f64::from(j) / f64::from(segments);
            [radius * phi.cos(), radius * phi.sin()]
        })
        .collect()
}

/// `segments` points of the rectangle `length × width` (along `x`, `y`) centred at the origin
/// with corners rounded to `corner` (`0 ≤ corner ≤ min(length, width)/2`), counter-clockwise
/// from the lower end of the `+x` side.
///
/// Each non-empty piece (side or quarter corner) starts with a sample, so the sides' end points
/// and the corners' tangent points are sampled exactly and the samples' bounding box is exactly
/// `length × width`. The other samples go to the pieces so that their spacings are as equal as
/// possible: each piece gets `m ≥ 1` samples at fractions `i/m` of its length.
/// `segments` must be at least [`MIN_SEGMENTS`].
pub(crate) fn rounded_rectangle(
    length: f64,
    width: f64,
    corner: f64,
    segments: u32,
) -> Vec<[f64; 2]> {
    let (a, b) = (0.5 * length, 0.5 * width);
    let (ai, bi) = (a - corner, b - corner);
    let quarter = |centre, start| Piece::Quarter {
        centre,
        radius: corner,
        start,
    };
    let pieces = [
        Piece::Line([a, -bi], [a, bi]),
        quarter([ai, bi], 0.0),
        Piece::Line([ai, b], [-ai, b]),
        quarter([-ai, bi], FRAC_PI_2),
        Piece::Line([-a, bi], [-a, -bi]),
        quarter([-ai, -bi], PI),
        Piece::Line([-ai, -b], [ai, -b]),
        quarter([ai, -bi], 3.0 * FRAC_PI_2),
    ];
    // A piece shorter than this is a point (a sharp corner, or the side of a stadium).
    let negligible = 1e-9 * (a + b);
    let pieces: Vec<&Piece> = pieces.iter().filter(|p| p.length() > negligible).collect();
    let lengths: Vec<f64> = pieces.iter().map(|p| p.length()).collect();
    let counts = share_samples(&lengths, segments as usize);
    let mut points = Vec::with_capacity(segments as usize);
    for (piece, &m) in pieces.iter().zip(&counts) {
        for i in 0..m {
            points.push(piece.at(i as f64 / m as f64));
        }
    }
    points
}

/// Splits `total` samples among pieces of the given lengths: at least one each, then one at a
/// time to the piece whose spacing `length/count` is largest (removing from the smallest spacing
/// if the minimum of one each already exceeds `total`).
fn share_samples(lengths: &[f64], total: usize) -> Vec<usize> {
    let sum: f64 = lengths.iter().sum();
    let mut counts: Vec<usize> = lengths
        .iter()
        .map(|&l| ((total as f64 * l / sum).floor() as usize).max(1))
        .collect();
    let spacing = |i: usize, c: &[usize]| lengths[i] / c[i] as f64;
    while counts.iter().sum::<usize>() < total {
        let widest = (0..counts.len())
            .max_by(|&i, &j| spacing(i, &counts).total_cmp(&spacing(j, &counts)))
            .unwrap_or(0);
        counts[widest] += 1;
    }
    while counts.iter().sum::<usize>() > total {
        let Some(closest) = (0..counts.len())
            .filter(|&i| counts[i] > 1)
            .min_by(|&i, &j| spacing(i, &counts).total_cmp(&spacing(j, &counts)))
        else {
            break;
        };
        counts[closest] -= 1;
    }
    counts
}

/// Bends the plane so that the `x` axis becomes the circle of radius `radius` through the origin
/// centred at `(0, −radius)`: the point `(s, t)` goes to
/// `((radius + t)·sin(s/radius), (radius + t)·cos(s/radius) − radius)`.
///
/// Arc length along the `x` axis is kept, `t` becomes the distance outward from the circle, and
/// the map is smooth with Jacobian `(radius + t)/radius > 0` (orientation-preserving) for
/// `t > −radius`, and one-to-one for `|s| < π·radius`.
pub(crate) fn bend(p: [f64; 2], radius: f64) -> [f64; 2] {
    let (s, t) = (p[0], p[1]);
    let phi = s / radius;
    [(radius + t) * phi.sin(), (radius + t) * phi.cos() - radius]
}

/// The plan (x, y) of every vertex of an implant mesh, and its triangles.
///
/// Vertex numbering, with `n` rings and `s` samples per ring:
/// - `0 .. s`: the rim (the base outline), counter-clockwise seen from `+z`;
/// - `s .. n·s + 1`: the base interior, rings `n − 1` down to `1` (outside in), then the centre;
/// - `n·s + 1 .. (2n − 1)·s + 2`: the dome interior, in the same order.
///
/// Base ring `k` is the outline scaled by `k/n`; dome ring `k` by `sin(π k / 2n)`, denser
/// towards the rim where the dome is steep (for a hemisphere the dome rings are equally spaced
/// along its meridians). Triangles: first the dome (counter-clockwise seen from `+z`), then the
/// base (clockwise seen from `+z`, so that its normal points down, out of the implant). Each is
/// a fan about the centre and bands of quads between rings, every quad split along its shorter
/// diagonal in plan.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    /// Plan position of every vertex.
    pub xy: Vec<[f64; 2]>,
    /// Dome triangles, then base triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Samples per ring (rim vertex count).
    pub segments: u32,
    /// First dome-interior vertex; `0 .. dome_start` is the base, rim first.
    pub dome_start: u32,
    /// Number of dome triangles (they come first).
    pub dome_triangles: usize,
}

impl Grid {
    /// Meshes the base bounded by `outline` (counter-clockwise, star-shaped about the origin)
    /// with `rings` rings, bending every plan point by [`bend`] when `bend_radius` is given.
    pub(crate) fn new(outline: &[[f64; 2]], rings: u32, bend_radius: Option<f64>) -> Grid {
        let n = rings;
        let s = outline.len() as u32;
        let map = |r: f64, p: [f64; 2]| {
            let q = [r * p[0], r * p[1]];
            match bend_radius {
                Some(radius) => bend(q, radius),
                None => q,
            }
        };
        let total = vertex_count(n, s) as usize;
        let mut xy = Vec::with_capacity(total);
        xy.extend(outline.iter().map(|&p| map(1.0, p)));
        let base_ring = |k: u32| f64::from(k) / f64::from(n);
        let dome_ring = |k: u32| (FRAC_PI_2 * f64::from(k) / f64::from(n)).sin();
        for ring in [&base_ring as &dyn Fn(u32) -> f64, &dome_ring] {
            for k in (1..n).rev() {
                let r = ring(k);
                xy.extend(outline.iter().map(|&p| map(r, p)));
            }
            xy.push(map(0.0, [0.0, 0.0]));
        }
        let dome_start = n * s + 1;
        // Index of sample `j` (taken mod s) of ring `k` (0 = centre, n = rim) of a surface whose
        // interior starts at `first`.
        let index = |first: u32, k: u32, j: u32| -> u32 {
            if k == n {
                j % s
            } else if k == 0 {
                first + (n - 1) * s
            } else {
                first + (n - 1 - k) * s + j % s
            }
        };
        let mut triangles = Vec::with_capacity(4 * ((2 * n - 1) * s) as usize);
        for (first, up) in [(dome_start, true), (s, false)] {
            let mut push = |[a, b, c]: [u32; 3]| {
                triangles.push(if up { [a, b, c] } else { [a, c, b] });
            };
            for j in 0..s {
                push([
                    index(first, 0, 0),
                    index(first, 1, j),
                    index(first, 1, j + 1),
                ]);
            }
            for k in 1..n {
                for j in 0..s {
                    let (a, b) = (index(first, k, j), index(first, k, j + 1));
                    let (c, d) = (index(first, k + 1, j), index(first, k + 1, j + 1));
                    // Quad a → c → d → b is counter-clockwise seen from +z.
                    if distance_sq(&xy, a, d) <= distance_sq(&xy, b, c) {
                        push([a, c, d]);
                        push([a, d, b]);
                    } else {
                        push([a, c, b]);
                        push([c, d, b]);
                    }
                }
            }
        }
        let dome_triangles = triangles.len() / 2;
        Grid {
            xy,
            triangles,
            segments: s,
            dome_start,
            dome_triangles,
        }
    }

    /// The smallest ratio, over all triangles, of the plan area (positive when the triangle has
    /// its surface's orientation: counter-clockwise for the dome, clockwise for the base) to the
    /// longest edge squared. Positive means every triangle is a proper, correctly wound triangle
    /// in plan, so the lifted surfaces are valid graphs over the base.
    pub(crate) fn worst_shape(&self) -> f64 {
        self.triangles
            .iter()
            .enumerate()
            .map(|(t, &[a, b, c])| {
                let [p, q, r] = [a, b, c].map(|i| self.xy[i as usize]);
                let doubled = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
                let longest = distance_sq(&self.xy, a, b)
                    .max(distance_sq(&self.xy, b, c))
                    .max(distance_sq(&self.xy, c, a));
                let sign = if t < self.dome_triangles { 1.0 } else { -1.0 };
                sign * 0.5 * doubled / longest
            })
            .fold(f64::INFINITY, f64::min)
    }
}

fn distance_sq(xy: &[[f64; 2]], a: u32, b: u32) -> f64 {
    let (p, q) = (xy[a as usize], xy[b as usize]);
    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_size_is_within_ten_percent_of_every_budget() {
        for budget in 50..=100_000u32 {
            let (n, s) = grid_size(budget);
            assert!(n >= MIN_RINGS && s >= MIN_SEGMENTS);
            let v = vertex_count(n, s) as f64;
            let error = (v - f64::from(budget)).abs() / f64::from(budget);
            assert!(error <= 0.1, "budget {budget}: {v} vertices");
        }
        assert_eq!(vertex_count(grid_size(500).0, grid_size(500).1), 497);
    }

    #[test]
    fn rounded_rectangle_samples_hit_the_bounding_box_exactly() {
        for corner in [0.0, 0.5, 1.0, 2.0] {
            let p = rounded_rectangle(8.0, 4.0, corner, 33);
            assert_eq!(p.len(), 33);
            let max_x = p.iter().map(|q| q[0]).fold(f64::MIN, f64::max);
            let min_y = p.iter().map(|q| q[1]).fold(f64::MAX, f64::min);
            assert!((max_x - 4.0).abs() < 1e-12 && (min_y + 2.0).abs() < 1e-12);
            // Counter-clockwise: positive shoelace area close to the exact area.
            let area: f64 = (0..p.len())
                .map(|i| {
                    let (a, b) = (p[i], p[(i + 1) % p.len()]);
                    0.5 * (a[0] * b[1] - a[1] * b[0])
                })
                .sum();
            let exact = 32.0 - (4.0 - PI) * corner * corner;
            assert!(
                area > 0.0 && (area - exact).abs() < 0.05 * exact,
                "{area} vs {exact}"
            );
        }
    }

    #[test]
    fn bend_keeps_arc_length_and_orientation() {
        let r = 5.0;
        let [x, y] = bend([PI * r / 2.0, 0.0], r);
        assert!((x - r).abs() < 1e-12 && (y + r).abs() < 1e-12);
        let grid = Grid::new(&rounded_rectangle(12.0, 4.0, 2.0, 40), 5, Some(6.0));
        assert!(grid.worst_shape() > 0.0);
    }
}
