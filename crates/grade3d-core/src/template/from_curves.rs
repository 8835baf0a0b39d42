//! Garment pieces from 3D boundary curves (issue #18 item 2; seed 001
//! §3.1): each panel given as its four boundary curves becomes a Coons
//! patch ([`crate::geom::coons`]), sampled into a mesh; the pieces then go
//! through [`super::from_garment::author_from_garment`] like a designed
//! garment's.
//!
//! # Method
//!
//! 1. Each [`CurvePanel`] is a Coons patch of its `bottom`, `top`, `left`
//!    and `right` polylines (metres; bottom and top running from the left
//!    curve to the right one, left and right from the bottom to the top;
//!    a side may be one point: a three-sided panel), with seed 001's
//!    bicubically blended expanded form (the printed Eq. (1) is `−P`,
//!    [`crate::geom::coons`]).
//! 2. Every patch is sampled on the same `samples × samples` grid of its
//!    chord-length parameters, so that two panels sharing a boundary curve
//!    (the same polyline, in either direction) get the same points along it
//!    — to rounding, which the weld of [`super::garment_panels::weld_panels`]
//!    absorbs — and are sewn there by the seam finding of step 1 of
//!    authoring.
//! 3. Each piece is turned to face away from the centroid of all the
//!    pieces' points (a garment goes round its body), so that the welded
//!    garment is consistently oriented whatever order each panel's curves
//!    were drawn in.
//!
//! Seed 001 §3.2's refinement by interior curves is not done: a panel
//! whose four sides do not carry its shape (a skirt from waist to hem
//! round the seat) is given as several panels, cut at the curves that
//! shape it (the hip), as a pattern maker's block is.
//!
//! # Failure modes
//!
//! [`FromCurvesError`]: no panel, a panel whose patch cannot be made (the
//! [`CoonsError`] with the panel's name: a side with no point, a
//! non-finite point, corners that do not meet, two opposite sides both
//! collapsed), a sampling out of range.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::garment_panels::PanelMesh;
use crate::geom::coons::{CoonsError, CoonsOptions, CoonsPatch};

/// One panel as its four boundary curves (module docs), metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CurvePanel {
    /// The piece's name.
    pub name: String,
    /// The bottom curve, from the left curve's first point to the right's.
    pub bottom: Vec<[f64; 3]>,
    /// The top curve, from the left curve's last point to the right's.
    pub top: Vec<[f64; 3]>,
    /// The left curve, from the bottom up.
    pub left: Vec<[f64; 3]>,
    /// The right curve, from the bottom up.
    pub right: Vec<[f64; 3]>,
}

/// Knobs of [`panels_from_curves`]; each documents its default and unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CurvesOptions {
    /// The patches' blends and corner tolerance. Default [`CoonsOptions::default`].
    pub coons: CoonsOptions,
    /// Intervals of every patch's sampling along each parameter (count).
    /// Default 24.
    pub samples: usize,
}

impl Default for CurvesOptions {
    fn default() -> Self {
        Self { coons: CoonsOptions::default(), samples: 24 }
    }
}

/// The most intervals [`CurvesOptions::samples`] may ask for (count).
pub const MAX_SAMPLES: usize = 256;

/// Why [`panels_from_curves`] failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FromCurvesError {
    /// No panel was given.
    #[error("no panel was given")]
    NoPanel,
    /// A panel's patch could not be made or sampled.
    #[error("panel `{panel}`: {source}")]
    Patch {
        /// The panel.
        panel: String,
        /// Why.
        source: CoonsError,
    },
    /// The sampling is out of range.
    #[error("option `samples` = {samples} is out of range (1 to {MAX_SAMPLES})")]
    Samples {
        /// What was asked.
        samples: usize,
    },
}

fn points(p: &[[f64; 3]]) -> Vec<DVec3> {
    p.iter().map(|&q| DVec3::from_array(q)).collect()
}

