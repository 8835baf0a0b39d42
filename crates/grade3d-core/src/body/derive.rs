//! Landmarks → feature curves, feature points and frames, on any mesh.
//!
//! The one path by which every body — a scan of any topology or the
//! embedded mannequin — becomes a [`FeatureBody`]:
//!
//! 1. **Weld** vertices closer than [`DeriveOptions::weld_tolerance_mm`]
//!    (split seams would cut plane sections into pieces), then **check** the mesh: stature (bounding-box height) within
//!    [`DeriveOptions::min_stature_m`, `max_stature_m`]; every landmark the
//!    vocabulary's curve rules need is present and finite.
//! 2. **Snap** each landmark to its closest surface point; one farther than
//!    [`DeriveOptions::max_landmark_offset_mm`] is rejected.
//!    **Plausibility**: every centre-front/back landmark given lies within
//!    [`DeriveOptions::max_midline_offset_mm`] of the mid-sagittal plane of
//!    the left/right landmark pairs ([`FeatureError::OffMidline`]); the
//!    landmarks lie in their order up the body, ankle to knee to thigh to
//!    crotch, crotch to hip to waist to bust to underarm to shoulder
//!    ([`FeatureError::LandmarkHeight`]: a girth off its landmark's height).
//!    Landmarks that are plausible but near a limit (a midline point more
//!    than [`DeriveOptions::warn_midline_offset_mm`] off centre, a landmark
//!    more than [`DeriveOptions::warn_landmark_offset_mm`] from the surface,
//!    a frame flatter than [`DeriveOptions::warn_frame_triple`]) are
//!    graded, with a [`FeatureWarning`] in the report.
//! 3. **Curves** (unless given as polylines): each curve by its rule in
//!    [`vocab::CURVES`] — a *section* is a plane section of the mesh
//!    ([`crate::geom::slice`]), the loop chosen as the one enclosing the
//!    landmarks' centroid (torso girths: not an arm) or the one nearest to
//!    them (limbs), oriented anticlockwise about the rule's axis; a *path*
//!    joins consecutive landmarks `p_i → p_{i+1}` by the shorter arc of the
//!    section by the plane through `p_i` with normal `(p_{i+1} − p_i) × d`.
//!    **Plausibility**: each girth at most [`DeriveOptions::max_girth_to_stature`]
//!    of the stature, each armscye at most [`DeriveOptions::max_armscye_to_chest`]
//!    of the chest girth ([`FeatureError::ImplausibleGirth`]: a section that
//!    runs through the torso).
//! 4. **Points**: each feature point is the crossing of its two curves
//!    nearest its landmark (closest approach of the polylines), snapped to
//!    the surface. Crossings farther apart than
//!    [`DeriveOptions::max_crossing_gap_mm`] are rejected.
//! 5. **Frames** (seed 000 §3.2): `t(f1)`, `t(f2)` are the curves' chord
//!    tangents over ±[`DeriveOptions::tangent_window_mm`], `n` the
//!    area-weighted normal over a disc of [`DeriveOptions::normal_radius_mm`];
//!    `|t(f1)·(t(f2)×n)| < min_frame_triple` is rejected, naming the point.

use std::collections::BTreeMap;

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::contact::{thigh_contact, ContactOptions};
use super::feature::{FeatureBody, FeatureCurve, FeaturePoint, Frame};
use super::vocab::{self, CurveId, CurveRule, LoopChoice, Pick, PlaneRule, PointId};
use crate::geom::mesh::{MeshError, TriMesh};
use crate::geom::plane::Plane;
use crate::geom::polyline::Polyline;
use crate::geom::query::SphereIndex;
use crate::geom::slice::slice;

/// Distance of the aiming point of a [`Pick::Toward`] crossing, m: far
/// beyond any body, so the nearest crossing is the extreme one.
const FAR_M: f64 = 100.0;

/// Where the middle of a leg lies between the midline and the mean of its
/// outer side points (a fraction of the way out).
const LEG_MIDDLE_FRACTION: f64 = 0.55;

/// Millimetres per metre.
pub const MM_PER_M: f64 = 1000.0;

/// Landmark positions (and optionally curves) supplied with a body.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Landmarks {
    /// Feature point ID → approximate position, metres.
    pub points: BTreeMap<PointId, DVec3>,
    /// Feature curves given explicitly (polylines on the surface, metres);
    /// the rest are derived.
    #[serde(default)]
    pub curves: BTreeMap<CurveId, Polyline>,
}

