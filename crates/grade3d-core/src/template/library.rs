//! The built-in template library: its authoring (`cargo xtask data templates`
//! writes `templates/garments/*.json`) and its loading at start-up.
//!
//! Templates are authored on a **reference body** — the embedded mannequin
//! with gender 0 (female) and every other parameter neutral — from that
//! body's feature curves: rings of nodes on the girths (eased outwards in
//! the girth's plane by the offset that adds `ease` to its tape length,
//! [`super::girth::ring_radial`]; decoding places them the same way on every
//! body, [`super::girth`]), vertical
//! node columns on the centre and side lines, and profiles sampled along
//! the eased girths and lines. The nodes are then encoded by seed 000
//! Eq. (1) ([`super::codec::encode`]).
//!
//! Ease (garment girth − body girth) is stated in each template's
//! `ease_mm`; the defaults follow common pattern-making allowances for a
//! fitted woven garment (waist 10 mm, hip 40 mm).

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::codec::{drop_axis, drop_position, encode, on_curve_point, CodecError, Draft, DraftPanel, DraftSeam};
use super::format::{Drop, Hang, OnCurve, Template, TemplateError};
use super::girth;
use crate::body::derive::{derive_features, DeriveOptions, FeatureError};
use crate::body::feature::FeatureBody;
use crate::body::vocab::{CurveId, PointId};
use crate::geom::plane::Plane;
use crate::geom::polyline::Polyline;
use crate::mannequin::landmarks::{hm08_landmarks, LandmarkError};
use crate::mannequin::model::{BodyModel, MannequinError, MannequinParams};

/// The built-in template documents, in the repository under `templates/garments/`.
const BUILTIN: &[(&str, &str)] = &[
    ("straight-skirt", include_str!("../../../../templates/garments/straight-skirt.json")),
    ("trousers", include_str!("../../../../templates/garments/trousers.json")),
    ("fitted-bodice", include_str!("../../../../templates/garments/fitted-bodice.json")),
    ("a-line-skirt", include_str!("../../../../templates/garments/a-line-skirt.json")),
];

/// Loads and validates every built-in template.
pub fn builtin() -> Result<Vec<Template>, (String, TemplateError)> {
    BUILTIN.iter().map(|(name, text)| Template::from_json(text).map_err(|e| ((*name).to_owned(), e))).collect()
}

