//! Exact geometric predicates in tissue's orientation convention, with a symbolic perturbation for
//! the in-sphere ties.
//!
//! `robust` (Shewchuk's adaptive predicates) answers with the exact sign for `f64` inputs. Its
//! `orient3d(a, b, c, d)` is positive when `d` lies *below* `abc`, which is minus tissue's
//! `(b − a)×(c − a)·(d − a)`; the wrappers here flip it so that "positive" means what
//! [`tissue_mesh::TetMesh`] means.
//!
//! In-sphere ties (five cospherical points, e.g. the corners of a cube of a lattice) are broken
//! by Simulation of Simplicity: the lifted coordinate `|x|²` of point `i` is raised by `εᵢ`, with
//! `εᵢ ≫ εⱼ` when `i < j`. Raising a point's lift moves it "out" of spheres, so when the exact
//! answer is 0 the point with the smallest index decides: if it is the query point, the answer is
//! "outside"; if it is tet vertex `v`, the answer is the sign of the query's barycentric
//! coordinate for `v` (the orientation of the tet with `v` replaced by the query), and a zero
//! there passes to the next index. The tet's own orientation is nonzero, so this always ends.
//! With ties broken this way the Delaunay tetrahedralisation is unique and has no flat
//! tetrahedra inside the convex hull.

use robust::Coord3D;

/// A point in `f64`.
pub(crate) type P3 = [f64; 3];

#[inline]
fn c(p: &P3) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// Sign-exact `(b − a)×(c − a)·(d − a)` (six times the signed volume): positive when `abcd` is
/// positively oriented in tissue's convention.
#[inline]
pub(crate) fn orient(a: &P3, b: &P3, cc: &P3, d: &P3) -> f64 {
    -robust::orient3d(c(a), c(b), c(cc), c(d))
}

/// `true` when `e` lies strictly inside the circumsphere of the positively oriented tet
/// `[p[0], p[1], p[2], p[3]]` (points `ids[0..4]`), ties broken by symbolic perturbation with
/// `e`'s index `ide` (see the module doc).
#[inline]
pub(crate) fn in_sphere(p: [&P3; 4], ids: [u32; 4], e: &P3, ide: u32) -> bool {
    // robust::insphere wants a positive orientation in its own (flipped) sense: swap a and b.
    let s = robust::insphere(c(p[1]), c(p[0]), c(p[2]), c(p[3]), c(e));
    if s != 0.0 {
        return s > 0.0;
    }
    // Tie: visit the five points by increasing index.
    let mut order = [
        (ids[0], 0usize),
        (ids[1], 1),
        (ids[2], 2),
        (ids[3], 3),
        (ide, 4),
    ];
    order.sort_unstable();
    for &(_, slot) in &order {
        if slot == 4 {
            return false;
        }
        let mut q = p;
        q[slot] = e;
        let o = orient(q[0], q[1], q[2], q[3]);
        if o != 0.0 {
            return o > 0.0;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: P3 = [0.0, 0.0, 0.0];
    const B: P3 = [1.0, 0.0, 0.0];
    const C: P3 = [0.0, 1.0, 0.0];
    const D: P3 = [0.0, 0.0, 1.0];

    #[test]
    fn orientation_matches_tissue_convention() {
        assert!(orient(&A, &B, &C, &D) > 0.0);
        assert!(orient(&B, &A, &C, &D) < 0.0);
        assert_eq!(orient(&A, &B, &C, &[1.0, 1.0, 0.0]), 0.0);
    }

    #[test]
    fn in_sphere_inside_outside() {
        let ids = [0, 1, 2, 3];
        assert!(in_sphere([&A, &B, &C, &D], ids, &[0.2, 0.2, 0.2], 4));
        assert!(!in_sphere([&A, &B, &C, &D], ids, &[2.0, 2.0, 2.0], 4));
    }

    #[test]
    fn cospherical_ties_are_consistent() {
        // A and G are opposite corners of the unit cube, all eight corners cospherical. Tets
        // (A, B, C, D) and (G, B, D, C) share face BCD with A and G on opposite
        // sides. The local Delaunay test of face BCD must give the same verdict seen from either
        // tet ("G in sphere(ABCD)" exactly when "A in sphere(GBDC)"), and the tie must be broken
        // (the exact test says 0).
        let g: P3 = [1.0, 1.0, 1.0];
        assert_eq!(robust::insphere(c(&B), c(&A), c(&C), c(&D), c(&g)), 0.0);
        let t2 = [&g, &B, &D, &C];
        assert!(orient(t2[0], t2[1], t2[2], t2[3]) > 0.0);
        for (ia, ig) in [(0, 4), (4, 0)] {
            let in1 = in_sphere([&A, &B, &C, &D], [ia, 1, 2, 3], &g, ig);
            let in2 = in_sphere(t2, [ig, 1, 3, 2], &A, ia);
            assert_eq!(in1, in2, "indices A={ia}, G={ig}");
        }
    }
}