/// Knobs of the derivation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DeriveOptions {
    /// Smallest accepted stature (bounding-box height), m. Default 0.5.
    pub min_stature_m: f64,
    /// Largest accepted stature, m. Default 2.5.
    pub max_stature_m: f64,
    /// Largest accepted distance from a landmark to the surface, mm. Default 30.
    pub max_landmark_offset_mm: f64,
    /// Half-width of the chord that defines a curve tangent, mm. Default 15.
    pub tangent_window_mm: f64,
    /// Radius of the disc over which the surface normal is averaged, mm. Default 15.
    pub normal_radius_mm: f64,
    /// Smallest accepted |t(f1)·(t(f2)×n)|. Default 0.1.
    pub min_frame_triple: f64,
    /// Largest accepted gap between two curves at their crossing, mm. Default 5.
    pub max_crossing_gap_mm: f64,
    /// How far below the armpit landmarks the chest girth is taken, mm. Default 10.
    pub chest_below_armpit_mm: f64,
    /// Half the width of an ankle, used to aim the leg sagittal line at the
    /// middle of the ankle from its outer side point where the body has no
    /// horizontal section there (the line is aimed at the middle of that
    /// section otherwise), mm. Default 35.
    pub ankle_half_width_mm: f64,
    /// Vertices closer than this are merged before slicing (scans often
    /// arrive split along UV or normal seams), mm. Default 0.01.
    pub weld_tolerance_mm: f64,
    /// How far a path continues past its first and last landmark, mm, so
    /// that a girth plane passing just beyond an end still crosses it.
    /// Default 30.
    pub path_extension_mm: f64,
    /// Largest accepted distance of a midline landmark (centre front and
    /// back: neck, bust, underbust, waist, hip front/back, crotch) from the
    /// mid-sagittal plane through the left/right landmark pairs, mm.
    /// Default 30 (placement error on a real scan is a few mm; 5 cm skews
    /// the whole garment).
    pub max_midline_offset_mm: f64,
    /// Largest accepted armscye girth as a share of the chest girth.
    /// Default 0.75 (bodies measure 0.40–0.55; a section through the torso
    /// measures more than the chest).
    pub max_armscye_to_chest: f64,
    /// Largest accepted girth as a share of the stature. Default 1.3 (the
    /// heaviest bodies of the hm08 model reach 1.1 at the hip).
    pub max_girth_to_stature: f64,
    /// A midline landmark farther than this from the mid-sagittal plane
    /// (but within [`Self::max_midline_offset_mm`]) is graded with a
    /// warning, mm. Default 15 (the garment is skewed by about as much).
    pub warn_midline_offset_mm: f64,
    /// A landmark farther than this from the surface (but within
    /// [`Self::max_landmark_offset_mm`]) is snapped with a warning, mm.
    /// Default 10.
    pub warn_landmark_offset_mm: f64,
    /// A frame with `|t(f1)·(t(f2)×n)|` below this (but at least
    /// [`Self::min_frame_triple`]) is used with a warning: Eq. (1) offsets
    /// along a nearly flat frame swing far for small changes. Default 0.2.
    pub warn_frame_triple: f64,
    /// Largest height difference of a left/right landmark pair, mm.
    /// Default 40 (shoulders differ by up to about 2 cm on a real body; a
    /// point placed at the wrong girth is 5 cm and more off).
    pub max_pair_height_mm: f64,
    /// How far a left point may lie to the right of its partner before the
    /// pair counts as swapped, mm. Default 10 (the inner points of thighs
    /// that touch meet at the centre line).
    pub max_pair_cross_mm: f64,
    /// Largest angle about the limb's centre (its horizontal section's
    /// centroid) between a leg's side, inner, front or back point and where
    /// it belongs, degrees. Default 45 (half way to the next line).
    pub max_side_angle_deg: f64,
    /// The thigh contact test ([`super::contact`]).
    pub contact: ContactOptions,
}

impl Default for DeriveOptions {
    fn default() -> Self {
        Self {
            min_stature_m: 0.5,
            max_stature_m: 2.5,
            max_landmark_offset_mm: 30.0,
            tangent_window_mm: 15.0,
            normal_radius_mm: 15.0,
            min_frame_triple: 0.1,
            max_crossing_gap_mm: 5.0,
            chest_below_armpit_mm: 10.0,
            path_extension_mm: 30.0,
            weld_tolerance_mm: 0.01,
            ankle_half_width_mm: 35.0,
            max_midline_offset_mm: 30.0,
            max_armscye_to_chest: 0.75,
            max_girth_to_stature: 1.3,
            warn_midline_offset_mm: 15.0,
            warn_landmark_offset_mm: 10.0,
            warn_frame_triple: 0.2,
            max_pair_height_mm: 40.0,
            max_pair_cross_mm: 10.0,
            max_side_angle_deg: 45.0,
            contact: ContactOptions::default(),
        }
    }
}

/// Something derivation accepted but a person should look at: the body is
/// graded, and the report lists it (issue #13, item 3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FeatureWarning {
    /// Kind: `landmark-near-midline-limit`, `landmark-far-from-surface`,
    /// `frame-nearly-degenerate`, `thighs-in-contact`.
    pub code: String,
    /// The landmark or feature point.
    pub point: PointId,
    /// What was measured, with the warning and refusal thresholds.
    pub detail: String,
}

