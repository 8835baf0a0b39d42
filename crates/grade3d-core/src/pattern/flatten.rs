//! Flattening one garment panel to the plane at true scale, for sewing
//! patterns: a least-squares conformal map as the start, then
//! as-rigid-as-possible local/global iterations in which every boundary edge
//! (every seam) keeps its 3D length.
//!
//! # Contract
//!
//! [`flatten`] takes the vertex `positions` (any length unit) and the
//! `triangles` of one panel that is a **topological disc** and returns one
//! plane point per vertex in the same unit ([`Flattening::uv`]): isometric
//! for a developable panel (cylinder, cone, plane: edge strain ≈ 1e-11),
//! low-distortion otherwise, with every boundary edge at its 3D length to
//! [`FlattenOptions::boundary_tolerance`] (so every seam chain too: the two
//! sides of a seam, flattened in different panels, agree), and
//! counter-clockwise where the input triangles are counter-clockwise seen
//! from the side their normals point to. [`flatten_with_seams`] holds only the named
//! seam chains exact and lets the rest of the boundary (hems) relax;
//! [`flatten_with_sewn_lengths`] holds them at given ratios `ℓ′/ℓ` of their
//! 3D lengths instead (the negotiated seams of [`super::garment`]): every
//! `ℓ_ij` below is then the held length `ratio · ℓ_ij`;
//! [`lscm`] is the start alone; [`distortion`] measures any flattening.
//!
//! # Method
//!
//! **LSCM** (Lévy, Petitjean, Ray & Maillot 2002, "Least squares conformal
//! maps for automatic texture atlas generation", DOI 10.1145/566654.566590),
//! in the cotangent form of Mullen, Tong, Alliez & Desbrun 2008 (DOI
//! 10.1111/j.1467-8659.2008.01287.x), which is the same energy: for
//! `U = u + iv`,
//!
//! ```text
//! E_C(U) = ½∫|∇u|² + ½∫|∇v|² − A(U) = ¼ Uᴴ (L − 4H) U,
//! ∫|∇u|² = ½ Σ_t Σ_{(i,j)∈t} cot θ_t^{ij} (u_i − u_j)²,     A(U) = ½ Σ_{(i→j)∈∂} Im(Ū_i U_j) = Uᴴ H U,
//! ```
//!
//! `θ_t^{ij}` the angle of `t` opposite the edge `ij`, `L` the cotangent
//! Laplacian, `A` the signed area of the image; `E_C ≥ 0` vanishes exactly on
//! orientation-preserving conformal maps. Two boundary vertices are pinned —
//! the two farthest apart in 3D, at `(0, 0)` and `(d, 0)`, `d` their 3D
//! distance (so LSCM's scale is only roughly right) — and the remaining
//! Hermitian system, positive definite for a disc, is solved with faer's
//! sparse Cholesky (`LLᴴ`, complex, AMD ordering).
//!
//! **ARAP** (Liu, Zhang, Xu, Gotsman & Gortler 2008, "A local/global approach
//! to mesh parameterization", DOI 10.1111/j.1467-8659.2008.01290.x), with
//! boundary springs. With `e_t^{ij}` the edge `ij` of triangle `t` laid out
//! isometrically in the triangle's plane and `c_t^{ij} = cot θ_t^{ij}`:
//!
//! ```text
//! E(u, R) = ½ Σ_t Σ_{(i,j)∈t} c_t^{ij} |(u_j − u_i) − R_t e_t^{ij}|²      (= Σ_t A_t ‖J_t − R_t‖²_F)
//!         + ½ w_b Σ_{(i→j)∈∂} |(u_j − u_i) − r_ij d_ij|²                   (springs, w_b = boundary_weight)
//! ```
//!
//! * *local step*: `R_t` is the rotation closest to
//!   `S_t = Σ c_t^{ij} (u_j − u_i)(e_t^{ij})ᵀ`, `(cos, sin) ∝ (S₀₀ + S₁₁,
//!   S₁₀ − S₀₁)` — a proper rotation by construction, so no reflection can
//!   arise; `d_ij` is the boundary edge's present direction;
//! * *global step*: `(L + w_b L_∂) u = b(R, d, r)`, `L_∂` the Laplacian of
//!   the boundary loop. The matrix never changes: it is factored **once**
//!   (faer's sparse Cholesky, the same symbolic analysis as LSCM's) and each
//!   iteration is one pass over the triangles and two triangular solves for
//!   both coordinates at once, without allocation. Translations, the null
//!   space, are removed by holding LSCM's first pin at the origin — an exact
//!   constraint, not a regularisation, since the energy is translation
//!   invariant.
//!
//! **Seam lengths** ([`FlattenOptions::exact_boundary`], beyond the paper).
//! Plain ARAP spreads the strain of curvature over the boundary as well: the
//! rim of a sphere cap of 60° aperture comes out 3.5 % long, a saddle's 2 %
//! short. The springs alone do not fix that (`w_b = 1000` still leaves
//! 0.13 %). So the rest lengths `r_ij` are updated after every global step by
//! the method of multipliers (augmented Lagrangian, penalty `w_b`) for the
//! constraints `|u_j − u_i| = ℓ_ij`, `ℓ_ij` the 3D length:
//! `r_ij ← r_ij − (|u_j − u_i| − ℓ_ij)`. The matrix stays constant, and at
//! the fixed point every boundary edge has its 3D length (to ~1e-7 with the
//! defaults). The price is paid inside: on the 60° cap the area shrinks by
//! 6.7 % instead of 0.04 % (the flat disc with that rim is smaller), edge
//! strain p95 4.8 % instead of 3.4 % — geometry, not the solver: only darts
//! avoid it.
//!
//! **Acceleration.** The fixed-point map `(u, r) ↦ (u′, r′)` of one
//! iteration is Anderson-accelerated ([`FlattenOptions::anderson_depth`];
//! Walker & Ni 2011, DOI 10.1137/10078356X; for local/global solvers Peng,
//! Deng, Zhang, Wang & Gotsman 2018, DOI 10.1145/3197517.3201290), with a
//! restart whenever an accelerated state's residual grows: 2–5× fewer
//! iterations (15 instead of 71 on the 60° cap, 59 instead of 125 on a
//! bodice panel). Where it keeps restarting
//! ([`FlattenOptions::max_anderson_restarts`]) the iteration goes on
//! plainly, to the tighter [`FlattenOptions::plain_tolerance`]: the princess
//! dress's side pieces, where it never converged.
//!
//! **Stopping.** When the ARAP energy changes by less than
//! [`FlattenOptions::tolerance`] of itself in one iteration and (exact
//! boundary) every boundary edge is within
//! [`FlattenOptions::boundary_tolerance`] of its length; when the
//! area-normalised energy is below [`FlattenOptions::energy_floor`] (an
//! isometry: developable panels stop after one iteration, since LSCM is then
//! a similarity, the local step finds the exact rotations and the global step
//! the exact layout); or after [`FlattenOptions::max_iterations`].
//!
//! **Flips.** Exact seams can fold a sliver triangle near a boundary corner
//! (seen on a real bodice panel). Interior vertices of flipped triangles are
//! then moved, each by the least step that puts its star back in order
//! ([`FlattenOptions::untangle_passes`]); boundary vertices never move. Any
//! flip left is counted in [`Flattening::flipped`]. Returning the LSCM map
//! instead ([`FlattenOptions::flip_fallback`]) is off by default: it is
//! flip-free but breaks the seams (2 % on that panel), the worse defect for a
//! pattern.
//!
//! **Metrics** ([`distortion`]; Wang, Smith & Yuen 2002, "Surface flattening
//! based on energy model", Computer-Aided Design 34(11), DOI
//! 10.1016/S0010-4485(01)00162-2): area accuracy `E_s = (A − A′)/A`, length
//! accuracy `E_c = (L − L′)/L`, edge strain `|ℓ′/ℓ − 1|` (mean, 95th
//! percentile, max), flipped triangles, boundary length error (see
//! [`Distortion`]).
//!
//! **Cost.** Linear in the triangles but for the factorisations: for 3,200
//! triangles about 2 ms of set-up (checks, both factorisations) and 0.1 ms
//! per iteration on one core; no threads are spawned.
//!
//! # Preconditions and failure modes
//! Finite coordinates; triangle indices in range; no triangle with a
//! repeated vertex or a relative area below
//! [`FlattenOptions::degenerate_area`]; every edge in at most two triangles,
//! which run it in opposite directions; a single fan of triangles around
//! every vertex; one connected piece; one boundary loop and Euler
//! characteristic `V − E + F = 1` (a disc); options in range. Each violation
//! is a [`FlattenError`] naming the offending element, checked in that
//! order; a numerically singular system (e.g. absurd weights) is
//! [`FlattenError::Factorisation`]. No input panics. Vertices in no triangle
//! are allowed and map to `(0, 0)`. Coordinates are rescaled internally by a
//! power of two (exactly), so any unit works, from nanometres to light
//! years.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{Argsort, FaerError, Pair, SparseColMat, SymbolicSparseColMat};
use faer::traits::ComplexField;
use faer::{c64, Conj, MatMut, Par, Side};
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use typed_index_collections::{TiSlice, TiVec};

use crate::geom::topology::{
    check_edge_uses, check_vertex_fans, triangle_edge_uses, MeshEdge, TopologyError, UnionFind,
};
use crate::pattern::panels::{PanelFace, PanelVertex};

/// Knobs of [`flatten`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FlattenOptions {
    /// Most ARAP local/global iterations (count). Default 1000 (at 300 the
    /// princess dress's back pieces, 1.35 m long, stopped short of
    /// converging: on `male-slim-tall-caucasian` their seams' two sides
    /// were left 10–18 mm apart; a piece that converges stops sooner).
    /// `0` returns the LSCM map as it is (scale set by the pins, not by
    /// the area).
    pub max_iterations: usize,
    /// ARAP stops when its energy changes by less than this fraction of
    /// itself in one iteration (dimensionless, ≥ 0). Default 1e-6.
    pub tolerance: f64,
    /// ARAP also stops when the area-normalised energy `E/A` — the
    /// area-weighted mean of `‖J − R‖²_F` — is below this (dimensionless,
    /// ≥ 0): the map is then isometric to rounding. Default 1e-20.
    pub energy_floor: f64,
    /// Stiffness `w_b` of the springs on the boundary edges relative to the
    /// cotangent weights, and the penalty of the multiplier updates
    /// (dimensionless, ≥ 0; 0 is the plain ARAP of the paper). With exact
    /// boundaries it sets the speed, not the result: 3 to 100 all converge
    /// to the same map, 10 in the fewest iterations over the test panels.
    /// Default 10.
    pub boundary_weight: f64,
    /// Stiffness of the springs on the boundary edges that are not seams when
    /// [`flatten_with_seams`] names the seams (hems, free edges: pulled
    /// towards their 3D length, never corrected), relative to the cotangent
    /// weights (dimensionless, ≥ 0; 0 leaves them to plain ARAP). Default 1:
    /// over the 160 library pieces (3 garments × 20 bodies and sizes) the
    /// worst |E_s| is 1.2 % (skirts), 1.5 % (trousers), 2.4 % (bodice); 0
    /// gives 1.0, 1.5, 1.9 % but a skirt's worst edge strain 24 % instead of
    /// 19 %; 10, as stiff as a seam, 2.3, 1.8, 4.4 %.
    pub hem_weight: f64,
    /// Correct the springs' rest lengths after every global step (method of
    /// multipliers, module docs) so that every boundary edge converges to its
    /// 3D length; without it the springs only pull (bool; needs
    /// `boundary_weight > 0`). Default true.
    pub exact_boundary: bool,
    /// Depth of the Anderson acceleration of the ARAP iterations (count of
    /// past iterates used, at most [`MAX_ANDERSON_DEPTH`]; 0 iterates
    /// plainly). Default 5.
    pub anderson_depth: usize,
    /// Restarts of the Anderson acceleration after which the iteration goes
    /// on plainly, to [`Self::plain_tolerance`] (count). On the princess
    /// dress's side pieces the accelerated iteration restarted about every
    /// fifth step (157–188 restarts in 1000) and never converged, its seams'
    /// residual growing to 3 %, so the pieces' shoulders jumped 2–3 mm from
    /// size to size; plain iterations converge there in 200–650 (measured).
    /// Default 20.
    pub max_anderson_restarts: usize,
    /// [`Self::tolerance`] once the iteration goes on plainly after
    /// [`Self::max_anderson_restarts`] (dimensionless, ≥ 0): a plain
    /// iteration's energy falls slowly, and at 1e-6 it stopped while the
    /// dress's pieces were still settling (9 of 270 grade points over the
    /// step bar on the men's chart against 5 at 1e-9, measured). Default 1e-9.
    pub plain_tolerance: f64,
    /// With `exact_boundary`, convergence also needs every boundary edge
    /// within this relative error of its 3D length (dimensionless, ≥ 0).
    /// Default 1e-5.
    pub boundary_tolerance: f64,
    /// A triangle is degenerate when twice its area is at most this times
    /// its longest edge squared (dimensionless, ≥ 0; the sine of its
    /// smallest angle, roughly). Default 1e-12.
    pub degenerate_area: f64,
    /// LSCM pins the two boundary vertices farthest apart; pairs whose 3D
    /// distance is within this fraction of the largest are ties, broken by
    /// the lowest vertex numbers, so that rounding (a change of unit, a
    /// rigid motion) cannot move the pins of a symmetric panel
    /// (dimensionless, ≥ 0). Default 1e-9.
    pub pin_tie: f64,
    /// Boundary vertex count up to which LSCM's pins are the exact farthest
    /// pair (`O(b²)` distances); above it, repeated farthest-point sweeps
    /// (`O(b)` each) find a mutually farthest pair, so that a huge boundary
    /// cannot stall a request (count). Default 2048.
    pub pin_search_limit: usize,
    /// Passes of local untangling when ARAP leaves flipped triangles: each
    /// interior vertex of a flipped triangle moves the least distance
    /// towards the point deepest inside the kernel of its star (the polygon
    /// of its neighbours) that gives each of its triangles at least half the
    /// height it can have there, up to half its 3D height — so that the
    /// triangles come out counter-clockwise and not slivers (count; 0 leaves
    /// flips as they are). Boundary vertices never move, so seam lengths are
    /// untouched. Default 8.
    pub untangle_passes: usize,
    /// When flipped triangles remain after untangling and the LSCM map has
    /// none, return the LSCM map scaled to the 3D area instead (bool). Off by
    /// default: that map breaks the seam lengths (module docs). Default
    /// false.
    pub flip_fallback: bool,
}

