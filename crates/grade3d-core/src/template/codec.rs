//! Encoding a garment mesh into a template on a reference body, and
//! decoding a template onto any feature human model (seed 000 §3.2, §4.2).
//!
//! **Encode.** Each node `v̄_i` at position `p` is tied to a feature point
//! `q_j` (the one given, else the nearest), and `(α, β, γ)` solve the 3×3
//! system of Eq. (1):
//!
//! `p − p(q_j) = α n(q_j) + β t(f1) + γ t(f2)`.
//!
//! The plain offset `d = p − p(q_j)` of Eq. (2) is stored too, and the
//! node's reference position (Eq. 5 needs it).
//!
//! **Decode.** On a body `H'`: `p'(v̄_i) = p'(q_j) + α n' + β t'(f1) + γ t'(f2)`
//! (Eq. 1), or `p'(q_j) + d` (Eq. 2, for comparison: it does not follow
//! the body's orientation, seed 000 Fig. 6). Profiles follow their end
//! nodes by Eq. (5) ([`Profile::relocated`]). With Eq. (1), the nodes of a
//! ring around a girth the template declares an ease for are first placed
//! on the body's own eased girth ([`super::girth::place_ring_nodes`]: where
//! authoring put them; Eq. (1) gives the same point on the reference body),
//! and after Eq. (5) the profiles of ring
//! edges around a girth the template declares an ease for are sampled again
//! along the body's own eased girth ([`super::girth::refit_rings`]), as
//! authoring sampled them on the reference body, so that the declared ease
//! holds on every body. Before the rings, a node the template places along
//! a body curve ([`OnCurve`], an armhole node on the armscye) goes there
//! ([`on_curve_nodes`]).
//!
//! Failure modes: a node tied to a feature point the body lacks, a
//! singular frame at encode time, a profile that cannot be built — each a
//! [`CodecError`] naming the node or edge.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::format::{
    Below, Between, Bracket, Dart, Drop, Edge, Face, GradingDefaults, GrainLine, Hang, Node, Notch, OnCurve, Panel,
    Relocation, Seam, Template, TemplateError, SCHEMA_ID, SCHEMA_VERSION,
};
use super::girth::{eased, eased_arc, girth_plane, place_ring_nodes, refit_rings, shorter_way};
use super::profile::{Profile, ProfileError};
use crate::body::feature::FeatureBody;
use crate::body::vocab::{CurveId, PointId, VOCABULARY_VERSION};
use crate::geom::plane::Plane;
use crate::geom::polyline::Polyline;

/// Why encoding or decoding failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CodecError {
    /// The body has no such feature point.
    #[error("node {node} is tied to `{point}`, which the body does not have{}", missing_hint(*point))]
    MissingPoint {
        /// The node.
        node: u32,
        /// The feature point.
        point: PointId,
    },
    /// The frame at a feature point is singular.
    #[error("node {node}: the frame at `{point}` is singular")]
    SingularFrame {
        /// The node.
        node: u32,
        /// The feature point.
        point: PointId,
    },
    /// A profile could not be built or moved.
    #[error("edge {edge}: {source}")]
    Profile {
        /// The edge.
        edge: u32,
        /// The cause.
        source: ProfileError,
    },
    /// A draft refers to something that does not exist.
    #[error("draft: {0}")]
    Draft(String),
    /// The encoded template is invalid.
    #[error(transparent)]
    Template(#[from] TemplateError),
}

/// What a body that lacks `point` needs: an optional (arm) point is derived
/// only where its landmarks are given ([`crate::body::vocab::optional_point`]).
fn missing_hint(point: PointId) -> &'static str {
    if crate::body::vocab::optional_point(point) {
        " (an arm point: give the body's arm landmarks, vocabulary 3, or send the scan without landmarks to have them found)"
    } else {
        ""
    }
}

/// A pattern piece of a draft: triangle indices into [`Draft::triangles`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DraftPanel {
    /// Piece name.
    pub name: String,
    /// Its triangles.
    pub triangles: Vec<usize>,
    /// Grain line `(from node, to node)`.
    pub grain: (u32, u32),
    /// The stack point's node, where it is not `grain.0` ([`GrainLine::stack`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stack: Option<u32>,
    /// Pieces to cut.
    pub quantity: u32,
}

/// A seam of a draft: a chain of nodes along which two panels meet.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DraftSeam {
    /// Seam name.
    pub name: String,
    /// One panel.
    pub panel_a: String,
    /// The other.
    pub panel_b: String,
    /// Nodes along the seam, in order.
    pub nodes: Vec<u32>,
}

