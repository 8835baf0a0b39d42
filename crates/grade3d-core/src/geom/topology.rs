//! Topology checks of triangle meshes, shared by every algorithm that needs
//! an oriented manifold (issue #16, item 2): edge uses, vertex fans, and
//! one union–find.
//!
//! Method: every face contributes one *use* per edge (the face, and whether
//! it runs the edge forward); the uses are sorted by edge and grouped.
//! An edge is *manifold* when one face (a boundary edge) or two faces use
//! it, and the orientation is *consistent* when two faces run it in
//! opposite directions ([`check_edge_uses`]). The edge may be a pair of
//! vertex ids ([`MeshEdge`]: forward = from the lower id to the higher) or
//! a named edge of a template (forward = from its start to its end).
//! A vertex is *manifold* when the corners around it form one fan: corners
//! of two faces that share an interior edge are joined in a union–find,
//! and a vertex whose corners have more than one root is a "bow tie"
//! ([`check_vertex_fans`]).
//!
//! The first offence in edge order (then face order) is the one reported,
//! whatever the order of the faces: the checks are deterministic.
//!
//! Failure modes: [`TopologyError`], naming the edge or vertex and the
//! faces. Preconditions: the faces' vertex ids are in range and no face
//! repeats a vertex (each caller checks those first, with its own ids).

use std::fmt;

use crate::geom::mesh::{FaceId, MeshIndex, VertexId};

/// An undirected edge of a mesh, its lower vertex first; `V` is the kind of
/// vertex id (a garment mesh's [`VertexId`], a panel's local id, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MeshEdge<V = VertexId> {
    /// The lower vertex id.
    pub a: V,
    /// The higher vertex id.
    pub b: V,
}

impl<V: Ord> MeshEdge<V> {
    /// The edge between `u` and `v`, in either order.
    pub fn new(u: V, v: V) -> Self {
        if u <= v {
            Self { a: u, b: v }
        } else {
            Self { a: v, b: u }
        }
    }
}

impl<V: fmt::Display> fmt::Display for MeshEdge<V> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}–{}", self.a, self.b)
    }
}

/// Why a set of faces is not an oriented manifold. `E` names edges: a
/// [`MeshEdge`], or a template's edge id; `V` names vertices.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TopologyError<E: fmt::Display, V: fmt::Display = VertexId> {
    /// More than two faces use one edge.
    #[error("edge {edge} is shared by {faces} faces (non-manifold)")]
    NonManifoldEdge {
        /// The edge.
        edge: E,
        /// How many faces use it.
        faces: usize,
    },
    /// Two faces run one edge in the same direction.
    #[error("edge {edge} is run in the same direction by faces {} and {} (inconsistent orientation)", face_a.0, face_b.0)]
    InconsistentOrientation {
        /// The edge.
        edge: E,
        /// The first face (lower id).
        face_a: FaceId,
        /// The second.
        face_b: FaceId,
    },
    /// The faces around a vertex form more than one fan (a "bow tie").
    #[error("the faces around vertex {vertex} form {fans} separate fans (non-manifold vertex)")]
    NonManifoldVertex {
        /// The vertex.
        vertex: V,
        /// How many fans.
        fans: usize,
    },
}

impl<V: MeshIndex> TopologyError<MeshEdge<V>, V> {
    /// The same error with its vertex ids mapped by `f` (a caller's compact
    /// numbering back to its input's).
    pub fn map_vertices<W: MeshIndex>(self, f: impl Fn(V) -> W) -> TopologyError<MeshEdge<W>, W> {
        let edge = |e: MeshEdge<V>| MeshEdge::new(f(e.a), f(e.b));
        match self {
            Self::NonManifoldEdge { edge: e, faces } => TopologyError::NonManifoldEdge { edge: edge(e), faces },
            Self::InconsistentOrientation { edge: e, face_a, face_b } => {
                TopologyError::InconsistentOrientation { edge: edge(e), face_a, face_b }
            }
            Self::NonManifoldVertex { vertex, fans } => TopologyError::NonManifoldVertex { vertex: f(vertex), fans },
        }
    }
}

