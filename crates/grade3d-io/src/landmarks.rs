//! The landmarks JSON that comes with a body scan.
//!
//! ```json
//! { "vocabulary": 1, "units": "m",
//!   "points": { "waist_front": [0.0, 1.02, 0.13], "…": [0, 0, 0] },
//!   "curves": { "waist": [[0.0, 1.02, 0.13], "…"] } }
//! ```
//! `points` maps feature point IDs ([`PointId`]) to approximate positions
//! (metres unless `units` says `mm` or `cm`; Y up, facing +Z). `curves` is
//! optional: polylines of feature curves ([`CurveId`]) the scanner already
//! has; sections are read as closed, paths as open. `vocabulary` is the
//! registry version the file was written against; a newer one than this
//! build knows is refused. Every error names the offending ID.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::body::derive::Landmarks;
use crate::body::vocab::{curve_def, CurveId, CurveRule, PointId, VOCABULARY_VERSION};
use crate::geom::polyline::Polyline;

/// What is wrong with a landmarks file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LandmarkFileError {
    /// Not valid JSON of the expected shape.
    #[error("landmarks JSON: {0}")]
    Syntax(String),
    /// A point ID the vocabulary doesn't know.
    #[error("unknown landmark `{id}`")]
    UnknownPoint {
        /// The ID given.
        id: String,
    },
    /// A curve ID the vocabulary doesn't know.
    #[error("unknown feature curve `{id}`")]
    UnknownCurve {
        /// The ID given.
        id: String,
    },
    /// A coordinate that is not finite.
    #[error("`{id}` has a non-finite coordinate")]
    NonFinite {
        /// The point or curve.
        id: String,
    },
    /// A vocabulary version newer than this build.
    #[error("vocabulary version {found} is newer than this service's {supported}")]
    FutureVocabulary {
        /// Version in the file.
        found: u32,
        /// Newest supported.
        supported: u32,
    },
    /// Unknown unit.
    #[error("unknown units `{0}` (use m, cm or mm)")]
    Units(String),
    /// A curve with fewer than two points.
    #[error("curve `{id}` has fewer than two points")]
    ShortCurve {
        /// The curve.
        id: String,
    },
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    vocabulary: u32,
    #[serde(default)]
    units: Option<String>,
    points: BTreeMap<String, [f64; 3]>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    curves: BTreeMap<String, Vec<[f64; 3]>>,
}

/// Parses a landmarks file into metres.
pub fn parse_landmarks(text: &str) -> Result<Landmarks, LandmarkFileError> {
    let f: File = serde_json::from_str(text).map_err(|e| LandmarkFileError::Syntax(e.to_string()))?;
    if f.vocabulary > VOCABULARY_VERSION {
        return Err(LandmarkFileError::FutureVocabulary { found: f.vocabulary, supported: VOCABULARY_VERSION });
    }
    let scale = match f.units.as_deref().unwrap_or("m") {
        "m" => 1.0,
        "cm" => 1e-2,
        "mm" => 1e-3,
        u => return Err(LandmarkFileError::Units(u.to_owned())),
    };
    let mut out = Landmarks::default();
    for (k, p) in f.points {
        let id: PointId = k.parse().map_err(|_| LandmarkFileError::UnknownPoint { id: k.clone() })?;
        let v = DVec3::from_array(p) * scale;
        if !v.is_finite() {
            return Err(LandmarkFileError::NonFinite { id: k });
        }
        out.points.insert(id, v);
    }
    for (k, pts) in f.curves {
        let id: CurveId = k.parse().map_err(|_| LandmarkFileError::UnknownCurve { id: k.clone() })?;
        if pts.len() < 2 {
            return Err(LandmarkFileError::ShortCurve { id: k });
        }
        let pts: Vec<DVec3> = pts.into_iter().map(|p| DVec3::from_array(p) * scale).collect();
        if pts.iter().any(|p| !p.is_finite()) {
            return Err(LandmarkFileError::NonFinite { id: k });
        }
        let closed = matches!(curve_def(id).rule, CurveRule::Section { .. });
        out.curves.insert(id, Polyline::new(pts, closed));
    }
    Ok(out)
}

/// Writes landmarks (metres) as a landmarks file.
pub fn write_landmarks(lm: &Landmarks) -> String {
    let f = File {
        vocabulary: VOCABULARY_VERSION,
        units: Some("m".into()),
        points: lm.points.iter().map(|(k, v)| (k.as_str().to_owned(), v.to_array())).collect(),
        curves: lm
            .curves
            .iter()
            .map(|(k, c)| (k.as_str().to_owned(), c.points.iter().map(|p| p.to_array()).collect()))
            .collect(),
    };
    serde_json::to_string_pretty(&f).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_units() {
        let mut lm = Landmarks::default();
        lm.points.insert(PointId::Crotch, DVec3::new(0.0, 0.8, 0.05));
        lm.curves.insert(CurveId::Waist, Polyline::new(vec![DVec3::X, DVec3::Z, -DVec3::X], true));
        let back = parse_landmarks(&write_landmarks(&lm)).unwrap();
        assert_eq!(back, lm);
        let mm = parse_landmarks(r#"{"vocabulary":1,"units":"mm","points":{"crotch":[0,800,50]}}"#).unwrap();
        assert!((mm.points[&PointId::Crotch] - DVec3::new(0.0, 0.8, 0.05)).length() < 1e-15);
    }

    #[test]
    fn bad_files_name_the_element() {
        let e = parse_landmarks(r#"{"vocabulary":1,"points":{"belly_button":[0,1,0]}}"#).unwrap_err();
        assert_eq!(e, LandmarkFileError::UnknownPoint { id: "belly_button".into() });
        let e = parse_landmarks(r#"{"vocabulary":1,"points":{},"curves":{"belt":[[0,0,0],[1,0,0]]}}"#).unwrap_err();
        assert_eq!(e, LandmarkFileError::UnknownCurve { id: "belt".into() });
        let e = parse_landmarks(r#"{"vocabulary":99,"points":{}}"#).unwrap_err();
        assert!(matches!(e, LandmarkFileError::FutureVocabulary { found: 99, .. }));
        let e = parse_landmarks(r#"{"vocabulary":1,"points":{"crotch":[0,1e999,0]}}"#).unwrap_err();
        assert!(matches!(e, LandmarkFileError::NonFinite { .. } | LandmarkFileError::Syntax(_)), "{e:?}");
        let e = parse_landmarks(r#"{"vocabulary":1,"units":"furlong","points":{}}"#).unwrap_err();
        assert!(matches!(e, LandmarkFileError::Units(_)));
        let e = parse_landmarks(r#"{"vocabulary":1,"points":{},"curves":{"waist":[[0,0,0]]}}"#).unwrap_err();
        assert_eq!(e, LandmarkFileError::ShortCurve { id: "waist".into() });
        assert!(matches!(parse_landmarks("[1,2"), Err(LandmarkFileError::Syntax(_))));
    }
}
