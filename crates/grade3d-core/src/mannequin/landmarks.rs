//! Landmarks of an hm08 body, found on its own geometry.
//!
//! MakeHuman's measurement rings (`measures.json`) are girth lines drawn
//! on the hm08 topology; they follow the body under every target. From
//! them, on any hm08 body:
//! * neck base: the plane through the medial end of MakeHuman's
//!   `shoulder-dist` measure and its mirror that contains the lateral axis,
//!   tilted forward-down by [`Hm08LandmarkOptions::neck_base_tilt_deg`],
//!   meets the sagittal plane at the front neck point and the cervicale,
//!   and the coronal plane through its section's centroid at the side neck
//!   points (on a full trapezius the measure's end itself slides onto the
//!   front of the neck, where the neck base runs along the shoulder line;
//!   the centroid of the section as a wire, [`Polyline::length_centroid`]:
//!   the section's vertices are where it crosses mesh edges, and their
//!   average jumped 1.7 mm back between two sizes of one graded chart);
//! * girth points: where a ring crosses the sagittal plane x = 0 (front:
//!   larger z, back: smaller z; moved to the closest point of the sagittal
//!   section, so that they lie on the surface at x = 0 even across the
//!   gluteal cleft) and the coronal plane through its centroid
//!   (left: larger x — the body's left is +X — right: smaller x);
//! * limb points: the outer crossing of the thigh, knee and ankle rings
//!   with the coronal plane through their centroids (the rings are on the
//!   left leg; the right leg's are their mirror images, `hm08.mirror`);
//!   a thigh point that would lie above
//!   [`Hm08LandmarkOptions::thigh_below_crotch_mm`] below the crotch comes
//!   from the leg's horizontal section at that depth instead (a thigh girth
//!   lies below the crotch);
//! * shoulder points: the lateral vertex of MakeHuman's `shoulder-dist`
//!   measure (the acromion) and its mirror;
//! * crotch: the lowest vertex on the sagittal plane (its own mirror);
//! * armpits: on the coronal section through the upper-arm ring, walking
//!   up the torso's side from bust height, the first local maximum of
//!   height (where the torso's side meets the underside of the arm);
//! * arms (vocabulary version 3): the elbow at the end of MakeHuman's
//!   `upperarm-length` measure, the wrist at the end of `lowerarm-length`,
//!   the upper arm at the centroid of `upperarm-circ`; each moved to the
//!   outermost point of the arm's section across its axis there (shoulder
//!   point to elbow for the upper arm, shoulder to wrist at the elbow,
//!   elbow to wrist at the wrist), outermost along `±Z × axis` — up and
//!   away from the body within the coronal plane, where the arm line runs
//!   over the top of the arm ([`outer_across`]). The right arm's from the
//!   mirrored vertices.
//!
//! Failure modes: a ring that does not cross its plane (a corrupt model)
//! gives [`LandmarkError`] naming the ring.

use glam::DVec3;

use super::model::BodyModel;
use crate::body::derive::Landmarks;
use crate::body::vocab::PointId;
use crate::geom::mesh::{TriMesh, VertexId};
use crate::geom::plane::Plane;
use crate::geom::polyline::Polyline;
use crate::geom::slice::{slice, Section};

/// Knobs of the hm08 landmark finder.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Hm08LandmarkOptions {
    /// Forward-down tilt of the neck base plane about the lateral axis
    /// through the side neck points, degrees (the front neck point lies
    /// below the cervicale). Default 25.
    pub neck_base_tilt_deg: f64,
    /// How far below the crotch the thigh points lie at least, mm. ISO
    /// 8559-1 measures the thigh girth just below the gluteal fold, so
    /// below the crotch; on heavy, short bodies MakeHuman's `thigh-circ`
    /// ring rides up to 14 mm *above* the crotch (it follows the topology,
    /// and the crotch sinks between full thighs), and its section there
    /// runs round both legs. The thigh points then come from the leg's
    /// horizontal section at this depth below the crotch instead. Default
    /// 10 (the fixtures' rings lie 14–57 mm below the crotch and keep
    /// their points).
    pub thigh_below_crotch_mm: f64,
}

