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
//! 3. Each patch is turned to face away from the centroid of all the
//!    patches' points (a garment goes round its body), so that the welded
//!    garment is consistently oriented whatever order each panel's curves
//!    were drawn in.
//! 4. Patches that name the same [`CurvePanel::piece`] are one pattern
//!    piece: seed 001 §3.2's sub-patches, case (d) of its Fig. 5 — a
//!    curve across two opposite sides of a region splits it into two
//!    4-sided patches that stay one surface. They are joined where they
//!    share points (within [`CurvesOptions::join_tolerance_mm`], the
//!    weld of [`super::garment_panels::weld_panels`]), so the curve
//!    between them is a line inside the piece (a skirt's hip line), not a
//!    seam. A piece is named by its first patch's `piece`, in the order
//!    its first patch comes. A piece's vertices are numbered by their first
//!    use in its triangles (as an OBJ reader numbers them).
//!
//! Seed 001 §3.2's strokes that end inside a patch (projected onto the
//! base surface and extended to its boundary) are not taken: a caller
//! draws a curve that shapes a piece (the hip girth eased) from side to
//! side, and the sub-patches of step 4 interpolate it exactly.
//!
//! # Failure modes
//!
//! [`FromCurvesError`]: no panel, a panel whose patch cannot be made (the
//! [`CoonsError`] with the panel's name: a side with no point, a
//! non-finite point, corners that do not meet, two opposite sides both
//! collapsed), a sampling out of range.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::garment_panels::{weld_panels, PanelError, PanelMesh, WeldOptions};
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
    /// The pattern piece this patch is part of: patches naming the same
    /// piece are joined where they share a curve, which is then a line
    /// inside the piece, not a seam (module docs, step 4); absent: a piece
    /// of its own, named `name`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub piece: Option<String>,
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
    /// Points of two patches of one piece closer than this are one point,
    /// mm. Default 0.01 (a shared curve samples to the same points, to
    /// rounding).
    pub join_tolerance_mm: f64,
}

