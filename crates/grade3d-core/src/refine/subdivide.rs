//! Modified variational subdivision of the coarse garment mesh `M0` (seed 000 §5.1–5.3).
//!
//! # Contract
//!
//! **Method.** `L` times ([`RefineOptions::levels`]): split every triangle into four
//! ([`split_with_boundary`], §5.2), place the new vertices of free boundaries by the
//! modified Butterfly boundary mask (§5.3), then fair the free vertices with the
//! second-order umbrella operator ([`fair`], §5.1, Eqs. 10–12).
//!
//! **Split (§5.2).** Every edge `v_s v_e` gets one new vertex `v*`:
//! `p(v*) = (p(v_s) + p(v_e)) / 2` without a profile, `p(v*) = c(1/2)` with a profile
//! `c`; the profile is divided into `c_f(t) = c(t/2)` and `c_b(t) = c(1/2 + t/2)`
//! ([`Profile::split_half`], whose shared point is `c(1/2)` bit for bit), attached to
//! the two new edges. Face `f = [a, b, c]` with new vertices `m_ab, m_bc, m_ca` becomes
//! faces `4f … 4f+3`: `[a, m_ab, m_ca]`, `[m_ab, b, m_bc]`, `[m_ca, m_bc, c]`,
//! `[m_ab, m_bc, m_ca]` (orientation kept). The new vertex of the `k`-th edge of
//! [`edge_keys`] (undirected, `(min, max)`, ascending) gets id `n_old + k`.
//!
//! **Boundary (§5.3).** A new vertex on a boundary edge `v_1 v_2` *without* profile is
//! placed by the modified Butterfly boundary mask (seed 000 Fig. 16, the 4-point rule)
//! over the boundary polygon of the previous level, `v_0 → v_1 → v_2 → v_3`:
//!
//! ```text
//! p(v*) = (−p(v_0) + 9 p(v_1) + 9 p(v_2) − p(v_3)) / 16
//! ```
//!
//! and is then fixed. Where the polygon has no unique predecessor of `v_1` (or
//! successor of `v_2`) — only at a non-manifold boundary vertex, where two boundary
//! loops touch — the chain is treated as ending there and the quadratic through the
//! three remaining points is used, `(3 p(v_1) + 6 p(v_2) − p(v_3)) / 8` (mirrored at
//! the other end); with neither neighbour, the midpoint. Boundary edges *with* a
//! profile get `c(1/2)` like any profiled edge. With [`RefineOptions::butterfly_boundary`]
//! off, such vertices are midpoints and stay free, and the free boundary shrinks under
//! fairing (seed 000 Fig. 15 b).
//!
//! **Fairing (§5.1).** With `N(v)` the umbrella neighbours of `v` and `n = |N(v)|`,
//!
//! ```text
//! U(v)  = (1/n) Σ_{k ∈ N(v)} v_k − v                                   (Eq. 10)
//! U²(v) = (1/n) Σ_{k ∈ N(v)} U(v_k) − U(v)                              (Eq. 11)
//! v ← v − (1/ν) U²(v),   ν = 1 + (1/n_i) Σ_k 1/n_{i,k}                   (Eq. 12)
//! ```
//!
//! where `n_i` is the valence of `v` and `n_{i,k}` that of its `k`-th neighbour: `ν` is
//! the coefficient of `v` in `U²(v)`, so Eq. 12 solves the row `U²(v) = 0` of one free
//! vertex exactly (Kobbelt's umbrella algorithm, seed 000 ref. 11). Fixed vertices
//! (all coarse nodes, all vertices on profiles, Butterfly boundary vertices) never move
//! but enter the rows of their free neighbours. `N(v)` is the full 1-ring of every
//! vertex, boundary vertices included, so `n_i U²(v_i) = (L D⁻¹ L p)_i` (`L` the graph
//! Laplacian, `D` the valences): the gradient of the discrete thin-plate energy
//! `½ Σ_v n_v |U(v)|²`, symmetric positive definite on the free vertices of every
//! component that holds a fixed vertex. A free boundary vertex (only with the Butterfly
//! step off) thus has the one-sided umbrella of its ring, which pulls it into the
//! surface: the shrinking of seed 000 Fig. 15 b. (A 1D umbrella along the boundary
//! instead would fair the boundary as a curve of its own; measured on the test tube it
//! does not shrink at all, so it is not what §5.3 corrects, and it breaks the symmetry.)
//!
//! Two solvers of the same system ([`FairingSolver`]): **Gauss–Seidel**, the paper's
//! scheme (Eq. 12 for the free vertices in ascending id, each update using the newest
//! positions), and **conjugate gradients** (default) on the symmetric form,
//! preconditioned by its diagonal `n_i ν_i`, so that the preconditioned residual is the
//! Eq. 12 update `−U²(v_i)/ν_i`. Gauss–Seidel contracts slowly at fine levels (biharmonic
//! rows; the move per sweep underestimates the remaining error by `1 / (1 − ρ)`, `ρ` the
//! contraction per sweep): on the decoded straight skirt, level 3 is still 0.5 mm from the
//! solution after 200 sweeps, where conjugate gradients reach 2 µm in 71 iterations. Every
//! level starts from the previous faired level. A level stops after the first sweep
//! (iteration) whose largest update `|U²(v)|/ν` is at most [`RefineOptions::tolerance`] ×
//! the level's bounding-box diagonal, or after [`RefineOptions::max_sweeps`];
//! [`LevelReport`] says which. Conjugate gradients check that on the recomputed residual.
//!
//! After every sweep (iteration) the hook of [`refine`] may move vertices (the collision
//! step, issue #4) and **hold** free vertices for the rest of the level: held vertices
//! join the fixed ones, so the level solves the fairing system of the remaining free
//! vertices with the held ones as constraints (an active set that only grows; it is
//! reset at the next level, whose split starts from collision-free positions). Its moves
//! of fixed vertices are undone; conjugate gradients restart from the true residual of
//! the current free set whenever the hook moved or held a free vertex. Because the set
//! only grows, it settles after finitely many restarts and the reduced system converges
//! like the unconstrained one ([`LevelReport::held`], [`LevelReport::converged`]).
//!
//! **Preconditions.** An oriented manifold triangle mesh, possibly with boundary: every
//! edge in one or two faces, traversed in opposite directions by its two faces; no
//! repeated vertex in a face; finite positions; one fixed flag per vertex; profiles only
//! on edges of the mesh, keyed `(min, max)`, oriented from the smaller id, their ends
//! bit-identical to the edge's vertices (what [`RefineMesh::from_coarse`] and
//! [`split`] produce). Vertices in no face are allowed and never move.
//!
//! **Failure modes.** A typed [`RefineError`] naming the offending edge, face or vertex;
//! no panics. Memory grows as `4^L` × the coarse face count; vertex ids must fit `u32`.

use std::collections::BTreeMap;

use crate::geom::mesh::{FaceId, VertexId};
use crate::geom::topology::{check_edge_uses, triangle_edge_uses, MeshEdge, TopologyError};
use crate::refine::lineage::Lineage;
use crate::template::codec::CoarseMesh;
use crate::template::profile::Profile;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use typed_index_collections::{TiSlice, TiVec};

/// How the fairing system `U²(v) = 0` (free vertices) is solved (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FairingSolver {
    /// Gauss–Seidel: Eq. 12 applied to the free vertices in ascending id, each update
    /// using the newest positions (seed 000 §5.1, Kobbelt's umbrella algorithm).
    GaussSeidel,
    /// Conjugate gradients on the symmetric form `n_i U²(v_i) = (L D⁻¹ L p)_i`,
    /// preconditioned by its diagonal `n_i ν_i` (so the preconditioned residual is the
    /// Eq. 12 update); the same solution, far fewer iterations at fine levels.
    #[default]
    ConjugateGradient,
}