impl Default for Hm08LandmarkOptions {
    fn default() -> Self {
        Self { neck_base_tilt_deg: 25.0, thigh_below_crotch_mm: 10.0 }
    }
}

/// A landmark that could not be found on an hm08 body.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("hm08 landmark `{point}` not found: {reason}")]
pub struct LandmarkError {
    /// The landmark.
    pub point: PointId,
    /// Why.
    pub reason: String,
}

fn ring(mesh: &TriMesh, ids: impl IntoIterator<Item = VertexId>) -> Polyline {
    let mut pts: Vec<DVec3> = Vec::new();
    for v in ids {
        let p = mesh.position(v);
        if pts.last() != Some(&p) {
            pts.push(p);
        }
    }
    if pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    Polyline::new(pts, true)
}

/// Points where a closed polyline crosses a plane.
fn plane_crossings(poly: &Polyline, plane: &Plane) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..poly.segment_count() {
        let (a, b) = poly.segment(i);
        let (da, db) = (plane.signed_distance(a), plane.signed_distance(b));
        if (da >= 0.0) != (db >= 0.0) {
            out.push(a.lerp(b, da / (da - db)));
        }
    }
    out
}

fn extreme(points: &[DVec3], key: impl Fn(DVec3) -> f64) -> Option<DVec3> {
    points.iter().copied().max_by(|a, b| key(*a).total_cmp(&key(*b)))
}

