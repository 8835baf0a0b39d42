//! Exact triangle–triangle intersection between a garment and a body: the
//! judge of *poke-through between vertices* (`DESIGN.md` §9, "no garment
//! triangle through a body triangle").
//!
//! # Method
//!
//! Two triangles that do not lie in one plane intersect iff an edge of one
//! crosses the other: their intersection is a segment (or a point) whose
//! ends each lie on the boundary of one of them (Möller 1997, *A fast
//! triangle–triangle intersection test*, §2; the edge formulation of Guigue
//! & Devillers 2003). A segment `pq` crosses triangle `abc` iff
//!
//! ```text
//! sign orient(a, b, c, p) ≠ sign orient(a, b, c, q)            (the ends lie on both sides)
//! and orient(p, q, a, b), orient(p, q, b, c), orient(p, q, c, a) share a sign  (the line passes inside)
//! ```
//!
//! with `orient(a, b, c, d) = (a − d)·((b − d) × (c − d))`, Shewchuk's
//! adaptive-precision predicate (crate `robust`, georust; chosen because a
//! hand-rolled `f64` determinant answers wrongly for nearly coplanar
//! configurations, which a garment 1 mm off the skin is full of). The
//! predicates are exact for the `f64` inputs: there is no tolerance.
//! Touching counts as intersecting (closed triangles); one end exactly on the
//! plane counts as crossing.
//!
//! Candidate pairs come from the body's bounding-volume hierarchy
//! ([`WindingTree::faces_in_box`]) queried with each garment triangle's box:
//! `O(G log B)` for `G` garment and `B` body triangles.
//!
//! # Preconditions and failure modes
//!
//! - Coplanar pairs (all four orientations of one triangle's corners against
//!   the other's plane zero) are reported as *not* intersecting: a garment
//!   lying exactly in the skin's plane has zero-volume overlap, and
//!   [`crate::refine::collision`] keeps every vertex at a clearance anyway.
//! - Degenerate (zero-area) triangles are segments or points and are tested
//!   as such by the same predicates.
//! - Non-finite coordinates give no intersection (every predicate is NaN).

use glam::DVec3;
use robust::{orient3d, Coord3D};

use typed_index_collections::TiSlice;

use crate::geom::mesh::{FaceId, TriMesh, VertexId};
use crate::geom::winding::WindingTree;

#[inline]
fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D { x: p.x, y: p.y, z: p.z }
}

/// Exact `orient(a, b, c, d)` (module docs): its sign tells on which side of
/// the plane `abc` the point `d` lies; zero when the four are coplanar.
#[inline]
pub fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Whether the closed segment `pq` crosses the closed triangle `t` (module
/// docs). A segment lying in the triangle's plane does not cross it.
pub fn segment_crosses_triangle(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    let [a, b, c] = t;
    let (sp, sq) = (orient(a, b, c, p), orient(a, b, c, q));
    if sp == 0.0 && sq == 0.0 {
        return false;
    }
    if (sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0) || sp.is_nan() || sq.is_nan() {
        return false;
    }
    let o = [orient(p, q, a, b), orient(p, q, b, c), orient(p, q, c, a)];
    o.iter().all(|&x| x >= 0.0) || o.iter().all(|&x| x <= 0.0)
}

/// Whether two closed triangles intersect (module docs; coplanar pairs do not).
pub fn triangles_intersect(s: [DVec3; 3], t: [DVec3; 3]) -> bool {
    (0..3).any(|k| segment_crosses_triangle(s[k], s[(k + 1) % 3], t))
        || (0..3).any(|k| segment_crosses_triangle(t[k], t[(k + 1) % 3], s))
}

/// One garment triangle through one body triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IntersectingPair {
    /// The garment triangle.
    pub garment: FaceId,
    /// The body triangle.
    pub body: FaceId,
}

/// Every garment triangle that intersects a body triangle, with the body
/// triangle; in garment order, then body face order (deterministic).
/// Triangles are vertex ids into `positions`.
pub fn intersecting_pairs(
    tree: &WindingTree,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
) -> Vec<IntersectingPair> {
    let mut out = Vec::new();
    let mut found = Vec::new();
    for (g, tri) in triangles.iter_enumerated() {
        let s = tri.map(|v| positions[v]);
        let lo = s[0].min(s[1]).min(s[2]);
        let hi = s[0].max(s[1]).max(s[2]);
        found.clear();
        tree.faces_in_box(lo, hi, |f, t| {
            if triangles_intersect(s, t) {
                found.push(f);
            }
        });
        found.sort_unstable_by_key(|f| f.0);
        out.extend(found.iter().map(|&body| IntersectingPair { garment: g, body }));
    }
    out
}