/// Knobs of the subdivision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RefineOptions {
    /// Subdivision levels `L` (count); `M_L` has `4^L` × the coarse faces. Default 3.
    pub levels: usize,
    /// Most fairing sweeps (Gauss–Seidel) or iterations (conjugate gradients) per level
    /// (count). Default 200.
    pub max_sweeps: usize,
    /// Fairing of a level stops after the first sweep (iteration) whose largest update
    /// `|U²(v)|/ν` is at most this fraction of the level's bounding-box diagonal (dimensionless; an
    /// absolute length in the mesh's unit if the diagonal is 0). Default 1e-7.
    pub tolerance: f64,
    /// New vertices on boundary edges without profile by the modified Butterfly
    /// boundary mask, then fixed (§5.3). Off: midpoints, free. Default on.
    pub butterfly_boundary: bool,
    /// Solver of the fairing system. Default [`FairingSolver::ConjugateGradient`].
    pub solver: FairingSolver,
    /// Sweeps of [`relax_tangentially`] after the last level (count; the grading
    /// pipeline runs them before the exact collision pass). Default 10.
    pub relax_sweeps: usize,
    /// Step `λ` of [`relax_tangentially`] (dimensionless, 0..1). Default 0.5.
    pub relax_step: f64,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            levels: 3,
            max_sweeps: 200,
            tolerance: 1e-7,
            butterfly_boundary: true,
            solver: FairingSolver::ConjugateGradient,
            relax_sweeps: 10,
            relax_step: 0.5,
        }
    }
}

/// Why subdivision failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RefineError {
    /// Not an oriented manifold: an edge of three or more faces, or one run
    /// twice in the same direction.
    #[error(transparent)]
    Topology(#[from] TopologyError<MeshEdge>),
    /// A face names a vertex that does not exist.
    #[error("face {face} names vertex {vertex}, but there are {count} vertices")]
    IndexOutOfRange {
        /// The face.
        face: FaceId,
        /// The vertex id.
        vertex: VertexId,
        /// Number of vertices.
        count: usize,
    },
    /// A face names a vertex twice.
    #[error("face {face} names vertex {vertex} twice")]
    DegenerateFace {
        /// The face.
        face: FaceId,
        /// The vertex id.
        vertex: VertexId,
    },
    /// A position is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinitePosition {
        /// The vertex id.
        vertex: VertexId,
    },
    /// `fixed` does not have one flag per vertex.
    #[error("{flags} fixed flags for {vertices} vertices")]
    FixedFlags {
        /// Number of vertices.
        vertices: usize,
        /// Number of flags.
        flags: usize,
    },
    /// The template's edge table and the coarse mesh's profiles differ in length.
    #[error("{edges} template edges but {profiles} profile entries")]
    EdgeTable {
        /// Number of edges given.
        edges: usize,
        /// Number of profile entries.
        profiles: usize,
    },
    /// A profile sits on a pair that is not an edge of the mesh (or a key not `(min, max)`).
    #[error("profile on {a}–{b}, which is not an edge of the mesh keyed (min, max)")]
    ProfileOnMissingEdge {
        /// First id of the key.
        a: VertexId,
        /// Second id of the key.
        b: VertexId,
    },
    /// A profile is unusable: its ends are not its edge's vertices, two profiles share
    /// an edge, or it cannot be reversed.
    #[error("profile on edge {a}–{b}: {reason}")]
    Profile {
        /// Smaller vertex id.
        a: VertexId,
        /// Larger vertex id.
        b: VertexId,
        /// What is wrong.
        reason: String,
    },
    /// The refined mesh would have more vertices than `u32` ids can name.
    #[error("{vertices} vertices exceed u32 vertex ids")]
    TooLarge {
        /// Vertices the split would produce.
        vertices: usize,
    },
}

/// A triangle mesh under refinement: positions, faces, which vertices are fixed,
/// and the profiles of its edges.
#[derive(Debug, Clone, PartialEq)]
pub struct RefineMesh {
    /// Vertex positions.
    pub positions: TiVec<VertexId, DVec3>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: TiVec<FaceId, [VertexId; 3]>,
    /// Per vertex: never moved by fairing (coarse nodes, profile and Butterfly vertices).
    pub fixed: TiVec<VertexId, bool>,
    /// Edge profiles, each oriented from the edge's lower vertex to its higher.
    pub edge_profiles: BTreeMap<MeshEdge, Profile>,
}

/// What [`refine`] made: the fine mesh `M_L`, how each level's fairing
/// went, and the lineage of its numbering (which vertex each split put on
/// each edge), which the pattern stage cuts panels and seams by.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The fine mesh.
    pub mesh: RefineMesh,
    /// Per level.
    pub levels: Vec<LevelReport>,
    /// The split vertices of every level.
    pub lineage: Lineage,
}

/// How one level's fairing went.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LevelReport {
    /// Level `j` of `M_j` (1 for the first split; 0 from a lone [`fair`]).
    pub level: usize,
    /// Faces of `M_j`.
    pub faces: usize,
    /// Gauss–Seidel sweeps or conjugate-gradient iterations done.
    pub fairing_sweeps: usize,
    /// Largest update `|U²(v)|/ν` of the last sweep (iteration) over the bounding-box
    /// diagonal (0 with no free vertex).
    pub final_update_rel: f64,
    /// Whether `final_update_rel` reached [`RefineOptions::tolerance`] (on the free
    /// vertices left once the hook has held some).
    pub converged: bool,
    /// Vertices the hook held for the rest of the level (the collision step's refused
    /// and pushed vertices); 0 without a hook.
    pub held: usize,
}

impl RefineMesh {
    /// The vertices along the refined profile of each coarse edge `a`–`b`
    /// of `pairs` (splits keep old ids, and every split of a profiled edge
    /// is profiled again), from `a` to `b`: the shortest path between them
    /// over profiled edges (breadth first; the adjacency is built once).
    /// `None` where no profiled path joins them.
    pub fn profile_chains(&self, pairs: &[(VertexId, VertexId)]) -> Vec<Option<Vec<VertexId>>> {
        let mut next: BTreeMap<VertexId, Vec<VertexId>> = BTreeMap::new();
        for &MeshEdge { a: x, b: y } in self.edge_profiles.keys() {
            next.entry(x).or_default().push(y);
            next.entry(y).or_default().push(x);
        }
        let chain = |a: VertexId, b: VertexId| -> Option<Vec<VertexId>> {
            let mut came: BTreeMap<VertexId, VertexId> = BTreeMap::from([(a, a)]);
            let mut queue = std::collections::VecDeque::from([a]);
            while let Some(v) = queue.pop_front() {
                if v == b {
                    let (mut path, mut at) = (vec![b], b);
                    while at != a {
                        at = *came.get(&at)?;
                        path.push(at);
                    }
                    path.reverse();
                    return Some(path);
                }
                for &w in next.get(&v).into_iter().flatten() {
                    if let std::collections::btree_map::Entry::Vacant(e) = came.entry(w) {
                        e.insert(v);
                        queue.push_back(w);
                    }
                }
            }
            None
        };
        pairs.iter().map(|&(a, b)| chain(a, b)).collect()
    }

    /// The mesh as a validated [`TriMesh`] (for measurements and exports).
    ///
    /// # Errors
    /// [`crate::geom::mesh::MeshError`] if a position is not finite or a triangle is invalid.
    pub fn to_tri_mesh(&self) -> Result<crate::geom::mesh::TriMesh, crate::geom::mesh::MeshError> {
        crate::geom::mesh::TriMesh::new(self.positions.raw.clone(), self.triangles.raw.clone())
    }

