//! Collision avoidance during refinement (seed 000 §5.4).
//!
//! After every fairing sweep ([`super::subdivide::refine`]'s hook), each
//! free vertex is tested against the body's depth maps by Eq. (13), with
//! the body thickened by [`CollisionOptions::detection_margin_mm`]
//! ([`crate::collide::depth::inside_with_margin`]):
//! * a vertex the sweep moved from outside to inside has its update
//!   **refused** — sub-stepped as the paper suggests: of the fractions
//!   `k/n` (`n` = [`CollisionOptions::substeps`]) of its update, the largest
//!   that stays outside is kept (0 if none);
//! * a vertex that is inside for any other reason (a new vertex of the
//!   split, a vertex inside since the start of the level) is **pushed out**
//!   along the body normal at the nearer depth-map face by its escape
//!   distance plus the clearance [`CollisionOptions::clearance_mm`].
//!
//! Either way the vertex is then **held** for the rest of the level (the
//! active set of [`super::subdivide::refine`]'s hook): the fairing converges
//! on the remaining free vertices with the held ones as constraints, instead
//! of fighting refusals with restarts.
//!
//! **Exact final pass** (beyond the paper, [`settle_exact`]): the depth maps
//! cannot tell in from out within about a pixel of the skin (issue #4
//! measured 0.26 % of free vertices ending ≤ 0.62 mm inside by the exact
//! test). After the last level every free vertex that the generalised winding
//! number ([`WindingTree::is_inside`]) finds inside is moved to its closest
//! point on the body plus [`CollisionOptions::clearance_mm`] along the
//! direction from the vertex to that point (outward). `O(V log F)`.
//!
//! Fixed vertices (nodes, profile and boundary vertices) are never moved by
//! the fairing hook nor by [`settle_exact`]; [`Collider::settle_fixed`] moves
//! those the exact test finds inside out to the smaller
//! [`ClearOptions::fixed_clearance_mm`] (issue #13: the report counts every
//! vertex). No failure modes: points outside every map are outside.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use typed_index_collections::TiSlice;

use crate::collide::depth::{inside_with_margin, DepthMap};
use crate::geom::mesh::VertexId;
use crate::geom::winding::{InsideMemo, WindingTree};
use crate::refine::clear::{push_out, ClearOptions, CoarseClearReport, SurfaceClearReport};

/// Knobs of collision avoidance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CollisionOptions {
    /// Distance a pushed-out vertex is placed outside the body, mm. Default 3.
    pub clearance_mm: f64,
    /// Sub-steps tried when a fairing update would enter the body. Default 4.
    pub substeps: u32,
    /// The body is thickened by this much along each view axis when
    /// testing, so that vertices a pixel's width from the skin — where the
    /// depth maps cannot resolve in from out — count as inside, mm.
    /// Default 1.5.
    pub detection_margin_mm: f64,
}

impl Default for CollisionOptions {
    fn default() -> Self {
        Self { clearance_mm: 3.0, substeps: 4, detection_margin_mm: 1.5 }
    }
}

/// What the collision step did over a refinement.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, utoipa::ToSchema)]
pub struct CollisionReport {
    /// Vertices pushed out of the body.
    pub pushed: usize,
    /// Fairing updates refused (wholly or partly).
    pub refused: usize,
    /// Vertices moved out by the exact final pass ([`settle_exact`]).
    pub settled: usize,
    /// Fixed vertices (nodes, profile and boundary vertices) the exact final
    /// pass found inside and moved out ([`Collider::settle_fixed`]).
    pub fixed_settled: usize,
    /// Template nodes and profile points moved out before refinement.
    pub coarse: CoarseClearReport,
    /// Garment triangles lifted off body triangles they crossed.
    pub surface: SurfaceClearReport,
}

/// The hook state: the depth maps and the positions after the last sweep.
pub struct Collider<'a> {
    maps: &'a [DepthMap],
    opts: CollisionOptions,
    previous: Vec<DVec3>,
    /// Running totals.
    pub report: CollisionReport,
    /// The exact passes' inside answers ([`InsideMemo`]): the surface
    /// clearing and the fit report ask again about the vertices they did
    /// not move.
    pub inside: InsideMemo,
}

impl<'a> Collider<'a> {
    /// A collider over the depth maps of one body.
    pub fn new(maps: &'a [DepthMap], opts: CollisionOptions) -> Self {
        Self { maps, opts, previous: Vec::new(), report: CollisionReport::default(), inside: InsideMemo::default() }
    }

