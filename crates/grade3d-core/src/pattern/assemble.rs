//! Pattern pieces from flattened panels (seed 000 §6; seed 002 §6 for seam,
//! grain and notch lines): orientation by the grain line, sew line, cut line
//! with mitred corners, notches, internal feature lines, grade points, and
//! the per-piece and per-seam figures of issue #5.
//!
//! # Contract
//!
//! **Placement.** The flattened panel (`uv`, metres) is scaled to mm,
//! mirrored if its outline runs clockwise (so every piece is seen from the
//! garment's outside, where the template's faces are counter-clockwise),
//! rotated so that the template's grain line `from → to` points along `−y`
//! (grain lines run down the body, so the piece is upright) and translated
//! so that the grain line's stack node (`GrainLine::stack`, else its `from`
//! node) — the **stack point** — is the origin.
//!
//! **Sew line** — the panel's outline, with each dart closed (straight across
//! its opening; the legs become an internal line). **Corners** (turn points) — template
//! nodes on the outline where a seam starts or ends, or where the outline
//! turns by more than [`PieceOptions::corner_angle_deg`]. **Grade points** —
//! every template node on the outline (the same set in every size) and the
//! notches.
//!
//! **Cut line** — the sew line offset outwards by the seam allowance `s`:
//! each edge moved by `s` along its outward normal `n = (d_y, −d_x)/|d|`
//! (counter-clockwise polygon), consecutive offset edges intersected (a
//! mitre); where the mitre would reach further than
//! [`PieceOptions::miter_limit`] × `s` from the corner the corner is
//! bevelled (two points instead).
//!
//! **Notches** — at every template notch node on the outline, across the
//! allowance along the vertex normal (bisector of the two edge normals).
//! Both sides of a seam get the notch at the same template node, so they
//! sit at matching distances along the seam up to the seam's mismatch
//! ([`SeamReport`]).
//!
//! **Internal lines** — (a) girth lines: interior template edges whose two
//! nodes lie on the same girth — their feature points both on that girth
//! curve ([`GIRTH_CURVES`]) and each node level with its point (its Eq. (2)
//! offset's height within [`RING_PLANE_TOLERANCE_M`]: a hem node tied to a
//! hip point 35 cm above is not on the hip) —, as fine chains, named after
//! the girth (`hip_line`, `thigh_line`, `bust_line`); a line whose ring is
//! open at a node with one girth edge (a trouser thigh's ends) runs on
//! along that node's edge to a crotch node on the outline — only there (an
//! authored skirt's closed hip ring met hem nodes tied to the crotch, and
//! its line branched); (b) every dart as a
//! pattern maker draws it, two straight legs from the mouth to the apex
//! (mouth → apex → mouth): the flattened slit's own legs bend and, where the
//! flattening squeezes a narrow dart, cross.
//!
//! **Failure modes** — [`PieceError`]: the grain line's nodes not in the
//! panel, or `uv` not one point per panel vertex.

use std::collections::{BTreeMap, HashMap, HashSet};

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use typed_index_collections::{TiSlice, TiVec};

use super::panels::{Panel, PanelVertex, SeamChain};
use super::piece::{GradePoint, GradePointKind, InternalLine, PatternPiece, PieceNotch};
use crate::body::vocab::{point_def, CurveId, PointId};
use crate::geom::mesh::VertexId;
use crate::geom::polyline::segment_crosses_polygon;
use crate::refine::lineage::{node_vertex, vertex_node, Lineage};
use crate::template::format::Template;
use crate::template::girth::RING_PLANE_TOLERANCE_M;

/// Metres to millimetres.
const MM_PER_M: f64 = 1e3;

/// Knobs of piece assembly.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PieceOptions {
    /// Seam allowance, mm. Default 10 (the template's `defaults.seam_allowance_mm` is
    /// what the grading pipeline passes).
    pub seam_allowance_mm: f64,
    /// A template node on the outline is a corner when the outline turns there by
    /// more than this, degrees. Default 30.
    pub corner_angle_deg: f64,
    /// A mitre longer than this multiple of the allowance is bevelled (count). Default 3.
    pub miter_limit: f64,
}