    /// The coarse mesh `M0` of a decoded template: all nodes fixed, every profile
    /// keyed `(min, max)` and oriented from the smaller id.
    ///
    /// `edges` is the template's edge table as `(start, end)`, in the order of
    /// `m.profiles` (`t.edges.iter().map(|e| (e.start, e.end))`).
    ///
    /// # Errors
    /// [`RefineError::EdgeTable`] for a length mismatch; a profile on a pair that is not a
    /// mesh edge, or whose ends are not its nodes, and every mesh error of the contract.
    pub fn from_coarse(m: &CoarseMesh, edges: &[(u32, u32)]) -> Result<Self, RefineError> {
        let node = VertexId;
        if edges.len() != m.profiles.len() {
            return Err(RefineError::EdgeTable { edges: edges.len(), profiles: m.profiles.len() });
        }
        let mut edge_profiles = BTreeMap::new();
        for (&(s, e), p) in edges.iter().zip(&m.profiles) {
            let Some(p) = p else { continue };
            let key = MeshEdge::new(node(s), node(e));
            let p = match s.cmp(&e) {
                std::cmp::Ordering::Less => p.clone(),
                std::cmp::Ordering::Greater => p.reversed(),
                std::cmp::Ordering::Equal => return Err(RefineError::ProfileOnMissingEdge { a: key.a, b: key.b }),
            };
            if edge_profiles.insert(key, p).is_some() {
                return Err(RefineError::Profile { a: key.a, b: key.b, reason: "two profiles on one edge".into() });
            }
        }
        let mesh = Self {
            positions: m.positions.iter().copied().collect(),
            triangles: m.triangles.iter().map(|t| t.map(node)).collect(),
            fixed: TiVec::from(vec![true; m.positions.len()]),
            edge_profiles,
        };
        Topology::of(&mesh)?;
        Ok(mesh)
    }
}

/// The undirected edges of `triangles`, ascending: the order in which
/// [`split`] numbers the new vertices (`n_old + k` for the `k`-th). Ids are not checked.
pub fn edge_keys(triangles: &TiSlice<FaceId, [VertexId; 3]>) -> Vec<MeshEdge> {
    let mut keys: Vec<MeshEdge> =
        triangles.iter().flat_map(|t| (0..3).map(move |k| MeshEdge::new(t[k], t[(k + 1) % 3]))).collect();
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// The 1-to-4 split of §5.2 alone: new boundary vertices without profile are midpoints
/// and free. Same as [`split_with_boundary`]`(mesh, false)`.
///
/// # Errors
/// Any violated precondition (module docs), as a [`RefineError`].
pub fn split(mesh: &RefineMesh) -> Result<RefineMesh, RefineError> {
    split_with_boundary(mesh, false)
}

/// The 1-to-4 split of §5.2 and, with `butterfly`, the boundary rule of §5.3 (module docs).
///
/// Old vertices keep their ids, positions and flags; new vertices on profiles (and, with
/// `butterfly`, on boundary edges without profile) are fixed, the others free.
///
/// # Errors
/// Any violated precondition (module docs), as a [`RefineError`]; [`RefineError::TooLarge`].
pub fn split_with_boundary(mesh: &RefineMesh, butterfly: bool) -> Result<RefineMesh, RefineError> {
    split_level(mesh, butterfly).map(|(m, _)| m)
}

/// The vertex one split put on each edge `(a, b)`, `a < b`: one level of a [`Lineage`].
type Midpoints = BTreeMap<MeshEdge, VertexId>;

/// [`split_with_boundary`], with the vertex it put on each edge.
fn split_level(mesh: &RefineMesh, butterfly: bool) -> Result<(RefineMesh, Midpoints), RefineError> {
    let topo = Topology::of(mesh)?;
    let n_old = mesh.positions.len();
    let total = n_old + topo.edges.len();
    if u32::try_from(total).is_err() {
        return Err(RefineError::TooLarge { vertices: total });
    }
    let mut positions = mesh.positions.clone();
    let mut fixed = mesh.fixed.clone();
    positions.reserve(topo.edges.len());
    fixed.reserve(topo.edges.len());
    let mut edge_profiles = BTreeMap::new();
    let mut new_id = BTreeMap::new();
    let p = &mesh.positions;
    for (k, (&key, edge)) in topo.edges.iter().enumerate() {
        let m = VertexId::from(n_old + k);
        let MeshEdge { a, b } = key;
        new_id.insert(key, m);
        if let Some(profile) = mesh.edge_profiles.get(&key) {
            let (front, back) = profile.split_half();
            positions.push(front.end());
            fixed.push(true);
            // m is above a and b: a profile keyed (b, m) runs from b to m
            edge_profiles.insert(MeshEdge { a: b, b: m }, back.reversed());
            edge_profiles.insert(MeshEdge { a, b: m }, front);
        } else if edge.faces == 1 && butterfly {
            let (x, y) = (edge.tail, edge.head);
            let before = topo.prev[x].map(|v| p[v]);
            let after = topo.next[y].map(|v| p[v]);
            positions.push(boundary_point(before, p[x], p[y], after));
            fixed.push(true);
        } else {
            positions.push(0.5 * (p[a] + p[b]));
            fixed.push(false);
        }
    }
    let mid = |a: VertexId, b: VertexId| new_id.get(&MeshEdge::new(a, b)).copied().unwrap_or(a);
    let mut triangles = TiVec::with_capacity(4 * mesh.triangles.len());
    for &[a, b, c] in &mesh.triangles {
        let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
        triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Ok((RefineMesh { positions, triangles, fixed, edge_profiles }, new_id))
}

/// The modified Butterfly boundary mask (4-point rule) for the new vertex between `x`
/// and `y`, with the fall-backs of the module docs when a neighbour is missing.
fn boundary_point(before: Option<DVec3>, x: DVec3, y: DVec3, after: Option<DVec3>) -> DVec3 {
    match (before, after) {
        (Some(w), Some(z)) => (9.0 * (x + y) - w - z) / 16.0,
        (None, Some(z)) => (3.0 * x + 6.0 * y - z) / 8.0,
        (Some(w), None) => (6.0 * x + 3.0 * y - w) / 8.0,
        (None, None) => 0.5 * (x + y),
    }
}

/// Discrete fairing (§5.1) of the free vertices of `mesh`, without a hook.
/// The report's `level` is 0.
///
/// # Errors
/// Any violated precondition (module docs), as a [`RefineError`].
pub fn fair(mesh: &mut RefineMesh, opts: &RefineOptions) -> Result<LevelReport, RefineError> {
    fair_level(mesh, opts, 0, &mut |_: &mut TiSlice<VertexId, DVec3>, _: &mut TiSlice<VertexId, bool>| {})
}

/// `opts.levels` × (split with the boundary rule, fairing) of `coarse` (module docs).
///
/// `after_sweep(positions, held)` runs after every fairing sweep (the collision step
/// pushes free vertices out of the body there); `held` marks the fixed vertices and those
/// held so far in this level, and the hook may hold more by setting their flag (module
/// docs: an active set). Its moves of fixed vertices are undone.
///
/// # Errors
/// Any violated precondition (module docs), as a [`RefineError`]; a non-finite position
/// left by the hook as [`RefineError::NonFinitePosition`].
pub fn refine<F: FnMut(&mut TiSlice<VertexId, DVec3>, &mut TiSlice<VertexId, bool>)>(
    coarse: RefineMesh,
    opts: &RefineOptions,
    mut after_sweep: F,
) -> Result<Refined, RefineError> {
    Topology::of(&coarse)?;
    let mut mesh = coarse;
    let mut levels = Vec::with_capacity(opts.levels);
    let mut lineage = Lineage::new();
    for level in 1..=opts.levels {
        let (fine, midpoints) = split_level(&mesh, opts.butterfly_boundary)?;
        mesh = fine;
        lineage.push_level(midpoints);
        levels.push(fair_level(&mut mesh, opts, level, &mut after_sweep)?);
    }
    Ok(Refined { mesh, levels, lineage })
}

/// Tangential relaxation (beyond the paper): `sweeps` Jacobi sweeps of
/// `v ← v + λ (U(v) − (U(v)·n_v) n_v)` over the free vertices, `U` the umbrella of
/// Eq. 10 and `n_v` the area-weighted vertex normal: vertices slide within the
/// surface towards the centre of their ring, which evens out the triangles the
/// fairing and the collision step leave skewed (slivers fold when the panel is
/// flattened), while the shape moves only to second order. Fixed vertices stay.
/// Returns the smallest triangle quality `2√3 A / Σ ℓ²` (1 for equilateral)
/// before and after.
///
/// # Errors
/// Any violated precondition (module docs), as a [`RefineError`].
pub fn relax_tangentially(mesh: &mut RefineMesh, sweeps: usize, lambda: f64) -> Result<(f64, f64), RefineError> {
    let ring = Topology::of(mesh)?.neighbours;
    let before = worst_quality(mesh);
    let n = mesh.positions.len();
    for _ in 0..sweeps {
        let mut normal: TiVec<VertexId, DVec3> = TiVec::from(vec![DVec3::ZERO; n]);
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| mesh.positions[v]);
            let w = (b - a).cross(c - a);
            for &v in t {
                normal[v] += w;
            }
        }
        let next: TiVec<VertexId, DVec3> = mesh
            .positions
            .iter_enumerated()
            .map(|(i, &p)| {
                if mesh.fixed[i] || ring[i].is_empty() {
                    return p;
                }
                let u = ring[i].iter().map(|&k| mesh.positions[k]).sum::<DVec3>() / ring[i].len() as f64 - p;
                let nv = normal[i].normalize_or_zero();
                p + lambda * (u - u.dot(nv) * nv)
            })
            .collect();
        mesh.positions = next;
    }
    Ok((before, worst_quality(mesh)))
}