/// Why a body could not be turned into a feature human model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FeatureError {
    /// The mesh itself is invalid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Stature outside the accepted range (wrong units?).
    #[error("the body is {stature_m} m tall; expected {min_m}–{max_m} m (are the units metres?)")]
    BodySize {
        /// Measured stature, m.
        stature_m: f64,
        /// Lower bound, m.
        min_m: f64,
        /// Upper bound, m.
        max_m: f64,
    },
    /// Landmarks the curve rules need are missing.
    #[error("missing landmarks: {}", .missing.iter().map(|p| p.as_str()).collect::<Vec<_>>().join(", "))]
    MissingLandmarks {
        /// The missing IDs.
        missing: Vec<PointId>,
    },
    /// A landmark coordinate is not finite.
    #[error("landmark `{point}` has a non-finite coordinate")]
    NonFiniteLandmark {
        /// The landmark.
        point: PointId,
    },
    /// A landmark lies too far from the surface.
    #[error("landmark `{point}` is {distance_mm:.1} mm from the body surface (limit {limit_mm} mm)")]
    LandmarkOffSurface {
        /// The landmark.
        point: PointId,
        /// Its distance to the surface, mm.
        distance_mm: f64,
        /// The limit, mm.
        limit_mm: f64,
    },
    /// A given curve polyline is unusable.
    #[error("curve `{curve}`: {reason}")]
    BadCurve {
        /// The curve.
        curve: CurveId,
        /// What is wrong.
        reason: String,
    },
    /// The plane of a curve does not cut the body where its landmarks are.
    #[error("curve `{curve}`: no section of the body {reason}")]
    NoSection {
        /// The curve.
        curve: CurveId,
        /// Where it was looked for.
        reason: String,
    },
    /// Two curves that define a point do not meet.
    #[error("curves `{f1}` and `{f2}` do not cross near `{point}`: closest {gap_mm:.1} mm apart")]
    CurvesDoNotCross {
        /// The point.
        point: PointId,
        /// First curve.
        f1: CurveId,
        /// Second curve.
        f2: CurveId,
        /// Their closest distance, mm.
        gap_mm: f64,
    },
    /// A centre-front or centre-back landmark lies off the body's
    /// mid-sagittal plane.
    #[error(
        "landmark `{point}` is {offset_mm:.1} mm from the mid-sagittal plane of the left/right landmarks \
         (plausible: up to {limit_mm} mm); place centre-front and centre-back points on the centre line"
    )]
    OffMidline {
        /// The landmark.
        point: PointId,
        /// Its distance from the plane, mm.
        offset_mm: f64,
        /// The limit, mm.
        limit_mm: f64,
    },
    /// A girth measures outside what a human body can have, given the
    /// stature and its neighbours (a section that runs through the torso).
    #[error("curve `{curve}` measures {girth_mm:.0} mm; plausible: {min_mm:.0}–{max_mm:.0} mm ({reason})")]
    ImplausibleGirth {
        /// The curve.
        curve: CurveId,
        /// Its tape length, mm.
        girth_mm: f64,
        /// Lower bound, mm.
        min_mm: f64,
        /// Upper bound, mm.
        max_mm: f64,
        /// The rule that bounds it.
        reason: String,
    },
    /// A landmark lies on the wrong side (in height) of another: a girth
    /// off its landmark's height (a thigh girth above the crotch runs round
    /// both legs; a waist below the hip is a mislabelled point).
    #[error("landmark `{point}` lies {gap_mm:.0} mm {side} `{other}`; it must lie {must} it ({reason})")]
    LandmarkHeight {
        /// The landmark.
        point: PointId,
        /// The landmark it is checked against.
        other: PointId,
        /// How far it lies on the wrong side, mm.
        gap_mm: f64,
        /// Where it lies: "above" or "below".
        side: &'static str,
        /// Where it must lie: "below" or "above".
        must: &'static str,
        /// The rule.
        reason: &'static str,
    },
    /// A left landmark lies on the body's right of its right partner
    /// (the body faces +Z, its left is +X): the pair is swapped.
    #[error(
        "landmark `{left}` lies {gap_mm:.0} mm to the right of `{right}`; the body's left is +X (it faces +Z): \
         are left and right swapped?"
    )]
    SwappedSides {
        /// The left landmark.
        left: PointId,
        /// Its right partner.
        right: PointId,
        /// How far it lies on the wrong side, mm.
        gap_mm: f64,
    },
    /// A left/right pair is not mirror-consistent: the two lie at heights
    /// that differ more than a body's left and right do.
    #[error(
        "landmarks `{left}` and `{right}` lie {gap_mm:.0} mm apart in height; a pair may differ by up to {limit_mm} mm"
    )]
    PairHeight {
        /// The left landmark.
        left: PointId,
        /// Its right partner.
        right: PointId,
        /// Their height difference, mm.
        gap_mm: f64,
        /// The limit, mm.
        limit_mm: f64,
    },
    /// A limb's side point is not on its side of the limb (a knee point at
    /// the front of the knee where the knee girth's side point is meant).
    #[error(
        "landmark `{point}` lies {angle_deg:.0}° round the {limb} from its {side} (allowed up to {limit_deg}°); \
         it is the girth's point on the {side}"
    )]
    OffSideLine {
        /// The landmark.
        point: PointId,
        /// The limb: `leg` or `arm`.
        limb: &'static str,
        /// Where it belongs: `outer side`, `inner side`, `front` or `back`.
        side: &'static str,
        /// Its angle from there about the limb's centre, degrees.
        angle_deg: f64,
        /// The limit, degrees.
        limit_deg: f64,
    },
    /// The frame at a point is (nearly) degenerate.
    #[error("degenerate frame at `{point}`: |t(f1)·(t(f2)×n)| = {triple:.3} < {min}")]
    DegenerateFrame {
        /// The point.
        point: PointId,
        /// The triple product.
        triple: f64,
        /// The threshold.
        min: f64,
    },
}

