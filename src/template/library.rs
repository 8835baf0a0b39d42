//! The built-in template library: its authoring (`grade3d data templates`
//! writes `templates/garments/*.json`) and its loading at start-up.
//!
//! Templates are authored on a **reference body** — the embedded mannequin
//! with gender 0 (female) and every other parameter neutral — from that
//! body's feature curves: rings of nodes on the girths (eased outwards by
//! `ease / 2π`, the radius increase that adds `ease` to a girth), vertical
//! node columns on the centre and side lines, and profiles sampled along
//! the eased girths and lines. The nodes are then encoded by seed 000
//! Eq. (1) ([`super::codec::encode`]).
//!
//! Ease (garment girth − body girth) is stated in each template's
//! `ease_mm`; the defaults follow common pattern-making allowances for a
//! fitted woven garment (waist 10 mm, hip 40 mm).

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::codec::{encode, CodecError, Draft, DraftPanel, DraftSeam};
use super::format::{Template, TemplateError};
use crate::body::derive::{derive_features, DeriveOptions, FeatureError};
use crate::body::feature::FeatureBody;
use crate::body::vocab::{CurveId, PointId};
use crate::geom::polyline::Polyline;
use crate::mannequin::landmarks::{hm08_landmarks, LandmarkError};
use crate::mannequin::model::{BodyModel, MannequinError, MannequinParams};

/// The built-in template documents, in the repository under `templates/garments/`.
const BUILTIN: &[(&str, &str)] = &[("straight-skirt", include_str!("../../templates/garments/straight-skirt.json"))];

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

/// A ring of nodes on a girth: node ids, the girth, their arc parameters
/// and the radial ease offset.
#[derive(Debug, Clone)]
struct Ring {
    nodes: Vec<u32>,
    curve: Polyline,
    params: Vec<f64>,
    radial: f64,
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

    /// A ring on girth `curve` through the `cardinal` points (in the girth's
    /// direction: anticlockwise seen from above), with a node midway (by
    /// arc length) between consecutive cardinals; eased outwards by
    /// `ease_mm / 2π`. Midway nodes are tied to the preceding cardinal.
    /// Every ring edge gets a profile along the eased girth.
    fn ring(&mut self, curve: CurveId, cardinal: &[PointId], ease_mm: f64) -> Result<Ring, AuthorError> {
        let loop_ = self.curve(curve)?.clone();
        let total = loop_.length();
        let mut s = Vec::new();
        for id in cardinal {
            let p = self.point(*id)?;
            s.push(loop_.closest(p).map_or(0.0, |c| c.s));
        }
        let fwd = |a: f64, b: f64| (b - a).rem_euclid(total);
        let k = s.len();
        let mut params = Vec::with_capacity(2 * k);
        let mut ties = Vec::with_capacity(2 * k);
        for i in 0..k {
            params.push(s[i]);
            ties.push(cardinal[i]);
            params.push((s[i] + 0.5 * fwd(s[i], s[(i + 1) % k])).rem_euclid(total));
            ties.push(cardinal[i]);
        }
        let radial = ease_mm * MM / std::f64::consts::TAU;
        let nodes: Vec<u32> =
            params.iter().zip(&ties).map(|(&t, &tie)| self.node(eased(&loop_, t, radial), Some(tie))).collect();
        let ring = Ring { nodes, curve: loop_, params, radial };
        for i in 0..ring.nodes.len() {
            let j = (i + 1) % ring.nodes.len();
            let pts = self.ring_arc(&ring, ring.params[i], ring.params[j]);
            self.draft.profiles.push(((ring.nodes[i], ring.nodes[j]), pts));
        }
        Ok(ring)
    }

    /// Profile points along a ring's eased girth from `s0` forward to `s1`.
    fn ring_arc(&self, ring: &Ring, s0: f64, s1: f64) -> Vec<DVec3> {
        let total = ring.curve.length();
        let d = (s1 - s0).rem_euclid(total);
        let n = self.profile_points;
        (0..n).map(|k| eased(&ring.curve, s0 + d * k as f64 / (n - 1) as f64, ring.radial)).collect()
    }

