//! Girth rings: ease as the template declares it, on every body (issue #13,
//! item 2; `DESIGN.md` §9 "Ease as declared").
//!
//! A template declares an ease `e` for a girth (`ease_mm["hip"] = 40`). It
//! was authored by easing the reference body's girth outward by the offset
//! `r` that adds `e` to the girth's tape length ([`ring_radial`]; `e / 2π`
//! for a circle): ring nodes
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
//! the new girth `ĉ` (each shifted by its node's `ring_shift`, a fraction of
//! the girth's length: [`ring_param`]), `Δs` the forward arc between them,
//! `n` the profile's point count and `p_a`, `p_b` the nodes as decoded. On the reference body
//! this reproduces the authored profiles, so encode → decode stays exact.
//!
//! **Ring edges** of a girth `g` are the template edges with a profile whose
//! two nodes are tied to feature points on `g`'s curve (one of the point's
//! two curves) and lie within [`RING_PLANE_TOLERANCE_M`] of its plane as
//! placed (before the hangs). Where they form an open chain, the node with
//! profiled edges to both its ends closes the ring ([`ring_loop`]: the
//! trouser thigh ring runs through the crotch node). The offset `r` is the
//! one that gives at least the declared ease on the tape of the ring *as
//! its profiles sample it*, that node included ([`sampled_radial`]; the
//! arcs to it as decoding carries them, Eq. (5) copies onto the eased
//! nodes), and the girth itself the declared ease ([`ring_radial`]). A hung
//! node keeps its hang, and its arcs Eq. (5)'s copy unless that cuts into
//! the body ([`refit_rings`]); the report states the
//! ease the hang gives ([`expected_ease`]).
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
    Walk::new(loop_).eased(s, radial, plane)
}

/// Every vertex of `loop_` moved `radial` outward within `plane` ([`eased`]
/// at each vertex's arc parameter): the girth eased as decoding places its
/// ring ([`ring_radial`]'s trial rings).
pub fn eased_vertices(loop_: &Polyline, radial: f64, plane: &Plane) -> Vec<DVec3> {
    Walk::new(loop_).eased_vertices(radial, plane)
}

/// A loop ready for many [`eased`] points: its cumulative arc lengths,
/// centroid and length taken once (issue #15: [`sampled_radial`]'s
/// bisection re-took them for every point of every trial ring), the points
/// the same to the bit.
struct Walk<'a> {
    loop_: &'a Polyline,
    cum: Vec<f64>,
    centroid: DVec3,
    length: f64,
}

impl<'a> Walk<'a> {
    fn new(loop_: &'a Polyline) -> Self {
        Self { loop_, cum: loop_.cumulative(), centroid: loop_.centroid(), length: loop_.length() }
    }

    /// [`eased_vertices`].
    fn eased_vertices(&self, radial: f64, plane: &Plane) -> Vec<DVec3> {
        self.cum[..self.loop_.points.len()].iter().map(|&s| self.eased(s, radial, plane)).collect()
    }

    /// [`eased`].
    fn eased(&self, s: f64, radial: f64, plane: &Plane) -> DVec3 {
        let p = self.loop_.point_at_with(&self.cum, s);
        p + outward(plane, self.centroid, p) * radial
    }
}

/// The unit direction from `centre` to `p` within `plane` (the direction
/// [`eased`] moves a girth point out along); zero where `p` lies over the
/// centre.
pub fn outward(plane: &Plane, centre: DVec3, p: DVec3) -> DVec3 {
    let d = p - centre;
    (d - plane.normal * d.dot(plane.normal)).normalize_or_zero()
}

/// The ring edges of `curve` in `t` decoded at `positions` (module docs),
/// `hung` the nodes a hang moved ([`ring_nodes`]).
pub fn ring_edges(t: &Template, body: &FeatureBody, positions: &[DVec3], curve: CurveId, hung: &[u32]) -> Vec<u32> {
    edges_between(t, &ring_nodes(t, body, positions, curve, hung))
}

/// The profiled template edges with both nodes in `nodes`.
fn edges_between(t: &Template, nodes: &[u32]) -> Vec<u32> {
    t.edges
        .iter()
        .enumerate()
        .filter(|(_, e)| !e.profile.is_empty() && nodes.contains(&e.start) && nodes.contains(&e.end))
        .map(|(i, _)| i as u32)
        .collect()
}

/// A girth's ring in the template: its ring nodes, the template edges
/// around it, and the node it closes through, if any.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RingLoop {
    /// Ring nodes (tied to feature points on the curve, [`ring_nodes`]).
    pub nodes: Vec<u32>,
    /// Template edges around the ring: the ring edges, and the two edges to
    /// and from `through`.
    pub edges: Vec<u32>,
    /// A node not on the curve that closes the ring: the ring edges form an
    /// open chain whose two ends both have a profiled edge to it (the
    /// trouser thigh ring closes through the crotch node).
    pub through: Option<u32>,
}

