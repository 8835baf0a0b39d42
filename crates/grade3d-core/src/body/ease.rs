//! Girth ease of a graded garment (`DESIGN.md` §5 "Ease", §9 "Ease as
//! declared"; issue #13 item 2): garment girth − body girth at each girth
//! the template declares an ease for, both taken with **the same tape
//! measure**.
//!
//! # Method
//!
//! The body's girth is the tape length of its feature curve
//! ([`crate::body::measure::girth_of`]): the perimeter of the convex hull of
//! the curve projected into its section plane `P` (the plane the curve was
//! cut with; else its least-squares plane). The garment's girth is the tape
//! length, in the same plane `P`, of the garment's own line at that girth:
//!
//! ```text
//! ease = tape_P(garment line) − tape_P(body curve)
//! ```
//!
//! - Where the template has a *ring* for the girth
//!   ([`crate::template::girth::ring_loop`]: the edges between nodes tied to
//!   the girth's feature points, closed through a node off it where the ring
//!   does so), the garment line is the refined garment's vertices along the
//!   ring's profiles (`lines`, [`crate::pipeline::Graded::girth_lines`]), as
//!   a pattern maker measures a garment on its hip or thigh line. A ring
//!   that hangs (a skirt's hip below a belly) or closes through the crotch
//!   lies partly off `P`; it is measured projected into `P`, as the
//!   expected figure is.
//! - Else, where the girth is an *opening* of the garment (every template
//!   edge around it lies on the template's boundary: a waistband, a
//!   neckline), the garment's boundary loop around the body curve.
//! - Else the garment is cut by `P` ([`slice`]); among the closed sections,
//!   the one whose projection into `P` contains the body curve's centroid
//!   and is the smallest such (a trouser leg around the left thigh, not the
//!   section around both legs; never one around the other leg's girth too).
//!
//! A template's ease entries name girths by their curve (`"hip"` is
//! `hip_girth`); entries that are not girths (`"hem_flare_radial"`,
//! `"crotch_drop"`) are not measured. A girth whose plane does not cut the
//! garment in a closed loop around the body curve (a sleeveless bodice's
//! armscye: the armhole is an opening) is *not covered* and left out.
//!
//! No failure modes: what cannot be measured is left out.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::body::feature::FeatureBody;
use crate::body::measure::{girth_of, MeasurementId};
use crate::body::vocab::{point_def, CurveId};
use crate::geom::mesh::{boundary_loops, TriMesh, VertexId};
use crate::geom::plane::Plane;
use crate::geom::polyline::{tape_length, Polyline};
use crate::geom::slice::slice;
use crate::template::format::Template;
use crate::template::girth::ring_curves;

/// Knobs of the ease measurement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EaseOptions {
    /// Rounding of the reported figures, mm. Default 0.1.
    pub round_mm: f64,
}

impl Default for EaseOptions {
    fn default() -> Self {
        Self { round_mm: 0.1 }
    }
}

/// The ease at one declared girth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct GirthEase {
    /// The template's name for it (`"hip"`).
    pub girth: String,
    /// The body measurement.
    pub measurement: MeasurementId,
    /// Body girth (tape), mm.
    pub body_mm: f64,
    /// Garment girth (tape, same plane), mm.
    pub garment_mm: f64,
    /// Garment − body, mm.
    pub measured_mm: f64,
    /// What the template declares, mm.
    pub declared_mm: f64,
    /// What the garment should have here, mm: the declared ease, or more
    /// where the template's shape rules add ease on purpose
    /// ([`crate::template::girth::expected_ease`]).
    pub expected_mm: f64,
}

/// The girth of the other side at the same level, for a leg or arm girth.
fn mirror(id: MeasurementId) -> Option<CurveId> {
    match id {
        MeasurementId::ThighGirth => Some(CurveId::ThighRight),
        MeasurementId::KneeGirth => Some(CurveId::KneeRight),
        MeasurementId::AnkleGirth => Some(CurveId::AnkleRight),
        MeasurementId::ArmscyeGirth => Some(CurveId::ArmscyeRight),
        _ => None,
    }
}