/// Smallest triangle quality `2√3 A / (ℓ₁² + ℓ₂² + ℓ₃²)` (1 for equilateral, 0 degenerate).
pub fn worst_quality(mesh: &RefineMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v]);
            let l = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
            if l > 0.0 {
                2.0 * 3f64.sqrt() * (b - a).cross(c - a).length() / l
            } else {
                0.0
            }
        })
        .fold(1.0, f64::min)
}

/// Solves `U²(v) = 0` for the free vertices with `opts.solver` (module docs).
fn fair_level<F: FnMut(&mut TiSlice<VertexId, DVec3>, &mut TiSlice<VertexId, bool>)>(
    mesh: &mut RefineMesh,
    opts: &RefineOptions,
    level: usize,
    after_sweep: &mut F,
) -> Result<LevelReport, RefineError> {
    let ring = Topology::of(mesh)?.neighbours;
    // ν of Eq. 12: 1 + (1/n_i) Σ_k 1/n_{i,k}, the coefficient of v_i in U²(v_i)
    let nu: TiVec<VertexId, f64> = ring
        .iter()
        .map(|r| {
            if r.is_empty() {
                0.0
            } else {
                1.0 + r.iter().map(|&k| 1.0 / ring[k].len() as f64).sum::<f64>() / r.len() as f64
            }
        })
        .collect();
    let diagonal = bounding_diagonal(&mesh.positions);
    let mut report = LevelReport {
        level,
        faces: mesh.triangles.len(),
        fairing_sweeps: 0,
        final_update_rel: 0.0,
        converged: false,
        held: 0,
    };
    let pinned: Vec<(VertexId, DVec3)> =
        mesh.fixed.iter_enumerated().filter(|(_, &f)| f).map(|(i, _)| (i, mesh.positions[i])).collect();
    let mut system = System {
        ring: &ring,
        nu_all: &nu,
        free: Vec::new(),
        nu: Vec::new(),
        held: mesh.fixed.clone(),
        scale: if diagonal > 0.0 { diagonal } else { 1.0 },
        pinned: &pinned,
        hook: after_sweep,
    };
    system.collect_free();
    if system.free.is_empty() {
        report.converged = true;
        return Ok(report);
    }
    let pos = &mut mesh.positions;
    match opts.solver {
        FairingSolver::GaussSeidel => system.gauss_seidel(pos, opts, &mut report),
        FairingSolver::ConjugateGradient => system.conjugate_gradient(pos, opts, &mut report),
    }
    report.held = system.held.iter().zip(&mesh.fixed).filter(|(h, f)| **h && !**f).count();
    if let Some(v) = pos.position(|p| !p.is_finite()) {
        return Err(RefineError::NonFinitePosition { vertex: v });
    }
    Ok(report)
}

/// The fairing system of one level: rows `U²(v_i) = 0` of the free vertices.
struct System<'a, F> {
    /// Sorted 1-ring of every vertex.
    ring: &'a TiSlice<VertexId, Vec<VertexId>>,
    /// `ν_i` of Eq. 12 per vertex (0 for an empty ring).
    nu_all: &'a TiSlice<VertexId, f64>,
    /// Free vertices with a non-empty ring, ascending: neither fixed nor held.
    free: Vec<VertexId>,
    /// `ν_i` per free vertex.
    nu: Vec<f64>,
    /// Fixed or held by the hook, per vertex; what the hook sees and may set.
    held: TiVec<VertexId, bool>,
    /// Length the updates are measured against (bounding-box diagonal, or 1).
    scale: f64,
    /// Fixed vertices and their positions, restored after the hook.
    pinned: &'a [(VertexId, DVec3)],
    /// Called after every sweep / iteration.
    hook: &'a mut F,
}

impl<F: FnMut(&mut TiSlice<VertexId, DVec3>, &mut TiSlice<VertexId, bool>)> System<'_, F> {
    /// The free vertices (neither fixed nor held, with a ring) and their `ν`.
    fn collect_free(&mut self) {
        self.free =
            self.held.iter_enumerated().filter(|&(i, &h)| !h && !self.ring[i].is_empty()).map(|(i, _)| i).collect();
        self.nu = self.free.iter().map(|&i| self.nu_all[i]).collect();
    }

    /// `U(v_k)` (Eq. 10).
    fn umbrella(&self, pos: &TiSlice<VertexId, DVec3>, k: VertexId) -> DVec3 {
        let ring = &self.ring[k];
        if ring.is_empty() {
            return DVec3::ZERO;
        }
        ring.iter().map(|&j| pos[j]).sum::<DVec3>() / ring.len() as f64 - pos[k]
    }

    /// Runs the hook, restores the fixed vertices and drops newly held vertices from
    /// the free set; whether the system changed (a free vertex moved or was held).
    fn after_sweep(&mut self, pos: &mut TiSlice<VertexId, DVec3>) -> bool {
        let before: Vec<DVec3> = self.free.iter().map(|&i| pos[i]).collect();
        (self.hook)(pos, &mut self.held);
        for &(i, p) in self.pinned {
            pos[i] = p;
            self.held[i] = true;
        }
        let moved = self.free.iter().zip(&before).any(|(&i, &b)| pos[i] != b);
        if self.free.iter().any(|&i| self.held[i]) {
            self.collect_free();
            return true;
        }
        moved
    }

    /// Eq. 12 for every free vertex in ascending id, in place, per sweep.
    fn gauss_seidel(&mut self, pos: &mut TiSlice<VertexId, DVec3>, opts: &RefineOptions, report: &mut LevelReport) {
        while report.fairing_sweeps < opts.max_sweeps {
            let mut largest = 0.0_f64;
            for (&i, &nu_i) in self.free.iter().zip(&self.nu) {
                let ring = &self.ring[i];
                let mean = ring.iter().map(|&k| self.umbrella(pos, k)).sum::<DVec3>() / ring.len() as f64;
                let step = (mean - self.umbrella(pos, i)) / nu_i;
                pos[i] -= step;
                largest = largest.max(step.length());
            }
            self.after_sweep(pos);
            report.fairing_sweeps += 1;
            report.final_update_rel = largest / self.scale;
            if report.final_update_rel <= opts.tolerance || self.free.is_empty() {
                report.converged = true;
                return;
            }
        }
    }

    /// `n_i U²` of the field `q` at every free vertex, `(L D⁻¹ L q)_i`, into `out`
    /// (`u` is scratch for the umbrella of every vertex).
    fn apply(&self, q: &TiSlice<VertexId, DVec3>, u: &mut TiSlice<VertexId, DVec3>, out: &mut [DVec3]) {
        for (k, uk) in u.iter_mut_enumerated() {
            *uk = self.umbrella(q, k);
        }
        for (o, &i) in out.iter_mut().zip(&self.free) {
            *o = self.ring[i].iter().map(|&k| u[k]).sum::<DVec3>() - self.ring[i].len() as f64 * u[i];
        }
    }

    /// Preconditioned residual `z_i = −U²(v_i) / ν_i` (the Eq. 12 update) from `r_i = −n_i U²(v_i)`.
    fn precondition(&self, r: &[DVec3], z: &mut [DVec3]) {
        for ((zj, &rj), (&i, &nu_i)) in z.iter_mut().zip(r).zip(self.free.iter().zip(&self.nu)) {
            *zj = rj / (self.ring[i].len() as f64 * nu_i);
        }
    }

    /// Diagonally preconditioned conjugate gradients, the three coordinates as three
    /// independent systems; restarted from the true residual (of the current free set)
    /// when the hook moves or holds a free vertex, and before accepting convergence.
    fn conjugate_gradient(
        &mut self,
        pos: &mut TiSlice<VertexId, DVec3>,
        opts: &RefineOptions,
        report: &mut LevelReport,
    ) {
        let n = pos.len();
        let mut u: TiVec<VertexId, DVec3> = TiVec::from(vec![DVec3::ZERO; n]);
        let mut q: TiVec<VertexId, DVec3> = TiVec::from(vec![DVec3::ZERO; n]);
        let (mut r, mut z, mut p, mut ap) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut restart = true;
        let mut rz = DVec3::ZERO;
        loop {
            if restart {
                let m = self.free.len();
                for v in [&mut r, &mut z, &mut p, &mut ap] {
                    v.clear();
                    v.resize(m, DVec3::ZERO);
                }
                self.apply(pos, &mut u, &mut r);
                r.iter_mut().for_each(|x| *x = -*x);
                self.precondition(&r, &mut z);
                p.copy_from_slice(&z);
                rz = dot(&r, &z);
            }
            let largest = z.iter().map(|x| x.length()).fold(0.0, f64::max);
            report.final_update_rel = largest / self.scale;
            if report.final_update_rel <= opts.tolerance {
                if restart {
                    report.converged = true;
                    return;
                }
                restart = true;
                continue;
            }
            if report.fairing_sweeps >= opts.max_sweeps {
                return;
            }
            q.iter_mut().for_each(|x| *x = DVec3::ZERO);
            for (&i, &pj) in self.free.iter().zip(&p) {
                q[i] = pj;
            }
            self.apply(&q, &mut u, &mut ap);
            let alpha = ratio(rz, dot(&p, &ap));
            for (j, &i) in self.free.iter().enumerate() {
                pos[i] += alpha * p[j];
                r[j] -= alpha * ap[j];
            }
            report.fairing_sweeps += 1;
            restart = self.after_sweep(pos);
            if !restart {
                self.precondition(&r, &mut z);
                let rz_new = dot(&r, &z);
                let beta = ratio(rz_new, rz);
                for (pj, &zj) in p.iter_mut().zip(&z) {
                    *pj = zj + beta * *pj;
                }
                rz = rz_new;
            }
        }
    }
}

