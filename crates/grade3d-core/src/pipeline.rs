//! One grade: a template on a feature body, end to end — decode (seed 000
//! Eq. 1), nodes and profile points moved out of the body
//! ([`crate::refine::clear::clear_coarse`], issue #13), refine with
//! collision avoidance (§5, issue #4), tangential relaxation, the exact final
//! pass over every vertex (fixed ones to their smaller clearance), the
//! garment surface lifted until no triangle crosses the body
//! ([`crate::refine::clear::clear_surface`]), and the sewing pattern (§6,
//! issue #5), cut from the surface before that lift
//! ([`crate::refine::clear::ClearOptions::pattern_before_lift`]: the lifts
//! are bumps cloth drapes over, not shape to cut). The expected ease of each
//! declared girth is taken after decoding ([`Graded::expected_ease_mm`]).
//!
//! Pure core: data in, data out; the body's depth maps come in as an
//! [`Obstacle`] that the caller builds ([`Obstacle::build`], from any
//! [`crate::collide::DepthRenderer`]: the service's is wgpu's, in
//! `grade3d-render`) and caches. Without an obstacle the garment
//! is refined without collision avoidance. Each stage's wall time is
//! reported ([`StageTimings`]) for the service's metrics and the fit report.
//!
//! **Failure modes** — [`PipelineError`], the failing stage's typed error.

use std::time::Instant;

use typed_index_collections::{TiSlice, TiVec};

use serde::{Deserialize, Serialize};

use crate::body::feature::FeatureBody;
use crate::collide::Obstacle;
use crate::geom::mesh::{FaceId, VertexId};
use crate::pattern::garment::{
    pattern_with_darts, DartBarrier, DartPlan, DartSource, GarmentPattern, PatternError, PatternOptions,
};
use crate::refine::clear::{clear_coarse, clear_surface, ClearError, ClearOptions};
use crate::refine::collision::{Collider, CollisionOptions, CollisionReport};
use crate::refine::lineage::{node_vertex, Lineage};
use crate::refine::subdivide::{
    refine, relax_tangentially, LevelReport, RefineError, RefineMesh, RefineOptions, Refined,
};
use crate::refine::symmetry::{symmetrize, SymmetryOptions, Topology};
use crate::template::codec::{decode, CodecError};
use crate::template::format::Template;
use crate::template::girth::{expected_ease, ring_curves, ring_loop};

/// Knobs of one grade. Levels, clearance, seam allowance and relocation
/// default to the template's `defaults` where the field is `None`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct GradeOptions {
    /// Subdivision levels (count). Default: the template's (3 for the built-ins).
    pub levels: Option<usize>,
    /// Clearance between garment and body, mm. Default: the template's (3).
    pub clearance_mm: Option<f64>,
    /// Seam allowance, mm. Default: the template's (10).
    pub seam_allowance_mm: Option<f64>,
    /// Fairing (levels/clearance above override its fields).
    pub refine: RefineOptions,
    /// Collision avoidance (the clearance above overrides its field).
    pub collision: CollisionOptions,
    /// Keeping fixed vertices and the garment surface outside the body.
    pub clear: ClearOptions,
    /// Pattern pieces and flattening (the allowance above overrides its field).
    pub pattern: PatternOptions,
    /// Mirror symmetry of the surface the pattern is cut from, on a
    /// symmetric body ([`crate::refine::symmetry`]).
    pub symmetry: SymmetryOptions,
}