/// Builds the feature human model of `mesh` from `landmarks`.
pub fn derive_features(
    mesh: TriMesh,
    landmarks: &Landmarks,
    opts: &DeriveOptions,
) -> Result<FeatureBody, FeatureError> {
    let mesh = mesh.welded(opts.weld_tolerance_mm / MM_PER_M)?;
    let stature = mesh.aabb().size().y;
    if !(stature >= opts.min_stature_m && stature <= opts.max_stature_m) {
        return Err(FeatureError::BodySize {
            stature_m: stature,
            min_m: opts.min_stature_m,
            max_m: opts.max_stature_m,
        });
    }
    // landmarks needed: those of the curves not given explicitly; an optional curve (an arm) is
    // derived only where all its landmarks are given
    let rule_landmarks = |c: &vocab::CurveDef| match c.rule {
        CurveRule::Section { landmarks, .. } | CurveRule::Path { landmarks, .. } => landmarks,
    };
    let wanted = |c: &&vocab::CurveDef| {
        landmarks.curves.contains_key(&c.id)
            || !vocab::optional_curve(c.id)
            || rule_landmarks(c).iter().all(|p| landmarks.points.contains_key(p))
    };
    let mut missing: Vec<PointId> = vocab::CURVES
        .iter()
        .filter(|c| !landmarks.curves.contains_key(&c.id) && !vocab::optional_curve(c.id))
        .flat_map(|c| rule_landmarks(c).iter().copied())
        .filter(|p| !landmarks.points.contains_key(p))
        .collect();
    missing.sort();
    missing.dedup();
    if !missing.is_empty() {
        return Err(FeatureError::MissingLandmarks { missing });
    }
    // one index for the landmarks' snapping and the frames' normals
    let index = SphereIndex::new(&mesh);
    let mut snapped: BTreeMap<PointId, DVec3> = BTreeMap::new();
    let mut warnings = Vec::new();
    for (&id, &p) in &landmarks.points {
        if !p.is_finite() {
            return Err(FeatureError::NonFiniteLandmark { point: id });
        }
        let sp = index.closest_point(&mesh, p);
        let mm = sp.distance * MM_PER_M;
        if mm > opts.max_landmark_offset_mm {
            return Err(FeatureError::LandmarkOffSurface {
                point: id,
                distance_mm: mm,
                limit_mm: opts.max_landmark_offset_mm,
            });
        }
        if mm > opts.warn_landmark_offset_mm {
            warnings.push(FeatureWarning {
                code: "landmark-far-from-surface".into(),
                point: id,
                detail: format!(
                    "landmark `{id}` lies {mm:.1} mm from the surface (warned above {} mm, refused above {} mm); \
                     it was moved onto it",
                    opts.warn_landmark_offset_mm, opts.max_landmark_offset_mm
                ),
            });
        }
        snapped.insert(id, sp.point);
    }
    check_midline(&snapped, opts, &mut warnings)?;
    check_heights(&snapped)?;
    check_pairs(&snapped, opts)?;

    // the curves are independent sections and paths: derived side by side on rayon's pool
    // (issue #15), the first failure in vocabulary order reported, as one after another would
    let defs: Vec<&vocab::CurveDef> = vocab::CURVES.iter().filter(wanted).collect();
    let derived: Vec<Result<FeatureCurve, FeatureError>> = defs
        .par_iter()
        .map(|def| match landmarks.curves.get(&def.id) {
            Some(given) => given_curve(def.id, given),
            None => curve_by_rule(&mesh, def.id, &def.rule, &snapped, opts),
        })
        .collect();
    let mut curves = BTreeMap::new();
    for (def, curve) in defs.iter().zip(derived) {
        curves.insert(def.id, curve?);
    }
    check_limb_sides(&curves, &snapped, opts)?;
    check_girths(&curves, stature, opts)?;

    let mut points = BTreeMap::new();
    let h = opts.tangent_window_mm / MM_PER_M;
    for def in vocab::POINTS {
        // a point on an optional curve the body lacks (its arms, without their landmarks)
        let (Some(c1), Some(c2)) = (curves.get(&def.f1), curves.get(&def.f2)) else { continue };
        let (c1, c2) = (&c1.polyline, &c2.polyline);
        let near = match def.pick {
            Pick::Landmark => snapped.get(&def.id).copied().unwrap_or_else(|| 0.5 * (c1.centroid() + c2.centroid())),
            Pick::Toward(dir) => c1.centroid() + DVec3::from_array(dir) * FAR_M,
        };
        let gap_tol = 1e-9 * stature;
        let cross = c1.crossing(c2, near, gap_tol).ok_or(FeatureError::CurvesDoNotCross {
            point: def.id,
            f1: def.f1,
            f2: def.f2,
            gap_mm: f64::INFINITY,
        })?;
        if cross.gap * MM_PER_M > opts.max_crossing_gap_mm {
            return Err(FeatureError::CurvesDoNotCross {
                point: def.id,
                f1: def.f1,
                f2: def.f2,
                gap_mm: cross.gap * MM_PER_M,
            });
        }
        let position = cross.point;
        let degenerate =
            |triple: f64| FeatureError::DegenerateFrame { point: def.id, triple, min: opts.min_frame_triple };
        let t1 = c1.tangent_at(cross.s_a, h).ok_or_else(|| degenerate(0.0))?;
        let t2 = c2.tangent_at(cross.s_b, h).ok_or_else(|| degenerate(0.0))?;
        let n = index.disc_normal(&mesh, position, opts.normal_radius_mm / MM_PER_M).ok_or_else(|| degenerate(0.0))?;
        let frame = Frame { t1, t2, n };
        let triple = frame.triple();
        if triple.is_nan() || triple.abs() < opts.min_frame_triple {
            return Err(degenerate(triple));
        }
        if triple.abs() < opts.warn_frame_triple {
            warnings.push(FeatureWarning {
                code: "frame-nearly-degenerate".into(),
                point: def.id,
                detail: format!(
                    "the frame at `{}` is nearly flat: |t(f1)·(t(f2)×n)| = {:.3} (warned below {}, refused below {}); \
                     nodes tied to it may sit off where the template meant",
                    def.id,
                    triple.abs(),
                    opts.warn_frame_triple,
                    opts.min_frame_triple
                ),
            });
        }
        points.insert(def.id, FeaturePoint { position, frame, crossing_gap: cross.gap });
    }
    let thigh_contact = match (midsagittal_plane(&snapped), snapped.get(&PointId::Crotch)) {
        (Some(plane), Some(&crotch)) => thigh_contact(&mesh, &plane, crotch, &opts.contact),
        _ => None,
    };
    if let Some(c) = &thigh_contact {
        warnings.push(FeatureWarning {
            code: "thighs-in-contact".into(),
            point: PointId::Crotch,
            detail: format!(
                "the thighs touch each other (within {} mm) from {:.0} mm below the crotch point down, over {:.0} mm \
                 front to back: no trouser leg can pass between them outside the body, so garment triangles \
                 cross the body there (counted apart in the report's penetration)",
                opts.contact.cloth_gap_mm, c.depth_below_crotch_mm, c.length_mm
            ),
        });
    }
    Ok(FeatureBody { mesh, curves, points, warnings, thigh_contact })
}

/// Landmarks that lie on the centre front or centre back line.
const MIDLINE: [PointId; 12] = [
    PointId::NeckFront,
    PointId::NeckBack,
    PointId::ChestFront,
    PointId::ChestBack,
    PointId::BustFront,
    PointId::BustBack,
    PointId::UnderbustFront,
    PointId::UnderbustBack,
    PointId::WaistFront,
    PointId::WaistBack,
    PointId::HipFront,
    PointId::HipBack,
];

