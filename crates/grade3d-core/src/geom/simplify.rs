//! Quadric-error-metric edge contraction with locked ("encoded") vertices.
//!
//! # Contract
//!
//! **Method.** Iterative edge contraction driven by quadric error metrics
//! (M. Garland and P. S. Heckbert, "Surface simplification using quadric
//! error metrics", SIGGRAPH 1997), in the variant used by §3.3 of our design
//! (C. C. L. Wang, Y. Wang and M. M. F. Yuen, "Feature based 3D garment
//! design through 2D sketches", Computer-Aided Design 35(7), 2003; "2002" in
//! our design, seed 000): some vertices
//! are *encoded* (locked). A locked vertex never moves; when it is contracted
//! with a free vertex the result sits exactly at the locked position; two
//! locked vertices are never contracted together. The seed-000 stopping rule
//! runs until every remaining edge joins two locked vertices.
//!
//! **Preconditions.** The input is an oriented, 2-manifold triangle mesh,
//! possibly with boundary: every edge is used by one (boundary) or two
//! (interior) triangles, an interior edge is used once in each direction,
//! and the triangles around every vertex form a single fan. Several
//! connected components and unreferenced vertices are allowed.
//!
//! **Guarantees.** The output is again an oriented 2-manifold with the same
//! number of components, boundary loops and Euler characteristic per
//! component (contractions that would change the topology are rejected);
//! locked vertices keep their input coordinates bit for bit; the result is
//! deterministic (no hash-order dependence; ties in the priority queue are
//! broken by edge length, then vertex ids).
//!
//! **Failure modes** (all reported as [`SimplifyError`], never a panic or an
//! endless loop): an edge shared by more than two triangles, an edge used
//! twice in the same direction, a vertex whose triangles form several fans,
//! two triangles on the same three vertices, a locked id out of range or
//! given twice, an option out of range, and — with no face target and the
//! stop rule on — free vertices that cannot be removed without breaking one
//! of the rules below ([`SimplifyError::StopRuleUnreachable`]).
//!
//! # Formulas
//!
//! Every triangle with unit normal `n` through corner `p₀` spans the plane
//! `p = [a b c d]ᵀ = [nₓ n_y n_z −n·p₀]ᵀ`, whose fundamental error quadric is
//! `K_p = p pᵀ` (a symmetric 4×4 matrix). The quadric of a vertex is
//! `Q = Σ w_p K_p` over the planes of its triangles, with the area weight
//! `w_p = A_p / Ā` (triangle area over the mean input triangle area; it makes
//! the error independent of the tessellation density and is exactly the
//! unweighted `Q = Σ K_p` of Garland & Heckbert on a uniform mesh). The cost
//! of placing a vertex at `v = [x y z 1]ᵀ` is `Δ(v) = vᵀ Q v`, a weighted sum
//! of squared distances to the planes (unit: length²). Contracting the edge
//! `(v₁, v₂)` uses `Q̄ = Q₁ + Q₂`:
//!
//! * both free: `v̄` minimises `vᵀ Q̄ v`, i.e. solves the 3×3 system
//!   `A v̄ = −b` for `Q̄ = [[A, b], [bᵀ, c]]`; when `A` is near-singular
//!   (`det A ≤ 10⁻¹⁰ (tr A / 3)³`) or the solution lies farther than one edge
//!   length from the midpoint, the best of the two endpoints and the midpoint
//!   is used instead; when the guards below reject the chosen position, the
//!   other candidates (endpoints, midpoint) are tried in order of cost;
//! * one locked: `v̄` is the locked position;
//! * both locked: never contracted.
//!
//! **Boundary-preserving penalty planes.** For each boundary edge `(p, q)` of
//! a triangle with unit normal `n`, the plane through `p` with normal
//! `(q − p) × n / |(q − p) × n|` (perpendicular to the triangle, containing
//! the edge) is added to the quadrics of `p` and `q` with weight
//! `boundary_weight · w_p`, so moving a boundary vertex off its boundary is
//! expensive. [`BoundaryMode`] adds hard rules on top.
//!
//! # Validity of a contraction
//!
//! A contraction of edge `uv` is rejected when
//! * the link condition fails: the common neighbours of `u` and `v` must be
//!   exactly the opposite vertices of the triangles on `uv` (two for an
//!   interior edge, one for a boundary edge);
//! * `uv` is an interior edge whose two ends are both on the boundary (that
//!   would pinch the surface or merge two boundary loops);
//! * it would create two triangles on the same vertices, or leave a vertex or
//!   the whole mesh without triangles;
//! * the unit normal of any surviving triangle around `u` or `v` would turn
//!   by more than allowed (`cos < min_normal_cos`) or collapse to zero area;
//! * the optional triangle-quality guard fails;
//! * [`BoundaryMode`] forbids it.
//!
//! **Stop-rule rescue (extension).** Pure contraction can strand a free
//! vertex whose fan cannot be re-rooted at any neighbour without folding a
//! triangle (typically a free boundary vertex between locked ones). With
//! [`SimplifyOptions::flip_to_unblock`] (default on), when the stop rule is in
//! force and the queue runs dry, edges incident to each stranded free vertex
//! are flipped — no vertex moves, the normal guard applies, no degenerate or
//! duplicate edge is made — until one of its contractions becomes admissible.
//! Each flip lowers that vertex's valence, so the rescue terminates; what it
//! cannot free is reported as [`SimplifyError::StopRuleUnreachable`].
//!
//! The priority queue is a binary heap with lazy invalidation: each vertex
//! carries a version counter, bumped whenever its quadric, position or
//! neighbourhood changes; stale entries are skipped when popped. After a
//! contraction every edge touching the survivor's one-ring is re-evaluated,
//! so an edge that was rejected gets another chance once its neighbourhood
//! changes.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

use crate::geom::mesh::{FaceId, MeshError, TriMesh, VertexId};
use crate::geom::topology::{
    check_edge_uses, check_vertex_fans, triangle_edge_uses, MeshEdge, TopologyError, UnionFind,
};

/// How boundary vertices may move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum BoundaryMode {
    /// Boundary vertices are only held by the penalty planes; a boundary
    /// vertex may be contracted with an interior vertex to an optimal point.
    Free,
    /// Boundary vertices move along the boundary only: two boundary vertices
    /// are contracted only along a boundary edge, and a boundary vertex
    /// contracted with an interior one keeps its position (default).
    #[default]
    Slide,
    /// Boundary vertices are treated like locked vertices: they never move
    /// and never merge with each other or with locked vertices. The stop rule
    /// then counts them as locked.
    Fixed,
}

/// Parameters of [`simplify`]. All fields have documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SimplifyOptions {
    /// Stop as soon as the mesh has at most this many triangles (count,
    /// default `None`). When set, the stop rule is not enforced.
    pub target_faces: Option<usize>,
    /// Seed-000 stopping rule, used when `target_faces` is `None`: contract
    /// until every remaining edge joins two locked vertices, and fail with
    /// [`SimplifyError::StopRuleUnreachable`] if that cannot be reached
    /// (bool, default `true`). When `false` and no target is set, the mesh
    /// is simplified as far as the rules and `max_error` allow.
    pub stop_when_only_locked_edges: bool,
    /// Stop before any contraction whose cost `vᵀ Q̄ v` exceeds this value
    /// (length², in the area-weighted sense of the module doc; default
    /// `None` = no limit).
    pub max_error: Option<f64>,
    /// Weight of the boundary penalty planes relative to the weight of the
    /// triangle the boundary edge belongs to (dimensionless, default `1e3`).
    pub boundary_weight: f64,
    /// How boundary vertices may move (default [`BoundaryMode::Slide`]).
    pub boundary: BoundaryMode,
    /// Normal-flip guard: minimum cosine between the old and new unit normal
    /// of every triangle a contraction changes (dimensionless in `[-1, 1]`,
    /// default `0.2`, i.e. a turn of at most ~78°).
    pub min_normal_cos: f64,
    /// Triangle-quality guard: reject a contraction whose worst new triangle
    /// has quality `2√3 |e₁ × e₂| / Σ|eᵢ|²` (1 for equilateral, 0 for
    /// degenerate) below this value *and* below the worst old triangle it
    /// replaces (dimensionless in `[0, 1]`, default `0.0` = off).
    pub min_quality: f64,
    /// Stop-rule rescue (bool, default `true`): when the stop rule is in
    /// force and no admissible contraction is left while free vertices
    /// remain, flip edges incident to each stuck free vertex (never moving a
    /// vertex; same normal guard, no degenerate triangles) until one of its
    /// contractions becomes admissible, then resume. Pure contraction often
    /// strands a free boundary vertex whose fan cannot be re-rooted at a
    /// locked neighbour without folding; the flips fix that. Off: fail with
    /// [`SimplifyError::StopRuleUnreachable`] instead.
    pub flip_to_unblock: bool,
}