impl Default for FlattenOptions {
    fn default() -> Self {
        Self {
            max_iterations: 1000,
            tolerance: 1e-6,
            energy_floor: 1e-20,
            boundary_weight: 10.0,
            exact_boundary: true,
            hem_weight: 1.0,
            anderson_depth: 5,
            max_anderson_restarts: 20,
            plain_tolerance: 1e-9,
            boundary_tolerance: 1e-5,
            degenerate_area: 1e-12,
            pin_tie: 1e-9,
            pin_search_limit: 2048,
            untangle_passes: 8,
            flip_fallback: false,
        }
    }
}

/// Why a panel could not be flattened. Vertex and triangle ids are the
/// panel's.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlattenError {
    /// No triangles.
    #[error("the panel has no triangles")]
    Empty,
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// The vertex.
        vertex: PanelVertex,
    },
    /// A triangle refers to a vertex beyond the vertex array.
    #[error("triangle {face} refers to vertex {index}, beyond the vertex array")]
    IndexOutOfRange {
        /// The triangle.
        face: PanelFace,
        /// The index it holds.
        index: PanelVertex,
    },
    /// A triangle repeats a vertex or has (relatively) no area.
    #[error("triangle {face} is degenerate")]
    DegenerateTriangle {
        /// The triangle.
        face: PanelFace,
    },
    /// Not an oriented manifold: an edge of three or more triangles, one run
    /// twice in the same direction, or a "bow tie" vertex.
    #[error(transparent)]
    Topology(#[from] TopologyError<MeshEdge<PanelVertex>, PanelVertex>),
    /// The triangles form more than one connected piece.
    #[error("vertex {vertex} is not connected to the piece of the first triangle")]
    Disconnected {
        /// A vertex outside the first piece.
        vertex: PanelVertex,
    },
    /// The panel is not a topological disc.
    #[error("the panel is not a disc: {boundary_loops} boundary loops, Euler characteristic {euler}")]
    NotADisc {
        /// Boundary loops found.
        boundary_loops: usize,
        /// `V − E + F` (1 for a disc).
        euler: i64,
    },
    /// A seam chain names a vertex beyond the vertex array or in no triangle.
    #[error("seam chain {seam} names vertex {vertex}, which is in no triangle")]
    SeamVertex {
        /// The chain (index into the caller's list).
        seam: usize,
        /// The vertex.
        vertex: PanelVertex,
    },
    /// A sewn-length ratio ([`flatten_with_sewn_lengths`]) is not finite and positive.
    #[error("seam chain {seam}, edge {edge}: sewn-length ratio {ratio} is not finite and positive")]
    SewnRatio {
        /// The chain (index into the caller's list).
        seam: usize,
        /// The edge of the chain.
        edge: usize,
        /// The ratio given.
        ratio: f64,
    },
    /// An option is out of its range: a real one negative or not finite,
    /// or [`FlattenOptions::anderson_depth`] above [`MAX_ANDERSON_DEPTH`].
    #[error("option {field} is out of range")]
    InvalidOption {
        /// The field of [`FlattenOptions`].
        field: &'static str,
    },
    /// The sparse Cholesky factorisation failed (numerically singular system).
    #[error("sparse factorisation failed: {0}")]
    Factorisation(String),
}

/// A flattened panel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Flattening {
    /// Plane position of every input vertex, in the input unit (`(0, 0)` for
    /// vertices in no triangle).
    pub uv: TiVec<PanelVertex, DVec2>,
    /// ARAP iterations (global solves) done.
    pub iterations: usize,
    /// Whether ARAP met its stopping criterion before `max_iterations`.
    pub converged: bool,
    /// ARAP energy `½ Σ_t Σ c |Δu − R Δx|² = Σ_t A_t ‖J_t − R_t‖²_F` of the
    /// ARAP map (input unit²; springs excluded).
    pub energy: f64,
    /// The two vertices LSCM pinned.
    pub lscm_pins: [PanelVertex; 2],
    /// Largest relative length error `|ℓ′/ℓ − 1|` of a boundary edge in `uv`
    /// (dimensionless); bounds the relative length error of every boundary
    /// chain.
    pub boundary_residual: f64,
    /// Triangles with non-positive signed area in `uv`.
    pub flipped: usize,
    /// Interior vertices moved after ARAP to unflip their triangles
    /// ([`FlattenOptions::untangle_passes`]).
    pub untangled: usize,
    /// Whether ARAP had flips and the LSCM map (scaled to the 3D area) was
    /// returned instead.
    pub fallback: bool,
}

/// Distortion of a flattening (Wang, Smith & Yuen 2002; module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Distortion {
    /// Area accuracy `E_s = (A − A′)/A`: `A` the 3D area, `A′` the sum of the
    /// 2D triangle areas (absolute values).
    pub area_accuracy: f64,
    /// Length accuracy `E_c = (L − L′)/L`: `L`, `L′` the total 3D and 2D
    /// length over all unique edges.
    pub length_accuracy: f64,
    /// Mean edge strain `|ℓ′/ℓ − 1|` over unique edges.
    pub strain_mean: f64,
    /// 95th percentile of the edge strain (nearest rank: the
    /// `⌈0.95 m⌉`-th smallest of `m`).
    pub strain_p95: f64,
    /// Largest edge strain.
    pub strain_max: f64,
    /// Triangles whose 2D signed area is ≤ 0 once the map is mirrored, if
    /// needed, so that its total signed area is positive.
    pub flipped: usize,
    /// `(B′ − B)/B`: signed relative error of the total boundary length
    /// (edges in one triangle).
    pub boundary_length_error: f64,
    /// Largest boundary edge strain `|ℓ′/ℓ − 1|`; bounds the relative length
    /// error of every boundary chain (seam).
    pub boundary_strain_max: f64,
}

/// Largest accepted [`FlattenOptions::anderson_depth`] (count).
pub const MAX_ANDERSON_DEPTH: usize = 64;

/// Percentile reported as [`Distortion::strain_p95`].
const STRAIN_PERCENTILE: f64 = 0.95;

/// Least-squares conformal map of the panel (module docs): the two boundary
/// vertices farthest apart in 3D pinned at `(0, 0)` and `(d, 0)`, `d` their
/// 3D distance. Vertices in no triangle map to `(0, 0)`.
///
/// # Errors
/// [`FlattenError`] for input that is not a valid disc (default
/// [`FlattenOptions::degenerate_area`]), or a failed factorisation.
pub fn lscm(
    positions: &TiSlice<PanelVertex, DVec3>,
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
) -> Result<TiVec<PanelVertex, DVec2>, FlattenError> {
    let o = FlattenOptions::default();
    let mesh = Mesh::new(positions, triangles, o.degenerate_area)?;
    let (uv, _) = mesh.lscm(&Sparse::new(&mesh)?, o.pin_tie, o.pin_search_limit)?;
    Ok(mesh.export(&uv))
}

/// Flattens the panel: LSCM, then ARAP with every boundary edge held at its
/// 3D length (module docs); [`flatten_with_seams`] with no chains.
///
/// # Errors
/// [`FlattenError`]: invalid options or input, or a failed factorisation.
pub fn flatten(
    positions: &TiSlice<PanelVertex, DVec3>,
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
    opts: &FlattenOptions,
) -> Result<Flattening, FlattenError> {
    flatten_with_seams(positions, triangles, &[], opts)
}

/// [`flatten`], told which parts of the boundary are seams: `seams` are
/// chains of vertices (input numbering), and only the boundary edges between
/// consecutive vertices of a chain (either direction) are held at their 3D
/// length; the other boundary edges (hems, free edges) keep only soft
/// springs towards it ([`FlattenOptions::hem_weight`]), which lets them
/// absorb some of the strain of curvature. With
/// no chains every boundary edge is a seam. Chain edges that are not
/// boundary edges are ignored.
///
/// # Errors
/// [`FlattenError`]: invalid options or input, a chain vertex beyond the
/// vertex array or in no triangle ([`FlattenError::SeamVertex`]), or a failed
/// factorisation.
pub fn flatten_with_seams(
    positions: &TiSlice<PanelVertex, DVec3>,
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
    seams: &[Vec<PanelVertex>],
    opts: &FlattenOptions,
) -> Result<Flattening, FlattenError> {
    flatten_with_sewn_lengths(positions, triangles, seams, &[], opts)
}

/// [`flatten_with_seams`] with the seams held at lengths other than their
/// 3D ones: `sewn[k][i]` (when given) is the ratio `ℓ′/ℓ` that the `i`-th
/// edge of chain `k` (from `seams[k][i]` to `seams[k][i + 1]`) is held at,
/// `ℓ` its 3D length; missing entries are 1. Two panels flattened with the
/// same ratios on a shared chain sew up edge for edge.
///
/// # Errors
/// As [`flatten_with_seams`]; also [`FlattenError::SewnRatio`].
pub fn flatten_with_sewn_lengths(
    positions: &TiSlice<PanelVertex, DVec3>,
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
    seams: &[Vec<PanelVertex>],
    sewn: &[Vec<f64>],
    opts: &FlattenOptions,
) -> Result<Flattening, FlattenError> {
    opts.validate()?;
    let mut mesh = Mesh::new(positions, triangles, opts.degenerate_area)?;
    let mut chain_edges = Vec::new();
    for (k, chain) in seams.iter().enumerate() {
        let local = |v: PanelVertex| match mesh.compact.get(v) {
            Some(&c) if c != u32::MAX => Ok(c),
            _ => Err(FlattenError::SeamVertex { seam: k, vertex: v }),
        };
        for (i, pair) in chain.windows(2).enumerate() {
            let ratio = sewn.get(k).and_then(|r| r.get(i)).copied().unwrap_or(1.0);
            if !(ratio.is_finite() && ratio > 0.0) {
                return Err(FlattenError::SewnRatio { seam: k, edge: i, ratio });
            }
            chain_edges.push((edge_key(local(pair[0])?, local(pair[1])?), ratio));
        }
        if let [v] = chain[..] {
            local(v)?;
        }
    }
    chain_edges.sort_unstable_by_key(|a| a.0);
    let mut seam = vec![seams.is_empty(); mesh.boundary.len()];
    for (k, e) in mesh.boundary.iter().enumerate() {
        if let Ok(at) = chain_edges.binary_search_by(|c| c.0.cmp(&edge_key(e[0], e[1]))) {
            seam[k] = true;
            mesh.boundary_length[k] *= chain_edges[at].1;
        }
    }
    let sparse = Sparse::new(&mesh)?;
    let (start, pins) = mesh.lscm(&sparse, opts.pin_tie, opts.pin_search_limit)?;
    let arap = mesh.arap(&sparse, &start, pins[0], &seam, opts)?;
    let mut uv = arap.uv;
    if opts.exact_boundary && opts.boundary_weight > 0.0 && seam.iter().any(|&s| !s) {
        // the seams end somewhere: lay each run of seam edges exactly, unless that folds a triangle
        let before = mesh.flips(&uv);
        let mut trued = uv.clone();
        mesh.true_runs(&mut trued, &seam);
        if mesh.flips(&trued) <= before {
            uv = trued;
        }
    }
    let mut flipped = mesh.flips(&uv);
    let mut untangled = 0;
    if flipped > 0 {
        untangled = mesh.untangle(&mut uv, opts.untangle_passes);
        flipped = mesh.flips(&uv);
    }
    let mut fallback = false;
    if flipped > 0 && opts.flip_fallback && mesh.flips(&start) == 0 {
        let area: f64 = mesh.tris.iter().map(|t| signed_area(t.map(|i| start[i as usize]))).sum();
        let k = if area > 0.0 { (mesh.area / area).sqrt() } else { 1.0 };
        uv = start.iter().map(|p| *p * k).collect();
        flipped = 0;
        fallback = true;
    }
    let boundary_residual = mesh
        .boundary
        .iter()
        .zip(&mesh.boundary_length)
        .zip(&seam)
        .filter(|(_, &s)| s)
        .map(|((e, l), _)| (uv[e[1] as usize].distance(uv[e[0] as usize]) / l - 1.0).abs())
        .fold(0.0, f64::max);
    Ok(Flattening {
        uv: mesh.export(&uv),
        iterations: arap.iterations,
        converged: arap.converged,
        energy: arap.energy / (mesh.scale * mesh.scale),
        lscm_pins: pins.map(|p| mesh.verts[p as usize]),
        boundary_residual,
        flipped,
        untangled,
        fallback,
    })
}

