//! A scan's frame and pose (issue #17, item 1): units, up axis and facing
//! direction detected (or taken as given) and the body brought into the
//! frame every body here is in — metres, `+Y` up, facing `+Z`, its left at
//! `+X` — and a body that is not in the reference pose refused with what is
//! off.
//!
//! # Method
//!
//! With `h` the extent along the up axis (the stature of a standing body)
//! and slabs taken as shares of it, measured from the soles:
//! - **Up axis**: glTF's `+Y`, or `+Z` (scanners and CAD tools that export
//!   without converting). Detected as the longer of the Y and Z extents —
//!   a standing body is taller than it is wide or deep (a T-pose is as wide
//!   as tall, and is refused below).
//! - **Units**: the first of metres, centimetres and millimetres in which
//!   `h` is a plausible stature ([`FrameOptions::min_stature_m`] to
//!   [`FrameOptions::max_stature_m`]).
//! - **Facing**: the lateral axis is the wider of the two horizontal axes
//!   (shoulders and arms against chest depth); along the other, the body
//!   faces where its feet point: the area-weighted centroid of the skin
//!   below [`FrameOptions::toe_share`] × `h` (the feet, toes forward of the
//!   ankle) lies ahead of the centroid of the slab just above the feet
//!   ([`FrameOptions::ankle_shares`]), by a tenth of a foot or more.
//! - **Pose**: the reference pose is MakeHuman's A-pose, upright.
//!   *Lean*: the angle from vertical of the line through the centroids of
//!   the ankle slab and the head slab ([`FrameOptions::head_shares`]; a
//!   plumb line from the ear falls just ahead of the ankle), at most
//!   [`FrameOptions::max_lean_deg`]. *Arms*: the body's width above mid
//!   height over `h` (arms down: about 0.3; the A-pose: 0.5–0.6; a T-pose:
//!   1.0) within [`FrameOptions::arm_span_range`].
//!
//! The transform is `p ↦ s R p` (scale to metres, rotation to the body
//! frame); no translation, so a body's landmarks, given in its own axes,
//! follow by `R` alone ([`BodyFrame::rotate`]; a landmarks document states
//! its own units).
//!
//! # Failure modes
//!
//! [`FrameError`]: no unit makes the height a stature, a facing that
//! cannot be told, a lean or an arm span outside the reference pose — each
//! naming the figure and the range allowed.

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

use crate::geom::mesh::{MeshError, TriMesh};

/// Length units of a scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
pub enum Units {
    /// Metres (glTF's unit).
    #[serde(rename = "m")]
    Metres,
    /// Centimetres.
    #[serde(rename = "cm")]
    Centimetres,
    /// Millimetres.
    #[serde(rename = "mm")]
    Millimetres,
}

impl Units {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            Self::Metres => 1.0,
            Self::Centimetres => 1e-2,
            Self::Millimetres => 1e-3,
        }
    }

    /// Every unit, in the order detection tries them.
    pub const ALL: [Units; 3] = [Units::Metres, Units::Centimetres, Units::Millimetres];
}

/// A signed axis of the input's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
pub enum Axis {
    /// `+X`.
    #[serde(rename = "+x")]
    PosX,
    /// `−X`.
    #[serde(rename = "-x")]
    NegX,
    /// `+Y`.
    #[serde(rename = "+y")]
    PosY,
    /// `−Y`.
    #[serde(rename = "-y")]
    NegY,
    /// `+Z`.
    #[serde(rename = "+z")]
    PosZ,
    /// `−Z`.
    #[serde(rename = "-z")]
    NegZ,
}

impl Axis {
    /// The unit vector.
    pub fn vector(self) -> DVec3 {
        match self {
            Self::PosX => DVec3::X,
            Self::NegX => DVec3::NEG_X,
            Self::PosY => DVec3::Y,
            Self::NegY => DVec3::NEG_Y,
            Self::PosZ => DVec3::Z,
            Self::NegZ => DVec3::NEG_Z,
        }
    }