/// Pairs of triangles of one mesh that cross each other without sharing a
/// vertex: where two parts of a body are pressed into each other (thighs,
/// an arm on the torso), its surface crosses itself and no garment surface
/// can pass between them. `(a, b)` with `a < b`, ascending.
pub fn self_intersections(tree: &WindingTree, mesh: &TriMesh) -> Vec<(FaceId, FaceId)> {
    let mut out = Vec::new();
    for (i, t) in mesh.triangles().iter().enumerate() {
        let s = mesh.corners(FaceId(i as u32));
        let lo = s[0].min(s[1]).min(s[2]);
        let hi = s[0].max(s[1]).max(s[2]);
        let mut found = Vec::new();
        tree.faces_in_box(lo, hi, |f, c| {
            let u = mesh.triangles()[f.idx()];
            if f.idx() > i && !u.iter().any(|v| t.contains(v)) && triangles_intersect(s, c) {
                found.push(f);
            }
        });
        found.sort_unstable_by_key(|f| f.0);
        out.extend(found.into_iter().map(|f| (FaceId(i as u32), f)));
    }
    out
}

/// Counts of [`intersecting_pairs`]: pairs, and distinct garment triangles.
pub fn count_pairs(pairs: &[IntersectingPair]) -> (usize, usize) {
    let mut g: Vec<FaceId> = pairs.iter().map(|p| p.garment).collect();
    g.dedup();
    (pairs.len(), g.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::VertexId;
    use crate::geom::winding::WindingOptions;
    use glam::DQuat;
    use proptest::prelude::*;
    use typed_index_collections::TiVec;

    fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [DVec3; 3] {
        [DVec3::from_array(a), DVec3::from_array(b), DVec3::from_array(c)]
    }

    #[test]
    fn exact_answers() {
        let floor = tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        // a triangle piercing the floor through its interior
        assert!(triangles_intersect(floor, tri([0.2, 0.2, -1.0], [0.3, 0.2, 1.0], [0.2, 0.3, 1.0])));
        // the same, lifted off the floor by 1e-12: separate
        assert!(!triangles_intersect(floor, tri([0.2, 0.2, 1e-12], [0.3, 0.2, 1.0], [0.2, 0.3, 1.0])));
        // a bar through the floor's interior, the floor's edges not touching the bar
        // (only the second triangle's edges cross): still found
        let big = tri([-5.0, -5.0, 0.0], [5.0, -5.0, 0.0], [0.0, 5.0, 0.0]);
        assert!(triangles_intersect(big, tri([0.0, 0.0, -1.0], [0.1, 0.0, 1.0], [0.0, 0.1, 1.0])));
        assert!(triangles_intersect(tri([0.0, 0.0, -1.0], [0.1, 0.0, 1.0], [0.0, 0.1, 1.0]), big));
        // a vertex touching the floor: closed triangles intersect
        assert!(triangles_intersect(floor, tri([0.2, 0.2, 0.0], [0.3, 0.2, 1.0], [0.2, 0.3, 1.0])));
        // passing beside the floor's hypotenuse
        assert!(!triangles_intersect(floor, tri([0.6, 0.6, -1.0], [0.7, 0.6, 1.0], [0.6, 0.7, 1.0])));
        // coplanar overlap is not counted (module docs)
        assert!(!triangles_intersect(floor, tri([0.1, 0.1, 0.0], [2.0, 0.1, 0.0], [0.1, 2.0, 0.0])));
        // a nearly coplanar crossing that a naive f64 determinant gets wrong is still exact:
        // the tilted triangle crosses z = 0 at x = 0.5 exactly
        let eps = 1e-17;
        let tilted = tri([0.0, 0.3, -0.5 * eps], [1.0, 0.3, 0.5 * eps], [0.0, 0.31, -0.5 * eps]);
        assert!(triangles_intersect(floor, tilted));
        // NaN never intersects
        assert!(!triangles_intersect(floor, tri([f64::NAN, 0.0, 0.0], [0.3, 0.2, 1.0], [0.2, 0.3, 1.0])));
    }

    /// A closed octahedron of radius `r` at `c`.
    fn octahedron(c: DVec3, r: f64) -> TriMesh {
        let p = vec![
            c + DVec3::X * r,
            c - DVec3::X * r,
            c + DVec3::Y * r,
            c - DVec3::Y * r,
            c + DVec3::Z * r,
            c - DVec3::Z * r,
        ];
        let t = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        TriMesh::new(p, t.iter().map(|f| f.map(VertexId)).collect()).unwrap()
    }

    #[test]
    fn bvh_query_matches_all_pairs_on_a_fine_body() {
        // a sphere-like body (icosahedron split 3 times) and a coarse plane sheet through it
        let mut body = TriMesh::icosahedron();
        for _ in 0..3 {
            body = crate::geom::simplify::split_midpoints(&body);
        }
        let body = body.map_positions(|p| p.normalize() * 0.2).unwrap();
        let tree = WindingTree::new(&body, &WindingOptions::default());
        let n = 12;
        let mut pos = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (-0.3 + 0.6 * i as f64 / n as f64, -0.3 + 0.6 * j as f64 / n as f64);
                pos.push(DVec3::new(x, y, 0.05 + 0.01 * (x * 40.0).sin()));
            }
        }
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let v = |i: usize, j: usize| VertexId::from(j * (n + 1) + i);
                tris.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                tris.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        let (pos, tris): (TiVec<VertexId, DVec3>, TiVec<FaceId, _>) = (pos.into(), tris.into());
        let fast = intersecting_pairs(&tree, &pos, &tris);
        let mut brute = Vec::new();
        for (g, t) in tris.iter_enumerated() {
            let s = t.map(|v| pos[v]);
            for f in 0..body.face_count() {
                if triangles_intersect(s, body.corners(FaceId(f as u32))) {
                    brute.push(IntersectingPair { garment: g, body: FaceId(f as u32) });
                }
            }
        }
        assert!(!brute.is_empty());
        assert_eq!(fast, brute);
        // a sheet above the sphere touches nothing
        let above: TiVec<VertexId, DVec3> = pos.iter().map(|p| *p + DVec3::Z * 0.2).collect();
        assert!(intersecting_pairs(&tree, &above, &tris).is_empty());
        let (pairs, garment) = count_pairs(&fast);
        assert!(garment <= pairs && garment > 0);
    }

    proptest! {
        /// Planted answers under rigid motions: a small octahedron's faces cross a
        /// big one's exactly when it straddles the big one's surface.
        #[test]
        fn rigid_motions_keep_the_answer(
            axis in (-1.0f64..1.0, -1.0f64..1.0, 0.1f64..1.0),
            angle in 0.0f64..std::f64::consts::TAU,
            shift in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            offset in 0.0f64..0.3,
        ) {
            let rot = DQuat::from_axis_angle(DVec3::new(axis.0, axis.1, axis.2).normalize(), angle);
            let t = DVec3::new(shift.0, shift.1, shift.2);
            let big = octahedron(DVec3::ZERO, 1.0).map_positions(|p| rot * p + t).unwrap();
            // small octahedron centred on the +X vertex's face normal direction, at a distance
            let dir = DVec3::ONE.normalize();
            let centre = dir * (1.0 / 3f64.sqrt() + offset - 0.15);
            let small = octahedron(centre, 0.1);
            let pos: TiVec<VertexId, DVec3> = small.positions().iter().map(|&p| rot * p + t).collect();
            let tris: TiVec<FaceId, [VertexId; 3]> = small.triangles().to_vec().into();
            let tree = WindingTree::new(&big, &WindingOptions::default());
            let hits = intersecting_pairs(&tree, &pos, &tris);
            // the face x+y+z = 1 is at distance 1/√3; the small body spans ±0.1 along `dir`
            // only to within 0.1·√3 (its vertices are on the axes), so decide on the clear cases
            let gap = offset - 0.15; // centre's signed distance from the face
            if gap.abs() < 0.1 / 3f64.sqrt() - 1e-9 {
                prop_assert!(!hits.is_empty(), "straddling at {gap}");
            } else if gap.abs() > 0.1 + 1e-9 {
                prop_assert!(hits.is_empty(), "clear at {gap}: {hits:?}");
            }
        }
    }
}
