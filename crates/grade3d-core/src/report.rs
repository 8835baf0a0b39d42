//! The fit report of one graded garment on one body (issue #16, item 3: a
//! step of the core, not geometry in the service's shell).
//!
//! Method: every vertex of the refined garment `M_L` (seed 000 §5) is
//! measured against the body by the exact signed distance of the winding
//! hierarchy ([`crate::geom::winding::WindingTree::signed_depth`]): the
//! *ease* `e(v) = −d(v)`, positive outside the body, in mm. The report
//! gives its quantiles (nearest rank on the sorted values), the vertices
//! inside (`e < 0`), the deepest one with the feature point nearest to it,
//! the garment/body triangle pairs the pipeline's last surface-clearing
//! round left crossing ([`crate::refine::clear`]), and the ease at every
//! girth the template declares, measured on the garment as cut
//! ([`crate::body::ease::girth_ease`]).
//!
//! Without an obstacle (no depth maps: collision avoidance was off) the
//! ease is reported as zero everywhere and `collision_checked` is false.
//!
//! Failure modes: [`FitReportError`] when the garment's triangles do not
//! index its vertices (a broken [`Graded`], never the caller's input).

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::body::ease::{girth_ease, EaseOptions, GirthEase};
use crate::body::feature::FeatureBody;
use crate::collide::Obstacle;
use crate::geom::mesh::MeshError;
use crate::pattern::assemble::SeamReport;
use crate::pattern::garment::PieceReport;
use crate::pipeline::Graded;
use crate::refine::collision::CollisionReport;
use crate::template::format::Template;

/// Knobs of the fit report.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct FitReportOptions {
    /// How girth ease is measured and rounded (default [`EaseOptions::default`]: 0.1 mm).
    pub ease: EaseOptions,
}

/// Why the fit report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FitReportError {
    /// The garment as cut is not a mesh (internal: the pipeline's output is broken).
    #[error("the garment as cut is not a mesh: {0}")]
    CutMesh(#[source] MeshError),
}

/// Quantiles of the garment's distance to the body over its vertices, mm
/// (positive outside; `None` for a garment with no vertices).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct DistanceQuantiles {
    /// Smallest (the deepest inside when negative).
    pub min: Option<f64>,
    /// 5th percentile.
    pub p05: Option<f64>,
    /// Median.
    pub median: Option<f64>,
    /// 95th percentile.
    pub p95: Option<f64>,
    /// Largest.
    pub max: Option<f64>,
}

/// A feature point near a garment vertex.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct NearestFeature {
    /// The feature point's id (`hip_front`).
    pub feature_point: String,
    /// Its distance from the vertex, mm (0.1 mm).
    pub distance_mm: f64,
}

/// The garment's penetration of the body by the exact tests.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PenetrationReport {
    /// Garment vertices (fixed ones included).
    pub vertices: usize,
    /// Of them inside the body by the exact inside test.
    pub vertices_inside: usize,
    /// Depth of the deepest one, mm (0.01 mm; 0 when none is inside).
    pub deepest_mm: f64,
    /// The feature point nearest to the deepest one (none when none is inside).
    pub deepest_near: Option<NearestFeature>,
    /// Garment triangles.
    pub garment_triangles: usize,
    /// Garment/body triangle pairs that intersect after the last clearing round.
    pub intersecting_triangle_pairs: usize,
    /// Of them at a thigh contact, where no two-legged garment can pass
    /// between the thighs outside the body ([`crate::body::contact`]).
    pub intersecting_triangle_pairs_at_thigh_contact: usize,
    /// Garment/body triangle pairs that intersected before clearing.
    pub intersecting_triangle_pairs_before_clearing: usize,
}

/// How one garment fits one body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct FitReport {
    /// Whether the body was an obstacle (depth maps rendered): without one
    /// the distances are zeros and there is no penetration figure.
    pub collision_checked: bool,
    /// The garment's distance to the body over its vertices, mm.
    pub distance_to_body_mm: DistanceQuantiles,
    /// Garment vertices inside the body.
    pub vertices_inside_body: usize,
    /// Penetration by the exact tests (with collision checking only).
    pub penetration: Option<PenetrationReport>,
    /// Per girth the template declares and the garment covers: body and
    /// garment tape in the girth's plane, measured, declared and expected ease.
    pub girth_ease: Vec<GirthEase>,
}

/// A fit report and the per-vertex ease it was made from.
#[derive(Debug, Clone, PartialEq)]
pub struct FitStep {
    /// Each refined garment vertex's distance to the body, mm (positive
    /// outside), in vertex order: the garment GLB's `_EASE_MM` attribute.
    pub ease_mm: Vec<f64>,
    /// The report.
    pub report: FitReport,
}

/// The report of one garment of a grade: its fit, what collision avoidance
/// did, and its pattern's figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct GarmentReport {
    /// The template's name.
    pub template: String,
    /// How it fits ([`fit_report`]).
    pub fit: FitReport,
    /// What collision avoidance did during refinement.
    pub collision: CollisionReport,
    /// Figures of every piece.
    pub pieces: Vec<PieceReport>,
    /// Per seam: length mismatch and how it was negotiated.
    pub seams: Vec<SeamReport>,
    /// Declared darts left out, with their opening when tried, mm (negative: inverted).
    #[schema(value_type = Vec<DartLeftOut>)]
    pub darts_left_out: Vec<(String, f64)>,
}