/// Left/right landmark pairs that span the mid-sagittal plane.
const PAIRS: [(PointId, PointId); 5] = [
    (PointId::ShoulderLeft, PointId::ShoulderRight),
    (PointId::UnderarmLeft, PointId::UnderarmRight),
    (PointId::WaistLeft, PointId::WaistRight),
    (PointId::HipLeft, PointId::HipRight),
    (PointId::NeckLeft, PointId::NeckRight),
];

/// Plausibility of the midline landmarks: the mid-sagittal plane passes
/// through the mean midpoint of the left/right pairs given, with the mean
/// right-to-left direction (made horizontal) as its normal; every midline
/// landmark given must lie within [`DeriveOptions::max_midline_offset_mm`];
/// one beyond [`DeriveOptions::warn_midline_offset_mm`] is a warning.
/// Without a pair there is nothing to check against.
/// The mid-sagittal plane of the left/right landmark pairs
/// ([`Plane::bisecting`], upright: up is +Y). `None` without a pair, or
/// where they sum to vertical.
fn midsagittal_plane(snapped: &BTreeMap<PointId, DVec3>) -> Option<Plane> {
    let pairs: Vec<(DVec3, DVec3)> =
        PAIRS.iter().filter_map(|(l, r)| Some((*snapped.get(l)?, *snapped.get(r)?))).collect();
    Plane::bisecting(&pairs, Some(DVec3::Y))
}

fn check_midline(
    snapped: &BTreeMap<PointId, DVec3>,
    opts: &DeriveOptions,
    warnings: &mut Vec<FeatureWarning>,
) -> Result<(), FeatureError> {
    let Some(plane) = midsagittal_plane(snapped) else { return Ok(()) };
    for id in MIDLINE {
        let Some(&p) = snapped.get(&id) else { continue };
        let offset_mm = plane.signed_distance(p).abs() * MM_PER_M;
        if offset_mm > opts.max_midline_offset_mm {
            return Err(FeatureError::OffMidline { point: id, offset_mm, limit_mm: opts.max_midline_offset_mm });
        }
        if offset_mm > opts.warn_midline_offset_mm {
            warnings.push(FeatureWarning {
                code: "landmark-near-midline-limit".into(),
                point: id,
                detail: format!(
                    "landmark `{id}` is {offset_mm:.1} mm from the mid-sagittal plane of the left/right landmarks \
                     (warned above {} mm, refused above {} mm): the garment is skewed by about as much",
                    opts.warn_midline_offset_mm, opts.max_midline_offset_mm
                ),
            });
        }
    }
    Ok(())
}

/// Landmarks that lie below others (up is +Y), with the rule: `(lower,
/// upper, why)`. Each pair given is checked.
const BELOW: [(PointId, PointId, &str); 22] = {
    use PointId as P;
    const LEG: &str = "ankle, knee and thigh girths lie in that order up the leg";
    const THIGH: &str =
        "a thigh girth is measured below the crotch (ISO 8559-1 5.3.20); above it, it runs round both legs";
    const TORSO: &str = "crotch, hip, waist, bust, underarm and shoulder lie in that order up the body";
    const ARM: &str = "in the reference (A-) pose, wrist, elbow, upper arm and shoulder lie in that order up the arm";
    [
        (P::AnkleLeft, P::KneeLeft, LEG),
        (P::AnkleRight, P::KneeRight, LEG),
        (P::KneeLeft, P::ThighLeft, LEG),
        (P::KneeRight, P::ThighRight, LEG),
        (P::ThighLeft, P::Crotch, THIGH),
        (P::ThighRight, P::Crotch, THIGH),
        (P::Crotch, P::HipLeft, TORSO),
        (P::Crotch, P::HipRight, TORSO),
        (P::HipLeft, P::WaistLeft, TORSO),
        (P::HipRight, P::WaistRight, TORSO),
        (P::WaistLeft, P::BustLeft, TORSO),
        (P::WaistRight, P::BustRight, TORSO),
        (P::BustLeft, P::UnderarmLeft, TORSO),
        (P::BustRight, P::UnderarmRight, TORSO),
        (P::UnderarmLeft, P::ShoulderLeft, TORSO),
        (P::UnderarmRight, P::ShoulderRight, TORSO),
        (P::WristLeft, P::ElbowLeft, ARM),
        (P::WristRight, P::ElbowRight, ARM),
        (P::ElbowLeft, P::UpperArmLeft, ARM),
        (P::ElbowRight, P::UpperArmRight, ARM),
        (P::UpperArmLeft, P::ShoulderLeft, ARM),
        (P::UpperArmRight, P::ShoulderRight, ARM),
    ]
};

/// Every left/right pair of the vocabulary (`*_left*` and its `*_right*`).
fn left_right_pairs() -> impl Iterator<Item = (PointId, PointId)> {
    PointId::ALL.iter().filter_map(|&l| {
        let name = l.as_str();
        name.contains("_left").then(|| name.replacen("_left", "_right", 1).parse::<PointId>().ok().map(|r| (l, r)))?
    })
}

/// Mirror consistency of the left/right pairs given (issue #17, item 3):
/// the left point on the body's left (+X; it faces +Z) of its partner
/// ([`FeatureError::SwappedSides`]), and the two at about one height
/// ([`FeatureError::PairHeight`]).
fn check_pairs(snapped: &BTreeMap<PointId, DVec3>, opts: &DeriveOptions) -> Result<(), FeatureError> {
    for (left, right) in left_right_pairs() {
        let (Some(l), Some(r)) = (snapped.get(&left), snapped.get(&right)) else { continue };
        let cross_mm = (r.x - l.x) * MM_PER_M;
        if cross_mm > opts.max_pair_cross_mm {
            return Err(FeatureError::SwappedSides { left, right, gap_mm: cross_mm });
        }
        let gap_mm = (l.y - r.y).abs() * MM_PER_M;
        if gap_mm > opts.max_pair_height_mm {
            return Err(FeatureError::PairHeight { left, right, gap_mm, limit_mm: opts.max_pair_height_mm });
        }
    }
    Ok(())
}

