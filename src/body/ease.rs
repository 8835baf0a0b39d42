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
//! cut with; else its least-squares plane). The garment is cut by the same
//! plane `P` ([`slice`]); among the closed sections, the one whose
//! projection into `P` contains the body curve's centroid and is the
//! smallest such is the garment at that girth (a trouser leg around the
//! left thigh, not the section around both legs); its tape length is the
//! garment girth. Then
//!
//! ```text
//! ease = tape(garment ∩ P) − tape(body curve)
//! ```
//!
//! A template's ease entries name girths by their curve (`"hip"` is
//! `hip_girth`); entries that are not girths (`"hem_flare_radial"`,
//! `"crotch_drop"`) are not measured. A girth whose plane does not cut the
//! garment in a closed loop around the body curve (a sleeveless bodice's
//! armscye: the armhole is an opening) is *not covered* and left out.
//!
//! No failure modes: what cannot be measured is left out.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::body::feature::FeatureBody;
use crate::body::measure::{girth_of, MeasurementId};
use crate::geom::mesh::TriMesh;
use crate::geom::plane::Plane;
use crate::geom::polyline::tape_length;
use crate::geom::slice::slice;
use crate::template::format::Template;

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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// What the garment should have here, mm: the declared ease.
    pub expected_mm: f64,
}

/// Signed area of a closed polygon.
fn area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    0.5 * (0..n).map(|i| poly[i].perp_dot(poly[(i + 1) % n])).sum::<f64>()
}

/// The ease of `garment` on `body` at every girth `t` declares one for and
/// the garment covers (module docs), in the template's order of names.
pub fn girth_ease(body: &FeatureBody, garment: &TriMesh, t: &Template, opts: &EaseOptions) -> Vec<GirthEase> {
    let round = |x: f64| if opts.round_mm > 0.0 { (x / opts.round_mm).round() * opts.round_mm } else { x };
    let mut out = Vec::new();
    for (name, &declared) in &t.ease_mm {
        let Ok(id) = format!("{name}_girth").parse::<MeasurementId>() else { continue };
        let Some(curve) = id.girth_curve().and_then(|c| body.curves.get(&c)) else { continue };
        let Some(plane) = curve.plane.or_else(|| Plane::fit(&curve.polyline.points)) else { continue };
        let body_m = girth_of(&curve.polyline, Some(&plane));
        let centre: DVec3 = curve.polyline.centroid();
        let best = slice(garment, &plane)
            .into_iter()
            .filter(|s| s.polyline.closed && s.polyline.contains_projected(&plane, centre))
            .map(|s| (area(&s.polyline.to_plane_2d(&plane)).abs(), s.polyline))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let Some((_, loop_)) = best else { continue };
        let garment_m = tape_length(&[&loop_], &plane);
        out.push(GirthEase {
            girth: name.clone(),
            measurement: id,
            body_mm: round(body_m * 1e3),
            garment_mm: round(garment_m * 1e3),
            measured_mm: round((garment_m - body_m) * 1e3),
            declared_mm: declared,
            expected_mm: declared,
        });
    }
    out
}