/// One face's use of an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct EdgeUse {
    /// The face.
    pub face: FaceId,
    /// Its corner whose edge this is (edge `k` runs corner `k` → `k + 1`).
    pub corner: u8,
    /// Whether the face runs the edge forward.
    pub forward: bool,
}

/// The faces of one edge that passed [`check_edge_uses`]: one (a boundary
/// edge) or two running it in opposite directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeFaces<E> {
    /// The edge.
    pub edge: E,
    /// The use of the lower face.
    pub first: EdgeUse,
    /// The other face's use; `None` on the boundary.
    pub second: Option<EdgeUse>,
}

/// Checks that every edge is used by one or two faces, two in opposite
/// directions (module docs), and returns the edges in their order with
/// their faces.
///
/// # Errors
/// [`TopologyError::NonManifoldEdge`] or
/// [`TopologyError::InconsistentOrientation`] for the first offending edge.
pub fn check_edge_uses<E: Ord + Copy + fmt::Display, V: fmt::Display>(
    mut uses: Vec<(E, EdgeUse)>,
) -> Result<Vec<EdgeFaces<E>>, TopologyError<E, V>> {
    uses.sort_unstable();
    let mut out = Vec::with_capacity(uses.len() / 2 + 1);
    for group in uses.chunk_by(|x, y| x.0 == y.0) {
        let (edge, first) = group[0];
        match group {
            [_] => out.push(EdgeFaces { edge, first, second: None }),
            [_, (_, second)] if second.forward != first.forward => {
                out.push(EdgeFaces { edge, first, second: Some(*second) })
            }
            [_, (_, second)] => {
                return Err(TopologyError::InconsistentOrientation { edge, face_a: first.face, face_b: second.face })
            }
            _ => return Err(TopologyError::NonManifoldEdge { edge, faces: group.len() }),
        }
    }
    Ok(out)
}

/// The edge uses of indexed triangles (vertex-pair edges), for
/// [`check_edge_uses`].
pub fn triangle_edge_uses<V: MeshIndex>(triangles: &[[V; 3]]) -> Vec<(MeshEdge<V>, EdgeUse)> {
    let mut uses = Vec::with_capacity(3 * triangles.len());
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            uses.push((MeshEdge::new(u, v), EdgeUse { face: FaceId::from(f), corner: k as u8, forward: u < v }));
        }
    }
    uses
}

/// Checks that the corners around every vertex of `triangles` form one fan
/// (module docs); `edges` are the triangles' checked edges
/// ([`check_edge_uses`]), `vertices` the vertex count.
///
/// # Errors
/// [`TopologyError::NonManifoldVertex`] for the lowest offending vertex.
pub fn check_vertex_fans<E: fmt::Display, V: MeshIndex>(
    triangles: &[[V; 3]],
    vertices: usize,
    edges: &[EdgeFaces<MeshEdge<V>>],
) -> Result<(), TopologyError<E, V>> {
    let corner = |u: EdgeUse| 3 * u.face.0 + u32::from(u.corner);
    let next = |c: u32| 3 * (c / 3) + (c % 3 + 1) % 3;
    let mut fans = UnionFind::new(3 * triangles.len());
    for e in edges {
        // corner c1 sits at one end of the edge and next(c1) at the other; the
        // other face runs it backwards: its corner c2 sits at the second end
        if let Some(second) = e.second {
            let (c1, c2) = (corner(e.first), corner(second));
            fans.union(c1, next(c2));
            fans.union(next(c1), c2);
        }
    }
    // each vertex's first fan, one pass over the corners; the fan count only for the offender
    let mut first = vec![u32::MAX; vertices];
    let mut offender: Option<V> = None;
    for (f, t) in triangles.iter().enumerate() {
        for (k, &v) in t.iter().enumerate() {
            let root = fans.find(3 * f as u32 + k as u32);
            match first.get_mut(v.into()) {
                Some(r) if *r == u32::MAX => *r = root,
                Some(r) if *r != root => offender = Some(offender.map_or(v, |o| o.min(v))),
                _ => {}
            }
        }
    }
    if let Some(v) = offender {
        let mut roots: Vec<u32> = Vec::new();
        for (f, t) in triangles.iter().enumerate() {
            for (k, _) in t.iter().enumerate().filter(|(_, &u)| u == v) {
                roots.push(fans.find(3 * f as u32 + k as u32));
            }
        }
        roots.sort_unstable();
        roots.dedup();
        return Err(TopologyError::NonManifoldVertex { vertex: v, fans: roots.len() });
    }
    Ok(())
}