/// The template edge between nodes `a` and `b` that carries a profile.
fn profiled_edge(t: &Template, a: u32, b: u32) -> Option<u32> {
    t.edges
        .iter()
        .position(|e| !e.profile.is_empty() && ((e.start == a && e.end == b) || (e.start == b && e.end == a)))
        .map(|i| i as u32)
}

/// The ring of `curve` in `t` decoded at `positions` ([`RingLoop`]),
/// `hung` the nodes a hang moved ([`ring_nodes`]). Where the ring edges form an open chain,
/// the node with profiled edges to both of its ends closes it (the one
/// nearest the girth's plane when several do).
pub fn ring_loop(t: &Template, body: &FeatureBody, positions: &[DVec3], curve: CurveId, hung: &[u32]) -> RingLoop {
    let nodes = ring_nodes(t, body, positions, curve, hung);
    let mut edges = edges_between(t, &nodes);
    let mut degree: std::collections::BTreeMap<u32, usize> = nodes.iter().map(|&n| (n, 0)).collect();
    for &e in &edges {
        let e = &t.edges[e as usize];
        for n in [e.start, e.end] {
            *degree.entry(n).or_default() += 1;
        }
    }
    let ends: Vec<u32> = degree.iter().filter(|(_, &d)| d == 1).map(|(&n, _)| n).collect();
    let mut through = None;
    if let ([a, b], Some(plane)) = (ends.as_slice(), girth_plane(body, curve)) {
        let off_plane = |x: u32| positions.get(x as usize).map_or(f64::INFINITY, |p| plane.signed_distance(*p).abs());
        through = (0..t.nodes.len() as u32)
            .filter(|x| !nodes.contains(x))
            .filter_map(|x| Some((x, profiled_edge(t, *a, x)?, profiled_edge(t, *b, x)?)))
            .min_by(|p, q| off_plane(p.0).total_cmp(&off_plane(q.0)));
    }
    if let Some((_, ea, eb)) = through {
        edges.extend([ea, eb]);
    }
    RingLoop { nodes, edges, through: through.map(|(x, _, _)| x) }
}

/// The forward arc length from `s0` to `s1` round a closed loop of length
/// `total`, or the backward one (negative) where that is shorter.
pub fn shorter_way(s0: f64, s1: f64, total: f64) -> f64 {
    let fwd = (s1 - s0).rem_euclid(total);
    if fwd <= 0.5 * total {
        fwd
    } else {
        fwd - total
    }
}

/// `n` points of `loop_` eased by `radial` within `plane` from arc
/// parameter `s0` over `ds` (signed), the ends bent onto `ends` where given
/// (a node off the loop: a linear blend along the arc,
/// `Q_j += (1 − w_j)·(e_0 − Q_0) + w_j·(e_1 − Q_{n−1})`, and the end points
/// set exactly).
pub fn eased_arc(
    loop_: &Polyline,
    plane: &Plane,
    s0: f64,
    ds: f64,
    n: usize,
    radial: f64,
    ends: (Option<DVec3>, Option<DVec3>),
) -> Vec<DVec3> {
    eased_arc_on(&Walk::new(loop_), plane, s0, ds, n, radial, ends)
}

/// [`eased_arc`] on a [`Walk`].
fn eased_arc_on(
    walk: &Walk<'_>,
    plane: &Plane,
    s0: f64,
    ds: f64,
    n: usize,
    radial: f64,
    ends: (Option<DVec3>, Option<DVec3>),
) -> Vec<DVec3> {
    let n = n.max(2);
    let mut pts: Vec<DVec3> = (0..n).map(|i| walk.eased(s0 + ds * i as f64 / (n - 1) as f64, radial, plane)).collect();
    let shift_a = ends.0.map_or(DVec3::ZERO, |e| e - pts[0]);
    let shift_b = ends.1.map_or(DVec3::ZERO, |e| e - pts[n - 1]);
    if ends.0.is_some() || ends.1.is_some() {
        for (i, p) in pts.iter_mut().enumerate() {
            let w = i as f64 / (n - 1) as f64;
            *p += shift_a * (1.0 - w) + shift_b * w;
        }
    }
    // exactly on the given ends (the blend is exact only up to rounding)
    if let Some(e) = ends.0 {
        pts[0] = e;
    }
    if let Some(e) = ends.1 {
        pts[n - 1] = e;
    }
    pts
}

