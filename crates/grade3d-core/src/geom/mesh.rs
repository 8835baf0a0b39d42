//! Indexed triangle meshes with typed indices and validation.
//!
//! Contract: a [`TriMesh`] built by [`TriMesh::new`] has at least one
//! triangle, only finite coordinates, every index in range and no triangle
//! that repeats a vertex. Zero-area triangles are allowed (scans have them);
//! every computation here weights by area, so they contribute nothing.
//! Units are whatever the caller uses; the body layer works in metres.

use glam::DVec3;

/// A typed index into per-element data (issue #16, item 2): a `u32`
/// newtype per kind of element, so that a panel's local vertex cannot be
/// used where a garment-mesh vertex is meant. Every id type implements
/// [`MeshIndex`], indexes [`TiVec`](typed_index_collections::TiVec)s
/// (per-element data), prints as its number and serialises as it.
///
/// Conversion from `usize` truncates to 32 bits: every mesh that mints ids
/// refuses more than `u32::MAX` elements first ([`MeshError::TooLarge`] and
/// its counterparts in refine and flatten).
macro_rules! typed_id {
    ($(#[$meta:meta])* $name:ident) => {
        $(#[$meta])*
        #[derive(
            Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
        )]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The index as `usize`.
            #[inline]
            pub fn idx(self) -> usize {
                self.0 as usize
            }
        }

        impl From<usize> for $name {
            #[inline]
            fn from(i: usize) -> Self {
                debug_assert!(u32::try_from(i).is_ok(), "index {i} exceeds u32");
                Self(i as u32)
            }
        }

        impl From<$name> for usize {
            #[inline]
            fn from(i: $name) -> usize {
                i.0 as usize
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                self.0.fmt(f)
            }
        }

        impl $crate::geom::mesh::MeshIndex for $name {}
    };
}
pub(crate) use typed_id;

/// What every typed element id is (made by the crate's `typed_id!` macro): copyable, ordered,
/// printable, convertible to and from a `usize` position. The topology
/// checks ([`crate::geom::topology`]) are generic over it.
pub trait MeshIndex:
    Copy + Ord + std::hash::Hash + std::fmt::Debug + std::fmt::Display + From<usize> + Into<usize>
{
}

typed_id!(
    /// Index of a vertex of a mesh: a [`TriMesh`]'s, or the garment mesh a
    /// refinement makes ([`crate::refine::subdivide::RefineMesh`]), whose
    /// first vertices are the template's nodes in their order.
    VertexId
);

typed_id!(
    /// Index of a triangle of a mesh (a [`TriMesh`]'s, or the triangle list
    /// at hand: a panel's faces are numbered in [`crate::pattern::panels::Panel::triangles`]).
    FaceId
);

/// What is wrong with a mesh handed to [`TriMesh::new`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// No vertices or no triangles.
    #[error("the mesh is empty ({vertices} vertices, {triangles} triangles)")]
    Empty {
        /// Number of vertices given.
        vertices: usize,
        /// Number of triangles given.
        triangles: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// The offending vertex.
        vertex: u32,
    },
    /// A triangle names a vertex that does not exist.
    #[error("triangle {face} refers to vertex {index}, but the mesh has only {count} vertices")]
    IndexOutOfRange {
        /// The offending triangle.
        face: u32,
        /// The index it holds.
        index: u64,
        /// Number of vertices.
        count: usize,
    },
    /// A triangle uses the same vertex twice.
    #[error("triangle {face} repeats vertex {vertex}")]
    RepeatedVertex {
        /// The offending triangle.
        face: u32,
        /// The repeated vertex.
        vertex: u32,
    },
    /// More vertices or triangles than a `u32` index can hold.
    #[error("the mesh has too many elements ({count}) for 32-bit indices")]
    TooLarge {
        /// The element count.
        count: usize,
    },
}

/// An indexed triangle mesh. Immutable once validated.
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    positions: Vec<DVec3>,
    triangles: Vec<[VertexId; 3]>,
}

/// Axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Aabb {
    /// Extent along each axis.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }
    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        self.size().length()
    }
    /// Centre point.
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }
}