impl Default for SimplifyOptions {
    fn default() -> Self {
        Self {
            target_faces: None,
            stop_when_only_locked_edges: true,
            max_error: None,
            boundary_weight: 1e3,
            boundary: BoundaryMode::Slide,
            min_normal_cos: 0.2,
            min_quality: 0.0,
            flip_to_unblock: true,
        }
    }
}

/// Result of [`simplify`].
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    /// The simplified mesh (unreferenced free vertices are dropped; locked
    /// vertices are always kept).
    pub mesh: TriMesh,
    /// For each output vertex, the input vertex it came from (the survivor of
    /// its contractions).
    pub vertex_origin: Vec<VertexId>,
    /// Where each input locked vertex ended up, in the order of `locked`.
    pub locked_output: Vec<VertexId>,
    /// Largest quadric error `vᵀ Q v` over the output vertices (length²).
    pub max_error: f64,
    /// Sum of `vᵀ Q v` over the output vertices (length²).
    pub total_error: f64,
    /// Number of edge contractions performed.
    pub contractions: usize,
    /// Number of edge flips made to unblock the stop rule (see
    /// [`SimplifyOptions::flip_to_unblock`]).
    pub flips: usize,
}

/// Topological summary returned by [`check_oriented_manifold`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ManifoldStats {
    /// Vertices used by at least one triangle.
    pub vertices: usize,
    /// Vertices used by no triangle.
    pub isolated_vertices: usize,
    /// Undirected edges.
    pub edges: usize,
    /// Triangles.
    pub faces: usize,
    /// Edges with a single triangle.
    pub boundary_edges: usize,
    /// Closed chains of boundary edges.
    pub boundary_loops: usize,
    /// Connected components (of the triangles).
    pub components: usize,
    /// `V − E + F` over the referenced vertices.
    pub euler_characteristic: i64,
}

impl ManifoldStats {
    /// Whether the surface has no boundary.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges == 0
    }

    /// Genus `g = (2 − χ − b) / 2` of a connected surface; `None` when the
    /// mesh has several components.
    pub fn genus(&self) -> Option<i64> {
        (self.components == 1).then(|| (2 - self.euler_characteristic - self.boundary_loops as i64) / 2)
    }
}

/// What went wrong in [`simplify`], [`remesh_unrelated`] or
/// [`check_oriented_manifold`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimplifyError {
    /// Not an oriented manifold: an edge of three or more triangles, one
    /// run twice in the same direction, or a "bow tie" vertex.
    #[error(transparent)]
    Topology(#[from] TopologyError<MeshEdge>),
    /// Two triangles use the same three vertices.
    #[error("triangles {} and {} use the same three vertices", first.0, second.0)]
    DuplicateFace {
        /// The first triangle.
        first: FaceId,
        /// The triangle repeating it.
        second: FaceId,
    },
    /// A locked vertex id does not exist in the mesh.
    #[error("locked vertex {} is out of range (the mesh has {count} vertices)", vertex.0)]
    LockedOutOfRange {
        /// The offending id.
        vertex: VertexId,
        /// Number of vertices in the mesh.
        count: usize,
    },
    /// A locked vertex id is given more than once.
    #[error("locked vertex {} is listed more than once", vertex.0)]
    DuplicateLocked {
        /// The repeated id.
        vertex: VertexId,
    },
    /// An option is out of its documented range.
    #[error("option `{option}` has invalid value {value}")]
    InvalidOption {
        /// Field name.
        option: &'static str,
        /// The value given.
        value: f64,
    },
    /// The stop rule (only locked–locked edges left) cannot be reached: the
    /// remaining free vertices cannot be contracted without breaking the
    /// manifold, orientation, normal or boundary rules (or `max_error`).
    #[error("stop rule unreachable: {free_remaining} free vertices remain after {contractions} contractions")]
    StopRuleUnreachable {
        /// Free (unlocked) vertices still in the mesh.
        free_remaining: usize,
        /// Contractions performed before giving up.
        contractions: usize,
    },
    /// Building the output mesh failed. Not expected: contractions never
    /// remove the last triangle and never create an invalid one.
    #[error("building the output mesh failed: {0}")]
    Mesh(#[from] MeshError),
}

// ---------------------------------------------------------------------------
// Topology analysis
// ---------------------------------------------------------------------------

/// Edge structure of a validated oriented manifold.
struct Analysis {
    /// Undirected edges `(lo, hi)`, sorted.
    edges: Vec<(u32, u32)>,
    /// Boundary half-edges `(from, to, face)` in triangle orientation.
    boundary_halfedges: Vec<(u32, u32, u32)>,
    stats: ManifoldStats,
}

fn analyse(mesh: &TriMesh) -> Result<Analysis, SimplifyError> {
    let tris = mesh.triangles();
    let n = mesh.vertex_count();
    let checked = check_edge_uses(triangle_edge_uses(tris))?;
    let edges: Vec<(u32, u32)> = checked.iter().map(|e| (e.edge.a.0, e.edge.b.0)).collect();
    let boundary_halfedges: Vec<(u32, u32, u32)> = checked
        .iter()
        .filter(|e| e.second.is_none())
        .map(|e| {
            let (lo, hi) = (e.edge.a.0, e.edge.b.0);
            let (from, to) = if e.first.forward { (lo, hi) } else { (hi, lo) };
            (from, to, e.first.face.0)
        })
        .collect();

    // Duplicate triangles (same vertex set, any orientation).
    let mut keyed: Vec<([u32; 3], u32)> = tris
        .iter()
        .enumerate()
        .map(|(f, t)| {
            let mut k = [t[0].0, t[1].0, t[2].0];
            k.sort_unstable();
            (k, f as u32)
        })
        .collect();
    keyed.sort_unstable();
    for w in keyed.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(SimplifyError::DuplicateFace { first: FaceId(w[0].1), second: FaceId(w[1].1) });
        }
    }

    // Vertex fans: the corners around each vertex must form one fan.
    check_vertex_fans(tris, n, &checked)?;
    let mut referenced_vertex = vec![false; n];
    for t in tris {
        for &v in t {
            referenced_vertex[v.idx()] = true;
        }
    }
    let referenced = referenced_vertex.iter().filter(|&&r| r).count();

    // Boundary loops: each boundary vertex has exactly one outgoing boundary half-edge.
    let mut next = vec![u32::MAX; n];
    for &(a, b, _) in &boundary_halfedges {
        next[a as usize] = b;
    }
    let mut seen = vec![false; n];
    let mut boundary_loops = 0;
    for v in 0..n {
        if next[v] == u32::MAX || seen[v] {
            continue;
        }
        boundary_loops += 1;
        let mut x = v;
        while !seen[x] && next[x] != u32::MAX {
            seen[x] = true;
            x = next[x] as usize;
        }
    }

    // Components.
    let mut parts = UnionFind::new(n);
    for &(a, b) in &edges {
        parts.union(a, b);
    }
    let components = (0..n).filter(|&v| referenced_vertex[v] && parts.find(v as u32) == v as u32).count();

    let stats = ManifoldStats {
        vertices: referenced,
        isolated_vertices: n - referenced,
        edges: edges.len(),
        faces: tris.len(),
        boundary_edges: boundary_halfedges.len(),
        boundary_loops,
        components,
        euler_characteristic: referenced as i64 - edges.len() as i64 + tris.len() as i64,
    };
    Ok(Analysis { edges, boundary_halfedges, stats })
}