/// Why authoring failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AuthorError {
    /// The reference body could not be built.
    #[error(transparent)]
    Mannequin(#[from] MannequinError),
    /// Its landmarks could not be found.
    #[error(transparent)]
    Landmark(#[from] LandmarkError),
    /// Its features could not be derived.
    #[error(transparent)]
    Feature(#[from] FeatureError),
    /// A curve or point the style needs is missing.
    #[error("the reference body lacks `{0}`")]
    Missing(String),
    /// Encoding failed.
    #[error(transparent)]
    Codec(#[from] CodecError),
    /// A style drawn as curves (issue #18 item 2) could not be sampled.
    #[error(transparent)]
    Curves(#[from] super::from_curves::FromCurvesError),
    /// A style authored from its garment (issue #18 item 1) could not be.
    #[error(transparent)]
    Garment(#[from] Box<super::from_garment::FromGarmentError>),
    /// A chart size's mannequin could not be fitted (a design body).
    #[error(transparent)]
    Fit(#[from] crate::mannequin::fit::FitError),
}

/// The reference body templates are authored on.
pub fn reference_body() -> Result<FeatureBody, AuthorError> {
    let model = BodyModel::embedded()?;
    let mut params = MannequinParams::default();
    params.macros.gender = 0.0;
    let mesh = model.build(&params)?;
    let lm = hm08_landmarks(model, &mesh, &Default::default())?;
    Ok(derive_features(mesh, &lm, &DeriveOptions::default())?)
}

/// Knobs of the straight skirt.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SkirtOptions {
    /// Waist ease, mm. Default 10.
    pub waist_ease_mm: f64,
    /// Hip ease, mm. Default 40.
    pub hip_ease_mm: f64,
    /// Hem below the hip line, m. Default 0.35.
    pub length_below_hip_m: f64,
    /// Outward flare of the hem beyond the eased hip, mm (clears the
    /// mannequin's spread legs). Default 60.
    pub hem_flare_mm: f64,
    /// Attached points per profile. Default 7.
    pub profile_points: usize,
}

impl Default for SkirtOptions {
    fn default() -> Self {
        Self { waist_ease_mm: 10.0, hip_ease_mm: 40.0, length_below_hip_m: 0.35, hem_flare_mm: 60.0, profile_points: 7 }
    }
}

const MM: f64 = 1e-3;

macro_rules! torso_ring {
    ($f:ident, $fl:ident, $l:ident, $bl:ident, $b:ident, $br:ident, $r:ident, $fr:ident) => {
        [PointId::$f, PointId::$fl, PointId::$l, PointId::$bl, PointId::$b, PointId::$br, PointId::$r, PointId::$fr]
    };
}

/// Ring nodes of the torso girths: front, front-left, left, back-left,
/// back, back-right, right, front-right (anticlockwise seen from above).
const NECK_RING: [PointId; 8] =
    torso_ring!(NeckFront, NeckFrontLeft, NeckLeft, NeckBackLeft, NeckBack, NeckBackRight, NeckRight, NeckFrontRight);
const CHEST_RING: [PointId; 8] = torso_ring!(
    ChestFront,
    ChestFrontLeft,
    UnderarmLeft,
    ChestBackLeft,
    ChestBack,
    ChestBackRight,
    UnderarmRight,
    ChestFrontRight
);
const BUST_RING: [PointId; 8] =
    torso_ring!(BustFront, BustFrontLeft, BustLeft, BustBackLeft, BustBack, BustBackRight, BustRight, BustFrontRight);
const WAIST_RING: [PointId; 8] = torso_ring!(
    WaistFront,
    WaistFrontLeft,
    WaistLeft,
    WaistBackLeft,
    WaistBack,
    WaistBackRight,
    WaistRight,
    WaistFrontRight
);
const HIP_RING: [PointId; 8] =
    torso_ring!(HipFront, HipFrontLeft, HipLeft, HipBackLeft, HipBack, HipBackRight, HipRight, HipFrontRight);

/// A ring of nodes on a girth: node ids, the girth, their arc parameters
/// and the radial ease offset.
#[derive(Debug, Clone)]
struct Ring {
    nodes: Vec<u32>,
    curve: Polyline,
    params: Vec<f64>,
    radial: f64,
    /// The plane the ring is eased in (the girth's: [`girth::girth_plane`]).
    plane: Plane,
}

/// Incremental construction of a [`Draft`] on the reference body.
struct Builder<'a> {
    body: &'a FeatureBody,
    draft: Draft,
    profile_points: usize,
}

impl<'a> Builder<'a> {
    fn new(body: &'a FeatureBody, profile_points: usize) -> Self {
        Self { body, draft: Draft::default(), profile_points: profile_points.max(2) }
    }

    fn point(&self, id: PointId) -> Result<DVec3, AuthorError> {
        self.body.points.get(&id).map(|p| p.position).ok_or_else(|| AuthorError::Missing(id.to_string()))
    }

    fn curve(&self, id: CurveId) -> Result<&Polyline, AuthorError> {
        self.body.curves.get(&id).map(|c| &c.polyline).ok_or_else(|| AuthorError::Missing(id.to_string()))
    }

    fn node(&mut self, p: DVec3, tie: Option<PointId>) -> u32 {
        self.draft.positions.push(p);
        self.draft.ties.push(tie);
        (self.draft.positions.len() - 1) as u32
    }

    /// A ring on girth `curve` with a node at each feature point of
    /// `points` (in the girth's direction: anticlockwise seen from above),
    /// each tied to its point and eased outwards by [`girth::ring_radial`]. Every
    /// ring edge gets a profile along the eased girth.
    fn ring(&mut self, curve: CurveId, points: &[PointId], ease_mm: f64) -> Result<Ring, AuthorError> {
        self.ring_through(curve, points, ease_mm, None)
    }

    /// [`Self::ring`], its node `k` replaced by the existing node `node`
    /// when `through` is `Some((k, node))`: the ring's arcs to and from it
    /// are bent (by a linear blend along the arc) to end there.
    fn ring_through(
        &mut self,
        curve: CurveId,
        points: &[PointId],
        ease_mm: f64,
        through: Option<(usize, u32)>,
    ) -> Result<Ring, AuthorError> {
        let plane = girth::girth_plane(self.body, curve).ok_or_else(|| AuthorError::Missing(curve.to_string()))?;
        let loop_ = girth::bridged(self.curve(curve)?, &plane);
        let mut params = Vec::with_capacity(points.len());
        for (k, id) in points.iter().enumerate() {
            // the node off the girth sits at the loop's point nearest to it, as decoding finds it
            let p = match through {
                Some((at, node)) if at == k => self.draft.positions[node as usize],
                _ => self.point(*id)?,
            };
            params.push(loop_.closest(p).map_or(0.0, |c| c.s));
        }
        // the declared ease on the tape of the ring as its profiles sample it, a node
        // off the girth (the crotch) included
        let ends: Vec<Option<DVec3>> = (0..points.len())
            .map(|k| through.and_then(|(at, node)| (k == at).then(|| self.draft.positions[node as usize])))
            .collect();
        let counts = vec![self.profile_points; points.len()];
        let radial = girth::sampled_radial(&loop_, &plane, ease_mm * MM, &params, &ends, &counts, &[])
            .max(girth::ring_radial(&loop_, &plane, ease_mm * MM));
        let nodes: Vec<u32> = params
            .iter()
            .zip(points)
            .enumerate()
            .map(|(k, (&t, &tie))| match through {
                Some((at, node)) if at == k => node,
                _ => self.node(girth::eased(&loop_, t, radial, &plane), Some(tie)),
            })
            .collect();
        let arcs = girth::ring_arcs(&loop_, &plane, &params, &ends, &counts, &[], radial);
        let ring = Ring { nodes, curve: loop_, params, radial, plane };
        for (i, pts) in arcs.into_iter().enumerate() {
            let j = (i + 1) % ring.nodes.len();
            self.draft.profiles.push(((ring.nodes[i], ring.nodes[j]), pts));
        }
        Ok(ring)
    }

    /// Profile points along a ring's eased girth from `s0` forward to `s1`.
    fn ring_arc(&self, ring: &Ring, s0: f64, s1: f64) -> Vec<DVec3> {
        let d = (s1 - s0).rem_euclid(ring.curve.length());
        girth::eased_arc(&ring.curve, &ring.plane, s0, d, self.profile_points, ring.radial, (None, None))
    }

    /// A profile along a feature line between the nodes `a` and `b`,
    /// sampled between the line's points nearest to them and moved outward
    /// along the body normal by the nodes' own distance from the body.
    fn line_profile(&mut self, a: u32, b: u32, line: CurveId) -> Result<(), AuthorError> {
        self.profile_along(a, b, line, None)
    }

    /// Every node of `ring` hangs straight between the same-index nodes of
    /// `upper` and `lower` ([`Hang`]).
    fn hang(&mut self, ring: &Ring, upper: &Ring, lower: &Ring) {
        for ((&node, &up), &low) in ring.nodes.iter().zip(&upper.nodes).zip(&lower.nodes) {
            self.draft.hangs.push(Hang { node, upper: up, lower: low });
        }
    }

    /// [`Self::line_profile`] along the line bridged as a tape (or cloth)
    /// pressed on it from outside bridges it: between the points nearest
    /// the nodes, the line is replaced by its convex hull on the side away
    /// from `interior`, in the plane of the line's chord and the vertical
    /// (a crotch seam does not follow the body into the groove between the
    /// thighs, a back seam does not follow the gluteal cleft).
    fn bridged_line_profile(&mut self, a: u32, b: u32, line: CurveId, interior: DVec3) -> Result<(), AuthorError> {
        self.profile_along(a, b, line, Some(interior))
    }

    /// The profile of [`Self::line_profile`], its line bridged away from
    /// `bridge_from` when given ([`Self::bridged_line_profile`]).
    fn profile_along(&mut self, a: u32, b: u32, line: CurveId, bridge_from: Option<DVec3>) -> Result<(), AuthorError> {
        let poly = self.curve(line)?.clone();
        let (pa, pb) = (self.draft.positions[a as usize], self.draft.positions[b as usize]);
        let (Some(ca), Some(cb)) = (poly.closest(pa), poly.closest(pb)) else {
            return Err(AuthorError::Missing(format!("{line} near nodes {a}–{b}")));
        };
        // the path from the point nearest `a` to the point nearest `b`, and its arc-length span
        let (path, s0, s1) = match bridge_from {
            None => (poly, ca.s, cb.s),
            Some(interior) => {
                let hull = outer_hull(&poly, ca.s, cb.s, interior);
                let total = hull.length();
                (hull, 0.0, total)
            }
        };
        let (oa, ob) = (pa - ca.point, pb - cb.point);
        let n = self.profile_points;
        let pts = (0..n)
            .map(|k| {
                let t = k as f64 / (n - 1) as f64;
                path.point_at(s0 + (s1 - s0) * t) + oa.lerp(ob, t)
            })
            .collect();
        self.draft.profiles.push(((a, b), pts));
        Ok(())
    }

    fn tri(&mut self, a: u32, b: u32, c: u32) -> usize {
        self.draft.triangles.push([a, b, c]);
        self.draft.triangles.len() - 1
    }

    /// Two triangles `[a, b, c]`, `[a, c, d]`; returns their indices.
    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32) -> [usize; 2] {
        [self.tri(a, b, c), self.tri(a, c, d)]
    }

    /// Quads between two rings of equal length, column `i` joining ring
    /// nodes `i` and `i + 1`; returns the triangles of each column. The
    /// diagonals mirror across the body's mid-sagittal plane (issue #14:
    /// mirror pairs): a column on the body's left (+X of the centre front)
    /// is split by `upper_i – lower_j`, one on its right by `upper_j –
    /// lower_i`, so that a right piece is refined as the mirror image of
    /// its left one (the same diagonal everywhere gave the right half
    /// another triangulation, other found darts and another flattening).
    fn band(&mut self, upper: &Ring, lower: &Ring) -> Vec<[usize; 2]> {
        let n = upper.nodes.len();
        let mid_x = self.body.points.get(&PointId::WaistFront).map_or(0.0, |q| q.position.x);
        (0..n)
            .map(|i| {
                let j = (i + 1) % n;
                let (ui, uj, lj, li) = (upper.nodes[i], upper.nodes[j], lower.nodes[j], lower.nodes[i]);
                let x = [ui, uj, lj, li].iter().map(|&v| self.draft.positions[v as usize].x).sum::<f64>() / 4.0;
                if x >= mid_x {
                    self.quad(ui, uj, lj, li)
                } else {
                    self.quad(uj, lj, li, ui)
                }
            })
            .collect()
    }

    /// Orients every triangle consistently (breadth-first over shared
    /// edges) and outwards: the area-weighted vote of each triangle's
    /// normal against the body normal at the closest body point.
    fn orient(&mut self) {
        let tris = &mut self.draft.triangles;
        let mut by_edge: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
        for (f, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                by_edge.entry((a.min(b), a.max(b))).or_default().push(f);
            }
        }
        let has_dir = |t: &[u32; 3], a: u32, b: u32| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
        let mut done = vec![false; tris.len()];
        for seed in 0..tris.len() {
            if done[seed] {
                continue;
            }
            done[seed] = true;
            let mut queue = std::collections::VecDeque::from([seed]);
            while let Some(f) = queue.pop_front() {
                let t = tris[f];
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    for &g in &by_edge[&(a.min(b), a.max(b))] {
                        if g == f || done[g] {
                            continue;
                        }
                        if has_dir(&tris[g], a, b) {
                            tris[g].swap(1, 2);
                        }
                        done[g] = true;
                        queue.push_back(g);
                    }
                }
            }
        }
        let pos = &self.draft.positions;
        let mesh = &self.body.mesh;
        let vote: f64 = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| pos[v as usize]);
                let n = (b - a).cross(c - a);
                let body = crate::geom::query::closest_point(mesh, (a + b + c) / 3.0);
                n.dot(mesh.face_area_vector(body.face).normalize_or_zero())
            })
            .sum();
        if vote < 0.0 {
            for t in tris.iter_mut() {
                t.swap(1, 2);
            }
        }
    }

    fn panel(&mut self, name: &str, triangles: Vec<usize>, grain: (u32, u32)) {
        self.draft.panels.push(DraftPanel { name: name.to_owned(), triangles, grain, stack: None, quantity: 1 });
    }

    fn seam(&mut self, name: &str, a: &str, b: &str, nodes: Vec<u32>) {
        self.draft.seams.push(DraftSeam { name: name.into(), panel_a: a.into(), panel_b: b.into(), nodes });
    }
}

