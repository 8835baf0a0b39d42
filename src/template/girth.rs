//! Girth rings: ease as the template declares it, on every body (issue #13,
//! item 2; `DESIGN.md` §9 "Ease as declared").
//!
//! A template declares an ease `e` for a girth (`ease_mm["hip"] = 40`). It
//! was authored by easing the reference body's girth outward by the radius
//! increase `r = e / 2π` that adds `e` to a convex loop's length: ring nodes
//! at `c(s_j) + r·u(s_j)` and ring edge profiles sampled along the eased
//! loop between them, with `c` the girth *bridged* as a tape bridges it (its
//! concavities filled to the convex hull in its plane) and `u` the outward
//! in-plane direction from the loop's centroid.
//!
//! Eq. (1) carries the nodes to a new body along their frames, but Eq. (5)
//! carries the profiles as an affine copy of the reference body's; between
//! two nodes the new body's girth may bulge more (the profile cuts in, and
//! is then pushed out: ease grows) or less (a gap: ease grows). So, after
//! Eq. (5), [`refit_rings`] samples every *ring edge* again along the new
//! body's eased girth, exactly as authoring did on the reference body:
//!
//! ```text
//! Q_k = ĉ(s_a + (k/(n−1))·Δs) + r·û(·),   k = 0…n−1
//! Q_k += (1 − k/(n−1))·(p_a − Q_0) + (k/(n−1))·(p_b − Q_{n−1})      (ends on the decoded nodes)
//! ```
//!
//! with `s_a`, `s_b` the arc parameters of the two nodes' feature points on
//! the new girth `ĉ`, `Δs` the forward arc between them, `n` the profile's
//! point count and `p_a`, `p_b` the nodes as decoded. On the reference body
//! this reproduces the authored profiles, so encode → decode stays exact.
//!
//! **Ring edges** of a girth `g` are the template edges with a profile whose
//! two nodes are tied to feature points on `g`'s curve (one of the point's
//! two curves) and lie within [`RING_PLANE_TOLERANCE_M`] of its plane, and
//! neither of which a hang moved (a hung ring is shaped by its hang: the
//! report states the ease it gives, [`ring_tape`]).
//!
//! No failure modes beyond a profile that cannot be built
//! ([`ProfileError`], with the edge).

use glam::{DVec2, DVec3};

use crate::body::feature::FeatureBody;
use crate::body::vocab::{point_def, CurveId};
use crate::geom::plane::Plane;
use crate::geom::polyline::{convex_hull_2d, tape_length, Polyline};
use crate::template::codec::CoarseMesh;
use crate::template::format::Template;
use crate::template::profile::{Profile, ProfileError};

/// How far from a girth's plane a ring node may lie, m (ring nodes are eased
/// within the plane; a hem tied to the same points hangs decimetres below).
pub const RING_PLANE_TOLERANCE_M: f64 = 0.03;

/// The body curves an `ease_mm` entry names: one for a torso girth, both
/// legs' for a leg girth; none for entries that are not girths.
pub fn ring_curves(name: &str) -> &'static [CurveId] {
    match name {
        "neck_base" => &[CurveId::NeckBase],
        "chest" => &[CurveId::Chest],
        "bust" => &[CurveId::Bust],
        "underbust" => &[CurveId::Underbust],
        "waist" => &[CurveId::Waist],
        "hip" => &[CurveId::Hip],
        "thigh" => &[CurveId::ThighLeft, CurveId::ThighRight],
        "knee" => &[CurveId::KneeLeft, CurveId::KneeRight],
        _ => &[],
    }
}

/// The plane a girth lies in: its section plane, else its best fit.
pub fn girth_plane(body: &FeatureBody, curve: CurveId) -> Option<Plane> {
    let c = body.curves.get(&curve)?;
    c.plane.or_else(|| Plane::fit(&c.polyline.points))
}

/// The girth with its concavities bridged, as a tape measure and cloth
/// bridge them: every point inside the convex hull of the girth projected
/// into `plane` is moved radially (from the centroid, within the plane) out
/// to the hull; its distance from the plane is kept.
pub fn bridged(loop_: &Polyline, plane: &Plane) -> Polyline {
    let c = loop_.centroid();
    let (u, v) = plane.basis();
    let n = plane.normal;
    let flat: Vec<DVec2> = loop_.points.iter().map(|p| DVec2::new((*p - c).dot(u), (*p - c).dot(v))).collect();
    let hull = convex_hull_2d(&flat);
    let m = hull.len();
    if m < 3 {
        return loop_.clone();
    }
    let points = loop_
        .points
        .iter()
        .zip(&flat)
        .map(|(p, q)| {
            let dir = q.normalize_or_zero();
            // the ray from the centroid through q leaves the hull at the largest t
            // with t·dir on an edge
            let mut reach = q.length();
            for i in 0..m {
                let (a, b) = (hull[i], hull[(i + 1) % m]);
                let e = b - a;
                let den = dir.perp_dot(e);
                if den.abs() <= f64::EPSILON {
                    continue;
                }
                let t = a.perp_dot(e) / den;
                let w = a.perp_dot(dir) / den;
                if t > 0.0 && (-1e-12..=1.0 + 1e-12).contains(&w) {
                    reach = reach.max(t);
                }
            }
            let out = dir * reach;
            c + u * out.x + v * out.y + n * (*p - c).dot(n)
        })
        .collect();
    Polyline::new(points, loop_.closed)
}

/// The point at arc parameter `s` of `loop_`, moved `radial` outward within
/// `plane` (away from the loop's centroid).
pub fn eased(loop_: &Polyline, s: f64, radial: f64, plane: &Plane) -> DVec3 {
    let p = loop_.point_at(s);
    let d = p - loop_.centroid();
    let out = (d - plane.normal * d.dot(plane.normal)).normalize_or_zero();
    p + out * radial
}