/// Whether girth `name` is an opening of the garment: every template edge
/// between two nodes tied to feature points on its curves lies on the
/// template's boundary (a waistband, a neckline), rather than around the
/// body inside the garment.
fn is_opening(t: &Template, name: &str) -> bool {
    let curves = ring_curves(name);
    let on = |node: u32| {
        t.nodes.get(node as usize).is_some_and(|n| {
            let d = point_def(n.point);
            curves.contains(&d.f1) || curves.contains(&d.f2)
        })
    };
    let mut uses: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for f in 0..t.faces.len() {
        let v = t.face_nodes(f);
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let ring: Vec<usize> = t
        .edges
        .iter()
        .filter(|e| on(e.start) && on(e.end))
        .map(|e| uses.get(&(e.start.min(e.end), e.start.max(e.end))).copied().unwrap_or(0))
        .collect();
    !ring.is_empty() && ring.iter().all(|&u| u == 1)
}

/// The boundary loops of a mesh as closed polylines.
fn boundary_polylines(mesh: &TriMesh) -> Vec<Polyline> {
    boundary_loops(mesh.triangles())
        .into_iter()
        .filter(|ids| ids.len() >= 3)
        .map(|ids| Polyline::new(ids.iter().map(|&v| mesh.positions()[v.idx()]).collect(), true))
        .collect()
}

/// Signed area of a closed polygon.
fn area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    0.5 * (0..n).map(|i| poly[i].perp_dot(poly[(i + 1) % n])).sum::<f64>()
}

/// The ease of `garment` on `body` at every girth `t` declares one for and
/// the garment covers (module docs), in the template's order of names;
/// `expected` the ease each should have (`Graded::expected_ease_mm`),
/// the declared one where absent; `lines` the garment's vertices along each
/// girth's ring (`Graded::girth_lines`).
pub fn girth_ease(
    body: &FeatureBody,
    garment: &TriMesh,
    t: &Template,
    expected: &BTreeMap<String, f64>,
    lines: &BTreeMap<String, Vec<VertexId>>,
    opts: &EaseOptions,
) -> Vec<GirthEase> {
    let round = |x: f64| if opts.round_mm > 0.0 { (x / opts.round_mm).round() * opts.round_mm } else { x };
    let mut out = Vec::new();
    for (name, &declared) in &t.ease_mm {
        let Ok(id) = format!("{name}_girth").parse::<MeasurementId>() else { continue };
        let Some(curve) = id.girth_curve().and_then(|c| body.curves.get(&c)) else { continue };
        let Some(plane) = curve.plane.or_else(|| Plane::fit(&curve.polyline.points)) else { continue };
        let body_m = girth_of(&curve.polyline, Some(&plane));
        let centre: DVec3 = curve.polyline.centroid();
        // the other leg's girth at the same level must not be inside the loop
        let other: Option<DVec3> = mirror(id).and_then(|c| body.curves.get(&c)).map(|c| c.polyline.centroid());
        let ring_line = lines.get(name).map(|ids| {
            let p = garment.positions();
            Polyline::new(ids.iter().filter_map(|&v| p.get(v.idx()).copied()).collect(), true)
        });
        let best = if let Some(l) = ring_line.filter(|l| l.points.len() >= 3) {
            Some((0.0, l))
        } else if is_opening(t, name) {
            // an opening (a waistband, a neckline): the garment's boundary loop around the girth
            boundary_polylines(garment)
                .into_iter()
                .filter(|l| l.contains_projected(&plane, centre))
                .map(|l| (l.centroid().distance(centre), l))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        } else {
            slice(garment, &plane)
                .into_iter()
                .filter(|s| s.polyline.closed && s.polyline.contains_projected(&plane, centre))
                .filter(|s| other.is_none_or(|o| !s.polyline.contains_projected(&plane, o)))
                .map(|s| (area(&s.polyline.to_plane_2d(&plane)).abs(), s.polyline))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        };
        let Some((_, loop_)) = best else { continue };
        let garment_m = tape_length(&[&loop_], &plane);
        out.push(GirthEase {
            girth: name.clone(),
            measurement: id,
            body_mm: round(body_m * 1e3),
            garment_mm: round(garment_m * 1e3),
            measured_mm: round((garment_m - body_m) * 1e3),
            declared_mm: declared,
            expected_mm: expected.get(name).copied().unwrap_or(declared),
        });
    }
    out
}
