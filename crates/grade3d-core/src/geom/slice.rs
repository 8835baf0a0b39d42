//! Plane sections of a triangle mesh.
//!
//! Every triangle whose vertices lie on both sides of the plane contributes
//! one segment joining the points where two of its edges cross the plane
//! (linear interpolation of the signed distances). Segments that cross the
//! same mesh edge are chained, ignoring orientation, so the result does not
//! depend on the mesh being consistently oriented. On a closed manifold mesh
//! every chain is a closed loop; a boundary (or a non-manifold edge) ends an
//! open chain.
//!
//! Vertices exactly on the plane count as lying on its positive side
//! (symbolic perturbation), so no segment degenerates into a vertex fan.
//! Preconditions: a validated [`TriMesh`]. No failure modes: a plane that
//! misses the mesh gives an empty list.

use glam::DVec3;

use super::mesh::{TriMesh, VertexId};
use super::plane::Plane;
use super::polyline::Polyline;

/// One connected component of a plane section.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// The points, in chain order.
    pub polyline: Polyline,
    /// For each point, the mesh edge (smaller id first) it lies on.
    pub edges: Vec<(VertexId, VertexId)>,
}

fn edge_key(a: VertexId, b: VertexId) -> (VertexId, VertexId) {
    if a < b {
        (a, b)
    } else {
        (b, a)
    }
}

