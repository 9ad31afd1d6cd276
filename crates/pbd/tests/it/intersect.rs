//! The exact counter of intersecting surface triangle pairs (issue 35, `intersect.rs`): the
//! hierarchy's pairs against the O(n²) reference on random meshes, and on a closed surface.

use glam::{Vec3, Vec3A};
use tissue_mesh::tet_box;
use tissue_pbd::{count_intersecting_pairs, intersecting_pairs, intersecting_pairs_brute_force};

use crate::common::Rng;

/// Random triangles over a small pool of vertices (so that many share one or two corners), some
/// flattened into one plane (coplanar pairs), in a 2 cm cube.
fn random_mesh(rng: &mut Rng, vertices: usize, triangles: usize) -> (Vec<Vec3A>, Vec<[u32; 3]>) {
    let mut p: Vec<Vec3A> = (0..vertices).map(|_| Vec3A::from(rng.vec3(1.0))).collect();
    for x in p.iter_mut().step_by(3) {
        x.z = 0.0;
    }
    let mut t = Vec::new();
    while t.len() < triangles {
        let n = vertices as u64;
        let tri = [
            (rng.next_u64() % n) as u32,
            (rng.next_u64() % n) as u32,
            (rng.next_u64() % n) as u32,
        ];
        if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
            t.push(tri);
        }
    }
    (p, t)
}

#[test]
fn hierarchy_matches_brute_force_on_random_meshes() {
    let mut rng = Rng(35);
    let mut total = 0;
    for round in 0..20 {
        let (p, t) = random_mesh(&mut rng, 30 + 10 * round, 60 + 15 * round);
        let fast = intersecting_pairs(&p, &t).unwrap();
        let slow = intersecting_pairs_brute_force(&p, &t).unwrap();
        assert_eq!(fast, slow, "round {round}");
        total += fast.len();
    }
    // The meshes are tangled: the comparison is not of two empty lists.
    assert!(total > 1000, "{total}");
}

#[test]
fn a_closed_surface_does_not_intersect_itself_until_folded_through() {
    let mesh = tet_box(6, 2, 3, Vec3::new(6.0, 1.0, 0.4)).unwrap();
    let mut p: Vec<Vec3A> = mesh.positions().iter().map(|&x| x.into()).collect();
    let tris: Vec<[u32; 3]> = mesh.boundary_faces().to_vec();
    assert_eq!(count_intersecting_pairs(&p, &tris).unwrap(), 0);
    // Fold the right half (x > 0; the box is centred) about the plane x = 0, half through the left.
    for x in &mut p {
        if x.x > 0.0 {
            x.x = -x.x;
            x.y -= 0.5;
        }
    }
    assert!(count_intersecting_pairs(&p, &tris).unwrap() > 0);
    assert_eq!(
        intersecting_pairs(&p, &tris).unwrap(),
        intersecting_pairs_brute_force(&p, &tris).unwrap()
    );
}