/// Checks that `mesh` is an oriented 2-manifold, possibly with boundary, and
/// returns its topological summary.
///
/// Checks, in this order: every edge has one or two triangles, an interior
/// edge is used once in each direction ([`crate::geom::topology`]); no two
/// triangles share all three vertices ([`SimplifyError::DuplicateFace`]);
/// the triangles around each vertex form one fan. The first offending
/// element in sorted id order is reported.
pub fn check_oriented_manifold(mesh: &TriMesh) -> Result<ManifoldStats, SimplifyError> {
    analyse(mesh).map(|a| a.stats)
}

// ---------------------------------------------------------------------------
// Quadrics
// ---------------------------------------------------------------------------

/// Symmetric 4×4 quadric stored as its upper triangle:
/// `a00 a01 a02 a03 a11 a12 a13 a22 a23 a33`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Quadric([f64; 10]);

impl Quadric {
    /// `w · p pᵀ` for the plane `n·x + d = 0`.
    fn plane(n: DVec3, d: f64, w: f64) -> Self {
        let (a, b, c) = (n.x, n.y, n.z);
        Self([
            w * a * a,
            w * a * b,
            w * a * c,
            w * a * d,
            w * b * b,
            w * b * c,
            w * b * d,
            w * c * c,
            w * c * d,
            w * d * d,
        ])
    }

    fn add(&mut self, o: &Self) {
        for (x, y) in self.0.iter_mut().zip(o.0.iter()) {
            *x += y;
        }
    }

    fn sum(&self, o: &Self) -> Self {
        let mut s = *self;
        s.add(o);
        s
    }

    /// `vᵀ Q v` with `v = [p, 1]`, clamped at zero against round-off.
    fn eval(&self, p: DVec3) -> f64 {
        let q = &self.0;
        let (x, y, z) = (p.x, p.y, p.z);
        let e = q[0] * x * x
            + q[4] * y * y
            + q[7] * z * z
            + 2.0 * (q[1] * x * y + q[2] * x * z + q[5] * y * z)
            + 2.0 * (q[3] * x + q[6] * y + q[8] * z)
            + q[9];
        e.max(0.0)
    }

    /// Minimiser of `vᵀ Q v` when the 3×3 block is well conditioned.
    fn minimiser(&self) -> Option<DVec3> {
        let q = &self.0;
        let a =
            DMat3::from_cols(DVec3::new(q[0], q[1], q[2]), DVec3::new(q[1], q[4], q[5]), DVec3::new(q[2], q[5], q[7]));
        let tr = q[0] + q[4] + q[7];
        if tr.partial_cmp(&0.0) != Some(Ordering::Greater) {
            return None;
        }
        let s = tr / 3.0;
        let det = a.determinant();
        if det <= 1e-10 * s * s * s {
            return None;
        }
        let x = a.inverse() * -DVec3::new(q[3], q[6], q[8]);
        x.is_finite().then_some(x)
    }
}

/// Quality `2√3 |e₁ × e₂| / Σ|eᵢ|²` of a triangle (1 equilateral, 0 degenerate).
fn quality(p: [DVec3; 3]) -> f64 {
    let s = (p[1] - p[0]).length_squared() + (p[2] - p[1]).length_squared() + (p[0] - p[2]).length_squared();
    if s <= 0.0 {
        return 0.0;
    }
    2.0 * 3f64.sqrt() * (p[1] - p[0]).cross(p[2] - p[0]).length() / s
}

// ---------------------------------------------------------------------------
// Contraction state
// ---------------------------------------------------------------------------

/// Heap entry; ordered so that the cheapest edge (then the shortest, then the
/// lowest ids) pops first.
#[derive(Debug, Clone, Copy)]
struct Entry {
    cost: f64,
    /// Squared edge length: among equal costs (flat regions) the shortest
    /// edge goes first, which keeps triangles well shaped.
    len2: f64,
    a: u32,
    b: u32,
    va: u32,
    vb: u32,
}

impl Ord for Entry {
    fn cmp(&self, o: &Self) -> Ordering {
        o.cost
            .total_cmp(&self.cost)
            .then_with(|| o.len2.total_cmp(&self.len2))
            .then_with(|| o.a.cmp(&self.a))
            .then_with(|| o.b.cmp(&self.b))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}

impl Eq for Entry {}

/// A planned contraction: `remove` is merged into `keep`, which moves to `target`.
#[derive(Debug, Clone, Copy, Default)]
struct Plan {
    keep: u32,
    remove: u32,
    target: DVec3,
    cost: f64,
}

/// Candidate placements of one contraction, cheapest first.
#[derive(Debug, Clone, Copy, Default)]
struct Plans {
    items: [Plan; 4],
    len: usize,
}

impl Plans {
    fn push(&mut self, p: Plan) {
        if self.len < self.items.len() {
            self.items[self.len] = p;
            self.len += 1;
        }
    }

    fn first(&self) -> Option<Plan> {
        self.as_slice().first().copied()
    }

    fn as_slice(&self) -> &[Plan] {
        &self.items[..self.len]
    }
}

struct State<'a> {
    opts: &'a SimplifyOptions,
    /// Quadrics are built in coordinates relative to this point (round-off).
    origin: DVec3,
    pos: Vec<DVec3>,
    quad: Vec<Quadric>,
    faces: Vec<[u32; 3]>,
    face_alive: Vec<bool>,
    adj: Vec<Vec<u32>>,
    alive: Vec<bool>,
    pinned: Vec<bool>,
    boundary: Vec<bool>,
    version: Vec<u32>,
    alive_faces: usize,
    heap: BinaryHeap<Entry>,
    contractions: usize,
    flips: usize,
}