impl Default for CurvesOptions {
    fn default() -> Self {
        Self { coons: CoonsOptions::default(), samples: 24, join_tolerance_mm: 0.01 }
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
    /// The patches of a piece could not be joined (a tolerance that is not
    /// positive and finite; an edge of three patches).
    #[error("piece `{piece}`: {source}")]
    Join {
        /// The piece.
        piece: String,
        /// Why.
        source: PanelError,
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
    let mut patches = Vec::with_capacity(panels.len());
    for p in panels {
        let patch = |e| FromCurvesError::Patch { panel: p.name.clone(), source: e };
        let coons =
            CoonsPatch::new(&points(&p.bottom), &points(&p.top), &points(&p.left), &points(&p.right), &opts.coons)
                .map_err(patch)?;
        let (positions, triangles) = coons.sample(opts.samples, opts.samples).map_err(patch)?;
        patches.push(PanelMesh { name: p.name.clone(), positions, triangles, uv: Vec::new() });
    }
    // every patch faces away from the centroid of all their points
    let all: Vec<DVec3> = patches.iter().flat_map(|p| p.positions.iter().copied()).collect();
    let centre = all.iter().copied().sum::<DVec3>() / all.len().max(1) as f64;
    for piece in &mut patches {
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
    // the patches of one piece joined into it (step 4)
    let mut order: Vec<String> = Vec::new();
    let mut members: Vec<Vec<PanelMesh>> = Vec::new();
    for (p, mesh) in panels.iter().zip(patches) {
        let piece = p.piece.clone().unwrap_or_else(|| p.name.clone());
        match order.iter().position(|o| *o == piece) {
            Some(i) => members[i].push(mesh),
            None => {
                order.push(piece);
                members.push(vec![mesh]);
            }
        }
    }
    let weld = WeldOptions { tolerance_mm: opts.join_tolerance_mm };
    let mut pieces = Vec::with_capacity(order.len());
    for (name, mut parts) in order.into_iter().zip(members) {
        if parts.len() == 1 {
            let mut only = parts.remove(0);
            only.name = name;
            pieces.push(only);
            continue;
        }
        let joined =
            weld_panels(&parts, &weld).map_err(|source| FromCurvesError::Join { piece: name.clone(), source })?;
        pieces.push(PanelMesh { name, positions: joined.positions, triangles: joined.triangles, uv: Vec::new() });
    }
    Ok(pieces.into_iter().map(by_first_use).collect())
}

/// `piece` with its vertices numbered by their first use in its triangles
/// (as an OBJ reader numbers them: the pieces written and read back are the
/// same to the written precision, and author alike).
fn by_first_use(piece: PanelMesh) -> PanelMesh {
    let mut new_of = vec![u32::MAX; piece.positions.len()];
    let mut positions = Vec::with_capacity(piece.positions.len());
    let triangles = piece
        .triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                let slot = &mut new_of[v as usize];
                if *slot == u32::MAX {
                    *slot = positions.len() as u32;
                    positions.push(piece.positions[v as usize]);
                }
                *slot
            })
        })
        .collect();
    PanelMesh { name: piece.name, positions, triangles, uv: Vec::new() }
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
            piece: None,
        };
        if flip {
            // the same panel drawn mirrored: left and right swapped, bottom and top reversed
            p = CurvePanel {
                name: p.name,
                bottom: p.bottom.into_iter().rev().collect(),
                top: p.top.into_iter().rev().collect(),
                left: p.right,
                right: p.left,
                piece: None,
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

    /// A half-cylinder drawn as two patches stacked at y = 0.25 with
    /// `piece` "front", and a back as one patch: two pieces; the front's
    /// 25 × 49 grid of points once each (the shared row joined), the shared
    /// row inside the piece (every edge along it in two triangles), every
    /// point on the cylinder; a join tolerance of 0 is named with the piece.
    #[test]
    fn patches_of_one_piece_are_joined_at_their_shared_curve() {
        let cut = |p: &CurvePanel, y0: f64, y1: f64, name: &str| {
            let at = |q: &[[f64; 3]], y: f64| q.iter().map(|r| [r[0], y, r[2]]).collect::<Vec<_>>();
            let side = |q: &[[f64; 3]]| vec![[q[0][0], y0, q[0][2]], [q[0][0], y1, q[0][2]]];
            CurvePanel {
                name: name.into(),
                bottom: at(&p.bottom, y0),
                top: at(&p.top, y1),
                left: side(&p.left),
                right: side(&p.right),
                piece: Some("front".into()),
            }
        };
        let whole = half("front", 0.0, false);
        let panels = [
            cut(&whole, 0.0, 0.25, "front-lower"),
            half("back", std::f64::consts::PI, true),
            cut(&whole, 0.25, 0.5, "front-upper"),
        ];
        let pieces = panels_from_curves(&panels, &CurvesOptions::default()).unwrap();
        let names: Vec<&str> = pieces.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["front", "back"]);
        let front = &pieces[0];
        assert_eq!((front.positions.len(), front.triangles.len()), (25 * 49, 2 * 1152));
        for p in &front.positions {
            assert!(((p.x * p.x + p.z * p.z).sqrt() - 0.2).abs() < 2e-3, "{p}");
        }
        let mut uses: std::collections::BTreeMap<(u32, u32), usize> = Default::default();
        for t in &front.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let on_row = |v: u32| (front.positions[v as usize].y - 0.25).abs() < 1e-12;
        let row: Vec<usize> = uses.iter().filter(|((a, b), _)| on_row(*a) && on_row(*b)).map(|(_, &n)| n).collect();
        assert_eq!(row.len(), 24, "the shared row's edges");
        assert!(row.iter().all(|&n| n == 2), "the shared row is inside the piece: {row:?}");
        let opts = CurvesOptions { join_tolerance_mm: 0.0, ..Default::default() };
        match panels_from_curves(&panels, &opts) {
            Err(FromCurvesError::Join { piece, .. }) => assert_eq!(piece, "front"),
            other => panic!("{other:?}"),
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