/// The schema of a declared dart left out: `[name, opening_mm]`, a pair
/// (written as a two-item array of mixed types rather than a tuple schema,
/// which generated clients do not read).
pub struct DartLeftOut;

impl utoipa::PartialSchema for DartLeftOut {
    fn schema() -> utoipa::openapi::RefOr<utoipa::openapi::schema::Schema> {
        use utoipa::openapi::schema::{ArrayBuilder, ObjectBuilder, OneOfBuilder, Type};
        ArrayBuilder::new()
            .items(
                OneOfBuilder::new()
                    .item(ObjectBuilder::new().schema_type(Type::String))
                    .item(ObjectBuilder::new().schema_type(Type::Number)),
            )
            .min_items(Some(2))
            .max_items(Some(2))
            .description(Some("`[dart name, opening mm]` (negative opening: inverted)"))
            .into()
    }
}

impl ToSchema for DartLeftOut {}

impl GarmentReport {
    /// The report of `g`, graded from template `template`, with its fit
    /// (its pattern's figures moved in, not copied).
    pub fn new(template: &str, g: Graded, fit: FitReport) -> Self {
        Self {
            template: template.to_owned(),
            fit,
            collision: g.collision,
            pieces: g.pattern.reports,
            seams: g.pattern.seams,
            darts_left_out: g.pattern.darts_left_out,
        }
    }
}

/// Nearest-rank quantiles of `values` (module docs).
fn quantiles(values: &[f64]) -> DistanceQuantiles {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let pick = |q: f64| sorted.get(((sorted.len().saturating_sub(1)) as f64 * q).round() as usize).copied();
    DistanceQuantiles { min: pick(0.0), p05: pick(0.05), median: pick(0.5), p95: pick(0.95), max: pick(1.0) }
}

/// The fit of garment `g`, graded from `t`, on `body` (module docs);
/// `obstacle` the body's winding hierarchy, `None` when collision avoidance
/// was off.
///
/// # Errors
/// [`FitReportError::CutMesh`] when the garment as cut is not a mesh.
pub fn fit_report(
    t: &Template,
    g: &Graded,
    body: &FeatureBody,
    obstacle: Option<&Obstacle>,
    opts: &FitReportOptions,
) -> Result<FitStep, FitReportError> {
    // girths are measured on the garment as cut (the pattern's surface)
    let cut = g.cut_mesh().map_err(FitReportError::CutMesh)?;
    let ease_mm: Vec<f64> = match obstacle {
        // the inside answers the grade's exact passes already have are not asked again
        Some(ob) => g
            .mesh
            .positions
            .iter_enumerated()
            .map(|(v, &p)| -ob.tree.signed_depth_known(p, g.inside.get(v).copied().flatten()) * 1e3)
            .collect(),
        None => vec![0.0; g.mesh.positions.len()],
    };
    let inside = ease_mm.iter().filter(|&&e| e < 0.0).count();
    let report = FitReport {
        collision_checked: obstacle.is_some(),
        distance_to_body_mm: quantiles(&ease_mm),
        vertices_inside_body: inside,
        penetration: obstacle.map(|_| penetration(g, body, &ease_mm, inside)),
        girth_ease: girth_ease(body, &cut, t, &g.expected_ease_mm, &g.girth_lines, &opts.ease),
    };
    Ok(FitStep { ease_mm, report })
}

/// Every garment vertex (fixed ones included) by the exact inside test, the
/// deepest one with the feature point nearest to it, and the garment/body
/// triangle pairs that intersect (the exact test of the pipeline's last
/// surface-clearing round). `ease_mm` is each vertex's signed distance to
/// the body, mm (negative inside), `inside` how many are negative.
fn penetration(g: &Graded, body: &FeatureBody, ease_mm: &[f64], inside: usize) -> PenetrationReport {
    let deepest = ease_mm.iter().enumerate().filter(|(_, &e)| e < 0.0).min_by(|a, b| a.1.total_cmp(b.1));
    let nearest = deepest.and_then(|(i, _)| {
        let p = g.mesh.positions.raw[i];
        body.points.iter().min_by(|a, b| a.1.position.distance(p).total_cmp(&b.1.position.distance(p))).map(
            |(id, q)| NearestFeature {
                feature_point: id.as_str().to_owned(),
                distance_mm: (q.position.distance(p) * 1e4).round() / 10.0,
            },
        )
    });
    PenetrationReport {
        vertices: ease_mm.len(),
        vertices_inside: inside,
        deepest_mm: deepest.map_or(0.0, |(_, &e)| (-e * 100.0).round() / 100.0),
        deepest_near: nearest,
        garment_triangles: g.collision.surface.garment_triangles,
        intersecting_triangle_pairs: g.collision.surface.pairs_after,
        intersecting_triangle_pairs_at_thigh_contact: g.collision.surface.pairs_after_at_thigh_contact,
        intersecting_triangle_pairs_before_clearing: g.collision.surface.pairs_before,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_nearest_rank_and_empty_gives_none() {
        // exact answers: 0..=100 has its quantiles at their own values
        let v: Vec<f64> = (0..=100).rev().map(f64::from).collect();
        let q = quantiles(&v);
        assert_eq!((q.min, q.p05, q.median, q.p95, q.max), (Some(0.0), Some(5.0), Some(50.0), Some(95.0), Some(100.0)));
        let e = quantiles(&[]);
        assert_eq!((e.min, e.median, e.max), (None, None, None));
    }
}