/// Distortion figures of `uv` against the 3D panel ([`Distortion`]).
/// Triangles with an index beyond `positions` or `uv` are skipped, so are
/// zero-length edges for the strain; never panics.
pub fn distortion(
    positions: &TiSlice<PanelVertex, DVec3>,
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
    uv: &TiSlice<PanelVertex, DVec2>,
) -> Distortion {
    let n = positions.len().min(uv.len());
    let valid: Vec<[PanelVertex; 3]> = triangles.iter().filter(|t| t.iter().all(|i| i.idx() < n)).copied().collect();
    let (mut a3, mut a2, mut total) = (0.0, 0.0, 0.0);
    let mut signed = Vec::with_capacity(valid.len());
    for t in &valid {
        let [a, b, c] = t.map(|i| positions[i]);
        a3 += 0.5 * (b - a).cross(c - a).length();
        let s = signed_area(t.map(|i| uv[i]));
        a2 += s.abs();
        total += s;
        signed.push(s);
    }
    let orient = if total < 0.0 { -1.0 } else { 1.0 };
    let flipped = signed.iter().filter(|&&s| orient * s <= 0.0).count();
    let mut keys: Vec<u64> = valid
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|(i, j)| i != j)
        .map(|(i, j)| edge_key(i.0, j.0))
        .collect();
    keys.sort_unstable();
    let (mut l3, mut l2, mut b3, mut b2, mut bmax) = (0.0, 0.0, 0.0, 0.0, 0.0f64);
    let mut strains = Vec::with_capacity(keys.len() / 2 + 1);
    for group in keys.chunk_by(|a, b| a == b) {
        let (i, j) = split_key(group[0]);
        let (i, j) = (PanelVertex(i), PanelVertex(j));
        let d3 = positions[i].distance(positions[j]);
        let d2 = uv[i].distance(uv[j]);
        l3 += d3;
        l2 += d2;
        let strain = if d3 > 0.0 { Some((d2 / d3 - 1.0).abs()) } else { None };
        if group.len() == 1 {
            b3 += d3;
            b2 += d2;
            bmax = bmax.max(strain.unwrap_or(0.0));
        }
        strains.extend(strain);
    }
    strains.sort_by(f64::total_cmp);
    let ratio = |x: f64, y: f64| if x > 0.0 { (x - y) / x } else { 0.0 };
    let m = strains.len();
    Distortion {
        area_accuracy: ratio(a3, a2),
        length_accuracy: ratio(l3, l2),
        strain_mean: if m > 0 { strains.iter().sum::<f64>() / m as f64 } else { 0.0 },
        strain_p95: if m > 0 { strains[((STRAIN_PERCENTILE * m as f64).ceil() as usize).clamp(1, m) - 1] } else { 0.0 },
        strain_max: strains.last().copied().unwrap_or(0.0),
        flipped,
        boundary_length_error: if b3 > 0.0 { (b2 - b3) / b3 } else { 0.0 },
        boundary_strain_max: bmax,
    }
}

impl FlattenOptions {
    fn validate(&self) -> Result<(), FlattenError> {
        for (field, x) in [
            ("tolerance", self.tolerance),
            ("plain_tolerance", self.plain_tolerance),
            ("energy_floor", self.energy_floor),
            ("boundary_weight", self.boundary_weight),
            ("hem_weight", self.hem_weight),
            ("boundary_tolerance", self.boundary_tolerance),
            ("degenerate_area", self.degenerate_area),
            ("pin_tie", self.pin_tie),
        ] {
            if !(x.is_finite() && x >= 0.0) {
                return Err(FlattenError::InvalidOption { field });
            }
        }
        if self.anderson_depth > MAX_ANDERSON_DEPTH {
            return Err(FlattenError::InvalidOption { field: "anderson_depth" });
        }
        Ok(())
    }
}

/// Signed area of a 2D triangle (positive when counter-clockwise).
fn signed_area([a, b, c]: [DVec2; 3]) -> f64 {
    0.5 * (b - a).perp_dot(c - a)
}

/// Undirected edge key, smaller index in the high half.
fn edge_key(i: u32, j: u32) -> u64 {
    (u64::from(i.min(j)) << 32) | u64::from(i.max(j))
}

fn split_key(k: u64) -> (u32, u32) {
    ((k >> 32) as u32, k as u32)
}

/// The checked panel in compact numbering (referenced vertices only) and
/// rescaled coordinates. The compact numbering is the solver's (rows of its
/// sparse systems), hence plain `u32`; the panel's ids are typed.
struct Mesh {
    /// Compact → input vertex.
    verts: Vec<PanelVertex>,
    /// Input → compact vertex (`u32::MAX`: in no triangle).
    compact: TiVec<PanelVertex, u32>,
    /// Triangles, compact numbering.
    tris: Vec<[u32; 3]>,
    /// Per triangle, edge `k` (corner `k` → corner `k+1`) laid out in its plane.
    edges: Vec<[DVec2; 3]>,
    /// Per triangle, cotangent of the angle opposite edge `k`.
    cot: Vec<[f64; 3]>,
    /// Total 3D area (rescaled unit²).
    area: f64,
    /// The boundary loop, directed edges in order (compact).
    boundary: Vec<[u32; 2]>,
    /// The corner `3 f + k` whose edge `k` of triangle `f` is each boundary edge.
    boundary_corner: Vec<usize>,
    /// 3D length of each boundary edge (rescaled unit).
    boundary_length: Vec<f64>,
    /// Rescaled 3D positions (compact).
    pos: Vec<DVec3>,
    /// The power of two the input was multiplied by.
    scale: f64,
}