/// Arc `s0 → s1` of `line` (64 samples) replaced by its convex hull on the
/// side away from `interior`, in the plane of the arc's chord and the
/// vertical: a monotone chain along the chord, turning one way only.
fn outer_hull(line: &Polyline, s0: f64, s1: f64, interior: DVec3) -> Polyline {
    const SAMPLES: usize = 64;
    let pts: Vec<DVec3> = (0..=SAMPLES).map(|k| line.point_at(s0 + (s1 - s0) * k as f64 / SAMPLES as f64)).collect();
    let (first, last) = (pts[0], pts[SAMPLES]);
    let u = (last - first).normalize_or_zero();
    let mut n = u.cross(DVec3::Y.cross(u)).normalize_or_zero();
    if n.length_squared() == 0.0 {
        n = DVec3::Z;
    }
    if n.dot(interior - (first + last) / 2.0) > 0.0 {
        n = -n;
    }
    let key = |q: DVec3| DVec2::new((q - first).dot(u), (q - first).dot(n));
    let mut chain: Vec<DVec3> = Vec::new();
    for p in pts {
        // drop the last point while it lies on or inside the line from the one before to p
        while let [.., o, m] = chain[..] {
            if (key(m) - key(o)).perp_dot(key(p) - key(o)) >= 0.0 {
                chain.pop();
            } else {
                break;
            }
        }
        chain.push(p);
    }
    Polyline::new(chain, false)
}