/// Per-coordinate dot product of two fields.
fn dot(a: &[DVec3], b: &[DVec3]) -> DVec3 {
    a.iter().zip(b).map(|(&x, &y)| x * y).sum()
}

/// Per-coordinate `a / b`, 0 where that is not finite (a coordinate already solved).
fn ratio(a: DVec3, b: DVec3) -> DVec3 {
    let x = a / b;
    DVec3::select(x.is_finite_mask(), x, DVec3::ZERO)
}

/// Length of the diagonal of the axis-aligned bounding box (0 for no points).
fn bounding_diagonal(points: &TiSlice<VertexId, DVec3>) -> f64 {
    let Some(&first) = points.first() else { return 0.0 };
    let (lo, hi) = points.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    lo.distance(hi)
}

/// The profile `c(1 − u)`: points and knots reversed (`u → 1 − u`), slopes negated.
///
/// One undirected edge: how many faces use it and its direction in the first.
#[derive(Debug, Clone, Copy)]
struct EdgeUse {
    faces: usize,
    tail: VertexId,
    head: VertexId,
}

/// Adjacency of a validated [`RefineMesh`].
struct Topology {
    /// Undirected edges.
    edges: BTreeMap<MeshEdge, EdgeUse>,
    /// Sorted 1-ring of every vertex.
    neighbours: TiVec<VertexId, Vec<VertexId>>,
    /// The unique boundary successor (head of the one boundary half-edge leaving the vertex).
    next: TiVec<VertexId, Option<VertexId>>,
    /// The unique boundary predecessor.
    prev: TiVec<VertexId, Option<VertexId>>,
}

impl Topology {
    /// Checks every precondition of the module docs and builds the adjacency.
    fn of(mesh: &RefineMesh) -> Result<Self, RefineError> {
        let n = mesh.positions.len();
        if mesh.fixed.len() != n {
            return Err(RefineError::FixedFlags { vertices: n, flags: mesh.fixed.len() });
        }
        if let Some(v) = mesh.positions.position(|p| !p.is_finite()) {
            return Err(RefineError::NonFinitePosition { vertex: v });
        }
        for (face, t) in mesh.triangles.iter_enumerated() {
            for k in 0..3 {
                let v = t[k];
                if v.idx() >= n {
                    return Err(RefineError::IndexOutOfRange { face, vertex: v, count: n });
                }
                if t[(k + 1) % 3] == v {
                    return Err(RefineError::DegenerateFace { face, vertex: v });
                }
            }
        }
        let mut edges = BTreeMap::new();
        let mut neighbours: TiVec<VertexId, Vec<VertexId>> = TiVec::from(vec![Vec::new(); n]);
        let (mut next, mut prev): (TiVec<VertexId, _>, TiVec<VertexId, _>) =
            (vec![None; n].into(), vec![None; n].into());
        let (mut out_count, mut in_count): (TiVec<VertexId, usize>, TiVec<VertexId, usize>) =
            (vec![0; n].into(), vec![0; n].into());
        for e in check_edge_uses(triangle_edge_uses(&mesh.triangles.raw))? {
            let MeshEdge { a, b } = e.edge;
            // the direction of the first face's use (the boundary's, on a boundary edge)
            let (tail, head) = if e.first.forward { (a, b) } else { (b, a) };
            let faces = 1 + usize::from(e.second.is_some());
            edges.insert(e.edge, EdgeUse { faces, tail, head });
            neighbours[a].push(b);
            neighbours[b].push(a);
            if faces == 1 {
                next[tail] = Some(head);
                out_count[tail] += 1;
                prev[head] = Some(tail);
                in_count[head] += 1;
            }
        }
        for v in (0..n).map(VertexId::from) {
            neighbours[v].sort_unstable();
            if out_count[v] != 1 {
                next[v] = None;
            }
            if in_count[v] != 1 {
                prev[v] = None;
            }
        }
        for (&key, profile) in &mesh.edge_profiles {
            let MeshEdge { a, b } = key;
            if !edges.contains_key(&key) {
                return Err(RefineError::ProfileOnMissingEdge { a, b });
            }
            if profile.start() != mesh.positions[a] || profile.end() != mesh.positions[b] {
                return Err(RefineError::Profile { a, b, reason: "its ends are not the edge's vertices".into() });
            }
        }
        Ok(Self { edges, neighbours, next, prev })
    }
}

#[cfg(test)]
mod tests {
    use std::sync::OnceLock;

    use crate::template::codec::decode;
    use crate::template::library::{builtin, reference_body};
    use proptest::prelude::*;

    use super::*;

    /// Plain test ids as the mesh's typed ones.
    fn v(i: u32) -> VertexId {
        VertexId(i)
    }

    /// Test triangles in typed ids.
    fn tris(t: &[[u32; 3]]) -> TiVec<FaceId, [VertexId; 3]> {
        t.iter().map(|f| f.map(VertexId)).collect()
    }

    /// A regular icosahedron (20 faces, outward).
    fn icosahedron() -> RefineMesh {
        let m = crate::geom::mesh::TriMesh::icosahedron();
        let n = m.vertex_count();
        RefineMesh {
            positions: m.positions().to_vec().into(),
            triangles: m.triangles().to_vec().into(),
            fixed: vec![true; n].into(),
            edge_profiles: BTreeMap::new(),
        }
    }

