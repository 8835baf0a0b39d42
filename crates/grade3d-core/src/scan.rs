//! Scans as they come (issue #17): a triangle soup as a scanner or a phone
//! app hands it over — any units, `+Y` or `+Z` up, any facing, holes,
//! degenerate and duplicate triangles, with or without landmarks — made
//! into a [`FeatureBody`].
//!
//! # Method
//!
//! 1. [`repair`] (counted in [`RepairReport`]);
//! 2. [`body_frame`]: units, up axis and facing detected or taken as
//!    given, the body brought into metres, `+Y` up, facing `+Z`, and a
//!    body out of the reference pose refused;
//! 3. landmarks: those supplied (in the scan's axes, their document's own
//!    units) are turned with the body; where they lack any the vocabulary
//!    requires ([`required_landmarks`]), the embedded model is registered
//!    to the scan ([`register`]) and gives every landmark, the supplied
//!    ones overriding its points one by one;
//! 4. [`derive_features`] on the repaired, framed scan.
//!
//! # Failure modes
//!
//! [`ScanError`]: one variant per step, each carrying the step's own error.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::body::derive::{derive_features, DeriveOptions, FeatureError, Landmarks};
use crate::body::feature::FeatureBody;
use crate::body::frame::{body_frame, FrameError, FrameHints, FrameOptions, FrameReport};
use crate::body::vocab::{required_landmarks, PointId};
use crate::geom::polyline::Polyline;
use crate::geom::repair::{repair, RepairError, RepairOptions, RepairReport};
use crate::mannequin::model::{BodyModel, MannequinError};
use crate::mannequin::register::{register, RegisterError, RegisterOptions, RegistrationReport};

/// Knobs of [`scan_body`], one per step.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct ScanOptions {
    /// Step 1.
    pub repair: RepairOptions,
    /// Step 2.
    pub frame: FrameOptions,
    /// Step 3, where landmarks are missing.
    pub register: RegisterOptions,
    /// Step 4.
    pub derive: DeriveOptions,
}

/// What [`scan_body`] did to the input, for the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct ScanReport {
    /// Step 1's counts.
    pub repair: RepairReport,
    /// Step 2's findings.
    pub frame: FrameReport,
    /// Landmarks supplied (and used).
    pub landmarks_supplied: usize,
    /// Landmarks found by registration and used (not overridden).
    pub landmarks_found: usize,
    /// The registration, where one ran.
    pub registration: Option<RegistrationReport>,
    /// Every landmark used (supplied or found), on the scan, in the scan's
    /// own axes and in metres: a landmarks document's `points` as they
    /// were read, so that one can be corrected and the scan sent again.
    #[schema(value_type = BTreeMap<String, [f64; 3]>)]
    pub landmarks: BTreeMap<PointId, [f64; 3]>,
}

