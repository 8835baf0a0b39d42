//! Mirror symmetry of a garment graded on a mirror-symmetric body (issue
//! #14, item 2: mirror pairs are mirror images).
//!
//! # Method
//!
//! On a mannequin the body is its own mirror image across its mid-sagittal
//! plane `P` (`n·p = d`, `n` the mean direction from the right to the left
//! point of the body's left/right feature-point pairs, `d` the mean of their
//! midpoints), and the template's triangulation is mirrored too (the
//! authoring splits quads with mirrored diagonals), so the refined garment
//! should be its own mirror image. The collision stage breaks that by up to
//! a few millimetres (depth-map pushes in vertex order). Where the body
//! mirrors within [`SymmetryOptions::body_tolerance_mm`] and every garment
//! vertex `v` has a nearest vertex `w` to its mirror image
//! `M(p_v) = p_v − 2(n·p_v − d)n` within
//! [`SymmetryOptions::vertex_tolerance_mm`], every vertex is set to
//! `(p_v + M(p_w)) / 2` — exactly symmetric where the partners are mutual,
//! each vertex moved by half the asymmetry; passes repeat (at most
//! [`SYMMETRY_PASSES`]) until every partner is mutual. A vertex that is its
//! own partner lands on `P`.
//!
//! # Contract
//!
//! Input: the template (for nothing but its mirror pairs: a template without
//! any is left alone), the body, the garment's positions (the surface the
//! pattern is cut from). Output: the symmetrised positions, or `None` where
//! the body is not symmetric (a scan) or the garment has no vertex-to-vertex
//! mirror map. No failure modes. The lifted garment surface (what the
//! outside-the-body bars judge) is not touched.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::body::feature::FeatureBody;
use crate::geom::plane::Plane;
use crate::template::format::Template;

/// Passes at most: where the asymmetry rivals the vertex spacing (small
/// triangles at the crotch) a partner may not be mutual; each pass halves
/// the asymmetry there and the partners become mutual.
const SYMMETRY_PASSES: usize = 4;

/// Knobs of the symmetrisation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SymmetryOptions {
    /// Symmetrise at all. Default true.
    pub enabled: bool,
    /// The body is mirror-symmetric when every left/right feature-point pair
    /// mirrors within this, mm. Default 0.5 (a mannequin mirrors within
    /// 10⁻⁶ mm; a scan's halves differ by centimetres).
    pub body_tolerance_mm: f64,
    /// A garment vertex's mirror partner lies within this of its mirror
    /// image, mm. Default 5 (the collision stage's asymmetry is below 3 mm;
    /// refined edges are 10–30 mm long).
    pub vertex_tolerance_mm: f64,
}

impl Default for SymmetryOptions {
    fn default() -> Self {
        Self { enabled: true, body_tolerance_mm: 0.5, vertex_tolerance_mm: 5.0 }
    }
}

/// The body's mid-sagittal plane `(n, d)` and how far its left/right feature
/// points are from mirroring, m; `None` without such pairs.
fn body_plane(body: &FeatureBody) -> Option<((DVec3, f64), f64)> {
    let mut pairs = Vec::new();
    for (id, p) in &body.points {
        let name = id.as_str();
        let Some(right) = (name.contains("left")).then(|| name.replace("left", "right")) else { continue };
        if let Some((_, q)) = body.points.iter().find(|(k, _)| k.as_str() == right) {
            pairs.push((p.position, q.position));
        }
    }
    let Plane { normal: n, offset: d } = Plane::bisecting(&pairs, None)?;
    let mirror = |p: DVec3| p - 2.0 * (n.dot(p) - d) * n;
    let worst = pairs.iter().map(|(l, r)| mirror(*l).distance(*r)).fold(0.0, f64::max);
    Some(((n, d), worst))
}