impl Default for PieceOptions {
    fn default() -> Self {
        Self { seam_allowance_mm: 10.0, corner_angle_deg: 30.0, miter_limit: 3.0 }
    }
}

/// Why a piece could not be assembled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PieceError {
    /// A grain-line node is not in the panel.
    #[error("panel '{panel}': grain-line node {node} is not in the panel")]
    GrainOffPanel {
        /// Panel name.
        panel: String,
        /// Template node.
        node: u32,
    },
    /// The grain line has zero length in the flattened panel.
    #[error("panel '{panel}': the grain line has zero length when flattened")]
    DegenerateGrain {
        /// Panel name.
        panel: String,
    },
    /// `uv` does not have one point per panel vertex.
    #[error("panel '{panel}': {uv} flattened points for {vertices} vertices")]
    UvCount {
        /// Panel name.
        panel: String,
        /// Points given.
        uv: usize,
        /// Panel vertices.
        vertices: usize,
    },
}

/// A piece in mm, aligned, with its panel's local vertex positions in 2D.
#[derive(Debug, Clone, PartialEq)]
pub struct PlacedPanel {
    /// The pattern piece.
    pub piece: PatternPiece,
    /// Every panel vertex in piece coordinates, mm (local ids of the [`Panel`]).
    pub uv_mm: TiVec<PanelVertex, DVec2>,
}

/// Figures of one seam: the two sides' 2D lengths against the 3D length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SeamReport {
    /// Seam name.
    pub name: String,
    /// Piece of side a.
    pub piece_a: String,
    /// Piece of side b.
    pub piece_b: String,
    /// Length on the 3D garment, mm.
    pub length_3d_mm: f64,
    /// Sew-line length of side a, mm.
    pub length_a_mm: f64,
    /// Sew-line length of side b, mm.
    pub length_b_mm: f64,
    /// `|length_a − length_b|`, mm.
    pub mismatch_mm: f64,
    /// Largest difference of a notch's distance from the seam start between the sides, mm
    /// (0 when the seam has no notch).
    pub notch_mismatch_mm: f64,
}

