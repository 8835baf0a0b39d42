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
use super::format::{GradingDefaults, Template, TemplateError};
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

/// Arc-length parameters of 8 ring nodes on a girth: front, front-left,
/// left, back-left, back, back-right, right, front-right (the girth runs
/// anticlockwise seen from above, front → left → back → right).
fn ring_params(
    body: &FeatureBody,
    curve: CurveId,
    cardinal: [PointId; 4],
) -> Result<(Polyline, [f64; 8]), AuthorError> {
    let loop_ = body.curves.get(&curve).ok_or_else(|| AuthorError::Missing(curve.to_string()))?.polyline.clone();
    let total = loop_.length();
    let mut s = [0.0; 4];
    for (k, id) in cardinal.iter().enumerate() {
        let p = body.points.get(id).ok_or_else(|| AuthorError::Missing(id.to_string()))?.position;
        s[k] = loop_.closest(p).map_or(0.0, |c| c.s);
    }
    let fwd = |a: f64, b: f64| (b - a).rem_euclid(total);
    let mut out = [0.0; 8];
    for k in 0..4 {
        out[2 * k] = s[k];
        out[2 * k + 1] = (s[k] + 0.5 * fwd(s[k], s[(k + 1) % 4])).rem_euclid(total);
    }
    Ok((loop_, out))
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
    let two_pi = std::f64::consts::TAU;
    let (waist, ws) = ring_params(body, CurveId::Waist, [P::WaistFront, P::WaistLeft, P::WaistBack, P::WaistRight])?;
    let (hip, hs) = ring_params(body, CurveId::Hip, [P::HipFront, P::HipLeft, P::HipBack, P::HipRight])?;
    let rw = o.waist_ease_mm * MM / two_pi;
    let rh = o.hip_ease_mm * MM / two_pi;
    let hip_c = hip.centroid();
    let hem_of = |p: DVec3| -> DVec3 {
        let out = DVec3::new(p.x - hip_c.x, 0.0, p.z - hip_c.z).normalize_or_zero();
        p - DVec3::Y * o.length_below_hip_m + out * (o.hem_flare_mm * MM)
    };
    let mut positions = Vec::new();
    let mut ties = Vec::new();
    let waist_ties = [P::WaistFront, P::WaistLeft, P::WaistBack, P::WaistRight];
    let hip_ties = [P::HipFront, P::HipLeft, P::HipBack, P::HipRight];
    for (k, &s) in ws.iter().enumerate() {
        positions.push(eased(&waist, s, rw));
        ties.push(Some(waist_ties[k / 2]));
    }
    for (k, &s) in hs.iter().enumerate() {
        positions.push(eased(&hip, s, rh));
        ties.push(Some(hip_ties[k / 2]));
    }
    for k in 0..8 {
        positions.push(hem_of(positions[8 + k]));
        ties.push(Some(hip_ties[k / 2]));
    }
    // triangles: quads between rings, outward-facing
    let mut triangles = Vec::new();
    let mut quad_of_column: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for r in 0..2u32 {
        for i in 0..8u32 {
            let a = r * 8 + i;
            let b = r * 8 + (i + 1) % 8;
            let c = (r + 1) * 8 + (i + 1) % 8;
            let d = (r + 1) * 8 + i;
            quad_of_column.entry(i as usize).or_default().extend([triangles.len(), triangles.len() + 1]);
            triangles.push([a, d, c]);
            triangles.push([a, c, b]);
        }
    }
    // profiles
    let n = o.profile_points.max(2);
    let total_w = waist.length();
    let total_h = hip.length();
    let mut profiles = Vec::new();
    for i in 0..8 {
        let j = (i + 1) % 8;
        let span = |s0: f64, s1: f64, total: f64| (s1 - s0).rem_euclid(total);
        let (sw0, dw) = (ws[i], span(ws[i], ws[j], total_w));
        let (sh0, dh) = (hs[i], span(hs[i], hs[j], total_h));
        let wpts: Vec<DVec3> = (0..n).map(|k| eased(&waist, sw0 + dw * k as f64 / (n - 1) as f64, rw)).collect();
        let hpts: Vec<DVec3> = (0..n).map(|k| eased(&hip, sh0 + dh * k as f64 / (n - 1) as f64, rh)).collect();
        let hem: Vec<DVec3> = hpts.iter().map(|&p| hem_of(p)).collect();
        profiles.push(((i as u32, j as u32), wpts));
        profiles.push(((8 + i as u32, 8 + j as u32), hpts));
        profiles.push(((16 + i as u32, 16 + j as u32), hem));
    }
    // vertical profiles waist → hip along the centre and side lines
    let columns = [
        (0u32, CurveId::CentreFront),
        (2, CurveId::SideLineLeft),
        (4, CurveId::CentreBack),
        (6, CurveId::SideLineRight),
    ];
    for (col, curve) in columns {
        let line = &body.curves.get(&curve).ok_or_else(|| AuthorError::Missing(curve.to_string()))?.polyline;
        let a = body.points[&waist_ties[col as usize / 2]].position;
        let b = body.points[&hip_ties[col as usize / 2]].position;
        let (Some(ca), Some(cb)) = (line.closest(a), line.closest(b)) else {
            return Err(AuthorError::Missing(format!("{curve} between waist and hip")));
        };
        let pts: Vec<DVec3> = (0..n)
            .map(|k| {
                let t = k as f64 / (n - 1) as f64;
                let p = line.point_at(ca.s + (cb.s - ca.s) * t);
                let c = waist.centroid().lerp(hip_c, t);
                let out = DVec3::new(p.x - c.x, 0.0, p.z - c.z).normalize_or_zero();
                p + out * (rw + (rh - rw) * t)
            })
            .collect();
        profiles.push(((col, 8 + col), pts));
    }
    let panel = |name: &str, cols: [usize; 4], grain: (u32, u32)| DraftPanel {
        name: name.to_owned(),
        triangles: cols.iter().flat_map(|c| quad_of_column[c].clone()).collect(),
        grain,
        quantity: 1,
    };
    let draft = Draft {
        name: "straight-skirt".into(),
        version: 1,
        description: "Straight skirt with a slight hem flare: waistband line, hip line and hem; front and back \
                      panels joined by side seams."
            .into(),
        ease_mm: BTreeMap::from([
            ("waist".to_owned(), o.waist_ease_mm),
            ("hip".to_owned(), o.hip_ease_mm),
            ("hem_flare_radial".to_owned(), o.hem_flare_mm),
        ]),
        positions,
        ties,
        triangles,
        profiles,
        panels: vec![panel("front", [6, 7, 0, 1], (0, 16)), panel("back", [2, 3, 4, 5], (4, 20))],
        seams: vec![
            DraftSeam {
                name: "side_left".into(),
                panel_a: "front".into(),
                panel_b: "back".into(),
                nodes: vec![2, 10, 18],
            },
            DraftSeam {
                name: "side_right".into(),
                panel_a: "back".into(),
                panel_b: "front".into(),
                nodes: vec![6, 14, 22],
            },
        ],
        notches: vec![("hip".into(), 10), ("hip".into(), 14)],
        defaults: GradingDefaults::default(),
    };
    Ok(encode(&draft, body)?)
}

/// Authors every built-in template on the reference body.
pub fn author_all() -> Result<Vec<Template>, AuthorError> {
    let body = reference_body()?;
    Ok(vec![straight_skirt(&body, &SkirtOptions::default())?])
}