/// The landmarks of an hm08 body (a mesh built by [`BodyModel::build`]).
pub fn hm08_landmarks(
    model: &BodyModel,
    mesh: &TriMesh,
    opts: &Hm08LandmarkOptions,
) -> Result<Landmarks, LandmarkError> {
    let data = model.data();
    let ring_ids = |name: &str| -> Vec<VertexId> {
        data.rings.get(name).map(|r| r.iter().map(|&v| VertexId(u32::from(v))).collect()).unwrap_or_default()
    };
    let err = |point: PointId, reason: &str| LandmarkError { point, reason: reason.to_owned() };
    let mut lm = Landmarks::default();
    let sagittal = Plane { normal: DVec3::X, offset: 0.0 };

    // Front and back points are moved onto the sagittal section itself: a
    // ring's chord bridges the gluteal cleft, and the closest surface point
    // to a point in the air above a crease is on one side or the other.
    // Only the body's outline (the longest loop) counts: where the buttocks
    // press together the mesh can cross x = 0 in small extra loops.
    let midline = slice(mesh, &sagittal)
        .into_iter()
        .map(|s| s.polyline)
        .max_by(|a, b| a.length().total_cmp(&b.length()))
        .ok_or_else(|| err(PointId::Crotch, "no sagittal section"))?;
    let on_midline = |p: DVec3| midline.closest(p).map_or(p, |c| c.point);
    let girths = [
        ("bust-circ", [PointId::BustFront, PointId::BustBack, PointId::BustLeft, PointId::BustRight]),
        (
            "underbust-circ",
            [PointId::UnderbustFront, PointId::UnderbustBack, PointId::UnderbustLeft, PointId::UnderbustRight],
        ),
        ("waist-circ", [PointId::WaistFront, PointId::WaistBack, PointId::WaistLeft, PointId::WaistRight]),
        ("hips-circ", [PointId::HipFront, PointId::HipBack, PointId::HipLeft, PointId::HipRight]),
    ];
    for (name, [front, back, left, right]) in girths {
        let r = ring(mesh, ring_ids(name));
        let mid = plane_crossings(&r, &sagittal);
        lm.points.insert(front, on_midline(extreme(&mid, |p| p.z).ok_or_else(|| err(front, "ring misses x = 0"))?));
        lm.points.insert(back, on_midline(extreme(&mid, |p| -p.z).ok_or_else(|| err(back, "ring misses x = 0"))?));
        let coronal = Plane { normal: DVec3::Z, offset: r.centroid().z };
        let side = plane_crossings(&r, &coronal);
        lm.points.insert(left, extreme(&side, |p| p.x).ok_or_else(|| err(left, "ring misses its coronal plane"))?);
        lm.points.insert(right, extreme(&side, |p| -p.x).ok_or_else(|| err(right, "ring misses its coronal plane"))?);
    }
    // neck base: the plane through the side neck points (medial end of
    // MakeHuman's `shoulder-dist`, and its mirror), containing the lateral
    // axis and tilted forward-down by `neck_base_tilt_deg`; the front and
    // back neck points are where its section meets the sagittal plane.
    let side = ring_ids("shoulder-dist")
        .into_iter()
        .min_by(|a, b| mesh.position(*a).x.abs().total_cmp(&mesh.position(*b).x.abs()))
        .ok_or_else(|| err(PointId::NeckLeft, "no shoulder-dist measure"))?;
    let (nl, nr) = (mesh.position(side), mesh.position(model.mirror(side)));
    let (nl, nr) = if nl.x >= nr.x { (nl, nr) } else { (nr, nl) };
    let tilt = opts.neck_base_tilt_deg.to_radians();
    let centre = 0.5 * (nl + nr);
    let neck_plane = Plane::from_point_normal(centre, DVec3::new(0.0, tilt.cos(), tilt.sin()))
        .ok_or_else(|| err(PointId::NeckFront, "bad neck plane"))?;
    let neck = slice(mesh, &neck_plane)
        .into_iter()
        .map(|s| s.polyline)
        .filter(|p| p.closed && p.contains_projected(&neck_plane, centre))
        .min_by(|a, b| a.length().total_cmp(&b.length()))
        .ok_or_else(|| err(PointId::NeckFront, "the neck base plane misses the neck"))?;
    let mid = plane_crossings(&neck, &sagittal);
    lm.points.insert(PointId::NeckFront, extreme(&mid, |p| p.z).ok_or_else(|| err(PointId::NeckFront, "no front"))?);
    lm.points.insert(PointId::NeckBack, extreme(&mid, |p| -p.z).ok_or_else(|| err(PointId::NeckBack, "no back"))?);
    // the side neck points: where that section meets the coronal plane
    // through its centroid (as a wire: independent of which mesh edges the
    // plane crosses), as the girths' side points (the medial end of
    // `shoulder-dist` slides onto the front of a full trapezius: pop36)
    let coronal = Plane { normal: DVec3::Z, offset: neck.length_centroid().z };
    let side = plane_crossings(&neck, &coronal);
    let nl = extreme(&side, |p| p.x).ok_or_else(|| err(PointId::NeckLeft, "neck base misses its coronal plane"))?;
    let nr = extreme(&side, |p| -p.x).ok_or_else(|| err(PointId::NeckRight, "neck base misses its coronal plane"))?;
    lm.points.insert(PointId::NeckLeft, nl);
    lm.points.insert(PointId::NeckRight, nr);
    // crotch: lowest vertex on the sagittal plane (mirror of itself)
    let crotch = (0..mesh.vertex_count() as u32)
        .map(VertexId)
        .filter(|&v| model.mirror(v) == v)
        .map(|v| mesh.position(v))
        .min_by(|a, b| a.y.total_cmp(&b.y))
        .ok_or_else(|| err(PointId::Crotch, "no vertex on the sagittal plane"))?;
    lm.points.insert(PointId::Crotch, crotch);
    let thigh_top = crotch.y - opts.thigh_below_crotch_mm * 1e-3;
    let limbs = [
        ("thigh-circ", PointId::ThighLeft, PointId::ThighRight),
        ("knee-circ", PointId::KneeLeft, PointId::KneeRight),
        ("ankle-circ", PointId::AnkleLeft, PointId::AnkleRight),
    ];
    for (name, left, right) in limbs {
        let ids = ring_ids(name);
        let rl = ring(mesh, ids.iter().copied());
        let rr = ring(mesh, ids.iter().map(|&v| model.mirror(v)));
        // make sure "left" is the ring on +X whatever side the data uses
        let (rl, rr) = if rl.centroid().x >= rr.centroid().x { (rl, rr) } else { (rr, rl) };
        let cl = plane_crossings(&rl, &Plane { normal: DVec3::Z, offset: rl.centroid().z });
        let cr = plane_crossings(&rr, &Plane { normal: DVec3::Z, offset: rr.centroid().z });
        let mut pl = extreme(&cl, |p| p.x).ok_or_else(|| err(left, "ring misses its coronal plane"))?;
        let mut pr = extreme(&cr, |p| -p.x).ok_or_else(|| err(right, "ring misses its coronal plane"))?;
        if left == PointId::ThighLeft {
            // the thigh girth lies below the crotch (ISO 8559-1 5.3.20); one section for both legs
            let below = std::cell::OnceCell::new();
            let level = || below.get_or_init(|| slice(mesh, &Plane { normal: DVec3::Y, offset: thigh_top }));
            if pl.y > thigh_top {
                pl = outer_point_at(level(), pl, rl.centroid().z, 1.0).ok_or_else(|| err(left, BELOW))?;
            }
            if pr.y > thigh_top {
                pr = outer_point_at(level(), pr, rr.centroid().z, -1.0).ok_or_else(|| err(right, BELOW))?;
            }
        }
        lm.points.insert(left, pl);
        lm.points.insert(right, pr);
    }
    // shoulders: the lateral end of MakeHuman's shoulder-dist measure
    let sd = ring_ids("shoulder-dist");
    let acromion = sd
        .iter()
        .copied()
        .max_by(|a, b| mesh.position(*a).x.abs().total_cmp(&mesh.position(*b).x.abs()))
        .ok_or_else(|| err(PointId::ShoulderLeft, "no shoulder-dist measure"))?;
    let (sl, sr) = (mesh.position(acromion), mesh.position(model.mirror(acromion)));
    let (sl, sr) = if sl.x >= sr.x { (sl, sr) } else { (sr, sl) };
    lm.points.insert(PointId::ShoulderLeft, sl);
    lm.points.insert(PointId::ShoulderRight, sr);
    // armpits: on the coronal section through the upper arm
    let arm_z = ring(mesh, ring_ids("upperarm-circ")).centroid().z;
    // one coronal section for both sides (issue #15: it was cut twice)
    let coronal = slice(mesh, &Plane { normal: DVec3::Z, offset: arm_z });
    for (bust, id, sign) in
        [(PointId::BustLeft, PointId::UnderarmLeft, 1.0), (PointId::BustRight, PointId::UnderarmRight, -1.0)]
    {
        let start_y = lm.points[&bust].y;
        lm.points.insert(id, armpit(&coronal, start_y, sign).ok_or_else(|| err(id, "no armpit above the bust"))?);
    }
    // arms: MakeHuman's arm-length measures end at the elbow and the wrist
    let end =
        |name: &str, point: PointId| ring_ids(name).last().copied().ok_or_else(|| err(point, "no arm-length measure"));
    let (elbow_v, wrist_v) = (end("upperarm-length", PointId::ElbowLeft)?, end("lowerarm-length", PointId::WristLeft)?);
    let upper_ring = ring_ids("upperarm-circ");
    for (sign, [shoulder, upper, elbow, wrist]) in [
        (1.0, [PointId::ShoulderLeft, PointId::UpperArmLeft, PointId::ElbowLeft, PointId::WristLeft]),
        (-1.0, [PointId::ShoulderRight, PointId::UpperArmRight, PointId::ElbowRight, PointId::WristRight]),
    ] {
        // of a position and its mirror image, the one on this side (the data's arm may be either)
        let this_side = |a: DVec3, b: DVec3| if a.x * sign >= b.x * sign { a } else { b };
        let on_side = |v: VertexId| this_side(mesh.position(v), mesh.position(model.mirror(v)));
        let s = lm.points[&shoulder];
        let (e0, w0) = (on_side(elbow_v), on_side(wrist_v));
        let ring_centre = this_side(
            ring(mesh, upper_ring.iter().copied()).centroid(),
            ring(mesh, upper_ring.iter().map(|&v| model.mirror(v))).centroid(),
        );
        let w = outer_across(mesh, w0, w0 - e0, sign).ok_or_else(|| err(wrist, "no section across the forearm"))?;
        let e = outer_across(mesh, e0, w - s, sign).ok_or_else(|| err(elbow, "no section across the elbow"))?;
        let u = outer_across(mesh, ring_centre, e - s, sign)
            .ok_or_else(|| err(upper, "no section across the upper arm"))?;
        lm.points.insert(upper, u);
        lm.points.insert(elbow, e);
        lm.points.insert(wrist, w);
    }
    Ok(lm)
}