/// Where each of a leg's girth points belongs round the leg: its girth
/// (left, right), its side, with the horizontal direction from the leg's
/// centre (left leg; the right leg's mirror).
const LEG_POINTS: [([PointId; 2], [CurveId; 2], &str, DVec3); 12] = {
    use CurveId as C;
    use PointId as P;
    const OUT: DVec3 = DVec3::X;
    const IN: DVec3 = DVec3::NEG_X;
    const FRONT: DVec3 = DVec3::Z;
    const BACK: DVec3 = DVec3::NEG_Z;
    const THIGH: [CurveId; 2] = [C::ThighLeft, C::ThighRight];
    const KNEE: [CurveId; 2] = [C::KneeLeft, C::KneeRight];
    const ANKLE: [CurveId; 2] = [C::AnkleLeft, C::AnkleRight];
    [
        ([P::ThighLeft, P::ThighRight], THIGH, "outer side", OUT),
        ([P::KneeLeft, P::KneeRight], KNEE, "outer side", OUT),
        ([P::AnkleLeft, P::AnkleRight], ANKLE, "outer side", OUT),
        ([P::ThighLeftInner, P::ThighRightInner], THIGH, "inner side", IN),
        ([P::KneeLeftInner, P::KneeRightInner], KNEE, "inner side", IN),
        ([P::AnkleLeftInner, P::AnkleRightInner], ANKLE, "inner side", IN),
        ([P::ThighLeftFront, P::ThighRightFront], THIGH, "front", FRONT),
        ([P::KneeLeftFront, P::KneeRightFront], KNEE, "front", FRONT),
        ([P::AnkleLeftFront, P::AnkleRightFront], ANKLE, "front", FRONT),
        ([P::ThighLeftBack, P::ThighRightBack], THIGH, "back", BACK),
        ([P::KneeLeftBack, P::KneeRightBack], KNEE, "back", BACK),
        ([P::AnkleLeftBack, P::AnkleRightBack], ANKLE, "back", BACK),
    ]
};

/// A leg's girth points on their lines (issue #17, item 3: a knee point at
/// the front of the knee, where the side point is meant, made every curve
/// through the leg miss its neighbours, and the refusal named the ankle):
/// the angle about the centroid of the point's girth (the leg's centre at
/// that height), between the point and where it belongs, at most
/// [`DeriveOptions::max_side_angle_deg`] ([`FeatureError::OffSideLine`]).
/// Run on the girths already derived: no section of its own.
fn check_limb_sides(
    curves: &BTreeMap<CurveId, FeatureCurve>,
    snapped: &BTreeMap<PointId, DVec3>,
    opts: &DeriveOptions,
) -> Result<(), FeatureError> {
    for (points, girths, side, dir) in LEG_POINTS {
        let wants = [dir, DVec3::new(-dir.x, dir.y, dir.z)];
        for ((point, girth), want) in points.into_iter().zip(girths).zip(wants) {
            let (Some(&p), Some(curve)) = (snapped.get(&point), curves.get(&girth)) else { continue };
            let centre = curve.polyline.length_centroid();
            let to = DVec3::new(p.x - centre.x, 0.0, p.z - centre.z);
            if to.length() == 0.0 {
                continue;
            }
            let angle_deg = to.angle_between(want).to_degrees();
            if angle_deg > opts.max_side_angle_deg {
                return Err(FeatureError::OffSideLine {
                    point,
                    limb: "leg",
                    side,
                    angle_deg,
                    limit_deg: opts.max_side_angle_deg,
                });
            }
        }
    }
    Ok(())
}

/// Plausibility of the landmarks' heights ([`BELOW`]): a girth off its
/// landmark's height is refused, naming both landmarks and the gap
/// ([`FeatureError::LandmarkHeight`]).
fn check_heights(snapped: &BTreeMap<PointId, DVec3>) -> Result<(), FeatureError> {
    for (lower, upper, reason) in BELOW {
        let (Some(l), Some(u)) = (snapped.get(&lower), snapped.get(&upper)) else { continue };
        if l.y > u.y {
            return Err(FeatureError::LandmarkHeight {
                point: lower,
                other: upper,
                gap_mm: (l.y - u.y) * MM_PER_M,
                side: "above",
                must: "below",
                reason,
            });
        }
    }
    Ok(())
}

/// Plausibility of the girths: each at most [`DeriveOptions::max_girth_to_stature`]
/// of the stature, and each armscye at most [`DeriveOptions::max_armscye_to_chest`]
/// of the chest girth.
fn check_girths(
    curves: &BTreeMap<CurveId, FeatureCurve>,
    stature: f64,
    opts: &DeriveOptions,
) -> Result<(), FeatureError> {
    let girth = |id: CurveId| curves.get(&id).map(|c| super::measure::girth_of(&c.polyline, c.plane.as_ref()));
    let too_long = |curve: CurveId, g: f64, max: f64, reason: String| {
        if g > max {
            return Err(FeatureError::ImplausibleGirth {
                curve,
                girth_mm: g * MM_PER_M,
                min_mm: 0.0,
                max_mm: max * MM_PER_M,
                reason,
            });
        }
        Ok(())
    };
    use CurveId as C;
    for id in [
        C::NeckBase,
        C::Chest,
        C::Bust,
        C::Underbust,
        C::Waist,
        C::Hip,
        C::ThighLeft,
        C::ThighRight,
        C::KneeLeft,
        C::KneeRight,
        C::AnkleLeft,
        C::AnkleRight,
        C::ArmscyeLeft,
        C::ArmscyeRight,
    ] {
        if let Some(g) = girth(id) {
            let max = opts.max_girth_to_stature * stature;
            too_long(id, g, max, format!("at most {} × the stature", opts.max_girth_to_stature))?;
        }
    }
    if let Some(chest) = girth(CurveId::Chest) {
        for id in [CurveId::ArmscyeLeft, CurveId::ArmscyeRight] {
            if let Some(g) = girth(id) {
                let reason = format!(
                    "at most {} × the chest girth of {:.0} mm: the armscye section runs through the torso?",
                    opts.max_armscye_to_chest,
                    chest * MM_PER_M
                );
                too_long(id, g, opts.max_armscye_to_chest * chest, reason)?;
            }
        }
    }
    Ok(())
}