/// A garment mesh placed on a reference body, before encoding.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Draft {
    /// Template name.
    pub name: String,
    /// Template version.
    pub version: u32,
    /// Description.
    pub description: String,
    /// Ease by girth, mm.
    pub ease_mm: BTreeMap<String, f64>,
    /// Node positions on the reference body.
    pub positions: Vec<DVec3>,
    /// Feature point each node is tied to (`None`: the nearest).
    pub ties: Vec<Option<PointId>>,
    /// Ring nodes' shifts along their girth, by node
    /// ([`super::format::Node::ring_shift`]); a node not listed has none.
    pub ring_shifts: BTreeMap<u32, f64>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Profiles: `(start node, end node)` → attached points from start to end.
    pub profiles: Vec<((u32, u32), Vec<DVec3>)>,
    /// Pattern pieces.
    pub panels: Vec<DraftPanel>,
    /// Seams.
    pub seams: Vec<DraftSeam>,
    /// Notches `(name, node)`.
    pub notches: Vec<(String, u32)>,
    /// Darts `(name, panel, nodes from the outline to the apex)`.
    pub darts: Vec<(String, String, Vec<u32>)>,
    /// Nodes that drop from another perpendicular to a girth.
    pub drops: Vec<Drop>,
    /// Nodes placed along a body curve.
    pub on_curve: Vec<OnCurve>,
    /// Nodes lofted between two girths.
    pub between: Vec<Between>,
    /// Nodes hanging below a girth.
    pub below: Vec<Below>,
    /// Nodes that hang straight between two others.
    pub hangs: Vec<Hang>,
    /// Mirror-pair panels (the template's `mirror_pairs`).
    pub mirror_pairs: Vec<[String; 2]>,
    /// Default grading options.
    pub defaults: GradingDefaults,
}

/// Encodes a draft on its reference body into a template.
///
/// The draft's drops and hangs are applied on the reference body first
/// (nodes moved, the profiles of their edges relocated by Eq. (5)), so that
/// decoding on the reference body reproduces the stored nodes.
pub fn encode(draft: &Draft, body: &FeatureBody) -> Result<Template, CodecError> {
    let mut hung = draft.clone();
    let mut moved: Vec<u32> =
        on_curve_nodes(&draft.on_curve, body, &mut hung.positions).into_iter().map(|(v, _)| v).collect();
    moved.extend(between_nodes(&draft.between, body, &mut hung.positions));
    moved.extend(below_nodes(&draft.below, body, &mut hung.positions));
    moved.extend(drop_nodes(&draft.drops, body, &mut hung.positions));
    moved.extend(hang(&draft.hangs, body, &mut hung.positions));
    if !moved.is_empty() {
        for ((a, b), pts) in &mut hung.profiles {
            if moved.contains(a) || moved.contains(b) {
                let profile = Profile::new(pts.clone())
                    .and_then(|p| p.relocated(hung.positions[*a as usize], hung.positions[*b as usize]))
                    .map_err(|e| CodecError::Draft(format!("profile {a}–{b} of a hanging node: {e}")))?;
                *pts = profile.points().to_vec();
            }
        }
    }
    let draft = &hung;
    let mut nodes = Vec::with_capacity(draft.positions.len());
    for (i, &p) in draft.positions.iter().enumerate() {
        let node = i as u32;
        let tie = match draft.ties.get(i).copied().flatten() {
            Some(t) => t,
            None => body
                .points
                .iter()
                .min_by(|a, b| a.1.position.distance(p).total_cmp(&b.1.position.distance(p)))
                .map(|(k, _)| *k)
                .ok_or_else(|| CodecError::Draft("the reference body has no feature points".into()))?,
        };
        let q = body.points.get(&tie).ok_or(CodecError::MissingPoint { node, point: tie })?;
        let d = p - q.position;
        let (alpha, beta, gamma) = q.frame.coordinates(d).ok_or(CodecError::SingularFrame { node, point: tie })?;
        nodes.push(Node {
            point: tie,
            alpha,
            beta,
            gamma,
            offset: d.to_array(),
            reference: p.to_array(),
            ring_shift: draft.ring_shifts.get(&node).copied(),
        });
    }
    // edge table: one row per undirected edge, start < end
    let mut edge_ids: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    let mut edges: Vec<Edge> = Vec::new();
    let mut faces = Vec::with_capacity(draft.triangles.len());
    for t in &draft.triangles {
        let mut fe = [0u32; 3];
        let mut fd = [0i8; 3];
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a as usize >= nodes.len() || b as usize >= nodes.len() {
                return Err(CodecError::Draft(format!("triangle {t:?} names a missing node")));
            }
            let key = (a.min(b), a.max(b));
            let id = *edge_ids.entry(key).or_insert_with(|| {
                edges.push(Edge { start: key.0, end: key.1, profile: Vec::new() });
                (edges.len() - 1) as u32
            });
            fe[k] = id;
            fd[k] = if a < b { 1 } else { -1 };
        }
        faces.push(Face { edges: fe, directions: fd });
    }
    for ((a, b), pts) in &draft.profiles {
        let key = ((*a).min(*b), (*a).max(*b));
        let id = *edge_ids.get(&key).ok_or_else(|| CodecError::Draft(format!("profile on missing edge {a}–{b}")))?;
        let mut pts = pts.clone();
        if a > b {
            pts.reverse();
        }
        // the profile interpolates its end nodes exactly
        if let Some(first) = pts.first_mut() {
            *first = draft.positions[key.0 as usize];
        }
        if let Some(last) = pts.last_mut() {
            *last = draft.positions[key.1 as usize];
        }
        Profile::new(pts.clone()).map_err(|source| CodecError::Profile { edge: id, source })?;
        edges[id as usize].profile = pts.iter().map(|p| p.to_array()).collect();
    }
    let panels = draft
        .panels
        .iter()
        .map(|p| Panel {
            name: p.name.clone(),
            faces: p.triangles.iter().map(|&t| t as u32).collect(),
            grain: GrainLine { from: p.grain.0, to: p.grain.1, stack: p.stack.filter(|&s| s != p.grain.0) },
            quantity: p.quantity,
        })
        .collect();
    // the template edges along a node path (seams, darts)
    let edges_along = |what: &str, nodes: &[u32]| -> Result<Vec<u32>, CodecError> {
        nodes
            .windows(2)
            .map(|w| {
                edge_ids
                    .get(&(w[0].min(w[1]), w[0].max(w[1])))
                    .copied()
                    .ok_or_else(|| CodecError::Draft(format!("{what} runs along missing edge {}–{}", w[0], w[1])))
            })
            .collect()
    };
    let seams = draft
        .seams
        .iter()
        .map(|s| {
            let edges = edges_along(&format!("seam `{}`", s.name), &s.nodes)?;
            Ok(Seam { name: s.name.clone(), panel_a: s.panel_a.clone(), panel_b: s.panel_b.clone(), edges })
        })
        .collect::<Result<Vec<_>, CodecError>>()?;
    let darts = draft
        .darts
        .iter()
        .map(|(name, panel, nodes)| {
            let edges = edges_along(&format!("dart `{name}`"), nodes)?;
            Ok(Dart { name: name.clone(), panel: panel.clone(), edges })
        })
        .collect::<Result<Vec<_>, CodecError>>()?;
    let t = Template {
        schema: SCHEMA_ID.to_owned(),
        schema_version: SCHEMA_VERSION,
        vocabulary: VOCABULARY_VERSION,
        name: draft.name.clone(),
        version: draft.version,
        description: draft.description.clone(),
        ease_mm: draft.ease_mm.clone(),
        ease_range_mm: BTreeMap::new(),
        design_body: None,
        nodes,
        edges,
        faces,
        panels,
        seams,
        notches: draft.notches.iter().map(|(n, v)| Notch { name: n.clone(), node: *v }).collect(),
        darts,
        drops: draft.drops.clone(),
        on_curve: draft.on_curve.clone(),
        between: draft.between.clone(),
        below: draft.below.clone(),
        hangs: draft.hangs.clone(),
        mirror_pairs: draft.mirror_pairs.clone(),
        defaults: draft.defaults.clone(),
    };
    t.validate()?;
    // store the ring profiles as decoding builds them on this body (a hung ring's
    // arcs bent onto its hung nodes), so that decode ∘ encode is exact here
    let mut t = t;
    if t.defaults.relocation == Relocation::Eq1Frame {
        let m = decode(&t, body, Relocation::Eq1Frame)?;
        for (e, p) in t.edges.iter_mut().zip(&m.profiles) {
            if let Some(p) = p {
                e.profile = p.points().iter().map(|q| q.to_array()).collect();
            }
        }
    }
    Ok(t)
}