/// The outermost point of the arm's section across `axis` through `at`
/// (the closed loop nearest `at`): farthest along `sign · (Z × axis)` (`sign`
/// +1 for the left arm, −1 for the right), up and away from the body
/// within the coronal plane. `None` where the plane misses the arm.
fn outer_across(mesh: &TriMesh, at: DVec3, axis: DVec3, sign: f64) -> Option<DVec3> {
    let plane = Plane::from_point_normal(at, axis)?;
    let out = DVec3::Z.cross(axis) * sign;
    let near = slice(mesh, &plane).into_iter().map(|s| s.polyline).filter(|p| p.closed).min_by(|a, b| {
        let d = |p: &Polyline| p.closest(at).map_or(f64::INFINITY, |c| c.distance);
        d(a).total_cmp(&d(b))
    })?;
    extreme(&near.points, |p| p.dot(out))
}

/// Why a thigh point below the crotch was not found.
const BELOW: &str = "no section of the leg below the crotch";

/// The outer point (`sign` +1: largest x, −1: smallest) where the loop of
/// `level` (the mesh's horizontal section at some height) nearest to
/// `near` crosses the coronal plane `z = z`: the loop round the leg, or
/// round both legs where they touch (its outer crossing is still this
/// leg's side), never a hand.
fn outer_point_at(level: &[Section], near: DVec3, z: f64, sign: f64) -> Option<DVec3> {
    let leg = level.iter().map(|s| &s.polyline).filter(|p| p.closed).min_by(|a, b| {
        let d = |p: &Polyline| p.closest(near).map_or(f64::INFINITY, |c| c.point.distance(near));
        d(a).total_cmp(&d(b))
    })?;
    extreme(&plane_crossings(leg, &Plane { normal: DVec3::Z, offset: z }), |p| sign * p.x)
}