/// The arcs of a ring on `loop_` eased by `radial` within `plane`: arc `k`
/// runs the shorter way round the loop from `params[k]` to `params[k + 1]`
/// (cyclically), sampled at `counts[k]` points, its ends bent onto
/// `ends[k]` and `ends[k + 1]` where given ([`eased_arc`]). Where
/// `copies[k]` is given (an arc to a node off the girth, which decoding
/// carries by Eq. (5)), arc `k` is that profile relocated onto its two
/// ends instead ([`Profile::relocated`]: the ends on the loop at `radial`,
/// or `ends`), as decoding builds it.
pub fn ring_arcs(
    loop_: &Polyline,
    plane: &Plane,
    params: &[f64],
    ends: &[Option<DVec3>],
    counts: &[usize],
    copies: &[Option<Profile>],
    radial: f64,
) -> Vec<Vec<DVec3>> {
    ring_arcs_on(&Walk::new(loop_), plane, params, ends, counts, copies, radial)
}

/// [`ring_arcs`] on a [`Walk`].
fn ring_arcs_on(
    walk: &Walk<'_>,
    plane: &Plane,
    params: &[f64],
    ends: &[Option<DVec3>],
    counts: &[usize],
    copies: &[Option<Profile>],
    radial: f64,
) -> Vec<Vec<DVec3>> {
    let total = walk.length;
    let m = params.len();
    let end = |k: usize| ends.get(k).copied().flatten();
    let at = |k: usize| end(k).unwrap_or_else(|| walk.eased(params[k], radial, plane));
    (0..m)
        .map(|k| {
            let j = (k + 1) % m;
            let n = counts.get(k).copied().unwrap_or(2);
            if let Some(Ok(copy)) = copies.get(k).and_then(|c| c.as_ref()).map(|c| c.relocated(at(k), at(j))) {
                return copy.points().to_vec();
            }
            eased_arc_on(walk, plane, params[k], shorter_way(params[k], params[j], total), n, radial, (end(k), end(j)))
        })
        .collect()
}

/// Bisection steps of [`sampled_radial`] (each halves the bracket; 40 take
/// a metre to below a nanometre).
const RADIAL_BISECTIONS: usize = 40;