/// The unit normal `u` of `girth`'s plane pointing up the body (from the
/// crotch towards the back neck point), along which a [`Drop`] falls;
/// `None` where the body lacks the girth or those points.
pub fn drop_axis(body: &FeatureBody, girth: CurveId) -> Option<DVec3> {
    let up_the_body = body.points.get(&PointId::NeckBack)?.position - body.points.get(&PointId::Crotch)?.position;
    let n = girth_plane(body, girth)?.normal;
    Some(if n.dot(up_the_body) >= 0.0 { n } else { -n })
}

/// Where a [`Drop`] of `length` and `flare` (m) from `from` lands:
/// `from − length·u + flare·o`, `o` the unit direction from `centre` to
/// `from` within the plane normal to `u`.
pub fn drop_position(from: DVec3, u: DVec3, centre: DVec3, length: f64, flare: f64) -> DVec3 {
    let out = from - centre;
    from - u * length + (out - out.dot(u) * u).normalize_or_zero() * flare
}

/// Places each dropping node ([`Drop`]; formula there), the centre of each
/// girth's drops the mean of their `from` nodes. Returns the nodes placed;
/// a drop whose [`drop_axis`] the body lacks is left alone.
pub fn drop_nodes(drops: &[Drop], body: &FeatureBody, positions: &mut [DVec3]) -> Vec<u32> {
    let mut placed = Vec::new();
    let girths: std::collections::BTreeSet<CurveId> = drops.iter().map(|d| d.girth).collect();
    for girth in girths {
        let Some(u) = drop_axis(body, girth) else { continue };
        let ours: Vec<&Drop> = drops.iter().filter(|d| d.girth == girth).collect();
        let froms: Vec<DVec3> = ours.iter().filter_map(|d| positions.get(d.from as usize).copied()).collect();
        let centre = froms.iter().copied().sum::<DVec3>() / froms.len().max(1) as f64;
        for d in ours {
            let Some(&from) = positions.get(d.from as usize) else { continue };
            if let Some(p) = positions.get_mut(d.node as usize) {
                *p = drop_position(from, u, centre, d.length_m, d.flare_m);
                placed.push(d.node);
            }
        }
    }
    placed
}