/// Authors the straight skirt: waist, hip and hem rings of 8 nodes, front
/// and back panels, side seams, profiles on the waist opening, hip line,
/// hem, and on the centre and side lines between waist and hip.
pub fn straight_skirt(body: &FeatureBody, o: &SkirtOptions) -> Result<Template, AuthorError> {
    let mut b = Builder::new(body, o.profile_points);
    let waist = b.ring(CurveId::Waist, &WAIST_RING, o.waist_ease_mm)?;
    let hip = b.ring(CurveId::Hip, &HIP_RING, o.hip_ease_mm)?;
    // Hem nodes drop 35 cm below the hip nodes, perpendicular to the hip
    // girth's plane, and flare outwards within it ([`Drop`]): as decoding
    // places them, so that decode ∘ encode is exact here. (Tied by Eq. (1)
    // to hip points, a 35 cm offset along a tangent a few degrees off the
    // vertical threw the hem by centimetres on other bodies.)
    let up = drop_axis(body, CurveId::Hip).ok_or_else(|| AuthorError::Missing("hip".into()))?;
    let hip_c = hip.nodes.iter().map(|&v| b.draft.positions[v as usize]).sum::<DVec3>() / hip.nodes.len() as f64;
    let (length, flare) = (o.length_below_hip_m, o.hem_flare_mm * MM);
    let hem_of = |p: DVec3| drop_position(p, up, hip_c, length, flare);
    let hem_nodes: Vec<u32> = hip
        .nodes
        .iter()
        .zip(HIP_RING)
        .map(|(&v, point)| {
            let p = b.draft.positions[v as usize];
            let node = b.node(hem_of(p), Some(point));
            b.draft.drops.push(Drop { node, from: v, girth: CurveId::Hip, length_m: length, flare_m: flare });
            node
        })
        .collect();
    for i in 0..8 {
        let j = (i + 1) % 8;
        let pts: Vec<DVec3> = b.ring_arc(&hip, hip.params[i], hip.params[j]).into_iter().map(hem_of).collect();
        b.draft.profiles.push(((hem_nodes[i], hem_nodes[j]), pts));
    }
    let hem = Ring { nodes: hem_nodes, ..hip.clone() };
    // on a body whose waist stands further out than its hip (a belly), the skirt
    // hangs straight from the waist past the hip
    b.hang(&hip, &waist, &hem);
    let upper = b.band(&waist, &hip);
    let lower = b.band(&hip, &hem);
    for (col, line) in
        [(0, CurveId::CentreFront), (2, CurveId::SideLineLeft), (4, CurveId::CentreBack), (6, CurveId::SideLineRight)]
    {
        b.line_profile(waist.nodes[col], hip.nodes[col], line)?;
    }
    b.orient();
    let cols = |c: [usize; 4]| -> Vec<usize> { c.iter().flat_map(|&i| upper[i].into_iter().chain(lower[i])).collect() };
    // grain down the centre line below the hip, where the skirt hangs straight; its
    // upper end, on the hip line, is the stack point: a graded nest grows both ways
    // from the hip, as a pattern maker stacks a skirt (waist up, hem down)
    b.panel("front", cols([6, 7, 0, 1]), (hip.nodes[0], hem.nodes[0]));
    b.panel("back", cols([2, 3, 4, 5]), (hip.nodes[4], hem.nodes[4]));
    b.seam("side_left", "front", "back", vec![waist.nodes[2], hip.nodes[2], hem.nodes[2]]);
    b.seam("side_right", "back", "front", vec![waist.nodes[6], hip.nodes[6], hem.nodes[6]]);
    b.draft.notches = vec![("hip".into(), hip.nodes[2]), ("hip".into(), hip.nodes[6])];
    // waist darts from the oblique waist points to the hip line, where the flattening
    // measured the strain gathering (issue #5); a body that wants none drops them
    b.draft.darts =
        [("front_left", "front", 1), ("front_right", "front", 7), ("back_left", "back", 3), ("back_right", "back", 5)]
            .iter()
            .map(|&(name, panel, k)| (format!("dart_{name}"), panel.to_string(), vec![waist.nodes[k], hip.nodes[k]]))
            .collect();
    b.draft.name = "straight-skirt".into();
    b.draft.version = 2;
    b.draft.description = "Straight skirt with a slight hem flare: waistband line, hip line and hem; front and back \
                           panels joined by side seams."
        .into();
    b.draft.ease_mm = BTreeMap::from([
        ("waist".to_owned(), o.waist_ease_mm),
        ("hip".to_owned(), o.hip_ease_mm),
        ("hem_flare_radial".to_owned(), o.hem_flare_mm),
    ]);
    Ok(encode(&b.draft, body)?)
}

