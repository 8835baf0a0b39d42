//! Splitting a triangle mesh along a plane, so that the plane's section
//! becomes a chain of mesh edges (issue #18: a garment cut at its side
//! seams, its girth lines made into template edges).
//!
//! # Method
//!
//! With `d(v)` the signed distance of vertex `v` to the plane, a vertex with
//! `|d(v)| ≤ snap` is moved onto the plane (its projection) and counts as
//! *on* it (`d = 0`). Every edge whose two ends lie strictly on opposite
//! sides gets one new vertex at its crossing
//!
//! ```text
//! x = a + t·(b − a),   t = d(a) / (d(a) − d(b))
//! ```
//!
//! shared by the two triangles of the edge. A triangle is then split along
//! the segment between its crossings (or between a crossing and its vertex
//! on the plane): one crossing and one vertex on the plane → two triangles;
//! two crossings → three (the lone vertex's triangle and a quad cut along
//! its shorter diagonal). The corners keep the input's orientation, so an
//! oriented manifold stays one; every output triangle lies on one side of
//! the plane (its *side*, `+1`/`−1`) and carries its input triangle's id.
//!
//! # Failure modes
//!
//! None on finite input: a plane that misses the mesh returns it unchanged
//! (every triangle on one side), a triangle lying in the plane gets side 0.

use std::collections::BTreeMap;

use glam::DVec3;

use super::plane::Plane;

/// The mesh after [`split_by_plane`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneSplit {
    /// Input vertices (those within the snap distance moved onto the plane),
    /// then the crossings.
    pub positions: Vec<DVec3>,
    /// The triangles, input orientation kept.
    pub triangles: Vec<[u32; 3]>,
    /// The input triangle each output triangle came from.
    pub parent: Vec<u32>,
    /// The side of the plane each triangle lies on: `+1` along the plane's
    /// normal, `−1` against it, `0` in the plane.
    pub side: Vec<i8>,
    /// Whether each vertex lies on the plane (snapped or a crossing).
    pub on_plane: Vec<bool>,
    /// For each crossing (vertex `input count + k`), the input edge it
    /// splits (smaller id first).
    pub crossings: Vec<[u32; 2]>,
}