    /// The axis along `v`'s largest component, with its sign.
    fn of(v: DVec3) -> Self {
        let a = v.abs();
        if a.x >= a.y && a.x >= a.z {
            if v.x >= 0.0 {
                Self::PosX
            } else {
                Self::NegX
            }
        } else if a.y >= a.z {
            if v.y >= 0.0 {
                Self::PosY
            } else {
                Self::NegY
            }
        } else if v.z >= 0.0 {
            Self::PosZ
        } else {
            Self::NegZ
        }
    }
}

/// What the caller states about a scan; the rest is detected.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FrameHints {
    /// Its units.
    pub units: Option<Units>,
    /// Its up direction (`+y` or `+z`).
    pub up: Option<Axis>,
    /// The direction the body faces, in the scan's axes.
    pub facing: Option<Axis>,
}

/// Knobs of [`body_frame`]; shares are of the stature, measured from the soles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FrameOptions {
    /// Smallest stature taken as a body's, m. Default 0.5 (as
    /// [`crate::body::derive::DeriveOptions::min_stature_m`]).
    pub min_stature_m: f64,
    /// Largest, m. Default 2.5.
    pub max_stature_m: f64,
    /// The feet slab: below this share. Default 0.03 (about 5 cm: toes and
    /// heel, under the ankle bone).
    pub toe_share: f64,
    /// The slab above the feet, as shares. Default 0.05–0.09 (the ankle
    /// and lower shin, over the heel).
    pub ankle_shares: [f64; 2],
    /// Least forward offset of the feet over the ankles that tells the
    /// facing, share. Default 0.006 (1 cm at 1.7 m; an hm08 foot is 4–7 cm
    /// ahead of its ankle).
    pub min_toe_offset_share: f64,
    /// The head slab, whose centroid the lean is measured to from the
    /// ankles'. Default 0.88–0.94 (chin to brow: the head alone, no arms).
    pub head_shares: [f64; 2],
    /// Largest lean from vertical, degrees. Default 10 (the population of
    /// issue #7 stands within 3°).
    pub max_lean_deg: f64,
    /// Allowed width of the body above mid height over its stature.
    /// Default 0.40–0.80 (the hm08 population's A-pose spans 0.48–0.66;
    /// arms against the body or raised to a T-pose fall outside).
    pub arm_span_range: [f64; 2],
}

impl Default for FrameOptions {
    fn default() -> Self {
        Self {
            min_stature_m: 0.5,
            max_stature_m: 2.5,
            toe_share: 0.03,
            ankle_shares: [0.05, 0.09],
            min_toe_offset_share: 0.006,
            head_shares: [0.88, 0.94],
            max_lean_deg: 10.0,
            arm_span_range: [0.40, 0.80],
        }
    }
}

/// The transform into the body frame (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyFrame {
    /// Metres per input unit.
    pub scale: f64,
    /// Input axes → body axes.
    pub rotation: DMat3,
}

impl BodyFrame {
    /// A point of the input, in the body frame.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.rotation * p * self.scale
    }

    /// A point already in metres, in the input's axes, in the body frame.
    pub fn rotate(&self, p: DVec3) -> DVec3 {
        self.rotation * p
    }
}

/// The rotation taking up axis `up` (`+Y` or `+Z`) to `+Y`.
fn upright(up: Axis) -> DMat3 {
    match up {
        // the columns are the images of the input's axes: (x, y, z) ↦ (x, z, −y)
        Axis::PosZ => DMat3::from_cols(DVec3::X, DVec3::NEG_Z, DVec3::Y),
        _ => DMat3::IDENTITY,
    }
}

/// The rotation about `+Y` taking the horizontal axis direction `facing`
/// to `+Z` (its entries snapped to −1, 0, 1).
fn turn_to_face(facing: DVec3) -> DMat3 {
    let turn = DMat3::from_rotation_y(facing.x.atan2(facing.z)).transpose();
    DMat3::from_cols(snap(turn.x_axis), snap(turn.y_axis), snap(turn.z_axis))
}

impl FrameReport {
    /// The transform [`body_frame`] applied to the scan it reports on
    /// (from its units, up axis and facing): what brings anything given in
    /// the scan's own axes and units into the body frame with it — a
    /// garment exported with the avatar it was draped on.
    pub fn transform(&self) -> BodyFrame {
        let upright = upright(self.up);
        BodyFrame { scale: self.units.metres(), rotation: turn_to_face(upright * self.facing.vector()) * upright }
    }
}