/// The ring edges of `curve` in `t` decoded at `positions` (module docs),
/// `hung` the nodes a hang moved.
pub fn ring_edges(t: &Template, body: &FeatureBody, positions: &[DVec3], curve: CurveId, hung: &[u32]) -> Vec<u32> {
    let Some(plane) = girth_plane(body, curve) else { return Vec::new() };
    let on_ring = |node: u32| -> bool {
        let Some(n) = t.nodes.get(node as usize) else { return false };
        let def = point_def(n.point);
        (def.f1 == curve || def.f2 == curve)
            && !hung.contains(&node)
            && positions.get(node as usize).is_some_and(|p| plane.signed_distance(*p).abs() <= RING_PLANE_TOLERANCE_M)
    };
    t.edges
        .iter()
        .enumerate()
        .filter(|(_, e)| !e.profile.is_empty() && on_ring(e.start) && on_ring(e.end))
        .map(|(i, _)| i as u32)
        .collect()
}

/// Samples every ring edge's profile again along the body's eased girth
/// (module docs). `profiles` are indexed by template edge and oriented from
/// the edge's start node; `hung` are the nodes a hang moved. Returns how many
/// profiles were refitted.
///
/// # Errors
/// `(edge, ProfileError)` for a profile that cannot be built.
pub fn refit_rings(
    t: &Template,
    body: &FeatureBody,
    positions: &[DVec3],
    profiles: &mut [Option<Profile>],
    hung: &[u32],
) -> Result<usize, (u32, ProfileError)> {
    let mut refitted = 0;
    for (name, &ease) in &t.ease_mm {
        let radial = ease * 1e-3 / std::f64::consts::TAU;
        for &curve in ring_curves(name) {
            let (Some(c), Some(plane)) = (body.curves.get(&curve), girth_plane(body, curve)) else { continue };
            let loop_ = bridged(&c.polyline, &plane);
            let total = loop_.length();
            if total <= 0.0 {
                continue;
            }
            for edge in ring_edges(t, body, positions, curve, hung) {
                let e = &t.edges[edge as usize];
                let Some(old) = profiles.get(edge as usize).and_then(|p| p.as_ref()) else { continue };
                let n = old.points().len().max(2);
                let param = |node: u32| -> Option<f64> {
                    let q = body.points.get(&t.nodes[node as usize].point)?.position;
                    Some(loop_.closest(q)?.s)
                };
                let (Some(sa), Some(sb)) = (param(e.start), param(e.end)) else { continue };
                // the ring runs the shorter way round between neighbouring nodes
                let fwd = (sb - sa).rem_euclid(total);
                let ds = if fwd <= 0.5 * total { fwd } else { fwd - total };
                let mut pts: Vec<DVec3> =
                    (0..n).map(|k| eased(&loop_, sa + ds * k as f64 / (n - 1) as f64, radial, &plane)).collect();
                let (pa, pb) = (positions[e.start as usize], positions[e.end as usize]);
                let (shift_a, shift_b) = (pa - pts[0], pb - pts[n - 1]);
                for (k, p) in pts.iter_mut().enumerate() {
                    let w = k as f64 / (n - 1) as f64;
                    *p += shift_a * (1.0 - w) + shift_b * w;
                }
                pts[0] = pa;
                pts[n - 1] = pb;
                profiles[edge as usize] = Some(Profile::new(pts).map_err(|err| (edge, err))?);
                refitted += 1;
            }
        }
    }
    Ok(refitted)
}

/// Tape length of the ring of `curve` (its ring edges' profiles, `hung`
/// nodes included) in the girth's plane, m; `None` without ring edges.
pub fn ring_tape(
    t: &Template,
    body: &FeatureBody,
    positions: &[DVec3],
    profiles: &[Option<Profile>],
    curve: CurveId,
) -> Option<f64> {
    let plane = girth_plane(body, curve)?;
    let points: Vec<DVec3> = ring_edges(t, body, positions, curve, &[])
        .iter()
        .filter_map(|&e| profiles.get(e as usize)?.as_ref())
        .flat_map(|p| p.points().to_vec())
        .collect();
    if points.len() < 3 {
        return None;
    }
    Some(tape_length(&[&Polyline::new(points, true)], &plane))
}

/// The ease each declared girth should have on `body` (mm, by `ease_mm`
/// name; the left leg for leg girths): the declared ease, or, where a hang
/// moved a node of the ring (a skirt falling straight from the waist past
/// the hip), the larger ease of the ring as decoded (`m`, before any
/// clearing), which the shape adds on purpose.
pub fn expected_ease(t: &Template, body: &FeatureBody, m: &CoarseMesh) -> std::collections::BTreeMap<String, f64> {
    let mut out = std::collections::BTreeMap::new();
    for (name, &declared) in &t.ease_mm {
        let Some(&curve) = ring_curves(name).first() else { continue };
        let mut expected = declared;
        let hung_here = !m.hung.is_empty()
            && ring_edges(t, body, &m.positions, curve, &[])
                .iter()
                .any(|&e| m.hung.contains(&t.edges[e as usize].start) || m.hung.contains(&t.edges[e as usize].end));
        if hung_here {
            let body_girth =
                body.curves.get(&curve).map(|c| crate::body::measure::girth_of(&c.polyline, c.plane.as_ref()));
            if let (Some(tape), Some(g)) = (ring_tape(t, body, &m.positions, &m.profiles, curve), body_girth) {
                expected = expected.max((tape - g) * 1e3);
            }
        }
        out.insert(name.clone(), expected);
    }
    out
}