/// Knobs of the fitted bodice.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BodiceOptions {
    /// Neck base ease, mm. Default 20.
    pub neck_ease_mm: f64,
    /// Chest (armpit level) ease, mm. Default 60.
    pub chest_ease_mm: f64,
    /// Bust ease, mm. Default 80.
    pub bust_ease_mm: f64,
    /// Waist ease, mm. Default 50.
    pub waist_ease_mm: f64,
    /// Armhole ease (added to the armscye girth), mm. Default 40.
    pub armhole_ease_mm: f64,
    /// Lift of the shoulder seam off the shoulder, mm. Default 4.
    pub shoulder_lift_mm: f64,
    /// Attached points per profile. Default 7.
    pub profile_points: usize,
}

impl Default for BodiceOptions {
    fn default() -> Self {
        Self {
            neck_ease_mm: 20.0,
            chest_ease_mm: 60.0,
            bust_ease_mm: 80.0,
            waist_ease_mm: 50.0,
            armhole_ease_mm: 40.0,
            shoulder_lift_mm: 4.0,
            profile_points: 7,
        }
    }
}

/// Authors the fitted bodice (a shell top to the waist): neck, chest, bust
/// and waist rings, shoulder points, armholes following the armscyes;
/// front and back panels; side and shoulder seams.
pub fn fitted_bodice(body: &FeatureBody, o: &BodiceOptions) -> Result<Template, AuthorError> {
    use PointId as P;
    let mut b = Builder::new(body, o.profile_points);
    let neck = b.ring(CurveId::NeckBase, &NECK_RING, o.neck_ease_mm)?;
    let chest = b.ring(CurveId::Chest, &CHEST_RING, o.chest_ease_mm)?;
    let bust = b.ring(CurveId::Bust, &BUST_RING, o.bust_ease_mm)?;
    let waist = b.ring(CurveId::Waist, &WAIST_RING, o.waist_ease_mm)?;
    let mut front = Vec::new();
    let mut back = Vec::new();
    let mut shoulders = Vec::new();
    // upper torso, per side: (neck column of the side neck point, chest column of the armpit)
    for (side, col, armscye, shoulder) in
        [(0usize, 2usize, CurveId::ArmscyeLeft, P::ShoulderLeft), (1, 6, CurveId::ArmscyeRight, P::ShoulderRight)]
    {
        let sp = b.point(shoulder)?;
        let n = b.body.points[&shoulder].frame.n;
        let sl = b.node(sp + n * (o.shoulder_lift_mm * MM), Some(shoulder));
        shoulders.push(sl);
        // armhole nodes midway along the armscye, front and back of the arm,
        // between the shoulder point and the armscye point nearest the armpit
        // point: placed there on every body (`OnCurve`), not by Eq. (1)
        let loop_ = b.curve(armscye)?.clone();
        let total = loop_.length();
        let underarm = if side == 0 { P::UnderarmLeft } else { P::UnderarmRight };
        let up = b.point(underarm)?;
        let s_top = loop_.closest(sp).map_or(0.0, |c| c.s);
        let s_low = loop_.closest(up).map_or(0.0, |c| c.s);
        let radial = o.armhole_ease_mm * MM / std::f64::consts::TAU;
        let plane = girth::girth_plane(b.body, armscye).ok_or_else(|| AuthorError::Missing(armscye.to_string()))?;
        let on_armhole = |b: &mut Builder, via: PointId| -> Result<(u32, f64), AuthorError> {
            let v = b.point(via)?;
            let (s, p) = on_curve_point(&loop_, &plane, (sp, up, v), 0.5, radial)
                .ok_or_else(|| AuthorError::Missing(armscye.to_string()))?;
            let node = b.node(p, None);
            b.draft.on_curve.push(OnCurve {
                node,
                curve: armscye,
                from: shoulder,
                to: underarm,
                via,
                fraction: 0.5,
                radial_m: radial,
                normal_m: 0.0,
            });
            Ok((node, s))
        };
        let (af, s_front) = on_armhole(&mut b, P::ChestFront)?;
        let (ab, s_back) = on_armhole(&mut b, P::ChestBack)?;
        let ul = chest.nodes[col];
        let ul_pos = b.draft.positions[ul as usize];
        // the armhole's edges along the eased armscye, the shorter way round (decoding samples
        // them again on every body: `codec::refit_on_curve_edges`)
        let arc = |b: &Builder, s0: f64, s1: f64| -> Vec<DVec3> {
            girth::eased_arc(
                &loop_,
                &plane,
                s0,
                girth::shorter_way(s0, s1, total),
                b.profile_points,
                radial,
                (None, None),
            )
        };
        let p_top = arc(&b, s_top, s_front);
        b.draft.profiles.push(((sl, af), p_top));
        let mut p_low = arc(&b, s_front, s_low);
        p_low.push(ul_pos);
        b.draft.profiles.push(((af, ul), p_low));
        let mut p_low_b = arc(&b, s_low, s_back);
        p_low_b.insert(0, ul_pos);
        b.draft.profiles.push(((ul, ab), p_low_b));
        let p_top_b = arc(&b, s_back, s_top);
        b.draft.profiles.push(((ab, sl), p_top_b));
        // faces; `f`/`k` are the neck and chest nodes on the front and back side of this armhole
        let (nf, nk) = if side == 0 { (neck.nodes[1], chest.nodes[1]) } else { (neck.nodes[7], chest.nodes[7]) };
        let (nb, kb) = if side == 0 { (neck.nodes[3], chest.nodes[3]) } else { (neck.nodes[5], chest.nodes[5]) };
        let nl = neck.nodes[col];
        front.extend([b.tri(nf, nl, sl), b.tri(nf, sl, af), b.tri(nf, af, nk), b.tri(nk, af, ul)]);
        back.extend([b.tri(nb, nl, sl), b.tri(nb, sl, ab), b.tri(nb, ab, kb), b.tri(kb, ab, ul)]);
        b.line_profile(nl, sl, if side == 0 { CurveId::ShoulderLineLeft } else { CurveId::ShoulderLineRight })?;
    }
    // centre front/back quads between the neck and chest rings
    let (n, k) = (&neck.nodes, &chest.nodes);
    front.extend(b.quad(n[7], n[0], k[0], k[7]));
    front.extend(b.quad(n[0], n[1], k[1], k[0]));
    back.extend(b.quad(n[3], n[4], k[4], k[3]));
    back.extend(b.quad(n[4], n[5], k[5], k[4]));
    let upper = b.band(&chest, &bust);
    let lower = b.band(&bust, &waist);
    for c in [6usize, 7, 0, 1] {
        front.extend(upper[c].into_iter().chain(lower[c]));
    }
    for c in [2usize, 3, 4, 5] {
        back.extend(upper[c].into_iter().chain(lower[c]));
    }
    for (col, line) in [(0usize, CurveId::CentreFront), (4, CurveId::CentreBack)] {
        b.line_profile(neck.nodes[col], chest.nodes[col], line)?;
        b.line_profile(chest.nodes[col], bust.nodes[col], line)?;
        b.line_profile(bust.nodes[col], waist.nodes[col], line)?;
    }
    for (col, line) in [(2usize, CurveId::SideLineLeft), (6, CurveId::SideLineRight)] {
        b.line_profile(chest.nodes[col], bust.nodes[col], line)?;
        b.line_profile(bust.nodes[col], waist.nodes[col], line)?;
    }
    b.orient();
    b.panel("front", front, (neck.nodes[0], waist.nodes[0]));
    b.panel("back", back, (neck.nodes[4], waist.nodes[4]));
    b.seam("side_left", "front", "back", vec![chest.nodes[2], bust.nodes[2], waist.nodes[2]]);
    b.seam("side_right", "back", "front", vec![chest.nodes[6], bust.nodes[6], waist.nodes[6]]);
    b.seam("shoulder_left", "front", "back", vec![neck.nodes[2], shoulders[0]]);
    b.seam("shoulder_right", "back", "front", vec![neck.nodes[6], shoulders[1]]);
    b.draft.notches = vec![("bust".into(), bust.nodes[2]), ("bust".into(), bust.nodes[6])];
    b.draft.name = "fitted-bodice".into();
    b.draft.version = 1;
    b.draft.description = "Fitted bodice (shell top) to the waist: neckline, shoulders, armholes, bust and waist; \
                           front and back panels joined by side and shoulder seams."
        .into();
    b.draft.ease_mm = BTreeMap::from([
        ("neck_base".to_owned(), o.neck_ease_mm),
        ("chest".to_owned(), o.chest_ease_mm),
        ("bust".to_owned(), o.bust_ease_mm),
        ("waist".to_owned(), o.waist_ease_mm),
        ("armscye".to_owned(), o.armhole_ease_mm),
    ]);
    Ok(encode(&b.draft, body)?)
}