/// All connected components of the section of `mesh` by `plane`.
pub fn slice(mesh: &TriMesh, plane: &Plane) -> Vec<Section> {
    let pos = mesh.positions();
    let d: Vec<f64> = pos.iter().map(|&p| plane.signed_distance(p)).collect();
    // the sides as bytes: the scan over every triangle reads them from a table an eighth the size
    let side: Vec<bool> = d.iter().map(|&x| x >= 0.0).collect();
    let positive = |v: VertexId| side[v.idx()];

    // segments as pairs of edge keys (the index is looked up, never iterated: FxHash, issue #15)
    let mut edge_index: rustc_hash::FxHashMap<(VertexId, VertexId), u32> = rustc_hash::FxHashMap::default();
    let mut edge_list: Vec<(VertexId, VertexId)> = Vec::new();
    let mut incident: Vec<Vec<u32>> = Vec::new(); // edge -> segment ids
    let mut segments: Vec<[u32; 2]> = Vec::new();
    for t in mesh.triangles() {
        let s = [positive(t[0]), positive(t[1]), positive(t[2])];
        if s[0] == s[1] && s[1] == s[2] {
            continue;
        }
        let mut ends = [0u32; 2];
        let mut k = 0;
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            if positive(a) != positive(b) {
                let key = edge_key(a, b);
                let id = *edge_index.entry(key).or_insert_with(|| {
                    edge_list.push(key);
                    incident.push(Vec::new());
                    (edge_list.len() - 1) as u32
                });
                if k < 2 {
                    ends[k] = id;
                }
                k += 1;
            }
        }
        let seg = segments.len() as u32;
        segments.push(ends);
        incident[ends[0] as usize].push(seg);
        incident[ends[1] as usize].push(seg);
    }

    let point_of = |e: u32| -> DVec3 {
        let (a, b) = edge_list[e as usize];
        let (da, db) = (d[a.idx()], d[b.idx()]);
        let t = da / (da - db);
        pos[a.idx()].lerp(pos[b.idx()], t)
    };

    let mut used = vec![false; segments.len()];
    let mut out = Vec::new();
    // Start open chains from edges with a single segment first, so that
    // they are walked end to end; then the remaining (closed) loops.
    let mut starts: Vec<u32> = (0..edge_list.len() as u32).filter(|&e| incident[e as usize].len() == 1).collect();
    starts.extend((0..edge_list.len() as u32).filter(|&e| incident[e as usize].len() != 1));
    for start in starts {
        let Some(&first_seg) = incident[start as usize].iter().find(|&&s| !used[s as usize]) else {
            continue;
        };
        let mut chain = vec![start];
        let mut seg = first_seg;
        let mut at = start;
        let closed = loop {
            used[seg as usize] = true;
            let [e0, e1] = segments[seg as usize];
            let next = if e0 == at { e1 } else { e0 };
            if next == start {
                break true;
            }
            chain.push(next);
            at = next;
            match incident[at as usize].iter().find(|&&s| !used[s as usize]) {
                Some(&s) => seg = s,
                None => break false,
            }
        };
        let points: Vec<DVec3> = chain.iter().map(|&e| point_of(e)).collect();
        let edges = chain.iter().map(|&e| edge_list[e as usize]).collect();
        out.push(Section { polyline: Polyline::new(points, closed), edges });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed UV sphere of radius `r`.
    pub(crate) fn uv_sphere(r: f64, rings: usize, sectors: usize) -> TriMesh {
        let mut pos = vec![DVec3::new(0.0, r, 0.0)];
        for i in 1..rings {
            let phi = std::f64::consts::PI * i as f64 / rings as f64;
            for j in 0..sectors {
                let th = 2.0 * std::f64::consts::PI * j as f64 / sectors as f64;
                pos.push(DVec3::new(r * phi.sin() * th.cos(), r * phi.cos(), r * phi.sin() * th.sin()));
            }
        }
        pos.push(DVec3::new(0.0, -r, 0.0));
        let south = (pos.len() - 1) as u64;
        let idx = |i: usize, j: usize| (1 + (i - 1) * sectors + j % sectors) as u64;
        let mut tris = Vec::new();
        for j in 0..sectors {
            tris.push([0, idx(1, j + 1), idx(1, j)]);
            tris.push([south, idx(rings - 1, j), idx(rings - 1, j + 1)]);
        }
        for i in 1..rings - 1 {
            for j in 0..sectors {
                tris.push([idx(i, j), idx(i, j + 1), idx(i + 1, j + 1)]);
                tris.push([idx(i, j), idx(i + 1, j + 1), idx(i + 1, j)]);
            }
        }
        TriMesh::from_raw(pos, &tris).unwrap()
    }

    #[test]
    fn sphere_section_is_one_closed_circle() {
        let m = uv_sphere(1.0, 64, 128);
        let plane = Plane::from_point_normal(DVec3::new(0.0, 0.3, 0.0), DVec3::new(0.1, 1.0, 0.05)).unwrap();
        let s = slice(&m, &plane);
        assert_eq!(s.len(), 1);
        assert!(s[0].polyline.closed);
        let r = (1.0f64 - plane.offset * plane.offset).sqrt();
        let l = s[0].polyline.length();
        assert!((l - 2.0 * std::f64::consts::PI * r).abs() / l < 2e-3, "{l}");
        for p in &s[0].polyline.points {
            assert!(plane.signed_distance(*p).abs() < 1e-12);
        }
    }

    #[test]
    fn plane_through_vertices_and_missing_plane() {
        let m = uv_sphere(1.0, 8, 16);
        // y = 0 passes exactly through the equator's vertices
        let s = slice(&m, &Plane::from_point_normal(DVec3::ZERO, DVec3::Y).unwrap());
        assert_eq!(s.len(), 1);
        assert!(s[0].polyline.closed);
        assert!(slice(&m, &Plane::from_point_normal(DVec3::Y * 2.0, DVec3::Y).unwrap()).is_empty());
    }

    #[test]
    fn open_surface_gives_open_chain() {
        // a 2x1 strip of quads in the XY plane, cut by x = 0.5
        let pos = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
        ];
        let m = TriMesh::from_raw(pos, &[[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]]).unwrap();
        let s = slice(&m, &Plane::from_point_normal(DVec3::new(0.5, 0.0, 0.0), DVec3::X).unwrap());
        assert_eq!(s.len(), 1);
        assert!(!s[0].polyline.closed);
        assert!((s[0].polyline.length() - 1.0).abs() < 1e-12);
    }
}