/// The outward offset `r` whose ring, *as its profiles sample it*, adds
/// exactly `ease` (m) to the bridged girth's tape: the ring of
/// [`ring_arcs`]`(loop_, plane, params, ends, counts, copies, r)`, its tape taken
/// over all its points. The garment is the polygon through those samples,
/// not the smooth eased loop, whose hull is longer: with 7 points per arc
/// the ring fell 1–5 mm short of the declared ease ([`ring_radial`] on the
/// whole loop; a chest over the shoulder blades lost 5.4 mm of 60). A node
/// off the girth (`ends`: a crotch node between the thighs) may already add
/// more than `ease`: then `r = 0`, and the ring's ease is what the node
/// gives ([`expected_ease`]). `copies` as in [`ring_arcs`]: the arcs to
/// that node as decoding carries them. Bisection on `r`, the tape being
/// non-decreasing in `r`.
pub fn sampled_radial(
    loop_: &Polyline,
    plane: &Plane,
    ease: f64,
    params: &[f64],
    ends: &[Option<DVec3>],
    counts: &[usize],
    copies: &[Option<Profile>],
) -> f64 {
    let base = tape_length(&[loop_], plane);
    let walk = Walk::new(loop_);
    let gain = |r: f64| {
        let pts: Vec<DVec3> = ring_arcs_on(&walk, plane, params, ends, counts, copies, r).concat();
        tape_length(&[&Polyline::new(pts, true)], plane) - base
    };
    if ease.is_nan() || ease <= 0.0 || gain(0.0) >= ease {
        return 0.0;
    }
    let mut hi = ease / std::f64::consts::TAU;
    while gain(hi) < ease && hi < 1.0 {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..RADIAL_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if gain(mid) < ease {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Iterations of [`ring_radial`]'s secant refinement.
const RADIAL_ITERATIONS: usize = 4;

/// The outward offset `r` whose eased ring adds exactly `ease` (m) to the
/// tape length of the bridged girth `loop_` in `plane`. `e / 2π` does that
/// for a circle only: moving points radially from the centroid adds
/// `r ∮ sin φ dθ ≤ 2πr` (φ the angle between the loop's tangent and the
/// radius), so on an oval girth the ease would fall short (by 7–10 mm of
/// 50–80 over the population of issue #13). Starting from `e / 2π`, the
/// offset is scaled by `e / (tape(r) − tape(0))` a few times (tape length is
/// nearly linear in `r`). Returns `e / 2π` for a degenerate loop.
pub fn ring_radial(loop_: &Polyline, plane: &Plane, ease: f64) -> f64 {
    let mut r = ease / std::f64::consts::TAU;
    let base = tape_length(&[loop_], plane);
    let walk = Walk::new(loop_);
    for _ in 0..RADIAL_ITERATIONS {
        let ring = Polyline::new(walk.eased_vertices(r, plane), true);
        let gained = tape_length(&[&ring], plane) - base;
        if !(gained.is_finite() && gained.abs() > f64::EPSILON) || ease == 0.0 {
            break;
        }
        r *= ease / gained;
    }
    r
}

/// One girth ring of a template on a body, eased: its curve, the bridged
/// loop, its plane and the offset `r`. `r` is the larger
/// of the offset that eases the girth itself by the declared ease
/// ([`ring_radial`]) and the one that gives the ring *as sampled* the
/// declared ease ([`sampled_radial`]; where the ring edges close): a ring
/// through a crotch node between slim thighs keeps the thigh's own ease
/// and the node adds more on purpose (solving the whole ring down to the
/// declared ease tightened the leg, and 4 of 120 trouser pieces went over
/// the 3 % strain bar), a ring whose node sits inside the eased girth
/// (heavy thighs that touch) is eased further to make up for it.
struct EasedGirth {
    curve: CurveId,
    loop_: Polyline,
    plane: Plane,
    radial: f64,
}

/// A closed ring in the template's order around it.
struct RingOrder {
    /// `(node, arc parameter on the loop)` around the ring, from the node
    /// off the girth where it closes through one.
    order: Vec<(u32, f64)>,
    /// Per arc `k` (from `order[k]` to `order[k + 1]`): the template edge.
    edges: Vec<u32>,
    /// The node off the girth it closes through ([`RingLoop::through`]).
    through: Option<u32>,
}

impl RingOrder {
    fn params(&self) -> Vec<f64> {
        self.order.iter().map(|o| o.1).collect()
    }

    /// The node off the girth as an arc end, the others on the loop.
    fn ends(&self, positions: &[DVec3]) -> Vec<Option<DVec3>> {
        self.order.iter().map(|o| (Some(o.0) == self.through).then(|| positions[o.0 as usize])).collect()
    }

    /// Profile points per arc.
    fn counts(&self, t: &Template) -> Vec<usize> {
        self.edges.iter().map(|&e| t.edges[e as usize].profile.len()).collect()
    }

    /// Per arc, the template's profile oriented along the ring where the
    /// arc runs to or from the node off the girth (decoding carries those
    /// by Eq. (5), [`refit_rings`]), else `None`.
    fn copies(&self, t: &Template) -> Vec<Option<Profile>> {
        let m = self.order.len();
        (0..m)
            .map(|k| {
                let (a, b) = (self.order[k].0, self.order[(k + 1) % m].0);
                if self.through.is_none() || (Some(a) != self.through && Some(b) != self.through) {
                    return None;
                }
                let e = &t.edges[self.edges[k] as usize];
                let mut pts: Vec<DVec3> = e.profile.iter().map(|&p| DVec3::from_array(p)).collect();
                if e.start != a {
                    pts.reverse();
                }
                Profile::new(pts).ok()
            })
            .collect()
    }
}

/// The ring of `curve` ([`ring_loop`], no node hung) in the template's
/// order, when its edges close: from the node off the girth (or the first
/// ring node) along the ring edges and back; ring nodes at their feature
/// points' arc parameters on `loop_`, the node off the girth at the
/// parameter nearest its decoded position.
fn ring_order(
    t: &Template,
    body: &FeatureBody,
    positions: &[DVec3],
    curve: CurveId,
    loop_: &Polyline,
) -> Option<RingOrder> {
    let ring = ring_loop(t, body, positions, curve, &[]);
    let first = ring.through.or(ring.nodes.first().copied())?;
    let mut walk = vec![first];
    let mut edges = Vec::with_capacity(ring.edges.len());
    while edges.len() < ring.edges.len() {
        let at = *walk.last()?;
        let (e, next) = ring.edges.iter().filter(|e| !edges.contains(*e)).find_map(|&e| {
            let d = &t.edges[e as usize];
            (d.start == at).then_some((e, d.end)).or((d.end == at).then_some((e, d.start)))
        })?;
        edges.push(e);
        walk.push(next);
    }
    if walk.pop() != Some(first) || walk.len() < 3 {
        return None;
    }
    let mut order = Vec::with_capacity(walk.len());
    for &n in &walk {
        let s = if Some(n) == ring.through {
            loop_.closest(*positions.get(n as usize)?)?.s
        } else {
            ring_param(t, body, n, loop_)?
        };
        order.push((n, s));
    }
    Some(RingOrder { order, edges, through: ring.through })
}

/// Every girth ring `t` declares, on `body` decoded at `positions`
/// ([`EasedGirth`]).
fn eased_girths(t: &Template, body: &FeatureBody, positions: &[DVec3]) -> Vec<EasedGirth> {
    let mut out = Vec::new();
    for (name, &ease) in &t.ease_mm {
        for &curve in ring_curves(name) {
            let (Some(c), Some(plane)) = (body.curves.get(&curve), girth_plane(body, curve)) else { continue };
            let loop_ = bridged(&c.polyline, &plane);
            let ring = ring_order(t, body, positions, curve, &loop_);
            let radial = match &ring {
                None => ring_radial(&loop_, &plane, ease * 1e-3),
                Some(o) => sampled_radial(
                    &loop_,
                    &plane,
                    ease * 1e-3,
                    &o.params(),
                    &o.ends(positions),
                    &o.counts(t),
                    &o.copies(t),
                )
                .max(ring_radial(&loop_, &plane, ease * 1e-3)),
            };
            out.push(EasedGirth { curve, loop_, plane, radial });
        }
    }
    out
}

/// The ring nodes of `curve` (module docs): nodes tied to feature points on
/// the curve, within [`RING_PLANE_TOLERANCE_M`] of its plane, or `hung` (a
/// hang moved them along a line that may leave the plane: they stay on the
/// ring).
pub fn ring_nodes(t: &Template, body: &FeatureBody, positions: &[DVec3], curve: CurveId, hung: &[u32]) -> Vec<u32> {
    let Some(plane) = girth_plane(body, curve) else { return Vec::new() };
    (0..t.nodes.len() as u32)
        .filter(|&node| {
            let def = point_def(t.nodes[node as usize].point);
            (def.f1 == curve || def.f2 == curve)
                && (hung.contains(&node)
                    || positions
                        .get(node as usize)
                        .is_some_and(|p| plane.signed_distance(*p).abs() <= RING_PLANE_TOLERANCE_M))
        })
        .collect()
}

/// A ring node's arc parameter on the bridged girth `loop_`: its feature
/// point's, `s(q_j)`, shifted by its [`super::format::Node::ring_shift`]
/// `σ`: `s(q_j) + σ·L` modulo `L`, the loop's length. `None` where the body
/// lacks the point or the loop is degenerate.
pub fn ring_param(t: &Template, body: &FeatureBody, node: u32, loop_: &Polyline) -> Option<f64> {
    let n = t.nodes.get(node as usize)?;
    let s = loop_.closest(body.points.get(&n.point)?.position)?.s;
    match n.ring_shift {
        Some(shift) if shift != 0.0 => {
            let total = loop_.length();
            (total > 0.0).then(|| (s + shift * total).rem_euclid(total))
        }
        _ => Some(s),
    }
}

/// Places every ring node on the body's eased girth at its feature point
/// (shifted along it by its `ring_shift`, [`ring_param`]), `ĉ(s_j) + r·û`,
/// as authoring placed it on the reference body (where Eq. (1) gives the
/// same point): Eq. (1)'s fixed offset along a frame that tilts with the
/// body (a noisy scan, a full bust) would carry the node off the girth's
/// plane and its ease. Returns how many nodes moved.
pub fn place_ring_nodes(t: &Template, body: &FeatureBody, positions: &mut [DVec3]) -> usize {
    let mut moved = 0;
    for g in eased_girths(t, body, positions) {
        for node in ring_nodes(t, body, positions, g.curve, &[]) {
            let Some(s) = ring_param(t, body, node, &g.loop_) else { continue };
            positions[node as usize] = eased(&g.loop_, s, g.radial, &g.plane);
            moved += 1;
        }
    }
    moved
}

/// Samples every ring edge's profile again along the body's eased girth
/// (module docs). `placed` are the node positions before the hangs (which
/// nodes are ring nodes, as [`place_ring_nodes`] saw them), `positions` after
/// them, `hung` the nodes a hang moved; `profiles` are indexed by template
/// edge and oriented from the edge's start node. Each arc between two ring
/// nodes runs along the eased girth, its ends on the decoded nodes. The
/// arcs to a node the ring closes through ([`RingLoop::through`]) keep
/// Eq. (5)'s copy (the solved offset counts them as such,
/// [`sampled_radial`]): bending them along the new body's girth onto the
/// crotch node put 2–4 of 120 trouser pieces over the 3 % strain bar (a
/// kink where the arc turns up to the crotch). An arc to a hung node keeps
/// Eq. (5)'s copy, unless the copy cuts into the body: then each of its
/// points is replaced by the eased arc's (its end bent onto the hung node)
/// where that runs further out from the girth's centre in its plane.
/// Bending every such arc onto hung knee nodes left crotch triangles
/// through the body on three heavy men and on pop39's scan, and never
/// bending them let a slim woman's belly take 6 mm of the skirt's 40 mm hip
/// ease (the copy cut 10 mm into the girth; pop00).
/// Returns how many profiles were refitted.
///
/// # Errors
/// `(edge, ProfileError)` for a profile that cannot be built.
pub fn refit_rings(
    t: &Template,
    body: &FeatureBody,
    placed: &[DVec3],
    positions: &[DVec3],
    profiles: &mut [Option<Profile>],
    hung: &[u32],
) -> Result<usize, (u32, ProfileError)> {
    let mut refitted = 0;
    // built on the first hung arc: its copy's points are tested against the body
    let mut index: Option<crate::geom::query::SphereIndex> = None;
    for g in eased_girths(t, body, placed) {
        let (loop_, plane, radial) = (&g.loop_, &g.plane, g.radial);
        let total = loop_.length();
        if total <= 0.0 {
            continue;
        }
        let centre = plane.project(loop_.points.iter().copied().sum::<DVec3>() / loop_.points.len().max(1) as f64);
        // mean in-plane distance of an arc's points from the girth's centre
        let reach = |pts: &[DVec3]| {
            pts.iter().map(|&p| plane.project(p).distance(centre)).sum::<f64>() / pts.len().max(1) as f64
        };
        for edge in ring_edges(t, body, placed, g.curve, &[]) {
            let e = &t.edges[edge as usize];
            let hung_arc = hung.contains(&e.start) || hung.contains(&e.end);
            let Some(old) = profiles.get(edge as usize).and_then(|p| p.as_ref()) else { continue };
            let n = old.points().len();
            let param = |node: u32| ring_param(t, body, node, loop_);
            let (Some(sa), Some(sb)) = (param(e.start), param(e.end)) else { continue };
            // the ring runs the shorter way round between neighbouring nodes
            let ends = (Some(positions[e.start as usize]), Some(positions[e.end as usize]));
            let mut pts = eased_arc(loop_, plane, sa, shorter_way(sa, sb, total), n, radial, ends);
            // an arc to a hung node: each point of Eq. (5)'s copy, or of the eased arc where that
            // runs further out (a copy that cuts into this body's girth takes its ease away)
            if hung_arc {
                // only a copy that cuts into the body is bent (bending the others, hung knees,
                // left crotch triangles through the body)
                let index = index.get_or_insert_with(|| crate::geom::query::SphereIndex::new(&body.mesh));
                let cuts_in = old.points().iter().any(|&q| {
                    let c = index.closest_point(&body.mesh, q);
                    (q - c.point).dot(body.mesh.face_area_vector(c.face)) < 0.0
                });
                if !cuts_in || old.points().len() != pts.len() {
                    continue;
                }
                let mut any = false;
                for (p, &q) in pts.iter_mut().zip(old.points()) {
                    if reach(&[q]) >= reach(&[*p]) {
                        *p = q;
                    } else {
                        any = true;
                    }
                }
                if !any {
                    continue;
                }
            }
            profiles[edge as usize] = Some(Profile::new(pts).map_err(|err| (edge, err))?);
            refitted += 1;
        }
    }
    Ok(refitted)
}

/// Tape length of the ring of `curve` ([`ring_loop`]: its ring edges' and
/// closing edges' profiles, the `hung` nodes' included) in the girth's
/// plane, m; `None` without ring edges.
pub fn ring_tape(
    t: &Template,
    body: &FeatureBody,
    positions: &[DVec3],
    profiles: &[Option<Profile>],
    curve: CurveId,
    hung: &[u32],
) -> Option<f64> {
    let plane = girth_plane(body, curve)?;
    let points: Vec<DVec3> = ring_loop(t, body, positions, curve, hung)
        .edges
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
/// name; the left leg for leg girths): the declared ease, or, where the
/// template's shape rules add ease on purpose, the larger ease of the ring
/// as decoded and cleared of the body (`m` after
/// [`crate::refine::clear::clear_coarse`]: a profile point that decoding
/// left inside the body is moved out, and the ring is that much longer on
/// purpose): a hang moved a node of the ring
/// (a skirt falling straight from the waist past the hip), or the ring
/// closes through a node off its girth that alone adds more than declared
/// (a crotch node far from the thighs; Eq. (5)'s arcs to it cut into a
/// full inner thigh and are moved out: 7–9 mm more on pop05 and pop29).
pub fn expected_ease(t: &Template, body: &FeatureBody, m: &CoarseMesh) -> std::collections::BTreeMap<String, f64> {
    let mut out = std::collections::BTreeMap::new();
    for (name, &declared) in &t.ease_mm {
        let Some(&curve) = ring_curves(name).first() else { continue };
        let mut expected = declared;
        let ring = ring_loop(t, body, &m.positions, curve, &m.hung);
        let hung_here = ring.through.is_some()
            || ring
                .edges
                .iter()
                .any(|&e| m.hung.contains(&t.edges[e as usize].start) || m.hung.contains(&t.edges[e as usize].end));
        if hung_here {
            let body_girth =
                body.curves.get(&curve).map(|c| crate::body::measure::girth_of(&c.polyline, c.plane.as_ref()));
            if let (Some(tape), Some(g)) = (ring_tape(t, body, &m.positions, &m.profiles, curve, &m.hung), body_girth) {
                expected = expected.max((tape - g) * 1e3);
            }
        }
        out.insert(name.clone(), expected);
    }
    out
}

/// Coordinates within `plane` about the closed loop's centroid, in the
/// plane's basis ([`Plane::basis`]).
fn in_plane(loop_: &Polyline, plane: &Plane) -> impl Fn(DVec3) -> DVec2 {
    let centre = plane.project(loop_.centroid());
    let (e1, e2) = plane.basis();
    move |q: DVec3| DVec2::new((q - centre).dot(e1), (q - centre).dot(e2))
}

/// The arc parameter of the point of the closed loop `loop_` (in `plane`)
/// in the direction of `p` from the loop's centroid, within the plane.
pub fn loop_point_towards(loop_: &Polyline, plane: &Plane, p: DVec3) -> Option<f64> {
    let to2 = in_plane(loop_, plane);
    let dir = to2(plane.project(p)).try_normalize()?;
    let (k, u) = ray_exit(loop_, &to2, dir)?;
    let (a, b) = loop_.segment(k);
    Some(loop_.cumulative()[k] + u * a.distance(b))
}

/// Where the ray from the origin of the plane coordinates `to2` along `dir`
/// leaves the closed loop `loop_`: the segment it crosses farthest out and
/// the fraction along it; `None` where it crosses none.
pub fn ray_exit(loop_: &Polyline, to2: &dyn Fn(DVec3) -> DVec2, dir: DVec2) -> Option<(usize, f64)> {
    let mut hit: Option<(f64, usize, f64)> = None;
    for k in 0..loop_.segment_count() {
        let (a, b) = loop_.segment(k);
        let (a2, b2) = (to2(a), to2(b));
        let seg = b2 - a2;
        let den = dir.perp_dot(seg);
        if den.abs() < 1e-15 {
            continue;
        }
        let t = a2.perp_dot(seg) / den;
        let u = a2.perp_dot(dir) / den;
        if t > 0.0 && (0.0..=1.0).contains(&u) && hit.is_none_or(|(tt, _, _)| t > tt) {
            hit = Some((t, k, u));
        }
    }
    hit.map(|(_, k, u)| (k, u))
}

/// The signed angle (radians, in `(−π, π]`) from `a` to `b` as seen from
/// the centroid of the closed loop `loop_` within `plane`, and the angle of
/// `a` in the plane's basis; `None` where either lies on the centroid.
fn angles(loop_: &Polyline, plane: &Plane, a: DVec3, b: DVec3) -> Option<(f64, f64)> {
    let to2 = in_plane(loop_, plane);
    let (a2, b2) = (to2(plane.project(a)).try_normalize()?, to2(plane.project(b)).try_normalize()?);
    Some((a2.y.atan2(a2.x), a2.perp_dot(b2).atan2(a2.dot(b2))))
}

/// The fraction `f` of the angle from `from` to `to` (the shorter way) at
/// which `p` lies, all seen from the centroid of the closed loop `loop_`
/// within `plane`: `θ(p) = θ(from) + f·Δθ` (a [`crate::template::format::Below`]
/// placement by angle); `None` where the two points lie in one direction.
pub fn angle_fraction(loop_: &Polyline, plane: &Plane, (from, to): (DVec3, DVec3), p: DVec3) -> Option<f64> {
    let (_, span) = angles(loop_, plane, from, to)?;
    let (_, at) = angles(loop_, plane, from, p)?;
    (span.abs() > f64::EPSILON).then(|| at / span)
}

/// The arc parameter of the point of `loop_` at fraction `f` of the angle
/// from `from` to `to` ([`angle_fraction`]'s inverse): the loop's point in
/// the direction `θ(from) + f·Δθ` from its centroid.
pub fn loop_point_at_angle(loop_: &Polyline, plane: &Plane, (from, to): (DVec3, DVec3), fraction: f64) -> Option<f64> {
    let (theta, span) = angles(loop_, plane, from, to)?;
    let angle = theta + fraction * span;
    let centre = plane.project(loop_.centroid());
    let (e1, e2) = plane.basis();
    loop_point_towards(loop_, plane, centre + e1 * angle.cos() + e2 * angle.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ellipse(a: f64, b: f64, n: usize) -> Polyline {
        let pts = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                DVec3::new(a * t.cos(), 1.0, b * t.sin())
            })
            .collect();
        Polyline::new(pts, true)
    }

    /// Planted: on an oval (30 × 20 cm) with its side point on `+x` and its
    /// centre point on `+z`, a point in the direction 30° from the side
    /// lies at a third of the angle between them, whatever its distance from
    /// the centroid, and the loop's point at a third of the angle is the
    /// oval's point in that direction (exact up to the polygon's chords);
    /// the order of the two anchors flips the fraction's complement.
    #[test]
    fn a_hang_by_angle_keeps_its_direction_from_the_girths_centroid() {
        let plane = Plane { normal: DVec3::Y, offset: 1.0 };
        let (a, b) = (0.15, 0.10);
        let oval = ellipse(a, b, 3600);
        let (side, centre) = (DVec3::new(a, 1.0, 0.0), DVec3::new(0.0, 1.0, b));
        let dir = |deg: f64| DVec3::new(deg.to_radians().cos(), 0.0, deg.to_radians().sin());
        for reach in [0.05, 0.2, 0.4] {
            let p = DVec3::new(0.0, 1.0, 0.0) + dir(30.0) * reach;
            let f = angle_fraction(&oval, &plane, (side, centre), p).expect("a fraction");
            assert!((f - 1.0 / 3.0).abs() < 1e-9, "{f}");
            let back = angle_fraction(&oval, &plane, (centre, side), p).expect("a fraction");
            assert!((back - 2.0 / 3.0).abs() < 1e-9, "{back}");
        }
        let s = loop_point_at_angle(&oval, &plane, (side, centre), 1.0 / 3.0).expect("a point");
        let q = oval.point_at(s) - DVec3::new(0.0, 1.0, 0.0);
        let deg = q.z.atan2(q.x).to_degrees();
        assert!((deg - 30.0).abs() < 1e-6, "{deg}°");
        // on the oval: x²/a² + z²/b² = 1 up to the chords' sag
        assert!(((q.x / a).powi(2) + (q.z / b).powi(2) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn the_eased_ring_adds_exactly_the_declared_ease() {
        let plane = Plane { normal: DVec3::Y, offset: 1.0 };
        let tape_gain = |loop_: &Polyline, r: f64| {
            let cum = loop_.cumulative();
            let ring =
                Polyline::new(cum[..loop_.points.len()].iter().map(|&s| eased(loop_, s, r, &plane)).collect(), true);
            tape_length(&[&ring], &plane) - tape_length(&[loop_], &plane)
        };
        // a circle: e / 2π, as the radius increase of a circle
        let circle = ellipse(0.15, 0.15, 720);
        let r = ring_radial(&circle, &plane, 0.05);
        assert!((r - 0.05 / std::f64::consts::TAU).abs() < 1e-6, "{r}");
        // an oval waist (30 × 20 cm): e / 2π falls short, the refined offset does not
        let oval = ellipse(0.15, 0.10, 720);
        let short = tape_gain(&oval, 0.05 / std::f64::consts::TAU);
        assert!(short < 0.049, "radial e/2π adds {short}");
        let r = ring_radial(&oval, &plane, 0.05);
        assert!((tape_gain(&oval, r) - 0.05).abs() < 1e-5, "{}", tape_gain(&oval, r));
        // no ease, no offset
        assert_eq!(ring_radial(&oval, &plane, 0.0), 0.0);
    }

    #[test]
    fn bridging_fills_a_concavity_to_the_hull_and_keeps_the_convex_part() {
        let plane = Plane { normal: DVec3::Y, offset: 0.0 };
        // a square sampled evenly on every side, its first side pushed in (a cleft)
        let mut pts = Vec::new();
        let corners = [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)];
        for side in 0..4 {
            let (a, b) = (corners[side], corners[(side + 1) % 4]);
            for k in 0..40 {
                let t = k as f64 / 40.0;
                let dent = if side == 0 { 0.03 * (std::f64::consts::PI * t).sin() } else { 0.0 };
                pts.push(DVec3::new(a.0 + (b.0 - a.0) * t, 0.0, a.1 + (b.1 - a.1) * t + dent));
            }
        }
        let loop_ = Polyline::new(pts, true);
        let b = bridged(&loop_, &plane);
        // the pushed-in edge now lies on the hull: its middle on the line z = −0.1,
        // its ends (rays from the centroid near a corner) on the side edges
        for p in &b.points[10..30] {
            assert!((p.z + 0.1).abs() < 1e-9, "{p}");
        }
        for p in &b.points {
            let on_hull = (p.z + 0.1).abs() < 1e-9 || (p.x.abs() - 0.1).abs() < 1e-9 || (p.z - 0.1).abs() < 1e-9;
            assert!(on_hull, "{p}");
        }
        assert!((tape_length(&[&b], &plane) - tape_length(&[&loop_], &plane)).abs() < 1e-12);
    }
}