/// Splits the mesh `(positions, triangles)` along `plane` (module docs);
/// `snap` in the positions' unit.
pub fn split_by_plane(positions: &[DVec3], triangles: &[[u32; 3]], plane: &Plane, snap: f64) -> PlaneSplit {
    let mut pos = positions.to_vec();
    let mut d: Vec<f64> = pos.iter().map(|&p| plane.signed_distance(p)).collect();
    let mut on_plane = vec![false; pos.len()];
    for (k, p) in pos.iter_mut().enumerate() {
        if d[k].abs() <= snap {
            *p = plane.project(*p);
            d[k] = 0.0;
            on_plane[k] = true;
        }
    }
    let mut crossing_of: BTreeMap<[u32; 2], u32> = BTreeMap::new();
    let mut crossings: Vec<[u32; 2]> = Vec::new();
    let mut crossing = |a: u32, b: u32, pos: &mut Vec<DVec3>, on_plane: &mut Vec<bool>| -> u32 {
        let key = [a.min(b), a.max(b)];
        *crossing_of.entry(key).or_insert_with(|| {
            let (pa, pb) = (pos[key[0] as usize], pos[key[1] as usize]);
            let (da, db) = (d[key[0] as usize], d[key[1] as usize]);
            let t = da / (da - db);
            let x = plane.project(pa + (pb - pa) * t);
            pos.push(x);
            on_plane.push(true);
            crossings.push(key);
            (pos.len() - 1) as u32
        })
    };
    let sign = |x: f64| -> i8 {
        if x > 0.0 {
            1
        } else if x < 0.0 {
            -1
        } else {
            0
        }
    };
    let mut out = Vec::with_capacity(triangles.len() + 16);
    let mut parent = Vec::with_capacity(triangles.len() + 16);
    let mut side = Vec::with_capacity(triangles.len() + 16);
    for (f, t) in triangles.iter().enumerate() {
        let s = t.map(|v| sign(d[v as usize]));
        let has_pos = s.contains(&1);
        let has_neg = s.contains(&-1);
        if !(has_pos && has_neg) {
            out.push(*t);
            parent.push(f as u32);
            side.push(if has_pos {
                1
            } else if has_neg {
                -1
            } else {
                0
            });
            continue;
        }
        // rotate so that corner 0 is the one that is special: on the plane
        // (then 1 and 2 are opposite), or alone on its side
        let zero = (0..3).find(|&k| s[k] == 0);
        if let Some(k) = zero {
            let [a, b, c] = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
            let x = crossing(b, c, &mut pos, &mut on_plane);
            for tri in [[a, b, x], [a, x, c]] {
                out.push(tri);
                parent.push(f as u32);
            }
            side.push(s[(k + 1) % 3]);
            side.push(s[(k + 2) % 3]);
            continue;
        }
        let k = (0..3).find(|&k| s[k] != s[(k + 1) % 3] && s[k] != s[(k + 2) % 3]).unwrap_or(0);
        let [a, b, c] = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
        let xab = crossing(a, b, &mut pos, &mut on_plane);
        let xca = crossing(c, a, &mut pos, &mut on_plane);
        out.push([a, xab, xca]);
        parent.push(f as u32);
        side.push(s[k]);
        // the quad b, c, xca, xab: cut along its shorter diagonal
        let p = |v: u32| pos[v as usize];
        let quad = if p(b).distance_squared(p(xca)) <= p(c).distance_squared(p(xab)) {
            [[b, c, xca], [b, xca, xab]]
        } else {
            [[xab, b, c], [xab, c, xca]]
        };
        for tri in quad {
            out.push(tri);
            parent.push(f as u32);
            side.push(-s[k]);
        }
    }
    PlaneSplit { positions: pos, triangles: out, parent, side, on_plane, crossings }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(p: &[DVec3], t: &[[u32; 3]]) -> DVec3 {
        t.iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| p[v as usize]);
                (b - a).cross(c - a) * 0.5
            })
            .sum()
    }

    /// A unit square of two triangles in z = 0, cut by x = 0.3: counts,
    /// crossings on the plane, vector area kept, every triangle on one side.
    #[test]
    fn square_cut_through_the_middle() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let t = vec![[0, 1, 2], [0, 2, 3]];
        let plane = Plane::from_point_normal(DVec3::new(0.3, 0.0, 0.0), DVec3::X).unwrap();
        let s = split_by_plane(&p, &t, &plane, 1e-9);
        // edges 0-1, 0-2 (shared) and 2-3 are crossed: 3 new vertices
        assert_eq!(s.positions.len(), 7);
        assert_eq!(s.crossings.len(), 3);
        assert_eq!(s.triangles.len(), 6);
        for k in 4..7 {
            assert!(s.on_plane[k]);
            assert!((s.positions[k].x - 0.3).abs() < 1e-15);
        }
        assert!((area(&s.positions, &s.triangles) - area(&p, &t)).length() < 1e-15);
        for (tri, &side) in s.triangles.iter().zip(&s.side) {
            for v in tri {
                let x = s.positions[*v as usize].x - 0.3;
                assert!(x * f64::from(side) >= -1e-15, "triangle {tri:?} side {side}");
            }
            // no degenerate output
            let [a, b, c] = tri.map(|v| s.positions[v as usize]);
            assert!((b - a).cross(c - a).z > 0.0, "orientation kept");
        }
    }

    /// A vertex within the snap distance lands on the plane; a triangle
    /// through it and across is split in two, not three.
    #[test]
    fn snapped_vertex_splits_in_two() {
        let p = vec![DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, -1.0, 0.0), DVec3::new(1.0, 1.0, 0.0)];
        let t = vec![[0, 1, 2]];
        let plane = Plane::from_point_normal(DVec3::new(0.0, 1e-7, 0.0), DVec3::Y).unwrap();
        let s = split_by_plane(&p, &t, &plane, 1e-6);
        assert!(s.on_plane[0]);
        assert_eq!(s.triangles.len(), 2);
        assert_eq!(s.crossings, vec![[1, 2]]);
        let mut sides = s.side.clone();
        sides.sort();
        assert_eq!(sides, vec![-1, 1]);
    }

    /// A plane that misses the mesh returns it unchanged.
    #[test]
    fn plane_missing_the_mesh() {
        let m = crate::geom::mesh::TriMesh::icosahedron();
        let t: Vec<[u32; 3]> = m.triangles().iter().map(|t| t.map(|v| v.0)).collect();
        let plane = Plane::from_point_normal(DVec3::new(0.0, 5.0, 0.0), DVec3::Y).unwrap();
        let s = split_by_plane(m.positions(), &t, &plane, 1e-9);
        assert_eq!(s.triangles, t);
        assert!(s.side.iter().all(|&x| x == -1));
    }

    /// An icosahedron cut through its centre stays a closed oriented
    /// manifold, and its section is a closed chain of on-plane edges.
    #[test]
    fn closed_mesh_stays_closed() {
        let m = crate::geom::mesh::TriMesh::icosahedron();
        let t: Vec<[u32; 3]> = m.triangles().iter().map(|t| t.map(|v| v.0)).collect();
        let plane = Plane::from_point_normal(DVec3::new(0.01, 0.02, 0.03), DVec3::new(0.3, 1.0, 0.2)).unwrap();
        let s = split_by_plane(m.positions(), &t, &plane, 1e-12);
        let tris: Vec<[crate::geom::mesh::VertexId; 3]> =
            s.triangles.iter().map(|t| t.map(crate::geom::mesh::VertexId)).collect();
        let out = crate::geom::mesh::TriMesh::new(s.positions.clone(), tris).unwrap();
        let stats = crate::geom::simplify::check_oriented_manifold(&out).unwrap();
        assert!(stats.is_closed());
        assert_eq!(stats.euler_characteristic, 2);
        // triangles on the two sides meet only along on-plane edges
        let mut edge_side: BTreeMap<[u32; 2], Vec<i8>> = BTreeMap::new();
        for (tri, &side) in s.triangles.iter().zip(&s.side) {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                edge_side.entry([a.min(b), a.max(b)]).or_default().push(side);
            }
        }
        let cut: Vec<[u32; 2]> = edge_side.iter().filter(|(_, s)| s[0] != s[1]).map(|(e, _)| *e).collect();
        assert!(cut.len() >= 3);
        for e in &cut {
            assert!(s.on_plane[e[0] as usize] && s.on_plane[e[1] as usize]);
        }
        // every on-plane vertex of the cut has two cut edges: a closed chain
        let mut degree: BTreeMap<u32, usize> = BTreeMap::new();
        for e in &cut {
            *degree.entry(e[0]).or_default() += 1;
            *degree.entry(e[1]).or_default() += 1;
        }
        assert!(degree.values().all(|&d| d == 2));
    }
}