/// What [`body_frame`] found, for the report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FrameReport {
    /// The units.
    pub units: Units,
    /// Whether they were detected (not stated).
    pub units_detected: bool,
    /// The up direction, in the scan's axes.
    pub up: Axis,
    /// Whether it was detected.
    pub up_detected: bool,
    /// The facing direction, in the scan's axes.
    pub facing: Axis,
    /// Whether it was detected.
    pub facing_detected: bool,
    /// The stature, m.
    pub stature_m: f64,
    /// The lean from vertical, degrees.
    pub lean_deg: f64,
    /// Width above mid height over stature.
    pub arm_span_share: f64,
}

/// Why a scan could not be brought into the body frame.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// The mesh could not be transformed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A stated up direction other than `+y` or `+z`, or a facing not
    /// across it.
    #[error("{what} `{axis:?}` is not allowed: {reason}")]
    Axes {
        /// `up` or `facing`.
        what: &'static str,
        /// The axis given.
        axis: Axis,
        /// Why not.
        reason: &'static str,
    },
    /// No unit makes the height a stature.
    #[error(
        "the body is {height} units tall along {up:?}: not a stature of {min_m}–{max_m} m in metres, centimetres \
         or millimetres; state `units`"
    )]
    Units {
        /// Extent along the up axis, input units.
        height: f64,
        /// The up axis.
        up: Axis,
        /// Smallest stature, m.
        min_m: f64,
        /// Largest, m.
        max_m: f64,
    },
    /// The stated units make the height no stature.
    #[error("with `units` {units:?} the body is {stature_m:.3} m tall: not a stature of {min_m}–{max_m} m")]
    StatedUnits {
        /// The units stated.
        units: Units,
        /// The stature they give, m.
        stature_m: f64,
        /// Smallest stature, m.
        min_m: f64,
        /// Largest, m.
        max_m: f64,
    },
    /// The facing direction could not be told.
    #[error(
        "cannot tell which way the body faces: its feet reach {offset_mm:.0} mm ahead of the ankles either way \
         (at least {min_mm:.0} mm needed); state `facing`"
    )]
    Facing {
        /// The feet's offset found, mm.
        offset_mm: f64,
        /// The least that tells, mm.
        min_mm: f64,
    },
    /// The body is not in the reference pose.
    #[error("the body is not in the reference pose (upright, arms in an A-pose): {what} is {value:.2}, allowed {min:.2}–{max:.2}")]
    Pose {
        /// What is off: `lean (degrees)` or `arm span / stature`.
        what: &'static str,
        /// Its value.
        value: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
}

/// Area-weighted face centroids and areas.
fn weighted_centroids(mesh: &TriMesh) -> Vec<(DVec3, f64)> {
    (0..mesh.face_count())
        .map(|f| {
            let [a, b, c] = mesh.corners(f.into());
            ((a + b + c) / 3.0, 0.5 * (b - a).cross(c - a).length())
        })
        .collect()
}

/// The area-weighted centroid of the faces whose centroid height (`y`,
/// from `floor`) lies within `shares × h`.
fn slab(faces: &[(DVec3, f64)], floor: f64, h: f64, shares: [f64; 2]) -> Option<DVec3> {
    let (sum, w) = faces
        .iter()
        .filter(|(c, _)| (shares[0] * h..=shares[1] * h).contains(&(c.y - floor)))
        .fold((DVec3::ZERO, 0.0), |(s, w), (c, a)| (s + *c * *a, w + a));
    (w > 0.0).then(|| sum / w)
}