impl<'a> State<'a> {
    fn new(mesh: &TriMesh, analysis: &Analysis, locked: &[VertexId], opts: &'a SimplifyOptions) -> Self {
        let n = mesh.vertex_count();
        let origin = mesh.aabb().centre();
        let pos = mesh.positions().to_vec();
        let faces: Vec<[u32; 3]> = mesh.triangles().iter().map(|t| [t[0].0, t[1].0, t[2].0]).collect();
        let mut adj = vec![Vec::new(); n];
        for (f, t) in faces.iter().enumerate() {
            for &v in t {
                adj[v as usize].push(f as u32);
            }
        }
        let mut boundary = vec![false; n];
        for &(a, b, _) in &analysis.boundary_halfedges {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
        let mut pinned = vec![false; n];
        for v in locked {
            pinned[v.idx()] = true;
        }
        if opts.boundary == BoundaryMode::Fixed {
            for (p, &b) in pinned.iter_mut().zip(&boundary) {
                *p |= b;
            }
        }

        // Face planes, area weighted relative to the mean triangle area.
        let normals: Vec<DVec3> = faces
            .iter()
            .map(|t| (pos[t[1] as usize] - pos[t[0] as usize]).cross(pos[t[2] as usize] - pos[t[0] as usize]))
            .collect();
        let total: f64 = normals.iter().map(|c| c.length()).sum();
        let mean = total / normals.len() as f64;
        let weight = |c: DVec3| if mean > 0.0 { c.length() / mean } else { 1.0 };
        let mut quad = vec![Quadric::default(); n];
        for (t, &c) in faces.iter().zip(&normals) {
            let Some(unit) = c.try_normalize() else { continue };
            let d = -unit.dot(pos[t[0] as usize] - origin);
            let k = Quadric::plane(unit, d, weight(c));
            for &v in t {
                quad[v as usize].add(&k);
            }
        }
        for &(a, b, f) in &analysis.boundary_halfedges {
            let c = normals[f as usize];
            let Some(unit) = c.try_normalize() else { continue };
            let (pa, pb) = (pos[a as usize], pos[b as usize]);
            let Some(m) = (pb - pa).cross(unit).try_normalize() else {
                continue;
            };
            let d = -m.dot(pa - origin);
            let k = Quadric::plane(m, d, opts.boundary_weight * weight(c));
            quad[a as usize].add(&k);
            quad[b as usize].add(&k);
        }

        let alive = adj.iter().map(|a| !a.is_empty()).collect();
        let mut st = Self {
            opts,
            origin,
            pos,
            quad,
            face_alive: vec![true; faces.len()],
            alive_faces: faces.len(),
            faces,
            adj,
            alive,
            pinned,
            boundary,
            version: vec![0; n],
            heap: BinaryHeap::with_capacity(analysis.edges.len() * 2),
            contractions: 0,
            flips: 0,
        };
        for &(a, b) in &analysis.edges {
            st.push(a, b);
        }
        st
    }

    fn neighbours(&self, x: u32) -> Vec<u32> {
        let mut out = Vec::with_capacity(2 * self.adj[x as usize].len());
        for &f in &self.adj[x as usize] {
            for &y in &self.faces[f as usize] {
                if y != x {
                    out.push(y);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Triangles on edge `ab` (at most two in a manifold).
    fn edge_faces(&self, a: u32, b: u32) -> (usize, [u32; 2]) {
        let mut out = [u32::MAX; 2];
        let mut k = 0;
        for &f in &self.adj[a as usize] {
            if self.faces[f as usize].contains(&b) {
                if k < 2 {
                    out[k] = f;
                }
                k += 1;
            }
        }
        (k, out)
    }

    /// Decides who survives and where: up to four placements, cheapest
    /// first (the first is the heap priority; the others are tried in order
    /// when the guards reject it). Empty when the rules forbid contracting
    /// `ab` whatever its neighbourhood.
    fn plan(&self, a: u32, b: u32) -> Plans {
        let mut out = Plans::default();
        let (ai, bi) = (a as usize, b as usize);
        if !self.alive[ai] || !self.alive[bi] {
            return out;
        }
        let (nf, _) = self.edge_faces(a, b);
        if nf == 0 {
            return out;
        }
        let boundary_edge = nf == 1;
        let (ba, bb) = (self.boundary[ai], self.boundary[bi]);
        if !boundary_edge && ba && bb {
            return out;
        }
        let slide = self.opts.boundary == BoundaryMode::Slide;
        let q = self.quad[ai].sum(&self.quad[bi]);
        let (pa, pb) = (self.pos[ai], self.pos[bi]);
        let at = |target: DVec3| {
            // the survivor is the endpoint nearer to the new position
            let (keep, remove) =
                if target.distance_squared(pb) < target.distance_squared(pa) { (b, a) } else { (a, b) };
            Plan { keep, remove, target, cost: q.eval(target - self.origin) }
        };
        let fixed_at = |keep: u32, remove: u32| {
            let target = self.pos[keep as usize];
            Plan { keep, remove, target, cost: q.eval(target - self.origin) }
        };
        match (self.pinned[ai], self.pinned[bi]) {
            (true, true) => {}
            (true, false) | (false, true) => {
                let (keep, remove) = if self.pinned[ai] { (a, b) } else { (b, a) };
                if !(slide && self.boundary[remove as usize] && !boundary_edge) {
                    out.push(fixed_at(keep, remove));
                }
            }
            (false, false) if slide && ba != bb => out.push(if ba { fixed_at(a, b) } else { fixed_at(b, a) }),
            (false, false) => {
                let mid = 0.5 * (pa + pb);
                let len = pa.distance(pb);
                if let Some(x) = q.minimiser().map(|x| x + self.origin).filter(|x| x.distance(mid) <= len) {
                    out.push(at(x));
                }
                let mut rest = [at(pa), at(pb), at(mid)];
                rest.sort_by(|x, y| x.cost.total_cmp(&y.cost));
                for p in rest {
                    out.push(p);
                }
                // the solve can lose to an endpoint only by round-off; keep the cheapest first
                out.items[..out.len].sort_by(|x, y| x.cost.total_cmp(&y.cost));
            }
        }
        out
    }

    fn push(&mut self, a: u32, b: u32) {
        if let Some(p) = self.plan(a, b).first() {
            let (a, b) = (a.min(b), a.max(b));
            self.heap.push(Entry {
                cost: p.cost,
                len2: self.pos[a as usize].distance_squared(self.pos[b as usize]),
                a,
                b,
                va: self.version[a as usize],
                vb: self.version[b as usize],
            });
        }
    }

    /// Topological and geometric validity of a planned contraction.
    fn admissible(&self, p: &Plan) -> bool {
        let (u, v) = (p.keep, p.remove);
        let (nf, ef) = self.edge_faces(u, v);
        if nf == 0 || nf > 2 {
            return false;
        }
        let ef = &ef[..nf];
        // Link condition.
        let mut opp: Vec<u32> = ef
            .iter()
            .map(|&f| self.faces[f as usize].iter().copied().find(|&x| x != u && x != v).unwrap_or(u32::MAX))
            .collect();
        opp.sort_unstable();
        let (nu, nv) = (self.neighbours(u), self.neighbours(v));
        let common: Vec<u32> = nu.iter().copied().filter(|x| nv.binary_search(x).is_ok()).collect();
        if common != opp {
            return false;
        }
        // Nobody may be left without triangles.
        if self.alive_faces <= nf {
            return false;
        }
        if opp.iter().any(|&w| self.adj[w as usize].iter().all(|f| ef.contains(f))) {
            return false;
        }
        // Surviving triangles around u and v, after the contraction.
        let mut keys: Vec<[u32; 3]> = Vec::with_capacity(self.adj[u as usize].len() + self.adj[v as usize].len());
        let (mut old_q, mut new_q) = (f64::INFINITY, f64::INFINITY);
        for &f in self.adj[u as usize].iter().chain(&self.adj[v as usize]) {
            if ef.contains(&f) {
                continue;
            }
            let t = self.faces[f as usize];
            let old = t.map(|x| self.pos[x as usize]);
            let new = [0, 1, 2].map(|k| if t[k] == u || t[k] == v { p.target } else { old[k] });
            let mut key = t.map(|x| if x == v { u } else { x });
            key.sort_unstable();
            keys.push(key);
            let n_old = (old[1] - old[0]).cross(old[2] - old[0]);
            let n_new = (new[1] - new[0]).cross(new[2] - new[0]);
            let scale = |c: [DVec3; 3]| {
                (c[1] - c[0]).length_squared() + (c[2] - c[1]).length_squared() + (c[0] - c[2]).length_squared()
            };
            if n_old.length() <= 1e-12 * scale(old) {
                continue; // degenerate before: nothing to compare with
            }
            if n_new.length() <= 1e-12 * scale(new) {
                return false;
            }
            if n_old.normalize().dot(n_new.normalize()) < self.opts.min_normal_cos {
                return false;
            }
            if self.opts.min_quality > 0.0 {
                old_q = old_q.min(quality(old));
                new_q = new_q.min(quality(new));
            }
        }
        if keys.is_empty() {
            return false;
        }
        keys.sort_unstable();
        if keys.windows(2).any(|w| w[0] == w[1]) {
            return false;
        }
        !(self.opts.min_quality > 0.0 && new_q < self.opts.min_quality && new_q < old_q)
    }

    fn contract(&mut self, p: &Plan) {
        let (u, v) = (p.keep, p.remove);
        let (ui, vi) = (u as usize, v as usize);
        self.pos[ui] = p.target;
        let qv = self.quad[vi];
        self.quad[ui].add(&qv);
        self.alive[vi] = false;
        self.boundary[ui] |= self.boundary[vi];
        let faces_v = std::mem::take(&mut self.adj[vi]);
        for f in faces_v {
            let fi = f as usize;
            if self.faces[fi].contains(&u) {
                self.face_alive[fi] = false;
                self.alive_faces -= 1;
                for x in self.faces[fi] {
                    if x != v {
                        self.adj[x as usize].retain(|&g| g != f);
                    }
                }
            } else {
                for x in &mut self.faces[fi] {
                    if *x == v {
                        *x = u;
                    }
                }
                self.adj[ui].push(f);
            }
        }
        self.contractions += 1;
        // Every vertex whose star changed: the survivor and its one-ring.
        let mut touched = self.neighbours(u);
        touched.push(u);
        self.requeue(touched);
    }

    /// Bumps the versions of `touched` (vertices whose star changed) and
    /// re-evaluates every edge incident to them.
    fn requeue(&mut self, mut touched: Vec<u32>) {
        touched.sort_unstable();
        touched.dedup();
        for &x in &touched {
            self.version[x as usize] = self.version[x as usize].wrapping_add(1);
        }
        let mut edges = Vec::new();
        for &x in &touched {
            for y in self.neighbours(x) {
                edges.push((x.min(y), x.max(y)));
            }
        }
        edges.sort_unstable();
        edges.dedup();
        for (a, b) in edges {
            self.push(a, b);
        }
    }

    /// Cheapest admissible contraction that removes or absorbs free vertex `x`.
    fn best_contraction_of(&self, x: u32) -> Option<Plan> {
        let limit = self.opts.max_error.unwrap_or(f64::INFINITY);
        let mut best: Option<Plan> = None;
        for w in self.neighbours(x) {
            let plans = self.plan(x, w);
            if let Some(p) = plans.as_slice().iter().find(|p| p.cost <= limit && self.admissible(p)) {
                if best.is_none_or(|b| p.cost < b.cost) {
                    best = Some(*p);
                }
            }
        }
        best
    }

    /// Checks flipping interior edge `xl`: its triangles `(x, l, p)` and
    /// `(l, x, q)` become `(x, q, p)` and `(l, p, q)`. Returns the two faces,
    /// `p`, `q` and the worst quality of the new triangles.
    fn flip_candidate(&self, x: u32, l: u32) -> Option<([u32; 2], u32, u32, f64)> {
        let (nf, ef) = self.edge_faces(x, l);
        if nf != 2 {
            return None;
        }
        // Orient: f1 holds the half-edge x → l.
        let has = |f: u32, a: u32, b: u32| {
            let t = self.faces[f as usize];
            (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b)
        };
        let (f1, f2) = if has(ef[0], x, l) { (ef[0], ef[1]) } else { (ef[1], ef[0]) };
        let third = |f: u32| self.faces[f as usize].iter().copied().find(|&y| y != x && y != l);
        let (p, q) = (third(f1)?, third(f2)?);
        if p == q || self.neighbours(p).binary_search(&q).is_ok() {
            return None;
        }
        let at = |v: u32| self.pos[v as usize];
        let normal = |a: u32, b: u32, c: u32| (at(b) - at(a)).cross(at(c) - at(a));
        let (o1, o2) = (normal(x, l, p), normal(l, x, q));
        let (g1, g2) = ([x, q, p], [l, p, q]);
        let mut worst = f64::INFINITY;
        for g in [g1, g2] {
            let c = g.map(at);
            let n = normal(g[0], g[1], g[2]);
            let scale =
                (c[1] - c[0]).length_squared() + (c[2] - c[1]).length_squared() + (c[0] - c[2]).length_squared();
            if n.length() <= 1e-12 * scale {
                return None;
            }
            for o in [o1, o2] {
                let Some(o) = o.try_normalize() else { continue };
                if n.normalize().dot(o) < self.opts.min_normal_cos.max(1e-6) {
                    return None;
                }
            }
            worst = worst.min(quality(c));
        }
        Some(([f1, f2], p, q, worst))
    }

    fn apply_flip(&mut self, x: u32, l: u32, [f1, f2]: [u32; 2], p: u32, q: u32) {
        self.faces[f1 as usize] = [x, q, p];
        self.faces[f2 as usize] = [l, p, q];
        self.adj[x as usize].retain(|&f| f != f2);
        self.adj[l as usize].retain(|&f| f != f1);
        self.adj[p as usize].push(f2);
        self.adj[q as usize].push(f1);
        self.flips += 1;
        self.requeue(vec![x, l, p, q]);
    }

    /// Unblocks free vertices that no contraction can remove: flips their
    /// incident edges (best resulting triangle quality first; every flip
    /// lowers the vertex's valence by one, so this ends) until a contraction
    /// becomes admissible. Returns whether any contraction was made.
    fn rescue(&mut self) -> bool {
        let mut progress = false;
        for x in 0..self.alive.len() as u32 {
            let xi = x as usize;
            if !self.alive[xi] || self.pinned[xi] || self.adj[xi].is_empty() {
                continue;
            }
            loop {
                if let Some(p) = self.best_contraction_of(x) {
                    self.contract(&p);
                    progress = true;
                    break;
                }
                let mut best: Option<(u32, [u32; 2], u32, u32, f64)> = None;
                for l in self.neighbours(x) {
                    if let Some((fs, p, q, score)) = self.flip_candidate(x, l) {
                        if best.is_none_or(|b| score > b.4) {
                            best = Some((l, fs, p, q, score));
                        }
                    }
                }
                let Some((l, fs, p, q, _)) = best else { break };
                self.apply_flip(x, l, fs, p, q);
            }
        }
        progress
    }

    fn run(&mut self) {
        while let Some(e) = self.heap.pop() {
            if let Some(t) = self.opts.target_faces {
                if self.alive_faces <= t {
                    break;
                }
            }
            let (ai, bi) = (e.a as usize, e.b as usize);
            if !self.alive[ai] || !self.alive[bi] || self.version[ai] != e.va || self.version[bi] != e.vb {
                continue;
            }
            self.compact_heap();
            let plans = self.plan(e.a, e.b);
            let Some(best) = plans.first() else { continue };
            let limit = self.opts.max_error.unwrap_or(f64::INFINITY);
            if best.cost > limit {
                break;
            }
            if let Some(p) = plans.as_slice().iter().find(|p| p.cost <= limit && self.admissible(p)) {
                self.contract(p);
            }
        }
    }

    /// Drops stale entries once they outnumber the live edges eightfold, so
    /// the heap stays proportional to the mesh.
    fn compact_heap(&mut self) {
        let live_edges = 3 * self.alive_faces / 2 + 1;
        if self.heap.len() > 1024 && self.heap.len() > 8 * live_edges {
            let (alive, version) = (&self.alive, &self.version);
            self.heap.retain(|e| {
                let (a, b) = (e.a as usize, e.b as usize);
                alive[a] && alive[b] && version[a] == e.va && version[b] == e.vb
            });
        }
    }

    fn free_remaining(&self) -> usize {
        (0..self.alive.len()).filter(|&v| self.alive[v] && !self.pinned[v] && !self.adj[v].is_empty()).count()
    }
}

fn validate_options(opts: &SimplifyOptions) -> Result<(), SimplifyError> {
    let bad = |option: &'static str, value: f64| Err(SimplifyError::InvalidOption { option, value });
    if !(opts.boundary_weight.is_finite() && opts.boundary_weight >= 0.0) {
        return bad("boundary_weight", opts.boundary_weight);
    }
    if !(-1.0..=1.0).contains(&opts.min_normal_cos) {
        return bad("min_normal_cos", opts.min_normal_cos);
    }
    if !(0.0..=1.0).contains(&opts.min_quality) {
        return bad("min_quality", opts.min_quality);
    }
    if let Some(m) = opts.max_error {
        if m.is_nan() || m < 0.0 {
            return bad("max_error", m);
        }
    }
    Ok(())
}

/// Simplifies `mesh` by quadric-error edge contraction, keeping the `locked`
/// vertices exactly where they are (see the module doc for the contract).
///
/// Stopping: with `opts.target_faces = Some(n)` the contraction stops once
/// the mesh has at most `n` triangles (or nothing more can be contracted);
/// with `None` and `opts.stop_when_only_locked_edges`, it runs until every
/// remaining edge joins two locked vertices and fails with
/// [`SimplifyError::StopRuleUnreachable`] if that state cannot be reached.
/// `opts.max_error` stops before the first contraction costing more.
pub fn simplify(mesh: &TriMesh, locked: &[VertexId], opts: &SimplifyOptions) -> Result<Simplified, SimplifyError> {
    validate_options(opts)?;
    let n = mesh.vertex_count();
    if let Some(&v) = locked.iter().find(|v| v.idx() >= n) {
        return Err(SimplifyError::LockedOutOfRange { vertex: v, count: n });
    }
    let mut sorted = locked.to_vec();
    sorted.sort_unstable();
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(SimplifyError::DuplicateLocked { vertex: w[0] });
    }
    let analysis = analyse(mesh)?;
    let mut st = State::new(mesh, &analysis, locked, opts);
    st.run();
    let stop_rule = opts.target_faces.is_none() && opts.stop_when_only_locked_edges;
    while stop_rule && opts.flip_to_unblock && st.free_remaining() > 0 && st.rescue() {
        st.run();
    }
    if stop_rule {
        let free_remaining = st.free_remaining();
        if free_remaining > 0 {
            return Err(SimplifyError::StopRuleUnreachable { free_remaining, contractions: st.contractions });
        }
    }

    // Compact: referenced vertices plus every locked one, in input order.
    let mut keep = vec![false; n];
    for (t, &alive) in st.faces.iter().zip(&st.face_alive) {
        if alive {
            for &v in t {
                keep[v as usize] = true;
            }
        }
    }
    for v in locked {
        keep[v.idx()] = true;
    }
    let mut new_id = vec![u32::MAX; n];
    let mut positions = Vec::new();
    let mut vertex_origin = Vec::new();
    let (mut max_error, mut total_error) = (0.0f64, 0.0f64);
    for v in 0..n {
        if keep[v] {
            new_id[v] = positions.len() as u32;
            positions.push(st.pos[v]);
            vertex_origin.push(VertexId(v as u32));
            let e = st.quad[v].eval(st.pos[v] - st.origin);
            max_error = max_error.max(e);
            total_error += e;
        }
    }
    let triangles: Vec<[VertexId; 3]> = st
        .faces
        .iter()
        .zip(&st.face_alive)
        .filter(|(_, &alive)| alive)
        .map(|(t, _)| t.map(|v| VertexId(new_id[v as usize])))
        .collect();
    let locked_output = locked.iter().map(|v| VertexId(new_id[v.idx()])).collect();
    Ok(Simplified {
        mesh: TriMesh::new(positions, triangles)?,
        vertex_origin,
        locked_output,
        max_error,
        total_error,
        contractions: st.contractions,
        flips: st.flips,
    })
}

/// Splits every triangle 1 → 4 at its edge midpoints; a midpoint is shared
/// by the two triangles on its edge. The face count is exactly ×4, the
/// vertex count grows by the number of edges, positions of the input
/// vertices are unchanged (same ids) and orientation is preserved.
///
/// # Panics
///
/// Only if the result needs more than `u32::MAX` vertices or triangles.
pub fn split_midpoints(mesh: &TriMesh) -> TriMesh {
    let tris = mesh.triangles();
    let mut positions = mesh.positions().to_vec();
    // Undirected edges, sorted, each with its midpoint id.
    let mut edges: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].0.min(t[(k + 1) % 3].0), t[k].0.max(t[(k + 1) % 3].0))))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let base = positions.len() as u32;
    for &(a, b) in &edges {
        positions.push(0.5 * (positions[a as usize] + positions[b as usize]));
    }
    let mid = |a: VertexId, b: VertexId| {
        let key = (a.0.min(b.0), a.0.max(b.0));
        VertexId(base + edges.binary_search(&key).unwrap_or(0) as u32)
    };
    let mut out = Vec::with_capacity(tris.len() * 4);
    for &[a, b, c] in tris {
        let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
        out.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    TriMesh::new(positions, out).expect("midpoint split of a valid mesh is valid")
}

/// Floor on [`SimplifyOptions::min_quality`] used by [`remesh_unrelated`].
pub const REMESH_MIN_QUALITY: f64 = 0.2;

/// Re-meshes the surface of `mesh` with an unrelated connectivity and about
/// `target_faces` triangles: splits at edge midpoints at least once and until
/// the face count is at least 1.6 × `target_faces`, then simplifies with
/// [`simplify`] (no locks, `opts` with `target_faces` overridden and the stop
/// rule off, `min_quality` raised to at least [`REMESH_MIN_QUALITY`] so the
/// new mesh has no slivers). The result lies on (or, by the quadric placement, within the
/// quadric error of) the input surface. Its face count is the target, or one
/// less (an interior contraction removes two triangles), or more when the
/// guards of [`simplify`] block further contractions (tiny closed meshes).
pub fn remesh_unrelated(mesh: &TriMesh, target_faces: usize, opts: &SimplifyOptions) -> Result<TriMesh, SimplifyError> {
    if target_faces == 0 {
        return Err(SimplifyError::InvalidOption { option: "target_faces", value: 0.0 });
    }
    validate_options(opts)?;
    analyse(mesh)?; // report problems with input ids, not split ids
    let mut m = split_midpoints(mesh);
    while (m.face_count() as f64) < 1.6 * target_faces as f64 {
        m = split_midpoints(&m);
    }
    let o = SimplifyOptions {
        target_faces: Some(target_faces),
        stop_when_only_locked_edges: false,
        min_quality: opts.min_quality.max(REMESH_MIN_QUALITY),
        ..opts.clone()
    };
    Ok(simplify(&m, &[], &o)?.mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn icosahedron() -> TriMesh {
        TriMesh::icosahedron()
    }

    fn icosphere(splits: usize, radius: f64) -> TriMesh {
        let mut m = icosahedron();
        for _ in 0..splits {
            m = split_midpoints(&m).map_positions(|p| p.normalize()).unwrap();
        }
        m.map_positions(|p| p * radius).unwrap()
    }

    /// UV sphere with `2 · lon · (lat − 1)` triangles, outward orientation.
    fn uv_sphere(lat: usize, lon: usize, radius: f64) -> TriMesh {
        let mut p = vec![DVec3::Z * radius];
        for i in 1..lat {
            let th = std::f64::consts::PI * i as f64 / lat as f64;
            for j in 0..lon {
                let ph = std::f64::consts::TAU * j as f64 / lon as f64;
                p.push(radius * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
            }
        }
        let south = p.len() as u64;
        p.push(-DVec3::Z * radius);
        let ring = |i: usize, j: usize| (1 + (i - 1) * lon + j % lon) as u64;
        let mut f = Vec::new();
        for j in 0..lon {
            f.push([0, ring(1, j), ring(1, j + 1)]);
            f.push([south, ring(lat - 1, j + 1), ring(lat - 1, j)]);
        }
        for i in 1..lat - 1 {
            for j in 0..lon {
                f.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                f.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        TriMesh::from_raw(p, &f).unwrap()
    }

    /// Planar `nx × ny` vertex grid in z = 0 with unit spacing, normals +z.
    fn grid(nx: usize, ny: usize) -> TriMesh {
        let mut p = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                p.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let id = |i: usize, j: usize| (j * nx + i) as u64;
        let mut f = Vec::new();
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                // alternate diagonals so the grid is not trivially regular
                if (i + j) % 2 == 0 {
                    f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                } else {
                    f.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                    f.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
        }
        TriMesh::from_raw(p, &f).unwrap()
    }

    /// Open tube: `rings` circles of `n` vertices, no caps.
    fn tube(n: usize, rings: usize) -> TriMesh {
        let mut p = Vec::new();
        for r in 0..rings {
            for j in 0..n {
                let a = std::f64::consts::TAU * j as f64 / n as f64;
                p.push(DVec3::new(a.cos(), a.sin(), r as f64 * 0.3));
            }
        }
        let id = |r: usize, j: usize| (r * n + j % n) as u64;
        let mut f = Vec::new();
        for r in 0..rings - 1 {
            for j in 0..n {
                f.push([id(r, j), id(r, j + 1), id(r + 1, j + 1)]);
                f.push([id(r, j), id(r + 1, j + 1), id(r + 1, j)]);
            }
        }
        TriMesh::from_raw(p, &f).unwrap()
    }

    fn worst_input_quality(m: &TriMesh) -> f64 {
        (0..m.face_count()).map(|f| quality(m.corners(FaceId(f as u32)))).fold(1.0, f64::min)
    }

    fn edges_of(m: &TriMesh) -> Vec<(u32, u32)> {
        let mut e: Vec<(u32, u32)> = m
            .triangles()
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k].0.min(t[(k + 1) % 3].0), t[k].0.max(t[(k + 1) % 3].0))))
            .collect();
        e.sort_unstable();
        e.dedup();
        e
    }

    fn assert_locked_exact(input: &TriMesh, locked: &[VertexId], out: &Simplified) {
        assert_eq!(out.locked_output.len(), locked.len());
        for (l, o) in locked.iter().zip(&out.locked_output) {
            assert_eq!(out.mesh.position(*o).to_array(), input.position(*l).to_array(), "locked {l:?} moved");
            assert_eq!(out.vertex_origin[o.idx()], *l);
        }
        assert_eq!(out.vertex_origin.len(), out.mesh.vertex_count());
    }

    #[test]
    fn split_counts_and_topology() {
        let ico = icosahedron();
        let s1 = split_midpoints(&ico);
        assert_eq!((s1.face_count(), s1.vertex_count()), (80, 42));
        let s2 = split_midpoints(&s1);
        assert_eq!((s2.face_count(), s2.vertex_count()), (320, 162));
        for m in [&ico, &s1, &s2] {
            let st = check_oriented_manifold(m).unwrap();
            assert!(st.is_closed());
            assert_eq!((st.euler_characteristic, st.components, st.genus()), (2, 1, Some(0)));
        }
        // original vertices keep ids and positions
        assert_eq!(&s2.positions()[..12], ico.positions());
        let g = split_midpoints(&grid(4, 3));
        assert_eq!(g.face_count(), 4 * 12);
        let st = check_oriented_manifold(&g).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic), (1, 1));
    }

    #[test]
    fn manifold_checker_counts_loops_and_rejects_bad_input() {
        let st = check_oriented_manifold(&tube(8, 3)).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic, st.components), (2, 0, 1));
        assert_eq!(st.genus(), Some(0));
        // edge (0,1) shared by three triangles
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::NEG_Y];
        let m = TriMesh::from_raw(p.clone(), &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        let want = SimplifyError::Topology(TopologyError::NonManifoldEdge {
            edge: MeshEdge::new(VertexId(0), VertexId(1)),
            faces: 3,
        });
        assert_eq!(check_oriented_manifold(&m).unwrap_err(), want);
        assert_eq!(simplify(&m, &[], &SimplifyOptions::default()).unwrap_err(), want);
        // edge (1,2) used twice in the direction 1 → 2
        let m = TriMesh::from_raw(p.clone(), &[[0, 1, 2], [3, 1, 2]]).unwrap();
        let want = SimplifyError::Topology(TopologyError::InconsistentOrientation {
            edge: MeshEdge::new(VertexId(1), VertexId(2)),
            face_a: FaceId(0),
            face_b: FaceId(1),
        });
        assert_eq!(simplify(&m, &[], &SimplifyOptions::default()).unwrap_err(), want);
        assert_eq!(remesh_unrelated(&m, 10, &SimplifyOptions::default()).unwrap_err(), want);
        // bow tie: two triangles meeting at vertex 0 only
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::NEG_X, DVec3::NEG_Y];
        let m = TriMesh::from_raw(p, &[[0, 1, 2], [0, 3, 4]]).unwrap();
        assert_eq!(
            check_oriented_manifold(&m).unwrap_err(),
            SimplifyError::Topology(TopologyError::NonManifoldVertex { vertex: VertexId(0), fans: 2 })
        );
    }

    #[test]
    fn locked_id_errors_and_bad_options() {
        let g = grid(3, 3);
        let o = SimplifyOptions::default();
        assert_eq!(
            simplify(&g, &[VertexId(1), VertexId(9)], &o).unwrap_err(),
            SimplifyError::LockedOutOfRange { vertex: VertexId(9), count: 9 }
        );
        assert_eq!(
            simplify(&g, &[VertexId(4), VertexId(1), VertexId(4)], &o).unwrap_err(),
            SimplifyError::DuplicateLocked { vertex: VertexId(4) }
        );
        let bad = SimplifyOptions { min_normal_cos: 2.0, ..o };
        assert!(matches!(simplify(&g, &[], &bad), Err(SimplifyError::InvalidOption { option: "min_normal_cos", .. })));
    }

    #[test]
    fn locked_vertices_survive_on_sphere() {
        let s = icosphere(4, 1.0); // 5120 faces
        let locked: Vec<VertexId> = (0..s.vertex_count() as u32).step_by(37).map(VertexId).collect();
        let o = SimplifyOptions { target_faces: Some(600), ..SimplifyOptions::default() };
        let out = simplify(&s, &locked, &o).unwrap();
        assert!(out.mesh.face_count() <= 600 && out.mesh.face_count() >= 590, "{}", out.mesh.face_count());
        assert_locked_exact(&s, &locked, &out);
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.euler_characteristic, st.boundary_edges, st.isolated_vertices), (2, 0, 0));
        assert_eq!(out.contractions, s.vertex_count() - out.mesh.vertex_count());
    }

    #[test]
    fn stop_rule_leaves_only_locked_edges() {
        let g = grid(9, 9);
        let id = |i: u32, j: u32| VertexId(j * 9 + i);
        let locked = vec![id(0, 0), id(8, 0), id(8, 8), id(0, 8), id(2, 2), id(6, 3), id(4, 6), id(3, 4)];
        let out = simplify(&g, &locked, &SimplifyOptions::default()).unwrap();
        assert_locked_exact(&g, &locked, &out);
        assert_eq!(out.mesh.vertex_count(), locked.len());
        let is_locked = |v: u32| locked.contains(&out.vertex_origin[v as usize]);
        for (a, b) in edges_of(&out.mesh) {
            assert!(is_locked(a) && is_locked(b));
        }
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic, st.components), (1, 1, 1));
        // area of the square is kept: boundary vertices only slid along the boundary
        assert!((out.mesh.area() - 64.0).abs() < 1e-9, "{}", out.mesh.area());
        assert!(out.total_error < 1e-18);
    }

    #[test]
    fn stop_rule_uses_flips_when_contraction_is_stuck() {
        // 20 × 20 grid, corners and a scatter of interior vertices locked;
        // pure contraction strands free vertices, flips free them.
        let n = 20u32;
        let g = grid(n as usize, n as usize);
        let locked: Vec<VertexId> = (0..n * n)
            .filter(|&v| {
                let (i, j) = (v % n, v / n);
                let corner = (i == 0 || i == n - 1) && (j == 0 || j == n - 1);
                let interior = i > 0 && j > 0 && i < n - 1 && j < n - 1;
                corner || (interior && (i * 7 + j * 13) % 11 == 0)
            })
            .map(VertexId)
            .collect();
        let strict = SimplifyOptions { flip_to_unblock: false, ..SimplifyOptions::default() };
        assert!(matches!(simplify(&g, &locked, &strict), Err(SimplifyError::StopRuleUnreachable { .. })));
        let out = simplify(&g, &locked, &SimplifyOptions::default()).unwrap();
        assert!(out.flips > 0);
        assert_locked_exact(&g, &locked, &out);
        assert_eq!(out.mesh.vertex_count(), locked.len());
        for (a, b) in edges_of(&out.mesh) {
            assert!(locked.contains(&out.vertex_origin[a as usize]) && locked.contains(&out.vertex_origin[b as usize]));
        }
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic), (1, 1));
        assert!((out.mesh.area() - 361.0).abs() < 1e-9);
        for f in 0..out.mesh.face_count() {
            assert!(out.mesh.face_area_vector(FaceId(f as u32)).z > 0.0);
        }
    }

    #[test]
    fn stop_rule_reports_unreachable() {
        // tetrahedron: any contraction would leave two triangles on the same vertices
        let tet = TriMesh::from_raw(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap();
        assert_eq!(
            simplify(&tet, &[VertexId(0)], &SimplifyOptions::default()).unwrap_err(),
            SimplifyError::StopRuleUnreachable { free_remaining: 3, contractions: 0 }
        );
        // with a face target instead, the same input simply stays as it is
        let o = SimplifyOptions { target_faces: Some(1), ..SimplifyOptions::default() };
        assert_eq!(simplify(&tet, &[VertexId(0)], &o).unwrap().mesh, tet);
    }

    #[test]
    fn planar_grid_stays_planar() {
        let g = grid(21, 16);
        let o = SimplifyOptions { target_faces: Some(40), ..SimplifyOptions::default() };
        let out = simplify(&g, &[VertexId(170)], &o).unwrap();
        assert!(out.mesh.face_count() <= 40);
        assert!(out.mesh.positions().iter().all(|p| p.z == 0.0));
        assert!(out.total_error < 1e-18 && out.max_error < 1e-18, "{}", out.total_error);
        assert!((out.mesh.area() - 300.0).abs() < 1e-9);
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic), (1, 1));
        // every triangle still faces +z
        for f in 0..out.mesh.face_count() {
            assert!(out.mesh.face_area_vector(FaceId(f as u32)).z > 0.0);
        }
    }

    #[test]
    fn boundary_modes() {
        let g = grid(10, 8);
        let on_boundary = |p: DVec3| p.x == 0.0 || p.y == 0.0 || p.x == 9.0 || p.y == 7.0;
        let o = SimplifyOptions { target_faces: Some(0), boundary: BoundaryMode::Fixed, ..SimplifyOptions::default() };
        let out = simplify(&g, &[], &o).unwrap();
        let kept = out.mesh.positions().iter().filter(|p| on_boundary(**p)).count();
        assert_eq!(kept, 2 * (10 + 8) - 4, "every boundary vertex is kept");
        assert!(out.mesh.vertex_count() < g.vertex_count());
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic), (1, 1));
        let o = SimplifyOptions { boundary: BoundaryMode::Free, target_faces: Some(20), ..o };
        let out = simplify(&g, &[], &o).unwrap();
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic), (1, 1));
        assert!(out.mesh.face_count() <= 20);
    }

    #[test]
    fn isolated_vertices_locked_kept_free_dropped() {
        let mut p = grid(4, 4).positions().to_vec();
        p.push(DVec3::splat(9.0)); // 16: isolated, locked
        p.push(DVec3::splat(7.0)); // 17: isolated, free
        let m = TriMesh::new(p, grid(4, 4).triangles().to_vec()).unwrap();
        let st = check_oriented_manifold(&m).unwrap();
        assert_eq!((st.vertices, st.isolated_vertices), (16, 2));
        let locked = [VertexId(16), VertexId(0), VertexId(3), VertexId(12), VertexId(15)];
        let out = simplify(&m, &locked, &SimplifyOptions::default()).unwrap();
        assert_locked_exact(&m, &locked, &out);
        assert_eq!(out.mesh.vertex_count(), 5);
        assert_eq!(out.mesh.face_count(), 2);
    }

    #[test]
    fn boundary_loops_never_merge() {
        let t = tube(12, 4);
        let o = SimplifyOptions { target_faces: Some(0), ..SimplifyOptions::default() };
        let out = simplify(&t, &[], &o).unwrap();
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.boundary_loops, st.euler_characteristic, st.components), (2, 0, 1));
        assert!(out.mesh.face_count() < t.face_count());
    }

    #[test]
    fn sphere_20k_to_2k_stays_round() {
        let s = icosphere(5, 2.0); // 20480 faces
        let o = SimplifyOptions { target_faces: Some(2000), ..SimplifyOptions::default() };
        let out = simplify(&s, &[], &o).unwrap();
        assert!((1990..=2000).contains(&out.mesh.face_count()));
        for p in out.mesh.positions() {
            assert!((p.length() - 2.0).abs() < 0.02 * 2.0, "{}", p.length());
        }
        let st = check_oriented_manifold(&out.mesh).unwrap();
        assert_eq!((st.euler_characteristic, st.boundary_edges), (2, 0));
        // outward orientation kept
        for f in 0..out.mesh.face_count() {
            let f = FaceId(f as u32);
            let c = out.mesh.corners(f);
            assert!(out.mesh.face_area_vector(f).dot(c[0] + c[1] + c[2]) > 0.0);
        }
    }

    #[test]
    fn max_error_stops_early() {
        let s = icosphere(3, 1.0);
        let o =
            SimplifyOptions { stop_when_only_locked_edges: false, max_error: Some(1e-7), ..SimplifyOptions::default() };
        let out = simplify(&s, &[], &o).unwrap();
        assert!(out.mesh.face_count() == s.face_count(), "no contraction on a sphere is that cheap");
        let o = SimplifyOptions { max_error: Some(1e-3), ..o };
        let out = simplify(&s, &[], &o).unwrap();
        assert!(out.mesh.face_count() < s.face_count());
        assert!(out.contractions > 0);
    }

    #[test]
    fn remesh_sphere_hits_target() {
        let s = icosphere(3, 1.0); // 1280 faces
        let target = 3000;
        let r = remesh_unrelated(&s, target, &SimplifyOptions::default()).unwrap();
        assert!(r.face_count().abs_diff(target) <= target / 100, "{}", r.face_count());
        let st = check_oriented_manifold(&r).unwrap();
        assert_eq!((st.euler_characteristic, st.boundary_edges, st.components), (2, 0, 1));
        for p in r.positions() {
            assert!((p.length() - 1.0).abs() < 0.02, "{}", p.length());
        }
    }

    #[test]
    fn remesh_body_sized_sphere() {
        let s = uv_sphere(100, 136, 1.0); // 26 928 faces, like the body scan
        let target = 60_000;
        let t0 = std::time::Instant::now();
        let r = remesh_unrelated(&s, target, &SimplifyOptions::default()).unwrap();
        let dt = t0.elapsed();
        eprintln!(
            "remesh_unrelated {} -> {} faces (QEM input {}) in {dt:?}",
            s.face_count(),
            r.face_count(),
            4 * s.face_count()
        );
        assert!(r.face_count().abs_diff(target) <= target / 100, "{}", r.face_count());
        let st = check_oriented_manifold(&r).unwrap();
        assert_eq!((st.euler_characteristic, st.boundary_edges, st.components), (2, 0, 1));
        for p in r.positions() {
            assert!((p.length() - 1.0).abs() < 0.01, "{}", p.length());
        }
        let worst = (0..r.face_count()).map(|f| quality(r.corners(FaceId(f as u32)))).fold(1.0, f64::min);
        assert!(worst >= REMESH_MIN_QUALITY.min(worst_input_quality(&s)) - 1e-9, "{worst}");
    }

    #[test]
    fn deterministic() {
        let s = icosphere(3, 1.0);
        let locked = [VertexId(3), VertexId(100), VertexId(400)];
        let o = SimplifyOptions { target_faces: Some(300), ..SimplifyOptions::default() };
        assert_eq!(simplify(&s, &locked, &o).unwrap(), simplify(&s, &locked, &o).unwrap());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn random_locked_subsets_survive(mask in proptest::collection::vec(any::<bool>(), 36), target in 0usize..40) {
            let g = grid(6, 6).map_positions(|p| p + DVec3::new(0.0, 0.0, 0.05 * (p.x * p.y).sin())).unwrap();
            let locked: Vec<VertexId> =
                mask.iter().enumerate().filter(|(_, &b)| b).map(|(i, _)| VertexId(i as u32)).collect();
            let o = SimplifyOptions { target_faces: Some(target), ..SimplifyOptions::default() };
            let out = simplify(&g, &locked, &o).unwrap();
            assert_locked_exact(&g, &locked, &out);
            check_oriented_manifold(&out.mesh).unwrap();
            match simplify(&g, &locked, &SimplifyOptions::default()) {
                Ok(out) => {
                    assert_locked_exact(&g, &locked, &out);
                    let st = check_oriented_manifold(&out.mesh).unwrap();
                    prop_assert_eq!(st.boundary_loops, 1);
                }
                Err(SimplifyError::StopRuleUnreachable { .. }) => {}
                Err(e) => prop_assert!(false, "unexpected error {e}"),
            }
        }
    }
}