/// Builds the pattern piece of `panel` from its flattening `uv` (metres, one per
/// local vertex) — module docs.
///
/// # Errors
/// [`PieceError`].
pub fn assemble(
    t: &Template,
    panel: &Panel,
    seams: &[SeamChain],
    lineage: &Lineage,
    uv: &TiSlice<PanelVertex, DVec2>,
    size: &str,
    opts: &PieceOptions,
) -> Result<PlacedPanel, PieceError> {
    let name = || panel.name.clone();
    if uv.len() != panel.positions.len() {
        return Err(PieceError::UvCount { panel: name(), uv: uv.len(), vertices: panel.positions.len() });
    }
    let template_panel = &t.panels[panel.index];
    let node_local =
        |node: u32| panel.local(node_vertex(node)).ok_or(PieceError::GrainOffPanel { panel: name(), node });
    let (from, to) = (node_local(template_panel.grain.from)?, node_local(template_panel.grain.to)?);
    let stack = node_local(template_panel.grain.stack_node())?;
    let mut pts: TiVec<PanelVertex, DVec2> = uv.iter().map(|p| *p * MM_PER_M).collect();
    let rim = panel.rim();
    let outline_pts: Vec<DVec2> = rim.iter().map(|&l| pts[l]).collect();
    if signed_area(&outline_pts) < 0.0 {
        pts.iter_mut().for_each(|p| p.x = -p.x);
    }
    let grain = pts[to] - pts[from];
    if grain.length() <= f64::EPSILON {
        return Err(PieceError::DegenerateGrain { panel: name() });
    }
    // rotate grain onto −y: angle of grain to angle −π/2
    let rot = DVec2::from_angle(-std::f64::consts::FRAC_PI_2 - grain.y.atan2(grain.x));
    let origin = pts[stack];
    let pts: TiVec<PanelVertex, DVec2> = pts.iter().map(|&p| rot.rotate(p - origin)).collect();

    let sew_line: Vec<DVec2> = rim.iter().map(|&l| pts[l]).collect();
    // the template node at the k-th point of the sew line, if it is one
    let node_at = |k: usize| vertex_node(panel.global[rim[k]], t.nodes.len());
    // seam ends (fine vertices) touching this panel
    let seam_ends: HashSet<VertexId> = seams
        .iter()
        .filter(|s| s.panel_a == panel.index || s.panel_b == panel.index)
        .flat_map(|s| [s.chain.first().copied(), s.chain.last().copied()])
        .flatten()
        .collect();
    let n = sew_line.len();
    let cos_limit = opts.corner_angle_deg.to_radians().cos();
    let corners: Vec<usize> = (0..n)
        .filter(|&k| {
            if node_at(k).is_none() {
                return false;
            }
            if seam_ends.contains(&panel.global[rim[k]]) {
                return true;
            }
            let (a, b) = (sew_line[k] - sew_line[(k + n - 1) % n], sew_line[(k + 1) % n] - sew_line[k]);
            a.normalize_or_zero().dot(b.normalize_or_zero()) < cos_limit
        })
        .collect();
    let allowance = opts.seam_allowance_mm;
    let cut_line = untangle(offset_polygon(&sew_line, allowance, opts.miter_limit));

    // labels: the node's feature point, with the node id where a panel repeats it
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    for k in 0..n {
        if let Some(node) = node_at(k).and_then(|i| t.nodes.get(i as usize)) {
            *count.entry(node.point.as_str()).or_default() += 1;
        }
    }
    let label = |node: u32| {
        let p = t.nodes[node as usize].point.as_str();
        if count.get(p).copied().unwrap_or(0) > 1 {
            format!("{p}#{node}")
        } else {
            p.to_string()
        }
    };
    let mut notches = Vec::new();
    // grade points: every template node on the sew line (the same set in every size,
    // whatever the local turning angle), then the notches
    let mut seen = HashSet::new();
    let mut grade_points: Vec<GradePoint> = (0..n)
        .filter_map(|k| node_at(k).filter(|&node| seen.insert(node)).map(|node| (k, node)))
        .map(|(k, node)| GradePoint { node, label: label(node), at: sew_line[k], kind: GradePointKind::Corner })
        .collect();
    for notch in &t.notches {
        let Some(k) = (0..n).find(|&k| node_at(k) == Some(notch.node)) else { continue };
        let outward = vertex_normal(&sew_line, k);
        let at = sew_line[k];
        notches.push(PieceNotch { name: notch.name.clone(), at, outward, on_cut_line: at + outward * allowance });
        grade_points.push(GradePoint { node: notch.node, label: label(notch.node), at, kind: GradePointKind::Notch });
    }
    let mut internal_lines = internal_lines(t, panel, lineage, &pts);
    for d in &panel.darts {
        // the dart's legs, straight (opening → apex → opening), or as flattened where a
        // straight leg would leave the piece (a dart from a concave seam)
        let (Some(&mouth_a), Some(&apex), Some(&mouth_b)) = (d.a.first(), d.a.last(), d.b.first()) else { continue };
        let straight = vec![pts[mouth_a], pts[apex], pts[mouth_b]];
        let leaves = straight.windows(2).any(|leg| segment_crosses_polygon(leg[0], leg[1], &sew_line));
        let points =
            if leaves { d.a.iter().chain(d.b.iter().rev().skip(1)).map(|&l| pts[l]).collect() } else { straight };
        internal_lines.push(InternalLine { name: d.name.clone(), points });
    }
    let grain_len = grain.length();
    let piece = PatternPiece {
        name: panel.name.clone(),
        size: size.to_string(),
        quantity: template_panel.quantity,
        cut_pair: false,
        sew_line,
        corners,
        cut_line,
        seam_allowance_mm: allowance,
        notches,
        grain: [pts[from], pts[from] + DVec2::new(0.0, -grain_len)],
        internal_lines,
        grade_points,
        stack_point: DVec2::ZERO,
    };
    Ok(PlacedPanel { piece, uv_mm: pts })
}