/// Why a grade failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PipelineError {
    /// The template does not fit the body (a feature point is missing).
    #[error(transparent)]
    Decode(#[from] CodecError),
    /// Subdivision failed.
    #[error(transparent)]
    Refine(#[from] RefineError),
    /// A profile could not be solved again after it was moved out of the body.
    #[error(transparent)]
    Clear(#[from] ClearError),
    /// The pattern failed.
    #[error(transparent)]
    Pattern(#[from] PatternError),
    /// A nested option that a grade does not read was set (issue #16: it
    /// was overwritten silently): the grade takes `top`, or the template's
    /// default where `top` is `None`.
    #[error("option `{nested}` is not read by a grade; set `{top}` instead (unset: the template's default)")]
    ShadowedOption {
        /// The nested field that was set.
        nested: &'static str,
        /// The field a grade reads.
        top: &'static str,
    },
}

impl GradeOptions {
    /// Checks that no nested field shadowed by a top-level one
    /// (`refine.levels` by `levels`, `collision.clearance_mm` by
    /// `clearance_mm`, `pattern.piece.seam_allowance_mm` by
    /// `seam_allowance_mm`) differs from its default: a grade never reads
    /// them, so a value there would be lost.
    ///
    /// # Errors
    /// [`PipelineError::ShadowedOption`] naming the first such field.
    pub fn check(&self) -> Result<(), PipelineError> {
        let shadowed = [
            (self.refine.levels != RefineOptions::default().levels, "refine.levels", "levels"),
            (
                self.collision.clearance_mm != CollisionOptions::default().clearance_mm,
                "collision.clearance_mm",
                "clearance_mm",
            ),
            (
                self.pattern.piece.seam_allowance_mm != PatternOptions::default().piece.seam_allowance_mm,
                "pattern.piece.seam_allowance_mm",
                "seam_allowance_mm",
            ),
        ];
        match shadowed.into_iter().find(|s| s.0) {
            Some((_, nested, top)) => Err(PipelineError::ShadowedOption { nested, top }),
            None => Ok(()),
        }
    }
}

/// Wall time per stage, ms.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct StageTimings {
    /// Decoding the template onto the body.
    pub decode_ms: f64,
    /// Subdivision, fairing and collision avoidance (without the clearing below).
    pub refine_ms: f64,
    /// Moving nodes and profile points out before refinement and lifting the
    /// surface off the body after it (exact tests).
    pub clear_ms: f64,
    /// Cutting, flattening and assembling the pattern.
    pub pattern_ms: f64,
}

/// A graded garment.
#[derive(Debug, Clone, PartialEq)]
pub struct Graded {
    /// The refined garment `M_L` (metres).
    pub mesh: RefineMesh,
    /// Fairing per level.
    pub levels: Vec<LevelReport>,
    /// Which vertex each level's split put on each edge (the panels and
    /// seams are cut by it).
    pub lineage: Lineage,
    /// What collision avoidance did (zeros without an obstacle).
    pub collision: CollisionReport,
    /// The sewing pattern.
    pub pattern: GarmentPattern,
    /// Wall time per stage.
    pub timings: StageTimings,
    /// The ease each declared girth should have, mm
    /// ([`crate::template::girth::expected_ease`]).
    pub expected_ease_mm: std::collections::BTreeMap<String, f64>,
    /// The garment's line at each declared girth that has a ring in the
    /// template ([`crate::template::girth::ring_loop`]; the left leg's for a
    /// leg girth): the vertices of `mesh` along the ring's profiles, by
    /// `ease_mm` name. The ease is measured on it
    /// ([`crate::body::ease::girth_ease`]).
    pub girth_lines: std::collections::BTreeMap<String, Vec<VertexId>>,
    /// The surface the pattern was cut from (`mesh`'s positions before the
    /// surface lift, [`ClearOptions::pattern_before_lift`]; else `mesh`'s):
    /// the garment as made. Its girths are the garment's girths
    /// ([`crate::body::ease::girth_ease`]); the lift's local bumps over hip
    /// bones and knees are drape, not cloth length.
    pub cut_positions: TiVec<VertexId, glam::DVec3>,
    /// Per vertex of `mesh`, whether the body's exact inside test
    /// ([`crate::geom::winding::WindingTree::is_inside`]) found it inside
    /// at its final position, where one of the grade's exact passes asked
    /// (issue #15: the fit report then need not ask again); empty without
    /// an obstacle.
    pub inside: TiVec<VertexId, Option<bool>>,
}

impl Graded {
    /// The garment as cut ([`Self::cut_positions`] on `mesh`'s triangles),
    /// the surface whose girths the fit report measures.
    ///
    /// # Errors
    /// [`crate::geom::mesh::MeshError`] if a position is not finite.
    pub fn cut_mesh(&self) -> Result<crate::geom::mesh::TriMesh, crate::geom::mesh::MeshError> {
        crate::geom::mesh::TriMesh::new(self.cut_positions.raw.clone(), self.mesh.triangles.raw.clone())
    }
}

/// The vertices of `refined` along each declared girth's ring (module docs of
/// [`crate::template::girth`]), by `ease_mm` name; `coarse` the decoded node
/// positions (which nodes are ring nodes).
pub fn girth_lines(
    t: &Template,
    body: &FeatureBody,
    coarse: &[glam::DVec3],
    hung: &[u32],
    refined: &RefineMesh,
) -> std::collections::BTreeMap<String, Vec<VertexId>> {
    // every ring's template edges, then all their refined chains in one pass
    let rings: Vec<(&String, Vec<(VertexId, VertexId)>)> = t
        .ease_mm
        .keys()
        .filter_map(|name| {
            let &curve = ring_curves(name).first()?;
            let ring = ring_loop(t, body, coarse, curve, hung);
            let ends = |e: u32| (node_vertex(t.edges[e as usize].start), node_vertex(t.edges[e as usize].end));
            Some((name, ring.edges.iter().map(|&e| ends(e)).collect()))
        })
        .collect();
    let pairs: Vec<(VertexId, VertexId)> = rings.iter().flat_map(|r| r.1.iter().copied()).collect();
    let mut chains = refined.profile_chains(&pairs).into_iter();
    let mut out = std::collections::BTreeMap::new();
    for (name, edges) in rings {
        let mut line: Vec<VertexId> = chains.by_ref().take(edges.len()).flatten().flatten().collect();
        line.sort_unstable();
        line.dedup();
        if line.len() >= 3 {
            out.insert(name.clone(), line);
        }
    }
    out
}

/// The refined vertices of the garment's hanging region: those of the fine
/// faces whose coarse face has a node hanging below a girth
/// ([`Template::below`]). Below its lowest girth a skirt or dress falls
/// straight (a ruled surface: the method of [`Below`]), and darts go there
/// only where a piece needs them ([`DartBarrier::hanging`]).
///
/// [`Below`]: crate::template::format::Below
pub fn hanging_vertices(
    t: &Template,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    levels: usize,
) -> std::collections::HashSet<VertexId> {
    let hung: std::collections::HashSet<u32> = t.below.iter().map(|b| b.node).collect();
    let per = 1usize << (2 * levels);
    (0..t.faces.len())
        .filter(|&f| t.face_nodes(f).iter().any(|n| hung.contains(n)))
        .flat_map(|f| (f * per..(f + 1) * per).filter_map(|k| triangles.get(FaceId::from(k))).flatten().copied())
        .collect()
}

fn ms(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}

/// Grades `t` onto `body` (module docs); `size` names the result. The
/// pattern's darts are decided on this body ([`crate::pattern::garment::pattern`]).
///
/// # Errors
/// [`PipelineError`].
pub fn grade(
    t: &Template,
    body: &FeatureBody,
    obstacle: Option<&Obstacle>,
    size: &str,
    opts: &GradeOptions,
) -> Result<Graded, PipelineError> {
    grade_with_plan(t, body, obstacle, size, opts, None)
}

/// [`grade`], the pattern's darts those of `plan` where given: a size of a
/// run whose base size decided them (issue #14: one dart plan per grade
/// run, [`pattern_with_plan`]); the base size's plan is
/// `Graded::pattern.dart_plan`.
///
/// # Errors
/// [`PipelineError`].
pub fn grade_with_plan(
    t: &Template,
    body: &FeatureBody,
    obstacle: Option<&Obstacle>,
    size: &str,
    opts: &GradeOptions,
    plan: Option<&DartPlan>,
) -> Result<Graded, PipelineError> {
    grade_with_darts(t, body, obstacle, size, opts, DartSource::from(plan))
}

/// Size label of a template's block grade ([`block`]).
pub const BLOCK_SIZE: &str = "block";

/// A template's *block* (issue #15, [`DartSource::Block`]): its dart plan
/// on `reference`, the body it is authored on
/// ([`crate::template::library::reference_body`]), its darts decided there.
///
/// # Errors
/// [`PipelineError`] of that grade.
pub fn block(
    t: &Template,
    reference: &FeatureBody,
    obstacle: Option<&Obstacle>,
    opts: &GradeOptions,
) -> Result<DartPlan, PipelineError> {
    Ok(grade_with_darts(t, reference, obstacle, BLOCK_SIZE, opts, DartSource::Decide)?.pattern.dart_plan)
}

/// [`grade`], the pattern's darts from `darts` ([`DartSource`]: decided on
/// this body, a run's plan, or the template's block).
///
/// # Errors
/// [`PipelineError`].
pub fn grade_with_darts(
    t: &Template,
    body: &FeatureBody,
    obstacle: Option<&Obstacle>,
    size: &str,
    opts: &GradeOptions,
    darts: DartSource<'_>,
) -> Result<Graded, PipelineError> {
    opts.check()?;
    let levels = opts.levels.unwrap_or(t.defaults.levels as usize);
    let clearance_mm = opts.clearance_mm.unwrap_or(t.defaults.clearance_mm);
    let refine_opts = RefineOptions { levels, ..opts.refine };
    let collision_opts = CollisionOptions { clearance_mm, ..opts.collision };
    let mut pattern_opts = opts.pattern;
    pattern_opts.piece.seam_allowance_mm = opts.seam_allowance_mm.unwrap_or(t.defaults.seam_allowance_mm);
    pattern_opts.auto_darts.guided |= t.defaults.guided_darts;

    let start = Instant::now();
    let mut m0 = decode(t, body, t.defaults.relocation)?;
    let (decoded, hung) = (m0.positions.clone(), m0.hung.clone());
    let edges: Vec<(u32, u32)> = t.edges.iter().map(|e| (e.start, e.end)).collect();
    let clear_start = Instant::now();
    let coarse_clear = match obstacle {
        Some(ob) => clear_coarse(&mut m0, &edges, &ob.tree, &opts.clear)?,
        None => Default::default(),
    };
    let coarse_ms = ms(clear_start);
    let expected_ease_mm = expected_ease(t, body, &m0);
    let mut surface_ms = 0.0;
    let mut unlifted = None;
    let mut inside = TiVec::new();
    let coarse = RefineMesh::from_coarse(&m0, &edges)?;
    let decode_ms = ms(start) - coarse_ms;

    let start = Instant::now();
    let (mesh, level_reports, lineage, collision) = match obstacle {
        Some(ob) => {
            let mut collider = Collider::new(&ob.maps, collision_opts);
            let Refined { mut mesh, levels: reports, lineage } =
                refine(coarse, &refine_opts, |p, h| collider.after_sweep(p, h))?;
            relax_tangentially(&mut mesh, refine_opts.relax_sweeps, refine_opts.relax_step)?;
            collider.settle(&ob.tree, &mut mesh.positions, &mesh.fixed);
            collider.settle_fixed(&ob.tree, &mut mesh.positions, &mesh.fixed, &opts.clear);
            let mut report = collider.report;
            report.coarse = coarse_clear;
            unlifted = opts.clear.pattern_before_lift.then(|| mesh.positions.clone());
            let surface_start = Instant::now();
            report.surface = clear_surface(
                &ob.tree,
                &mut mesh.positions,
                &mesh.triangles,
                clearance_mm,
                body.thigh_contact.as_ref(),
                &opts.clear,
                &mut collider.inside,
            );
            surface_ms = ms(surface_start);
            inside = mesh.positions.iter().map(|&p| collider.inside.get(p)).collect();
            (mesh, reports, lineage, report)
        }
        None => {
            let Refined { mut mesh, levels: reports, lineage } = refine(coarse, &refine_opts, |_, _| {})?;
            relax_tangentially(&mut mesh, refine_opts.relax_sweeps, refine_opts.relax_step)?;
            (mesh, reports, lineage, CollisionReport::default())
        }
    };
    let refine_ms = ms(start);

    let start = Instant::now();
    let cut_from = unlifted.as_deref().unwrap_or(mesh.positions.as_slice());
    // on a symmetric body the surface the pattern is cut from is made exactly symmetric
    let topology = Topology { triangles: &mesh.triangles, nodes: &decoded };
    let symmetric = symmetrize(t, body, cut_from, Some(topology), &opts.symmetry);
    let cut_from = symmetric.as_deref().unwrap_or(cut_from);
    let girth_lines = girth_lines(t, body, &decoded, &hung, &mesh);
    // found darts run through no girth line, and into the region that hangs below one only where
    // a piece needs them there
    // (only guided darts read it)
    let barrier = if pattern_opts.auto_darts.guided {
        DartBarrier {
            girth_lines: girth_lines.values().flatten().copied().collect(),
            hanging: hanging_vertices(t, &mesh.triangles, lineage.levels()),
        }
    } else {
        DartBarrier::default()
    };
    let pattern = pattern_with_darts(t, cut_from, &mesh.triangles, &lineage, size, &pattern_opts, darts, &barrier)?;
    let pattern_ms = ms(start);
    let cut_positions = cut_from.to_owned();
    Ok(Graded {
        cut_positions,
        inside,
        girth_lines,
        mesh,
        levels: level_reports,
        lineage,
        collision,
        pattern,
        expected_ease_mm,
        timings: StageTimings {
            decode_ms,
            refine_ms: refine_ms - surface_ms,
            clear_ms: coarse_ms + surface_ms,
            pattern_ms,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shadowed_nested_option_is_an_error_not_overwritten() {
        // regression (issue #16): `refine.levels`, `collision.clearance_mm` and
        // `pattern.piece.seam_allowance_mm` were overwritten by the template's defaults
        assert_eq!(GradeOptions::default().check(), Ok(()));
        let mut o = GradeOptions::default();
        o.refine.levels = 2;
        assert_eq!(o.check(), Err(PipelineError::ShadowedOption { nested: "refine.levels", top: "levels" }));
        let mut o = GradeOptions { levels: Some(2), ..GradeOptions::default() };
        assert_eq!(o.check(), Ok(()));
        o.collision.clearance_mm = 5.0;
        let e = o.check().unwrap_err();
        assert_eq!(e, PipelineError::ShadowedOption { nested: "collision.clearance_mm", top: "clearance_mm" });
        assert!(e.to_string().contains("set `clearance_mm` instead"), "{e}");
        let mut o = GradeOptions::default();
        o.pattern.piece.seam_allowance_mm = 15.0;
        assert!(matches!(o.check(), Err(PipelineError::ShadowedOption { top: "seam_allowance_mm", .. })));
    }
}