/// The parameter on `loop_` of an [`OnCurve`] placement and the point
/// there: `s_from + f·Δs` along the arc from `from`'s nearest point to
/// `to`'s whose midpoint is nearer `via`, eased within `plane`
/// ([`super::girth::eased`]; formula at [`OnCurve`]); `None` for a loop
/// without length.
pub fn on_curve_point(
    loop_: &Polyline,
    plane: &Plane,
    (from, to, via): (DVec3, DVec3, DVec3),
    fraction: f64,
    radial: f64,
) -> Option<(f64, DVec3)> {
    let (s0, d) = on_curve_arc(loop_, (from, to, via))?;
    let s = (s0 + fraction * d).rem_euclid(loop_.length());
    Some((s, eased(loop_, s, radial, plane)))
}

/// The arc of an [`OnCurve`] placement on `loop_`: the parameter `s_from`
/// of the point nearest `from` and the signed arc length `Δs` to the point
/// nearest `to`, the way round whose midpoint is nearer `via`; `None` for a
/// loop without length.
pub fn on_curve_arc(loop_: &Polyline, (from, to, via): (DVec3, DVec3, DVec3)) -> Option<(f64, f64)> {
    let total = loop_.length();
    if total <= f64::EPSILON {
        return None;
    }
    let (s0, s1) = (loop_.closest(from)?.s, loop_.closest(to)?.s);
    let forward = (s1 - s0).rem_euclid(total);
    let backward = forward - total;
    let mid = |d: f64| loop_.point_at((s0 + 0.5 * d).rem_euclid(total)).distance(via);
    Some((s0, if mid(forward) <= mid(backward) { forward } else { backward }))
}

/// The normal `ν` of an [`OnCurve`] placement (formula there): `plane`'s
/// normal turned away from `via`, seen from the curve's centroid.
pub fn turned_normal(plane: &Plane, centroid: DVec3, via: DVec3) -> DVec3 {
    if plane.normal.dot(via - centroid) > 0.0 {
        -plane.normal
    } else {
        plane.normal
    }
}

/// Places each [`OnCurve`] node on the body's curve. Returns the nodes
/// placed with their curve parameters; one whose curve or points the body
/// lacks keeps its position.
pub fn on_curve_nodes(placements: &[OnCurve], body: &FeatureBody, positions: &mut [DVec3]) -> Vec<(u32, f64)> {
    let mut placed = Vec::new();
    for c in placements {
        let point = |id: PointId| body.points.get(&id).map(|q| q.position);
        let (Some(curve), Some(plane), Some(from), Some(to), Some(via)) =
            (body.curves.get(&c.curve), girth_plane(body, c.curve), point(c.from), point(c.to), point(c.via))
        else {
            continue;
        };
        let Some((s, p)) = on_curve_point(&curve.polyline, &plane, (from, to, via), c.fraction, c.radial_m) else {
            continue;
        };
        if let Some(slot) = positions.get_mut(c.node as usize) {
            *slot = p + turned_normal(&plane, curve.polyline.centroid(), via) * c.normal_m;
            placed.push((c.node, s));
        }
    }
    placed
}

/// A girth walked for [`Between`]: its bridged loop, cumulative arc
/// lengths, length and centroid.
#[derive(Debug, Clone)]
pub struct GirthWalk {
    /// The bridged loop.
    pub loop_: Polyline,
    cum: Vec<f64>,
    /// Its length, m.
    pub length: f64,
    /// Its centroid.
    pub centroid: DVec3,
}

impl GirthWalk {
    /// The body's girth `curve` bridged; `None` where it lacks it.
    pub fn new(body: &FeatureBody, curve: CurveId) -> Option<Self> {
        let plane = girth_plane(body, curve)?;
        Self::from_loop(super::girth::bridged(&body.curves.get(&curve)?.polyline, &plane))
    }

    /// A walk along `loop_` as it is; `None` where it has no length.
    pub fn from_loop(loop_: Polyline) -> Option<Self> {
        let length = loop_.length();
        (length > f64::EPSILON).then(|| Self { cum: loop_.cumulative(), centroid: loop_.centroid(), length, loop_ })
    }

    /// The arc parameter of the loop point nearest `p`.
    pub fn start(&self, p: DVec3) -> Option<f64> {
        Some(self.loop_.closest(p)?.s)
    }