/// Why a scan could not be made into a feature body.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScanError {
    /// The soup could not be repaired.
    #[error(transparent)]
    Repair(#[from] RepairError),
    /// Units, axes or pose.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// The embedded model could not be loaded.
    #[error(transparent)]
    Model(#[from] MannequinError),
    /// Automatic landmarks failed.
    #[error(transparent)]
    Register(#[from] RegisterError),
    /// The feature model could not be derived.
    #[error(transparent)]
    Feature(#[from] FeatureError),
}

/// A scan made into a feature body (module docs). `supplied`: the
/// landmarks given with it, if any.
///
/// # Errors
/// [`ScanError`].
pub fn scan_body(
    positions: &[DVec3],
    triangles: &[[u64; 3]],
    hints: &FrameHints,
    supplied: Option<&Landmarks>,
    opts: &ScanOptions,
) -> Result<(FeatureBody, ScanReport), ScanError> {
    let (mesh, repaired) = repair(positions, triangles, &opts.repair)?;
    let (mesh, frame, framed) = body_frame(&mesh, hints, &opts.frame)?;
    let mut landmarks = Landmarks::default();
    if let Some(given) = supplied {
        landmarks.points = given.points.iter().map(|(&id, &p)| (id, frame.rotate(p))).collect();
        landmarks.curves = given
            .curves
            .iter()
            .map(|(&id, c)| (id, Polyline::new(c.points.iter().map(|&p| frame.rotate(p)).collect(), c.closed)))
            .collect();
    }
    let landmarks_supplied = landmarks.points.len();
    let complete = required_landmarks().iter().all(|id| landmarks.points.contains_key(id));
    let (registration, landmarks_found) = if complete {
        (None, 0)
    } else {
        let model = BodyModel::embedded()?;
        let reg = register(model, &mesh, &repaired.read_faces(), &opts.register)?;
        let mut found = 0;
        for (id, p) in reg.landmarks.points {
            if let std::collections::btree_map::Entry::Vacant(e) = landmarks.points.entry(id) {
                e.insert(p);
                found += 1;
            }
        }
        (Some(reg.report), found)
    };
    let body = derive_features(mesh, &landmarks, &opts.derive)?;
    let back = frame.rotation.transpose();
    let used = landmarks.points.iter().map(|(&id, &p)| (id, (back * p).to_array())).collect();
    let report = ScanReport {
        repair: repaired,
        frame: framed,
        landmarks_supplied,
        landmarks_found,
        registration,
        landmarks: used,
    };
    Ok((body, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::frame::{Axis, Units};
    use crate::mannequin::landmarks::{hm08_landmarks, Hm08LandmarkOptions};
    use crate::mannequin::model::MannequinParams;
    use glam::DMat3;

    fn soup(tris: &[[crate::geom::mesh::VertexId; 3]]) -> Vec<[u64; 3]> {
        tris.iter().map(|t| t.map(|v| u64::from(v.0))).collect()
    }

    #[test]
    fn a_reference_body_with_its_landmarks_goes_straight_through() {
        let model = BodyModel::embedded().expect("model");
        let mesh = model.build(&MannequinParams::default()).expect("body");
        let lm = hm08_landmarks(model, &mesh, &Hm08LandmarkOptions::default()).expect("landmarks");
        let (body, r) = scan_body(
            mesh.positions(),
            &soup(mesh.triangles()),
            &FrameHints::default(),
            Some(&lm),
            &ScanOptions::default(),
        )
        .expect("a feature body");
        assert!(!r.repair.changed(), "{:?}", r.repair);
        assert_eq!((r.landmarks_supplied, r.landmarks_found, r.registration.is_none()), (lm.points.len(), 0, true));
        assert_eq!(body.mesh.vertex_count(), mesh.vertex_count());
    }

    #[test]
    fn a_millimetre_z_up_body_without_landmarks_is_framed_registered_and_derived() {
        let model = BodyModel::embedded().expect("model");
        let mesh = model.build(&MannequinParams::default()).expect("body");
        let z_up = DMat3::from_rotation_x(std::f64::consts::FRAC_PI_2);
        let positions: Vec<DVec3> = mesh.positions().iter().map(|&p| z_up * p * 1000.0).collect();
        // one supplied point, in metres in the scan's axes, overrides the model's
        let truth = hm08_landmarks(model, &mesh, &Hm08LandmarkOptions::default()).expect("landmarks");
        let mut given = Landmarks::default();
        let crotch = truth.points[&PointId::Crotch];
        given.points.insert(PointId::Crotch, z_up * crotch);
        let (body, r) = scan_body(
            &positions,
            &soup(mesh.triangles()),
            &FrameHints::default(),
            Some(&given),
            &ScanOptions::default(),
        )
        .expect("a feature body");
        assert_eq!((r.frame.units, r.frame.up, r.frame.facing), (Units::Millimetres, Axis::PosZ, Axis::NegY));
        assert_eq!(r.landmarks_supplied, 1);
        assert_eq!(r.landmarks_found, truth.points.len() - 1);
        let reg = r.registration.expect("registered");
        assert!(reg.rms_mm < 1.5, "{reg:?}");
        assert!(body.points[&PointId::Crotch].position.distance(crotch) < 0.01);
        // the landmarks used, in the scan's axes: the supplied one as it was given
        assert_eq!(r.landmarks.len(), truth.points.len());
        assert!(DVec3::from_array(r.landmarks[&PointId::Crotch]).distance(z_up * crotch) < 1e-12);
    }
}