/// Knobs of the trousers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrouserOptions {
    /// Waist ease, mm. Default 10.
    pub waist_ease_mm: f64,
    /// Hip ease, mm. Default 50.
    pub hip_ease_mm: f64,
    /// Thigh ease, mm. Default 70.
    pub thigh_ease_mm: f64,
    /// Least knee ease, mm: the leg hangs straight from the thigh to the hem
    /// (the knee nodes on the straight lines between), and the knee nodes are
    /// moved out to this ease over the knee girth only where those lines pass
    /// closer. Default 60.
    pub knee_ease_mm: f64,
    /// Hem ease over the ankle girth, mm. Default 200.
    pub hem_ease_mm: f64,
    /// Crotch depth ease: how far the crotch node sits below the crotch point, mm. Default 15.
    pub crotch_drop_mm: f64,
    /// Attached points per profile. Default 7.
    pub profile_points: usize,
}

impl Default for TrouserOptions {
    fn default() -> Self {
        Self {
            waist_ease_mm: 10.0,
            hip_ease_mm: 50.0,
            thigh_ease_mm: 70.0,
            knee_ease_mm: 60.0,
            hem_ease_mm: 200.0,
            crotch_drop_mm: 15.0,
            profile_points: 7,
        }
    }
}

/// Authors straight trousers: waist and hip rings, crotch node, thigh,
/// knee and hem rings per leg; front and back panels per leg; side,
/// inside-leg and crotch seams. Each thigh ring runs through the crotch
/// node in place of its inner point, so the four seams meet there as in a
/// cut pair of trousers: where the thighs touch, the inner point lies a few
/// millimetres from the crotch node (male-average fixture: 7 mm), and a
/// triangle between them and the thigh front subdivided into needles that
/// folded (front p95 strain 4.1 % with it, 2.5 % without).
pub fn trousers(body: &FeatureBody, o: &TrouserOptions) -> Result<Template, AuthorError> {
    use PointId as P;
    let mut b = Builder::new(body, o.profile_points);
    let waist = b.ring(CurveId::Waist, &WAIST_RING, o.waist_ease_mm)?;
    let hip = b.ring(CurveId::Hip, &HIP_RING, o.hip_ease_mm)?;
    let cp = b.point(P::Crotch)?;
    let c = b.node(cp - DVec3::Y * (o.crotch_drop_mm * MM), Some(P::Crotch));
    let torso = b.band(&waist, &hip);
    let h = hip.nodes.clone();
    let mut panels: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    let mut legs = Vec::new();
    for (side, name_f, name_b) in [(0usize, "left_front", "left_back"), (1, "right_front", "right_back")] {
        // rings from the outer point, anticlockwise seen from above
        let (thigh, knee, ankle) = if side == 0 {
            (
                (CurveId::ThighLeft, [P::ThighLeft, P::ThighLeftBack, P::ThighLeftInner, P::ThighLeftFront]),
                (CurveId::KneeLeft, [P::KneeLeft, P::KneeLeftBack, P::KneeLeftInner, P::KneeLeftFront]),
                (CurveId::AnkleLeft, [P::AnkleLeft, P::AnkleLeftBack, P::AnkleLeftInner, P::AnkleLeftFront]),
            )
        } else {
            (
                (CurveId::ThighRight, [P::ThighRight, P::ThighRightFront, P::ThighRightInner, P::ThighRightBack]),
                (CurveId::KneeRight, [P::KneeRight, P::KneeRightFront, P::KneeRightInner, P::KneeRightBack]),
                (CurveId::AnkleRight, [P::AnkleRight, P::AnkleRightFront, P::AnkleRightInner, P::AnkleRightBack]),
            )
        };
        // the thigh ring's inner node is the crotch node: the inside-leg seams start there
        let t = b.ring_through(thigh.0, &thigh.1, o.thigh_ease_mm, Some((2, c)))?;
        let k = b.ring(knee.0, &knee.1, o.knee_ease_mm)?;
        let a = b.ring(ankle.0, &ankle.1, o.hem_ease_mm)?;
        b.hang(&k, &t, &a);
        // ring order from the outer point: left leg outer, back, inner, front; right leg outer, front, inner, back
        let (to, ti) = (t.nodes[0], t.nodes[2]);
        let (tf, tb) = if side == 0 { (t.nodes[3], t.nodes[1]) } else { (t.nodes[1], t.nodes[3]) };
        let (front_cols, back_cols): ([usize; 2], [usize; 2]) =
            if side == 0 { ([2, 3], [0, 1]) } else { ([0, 1], [2, 3]) };
        let upper = b.band(&t, &k);
        let lower = b.band(&k, &a);
        let mut f = Vec::new();
        let mut bk = Vec::new();
        // junction between the hip ring and the thigh ring
        let (hf, hfs, hs, hbs, hb) =
            if side == 0 { (h[0], h[1], h[2], h[3], h[4]) } else { (h[0], h[7], h[6], h[5], h[4]) };
        f.extend(b.quad(hf, hfs, tf, c));
        f.extend(b.quad(hfs, hs, to, tf));
        bk.extend(b.quad(hs, hbs, tb, to));
        bk.extend(b.quad(hbs, hb, c, tb));
        for col in front_cols {
            f.extend(upper[col].into_iter().chain(lower[col]));
        }
        for col in back_cols {
            bk.extend(upper[col].into_iter().chain(lower[col]));
        }
        let torso_f: [usize; 2] = if side == 0 { [0, 1] } else { [6, 7] };
        let torso_b: [usize; 2] = if side == 0 { [2, 3] } else { [4, 5] };
        f.extend(torso_f.iter().flat_map(|&i| torso[i]));
        bk.extend(torso_b.iter().flat_map(|&i| torso[i]));
        let side_line = if side == 0 { CurveId::SideLineLeft } else { CurveId::SideLineRight };
        b.line_profile(waist.nodes[if side == 0 { 2 } else { 6 }], hs, side_line)?;
        b.line_profile(hs, to, side_line)?;
        b.line_profile(to, k.nodes[0], side_line)?;
        b.line_profile(k.nodes[0], a.nodes[0], side_line)?;
        panels.insert(name_f, f);
        panels.insert(name_b, bk);
        legs.push((t, k, a, to, ti, tf));
    }
    // the crotch seams bridge the groove between the thighs and the gluteal cleft
    let interior = hip.curve.centroid();
    b.line_profile(waist.nodes[0], h[0], CurveId::CentreFront)?;
    b.bridged_line_profile(h[0], c, CurveId::CentreFront, interior)?;
    b.line_profile(waist.nodes[4], h[4], CurveId::CentreBack)?;
    b.bridged_line_profile(h[4], c, CurveId::CentreBack, interior)?;
    b.orient();
    for (side, (_, k, a, _, _, _)) in legs.iter().enumerate() {
        let (nf, nb) = if side == 0 { ("left_front", "left_back") } else { ("right_front", "right_back") };
        let (kf, af, kb, ab) = if side == 0 {
            (k.nodes[3], a.nodes[3], k.nodes[1], a.nodes[1])
        } else {
            (k.nodes[1], a.nodes[1], k.nodes[3], a.nodes[3])
        };
        b.panel(nf, panels[nf].clone(), (kf, af));
        b.panel(nb, panels[nb].clone(), (kb, ab));
    }
    b.draft.mirror_pairs = vec![["left_front".into(), "right_front".into()], ["left_back".into(), "right_back".into()]];
    let (l, r) = (&legs[0], &legs[1]);
    b.seam("side_left", "left_front", "left_back", vec![waist.nodes[2], h[2], l.3, l.1.nodes[0], l.2.nodes[0]]);
    b.seam("side_right", "right_back", "right_front", vec![waist.nodes[6], h[6], r.3, r.1.nodes[0], r.2.nodes[0]]);
    b.seam("inseam_left", "left_back", "left_front", vec![c, l.1.nodes[2], l.2.nodes[2]]);
    b.seam("inseam_right", "right_front", "right_back", vec![c, r.1.nodes[2], r.2.nodes[2]]);
    b.seam("crotch_front", "right_front", "left_front", vec![waist.nodes[0], h[0], c]);
    b.seam("crotch_back", "left_back", "right_back", vec![waist.nodes[4], h[4], c]);
    b.draft.notches = vec![
        ("hip".into(), h[2]),
        ("hip".into(), h[6]),
        ("knee".into(), l.1.nodes[0]),
        ("knee".into(), l.1.nodes[2]),
        ("knee".into(), r.1.nodes[0]),
        ("knee".into(), r.1.nodes[2]),
        ("crotch".into(), c),
    ];
    b.draft.name = "trousers".into();
    b.draft.version = 1;
    b.draft.description = "Straight-leg trousers: waist, hip, crotch, thigh, knee and hem; front and back panels per \
                           leg joined by side, inside-leg and crotch seams."
        .into();
    b.draft.ease_mm = BTreeMap::from([
        ("waist".to_owned(), o.waist_ease_mm),
        ("hip".to_owned(), o.hip_ease_mm),
        ("thigh".to_owned(), o.thigh_ease_mm),
        ("knee".to_owned(), o.knee_ease_mm),
        ("hem_over_ankle".to_owned(), o.hem_ease_mm),
        ("crotch_drop".to_owned(), o.crotch_drop_mm),
    ]);
    Ok(encode(&b.draft, body)?)
}

/// Authors every built-in template on the reference body.
pub fn author_all() -> Result<Vec<Template>, AuthorError> {
    let body = reference_body()?;
    Ok(vec![
        straight_skirt(&body, &SkirtOptions::default())?,
        trousers(&body, &TrouserOptions::default())?,
        fitted_bodice(&body, &BodiceOptions::default())?,
        super::drawn::a_line_skirt(&body, &super::drawn::ALineOptions::default())?,
    ])
}