    /// The point at the fraction `f` of the length from parameter `s0`.
    pub fn at(&self, s0: f64, f: f64) -> DVec3 {
        self.loop_.point_at_with(&self.cum, (s0 + f * self.length).rem_euclid(self.length))
    }

    /// The point at the fraction `t` of the arc from parameter `s_from` to
    /// `s_to`, walked in the loop's direction ([`Bracket`]).
    pub fn at_bracket(&self, s_from: f64, s_to: f64, t: f64) -> DVec3 {
        let arc = (s_to - s_from).rem_euclid(self.length);
        self.loop_.point_at_with(&self.cum, (s_from + t * arc).rem_euclid(self.length))
    }

    /// The fraction of the arc from `s_from` to `s_to` (walked in the
    /// loop's direction) at which parameter `s` lies: the inverse of
    /// [`Self::at_bracket`]; `None` where `s` lies outside that arc.
    pub fn bracket_fraction(&self, s_from: f64, s_to: f64, s: f64) -> Option<f64> {
        let arc = (s_to - s_from).rem_euclid(self.length);
        let along = (s - s_from).rem_euclid(self.length);
        (arc > 0.0 && along <= arc).then(|| along / arc)
    }
}

/// The lofted point of a [`Between`] placement (formula there) from its
/// girth points `a`, `b` and the girths' centroids; `None` when the
/// centroids coincide.
pub fn loft((a, c_a): (DVec3, DVec3), (b, c_b): (DVec3, DVec3), height: f64, radial: f64) -> Option<DVec3> {
    let q = a + (b - a) * height;
    let c = c_a + (c_b - c_a) * height;
    let e = (c_b - c_a).normalize_or_zero();
    if e == DVec3::ZERO {
        return None;
    }
    let d = (q - c) - e * (q - c).dot(e);
    Some(q + d.normalize_or_zero() * radial)
}

/// Where a [`Between`] placement lands (formula there): the lofted point at
/// `fraction` and `height`, `radial` out; `None` when the girths' centroids
/// coincide.
pub fn between_point(
    (lower, s_lower): (&GirthWalk, f64),
    (upper, s_upper): (&GirthWalk, f64),
    fraction: f64,
    height: f64,
    radial: f64,
) -> Option<DVec3> {
    let (a, b) = (lower.at(s_lower, fraction), upper.at(s_upper, fraction));
    loft((a, lower.centroid), (b, upper.centroid), height, radial)
}

/// Places each node lofted between two girths ([`Between`]; formula
/// there). Returns the nodes placed; one whose girths or points the body
/// lacks keeps its position.
pub fn between_nodes(placements: &[Between], body: &FeatureBody, positions: &mut [DVec3]) -> Vec<u32> {
    let mut walks: BTreeMap<CurveId, Option<GirthWalk>> = BTreeMap::new();
    for b in
        [placements.iter().map(|b| b.lower).collect::<Vec<_>>(), placements.iter().map(|b| b.upper).collect()].concat()
    {
        walks.entry(b).or_insert_with(|| GirthWalk::new(body, b));
    }
    let mut placed = Vec::new();
    // each feature point's parameter on a girth, taken once (a closest-point search along it)
    let mut params: BTreeMap<(CurveId, PointId), Option<f64>> = BTreeMap::new();
    let mut param = |curve: CurveId, id: PointId| {
        *params.entry((curve, id)).or_insert_with(|| walks.get(&curve)?.as_ref()?.start(body.points.get(&id)?.position))
    };
    // a girth's point: in its bracket where the placement has one, else at the fraction of the
    // whole girth from its start
    let mut girth_point = |curve: CurveId, start: PointId, bracket: Option<Bracket>, fraction: f64| {
        let w = walks.get(&curve)?.as_ref()?;
        match bracket {
            Some(k) => Some(w.at_bracket(param(curve, k.from)?, param(curve, k.to)?, k.fraction)),
            None => Some(w.at(param(curve, start)?, fraction)),
        }
    };
    for b in placements {
        let (Some(a), Some(u)) = (
            girth_point(b.lower, b.lower_start, b.lower_bracket, b.fraction),
            girth_point(b.upper, b.upper_start, b.upper_bracket, b.fraction),
        ) else {
            continue;
        };
        let (Some(Some(lw)), Some(Some(uw))) = (walks.get(&b.lower), walks.get(&b.upper)) else { continue };
        let Some(p) = loft((a, lw.centroid), (u, uw.centroid), b.height, b.radial_m) else { continue };
        if let Some(slot) = positions.get_mut(b.node as usize) {
            *slot = p;
            placed.push(b.node);
        }
    }
    placed
}