/// On `coronal`, the mesh's section by a coronal plane through the upper
/// arms, starts at the torso's side at height `start_y` (the crossing
/// nearest the midline on the side `sign`) and walks up to the first local
/// maximum of height.
fn armpit(coronal: &[Section], start_y: f64, sign: f64) -> Option<DVec3> {
    let level = Plane { normal: DVec3::Y, offset: start_y };
    let mut best: Option<(f64, &Polyline, DVec3)> = None;
    for s in coronal.iter().filter(|s| s.polyline.closed) {
        for p in plane_crossings(&s.polyline, &level) {
            let x = p.x * sign;
            if x > 0.0 && best.as_ref().is_none_or(|b| x < b.0) {
                best = Some((x, &s.polyline, p));
            }
        }
    }
    let (_, poly, start) = best?;
    let n = poly.points.len();
    let i0 = (0..n).min_by(|&a, &b| poly.points[a].distance(start).total_cmp(&poly.points[b].distance(start)))?;
    let up = if poly.points[(i0 + 1) % n].y >= poly.points[(i0 + n - 1) % n].y { 1 } else { n - 1 };
    let mut i = i0;
    for _ in 0..n {
        let j = (i + up) % n;
        if poly.points[j].y < poly.points[i].y {
            return Some(poly.points[i]);
        }
        i = j;
    }
    None
}