impl TriMesh {
    /// Validates and builds a mesh from raw positions and raw indices.
    ///
    /// Indices are `u64` so that out-of-range values from any source can be
    /// reported rather than truncated.
    pub fn from_raw(positions: Vec<DVec3>, triangles: &[[u64; 3]]) -> Result<Self, MeshError> {
        let n = positions.len();
        let mut tris = Vec::with_capacity(triangles.len());
        for (f, t) in triangles.iter().enumerate() {
            let face = u32::try_from(f).map_err(|_| MeshError::TooLarge { count: triangles.len() })?;
            let mut ids = [VertexId(0); 3];
            for (k, &i) in t.iter().enumerate() {
                if i >= n as u64 {
                    return Err(MeshError::IndexOutOfRange { face, index: i, count: n });
                }
                ids[k] = VertexId(i as u32);
            }
            tris.push(ids);
        }
        Self::new(positions, tris)
    }

    /// Validates and builds a mesh.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[VertexId; 3]>) -> Result<Self, MeshError> {
        if positions.is_empty() || triangles.is_empty() {
            return Err(MeshError::Empty { vertices: positions.len(), triangles: triangles.len() });
        }
        if positions.len() > u32::MAX as usize || triangles.len() > u32::MAX as usize {
            return Err(MeshError::TooLarge { count: positions.len().max(triangles.len()) });
        }
        if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NonFinite { vertex: v as u32 });
        }
        let n = positions.len();
        for (f, t) in triangles.iter().enumerate() {
            for v in t {
                if v.idx() >= n {
                    return Err(MeshError::IndexOutOfRange { face: f as u32, index: u64::from(v.0), count: n });
                }
            }
            if t[0] == t[1] || t[0] == t[2] {
                return Err(MeshError::RepeatedVertex { face: f as u32, vertex: t[0].0 });
            }
            if t[1] == t[2] {
                return Err(MeshError::RepeatedVertex { face: f as u32, vertex: t[1].0 });
            }
        }
        Ok(Self { positions, triangles })
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Triangles as vertex triples (counter-clockwise seen from outside).
    pub fn triangles(&self) -> &[[VertexId; 3]] {
        &self.triangles
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// Position of a vertex.
    #[inline]
    pub fn position(&self, v: VertexId) -> DVec3 {
        self.positions[v.idx()]
    }

    /// The three corner positions of a triangle.
    #[inline]
    pub fn corners(&self, f: FaceId) -> [DVec3; 3] {
        let t = self.triangles[f.idx()];
        [self.position(t[0]), self.position(t[1]), self.position(t[2])]
    }

    /// Twice the area vector of a triangle: `(b − a) × (c − a)`.
    #[inline]
    pub fn face_area_vector(&self, f: FaceId) -> DVec3 {
        let [a, b, c] = self.corners(f);
        (b - a).cross(c - a)
    }

    /// Bounding box of all vertices.
    pub fn aabb(&self) -> Aabb {
        let mut min = DVec3::splat(f64::INFINITY);
        let mut max = DVec3::splat(f64::NEG_INFINITY);
        for p in &self.positions {
            min = min.min(*p);
            max = max.max(*p);
        }
        Aabb { min, max }
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len()).map(|f| 0.5 * self.face_area_vector(FaceId(f as u32)).length()).sum()
    }

    /// Area-weighted unit vertex normals (zero for isolated vertices).
    pub fn vertex_normals(&self) -> Vec<DVec3> {
        let mut n = vec![DVec3::ZERO; self.positions.len()];
        for (f, t) in self.triangles.iter().enumerate() {
            let a = self.face_area_vector(FaceId(f as u32));
            for v in t {
                n[v.idx()] += a;
            }
        }
        for x in &mut n {
            *x = x.normalize_or_zero();
        }
        n
    }

    /// Returns the mesh with every position mapped by `f` (validated again).
    pub fn map_positions(&self, f: impl Fn(DVec3) -> DVec3) -> Result<Self, MeshError> {
        Self::new(self.positions.iter().map(|&p| f(p)).collect(), self.triangles.clone())
    }

    /// The regular icosahedron with vertices `(±1, ±φ, 0)` and cyclic
    /// permutations (φ the golden ratio): 12 vertices, 20 outward faces.
    /// A reference shape for tests and benchmarks.
    pub fn icosahedron() -> Self {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let positions = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .map(DVec3::from_array)
        .to_vec();
        const FACES: [[u32; 3]; 20] = [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        let triangles = FACES.iter().map(|t| t.map(VertexId)).collect();
        Self { positions, triangles }
    }

    /// Merges vertices closer than `tolerance` (grid hashing; exact
    /// duplicates always merge) and drops triangles that collapse.
    /// Scans often arrive with vertices split along UV or normal seams; the
    /// slicer needs them welded to chain sections across such seams.
    pub fn welded(&self, tolerance: f64) -> Result<Self, MeshError> {
        let (out, remap) = weld_positions(&self.positions, tolerance);
        let tris: Vec<[VertexId; 3]> = self
            .triangles
            .iter()
            .map(|t| t.map(|v| VertexId(remap[v.idx()])))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        Self::new(out, tris)
    }
}