/// The girths whose lines are drawn inside a piece (module docs).
pub use crate::body::vocab::GIRTH_CURVES;

/// Interior girth lines of the panel (module docs), merged into polylines.
fn internal_lines(
    t: &Template,
    panel: &Panel,
    lineage: &Lineage,
    pts: &TiSlice<PanelVertex, DVec2>,
) -> Vec<InternalLine> {
    let on_outline: HashSet<PanelVertex> = panel.outline.iter().copied().collect();
    // the girth both nodes of an edge lie on, if any (module docs)
    let girth = |e: &crate::template::format::Edge| -> Option<CurveId> {
        let (na, nb) = (&t.nodes[e.start as usize], &t.nodes[e.end as usize]);
        let level = |n: &crate::template::format::Node| n.offset[1].abs() <= RING_PLANE_TOLERANCE_M;
        let curves = |p: crate::body::vocab::PointId| {
            let d = point_def(p);
            [d.f1, d.f2]
        };
        (level(na) && level(nb)).then_some(())?;
        GIRTH_CURVES.iter().copied().find(|c| curves(na.point).contains(c) && curves(nb.point).contains(c))
    };
    let side = |s: &'static str| s.strip_suffix("_left").or_else(|| s.strip_suffix("_right")).unwrap_or(s);
    let local_chain = |a: u32, b: u32| -> Option<Vec<PanelVertex>> {
        lineage.chain(node_vertex(a), node_vertex(b))?.iter().map(|&g| panel.local(g)).collect()
    };
    // per girth: the fine chains of its interior edges
    let mut lines: Vec<(String, Vec<PanelVertex>)> = Vec::new();
    for e in &t.edges {
        let (Some(a), Some(b)) = (panel.local(node_vertex(e.start)), panel.local(node_vertex(e.end))) else {
            continue;
        };
        let Some(curve) = girth(e) else { continue };
        if on_outline.contains(&a) && on_outline.contains(&b) {
            continue;
        }
        let Some(chain) = local_chain(e.start, e.end) else { continue };
        lines.push((format!("{}_line", side(curve.as_str())), chain));
    }
    // a ring that closes through the crotch node (the thigh, `template::girth::ring_loop`):
    // its line runs on to the crotch on the outline
    let crotch: Vec<u32> = (0..t.nodes.len() as u32)
        .filter(|&n| {
            t.nodes[n as usize].point == PointId::Crotch
                && panel.local(node_vertex(n)).is_some_and(|l| on_outline.contains(&l))
        })
        .collect();
    let ends_inside = |l: PanelVertex| !on_outline.contains(&l);
    // only an open ring closes through the crotch: a node with one girth edge
    // (the thigh's ends), not a closed ring's node with a free edge to a
    // node that happens to be tied to the crotch (an authored skirt's hem)
    let mut girth_degree: HashMap<u32, usize> = HashMap::new();
    for e in t.edges.iter().filter(|e| girth(e).is_some()) {
        *girth_degree.entry(e.start).or_default() += 1;
        *girth_degree.entry(e.end).or_default() += 1;
    }
    let mut closures = Vec::new();
    for (name, chain) in &lines {
        for &end in [chain[0], chain[chain.len() - 1]].iter().filter(|&&l| ends_inside(l)) {
            let Some(node) = vertex_node(panel.global[end], t.nodes.len()) else { continue };
            if girth_degree.get(&node).copied().unwrap_or(0) != 1 {
                continue;
            }
            for e in t.edges.iter().filter(|e| !e.profile.is_empty()) {
                let other = if e.start == node {
                    e.end
                } else if e.end == node {
                    e.start
                } else {
                    continue;
                };
                if crotch.contains(&other) && t.nodes[node as usize].point != PointId::Crotch {
                    if let Some(c) = local_chain(node, other) {
                        closures.push((name.clone(), c));
                    }
                }
            }
        }
    }
    lines.extend(closures);
    // chains of one girth joined end to end until none shares an end with another
    let mut merged: Vec<(String, Vec<PanelVertex>)> = Vec::new();
    for (name, chain) in lines {
        merged.push((name, chain));
        loop {
            let last = merged.len() - 1;
            let joined = (0..last).find_map(|i| {
                let (a, b) = (&merged[i].1, &merged[last].1);
                (merged[i].0 == merged[last].0).then_some(())?;
                let (a0, a1, b0, b1) = (a[0], a[a.len() - 1], b[0], b[b.len() - 1]);
                let line = if a1 == b0 {
                    a.iter().chain(&b[1..]).copied().collect()
                } else if a1 == b1 {
                    a.iter().chain(b.iter().rev().skip(1)).copied().collect()
                } else if a0 == b1 {
                    b.iter().chain(&a[1..]).copied().collect()
                } else if a0 == b0 {
                    b.iter().rev().chain(&a[1..]).copied().collect()
                } else {
                    return None;
                };
                Some((i, line))
            });
            let Some((i, line)) = joined else { break };
            let (name, _) = merged.remove(last);
            merged.remove(i);
            merged.push((name, line));
        }
    }
    let lines = merged;
    lines.into_iter().map(|(name, ids)| InternalLine { name, points: ids.iter().map(|&l| pts[l]).collect() }).collect()
}