/// The symmetrised positions (module docs), or `None`.
pub fn symmetrize(t: &Template, body: &FeatureBody, positions: &[DVec3], opts: &SymmetryOptions) -> Option<Vec<DVec3>> {
    if !opts.enabled || t.mirror_pairs.is_empty() || positions.is_empty() {
        return None;
    }
    let ((n, d), worst) = body_plane(body)?;
    if worst * 1e3 > opts.body_tolerance_mm {
        return None;
    }
    let mirror = |p: DVec3| p - 2.0 * (n.dot(p) - d) * n;
    let tol2 = (opts.vertex_tolerance_mm * 1e-3).powi(2);
    let mut out = positions.to_vec();
    for _ in 0..SYMMETRY_PASSES {
        let nearest = |q: DVec3| -> (usize, f64) {
            out.iter()
                .enumerate()
                .map(|(i, p)| (i, p.distance_squared(q)))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .unwrap_or((0, f64::INFINITY))
        };
        let partner: Vec<usize> = out
            .iter()
            .map(|&p| {
                let (w, d2) = nearest(mirror(p));
                (d2 <= tol2).then_some(w)
            })
            .collect::<Option<Vec<usize>>>()?;
        let mutual = partner.iter().enumerate().all(|(v, &w)| partner[w] == v);
        out = out.iter().zip(&partner).map(|(&p, &w)| 0.5 * (p + mirror(out[w]))).collect();
        if mutual {
            break;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::template::library::{builtin, reference_body};

    fn trousers() -> Template {
        builtin().unwrap().into_iter().find(|t| t.name == "trousers").unwrap()
    }

    #[test]
    fn a_planted_asymmetry_is_halved_onto_both_partners() {
        let body = reference_body().unwrap();
        let ((n, d), worst) = body_plane(&body).unwrap();
        assert!(worst < 1e-9, "the reference mannequin mirrors: {worst} m");
        let mirror = |p: DVec3| p - 2.0 * (n.dot(p) - d) * n;
        // a grid of points 20 mm apart on the left, their mirror images on the right
        let left: Vec<DVec3> = (0..6)
            .flat_map(|i| (0..6).map(move |j| (i, j)))
            .map(|(i, j)| d * n + n * (0.05 + 0.02 * f64::from(i)) + DVec3::new(0.0, 0.02 * f64::from(j), 0.1))
            .collect();
        let mut positions: Vec<DVec3> = left.iter().copied().chain(left.iter().map(|&p| mirror(p))).collect();
        let planted = DVec3::new(0.001, -0.0015, 0.0005);
        positions[7] += planted;
        let out = symmetrize(&trousers(), &body, &positions, &SymmetryOptions::default()).unwrap();
        let k = left.len();
        for v in 0..k {
            assert!(mirror(out[v]).distance(out[v + k]) < 1e-12, "vertex {v} and its partner mirror");
        }
        // each of the pair moved by half the asymmetry: p + δ/2 and M(p) + M(δ)/2
        assert!(out[7].distance(left[7] + 0.5 * planted) < 1e-12);
        assert!(out[7 + k].distance(mirror(left[7]) + 0.5 * (mirror(planted) - mirror(DVec3::ZERO))) < 1e-12);
        for v in (0..2 * k).filter(|&v| v != 7 && v != 7 + k) {
            assert!(out[v].distance(positions[v]) < 1e-12, "vertex {v} was symmetric and stays");
        }
    }

    #[test]
    fn an_asymmetric_body_or_a_garment_without_partners_is_left_alone() {
        let mut body = reference_body().unwrap();
        let positions = vec![DVec3::new(0.1, 1.0, 0.1), DVec3::new(-0.1, 1.0, 0.1)];
        let far = vec![DVec3::new(0.1, 1.0, 0.1), DVec3::new(-0.3, 1.0, 0.1)];
        let opts = SymmetryOptions::default();
        assert!(symmetrize(&trousers(), &body, &far, &opts).is_none(), "no partner within 5 mm");
        let mut skirt = trousers();
        skirt.mirror_pairs.clear();
        assert!(symmetrize(&skirt, &body, &positions, &opts).is_none(), "no mirror pairs declared");
        // a scan: one side's hip point 2 mm off its mirror image
        let hip = body.points.keys().copied().find(|k| k.as_str() == "hip_left").unwrap();
        body.points.get_mut(&hip).unwrap().position.y += 0.002;
        assert!(symmetrize(&trousers(), &body, &positions, &opts).is_none(), "the body does not mirror");
    }
}