impl Mesh {
    fn new(
        positions: &TiSlice<PanelVertex, DVec3>,
        triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
        degenerate_area: f64,
    ) -> Result<Self, FlattenError> {
        if triangles.is_empty() {
            return Err(FlattenError::Empty);
        }
        if let Some(v) = positions.position(|p| !p.is_finite()) {
            return Err(FlattenError::NonFinite { vertex: v });
        }
        let mut compact: TiVec<PanelVertex, u32> = TiVec::from(vec![u32::MAX; positions.len()]);
        for (f, t) in triangles.iter_enumerated() {
            for &i in t {
                match compact.get_mut(i) {
                    Some(c) => *c = 0,
                    None => return Err(FlattenError::IndexOutOfRange { face: f, index: i }),
                }
            }
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                return Err(FlattenError::DegenerateTriangle { face: f });
            }
        }
        let mut verts = Vec::new();
        for (v, c) in compact.iter_mut_enumerated() {
            if *c != u32::MAX {
                *c = verts.len() as u32;
                verts.push(v);
            }
        }
        let largest = verts.iter().map(|&v| positions[v].abs().max_element()).fold(0.0, f64::max);
        let scale = if largest > 0.0 {
            // 2^-e with |coordinates| · 2^-e ≤ 1: exact, and far from overflow and underflow
            let e = (largest.log2().ceil() as i32).clamp(1 - f64::MAX_EXP, f64::MAX_EXP - 1);
            2f64.powi(-e)
        } else {
            1.0
        };
        let pos: Vec<DVec3> = verts.iter().map(|&v| positions[v] * scale).collect();
        let tris: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(|i| compact[i])).collect();
        let n = verts.len();

        let mut edges = Vec::with_capacity(tris.len());
        let mut cot = Vec::with_capacity(tris.len());
        let mut area = 0.0;
        for (f, t) in tris.iter().enumerate() {
            let [a, b, c] = t.map(|i| pos[i as usize]);
            let (e1, e2) = (b - a, c - a);
            let twice = e1.cross(e2).length();
            let longest = e1.length_squared().max(e2.length_squared()).max((c - b).length_squared());
            if !(twice > degenerate_area * longest && twice.is_finite()) {
                return Err(FlattenError::DegenerateTriangle { face: PanelFace::from(f) });
            }
            let l = e1.length();
            let p = [DVec2::ZERO, DVec2::new(l, 0.0), DVec2::new(e1.dot(e2) / l, twice / l)];
            edges.push([p[1] - p[0], p[2] - p[1], p[0] - p[2]]);
            cot.push(std::array::from_fn(|k| {
                let o = p[(k + 2) % 3];
                (p[k] - o).dot(p[(k + 1) % 3] - o) / twice
            }));
            area += 0.5 * twice;
        }

        // unique edges: boundary (one triangle), interior (two, opposite directions); one fan
        // per vertex. Checked in the panel's ids, which the errors name (a face and its
        // corners are the same in both numberings).
        let checked = check_edge_uses(triangle_edge_uses(&triangles.raw))?;
        check_vertex_fans(&triangles.raw, positions.len(), &checked)?;
        let mut next = vec![(u32::MAX, 0); n];
        for e in checked.iter().filter(|e| e.second.is_none()) {
            let corner = 3 * e.first.face.idx() + usize::from(e.first.corner);
            let t = tris[corner / 3];
            next[t[corner % 3] as usize] = (t[(corner % 3 + 1) % 3], corner);
        }
        let unique_edges = checked.len() as i64;
        let mut pieces = UnionFind::new(n);
        for t in &tris {
            pieces.union(t[0], t[1]);
            pieces.union(t[0], t[2]);
        }
        let first = pieces.find(tris[0][0]);
        if let Some(v) = (0..n).find(|&v| pieces.find(v as u32) != first) {
            return Err(FlattenError::Disconnected { vertex: verts[v] });
        }

        // boundary loops: with single fans every boundary vertex has one successor
        let mut seen = vec![false; n];
        let mut loops = 0;
        let (mut boundary, mut boundary_corner) = (Vec::new(), Vec::new());
        for s in 0..n {
            if next[s].0 == u32::MAX || seen[s] {
                continue;
            }
            loops += 1;
            let mut v = s;
            while !seen[v] && next[v].0 != u32::MAX {
                seen[v] = true;
                if loops == 1 {
                    boundary.push([v as u32, next[v].0]);
                    boundary_corner.push(next[v].1);
                }
                v = next[v].0 as usize;
            }
        }
        let euler = n as i64 - unique_edges + tris.len() as i64;
        if loops != 1 || euler != 1 {
            return Err(FlattenError::NotADisc { boundary_loops: loops, euler });
        }
        let boundary_length = boundary.iter().map(|e| pos[e[0] as usize].distance(pos[e[1] as usize])).collect();
        Ok(Self { verts, compact, tris, edges, cot, area, boundary, boundary_corner, boundary_length, pos, scale })
    }

    /// Input-numbered, input-unit copy of a compact map.
    fn export(&self, uv: &[DVec2]) -> TiVec<PanelVertex, DVec2> {
        self.compact
            .iter()
            .map(|&c| match c {
                u32::MAX => DVec2::ZERO,
                c => uv[c as usize] / self.scale,
            })
            .collect()
    }

    /// Lays every maximal run of consecutive seam edges along the boundary
    /// loop again with each edge at exactly its 3D length, in its present
    /// direction, from the run's middle vertex outwards: the iterations leave
    /// edges within `boundary_tolerance` (≈ 10 µm per metre), this removes
    /// the rest while moving vertices by about as much. A loop made only of
    /// seams has no ends to absorb the change and is left as it is.
    fn true_runs(&self, uv: &mut [DVec2], seam: &[bool]) {
        let b = self.boundary.len();
        // start on a non-seam edge, so that no run wraps past the start
        let Some(mut k) = (0..b).find(|&k| !seam[k]) else { return };
        let mut visited = 0;
        let mut run = Vec::new();
        while visited < b {
            run.clear();
            while seam[k] && visited < b {
                run.push(k);
                k = (k + 1) % b;
                visited += 1;
            }
            if run.is_empty() {
                k = (k + 1) % b;
                visited += 1;
                continue;
            }
            let mid = run.len() / 2;
            // vertices of the run: boundary[run[i]][0] for i < len, then the last edge's end
            let vertex = |i: usize| if i < run.len() { self.boundary[run[i]][0] } else { self.boundary[run[i - 1]][1] };
            for (i, &edge) in run.iter().enumerate().skip(mid) {
                let (a, c) = (vertex(i) as usize, vertex(i + 1) as usize);
                let d = (uv[c] - uv[a]).normalize_or_zero();
                uv[c] = uv[a] + d * self.boundary_length[edge];
            }
            for (i, &edge) in run.iter().enumerate().take(mid).rev() {
                let (a, c) = (vertex(i + 1) as usize, vertex(i) as usize);
                let d = (uv[c] - uv[a]).normalize_or_zero();
                uv[c] = uv[a] + d * self.boundary_length[edge];
            }
        }
    }

    /// Local untangling ([`FlattenOptions::untangle_passes`]); returns the
    /// number of vertex moves.
    fn untangle(&self, uv: &mut [DVec2], passes: usize) -> usize {
        let n = uv.len();
        let mut on_boundary = vec![false; n];
        for e in &self.boundary {
            on_boundary[e[0] as usize] = true;
        }
        // triangles around each vertex (CSR)
        let mut start = vec![0usize; n + 1];
        for t in &self.tris {
            for &v in t {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut around = vec![0u32; 3 * self.tris.len()];
        for (f, t) in self.tris.iter().enumerate() {
            for &v in t {
                around[fill[v as usize]] = f as u32;
                fill[v as usize] += 1;
            }
        }
        let star_ok = |uv: &[DVec2], v: usize, at: DVec2| {
            around[start[v]..start[v + 1]].iter().all(|&f| {
                signed_area(self.tris[f as usize].map(|i| if i as usize == v { at } else { uv[i as usize] })) > 0.0
            })
        };
        let mut moves = 0;
        let mut star = Vec::new();
        for _ in 0..passes {
            let mut any = false;
            for (f, t) in self.tris.iter().enumerate() {
                if signed_area(t.map(|i| uv[i as usize])) > 0.0 {
                    continue;
                }
                any = true;
                for &v in t {
                    let v = v as usize;
                    if on_boundary[v] {
                        continue;
                    }
                    star.clear();
                    star.extend(around[start[v]..start[v + 1]].iter().map(|&g| {
                        let (t, e) = (self.tris[g as usize], self.edges[g as usize]);
                        let k = t.iter().position(|&w| w as usize == v).unwrap_or(0);
                        let opposite = e[(k + 1) % 3];
                        let height = e[0].perp_dot(e[1]) / opposite.length();
                        (uv[t[(k + 1) % 3] as usize], uv[t[(k + 2) % 3] as usize], height)
                    }));
                    if let Some((centre, lambda)) = kernel_centre(&star) {
                        // the least step towards the centre that gives every triangle at
                        // least half of the height it can have (at most half its 3D height)
                        let want = 0.5 * lambda.min(1.0);
                        let here = uv[v];
                        let gap = |x: DVec2, &(a, b, h): &(DVec2, DVec2, f64)| {
                            (b - a).perp().normalize_or_zero().dot(x - a) - want * h
                        };
                        let step = star.iter().fold(0.0f64, |t, l| {
                            let (g0, g1) = (gap(here, l), gap(centre, l));
                            if g0 < 0.0 && g1 > g0 {
                                t.max(-g0 / (g1 - g0))
                            } else {
                                t
                            }
                        });
                        let at = here + (centre - here) * step.min(1.0);
                        if star_ok(uv, v, at) {
                            uv[v] = at;
                            moves += 1;
                        }
                    }
                    if signed_area(self.tris[f].map(|i| uv[i as usize])) > 0.0 {
                        break;
                    }
                }
            }
            if !any {
                break;
            }
        }
        moves
    }

    fn flips(&self, uv: &[DVec2]) -> usize {
        self.tris.iter().filter(|t| signed_area(t.map(|i| uv[i as usize])) <= 0.0).count()
    }

    /// LSCM's pins ([`FlattenOptions::pin_search_limit`],
    /// [`FlattenOptions::pin_tie`]), lower number first.
    fn pins(&self, tie: f64, limit: usize) -> [u32; 2] {
        let ring: Vec<u32> = self.boundary.iter().map(|e| e[0]).collect();
        let d2 = |[a, b]: [u32; 2]| self.pos[a as usize].distance_squared(self.pos[b as usize]);
        let keep = 1.0 - tie.min(1.0);
        if ring.len() <= limit {
            let pairs =
                || ring.iter().enumerate().flat_map(|(k, &a)| ring[k + 1..].iter().map(move |&b| [a.min(b), a.max(b)]));
            let most = pairs().map(d2).fold(0.0, f64::max);
            return pairs().filter(|&p| d2(p) >= most * keep * keep).min().unwrap_or([ring[0], ring[1]]);
        }
        // the vertex farthest from `a`, ties to the lowest number
        let far = |a: u32| {
            let most = ring.iter().map(|&b| d2([a, b])).fold(0.0, f64::max);
            ring.iter().copied().filter(|&b| d2([a, b]) >= most * keep * keep).min().unwrap_or(a)
        };
        let mut a = ring.iter().copied().min().unwrap_or(0);
        let mut b = far(a);
        for _ in 0..ring.len() {
            let c = far(b);
            if c == a {
                break;
            }
            (a, b) = (b, c);
        }
        [a.min(b), a.max(b)]
    }

    /// LSCM (module docs) on the shared sparsity; returns the compact map and
    /// its pins.
    fn lscm(&self, sparse: &Sparse, pin_tie: f64, pin_limit: usize) -> Result<(Vec<DVec2>, [u32; 2]), FlattenError> {
        let n = self.pos.len();
        let pins = self.pins(pin_tie, pin_limit);
        let best = self.pos[pins[0] as usize].distance_squared(self.pos[pins[1] as usize]);
        let fixed = [c64::new(0.0, 0.0), c64::new(best.sqrt(), 0.0)];
        let pin_value = |v: usize| pins.iter().position(|&p| p as usize == v).map(|k| fixed[k]);
        // Q = L − 4H (module docs) in pattern order: diagonal, then one entry per triangle edge
        let mut q = vec![c64::new(0.0, 0.0); n + 3 * self.tris.len()];
        for (f, (t, c)) in self.tris.iter().zip(&self.cot).enumerate() {
            for k in 0..3 {
                q[t[k] as usize].re += c[k];
                q[t[(k + 1) % 3] as usize].re += c[k];
                q[n + 3 * f + k].re = -c[k];
            }
        }
        for (e, &corner) in self.boundary.iter().zip(&self.boundary_corner) {
            // stored at (row, col) = (max, min): Q_ij = L_ij + i for the boundary edge i → j
            q[n + corner].im = if e[0] > e[1] { 1.0 } else { -1.0 };
        }
        let mut rhs = vec![c64::new(0.0, 0.0); n];
        for (f, t) in self.tris.iter().enumerate() {
            for k in 0..3 {
                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let (row, col) = (i.max(j), i.min(j));
                let entry = &mut q[n + 3 * f + k];
                match (pin_value(row), pin_value(col)) {
                    (None, None) => continue,
                    (None, Some(x)) => rhs[row] -= *entry * x,
                    (Some(x), None) => rhs[col] -= entry.conj() * x,
                    (Some(_), Some(_)) => {}
                }
                *entry = c64::new(0.0, 0.0);
            }
        }
        for (&p, &x) in pins.iter().zip(&fixed) {
            q[p as usize] = c64::new(1.0, 0.0);
            rhs[p as usize] = x;
        }
        let l = sparse.factor(&q)?;
        let mut work = MemBuffer::try_new(sparse.symbolic.solve_in_place_scratch::<c64>(1, Par::Seq))
            .map_err(|e| factorisation(&e))?;
        LltRef::new(&sparse.symbolic, &l).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut work),
        );
        let uv: Vec<DVec2> = rhs.iter().map(|z| DVec2::new(z.re, z.im)).collect();
        if uv.iter().any(|p| !p.is_finite()) {
            return Err(FlattenError::Factorisation("the LSCM solution is not finite".into()));
        }
        Ok((uv, pins))
    }

    /// ARAP local/global from `start`, vertex `held` fixed at the origin
    /// (where LSCM put its first pin), boundary edge `k` held at its length
    /// when `seam[k]` (and the options ask for exact boundaries).
    fn arap(
        &self,
        sparse: &Sparse,
        start: &[DVec2],
        held: u32,
        seam: &[bool],
        opts: &FlattenOptions,
    ) -> Result<Arap, FlattenError> {
        let n = self.pos.len();
        let held = held as usize;
        let wb = opts.boundary_weight;
        let exact = opts.exact_boundary && wb > 0.0;
        let hem = opts.hem_weight;
        // L + w_b L_∂ in pattern order, the held vertex's row and column replaced by the identity's
        let mut a = vec![0.0; n + 3 * self.tris.len()];
        for (f, (t, c)) in self.tris.iter().zip(&self.cot).enumerate() {
            for k in 0..3 {
                a[t[k] as usize] += c[k];
                a[t[(k + 1) % 3] as usize] += c[k];
                a[n + 3 * f + k] = -c[k];
            }
        }
        if wb > 0.0 {
            for ((e, &corner), &s) in self.boundary.iter().zip(&self.boundary_corner).zip(seam) {
                let w = if s { wb } else { hem };
                a[e[0] as usize] += w;
                a[e[1] as usize] += w;
                a[n + corner] -= w;
            }
        }
        for (f, t) in self.tris.iter().enumerate() {
            for k in 0..3 {
                if t[k] as usize == held || t[(k + 1) % 3] as usize == held {
                    a[n + 3 * f + k] = 0.0;
                }
            }
        }
        a[held] = 1.0;
        let mut llt = Factor::new(sparse, &a)?;

        let mut u = start.to_vec();
        u[held] = DVec2::ZERO;
        let mut rot = vec![DVec2::X; self.tris.len()];
        let mut dir = vec![DVec2::X; self.boundary.len()];
        let mut rest = self.boundary_length.clone();
        let mut next_rest = rest.clone();
        let mut acc = vec![DVec2::ZERO; n];
        let mut next_u = u.clone();
        let mut anderson = Anderson::new(opts.anderson_depth, 2 * n + rest.len());
        let mut previous = f64::INFINITY;
        let (mut iterations, mut converged) = (0, false);
        let (mut best, mut best_u, mut energy) = ((f64::INFINITY, f64::INFINITY), u.clone(), f64::NAN);
        loop {
            acc.fill(DVec2::ZERO);
            // local step, fused with the energy of (u, R) and the right-hand side
            let mut e_arap = 0.0;
            for ((t, (ev, c)), r) in self.tris.iter().zip(self.edges.iter().zip(&self.cot)).zip(rot.iter_mut()) {
                let [p0, p1, p2] = t.map(|i| u[i as usize]);
                let du = [p1 - p0, p2 - p1, p0 - p2];
                let (mut s00, mut s01, mut s10, mut s11) = (0.0, 0.0, 0.0, 0.0);
                for k in 0..3 {
                    let (w, x) = (c[k] * du[k], ev[k]);
                    s00 += w.x * x.x;
                    s01 += w.x * x.y;
                    s10 += w.y * x.x;
                    s11 += w.y * x.y;
                }
                let q = DVec2::new(s00 + s11, s10 - s01);
                let len = q.length();
                if len > 0.0 && len.is_finite() {
                    *r = q / len;
                }
                for k in 0..3 {
                    let re = r.rotate(ev[k]);
                    e_arap += c[k] * (du[k] - re).length_squared();
                    let f = re * c[k];
                    acc[t[(k + 1) % 3] as usize] += f;
                    acc[t[k] as usize] -= f;
                }
            }
            e_arap *= 0.5;
            // springs: current directions, residual, multiplier update
            let (mut e_spring, mut residual) = (0.0, 0.0f64);
            for (k, e) in self.boundary.iter().enumerate() {
                let d = u[e[1] as usize] - u[e[0] as usize];
                let len = d.length();
                if len > 0.0 && len.is_finite() {
                    dir[k] = d / len;
                }
                let target = self.boundary_length[k];
                if seam[k] {
                    residual = residual.max((len / target - 1.0).abs());
                }
                next_rest[k] = if exact && seam[k] && iterations > 0 { rest[k] - (len - target) } else { rest[k] };
                let w = if seam[k] { wb } else { hem };
                if w > 0.0 {
                    e_spring += w * (len - next_rest[k]).powi(2);
                    let f = dir[k] * (w * next_rest[k]);
                    acc[e[1] as usize] += f;
                    acc[e[0] as usize] -= f;
                }
            }
            e_spring *= 0.5;
            if !(e_arap.is_finite() && e_spring.is_finite()) {
                // diverged (an extrapolated state overflowed): the best finite state stands. Its
                // residual would not show it (`f64::max` passes over NaN), and a NaN state taken
                // as the best failed the tights' back piece at 3000 iterations
                break;
            }
            let objective = if exact { e_arap } else { e_arap + e_spring };
            // the best state so far, for a stop at max_iterations (the present one may be an
            // extrapolation that the next step would reject): with exact boundaries the one
            // nearest to the seam lengths, then the lowest energy; else the lowest objective
            let merit = if exact { (residual.max(opts.boundary_tolerance), e_arap) } else { (objective, 0.0) };
            if merit.0 < best.0 || (merit.0 == best.0 && merit.1 <= best.1) {
                best = merit;
                best_u.copy_from_slice(&u);
                energy = e_arap;
            }
            if iterations > 0 {
                let change = if exact { (previous - objective).abs() } else { previous - objective };
                let tolerance = if anderson.plain { opts.plain_tolerance } else { opts.tolerance };
                let still = change <= tolerance * previous;
                let isometric = e_arap <= opts.energy_floor * self.area;
                if isometric || (still && (!exact || residual <= opts.boundary_tolerance)) {
                    converged = true;
                    best_u.copy_from_slice(&u);
                    energy = e_arap;
                    break;
                }
            }
            if iterations >= opts.max_iterations {
                break;
            }
            previous = objective;
            // global step: (next_u, next_rest) = G(u, rest)
            acc[held] = DVec2::ZERO;
            llt.solve(&acc, &mut next_u);
            iterations += 1;
            anderson.step(&mut u, &mut rest, &next_u, &next_rest);
            if anderson.m > 0 && anderson.restarts > opts.max_anderson_restarts {
                // the acceleration stalls: plain iterations from here
                (anderson.m, anderson.plain) = (0, true);
            }
        }
        if best_u.iter().any(|p| !p.is_finite()) {
            return Err(FlattenError::Factorisation("the ARAP solution is not finite".into()));
        }
        Ok(Arap { uv: best_u, iterations, converged, energy })
    }
}