/// Signed area of a closed polygon (positive counter-clockwise).
pub fn signed_area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0..n).map(|i| poly[i].perp_dot(poly[(i + 1) % n])).sum::<f64>() / 2.0
}

/// Unit outward normal of the counter-clockwise polygon's vertex `k`: the
/// normalised sum of its two edges' outward normals.
fn vertex_normal(poly: &[DVec2], k: usize) -> DVec2 {
    let n = poly.len();
    let edge_normal = |a: DVec2, b: DVec2| {
        let d = (b - a).normalize_or_zero();
        DVec2::new(d.y, -d.x)
    };
    let m = edge_normal(poly[(k + n - 1) % n], poly[k]) + edge_normal(poly[k], poly[(k + 1) % n]);
    m.normalize_or_zero()
}

/// The counter-clockwise polygon offset outwards by `d` with mitred corners,
/// bevelled where the mitre would reach beyond `miter_limit × d` (module docs).
pub fn offset_polygon(poly: &[DVec2], d: f64, miter_limit: f64) -> Vec<DVec2> {
    let n = poly.len();
    if n < 3 || d == 0.0 {
        return poly.to_vec();
    }
    let normal = |i: usize| {
        let e = (poly[(i + 1) % n] - poly[i]).normalize_or_zero();
        DVec2::new(e.y, -e.x)
    };
    let mut out = Vec::with_capacity(n + 8);
    for (k, &p) in poly.iter().enumerate() {
        let (n0, n1) = (normal((k + n - 1) % n), normal(k));
        let bis = n0 + n1;
        let denom = 1.0 + n0.dot(n1);
        // mitre point: p + d (n0 + n1) / (1 + n0·n1); its distance is d·√(2/(1+cos θ))
        if denom > f64::EPSILON && (2.0 / denom).sqrt() <= miter_limit {
            out.push(p + bis * (d / denom));
        } else {
            out.push(p + n0 * d);
            out.push(p + n1 * d);
        }
    }
    out
}