/// The distance from `girth`'s plane down to the body's ankle girths (the
/// mean of their centroids), along [`drop_axis`] ([`Below::leg_m`]);
/// `None` where the body lacks them or they do not lie below.
pub fn leg_length(body: &FeatureBody, girth: CurveId) -> Option<f64> {
    let up = drop_axis(body, girth)?;
    let plane = girth_plane(body, girth)?;
    let ankles: Vec<DVec3> = [CurveId::AnkleLeft, CurveId::AnkleRight]
        .iter()
        .filter_map(|c| Some(body.curves.get(c)?.polyline.centroid()))
        .collect();
    if ankles.is_empty() {
        return None;
    }
    let mean = ankles.iter().sum::<DVec3>() / ankles.len() as f64;
    let d = (plane.project(mean) - mean).dot(up);
    (d > 0.0).then_some(d)
}

/// Places each node hanging below a girth ([`Below`]; formula there).
/// Returns the nodes placed; one whose girth or points the body lacks
/// keeps its position.
pub fn below_nodes(placements: &[Below], body: &FeatureBody, positions: &mut [DVec3]) -> Vec<u32> {
    let mut placed = Vec::new();
    /// A girth's bridged loop, plane, up axis and leg length, taken once.
    type Hung = (Polyline, Plane, DVec3, Option<f64>);
    let mut girths: BTreeMap<CurveId, Option<Hung>> = BTreeMap::new();
    for b in placements {
        let girth = girths
            .entry(b.girth)
            .or_insert_with(|| {
                let plane = girth_plane(body, b.girth)?;
                let loop_ = super::girth::bridged(&body.curves.get(&b.girth)?.polyline, &plane);
                Some((loop_, plane, drop_axis(body, b.girth)?, leg_length(body, b.girth)))
            })
            .as_ref();
        let point = |id: PointId| body.points.get(&id).map(|q| q.position);
        let (Some((loop_, plane, up, leg)), Some(from), Some(to)) = (girth, point(b.from), point(b.to)) else {
            continue;
        };
        let on_girth = if b.by_angle {
            super::girth::loop_point_at_angle(loop_, plane, (from, to), b.fraction)
                .map(|s| super::girth::eased(loop_, s, b.radial_m, plane))
        } else {
            on_curve_point(loop_, plane, (from, to, (from + to) * 0.5), b.fraction, b.radial_m).map(|(_, p)| p)
        };
        let Some(p) = on_girth else { continue };
        let drop = match leg {
            Some(d) if b.leg_m > 0.0 => b.drop_m * d / b.leg_m,
            _ => b.drop_m,
        };
        if let Some(slot) = positions.get_mut(b.node as usize) {
            *slot = p - *up * drop;
            placed.push(b.node);
        }
    }
    placed
}

/// Samples the profile of every edge along an [`OnCurve`] curve again on
/// the body's own curve, as authoring sampled it (the armhole between the
/// shoulder, the armhole nodes and the armpit): an edge from a node placed
/// on curve `γ` to another placed on it, or to a node tied to one of the
/// placement's `from`/`to` feature points (parameter: that point's nearest
/// curve point), along the garment's outline (an edge of one face), runs
/// the shorter way round between the two parameters,
///
/// ```text
/// Q_k = γ̃(s_a + (k/(n−1))·Δs) + (1 − k/(n−1))·(p_a − γ̃(s_a)) + (k/(n−1))·(p_b − γ̃(s_b))
/// ```
///
/// `γ̃` the curve eased by the placement's offset within its plane
/// ([`super::girth::eased_arc`], ends bent onto the nodes), `n` the
/// profile's point count, `p_a`, `p_b` the decoded end nodes. Eq. (5)'s
/// affine copy of the reference body's armhole turns with the chord between
/// its nodes, and on a heavy man's scan (pop31) swung the armhole's lower
/// half 50 mm out into the arm. Returns how many profiles were refitted.
///
/// # Errors
/// `(edge, ProfileError)` for a profile that cannot be built.
pub fn refit_on_curve_edges(
    t: &Template,
    body: &FeatureBody,
    placed: &[(u32, f64)],
    positions: &[DVec3],
    profiles: &mut [Option<Profile>],
) -> Result<usize, (u32, ProfileError)> {
    let mut refitted = 0;
    // an armhole is an outline: edges of one face (an interior edge from an armhole node to a node
    // tied to the shoulder point is not bent along the armscye)
    let mut faces_of = vec![0u8; t.edges.len()];
    for f in &t.faces {
        for &e in &f.edges {
            if let Some(n) = faces_of.get_mut(e as usize) {
                *n = n.saturating_add(1);
            }
        }
    }
    let curves: std::collections::BTreeSet<CurveId> = t.on_curve.iter().map(|c| c.curve).collect();
    for curve in curves {
        let (Some(loop_), Some(plane)) = (body.curves.get(&curve).map(|c| &c.polyline), girth_plane(body, curve))
        else {
            continue;
        };
        let total = loop_.length();
        let ours: Vec<&OnCurve> = t.on_curve.iter().filter(|c| c.curve == curve).collect();
        let radial = ours.iter().map(|c| c.radial_m).sum::<f64>() / ours.len().max(1) as f64;
        let mut params: BTreeMap<u32, f64> = BTreeMap::new();
        let ends: std::collections::BTreeSet<PointId> = ours.iter().flat_map(|c| [c.from, c.to]).collect();
        for (node, n) in t.nodes.iter().enumerate() {
            if ends.contains(&n.point) {
                if let Some(at) = body.points.get(&n.point).and_then(|q| loop_.closest(q.position)) {
                    params.insert(node as u32, at.s);
                }
            }
        }
        let on: Vec<(u32, f64)> = placed.iter().filter(|(v, _)| ours.iter().any(|c| c.node == *v)).copied().collect();
        params.extend(on.iter().copied());
        for (i, e) in t.edges.iter().enumerate() {
            let (Some(&sa), Some(&sb)) = (params.get(&e.start), params.get(&e.end)) else { continue };
            if !on.iter().any(|&(v, _)| v == e.start || v == e.end) || faces_of[i] != 1 {
                continue;
            }
            let Some(Some(old)) = profiles.get(i) else { continue };
            let n = old.points().len().max(2);
            let ends = (Some(positions[e.start as usize]), Some(positions[e.end as usize]));
            let pts = eased_arc(loop_, &plane, sa, shorter_way(sa, sb, total), n, radial, ends);
            profiles[i] = Some(Profile::new(pts).map_err(|source| (i as u32, source))?);
            refitted += 1;
        }
    }
    Ok(refitted)
}