    /// A `k × k` grid of unit spacing in the plane z = 0; boundary vertices fixed.
    fn grid(k: u32) -> RefineMesh {
        let mut positions = Vec::new();
        let mut fixed = Vec::new();
        for j in 0..k {
            for i in 0..k {
                positions.push(DVec3::new(i as f64, j as f64, 0.0));
                fixed.push(i == 0 || j == 0 || i == k - 1 || j == k - 1);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..k - 1 {
            for i in 0..k - 1 {
                let v = j * k + i;
                triangles.push([v, v + 1, v + k + 1]);
                triangles.push([v, v + k + 1, v + k]);
            }
        }
        RefineMesh {
            positions: positions.into(),
            triangles: tris(&triangles),
            fixed: fixed.into(),
            edge_profiles: BTreeMap::new(),
        }
    }

    /// Nodes around the tube of [`tube`].
    const AROUND: u32 = 8;
    /// Tube radius and height, metres (a waist-sized band).
    const RADIUS: f64 = 0.15;
    const HEIGHT: f64 = 0.2;

    /// An open cylinder band: `AROUND` nodes on the ring y = 0 (ids 0…7) and on y = HEIGHT
    /// (ids 8…15), all fixed, no profiles, outward orientation.
    fn tube() -> RefineMesh {
        let mut positions = Vec::new();
        for y in [0.0, HEIGHT] {
            for i in 0..AROUND {
                let a = std::f64::consts::TAU * i as f64 / AROUND as f64;
                positions.push(DVec3::new(RADIUS * a.cos(), y, RADIUS * a.sin()));
            }
        }
        let mut triangles = Vec::new();
        for i in 0..AROUND {
            let j = (i + 1) % AROUND;
            triangles.push([i, i + AROUND, j + AROUND]);
            triangles.push([i, j + AROUND, j]);
        }
        RefineMesh {
            positions: positions.into(),
            triangles: tris(&triangles),
            fixed: vec![true; 16].into(),
            edge_profiles: BTreeMap::new(),
        }
    }

    /// The boundary loop of `mesh` through vertex `start`, in boundary order.
    fn boundary_loop(mesh: &RefineMesh, start: VertexId) -> Vec<VertexId> {
        let topo = Topology::of(mesh).expect("valid mesh");
        let mut lp = vec![start];
        let mut v = topo.next[start].expect("boundary vertex");
        while v != start {
            lp.push(v);
            v = topo.next[v].expect("manifold boundary");
        }
        lp
    }

    /// Closed polygon length.
    fn loop_length(p: &[DVec3]) -> f64 {
        (0..p.len()).map(|i| p[i].distance(p[(i + 1) % p.len()])).sum()
    }

    /// The decoded straight skirt as `M0`, its coarse profiles and its edge table.
    type Skirt = (RefineMesh, Vec<Option<Profile>>, Vec<(u32, u32)>);

    /// The straight skirt decoded on the reference body.
    fn skirt() -> &'static Skirt {
        static SKIRT: OnceLock<Skirt> = OnceLock::new();
        SKIRT.get_or_init(|| {
            let t = builtin().expect("library").into_iter().find(|t| t.name == "straight-skirt").expect("skirt");
            let body = reference_body().expect("reference body");
            let coarse = decode(&t, &body, t.defaults.relocation).expect("decode");
            let edges: Vec<(u32, u32)> = t.edges.iter().map(|e| (e.start, e.end)).collect();
            let mesh = RefineMesh::from_coarse(&coarse, &edges).expect("coarse mesh");
            (mesh, coarse.profiles, edges)
        })
    }

    fn no_hook(_: &mut TiSlice<VertexId, DVec3>, _: &mut TiSlice<VertexId, bool>) {}

    /// Total area of the triangles.
    fn area(mesh: &RefineMesh) -> f64 {
        let p = &mesh.positions;
        mesh.triangles.iter().map(|t| 0.5 * (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).length()).sum()
    }

    #[test]
    fn each_level_multiplies_faces_by_four() {
        let opts = RefineOptions::default();
        let Refined { mesh: fine, levels: reports, .. } = refine(icosahedron(), &opts, no_hook).expect("refine");
        let faces: Vec<usize> = reports.iter().map(|r| r.faces).collect();
        assert_eq!(faces, [80, 320, 1280]);
        assert_eq!(fine.triangles.len(), 1280);
        // closed genus 0: V = F/2 + 2
        assert_eq!(fine.positions.len(), 642);
        Topology::of(&fine).expect("oriented manifold");
        let (mesh, _, _) = skirt();
        let Refined { mesh: fine, levels: reports, .. } = refine(mesh.clone(), &opts, no_hook).expect("refine skirt");
        let faces: Vec<usize> = reports.iter().map(|r| r.faces).collect();
        let f0 = mesh.triangles.len();
        assert_eq!(faces, [4 * f0, 16 * f0, 64 * f0]);
        assert_eq!(fine.triangles.len(), 64 * f0);
        Topology::of(&fine).expect("refined skirt is an oriented manifold");
    }

    #[test]
    fn split_keeps_orientation_and_numbers_new_vertices_by_edge_keys() {
        let mesh = icosahedron();
        let fine = split(&mesh).expect("split");
        let keys = edge_keys(&mesh.triangles);
        assert_eq!(fine.positions.len(), mesh.positions.len() + keys.len());
        for (k, &MeshEdge { a, b }) in keys.iter().enumerate() {
            let m = fine.positions.raw[mesh.positions.len() + k];
            assert_eq!(m, 0.5 * (mesh.positions[a] + mesh.positions[b]));
            assert!(!fine.fixed.raw[mesh.positions.len() + k]);
        }
        // every child keeps its parent's normal direction (flat split: parallel normals)
        let normal = |m: &RefineMesh, t: [VertexId; 3]| {
            let p = |v: VertexId| m.positions[v];
            (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]))
        };
        for (f, &t) in mesh.triangles.iter().enumerate() {
            for c in 0..4 {
                let child = fine.triangles.raw[4 * f + c];
                assert!(normal(&fine, child).dot(normal(&mesh, t)) > 0.0, "face {f} child {c}");
            }
        }
    }

    #[test]
    fn a_faired_planar_patch_stays_planar() {
        let mut mesh = grid(33);
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut rand = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (p, &f) in mesh.positions.iter_mut().zip(&mesh.fixed) {
            if !f {
                *p += DVec3::new(0.4 * rand(), 0.4 * rand(), 0.0);
            }
        }
        for solver in [FairingSolver::ConjugateGradient, FairingSolver::GaussSeidel] {
            let mut m = mesh.clone();
            let opts = RefineOptions { solver, max_sweeps: 2000, ..RefineOptions::default() };
            let report = fair(&mut m, &opts).expect("fair");
            println!("planar grid 33×33 (961 free), {solver:?}: {report:?}");
            assert_eq!(report.converged, report.final_update_rel <= opts.tolerance);
            if solver == FairingSolver::ConjugateGradient {
                assert!(report.converged);
            }
            let worst = m.positions.iter().map(|p| p.z.abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-12, "z off the plane by {worst}");
        }
    }

    #[test]
    fn vertices_on_profiles_lie_on_the_coarse_profile() {
        let (coarse, profiles, edges) = skirt();
        let opts = RefineOptions::default();
        // which coarse edge every profiled edge descends from
        let mut lineage: BTreeMap<MeshEdge, usize> = BTreeMap::new();
        for (e, &(s, t)) in edges.iter().enumerate() {
            if profiles[e].is_some() {
                lineage.insert(MeshEdge::new(v(s), v(t)), e);
            }
        }
        let mut origin: Vec<(VertexId, usize)> = Vec::new();
        let mut mesh = coarse.clone();
        for level in 1..=opts.levels {
            let n_old = mesh.positions.len();
            let keys = edge_keys(&mesh.triangles);
            mesh = split_with_boundary(&mesh, opts.butterfly_boundary).expect("split");
            let mut next = BTreeMap::new();
            for (k, key) in keys.iter().enumerate() {
                if let Some(&e) = lineage.get(key) {
                    let m = VertexId::from(n_old + k);
                    assert!(mesh.fixed[m]);
                    next.insert(MeshEdge::new(key.a, m), e);
                    next.insert(MeshEdge::new(key.b, m), e);
                    origin.push((m, e));
                }
            }
            assert_eq!(next.keys().collect::<Vec<_>>(), mesh.edge_profiles.keys().collect::<Vec<_>>());
            lineage = next;
            fair_level(&mut mesh, &opts, level, &mut no_hook).expect("fair");
        }
        let diagonal = bounding_diagonal(&mesh.positions);
        let worst = origin
            .iter()
            .map(|&(v, e)| profiles[e].as_ref().map_or(f64::INFINITY, |c| c.closest_point(mesh.positions[v]).distance))
            .fold(0.0, f64::max);
        println!(
            "profile fidelity: {} vertices on {} coarse profiles, max distance {worst:.3e} m = {:.3e} × diagonal",
            origin.len(),
            profiles.iter().flatten().count(),
            worst / diagonal
        );
        assert!(worst <= 1e-9 * diagonal);
        let Refined { mesh: fine, levels: _, .. } = refine(coarse.clone(), &opts, no_hook).expect("refine");
        assert_eq!(fine, mesh, "refine() is the same split/fair sequence");
    }

    #[test]
    fn fairing_convergence_is_reported() {
        let (mesh, _, _) = skirt();
        let mut results = Vec::new();
        for solver in [FairingSolver::ConjugateGradient, FairingSolver::GaussSeidel] {
            let opts = RefineOptions { solver, ..RefineOptions::default() };
            let Refined { mesh: fine, levels: reports, .. } = refine(mesh.clone(), &opts, no_hook).expect("refine");
            for r in &reports {
                assert_eq!(r.converged, r.final_update_rel <= opts.tolerance);
            }
            results.push((solver, fine, reports));
        }
        // reference: the last level solved to rounding
        let mut reference = results[0].1.clone();
        let tight = RefineOptions { tolerance: 1e-14, max_sweeps: 10_000, ..RefineOptions::default() };
        let r = fair(&mut reference, &tight).expect("reference");
        assert!(r.converged);
        let diagonal = bounding_diagonal(&reference.positions);
        println!("skirt reference: {r:?}, diagonal {diagonal:.3} m");
        for (solver, fine, reports) in &results {
            for r in reports {
                println!(
                    "skirt {solver:?} level {}: {} faces, {} sweeps, final update {:.2e} × diagonal, converged {}",
                    r.level, r.faces, r.fairing_sweeps, r.final_update_rel, r.converged
                );
            }
            let err = fine.positions.iter().zip(&reference.positions).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
            println!("skirt {solver:?}: max distance from the fully converged level 3: {err:.3e} m");
        }
        let (_, cg, cg_reports) = &results[0];
        assert!(cg_reports.iter().all(|r| r.converged));
        let err = cg.positions.iter().zip(&reference.positions).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
        assert!(err <= 1e-5 * diagonal, "CG result {err} m from the solution");
    }

    /// Figures of one boundary ring of the refined tube: (length, coarse polygon length,
    /// largest distance out of the ring's plane, mean radius / RADIUS).
    fn ring_figures(mesh: &RefineMesh, start: VertexId, y: f64) -> (f64, f64, f64, f64) {
        let lp = boundary_loop(mesh, start);
        let pts: Vec<DVec3> = lp.iter().map(|&v| mesh.positions[v]).collect();
        let coarse: Vec<VertexId> = lp.iter().copied().filter(|&v| v.0 < 2 * AROUND).collect();
        assert_eq!(coarse.len(), AROUND as usize, "the boundary passes through every coarse node");
        let coarse_pts: Vec<DVec3> = coarse.iter().map(|&v| mesh.positions[v]).collect();
        let sag = pts.iter().map(|p| (p.y - y).abs()).fold(0.0, f64::max);
        let radius = pts.iter().map(|p| p.x.hypot(p.z)).sum::<f64>() / pts.len() as f64 / RADIUS;
        (loop_length(&pts), loop_length(&coarse_pts), sag, radius)
    }

    #[test]
    fn butterfly_boundary_prevents_shrinking() {
        let coarse = tube();
        let coarse_area = area(&coarse);
        let mut figures = Vec::new();
        for butterfly in [true, false] {
            let opts = RefineOptions { butterfly_boundary: butterfly, ..RefineOptions::default() };
            let Refined { mesh: fine, levels: reports, .. } =
                refine(coarse.clone(), &opts, no_hook).expect("refine tube");
            assert!(reports.iter().all(|r| r.converged));
            let mut sags = Vec::new();
            for (start, y) in [(v(0), 0.0), (v(AROUND), HEIGHT)] {
                let (len, coarse_len, sag, radius) = ring_figures(&fine, start, y);
                println!(
                    "tube, butterfly {butterfly:5}: ring y = {y} m: length {len:.4} m (coarse polygon {coarse_len:.4}, \
                     circle {:.4}), largest sag into the band {:.2} mm, mean radius {radius:.4} R",
                    std::f64::consts::TAU * RADIUS,
                    sag * 1e3,
                );
                assert!(len >= coarse_len);
                sags.push(sag);
            }
            let a = area(&fine);
            println!(
                "tube, butterfly {butterfly:5}: area {a:.5} m² (coarse {coarse_area:.5}, cylinder {:.5})",
                std::f64::consts::TAU * RADIUS * HEIGHT
            );
            figures.push((sags.into_iter().fold(0.0, f64::max), a));
        }
        let ((sag_on, area_on), (sag_off, area_off)) = (figures[0], figures[1]);
        // with the mask the boundary stays on the coarse boundary's plane (the 4-point rule
        // of coplanar points); without it the boundary is pulled into the band
        assert!(sag_on <= 1e-12 * HEIGHT);
        assert!(area_on >= coarse_area);
        assert!(sag_off >= 0.05 * HEIGHT, "no visible shrinking without the mask: {sag_off}");
        assert!(area_off < area_on);
    }

    #[test]
    fn butterfly_mask_is_the_four_point_rule_of_the_previous_boundary() {
        let coarse = tube();
        let fine = split_with_boundary(&coarse, true).expect("split");
        let keys = edge_keys(&coarse.triangles);
        let p = |i: u32| coarse.positions[v(i)];
        // boundary edge 0–1 of the ring y = 0, whose polygon runs … 2 → 1 → 0 → 7 … or the reverse
        let k = keys.iter().position(|&e| e == MeshEdge::new(v(0), v(1))).expect("edge 0–1");
        let m = fine.positions.raw[coarse.positions.len() + k];
        assert!(fine.fixed.raw[coarse.positions.len() + k]);
        let expected = (9.0 * (p(0) + p(1)) - p(7) - p(2)) / 16.0;
        assert!(m.distance(expected) <= 1e-15, "{m} vs {expected}");
        // the straight-line case is the midpoint, the chain-end rules reproduce quadratics
        let q = |t: f64| DVec3::new(t, t * t, 0.0);
        let line = |t: f64| DVec3::new(t, 2.0 * t, -t);
        let mid = boundary_point(Some(line(-1.0)), line(0.0), line(1.0), Some(line(2.0)));
        assert!(mid.distance(line(0.5)) <= 1e-15);
        assert!(boundary_point(None, q(0.0), q(1.0), Some(q(2.0))).distance(q(0.5)) <= 1e-15);
        assert!(boundary_point(Some(q(-1.0)), q(0.0), q(1.0), None).distance(q(0.5)) <= 1e-15);
        assert_eq!(boundary_point(None, q(0.0), q(1.0), None), 0.5 * (q(0.0) + q(1.0)));
    }

    #[test]
    fn the_hook_runs_after_every_sweep_and_cannot_move_fixed_vertices() {
        let (mesh, _, _) = skirt();
        let opts = RefineOptions::default();
        let mut calls = 0;
        let Refined { mesh: fine, levels: reports, .. } =
            refine(mesh.clone(), &opts, |pos: &mut TiSlice<VertexId, DVec3>, fixed: &mut TiSlice<VertexId, bool>| {
                calls += 1;
                for (p, &f) in pos.iter_mut().zip(fixed.iter()) {
                    if f {
                        *p += DVec3::ONE;
                    }
                }
            })
            .expect("refine");
        assert_eq!(calls, reports.iter().map(|r| r.fairing_sweeps).sum::<usize>());
        let Refined { mesh: plain, levels: _, .. } = refine(mesh.clone(), &opts, no_hook).expect("refine");
        assert_eq!(fine, plain);
    }

    #[test]
    fn held_vertices_stay_put_and_the_rest_converges() {
        // the hook holds every free vertex below the skirt's mid-height on its first
        // sight of it (an obstacle's active set): held vertices never move again, the
        // level still converges on the rest, and the report counts them
        let (mesh, _, _) = skirt();
        let opts = RefineOptions::default();
        let mid = mesh.positions.iter().map(|p| p.y).sum::<f64>() / mesh.positions.len() as f64;
        let mut first_held: TiVec<VertexId, Option<DVec3>> = TiVec::new();
        let mut moved_after_hold = 0usize;
        let Refined { mesh: _, levels: reports, .. } =
            refine(mesh.clone(), &opts, |pos: &mut TiSlice<VertexId, DVec3>, held: &mut TiSlice<VertexId, bool>| {
                if first_held.len() != pos.len() {
                    first_held = vec![None; pos.len()].into();
                }
                for (i, p) in pos.iter_enumerated() {
                    match first_held[i] {
                        Some(q) if q != *p => moved_after_hold += 1,
                        Some(_) => {}
                        None if !held[i] && p.y < mid => {
                            held[i] = true;
                            first_held[i] = Some(*p);
                        }
                        None => {}
                    }
                }
            })
            .expect("refine");
        assert_eq!(moved_after_hold, 0, "a held vertex moved");
        assert!(reports.iter().all(|r| r.converged), "{reports:?}");
        assert!(reports.iter().all(|r| r.held > 0), "{reports:?}");
    }

    #[test]
    fn bad_input_gives_typed_errors() {
        // three triangles on the edge 0–1
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::NEG_Y];
        let bad = RefineMesh {
            positions: positions.clone().into(),
            triangles: tris(&[[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
            fixed: vec![true; 5].into(),
            edge_profiles: BTreeMap::new(),
        };
        let err = split(&bad).expect_err("non-manifold");
        let e01 = MeshEdge::new(v(0), v(1));
        assert_eq!(err, RefineError::Topology(TopologyError::NonManifoldEdge { edge: e01, faces: 3 }));
        assert!(err.to_string().contains("0–1"), "{err}");
        assert_eq!(refine(bad.clone(), &RefineOptions::default(), no_hook).unwrap_err(), err);
        assert_eq!(fair(&mut bad.clone(), &RefineOptions::default()).unwrap_err(), err);
        let mut m = RefineMesh { triangles: tris(&[[0, 1, 2], [0, 1, 3]]), ..bad.clone() };
        assert!(matches!(
            split(&m).unwrap_err(),
            RefineError::Topology(TopologyError::InconsistentOrientation { edge, .. }) if edge == e01
        ));
        m.triangles = tris(&[[0, 1, 9]]);
        assert_eq!(split(&m).unwrap_err(), RefineError::IndexOutOfRange { face: FaceId(0), vertex: v(9), count: 5 });
        m.triangles = tris(&[[0, 1, 1]]);
        assert_eq!(split(&m).unwrap_err(), RefineError::DegenerateFace { face: FaceId(0), vertex: v(1) });
        m.triangles = tris(&[[0, 1, 2]]);
        m.positions[v(2)].y = f64::NAN;
        assert_eq!(split(&m).unwrap_err(), RefineError::NonFinitePosition { vertex: v(2) });
        m.positions = positions.into();
        m.fixed.pop();
        assert_eq!(split(&m).unwrap_err(), RefineError::FixedFlags { vertices: 5, flags: 4 });
        m.fixed.push(true);
        let profile = Profile::new(vec![DVec3::ZERO, DVec3::new(0.5, 0.1, 0.0), DVec3::X]).expect("profile");
        // a key built out of order (the fields are public) names no edge
        m.edge_profiles.insert(MeshEdge { a: v(1), b: v(0) }, profile.clone());
        assert_eq!(split(&m).unwrap_err(), RefineError::ProfileOnMissingEdge { a: v(1), b: v(0) });
        m.edge_profiles.clear();
        m.edge_profiles.insert(MeshEdge::new(v(0), v(2)), profile.clone());
        assert!(matches!(split(&m).unwrap_err(), RefineError::Profile { a: VertexId(0), b: VertexId(2), .. }));
        m.edge_profiles.clear();
        m.edge_profiles.insert(e01, profile.clone());
        let fine = split(&m).expect("profiled edge");
        assert_eq!(fine.positions[v(5)], profile.eval(0.5));
        assert!(fine.fixed[v(5)]);
        // from_coarse: table length, a profile given end → start is reversed
        let coarse = CoarseMesh {
            positions: m.positions.raw.clone(),
            triangles: vec![[0, 1, 2]],
            profiles: vec![Some(profile.clone()), None, None],
            hung: vec![],
        };
        assert_eq!(
            RefineMesh::from_coarse(&coarse, &[(0, 1)]).unwrap_err(),
            RefineError::EdgeTable { edges: 1, profiles: 3 }
        );
        let ok = RefineMesh::from_coarse(&coarse, &[(0, 1), (1, 2), (0, 2)]).expect("coarse");
        assert_eq!(ok.edge_profiles[&e01], profile);
        let flipped = Profile::new(vec![DVec3::X, DVec3::new(0.5, 0.1, 0.0), DVec3::ZERO]).expect("profile");
        let coarse = CoarseMesh { profiles: vec![Some(flipped), None, None], ..coarse };
        let ok = RefineMesh::from_coarse(&coarse, &[(1, 0), (1, 2), (0, 2)]).expect("reversed");
        let back = &ok.edge_profiles[&e01];
        assert_eq!((back.start(), back.end()), (DVec3::ZERO, DVec3::X));
        assert!(back.eval(0.25).distance(profile.eval(0.25)) < 1e-12);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn split_and_fair_keep_what_they_must(
            heights in proptest::collection::vec(-1.0..1.0f64, 25),
            flags in proptest::collection::vec(any::<bool>(), 25),
            butterfly in any::<bool>(),
        ) {
            let mut mesh = grid(5);
            for ((p, h), (f, g)) in mesh.positions.iter_mut().zip(&heights).zip(mesh.fixed.iter_mut().zip(&flags)) {
                p.z = *h;
                *f |= *g;
            }
            let fine = split_with_boundary(&mesh, butterfly).expect("split");
            prop_assert_eq!(fine.triangles.len(), 4 * mesh.triangles.len());
            prop_assert_eq!(&fine.positions.raw[..25], &mesh.positions.raw[..]);
            prop_assert_eq!(&fine.fixed.raw[..25], &mesh.fixed.raw[..]);
            prop_assert!(Topology::of(&fine).is_ok());
            let mut faired = fine.clone();
            let report = fair(&mut faired, &RefineOptions::default()).expect("fair");
            prop_assert!(report.converged);
            for ((i, a), b) in fine.positions.iter_enumerated().zip(&faired.positions) {
                if fine.fixed[i] {
                    prop_assert_eq!(a, b);
                }
            }
        }

        #[test]
        fn arbitrary_faces_never_panic(
            faces in proptest::collection::vec([0u32..7, 0u32..7, 0u32..7], 0..12),
        ) {
            let mesh = RefineMesh {
                positions: (0..6).map(|i| DVec3::new(i as f64, (i * i) as f64, 0.0)).collect(),
                triangles: tris(&faces),
                fixed: vec![false; 6].into(),
                edge_profiles: BTreeMap::new(),
            };
            let opts = RefineOptions { levels: 2, max_sweeps: 20, ..RefineOptions::default() };
            let _ = refine(mesh, &opts, no_hook);
        }
    }
}