fn given_curve(id: CurveId, given: &Polyline) -> Result<FeatureCurve, FeatureError> {
    if given.points.len() < 2 {
        return Err(FeatureError::BadCurve { curve: id, reason: "fewer than 2 points".into() });
    }
    if given.points.iter().any(|p| !p.is_finite()) {
        return Err(FeatureError::BadCurve { curve: id, reason: "non-finite coordinate".into() });
    }
    if given.length() <= 0.0 {
        return Err(FeatureError::BadCurve { curve: id, reason: "zero length".into() });
    }
    Ok(FeatureCurve { polyline: given.clone(), plane: None })
}

fn mean(points: &[DVec3]) -> DVec3 {
    points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64
}

fn section_plane(
    mesh: &TriMesh,
    curve: CurveId,
    rule: PlaneRule,
    pts: &[DVec3],
    opts: &DeriveOptions,
) -> Result<Plane, FeatureError> {
    let c = mean(pts);
    let horizontal = |y: f64| Plane { normal: DVec3::Y, offset: y };
    let plane = match rule {
        PlaneRule::BestFit => Plane::fit(pts).map(|p| p.oriented_towards(DVec3::Y)).unwrap_or(horizontal(c.y)),
        PlaneRule::Horizontal => horizontal(c.y),
        PlaneRule::HorizontalBelowArmpit => horizontal(c.y - opts.chest_below_armpit_mm / MM_PER_M),
        PlaneRule::Containing(axis) => {
            let (a, b) = match pts {
                [a, b, ..] => (*a, *b),
                _ => return Err(FeatureError::NoSection { curve, reason: "(rule needs two landmarks)".into() }),
            };
            Plane::from_point_normal(a, (b - a).cross(axis.vector())).ok_or_else(|| FeatureError::NoSection {
                curve,
                reason: "(its landmarks lie along the rule's axis)".into(),
            })?
        }
        PlaneRule::Normal(axis) => Plane { normal: axis.vector(), offset: axis.vector().dot(pts[0]) },
        PlaneRule::NormalThroughMean(axis) => Plane { normal: axis.vector(), offset: axis.vector().dot(c) },
        PlaneRule::VerticalAtAngle(deg) => {
            let t = deg.to_radians();
            let n = DVec3::new(t.cos(), 0.0, -t.sin());
            Plane { normal: n, offset: n.dot(c) }
        }
        PlaneRule::Across => {
            let (a, from, to) = match pts {
                [a, f, t, ..] => (*a, *f, *t),
                _ => return Err(FeatureError::NoSection { curve, reason: "(rule needs three landmarks)".into() }),
            };
            Plane::from_point_normal(a, to - from)
                .ok_or_else(|| FeatureError::NoSection { curve, reason: "(the limb's axis has no length)".into() })?
        }
        PlaneRule::LegSagittal => {
            // landmarks: thigh side point, ankle side point, crotch (the midline)
            let [thigh, ankle, crotch] = match pts {
                [t, a, c] => [*t, *a, *c],
                _ => {
                    return Err(FeatureError::NoSection {
                        curve,
                        reason: "(rule needs thigh, ankle and crotch)".into(),
                    })
                }
            };
            let thigh_mid = DVec3::new(crotch.x + LEG_MIDDLE_FRACTION * (thigh.x - crotch.x), thigh.y, thigh.z);
            let inward = (crotch.x - ankle.x).signum();
            // the middle of the ankle: its horizontal section's x extent (an ankle grows with the
            // body; a fixed half width would slide the line round the ankle from size to size)
            let ankle_x = ankle_middle_x(mesh, ankle).unwrap_or(ankle.x + inward * opts.ankle_half_width_mm / MM_PER_M);
            let ankle_mid = DVec3::new(ankle_x, ankle.y, ankle.z);
            Plane::from_point_normal(thigh_mid, (ankle_mid - thigh_mid).cross(DVec3::Z))
                .ok_or_else(|| FeatureError::NoSection { curve, reason: "(thigh and ankle points coincide)".into() })?
        }
    };
    Ok(plane)
}

/// x of the middle of the leg at the ankle side point `ankle`: the mean of
/// the x extremes of the horizontal section loop nearest to it; `None`
/// where no loop passes within a centimetre of the point.
fn ankle_middle_x(mesh: &TriMesh, ankle: DVec3) -> Option<f64> {
    const NEAR_M: f64 = 0.01;
    let loops = slice(mesh, &Plane { normal: DVec3::Y, offset: ankle.y });
    let near = loops
        .iter()
        .filter_map(|s| s.polyline.closest(ankle).map(|c| (c.distance, &s.polyline)))
        .filter(|(d, _)| *d < NEAR_M)
        .min_by(|a, b| a.0.total_cmp(&b.0))?
        .1;
    let xs = near.points.iter().map(|p| p.x);
    Some(0.5 * (xs.clone().fold(f64::INFINITY, f64::min) + xs.fold(f64::NEG_INFINITY, f64::max)))
}