/// The part of a hang's line a node may move to, as fractions of the line
/// from its upper node: a node beyond it is not hanging between the two.
pub const HANG_SPAN: (f64, f64) = (0.05, 0.95);

/// Moves each hanging node ([`Hang`]), in order, to the point of the line
/// `upper → lower` nearest to it, `u + s (l − u)` with
/// `s = (p − u)·(l − u) / |l − u|²` (only for `s` in [`HANG_SPAN`]), when that point lies further
/// from the body than the node: `(straight − p)·(p − c) > 0`, `c` the body
/// point closest to `p`. Rotation- and translation-covariant (no world axis).
/// Returns the nodes moved.
fn hang(hangs: &[Hang], body: &FeatureBody, positions: &mut [DVec3]) -> Vec<u32> {
    let mut moved = Vec::new();
    for h in hangs {
        let (Some(&p), Some(&u), Some(&l)) =
            (positions.get(h.node as usize), positions.get(h.upper as usize), positions.get(h.lower as usize))
        else {
            continue;
        };
        let chord = l - u;
        let len2 = chord.length_squared();
        if len2 <= f64::EPSILON {
            continue;
        }
        let s = (p - u).dot(chord) / len2;
        // a node that is not between the two (a misplaced decode) is left alone
        if !(HANG_SPAN.0..=HANG_SPAN.1).contains(&s) {
            continue;
        }
        let straight = u + chord * s;
        let out = p - crate::geom::query::closest_point(&body.mesh, p).point;
        // a relative floor keeps a node already on its line (the authoring body) in place
        if (straight - p).dot(out) > 1e-9 * len2 {
            positions[h.node as usize] = straight;
            moved.push(h.node);
        }
    }
    moved
}

/// The coarse garment mesh `M0` of a template on a body.
#[derive(Debug, Clone, PartialEq)]
pub struct CoarseMesh {
    /// Node positions.
    pub positions: Vec<DVec3>,
    /// Triangles (node indices), counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// The profile of every edge of the template's edge table, if any,
    /// oriented from the edge's start node to its end node.
    pub profiles: Vec<Option<Profile>>,
    /// Nodes a hang moved (the template's `hangs`).
    pub hung: Vec<u32>,
}