/// Welds positions within `tolerance` (grid hashing, first come first
/// served); returns the kept positions and each input vertex's new index.
/// Cells are [`WELD_CELLS`] tolerances wide, so a point is near a cell face
/// (and its neighbour across it must be searched) only on the axes where it
/// lies within a tolerance of one: usually its own cell alone is searched.
pub(crate) fn weld_positions(positions: &[DVec3], tolerance: f64) -> (Vec<DVec3>, Vec<u32>) {
    let cell = (WELD_CELLS * tolerance).max(f64::MIN_POSITIVE);
    // only looked up, never iterated: the hasher cannot change the result
    let mut grid: rustc_hash::FxHashMap<[i64; 3], Vec<u32>> = rustc_hash::FxHashMap::default();
    grid.reserve(positions.len());
    let mut out: Vec<DVec3> = Vec::with_capacity(positions.len());
    let mut remap = Vec::with_capacity(positions.len());
    for &p in positions {
        let q = p / cell;
        let base = q.floor();
        let k = [base.x as i64, base.y as i64, base.z as i64];
        // per axis, the neighbouring cells within a tolerance: −1, +1 or none
        let near = |f: f64| -> [i64; 2] {
            let frac = f - f.floor();
            [if frac * WELD_CELLS <= 1.0 { -1 } else { 0 }, if (1.0 - frac) * WELD_CELLS <= 1.0 { 1 } else { 0 }]
        };
        let [nx, ny, nz] = [near(q.x), near(q.y), near(q.z)];
        let mut found = None;
        'search: for dx in nx[0]..=nx[1] {
            for dy in ny[0]..=ny[1] {
                for dz in nz[0]..=nz[1] {
                    if let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        if let Some(&j) = list.iter().find(|&&j| out[j as usize].distance(p) <= tolerance) {
                            found = Some(j);
                            break 'search;
                        }
                    }
                }
            }
        }
        remap.push(found.unwrap_or_else(|| {
            let j = out.len() as u32;
            out.push(p);
            grid.entry(k).or_default().push(j);
            j
        }));
    }
    (out, remap)
}

/// Width of a weld cell, in weld tolerances (see [`weld_positions`]).
pub(crate) const WELD_CELLS: f64 = 4.0;