/// The pieces of `panels` (module docs), ready for
/// [`super::from_garment::author_from_garment`].
///
/// # Errors
/// [`FromCurvesError`].
pub fn panels_from_curves(panels: &[CurvePanel], opts: &CurvesOptions) -> Result<Vec<PanelMesh>, FromCurvesError> {
    if panels.is_empty() {
        return Err(FromCurvesError::NoPanel);
    }
    if opts.samples == 0 || opts.samples > MAX_SAMPLES {
        return Err(FromCurvesError::Samples { samples: opts.samples });
    }
    let mut pieces = Vec::with_capacity(panels.len());
    for p in panels {
        let patch = |e| FromCurvesError::Patch { panel: p.name.clone(), source: e };
        let coons =
            CoonsPatch::new(&points(&p.bottom), &points(&p.top), &points(&p.left), &points(&p.right), &opts.coons)
                .map_err(patch)?;
        let (positions, triangles) = coons.sample(opts.samples, opts.samples).map_err(patch)?;
        pieces.push(PanelMesh { name: p.name.clone(), positions, triangles });
    }
    // every piece faces away from the centroid of all their points
    let all: Vec<DVec3> = pieces.iter().flat_map(|p| p.positions.iter().copied()).collect();
    let centre = all.iter().copied().sum::<DVec3>() / all.len().max(1) as f64;
    for piece in &mut pieces {
        let outward: f64 = piece
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| piece.positions[v as usize]);
                (b - a).cross(c - a).dot((a + b + c) / 3.0 - centre)
            })
            .sum();
        if outward < 0.0 {
            for t in &mut piece.triangles {
                t.swap(1, 2);
            }
        }
    }
    Ok(pieces)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two half-cylinders sharing their two straight sides: the shared
    /// sides sample to the same points (the weld sews them), both pieces
    /// face outwards whichever way their curves run, and every sample lies
    /// on the cylinder (Coons reproduces a translational surface).
    fn half(name: &str, from: f64, flip: bool) -> CurvePanel {
        let arc = |y: f64| -> Vec<[f64; 3]> {
            (0..=32)
                .map(|k| {
                    let a = from + std::f64::consts::PI * k as f64 / 32.0;
                    [0.2 * a.cos(), y, 0.2 * a.sin()]
                })
                .collect()
        };
        let line = |a: f64| vec![[0.2 * a.cos(), 0.0, 0.2 * a.sin()], [0.2 * a.cos(), 0.5, 0.2 * a.sin()]];
        let mut p = CurvePanel {
            name: name.into(),
            bottom: arc(0.0),
            top: arc(0.5),
            left: line(from),
            right: line(from + std::f64::consts::PI),
        };
        if flip {
            // the same panel drawn mirrored: left and right swapped, bottom and top reversed
            p = CurvePanel {
                name: p.name,
                bottom: p.bottom.into_iter().rev().collect(),
                top: p.top.into_iter().rev().collect(),
                left: p.right,
                right: p.left,
            };
        }
        p
    }

    #[test]
    fn two_halves_share_their_sides_and_face_out() {
        let panels = [half("front", 0.0, false), half("back", std::f64::consts::PI, true)];
        let pieces = panels_from_curves(&panels, &CurvesOptions::default()).unwrap();
        assert_eq!(pieces.len(), 2);
        for piece in &pieces {
            // 25 × 25 grid, two triangles a cell
            assert_eq!((piece.positions.len(), piece.triangles.len()), (625, 1152), "{}", piece.name);
            for p in &piece.positions {
                assert!(((p.x * p.x + p.z * p.z).sqrt() - 0.2).abs() < 2e-3, "{p}");
            }
            for t in &piece.triangles {
                let [a, b, c] = t.map(|v| piece.positions[v as usize]);
                let n = (b - a).cross(c - a);
                let out = DVec3::new(a.x + b.x + c.x, 0.0, a.z + b.z + c.z);
                assert!(n.dot(out) > 0.0, "{} faces in", piece.name);
            }
        }
        // the shared sides: every point of one piece's seam is a point of the other's
        let on_seam = |p: &DVec3| p.z.abs() < 1e-9;
        let (a, b): (Vec<DVec3>, Vec<DVec3>) = (
            pieces[0].positions.iter().copied().filter(on_seam).collect(),
            pieces[1].positions.iter().copied().filter(on_seam).collect(),
        );
        assert_eq!(a.len(), 50);
        assert_eq!(b.len(), 50);
        for p in &a {
            assert!(b.iter().any(|q| q.distance(*p) < 1e-12), "{p}");
        }
    }

    #[test]
    fn refusals_name_the_panel() {
        assert_eq!(panels_from_curves(&[], &CurvesOptions::default()), Err(FromCurvesError::NoPanel));
        let mut p = half("front", 0.0, false);
        p.left[0][0] += 0.05;
        match panels_from_curves(&[p.clone()], &CurvesOptions::default()) {
            Err(FromCurvesError::Patch { panel, .. }) => assert_eq!(panel, "front"),
            other => panic!("{other:?}"),
        }
        let opts = CurvesOptions { samples: 0, ..Default::default() };
        assert_eq!(panels_from_curves(&[half("a", 0.0, false)], &opts), Err(FromCurvesError::Samples { samples: 0 }));
    }
}