/// Brings `mesh` into the body frame (module docs).
///
/// # Errors
/// [`FrameError`].
pub fn body_frame(
    mesh: &TriMesh,
    hints: &FrameHints,
    opts: &FrameOptions,
) -> Result<(TriMesh, BodyFrame, FrameReport), FrameError> {
    let size = mesh.aabb().size();
    let up = match hints.up {
        Some(a @ (Axis::PosY | Axis::PosZ)) => a,
        Some(a) => return Err(FrameError::Axes { what: "up", axis: a, reason: "a scan is +y up (glTF) or +z up" }),
        None if size.z > size.y => Axis::PosZ,
        None => Axis::PosY,
    };
    let height = size.dot(up.vector());
    let stature_ok = |u: Units| (opts.min_stature_m..=opts.max_stature_m).contains(&(height * u.metres()));
    let units = match hints.units {
        Some(u) if !stature_ok(u) => {
            return Err(FrameError::StatedUnits {
                units: u,
                stature_m: height * u.metres(),
                min_m: opts.min_stature_m,
                max_m: opts.max_stature_m,
            })
        }
        Some(u) => u,
        None => Units::ALL.into_iter().find(|&u| stature_ok(u)).ok_or(FrameError::Units {
            height,
            up,
            min_m: opts.min_stature_m,
            max_m: opts.max_stature_m,
        })?,
    };
    let scale = units.metres();
    // up to +Y first; the facing below is found in that frame
    let upright = upright(up);
    let standing = mesh.map_positions(|p| upright * p * scale)?;
    let faces = weighted_centroids(&standing);
    let aabb = standing.aabb();
    let (floor, h) = (aabb.min.y, aabb.size().y);
    let facing_body = match hints.facing {
        Some(a) => {
            let v = upright * a.vector();
            if v.y.abs() > 0.5 {
                return Err(FrameError::Axes { what: "facing", axis: a, reason: "the facing runs across the up axis" });
            }
            v
        }
        None => {
            // lateral: the wider horizontal axis; sagittal: the other
            let sagittal = if aabb.size().x >= aabb.size().z { DVec3::Z } else { DVec3::X };
            let feet = slab(&faces, floor, h, [0.0, opts.toe_share]);
            let ankles = slab(&faces, floor, h, opts.ankle_shares);
            let offset = match (feet, ankles) {
                (Some(f), Some(a)) => (f - a).dot(sagittal),
                _ => 0.0,
            };
            let min = opts.min_toe_offset_share * h;
            if offset.abs() < min {
                return Err(FrameError::Facing { offset_mm: offset.abs() * 1e3, min_mm: min * 1e3 });
            }
            sagittal * offset.signum()
        }
    };
    let turn = turn_to_face(facing_body);
    let rotation = turn * upright;
    let body = standing.map_positions(|p| turn * p)?;
    let faces: Vec<(DVec3, f64)> = faces.into_iter().map(|(c, a)| (turn * c, a)).collect();
    // pose
    let lean_deg = match (slab(&faces, floor, h, opts.head_shares), slab(&faces, floor, h, opts.ankle_shares)) {
        (Some(s), Some(p)) => {
            let d = s - p;
            DVec3::new(d.x, 0.0, d.z).length().atan2(d.y).to_degrees()
        }
        _ => 0.0,
    };
    if lean_deg > opts.max_lean_deg {
        return Err(FrameError::Pose { what: "lean (degrees)", value: lean_deg, min: 0.0, max: opts.max_lean_deg });
    }
    let (lo, hi) = body
        .positions()
        .iter()
        .filter(|p| p.y - floor > 0.5 * h)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.x), hi.max(p.x)));
    let arm_span_share = (hi - lo) / h;
    let [min, max] = opts.arm_span_range;
    if !(min..=max).contains(&arm_span_share) {
        return Err(FrameError::Pose { what: "arm span / stature", value: arm_span_share, min, max });
    }
    let facing = Axis::of(rotation.transpose() * DVec3::Z);
    let report = FrameReport {
        units,
        units_detected: hints.units.is_none(),
        up,
        up_detected: hints.up.is_none(),
        facing,
        facing_detected: hints.facing.is_none(),
        stature_m: h,
        lean_deg,
        arm_span_share,
    };
    Ok((body, BodyFrame { scale, rotation }, report))
}