/// Decodes a template onto a feature human model.
pub fn decode(t: &Template, body: &FeatureBody, relocation: Relocation) -> Result<CoarseMesh, CodecError> {
    let mut positions = Vec::with_capacity(t.nodes.len());
    for (i, n) in t.nodes.iter().enumerate() {
        let q = body.points.get(&n.point).ok_or(CodecError::MissingPoint { node: i as u32, point: n.point })?;
        let p = match relocation {
            Relocation::Eq1Frame => q.position + q.frame.offset(n.alpha, n.beta, n.gamma),
            Relocation::Eq2Offset => q.position + DVec3::from_array(n.offset),
        };
        positions.push(p);
    }
    // ring nodes on the body's eased girths (as authored), then the hangs from there
    let eq1 = relocation == Relocation::Eq1Frame;
    let mut on_curve = Vec::new();
    if eq1 {
        on_curve = on_curve_nodes(&t.on_curve, body, &mut positions);
        between_nodes(&t.between, body, &mut positions);
        below_nodes(&t.below, body, &mut positions);
        place_ring_nodes(t, body, &mut positions);
        drop_nodes(&t.drops, body, &mut positions);
    }
    let placed = positions.clone();
    let hung = hang(&t.hangs, body, &mut positions);
    let triangles = (0..t.faces.len()).map(|f| t.face_nodes(f)).collect();
    let mut profiles = Vec::with_capacity(t.edges.len());
    for (i, e) in t.edges.iter().enumerate() {
        if e.profile.is_empty() {
            profiles.push(None);
            continue;
        }
        let edge = i as u32;
        let old = Profile::new(e.profile.iter().map(|&p| DVec3::from_array(p)).collect())
            .map_err(|source| CodecError::Profile { edge, source })?;
        let moved = old
            .relocated(positions[e.start as usize], positions[e.end as usize])
            .map_err(|source| CodecError::Profile { edge, source })?;
        profiles.push(Some(moved));
    }
    // ring edges follow the body's eased girth, as on the reference body (ease as declared)
    if eq1 {
        refit_rings(t, body, &placed, &positions, &mut profiles, &hung)
            .map_err(|(edge, source)| CodecError::Profile { edge, source })?;
        refit_on_curve_edges(t, body, &on_curve, &positions, &mut profiles)
            .map_err(|(edge, source)| CodecError::Profile { edge, source })?;
    }
    Ok(CoarseMesh { positions, triangles, profiles, hung })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A horizontal circle of radius 0.1 m about the origin, 360 points.
    fn circle() -> Polyline {
        let pts = (0..360)
            .map(|k| {
                let a = (k as f64).to_radians();
                DVec3::new(0.1 * a.cos(), 0.0, 0.1 * a.sin())
            })
            .collect();
        Polyline::new(pts, true)
    }

    #[test]
    fn a_bracketed_girth_point_follows_its_two_feature_points() {
        // a circle of radius 0.1 m, and the same circle with its +x half stretched to 0.15 m
        let ring = |stretch: f64| {
            let pts = (0..360)
                .map(|k| {
                    let a = (k as f64).to_radians();
                    let x = 0.1 * a.cos();
                    DVec3::new(if x > 0.0 { x * stretch } else { x }, 0.0, 0.1 * a.sin())
                })
                .collect();
            GirthWalk::from_loop(Polyline::new(pts, true)).unwrap()
        };
        let (round, stretched) = (ring(1.0), ring(1.5));
        // feature points at 100° and 200° (on the −x half, which the stretch leaves alone), and a
        // point two fifths of the way from one to the other (140°)
        let at = |deg: f64| DVec3::new(0.1 * deg.to_radians().cos(), 0.0, 0.1 * deg.to_radians().sin());
        let planted = at(140.0);
        for w in [&round, &stretched] {
            let (s_from, s_to) = (w.start(at(100.0)).unwrap(), w.start(at(200.0)).unwrap());
            let p = w.at_bracket(s_from, s_to, 0.4);
            assert!(p.distance(planted) < 1e-4, "bracketed: {p} for {planted}");
            // the inverse, exact to rounding
            let t = w.bracket_fraction(s_from, s_to, w.start(p).unwrap()).unwrap();
            assert!((t - 0.4).abs() < 1e-9, "{t}");
            // outside the bracket: none
            assert!(w.bracket_fraction(s_from, s_to, w.start(at(300.0)).unwrap()).is_none());
        }
        // the whole girth's fraction from the 100° point parts from the planted point where the
        // other half grows: what the bracket is for
        let s0 = round.start(at(100.0)).unwrap();
        let f = (round.start(planted).unwrap() - s0).rem_euclid(round.length) / round.length;
        let moved = stretched.at(stretched.start(at(100.0)).unwrap(), f);
        assert!(moved.distance(planted) > 5e-3, "whole-girth fraction: {moved}");
        // a bracket across the loop's seam (from 300° through 0° to 60°) walks forward
        let (s_from, s_to) = (round.start(at(300.0)).unwrap(), round.start(at(60.0)).unwrap());
        assert!(round.at_bracket(s_from, s_to, 0.5).distance(at(0.0)) < 1e-4);
    }

    #[test]
    fn an_on_curve_node_lands_midway_on_the_arc_through_its_via_point_eased_out() {
        let c = circle();
        let plane = Plane { normal: DVec3::Y, offset: 0.0 };
        let (from, to) = (DVec3::new(0.2, 0.0, 0.0), DVec3::new(-0.2, 0.0, 0.0));
        // half way from +x to −x by the +z side, 5 mm out: (0, 0, 0.105)
        let (_, p) = on_curve_point(&c, &plane, (from, to, DVec3::new(0.0, 0.0, 1.0)), 0.5, 0.005).unwrap();
        assert!(p.distance(DVec3::new(0.0, 0.0, 0.105)) < 1e-4, "{p}");
        // by the −z side, a quarter of the way: at −45°
        let (_, q) = on_curve_point(&c, &plane, (from, to, DVec3::new(0.0, 0.0, -1.0)), 0.25, 0.0).unwrap();
        let at = DVec3::new(0.1 * 45f64.to_radians().cos(), 0.0, -0.1 * 45f64.to_radians().sin());
        assert!(q.distance(at) < 1e-4, "{q}");
        // a loop without length places nothing
        assert!(
            on_curve_point(&Polyline::new(vec![DVec3::ZERO; 3], true), &plane, (from, to, from), 0.5, 0.0).is_none()
        );
    }
}