/// Anderson acceleration (type II, depth `m`) of the fixed-point iteration
/// `x ← G(x)` on the state `x = (u, r)` (Walker & Ni 2011, DOI
/// 10.1137/10078356X; for local/global solvers Peng, Deng, Zhang, Wang &
/// Gotsman 2018, DOI 10.1145/3197517.3201290): the next state is
/// `G(x_k) − ΔG θ`, `θ = argmin |f_k − ΔF θ|`, `f = G(x) − x`, over the last
/// `m` differences. Safeguard: when an accelerated state's residual `|f|`
/// exceeds the previous one, the history is dropped and the plain iterate
/// `G(x_{k−1})` taken instead. All buffers are allocated up front.
struct Anderson {
    m: usize,
    /// Columns `ΔF`, `ΔG` in a ring of `m`, each of the state's length.
    df: Vec<Vec<f64>>,
    dg: Vec<Vec<f64>>,
    /// `ΔFᵀΔF`, row-major `m × m`.
    gram: Vec<f64>,
    /// Columns in the ring, and where the next goes.
    filled: usize,
    head: usize,
    f: Vec<f64>,
    g: Vec<f64>,
    f_prev: Vec<f64>,
    g_prev: Vec<f64>,
    /// `|f|²` of the previous step, and whether the present state was extrapolated.
    norm_prev: f64,
    extrapolated: bool,
    /// Small dense solve: matrix, right-hand side, θ.
    a: Vec<f64>,
    theta: Vec<f64>,
    /// Restarts so far, and whether the iteration went on plainly after too
    /// many ([`FlattenOptions::max_anderson_restarts`]).
    restarts: usize,
    plain: bool,
}

impl Anderson {
    fn new(m: usize, len: usize) -> Self {
        let state = if m > 0 { len } else { 0 };
        Self {
            m,
            df: vec![vec![0.0; state]; m],
            dg: vec![vec![0.0; state]; m],
            gram: vec![0.0; m * m],
            filled: 0,
            restarts: 0,
            plain: false,
            head: 0,
            f: vec![0.0; state],
            g: vec![0.0; state],
            f_prev: vec![0.0; state],
            g_prev: vec![0.0; state],
            norm_prev: f64::INFINITY,
            extrapolated: false,
            a: vec![0.0; m * m],
            theta: vec![0.0; m],
        }
    }

    /// Takes `G(x) = (gu, gr)` of the state `x = (u, r)` and overwrites the
    /// state with the next one.
    fn step(&mut self, u: &mut [DVec2], r: &mut [f64], gu: &[DVec2], gr: &[f64]) {
        if self.m == 0 {
            u.copy_from_slice(gu);
            r.copy_from_slice(gr);
            return;
        }
        let n2 = 2 * u.len();
        for (k, (p, q)) in u.iter().zip(gu).enumerate() {
            self.g[2 * k] = q.x;
            self.g[2 * k + 1] = q.y;
            self.f[2 * k] = q.x - p.x;
            self.f[2 * k + 1] = q.y - p.y;
        }
        for (k, (p, q)) in r.iter().zip(gr).enumerate() {
            self.g[n2 + k] = *q;
            self.f[n2 + k] = q - p;
        }
        let norm: f64 = self.f.iter().map(|x| x * x).sum();
        if self.extrapolated && (norm.is_nan() || norm > self.norm_prev) {
            // the extrapolated state did worse: restart from the last plain iterate
            self.restarts += 1;
            self.filled = 0;
            self.head = 0;
            self.extrapolated = false;
            self.norm_prev = f64::INFINITY;
            self.unpack(u, r, true);
            return;
        }
        if self.norm_prev.is_finite() {
            let h = self.head;
            for k in 0..self.f.len() {
                self.df[h][k] = self.f[k] - self.f_prev[k];
                self.dg[h][k] = self.g[k] - self.g_prev[k];
            }
            for j in 0..self.m.min(self.filled + 1) {
                let d: f64 = self.df[h].iter().zip(&self.df[j]).map(|(a, b)| a * b).sum();
                self.gram[h * self.m + j] = d;
                self.gram[j * self.m + h] = d;
            }
            self.filled = (self.filled + 1).min(self.m);
            self.head = (h + 1) % self.m;
        }
        std::mem::swap(&mut self.f, &mut self.f_prev);
        std::mem::swap(&mut self.g, &mut self.g_prev);
        self.norm_prev = norm;
        // θ from the normal equations ΔFᵀΔF θ = ΔFᵀ f (Cholesky; dependent columns get θ = 0)
        let m = self.filled;
        for j in 0..m {
            self.theta[j] = self.df[j].iter().zip(&self.f_prev).map(|(a, b)| a * b).sum();
            for i in 0..m {
                self.a[i * m + j] = self.gram[i * self.m + j];
            }
        }
        let ok = cholesky_solve(&mut self.a[..m * m], &mut self.theta[..m]);
        self.extrapolated = ok && m > 0;
        self.unpack(u, r, false);
    }

    /// Writes `g_prev − ΔG θ` (or just `g_prev`) into the state.
    fn unpack(&self, u: &mut [DVec2], r: &mut [f64], plain: bool) {
        let m = if plain || !self.extrapolated { 0 } else { self.filled };
        let at = |k: usize| {
            let mut x = self.g_prev[k];
            for j in 0..m {
                x -= self.theta[j] * self.dg[j][k];
            }
            x
        };
        for (k, p) in u.iter_mut().enumerate() {
            *p = DVec2::new(at(2 * k), at(2 * k + 1));
        }
        let n2 = 2 * u.len();
        for (k, x) in r.iter_mut().enumerate() {
            *x = at(n2 + k);
        }
    }
}

/// For the triangles `(v, a, b)` around a vertex `v`, given as `(a, b, h)`
/// with `h` the triangle's 3D height over `ab`: the largest `λ ≤ 1` such
/// that some point `x` lies at least `λ h` to the left of every line
/// `a → b` (in the kernel of the star, with every triangle at least `λ` of
/// its 3D height), and a point that achieves it: the centroid of that
/// region. Bisection on `λ`, each step clipping a square around the star by
/// the half-planes (`O(k²)` for `k` triangles). `None` when no `λ > 0` works
/// (an empty kernel).
fn kernel_centre(star: &[(DVec2, DVec2, f64)]) -> Option<(DVec2, f64)> {
    // n·x ≥ c + λ h with n the unit left normal of a → b and c = n·a
    let lines: Vec<(DVec2, f64, f64)> = star
        .iter()
        .filter_map(|&(a, b, h)| {
            let n = (b - a).perp().try_normalize()?;
            Some((n, n.dot(a), h))
        })
        .collect();
    let (lo, hi) = star
        .iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &(a, b, _)| (lo.min(a).min(b), hi.max(a).max(b)));
    let pad = DVec2::splat((hi - lo).max_element());
    if lines.is_empty() || !pad.is_finite() {
        return None;
    }
    let square = [lo - pad, DVec2::new(hi.x + pad.x, lo.y - pad.y), hi + pad, DVec2::new(lo.x - pad.x, hi.y + pad.y)];
    let (mut poly, mut next) = (Vec::with_capacity(lines.len() + 4), Vec::with_capacity(lines.len() + 4));
    // the region at λ, left in `poly`; false when it is empty
    let mut region = |lambda: f64, poly: &mut Vec<DVec2>| {
        poly.clear();
        poly.extend(square);
        for &(n, c, h) in &lines {
            let side = |x: DVec2| n.dot(x) - c - lambda * h;
            next.clear();
            for (k, &p) in poly.iter().enumerate() {
                let q = poly[(k + 1) % poly.len()];
                let (dp, dq) = (side(p), side(q));
                if dp >= 0.0 {
                    next.push(p);
                }
                if (dp < 0.0) != (dq < 0.0) {
                    next.push(p + (q - p) * (dp / (dp - dq)));
                }
            }
            std::mem::swap(poly, &mut next);
            if poly.len() < 3 {
                return false;
            }
        }
        true
    };
    let lambda = if region(1.0, &mut poly) {
        1.0
    } else {
        let (mut ok, mut bad) = (0.0, 1.0);
        while bad - ok > f64::EPSILON.sqrt() {
            let mid = 0.5 * (ok + bad);
            if region(mid, &mut poly) {
                ok = mid;
            } else {
                bad = mid;
            }
        }
        if ok <= 0.0 || !region(ok, &mut poly) {
            return None;
        }
        ok
    };
    Some((poly.iter().sum::<DVec2>() / poly.len() as f64, lambda))
}

/// Solves the small symmetric positive semi-definite system `a x = b` in
/// place (`a` row-major, overwritten by its Cholesky factor); a pivot below
/// `ε` times its diagonal entry marks a dependent column, whose unknown is
/// set to 0. Returns false if nothing could be solved.
///
/// Kept by hand (issue #16 item 7 asked for faer here; it stays): Anderson's
/// Gram matrix is semi-definite by construction once two differences are
/// parallel, and the right answer then is to drop that column (θ = 0 for
/// it), which is what this does. faer's dense LLT refuses a semi-definite
/// matrix outright, and its regularised variant replaces a small pivot by a
/// chosen δ instead of dropping the column, which gives the extrapolation a
/// large spurious coefficient; an LDLT or pivoted QR would change which
/// column is dropped. The system is at most [`MAX_ANDERSON_DEPTH`] square,
/// on the stack.
fn cholesky_solve(a: &mut [f64], b: &mut [f64]) -> bool {
    let m = b.len();
    let mut dependent = [false; MAX_ANDERSON_DEPTH];
    if m > dependent.len() {
        return false;
    }
    for j in 0..m {
        let d0 = a[j * m + j];
        let mut d = d0;
        for k in 0..j {
            d -= a[j * m + k] * a[j * m + k];
        }
        if d.is_nan() || d <= f64::EPSILON * d0 {
            dependent[j] = true;
            for i in j..m {
                a[i * m + j] = 0.0;
            }
            continue;
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            let mut s = a[i * m + j];
            for k in 0..j {
                s -= a[i * m + k] * a[j * m + k];
            }
            a[i * m + j] = s / d;
        }
    }
    for j in 0..m {
        if dependent[j] {
            b[j] = 0.0;
            continue;
        }
        let mut s = b[j];
        for k in 0..j {
            s -= a[j * m + k] * b[k];
        }
        b[j] = s / a[j * m + j];
    }
    for j in (0..m).rev() {
        if dependent[j] {
            b[j] = 0.0;
            continue;
        }
        let mut s = b[j];
        for k in j + 1..m {
            s -= a[k * m + j] * b[k];
        }
        b[j] = s / a[j * m + j];
    }
    b.iter().all(|x| x.is_finite())
}