    /// The hook: refuse updates that enter the body, push out what is inside,
    /// and hold both for the rest of the level (`held` as in
    /// [`super::subdivide::refine`]).
    pub fn after_sweep(&mut self, positions: &mut TiSlice<VertexId, DVec3>, held: &mut TiSlice<VertexId, bool>) {
        let clearance = self.opts.clearance_mm * 1e-3;
        let margin = self.opts.detection_margin_mm * 1e-3;
        let maps = self.maps;
        let hit = |q: DVec3| inside_with_margin(maps, q, margin);
        let same_level = self.previous.len() == positions.len();
        for (i, p) in positions.iter_mut_enumerated() {
            if held.get(i).copied().unwrap_or(true) {
                continue;
            }
            let Some(probe) = hit(*p) else { continue };
            if same_level && hit(self.previous[i.idx()]).is_none() {
                let from = self.previous[i.idx()];
                let n = self.opts.substeps.max(1);
                let mut kept = from;
                for k in (1..n).rev() {
                    let q = from.lerp(*p, f64::from(k) / f64::from(n));
                    if hit(q).is_none() {
                        kept = q;
                        break;
                    }
                }
                *p = kept;
                self.report.refused += 1;
            } else {
                // a push along one view's normal can land inside another view's
                // silhouette (folds, the crotch): push again from there, a few times
                let mut probe = probe;
                for _ in 0..self.opts.substeps.max(1) {
                    *p += probe.normal * (probe.escape - margin + clearance);
                    match hit(*p) {
                        Some(next) => probe = next,
                        None => break,
                    }
                }
                self.report.pushed += 1;
            }
            held[i] = true;
        }
        self.previous.clear();
        self.previous.extend_from_slice(&positions.raw);
    }
}

/// Steps of the exact pass per vertex before giving up on it.
const SETTLE_TRIES: usize = 4;

/// The exact final pass (module docs): every vertex not `fixed` that `tree`
/// finds inside the body goes to its closest body point plus `clearance_mm`
/// outward. Returns how many moved. A vertex exactly on the surface has no
/// direction and is left (it is not inside by more than rounding).
pub fn settle_exact(
    tree: &WindingTree,
    positions: &mut TiSlice<VertexId, DVec3>,
    fixed: &TiSlice<VertexId, bool>,
    clearance_mm: f64,
    memo: &mut InsideMemo,
) -> usize {
    let clearance = clearance_mm * 1e-3;
    let mut moved = 0;
    for (p, &f) in positions.iter_mut().zip(fixed) {
        if f || !memo.is_inside(tree, *p) {
            continue;
        }
        moved += 1;
        // where two parts of the body are close (under the arm) the clearance step
        // can land inside the other part: step again from there
        for _ in 0..SETTLE_TRIES {
            let (q, _, d) = tree.closest_point(*p);
            if !(d > 0.0 && d.is_finite()) {
                break;
            }
            *p = q + (q - *p) / d * clearance;
            if !memo.is_inside(tree, *p) {
                break;
            }
        }
    }
    moved
}

impl Collider<'_> {
    /// [`settle_exact`] with this collider's clearance, counted in its report.
    pub fn settle(
        &mut self,
        tree: &WindingTree,
        positions: &mut TiSlice<VertexId, DVec3>,
        fixed: &TiSlice<VertexId, bool>,
    ) {
        self.report.settled += settle_exact(tree, positions, fixed, self.opts.clearance_mm, &mut self.inside);
    }

    /// The exact final pass for the `fixed` vertices: each one `tree` finds
    /// inside goes out to [`ClearOptions::fixed_clearance_mm`]
    /// ([`push_out`]), counted in this collider's report.
    pub fn settle_fixed(
        &mut self,
        tree: &WindingTree,
        positions: &mut TiSlice<VertexId, DVec3>,
        fixed: &TiSlice<VertexId, bool>,
        opts: &ClearOptions,
    ) {
        for (p, &f) in positions.iter_mut().zip(fixed) {
            if f && self.inside.is_inside(tree, *p)
                && push_out(tree, p, opts.fixed_clearance_mm * 1e-3, opts.max_tries).is_some()
            {
                self.report.fixed_settled += 1;
            }
        }
    }
}