/// Removes the loops an offset makes where the sew line bends inwards more
/// tightly than the allowance (a concave curve of radius < `s`, a reflex
/// corner): at each crossing of two edges the polygon splits in two, and the
/// part with the larger counter-clockwise area is kept. Stops when no edges
/// cross (or after `n` cuts).
pub fn untangle(mut poly: Vec<DVec2>) -> Vec<DVec2> {
    for _ in 0..poly.len() {
        let n = poly.len();
        let mut cut = None;
        'find: for i in 0..n {
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue;
                }
                let (a, b, c, d) = (poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n]);
                if segments_intersect(a, b, c, d) {
                    cut = Some((i, j, crossing_point(a, b, c, d)));
                    break 'find;
                }
            }
        }
        let Some((i, j, x)) = cut else { break };
        // inner: x, i+1 ..= j; outer: 0 ..= i, x, j+1 .. n
        let inner: Vec<DVec2> = std::iter::once(x).chain(poly[i + 1..=j].iter().copied()).collect();
        let outer: Vec<DVec2> =
            poly[..=i].iter().copied().chain(std::iter::once(x)).chain(poly[j + 1..].iter().copied()).collect();
        poly = if signed_area(&inner) > signed_area(&outer) { inner } else { outer };
    }
    poly
}

/// Where the lines through `a b` and `c d` cross (the midpoint of `b c` if parallel).
fn crossing_point(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> DVec2 {
    let (r, s) = (b - a, d - c);
    let den = r.perp_dot(s);
    if den.abs() <= f64::EPSILON {
        return 0.5 * (b + c);
    }
    a + r * ((c - a).perp_dot(s) / den)
}

/// Length of an open polyline.
pub fn polyline_length(p: &[DVec2]) -> f64 {
    p.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// Length of an open 3D polyline.
pub fn polyline_length_3d(p: &[DVec3]) -> f64 {
    p.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// Largest distance of a polyline's points from the chord through its ends, mm
/// (seed 004's straightness of a key dimensional curve).
pub fn deviation_from_chord(p: &[DVec2]) -> f64 {
    let (Some(&a), Some(&b)) = (p.first(), p.last()) else { return 0.0 };
    let d = (b - a).normalize_or_zero();
    p.iter().map(|&q| (q - a).perp_dot(d).abs()).fold(0.0, f64::max)
}

/// Whether a closed polygon has two non-adjacent edges that intersect (or
/// touch). `O(n²)`.
pub fn self_intersects(poly: &[DVec2]) -> bool {
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            if segments_intersect(a, b, c, d) {
                return true;
            }
        }
    }
    false
}

/// Closed-segment intersection test by orientations.
fn segments_intersect(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        o(p, q, r) == 0.0 && r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    on(c, d, a) || on(c, d, b) || on(a, b, c) || on(a, b, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_of_a_square_is_mitred_and_a_notched_outline_untangles() {
        let sq = vec![DVec2::ZERO, DVec2::new(100.0, 0.0), DVec2::new(100.0, 100.0), DVec2::new(0.0, 100.0)];
        let off = offset_polygon(&sq, 10.0, 3.0);
        assert_eq!(
            off,
            vec![
                DVec2::new(-10.0, -10.0),
                DVec2::new(110.0, -10.0),
                DVec2::new(110.0, 110.0),
                DVec2::new(-10.0, 110.0)
            ]
        );
        assert!((signed_area(&off) - 120.0 * 120.0).abs() < 1e-9);
        // a slit 4 mm wide and 50 mm deep into the top edge: offsetting by 10 mm
        // folds the slit's walls over each other; untangling leaves a clean outline
        let slit = vec![
            DVec2::ZERO,
            DVec2::new(100.0, 0.0),
            DVec2::new(100.0, 100.0),
            DVec2::new(52.0, 100.0),
            DVec2::new(50.0, 50.0),
            DVec2::new(48.0, 100.0),
            DVec2::new(0.0, 100.0),
        ];
        let raw = offset_polygon(&slit, 10.0, 3.0);
        assert!(self_intersects(&raw));
        let clean = untangle(raw);
        assert!(!self_intersects(&clean));
        assert!(signed_area(&clean) > 100.0 * 100.0);
        assert!(
            !self_intersects(&sq)
                && self_intersects(&[DVec2::ZERO, DVec2::ONE, DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)])
        );
    }
}