/// Result of the ARAP stage (compact, rescaled).
struct Arap {
    uv: Vec<DVec2>,
    iterations: usize,
    converged: bool,
    energy: f64,
}

fn factorisation(e: &dyn std::fmt::Debug) -> FlattenError {
    FlattenError::Factorisation(format!("{e:?}"))
}

/// The lower triangle of the vertex graph (diagonal first, then one entry
/// per triangle edge, duplicates summed), its AMD ordering and symbolic
/// simplicial Cholesky factorisation: shared by the LSCM and the ARAP
/// systems, whose pinned vertices get identity rows.
struct Sparse {
    structure: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    /// Simplicial, so that the ARAP factor can be copied out of it.
    symbolic: SymbolicCholesky<usize>,
}

impl Sparse {
    fn new(mesh: &Mesh) -> Result<Self, FlattenError> {
        let n = mesh.pos.len();
        let mut idx = Vec::with_capacity(n + 3 * mesh.tris.len());
        idx.extend((0..n).map(|v| Pair { row: v, col: v }));
        for t in &mesh.tris {
            for k in 0..3 {
                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                idx.push(Pair { row: i.max(j), col: i.min(j) });
            }
        }
        let (structure, argsort) =
            SymbolicSparseColMat::try_new_from_indices(n, n, &idx).map_err(|e| factorisation(&e))?;
        let fail = |e: FaerError| factorisation(&e);
        let simplicial = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(structure.as_ref(), Side::Lower, SymmetricOrdering::Amd, simplicial)
            .map_err(fail)?;
        Ok(Self { structure, argsort, symbolic })
    }

    /// Numeric `LLᴴ` of the Hermitian matrix with these values in pattern order.
    fn factor<T: ComplexField + Copy + Default>(&self, values: &[T]) -> Result<Vec<T>, FlattenError> {
        let symbolic = &self.symbolic;
        if !values.iter().all(T::is_finite_impl) {
            return Err(FlattenError::Factorisation("the matrix has a non-finite entry".into()));
        }
        let a = SparseColMat::new_from_argsort(self.structure.clone(), &self.argsort, values)
            .map_err(|e| factorisation(&e))?;
        let mut l = vec![T::default(); symbolic.len_val()];
        let mut scratch = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<T>(Par::Seq, Default::default()))
            .map_err(|e| factorisation(&e))?;
        symbolic
            .factorize_numeric_llt(
                &mut l,
                a.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| factorisation(&e))?;
        Ok(l)
    }
}

/// A real `LLᵀ` factor copied into plain arrays (diagonal apart), solved for
/// both plane coordinates at once without allocating.
struct Factor {
    /// `y[i] = b[fwd[i]]` before the solve, `x[v] = y[inv[v]]` after.
    fwd: Vec<usize>,
    inv: Vec<usize>,
    diag: Vec<f64>,
    /// Strictly lower part, by column.
    col: Vec<usize>,
    row: Vec<usize>,
    val: Vec<f64>,
    y: Vec<DVec2>,
}

impl Factor {
    fn new(sparse: &Sparse, values: &[f64]) -> Result<Self, FlattenError> {
        let l = sparse.factor(values)?;
        let SymbolicCholeskyRaw::Simplicial(s) = sparse.symbolic.raw() else {
            return Err(FlattenError::Factorisation("expected a simplicial factor".into()));
        };
        let (cp, ri) = (s.col_ptr(), s.row_idx());
        let n = sparse.symbolic.nrows();
        let mut f = Self {
            fwd: (0..n).collect(),
            inv: (0..n).collect(),
            diag: vec![0.0; n],
            col: Vec::with_capacity(n + 1),
            row: Vec::with_capacity(l.len()),
            val: Vec::with_capacity(l.len()),
            y: vec![DVec2::ZERO; n],
        };
        if let Some(p) = sparse.symbolic.perm() {
            let (fwd, inv) = p.arrays();
            f.fwd.copy_from_slice(fwd);
            f.inv.copy_from_slice(inv);
        }
        f.col.push(0);
        for j in 0..n {
            for p in cp[j]..cp[j + 1] {
                if ri[p] == j {
                    f.diag[j] = l[p];
                } else {
                    f.row.push(ri[p]);
                    f.val.push(l[p]);
                }
            }
            f.col.push(f.row.len());
        }
        Ok(f)
    }

    /// `x = A⁻¹ b`, both coordinates at once.
    fn solve(&mut self, b: &[DVec2], x: &mut [DVec2]) {
        let y = &mut self.y;
        for (yi, &i) in y.iter_mut().zip(&self.fwd) {
            *yi = b[i];
        }
        for j in 0..y.len() {
            let yj = y[j] / self.diag[j];
            y[j] = yj;
            for p in self.col[j]..self.col[j + 1] {
                y[self.row[p]] -= yj * self.val[p];
            }
        }
        for j in (0..y.len()).rev() {
            let mut s = y[j];
            for p in self.col[j]..self.col[j + 1] {
                s -= y[self.row[p]] * self.val[p];
            }
            y[j] = s / self.diag[j];
        }
        for (xv, &i) in x.iter_mut().zip(&self.inv) {
            *xv = y[i];
        }
    }
}

/// Test surfaces shared by the pattern modules' tests (grids over the unit
/// square mapped onto a cylinder, cone, sphere cap, saddle).
#[cfg(test)]
pub(crate) mod shapes {
    use glam::{DVec2, DVec3};

    use typed_index_collections::{TiSlice, TiVec};

    use crate::pattern::panels::{PanelFace, PanelVertex};

    /// Positions and triangles, plain `u32` ids as the tests write them
    /// ([`vertices`] and [`faces`] give the panel's typed ids).
    pub(crate) type Panel = (Vec<DVec3>, Vec<[u32; 3]>);

    /// Test positions as a panel's per-vertex data.
    pub(crate) fn vertices<T>(p: &[T]) -> &TiSlice<PanelVertex, T> {
        TiSlice::from_ref(p)
    }

    /// Test triangles in a panel's typed ids.
    pub(crate) fn faces(t: &[[u32; 3]]) -> TiVec<PanelFace, [PanelVertex; 3]> {
        t.iter().map(|f| f.map(PanelVertex)).collect()
    }

    /// A test chain in a panel's typed ids.
    pub(crate) fn chain(c: &[u32]) -> Vec<PanelVertex> {
        c.iter().copied().map(PanelVertex).collect()
    }