    /// A profile along a feature line between the nodes `a` and `b`,
    /// sampled between the line's points nearest to them and moved outward
    /// along the body normal by the nodes' own distance from the body.
    fn line_profile(&mut self, a: u32, b: u32, line: CurveId) -> Result<(), AuthorError> {
        let poly = self.curve(line)?.clone();
        let (pa, pb) = (self.draft.positions[a as usize], self.draft.positions[b as usize]);
        let (Some(ca), Some(cb)) = (poly.closest(pa), poly.closest(pb)) else {
            return Err(AuthorError::Missing(format!("{line} near nodes {a}–{b}")));
        };
        let (oa, ob) = (pa - ca.point, pb - cb.point);
        let n = self.profile_points;
        let pts = (0..n)
            .map(|k| {
                let t = k as f64 / (n - 1) as f64;
                poly.point_at(ca.s + (cb.s - ca.s) * t) + oa.lerp(ob, t)
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
    /// nodes `i` and `i + 1`; returns the triangles of each column.
    fn band(&mut self, upper: &Ring, lower: &Ring) -> Vec<[usize; 2]> {
        let n = upper.nodes.len();
        (0..n)
            .map(|i| {
                let j = (i + 1) % n;
                self.quad(upper.nodes[i], upper.nodes[j], lower.nodes[j], lower.nodes[i])
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
        self.draft.panels.push(DraftPanel { name: name.to_owned(), triangles, grain, quantity: 1 });
    }

    fn seam(&mut self, name: &str, a: &str, b: &str, nodes: Vec<u32>) {
        self.draft.seams.push(DraftSeam { name: name.into(), panel_a: a.into(), panel_b: b.into(), nodes });
    }
}

/// A point of a girth at arc length `s`, moved outwards horizontally (away
/// from the girth's centroid) by `radial`.
fn eased(loop_: &Polyline, s: f64, radial: f64) -> DVec3 {
    let p = loop_.point_at(s);
    let c = loop_.centroid();
    let out = DVec3::new(p.x - c.x, 0.0, p.z - c.z).normalize_or_zero();
    p + out * radial
}

/// Authors the straight skirt: waist, hip and hem rings of 8 nodes, front
/// and back panels, side seams, profiles on the waist opening, hip line,
/// hem, and on the centre and side lines between waist and hip.
pub fn straight_skirt(body: &FeatureBody, o: &SkirtOptions) -> Result<Template, AuthorError> {
    use PointId as P;
    let mut b = Builder::new(body, o.profile_points);
    let waist = b.ring(CurveId::Waist, &[P::WaistFront, P::WaistLeft, P::WaistBack, P::WaistRight], o.waist_ease_mm)?;
    let hip = b.ring(CurveId::Hip, &[P::HipFront, P::HipLeft, P::HipBack, P::HipRight], o.hip_ease_mm)?;
    let hip_c = hip.curve.centroid();
    let hem_of = |p: DVec3| -> DVec3 {
        let out = DVec3::new(p.x - hip_c.x, 0.0, p.z - hip_c.z).normalize_or_zero();
        p - DVec3::Y * o.length_below_hip_m + out * (o.hem_flare_mm * MM)
    };
    let hem_nodes: Vec<u32> = hip
        .nodes
        .iter()
        .map(|&v| {
            let (p, tie) = (b.draft.positions[v as usize], b.draft.ties[v as usize]);
            b.node(hem_of(p), tie)
        })
        .collect();
    for i in 0..8 {
        let j = (i + 1) % 8;
        let pts: Vec<DVec3> = b.ring_arc(&hip, hip.params[i], hip.params[j]).into_iter().map(hem_of).collect();
        b.draft.profiles.push(((hem_nodes[i], hem_nodes[j]), pts));
    }
    let hem = Ring { nodes: hem_nodes, ..hip.clone() };
    let upper = b.band(&waist, &hip);
    let lower = b.band(&hip, &hem);
    for (col, line) in [(0, CurveId::CentreFront), (2, CurveId::SideLineLeft), (4, CurveId::CentreBack), (6, CurveId::SideLineRight)] {
        b.line_profile(waist.nodes[col], hip.nodes[col], line)?;
    }
    b.orient();
    let cols = |c: [usize; 4]| -> Vec<usize> { c.iter().flat_map(|&i| upper[i].into_iter().chain(lower[i])).collect() };
    b.panel("front", cols([6, 7, 0, 1]), (waist.nodes[0], hem.nodes[0]));
    b.panel("back", cols([2, 3, 4, 5]), (waist.nodes[4], hem.nodes[4]));
    b.seam("side_left", "front", "back", vec![waist.nodes[2], hip.nodes[2], hem.nodes[2]]);
    b.seam("side_right", "back", "front", vec![waist.nodes[6], hip.nodes[6], hem.nodes[6]]);
    b.draft.notches = vec![("hip".into(), hip.nodes[2]), ("hip".into(), hip.nodes[6])];
    b.draft.name = "straight-skirt".into();
    b.draft.version = 1;
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

/// Authors every built-in template on the reference body.
pub fn author_all() -> Result<Vec<Template>, AuthorError> {
    let body = reference_body()?;
    Ok(vec![straight_skirt(&body, &SkirtOptions::default())?])
}