/// A rotation column with its components rounded to −1, 0 or 1 where they
/// are within rounding of them (quarter turns stay exact).
fn snap(v: DVec3) -> DVec3 {
    let r = |x: f64| if (x - x.round()).abs() < 1e-12 { x.round() } else { x };
    DVec3::new(r(v.x), r(v.y), r(v.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mannequin::model::{BodyModel, MannequinParams};

    fn hm08() -> TriMesh {
        BodyModel::embedded().expect("model").build(&MannequinParams::default()).expect("body")
    }

    #[test]
    fn the_reference_body_is_left_where_it_is() {
        let body = hm08();
        let (out, frame, r) = body_frame(&body, &FrameHints::default(), &FrameOptions::default()).expect("frame");
        assert!(out == body, "unchanged");
        assert_eq!(frame.rotation, DMat3::IDENTITY);
        assert_eq!((r.units, r.up, r.facing), (Units::Metres, Axis::PosY, Axis::PosZ));
        assert!(r.lean_deg < 3.0, "{r:?}");
        assert!((0.45..0.7).contains(&r.arm_span_share), "{r:?}");
    }

    #[test]
    fn millimetres_z_up_and_any_facing_are_found_and_undone() {
        let body = hm08();
        // z up (x, y, z) -> (x, -z, y), then turned about the new up axis, in mm
        for (facing, turn) in [(Axis::NegY, 0.0), (Axis::PosX, 0.5), (Axis::PosY, 1.0), (Axis::NegX, 1.5)] {
            let rot = DMat3::from_rotation_z(turn * std::f64::consts::PI)
                * DMat3::from_rotation_x(std::f64::consts::FRAC_PI_2);
            let scan = body.map_positions(|p| rot * p * 1000.0).expect("mesh");
            let (out, frame, r) = body_frame(&scan, &FrameHints::default(), &FrameOptions::default()).expect("frame");
            assert_eq!((r.units, r.up, r.facing), (Units::Millimetres, Axis::PosZ, facing), "turn {turn}");
            // the report gives back the transform (a garment exported with the scan follows it)
            assert_eq!(r.transform(), frame, "turn {turn}");
            for (a, b) in out.positions().iter().zip(body.positions()) {
                assert!(a.distance(*b) < 1e-9, "turn {turn}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn stated_hints_are_kept_and_bad_ones_named() {
        let body = hm08().map_positions(|p| p * 100.0).expect("mesh");
        let hints = FrameHints { units: Some(Units::Centimetres), up: Some(Axis::PosY), facing: Some(Axis::PosZ) };
        let (_, _, r) = body_frame(&body, &hints, &FrameOptions::default()).expect("frame");
        assert!(!r.units_detected && !r.up_detected && !r.facing_detected);
        let bad = FrameHints { facing: Some(Axis::PosY), ..FrameHints::default() };
        assert!(matches!(
            body_frame(&body, &bad, &FrameOptions::default()),
            Err(FrameError::Axes { what: "facing", .. })
        ));
        let stated = FrameHints { units: Some(Units::Millimetres), ..FrameHints::default() };
        assert!(matches!(body_frame(&body, &stated, &FrameOptions::default()), Err(FrameError::StatedUnits { .. })));
        let tiny = hm08().map_positions(|p| p * 0.01).expect("mesh");
        assert!(matches!(
            body_frame(&tiny, &FrameHints::default(), &FrameOptions::default()),
            Err(FrameError::Units { .. })
        ));
    }

    #[test]
    fn a_lean_and_raised_arms_are_refused_by_name() {
        let body = hm08();
        // a 15° lean forward about the soles
        let lean = DMat3::from_rotation_x(15f64.to_radians());
        let leaning = body.map_positions(|p| lean * p).expect("mesh");
        let hints = FrameHints { facing: Some(Axis::PosZ), ..Default::default() };
        let e = body_frame(&leaning, &hints, &FrameOptions::default()).map(|r| r.2);
        assert!(matches!(e, Err(FrameError::Pose { what: "lean (degrees)", .. })), "{e:?}");
        // arms stretched sideways: every vertex beyond the shoulders moved out
        let (floor, h) = (body.aabb().min.y, body.aabb().size().y);
        let spread = body
            .map_positions(|p| {
                if p.y - floor > 0.55 * h && p.x.abs() > 0.2 {
                    DVec3::new(p.x.signum() * (p.x.abs() * 2.6), p.y, p.z)
                } else {
                    p
                }
            })
            .expect("mesh");
        let e = body_frame(&spread, &FrameHints::default(), &FrameOptions::default()).map(|r| r.2);
        assert!(matches!(e, Err(FrameError::Pose { what: "arm span / stature", .. })), "{e:?}");
    }
}