    /// A `rows × cols` grid over `(s, t) ∈ [0, 1]²` mapped by `f`, diagonals
    /// alternating; counter-clockwise in `(s, t)`.
    pub(crate) fn grid(rows: usize, cols: usize, f: impl Fn(f64, f64) -> DVec3) -> Panel {
        let mut p = Vec::new();
        for r in 0..=rows {
            for c in 0..=cols {
                p.push(f(c as f64 / cols as f64, r as f64 / rows as f64));
            }
        }
        let id = |r: usize, c: usize| (r * (cols + 1) + c) as u32;
        let mut t = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                if (r + c) % 2 == 0 {
                    t.push([id(r, c), id(r, c + 1), id(r + 1, c + 1)]);
                    t.push([id(r, c), id(r + 1, c + 1), id(r + 1, c)]);
                } else {
                    t.push([id(r, c), id(r, c + 1), id(r + 1, c)]);
                    t.push([id(r, c + 1), id(r + 1, c + 1), id(r + 1, c)]);
                }
            }
        }
        (p, t)
    }

    /// The unit square mapped onto the unit disc (elliptical grid mapping), then by `f`.
    pub(crate) fn disc(res: usize, f: impl Fn(DVec2) -> DVec3) -> Panel {
        grid(res, res, |s, t| {
            let (x, y) = (2.0 * s - 1.0, 2.0 * t - 1.0);
            f(DVec2::new(x * (1.0 - y * y / 2.0).sqrt(), y * (1.0 - x * x / 2.0).sqrt()))
        })
    }

    /// Radius 0.15 m, 120°, height 0.4 m, 3,168 triangles; normals outward.
    pub(crate) fn cylinder() -> Panel {
        grid(36, 44, |s, t| {
            let a = (s - 0.5) * 120f64.to_radians();
            DVec3::new(0.15 * a.sin(), 0.4 * t, 0.15 * a.cos())
        })
    }

    /// A cone frustum: radius 0.25 → 0.15 m over 0.4 m of height, 100° around.
    pub(crate) fn cone() -> Panel {
        grid(30, 40, |s, t| {
            let a = (s - 0.5) * 100f64.to_radians();
            let r = 0.25 - 0.1 * t;
            DVec3::new(r * a.sin(), 0.4 * t, r * a.cos())
        })
    }

    /// A polar cap of a sphere of radius `r`, angular radius `deg` (aperture 2·deg).
    pub(crate) fn cap(r: f64, deg: f64, res: usize) -> Panel {
        disc(res, |d| {
            let (th, phi) = (d.length() * deg.to_radians(), d.y.atan2(d.x));
            DVec3::new(th.sin() * phi.cos(), th.sin() * phi.sin(), th.cos()) * r
        })
    }

    /// A saddle 0.5 m across: curvature radii 0.3 m (convex, like around a
    /// hip) and 1 m (concave, like the waist's hollow).
    pub(crate) fn saddle() -> Panel {
        disc(30, |d| {
            let (x, y) = (0.25 * d.x, 0.25 * d.y);
            DVec3::new(x, y, x * x / (2.0 * 0.3) - y * y / (2.0 * 1.0))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::shapes::*;
    use super::*;
    use proptest::prelude::*;

    // The tests are written with plain `u32` ids and slices: these shadow the
    // typed API with the same names, converting on the way in and out.

    /// A [`Flattening`] with its map and pins as plain slices.
    #[derive(Debug, PartialEq)]
    struct Raw {
        uv: Vec<DVec2>,
        lscm_pins: [u32; 2],
        typed: Flattening,
    }

    impl std::ops::Deref for Raw {
        type Target = Flattening;
        fn deref(&self) -> &Flattening {
            &self.typed
        }
    }

    fn raw(f: Flattening) -> Raw {
        Raw { uv: f.uv.raw.clone(), lscm_pins: f.lscm_pins.map(|v| v.0), typed: f }
    }

    fn flatten(p: &[DVec3], t: &[[u32; 3]], o: &FlattenOptions) -> Result<Raw, FlattenError> {
        super::flatten(vertices(p), &faces(t), o).map(raw)
    }

    fn flatten_with_seams(
        p: &[DVec3],
        t: &[[u32; 3]],
        s: &[Vec<u32>],
        o: &FlattenOptions,
    ) -> Result<Raw, FlattenError> {
        let s: Vec<Vec<PanelVertex>> = s.iter().map(|c| chain(c)).collect();
        super::flatten_with_seams(vertices(p), &faces(t), &s, o).map(raw)
    }

    fn flatten_with_sewn_lengths(
        p: &[DVec3],
        t: &[[u32; 3]],
        s: &[Vec<u32>],
        sewn: &[Vec<f64>],
        o: &FlattenOptions,
    ) -> Result<Raw, FlattenError> {
        let s: Vec<Vec<PanelVertex>> = s.iter().map(|c| chain(c)).collect();
        super::flatten_with_sewn_lengths(vertices(p), &faces(t), &s, sewn, o).map(raw)
    }

    fn lscm(p: &[DVec3], t: &[[u32; 3]]) -> Result<Vec<DVec2>, FlattenError> {
        super::lscm(vertices(p), &faces(t)).map(|uv| uv.raw)
    }

    fn distortion(p: &[DVec3], t: &[[u32; 3]], uv: &[DVec2]) -> Distortion {
        super::distortion(vertices(p), &faces(t), vertices(uv))
    }

    /// The boundary loop (vertices in order).
    fn boundary_loop(triangles: &[[u32; 3]]) -> Vec<u32> {
        let mut directed = std::collections::HashSet::new();
        for t in triangles {
            for k in 0..3 {
                directed.insert((t[k], t[(k + 1) % 3]));
            }
        }
        let next: std::collections::HashMap<u32, u32> =
            directed.iter().filter(|&&(i, j)| !directed.contains(&(j, i))).copied().collect();
        let start = *next.keys().min().expect("a boundary");
        let mut ring = vec![start];
        while let Some(&v) = next.get(ring.last().expect("non-empty")) {
            if v == start {
                break;
            }
            ring.push(v);
        }
        ring
    }

    /// Relative length errors of the boundary cut into `k` chains of equal edge count.
    fn chain_errors(p: &[DVec3], t: &[[u32; 3]], uv: &[DVec2], k: usize) -> Vec<f64> {
        let ring = boundary_loop(t);
        let m = ring.len();
        (0..k)
            .map(|c| {
                let (mut l3, mut l2) = (0.0, 0.0);
                for e in c * m / k..(c + 1) * m / k {
                    let (a, b) = (ring[e] as usize, ring[(e + 1) % m] as usize);
                    l3 += p[a].distance(p[b]);
                    l2 += uv[a].distance(uv[b]);
                }
                l2 / l3 - 1.0
            })
            .collect()
    }

    fn scaled_to_area(p: &[DVec3], t: &[[u32; 3]], uv: &[DVec2]) -> Vec<DVec2> {
        let a3: f64 = t
            .iter()
            .map(|f| 0.5 * (p[f[1] as usize] - p[f[0] as usize]).cross(p[f[2] as usize] - p[f[0] as usize]).length())
            .sum();
        let a2: f64 = t.iter().map(|f| signed_area(f.map(|i| uv[i as usize]))).sum();
        uv.iter().map(|q| *q * (a3 / a2).sqrt()).collect()
    }

    fn report(name: &str, d: &Distortion) {
        eprintln!(
            "{name:>28}: strain mean {:.2e} p95 {:.2e} max {:.2e}  E_s {:+.2e}  E_c {:+.2e}  boundary {:+.2e} (edge max {:.2e})  flips {}",
            d.strain_mean, d.strain_p95, d.strain_max, d.area_accuracy, d.length_accuracy, d.boundary_length_error, d.boundary_strain_max, d.flipped
        );
    }

    #[test]
    fn developable_patches_flatten_isometrically() {
        for (name, (p, t)) in [("cylinder", cylinder()), ("cone", cone())] {
            let f = flatten(&p, &t, &FlattenOptions::default()).expect("flatten");
            let d = distortion(&p, &t, &f.uv);
            report(name, &d);
            assert!(d.strain_max < 1e-6, "{name}: {d:?} after {} iterations", f.iterations);
            assert!(d.area_accuracy.abs() < 1e-6, "{name}: {d:?}");
            assert_eq!((d.flipped, f.flipped, f.fallback, f.converged), (0, 0, false, true), "{name}");
            assert!(f.iterations <= 2, "{name}: {} iterations", f.iterations);
        }
        let (p, t) = grid(12, 17, |s, t| DVec3::new(0.3 * s, 0.2 * t + 0.05 * s * s, 0.0));
        for uv in [lscm(&p, &t).expect("lscm"), flatten(&p, &t, &FlattenOptions::default()).expect("flatten").uv] {
            let d = distortion(&p, &t, &uv);
            assert!(d.strain_max < 1e-9 && d.area_accuracy.abs() < 1e-9, "plane: {d:?}");
        }
    }

    #[test]
    fn doubly_curved_patches_have_no_flips_and_arap_beats_lscm() {
        let panels = [
            ("sphere cap 60°", cap(0.5, 30.0, 30)),
            ("hemisphere-like cap 150°", cap(0.2, 75.0, 30)),
            ("saddle", saddle()),
        ];
        for (name, (p, t)) in panels {
            let start = lscm(&p, &t).expect("lscm");
            let fair = scaled_to_area(&p, &t, &start);
            let f = flatten(&p, &t, &FlattenOptions::default()).expect("flatten");
            let plain = FlattenOptions { boundary_weight: 0.0, ..Default::default() };
            let fp = flatten(&p, &t, &plain).expect("flatten");
            let (dl, ds, d, dp) = (
                distortion(&p, &t, &start),
                distortion(&p, &t, &fair),
                distortion(&p, &t, &f.uv),
                distortion(&p, &t, &fp.uv),
            );
            eprintln!("{name} ({} triangles):", t.len());
            report("LSCM", &dl);
            report("LSCM scaled to the area", &ds);
            report(&format!("ARAP, plain ({} it)", fp.iterations), &dp);
            report(&format!("ARAP, exact boundary ({} it)", f.iterations), &d);
            for (fl, dd) in [(&f, &d), (&fp, &dp)] {
                assert_eq!((dd.flipped, fl.flipped, fl.fallback, fl.converged), (0, 0, false, true), "{name}");
            }
            assert_eq!(dl.flipped, 0, "{name}");
            assert!(dp.strain_mean < ds.strain_mean && dp.strain_max < ds.strain_max, "{name}: ARAP beats LSCM");
            assert!(d.strain_mean < dl.strain_mean && d.strain_p95 < dl.strain_p95, "{name}: ARAP beats raw LSCM");
        }
    }

    #[test]
    fn seams_are_held_at_their_sewn_ratios() {
        // a 60° cap: its rim wants to be longer than in 3D (module docs), so the ratios are felt
        let (p, t) = cap(0.5, 30.0, 24);
        let ring = boundary_loop(&t);
        let quarter = ring.len() / 4;
        let chains = vec![ring[..=quarter].to_vec(), ring[2 * quarter..=3 * quarter].to_vec()];
        let ratios = vec![vec![1.05; quarter], vec![0.97; quarter - 2]];
        let f = flatten_with_sewn_lengths(&p, &t, &chains, &ratios, &FlattenOptions::default()).expect("flatten");
        assert_eq!(distortion(&p, &t, &f.uv).flipped, 0);
        for (k, chain) in chains.iter().enumerate() {
            for (i, w) in chain.windows(2).enumerate() {
                let (a, b) = (w[0] as usize, w[1] as usize);
                // the second chain's last two edges have no ratio: their 3D length
                let want = ratios[k].get(i).copied().unwrap_or(1.0) * p[a].distance(p[b]);
                let got = f.uv[a].distance(f.uv[b]);
                assert!((got / want - 1.0).abs() < 1e-4, "chain {k} edge {i}: {got} for {want}");
            }
        }
        // ratios of 1 are the plain seams, bit for bit
        let ones: Vec<Vec<f64>> = chains.iter().map(|c| vec![1.0; c.len() - 1]).collect();
        let plain = flatten_with_seams(&p, &t, &chains, &FlattenOptions::default()).expect("flatten");
        let unit = flatten_with_sewn_lengths(&p, &t, &chains, &ones, &FlattenOptions::default()).expect("flatten");
        assert_eq!(plain.uv, unit.uv);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let ratios = vec![vec![1.0, 1.0, bad]];
            let got = flatten_with_sewn_lengths(&p, &t, &chains, &ratios, &FlattenOptions::default());
            assert!(
                matches!(got, Err(FlattenError::SewnRatio { seam: 0, edge: 2, ratio }) if ratio.to_bits() == bad.to_bits()),
                "{bad}: {got:?}"
            );
        }
    }

    #[test]
    fn boundary_lengths_survive_on_doubly_curved_patches() {
        for (name, (p, t)) in [("sphere cap 60°", cap(0.5, 30.0, 30)), ("saddle", saddle())] {
            eprintln!("{name} ({} triangles, boundary {:.3} m):", t.len(), {
                let ring = boundary_loop(&t);
                (0..ring.len())
                    .map(|k| p[ring[k] as usize].distance(p[ring[(k + 1) % ring.len()] as usize]))
                    .sum::<f64>()
            });
            let variants = [
                ("plain ARAP", FlattenOptions { boundary_weight: 0.0, exact_boundary: false, ..Default::default() }),
                ("springs w_b = 10", FlattenOptions { exact_boundary: false, ..Default::default() }),
                (
                    "springs w_b = 1000",
                    FlattenOptions { boundary_weight: 1e3, exact_boundary: false, ..Default::default() },
                ),
                ("default (exact boundary)", FlattenOptions::default()),
            ];
            let mut errors = Vec::new();
            for (label, o) in variants {
                let f = flatten(&p, &t, &o).expect("flatten");
                let d = distortion(&p, &t, &f.uv);
                let chains = chain_errors(&p, &t, &f.uv, 6);
                let worst = chains.iter().fold(0.0f64, |m, e| m.max(e.abs()));
                report(&format!("{label} ({} it)", f.iterations), &d);
                eprintln!("{:>28}  worst of 6 chains {worst:.2e}", "");
                assert_eq!(d.flipped, 0);
                errors.push((d.boundary_length_error.abs(), worst, d.strain_p95));
            }
            let (total, chain, _) = errors[3];
            assert!(total <= 5e-4 && chain <= 5e-4, "{name}: {errors:?}");
            assert!(errors[0].0 > 10.0 * total.max(5e-5), "{name}: the option matters: {errors:?}");
        }
    }

    #[test]
    fn named_seams_are_exact_and_free_edges_relax() {
        let (p, t) = cap(0.5, 30.0, 30);
        let ring = boundary_loop(&t);
        let q = ring.len() / 4;
        // two opposite quarters of the rim are seams, the rest hems
        let seams = vec![ring[..=q].to_vec(), ring[2 * q..=3 * q].to_vec()];
        let all = flatten(&p, &t, &FlattenOptions::default()).expect("flatten");
        let some = flatten_with_seams(&p, &t, &seams, &FlattenOptions::default()).expect("flatten");
        let (da, ds) = (distortion(&p, &t, &all.uv), distortion(&p, &t, &some.uv));
        report("every boundary edge a seam", &da);
        report("half the rim seams", &ds);
        let err = |uv: &[DVec2], chain: &[u32]| {
            let l = |f: &dyn Fn(usize) -> f64| (1..chain.len()).map(f).sum::<f64>();
            let l3 = l(&|k| p[chain[k - 1] as usize].distance(p[chain[k] as usize]));
            l(&|k| uv[chain[k - 1] as usize].distance(uv[chain[k] as usize])) / l3 - 1.0
        };
        for chain in &seams {
            // trued after the iterations: exact to rounding
            assert!(err(&some.uv, chain).abs() < 1e-12, "{}", err(&some.uv, chain));
        }
        let hem = ring[q..=2 * q].to_vec();
        assert!(err(&some.uv, &hem).abs() > 1e-3, "the hems are free: {}", err(&some.uv, &hem));
        assert!(ds.area_accuracy.abs() < da.area_accuracy.abs() && ds.strain_p95 < da.strain_p95);
        assert!(some.boundary_residual < 1e-12 && some.converged && ds.flipped == 0);
        assert_eq!(
            flatten_with_seams(&p, &t, &[vec![0, 1], vec![3, 99_999]], &FlattenOptions::default()),
            Err(FlattenError::SeamVertex { seam: 1, vertex: PanelVertex(99_999) })
        );
    }

    #[test]
    fn bad_input_is_named() {
        let o = FlattenOptions::default();
        let (p, t) = grid(2, 2, |s, t| DVec3::new(s, t, 0.0));
        let err = |p: &[DVec3], t: &[[u32; 3]]| flatten(p, t, &o).expect_err("bad input");
        assert_eq!(err(&p, &[]), FlattenError::Empty);
        let mut q = p.clone();
        q[4].y = f64::NAN;
        assert_eq!(err(&q, &t), FlattenError::NonFinite { vertex: PanelVertex(4) });
        q[4] = DVec3::new(0.5, 0.5, f64::INFINITY);
        assert_eq!(lscm(&q, &t), Err(FlattenError::NonFinite { vertex: PanelVertex(4) }));
        let mut bad = t.clone();
        bad[3][1] = 99;
        assert_eq!(err(&p, &bad), FlattenError::IndexOutOfRange { face: PanelFace(3), index: PanelVertex(99) });
        let mut bad = t.clone();
        bad[5] = [4, 4, 5];
        assert_eq!(err(&p, &bad), FlattenError::DegenerateTriangle { face: PanelFace(5) });
        let line = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert_eq!(err(&line, &[[0, 1, 2]]), FlattenError::DegenerateTriangle { face: PanelFace(0) });
        // three triangles on the edge 0–1
        let fin = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::NEG_Y];
        let fin_edge = |a, b| {
            FlattenError::Topology(TopologyError::NonManifoldEdge {
                edge: MeshEdge::new(PanelVertex(a), PanelVertex(b)),
                faces: 3,
            })
        };
        assert_eq!(err(&fin, &[[0, 1, 2], [1, 0, 3], [1, 0, 4]]), fin_edge(0, 1));
        // named in the input's ids, not the compact numbering (vertex 0 is in no triangle)
        let sparse = [DVec3::ONE, DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::NEG_Y];
        assert_eq!(err(&sparse, &[[1, 2, 3], [2, 1, 4], [2, 1, 5]]), fin_edge(1, 2));
        // the second triangle runs 0 → 1 too
        let sq = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::NEG_Y];
        assert_eq!(
            err(&sq, &[[0, 1, 2], [0, 1, 3]]),
            FlattenError::Topology(TopologyError::InconsistentOrientation {
                edge: MeshEdge::new(PanelVertex(0), PanelVertex(1)),
                face_a: crate::geom::mesh::FaceId(0),
                face_b: crate::geom::mesh::FaceId(1)
            })
        );
        // two triangles sharing only vertex 0 (a bow tie)
        let bow = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::NEG_X, DVec3::NEG_Y];
        assert_eq!(
            err(&bow, &[[0, 1, 2], [0, 3, 4]]),
            FlattenError::Topology(TopologyError::NonManifoldVertex { vertex: PanelVertex(0), fans: 2 })
        );
        // two separate triangles
        let two = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::Z + DVec3::X, DVec3::Z + DVec3::Y];
        assert_eq!(err(&two, &[[0, 1, 2], [3, 4, 5]]), FlattenError::Disconnected { vertex: PanelVertex(3) });
        // a closed octahedron, and an annulus (a square with a square hole)
        let oct = [DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z];
        let ot = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        assert_eq!(err(&oct, &ot), FlattenError::NotADisc { boundary_loops: 0, euler: 2 });
        let (ring, rt) = grid(3, 3, |s, t| DVec3::new(s, t, 0.0));
        let hole: Vec<[u32; 3]> = rt.iter().enumerate().filter(|&(f, _)| f / 2 != 4).map(|(_, t)| *t).collect();
        assert_eq!(err(&ring, &hole), FlattenError::NotADisc { boundary_loops: 2, euler: 0 });
        for (field, o) in [
            ("tolerance", FlattenOptions { tolerance: -1.0, ..o }),
            ("boundary_weight", FlattenOptions { boundary_weight: f64::NAN, ..o }),
            ("degenerate_area", FlattenOptions { degenerate_area: f64::INFINITY, ..o }),
            ("anderson_depth", FlattenOptions { anderson_depth: usize::MAX, ..o }),
            ("plain_tolerance", FlattenOptions { plain_tolerance: -1.0, ..o }),
        ] {
            assert_eq!(flatten(&p, &t, &o), Err(FlattenError::InvalidOption { field }));
        }
        // springs so stiff that the matrix overflows
        let r = flatten(&p, &t, &FlattenOptions { boundary_weight: f64::MAX, ..o });
        assert!(matches!(r, Err(FlattenError::Factorisation(_))), "{r:?}");
    }

    #[test]
    fn orientation_units_and_loose_vertices() {
        let (p, t) = saddle();
        let base = flatten(&p, &t, &FlattenOptions::default()).expect("flatten");
        assert!(t.iter().all(|f| signed_area(f.map(|i| base.uv[i as usize])) > 0.0), "counter-clockwise output");
        // reversed winding: still no flips in the caller's orientation, same figures
        let rev: Vec<[u32; 3]> = t.iter().map(|f| [f[0], f[2], f[1]]).collect();
        let r = flatten(&p, &rev, &FlattenOptions::default()).expect("flatten");
        assert!(rev.iter().all(|f| signed_area(f.map(|i| r.uv[i as usize])) > 0.0));
        let (d, dr) = (distortion(&p, &t, &base.uv), distortion(&p, &rev, &r.uv));
        assert!((d.strain_p95 - dr.strain_p95).abs() < 1e-9 && (d.area_accuracy - dr.area_accuracy).abs() < 1e-9);
        // mirrored output: the metric orients it first
        let mirrored: Vec<DVec2> = base.uv.iter().map(|q| DVec2::new(-q.x, q.y)).collect();
        assert_eq!(distortion(&p, &t, &mirrored), d);
        // millimetres, and absurd units: the same map, scaled
        for k in [1e3, 1e-150, 1e150] {
            let q: Vec<DVec3> = p.iter().map(|x| *x * k).collect();
            let f = flatten(&q, &t, &FlattenOptions::default()).expect("flatten");
            assert_eq!(f.iterations, base.iterations, "unit ×{k}");
            let err = f.uv.iter().zip(&base.uv).map(|(a, b)| (*a / k - *b).length()).fold(0.0, f64::max);
            assert!(err < 1e-9, "unit ×{k}: {err}");
            assert!((f.energy / (k * k) - base.energy).abs() <= 1e-9 * base.energy);
        }
        // a vertex in no triangle (first, so that every index shifts): (0, 0), the rest unchanged
        let mut q = vec![DVec3::new(9.0, 9.0, 9.0)];
        q.extend(&p);
        let shifted: Vec<[u32; 3]> = t.iter().map(|f| f.map(|i| i + 1)).collect();
        let f = flatten(&q, &shifted, &FlattenOptions::default()).expect("flatten");
        assert_eq!(f.uv[0], DVec2::ZERO);
        assert_eq!(f.uv[1..], base.uv[..]);
        assert_eq!(f.lscm_pins, base.lscm_pins.map(|i| i + 1));
        assert_eq!(lscm(&q, &shifted).expect("lscm")[0], DVec2::ZERO);
    }

    #[test]
    fn distortion_never_panics() {
        let (p, t) = grid(3, 3, |s, t| DVec3::new(s, t, 0.0));
        let uv: Vec<DVec2> = p.iter().map(|q| q.truncate()).collect();
        let d = distortion(&p, &t, &uv);
        assert_eq!((d.strain_max, d.area_accuracy, d.flipped, d.boundary_length_error), (0.0, 0.0, 0, 0.0));
        assert_eq!(distortion(&p, &[], &uv), Distortion::default());
        assert_eq!(distortion(&p, &t, &uv[..3]), Distortion::default());
        let mut bad = t.clone();
        bad.push([0, 1, 99]);
        bad.push([5, 5, 5]);
        assert_eq!(distortion(&p, &bad, &uv).strain_max, 0.0);
        let nan = vec![DVec2::NAN; uv.len()];
        assert!(distortion(&p, &t, &nan).strain_mean.is_nan());
        // one triangle flipped by hand
        let mut folded = uv.clone();
        folded[5] = DVec2::new(1.0, 1.0);
        assert!(distortion(&p, &t, &folded).flipped > 0);
    }

    #[test]
    fn the_two_coordinate_solve_matches_faer() {
        let (p, t) = cap(0.5, 30.0, 12);
        let mesh = Mesh::new(vertices(&p), &faces(&t), 1e-12).expect("valid");
        let sparse = Sparse::new(&mesh).expect("pattern");
        let n = mesh.pos.len();
        let mut a = vec![0.0; n + 3 * mesh.tris.len()];
        for (f, (tri, c)) in mesh.tris.iter().zip(&mesh.cot).enumerate() {
            for k in 0..3 {
                a[tri[k] as usize] += c[k] + 0.5;
                a[tri[(k + 1) % 3] as usize] += c[k] + 0.5;
                a[n + 3 * f + k] = -c[k] - 0.5;
            }
        }
        a[0] += 1.0;
        let b: Vec<DVec2> = (0..n).map(|i| DVec2::new((i as f64).sin(), (i as f64 * 0.7).cos())).collect();
        let mut x = vec![DVec2::ZERO; n];
        Factor::new(&sparse, &a).expect("factor").solve(&b, &mut x);
        let l = sparse.factor(&a).expect("factor");
        let mut rhs: Vec<f64> = b.iter().map(|q| q.x).chain(b.iter().map(|q| q.y)).collect();
        let mut work = MemBuffer::new(sparse.symbolic.solve_in_place_scratch::<f64>(2, Par::Seq));
        LltRef::new(&sparse.symbolic, &l).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut rhs, n, 2),
            Par::Seq,
            MemStack::new(&mut work),
        );
        for (v, q) in x.iter().enumerate() {
            assert!((*q - DVec2::new(rhs[v], rhs[n + v])).length() < 1e-12 * (1.0 + q.length()), "row {v}");
        }
    }

    #[test]
    fn untangling_unflips_without_touching_the_boundary() {
        let (p, t) = saddle();
        let mesh = Mesh::new(vertices(&p), &faces(&t), 1e-12).expect("valid");
        let f = flatten(&p, &t, &FlattenOptions::default()).expect("flatten");
        let mut uv: Vec<DVec2> = f.uv.iter().map(|q| *q * mesh.scale).collect();
        // fold an interior vertex over a neighbour: several flipped triangles
        let v = t.iter().flatten().copied().find(|&v| !mesh.boundary.iter().any(|e| e[0] == v)).expect("interior");
        let w = t.iter().find(|f| f.contains(&v)).and_then(|f| f.iter().copied().find(|&w| w != v)).expect("neighbour");
        uv[v as usize] = uv[w as usize] * 2.0 - uv[v as usize];
        let before = mesh.flips(&uv);
        let ring: Vec<DVec2> = mesh.boundary.iter().map(|e| uv[e[0] as usize]).collect();
        let moves = mesh.untangle(&mut uv, 8);
        eprintln!("{before} flipped, {moves} moves");
        assert!(before > 0 && moves > 0);
        assert_eq!(mesh.flips(&uv), 0);
        assert_eq!(ring, mesh.boundary.iter().map(|e| uv[e[0] as usize]).collect::<Vec<_>>());
        // a star with no kernel: nothing to do
        let bow = [(DVec2::ZERO, DVec2::X, 1.0), (DVec2::X, DVec2::ZERO, 1.0), (DVec2::Y, DVec2::ONE, 1.0)];
        assert_eq!(kernel_centre(&bow), None);
    }

    #[test]
    fn pins_are_the_farthest_boundary_pair() {
        for (p, t) in [lumpy(), cap(0.5, 30.0, 20), cylinder()] {
            let ring = boundary_loop(&t);
            let most = ring
                .iter()
                .flat_map(|&a| ring.iter().map(move |&b| (a, b)))
                .map(|(a, b)| p[a as usize].distance(p[b as usize]))
                .fold(0.0, f64::max);
            for limit in [usize::MAX, 0] {
                let o = FlattenOptions { pin_search_limit: limit, ..Default::default() };
                let f = flatten(&p, &t, &o).expect("flatten");
                let [a, b] = f.lscm_pins;
                assert!(a < b && ring.contains(&a) && ring.contains(&b));
                let d = p[a as usize].distance(p[b as usize]);
                assert!(d >= most * (1.0 - 1e-9), "limit {limit}: {d} < {most}");
                assert!((f.uv[a as usize] - DVec2::ZERO).length() < 1e-12 && f.boundary_residual < 1e-4);
            }
        }
    }

    /// An irregular, doubly curved patch with no symmetry (no ties among pins).
    fn lumpy() -> Panel {
        grid(11, 14, |s, t| {
            DVec3::new(0.4 * s + 0.05 * t * t, 0.3 * t + 0.02 * s, 0.2 * s * s - 0.1 * t * t + 0.03 * s * t)
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn rigid_motions_leave_the_figures_unchanged(
            axis in (-1.0f64..1.0, -1.0f64..1.0, 0.1f64..1.0),
            angle in -3.1f64..3.1,
            shift in (-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0),
            turn in -3.1f64..3.1,
        ) {
            let (p, t) = lumpy();
            let rot = glam::DQuat::from_axis_angle(DVec3::new(axis.0, axis.1, axis.2).normalize(), angle);
            let moved: Vec<DVec3> = p.iter().map(|q| rot * *q + DVec3::new(shift.0, shift.1, shift.2)).collect();
            let o = FlattenOptions::default();
            let (f, g) = (flatten(&p, &t, &o).expect("flatten"), flatten(&moved, &t, &o).expect("flatten"));
            let (a, b) = (distortion(&p, &t, &f.uv), distortion(&moved, &t, &g.uv));
            let pairs = [
                (a.area_accuracy, b.area_accuracy), (a.length_accuracy, b.length_accuracy),
                (a.strain_mean, b.strain_mean), (a.strain_p95, b.strain_p95), (a.strain_max, b.strain_max),
                (a.boundary_length_error, b.boundary_length_error), (a.boundary_strain_max, b.boundary_strain_max),
            ];
            for (x, y) in pairs {
                prop_assert!((x - y).abs() < 1e-9, "{a:?} vs {b:?}");
            }
            prop_assert_eq!(a.flipped, b.flipped);
            prop_assert_eq!(f.lscm_pins, g.lscm_pins);
            // the metric alone: a rigid motion of either side changes nothing
            let turned: Vec<DVec2> = f.uv.iter().map(|q| DVec2::from_angle(turn).rotate(*q) + DVec2::new(shift.0, shift.1)).collect();
            let c = distortion(&moved, &t, &turned);
            prop_assert!((c.strain_p95 - a.strain_p95).abs() < 1e-12 && (c.area_accuracy - a.area_accuracy).abs() < 1e-12);
        }
    }
}