/// Boundary loops of a triangle list (vertex ids), each run along its
/// faces' orientation: chains of half-edges with no opposite half-edge.
pub fn boundary_loops<V: Copy + Ord>(triangles: &[[V; 3]]) -> Vec<Vec<V>> {
    // every directed half-edge once, sorted
    let mut half: Vec<(V, V)> = triangles.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).collect();
    half.sort_unstable();
    half.dedup();
    // boundary half-edges (no opposite half-edge), sorted by tail then head
    let boundary: Vec<(V, V)> = half.iter().copied().filter(|&(a, b)| half.binary_search(&(b, a)).is_err()).collect();
    // per tail vertex, ascending: its range of boundary half-edges; a walk takes the
    // highest head left first (the range's end moves down)
    let mut tails: Vec<V> = Vec::new();
    let mut range: Vec<[usize; 2]> = Vec::new();
    for (i, &(a, _)) in boundary.iter().enumerate() {
        match tails.last() {
            Some(&last) if last == a => {
                if let Some(r) = range.last_mut() {
                    r[1] = i + 1;
                }
            }
            _ => {
                tails.push(a);
                range.push([i, i + 1]);
            }
        }
    }
    let mut loops = Vec::new();
    // the lowest tail with half-edges left starts the next loop; a tail's list only shrinks
    let mut cursor = 0;
    loop {
        while cursor < tails.len() && range[cursor][0] == range[cursor][1] {
            cursor += 1;
        }
        let Some(&start) = tails.get(cursor) else { break };
        let mut lp = vec![start];
        let mut at = start;
        while let Ok(g) = tails.binary_search(&at) {
            let [lo, hi] = range[g];
            if lo == hi {
                break;
            }
            range[g][1] = hi - 1;
            let to = boundary[hi - 1].1;
            if to == start {
                break;
            }
            lp.push(to);
            at = to;
        }
        loops.push(lp);
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::BTreeMap;

    /// The ordered-map walk `boundary_loops` replaced (issue #15), kept as
    /// the reference it must agree with loop for loop.
    fn boundary_loops_reference(triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
        let mut directed: BTreeMap<(u32, u32), usize> = BTreeMap::new();
        for t in triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        let mut next: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
        for &(a, b) in directed.keys() {
            if !directed.contains_key(&(b, a)) {
                next.entry(a).or_default().push(b);
            }
        }
        let mut loops = Vec::new();
        while let Some((&start, _)) = next.iter().find(|(_, v)| !v.is_empty()) {
            let mut lp = vec![start];
            let mut at = start;
            while let Some(to) = next.get_mut(&at).and_then(|v| v.pop()) {
                if to == start {
                    break;
                }
                lp.push(to);
                at = to;
            }
            loops.push(lp);
        }
        loops
    }

    /// The two triangles of each kept cell of a `w × h` grid of quads.
    fn grid_cells(w: u32, keep: &[bool]) -> Vec<[u32; 3]> {
        let v = |x: u32, y: u32| y * (w + 1) + x;
        keep.iter()
            .enumerate()
            .filter(|(_, &k)| k)
            .flat_map(|(c, _)| {
                let (x, y) = (c as u32 % w, c as u32 / w);
                [[v(x, y), v(x + 1, y), v(x + 1, y + 1)], [v(x, y), v(x + 1, y + 1), v(x, y + 1)]]
            })
            .collect()
    }

    #[test]
    fn boundary_loops_of_a_grid_with_a_hole_and_a_bowtie() {
        // 3 x 3 grid without its centre: an outer loop of 12 and a hole of 4
        let ring = grid_cells(3, &[true, true, true, true, false, true, true, true, true]);
        let loops = boundary_loops(&ring);
        assert_eq!(loops.iter().map(Vec::len).collect::<Vec<_>>(), vec![12, 4]);
        assert_eq!(loops, boundary_loops_reference(&ring));
        // two cells touching at one vertex (non-manifold): the walk still agrees
        let bowtie = grid_cells(2, &[true, false, false, true]);
        assert_eq!(boundary_loops(&bowtie), boundary_loops_reference(&bowtie));
        assert!(boundary_loops::<u32>(&[]).is_empty());
    }

    proptest! {
        /// Any subset of a grid's cells, any orientation of each triangle:
        /// the same loops as the reference, in the same order.
        #[test]
        fn boundary_loops_match_the_ordered_map_walk(
            keep in prop::collection::vec(any::<bool>(), 36),
            flip in prop::collection::vec(any::<bool>(), 72),
        ) {
            let mut tris = grid_cells(6, &keep);
            for (t, &f) in tris.iter_mut().zip(&flip) {
                if f {
                    t.swap(1, 2);
                }
            }
            prop_assert_eq!(boundary_loops(&tris), boundary_loops_reference(&tris));
        }
    }

    fn tet() -> TriMesh {
        TriMesh::from_raw(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap()
    }

    #[test]
    fn rejects_bad_input_with_named_element() {
        assert!(matches!(TriMesh::from_raw(vec![], &[]), Err(MeshError::Empty { .. })));
        let e = TriMesh::from_raw(vec![DVec3::ZERO, DVec3::X, DVec3::Y], &[[0, 1, 7]]).unwrap_err();
        assert_eq!(e, MeshError::IndexOutOfRange { face: 0, index: 7, count: 3 });
        let e =
            TriMesh::from_raw(vec![DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 0.0), DVec3::Y], &[[0, 1, 2]]).unwrap_err();
        assert_eq!(e, MeshError::NonFinite { vertex: 1 });
        let e = TriMesh::from_raw(vec![DVec3::ZERO, DVec3::X, DVec3::Y], &[[0, 1, 1]]).unwrap_err();
        assert_eq!(e, MeshError::RepeatedVertex { face: 0, vertex: 1 });
    }

    #[test]
    fn tetrahedron_area_and_outward_normals() {
        let m = tet();
        let expected = 1.5 + 3f64.sqrt() / 2.0;
        assert!((m.area() - expected).abs() < 1e-12);
        let n = m.vertex_normals();
        // vertex 3 = (0,0,1): its normal points away from the centroid
        let c = DVec3::splat(0.25);
        assert!(n[3].dot(DVec3::Z - c) > 0.0);
    }

    #[test]
    fn weld_merges_split_seams() {
        // two triangles sharing an edge, stored unwelded
        let m = TriMesh::from_raw(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X, DVec3::Y, DVec3::ONE],
            &[[0, 1, 2], [3, 5, 4]],
        )
        .unwrap();
        let w = m.welded(1e-9).unwrap();
        assert_eq!(w.vertex_count(), 4);
        assert_eq!(w.face_count(), 2);
    }
}