/// For a leg girth, the vertical plane midway between its side point and
/// the other leg's, facing this leg: where the legs touch (heavy thighs,
/// knees together) the section around one leg runs round both, and the
/// girth is the part on this leg's side, closed along the plane
/// ([`Polyline::clipped`]; a tape passed between the thighs). `None` for
/// other curves, or without the pair.
fn leg_midplane(id: CurveId, snapped: &BTreeMap<PointId, DVec3>) -> Option<Plane> {
    use CurveId as C;
    use PointId as P;
    let (this, other) = match id {
        C::ThighLeft => (P::ThighLeft, P::ThighRight),
        C::ThighRight => (P::ThighRight, P::ThighLeft),
        C::KneeLeft => (P::KneeLeft, P::KneeRight),
        C::KneeRight => (P::KneeRight, P::KneeLeft),
        C::AnkleLeft => (P::AnkleLeft, P::AnkleRight),
        C::AnkleRight => (P::AnkleRight, P::AnkleLeft),
        _ => return None,
    };
    let (a, b) = (*snapped.get(&this)?, *snapped.get(&other)?);
    let across = (a - b) * DVec3::new(1.0, 0.0, 1.0);
    Plane::from_point_normal(0.5 * (a + b), across)
}

/// One curve by its vocabulary rule, from landmarks already on the surface
/// (no snapping, no checks beyond the rule's own).
pub fn derive_curve(
    mesh: &TriMesh,
    id: CurveId,
    landmarks: &BTreeMap<PointId, DVec3>,
    opts: &DeriveOptions,
) -> Result<FeatureCurve, FeatureError> {
    let rule = &vocab::curve_def(id).rule;
    let needed = match rule {
        CurveRule::Section { landmarks, .. } | CurveRule::Path { landmarks, .. } => *landmarks,
    };
    let missing: Vec<PointId> = needed.iter().copied().filter(|p| !landmarks.contains_key(p)).collect();
    if !missing.is_empty() {
        return Err(FeatureError::MissingLandmarks { missing });
    }
    curve_by_rule(mesh, id, rule, landmarks, opts)
}

fn curve_by_rule(
    mesh: &TriMesh,
    id: CurveId,
    rule: &CurveRule,
    snapped: &BTreeMap<PointId, DVec3>,
    opts: &DeriveOptions,
) -> Result<FeatureCurve, FeatureError> {
    match *rule {
        CurveRule::Section { landmarks, plane, choice, orientation } => {
            let pts: Vec<DVec3> = landmarks.iter().map(|p| snapped[p]).collect();
            let plane = section_plane(mesh, id, plane, &pts, opts)?;
            let loops: Vec<Polyline> =
                slice(mesh, &plane).into_iter().map(|s| s.polyline).filter(|p| p.points.len() >= 3).collect();
            let centre = plane.project(mean(&pts));
            let chosen = match choice {
                LoopChoice::Encloses => loops
                    .iter()
                    .filter(|l| l.contains_projected(&plane, centre))
                    .min_by(|a, b| a.length().total_cmp(&b.length())),
                LoopChoice::Nearest => loops.iter().min_by(|a, b| {
                    let da: f64 = pts.iter().filter_map(|p| a.closest(*p)).map(|c| c.distance).sum();
                    let db: f64 = pts.iter().filter_map(|p| b.closest(*p)).map(|c| c.distance).sum();
                    da.total_cmp(&db)
                }),
            };
            let Some(chosen) = chosen else {
                return Err(FeatureError::NoSection {
                    curve: id,
                    reason: format!("around its landmarks ({} loops in its plane)", loops.len()),
                });
            };
            let mut poly = chosen.clone();
            poly.closed = true;
            // legs pressed together: the section runs round both; the girth is this
            // leg's side of the plane midway between the pair
            if let Some(mid) = leg_midplane(id, snapped) {
                poly = poly.clipped(&mid).ok_or_else(|| FeatureError::NoSection {
                    curve: id,
                    reason: "on its leg's side of the plane midway between the legs".into(),
                })?;
            }
            if poly.signed_area(orientation.vector()) < 0.0 {
                poly = poly.reversed();
            }
            Ok(FeatureCurve { polyline: poly, plane: Some(plane) })
        }
        CurveRule::Path { landmarks, depth } => {
            let mut out: Vec<DVec3> = Vec::new();
            let last = landmarks.len().saturating_sub(2);
            let ext = opts.path_extension_mm / MM_PER_M;
            for (k, pair) in landmarks.windows(2).enumerate() {
                let (a, b) = (snapped[&pair[0]], snapped[&pair[1]]);
                let extend = (if k == 0 { ext } else { 0.0 }, if k == last { ext } else { 0.0 });
                let piece = path_piece(mesh, a, b, depth.vector(), extend).ok_or_else(|| FeatureError::NoSection {
                    curve: id,
                    reason: format!("from `{}` to `{}`", pair[0], pair[1]),
                })?;
                let skip = usize::from(!out.is_empty());
                out.extend(piece.points.into_iter().skip(skip));
            }
            Ok(FeatureCurve { polyline: Polyline::new(out, false), plane: None })
        }
    }
}

/// The shorter arc from `a` to `b` of the section through `a` with normal
/// `(b − a) × d`, on the loop nearest to both points, continued by
/// `extend.0` before `a` and `extend.1` past `b` (m) along the same loop.
fn path_piece(mesh: &TriMesh, a: DVec3, b: DVec3, d: DVec3, extend: (f64, f64)) -> Option<Polyline> {
    let plane = Plane::from_point_normal(a, (b - a).cross(d))?;
    let sections = slice(mesh, &plane);
    let dist = |p: &Polyline, q: DVec3| p.closest(q).map_or(f64::INFINITY, |c| c.distance);
    let best = sections
        .iter()
        .map(|s| &s.polyline)
        .min_by(|x, y| (dist(x, a) + dist(x, b)).total_cmp(&(dist(y, a) + dist(y, b))))?;
    let sa = best.closest(a)?.s;
    let sb = best.closest(b)?.s;
    let forward = if best.closed { best.arc(sa, sb).length() <= best.arc(sb, sa).length() } else { sa <= sb };
    let arc = if forward {
        best.arc(sa - extend.0, sb + extend.1)
    } else {
        best.arc(sb - extend.1, sa + extend.0).reversed()
    };
    Some(arc)
}