/// Disjoint sets over `0..n` with path halving; a union's root is the lower
/// of the two roots, so every set's root is its least member (deterministic).
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    /// `n` singletons.
    pub fn new(n: usize) -> Self {
        Self { parent: (0..n as u32).collect() }
    }

    /// The root (least member) of `x`'s set.
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
        }
        x
    }

    /// Joins the sets of `a` and `b`; whether they were apart.
    pub fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb) as usize] = ra.min(rb);
        }
        ra != rb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type R = Result<(), TopologyError<MeshEdge>>;

    fn check(tris: &[[u32; 3]], n: usize) -> R {
        let tris: Vec<[VertexId; 3]> = tris.iter().map(|t| t.map(VertexId)).collect();
        let tris = &tris[..];
        let edges = check_edge_uses(triangle_edge_uses(tris))?;
        check_vertex_fans(tris, n, &edges)
    }

    #[test]
    fn a_closed_octahedron_passes_with_12_interior_edges() {
        // element counts: 8 faces, 12 edges, each used twice
        let tris = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        let edges = check_edge_uses::<_, VertexId>(triangle_edge_uses(&tris.map(|t| t.map(VertexId)))).unwrap();
        assert_eq!(edges.len(), 12);
        assert!(edges.iter().all(|e| e.second.is_some()));
        assert_eq!(check(&tris, 6), Ok(()));
    }

    #[test]
    fn the_three_offences_are_named() {
        let fin = [[0, 1, 2], [1, 0, 3], [1, 0, 4]];
        assert_eq!(
            check(&fin, 5),
            Err(TopologyError::NonManifoldEdge { edge: MeshEdge::new(VertexId(0), VertexId(1)), faces: 3 })
        );
        let twisted = [[0, 1, 2], [0, 1, 3]];
        assert_eq!(
            check(&twisted, 4),
            Err(TopologyError::InconsistentOrientation {
                edge: MeshEdge::new(VertexId(0), VertexId(1)),
                face_a: FaceId(0),
                face_b: FaceId(1)
            })
        );
        let bow_tie = [[0, 1, 2], [0, 3, 4]];
        assert_eq!(check(&bow_tie, 5), Err(TopologyError::NonManifoldVertex { vertex: VertexId(0), fans: 2 }));
        // a fan around a vertex, open or closed, is one
        assert_eq!(check(&[[0, 1, 2], [0, 2, 3], [0, 3, 4]], 5), Ok(()));
    }

    #[test]
    fn the_report_does_not_depend_on_face_order() {
        let a = [[5, 6, 7], [0, 1, 2], [1, 0, 3], [1, 0, 4], [5, 6, 8], [5, 6, 9]];
        let mut b = a;
        b.reverse();
        assert_eq!(check(&a, 10).unwrap_err(), check(&b, 10).unwrap_err());
    }

    #[test]
    fn union_find_roots_are_least_members() {
        let mut u = UnionFind::new(6);
        assert!(u.union(4, 2));
        assert!(u.union(5, 4));
        assert!(!u.union(2, 5));
        assert_eq!((u.find(5), u.find(4), u.find(3)), (2, 2, 3));
    }
}
