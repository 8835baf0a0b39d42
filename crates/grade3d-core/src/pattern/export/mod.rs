//! Exports of pattern pieces and grade rules to the formats pattern CAD
//! systems and people read (issue #5).
//!
//! # Contract
//!
//! Input: [`PatternPiece`]s at true scale — millimetres, x to the right, y up,
//! closed counter-clockwise polygons, stack point at the origin — and
//! [`GradeRuleTable`]s (`super::piece`).
//!
//! - [`svg`]: SVG 1.1 drawings at true scale (`width`/`height` in mm, a
//!   viewBox in mm, y flipped so that nothing is mirrored) of the pieces of
//!   one size side by side, or of a graded nest (all sizes of each piece
//!   overlaid, one colour per size).
//! - [`dxf`]: ASCII DXF in the AAMA / ASTM D6673-10 style (AutoCAD R12,
//!   `AC1009`): one block per piece (per size in a nest) with the numbered
//!   AAMA layers, style and piece system text, grade rule numbers; and the
//!   read-back of the boundaries for round-trip checks.
//! - [`rul`]: the grade rule table as CSV and as an AAMA/ASTM `.RUL` file.
//!
//! Shared here: the error type ([`ExportError`]) and the shelf layout
//! ([`ShelfLayout`]) that both drawings use to place pieces side by side
//! without overlap.
//!
//! Every export is deterministic: the same input gives byte-identical output
//! (no timestamps, no random identifiers, no hash-map iteration order).
//!
//! # Failure modes
//!
//! The SVG and rule exports are infallible: a coordinate that is not finite
//! is left out of the drawing. The DXF export fails with [`ExportError`] on
//! non-finite coordinates, on a piece whose cut line has fewer than three
//! points and on unusable options; reading a DXF back fails when the `dxf`
//! crate cannot read it.

pub mod dxf;
pub mod rul;
pub mod svg;

use glam::DVec2;

#[cfg(doc)]
use super::piece::GradeRuleTable;
use super::piece::{PatternPiece, PieceNotch};

/// Why an export (or the read-back of one) failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExportError {
    /// The CSV writer failed (it writes into memory, so only on a broken invariant).
    #[error("CSV: {0}")]
    Csv(String),
    /// A coordinate of a piece is NaN or infinite.
    #[error("piece '{piece}' (size '{size}'): {what} has a coordinate that is not finite")]
    NonFinite {
        /// Piece name.
        piece: String,
        /// Size name.
        size: String,
        /// Which geometry (`cut line`, `sew line`, `notch`, `grain line`, `internal line`, `grade point`).
        what: &'static str,
    },
    /// A piece's cut line (the AAMA boundary) has fewer than three points.
    #[error("piece '{piece}' (size '{size}'): the cut line has {points} points, at least 3 are needed")]
    DegenerateOutline {
        /// Piece name.
        piece: String,
        /// Size name.
        size: String,
        /// Number of points it has.
        points: usize,
    },
    /// An option is out of range.
    #[error("option {option} = {value} is out of range: {expected}")]
    BadOption {
        /// Option (field) name.
        option: &'static str,
        /// Its value, as text.
        value: String,
        /// What is allowed.
        expected: &'static str,
    },
    /// The `dxf` crate could not read a drawing (its message).
    #[error("DXF: {0}")]
    Dxf(String),
}

/// Shelf layout of pieces side by side: left to right in rows, a new row
/// below the previous one when a row would exceed
/// [`ShelfLayout::max_row_width_mm`]. Items never overlap: each occupies its
/// own bounding box, boxes are separated by at least [`ShelfLayout::gap_mm`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShelfLayout {
    /// Gap between neighbouring pieces, horizontally and between rows, mm.
    /// Default 20 mm; a negative value acts as 0.
    pub gap_mm: f64,
    /// Width after which a row is closed and the next piece starts a new
    /// row, mm (a piece wider than this gets a row of its own). Default
    /// 1600 mm, a common cutting-table width.
    pub max_row_width_mm: f64,
}

impl Default for ShelfLayout {
    fn default() -> Self {
        Self { gap_mm: 20.0, max_row_width_mm: 1600.0 }
    }
}

/// Axis-aligned bounding box, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bounds {
    /// Lower-left corner.
    pub min: DVec2,
    /// Upper-right corner.
    pub max: DVec2,
}

impl Bounds {
    /// Bounds of the finite points among `points`; `None` if there are none.
    pub fn of(points: impl IntoIterator<Item = DVec2>) -> Option<Self> {
        points.into_iter().filter(|p| p.is_finite()).fold(None, |b: Option<Self>, p| {
            Some(b.map_or(Self { min: p, max: p }, |b| Self { min: b.min.min(p), max: b.max.max(p) }))
        })
    }

    /// The smallest box holding both.
    pub fn union(self, other: Self) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// The union of optional boxes.
    pub fn union_opt(a: Option<Self>, b: Option<Self>) -> Option<Self> {
        match (a, b) {
            (Some(a), Some(b)) => Some(a.union(b)),
            (a, None) => a,
            (None, b) => b,
        }
    }

    /// Width and height.
    pub fn size(self) -> DVec2 {
        self.max - self.min
    }

    /// Centre.
    pub fn centre(self) -> DVec2 {
        (self.min + self.max) * 0.5
    }

    /// Translated by `t`.
    pub fn translated(self, t: DVec2) -> Self {
        Self { min: self.min + t, max: self.max + t }
    }
}

impl ShelfLayout {
    /// The translation of every item so that the items lie side by side in
    /// rows: the first row's top edge at y = 0, rows growing downwards (−y),
    /// each row starting at x = 0. An item without geometry (`None`) gets
    /// the translation of an empty box at the cursor.
    pub(crate) fn place(&self, items: &[Option<Bounds>]) -> Vec<DVec2> {
        let gap = if self.gap_mm.is_finite() { self.gap_mm.max(0.0) } else { 0.0 };
        let (mut x, mut row_top, mut row_height) = (0.0_f64, 0.0_f64, 0.0_f64);
        items
            .iter()
            .map(|item| {
                let b = item.unwrap_or(Bounds { min: DVec2::ZERO, max: DVec2::ZERO });
                let size = b.size();
                if x > 0.0 && x + size.x > self.max_row_width_mm {
                    row_top -= row_height + gap;
                    x = 0.0;
                    row_height = 0.0;
                }
                let t = DVec2::new(x - b.min.x, row_top - b.max.y);
                x += size.x + gap;
                row_height = row_height.max(size.y);
                t
            })
            .collect()
    }
}

/// A notch as drawn: it starts on the cut line and runs into the piece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NotchMark {
    /// Where it meets the cut line: the point of the cut line closest to
    /// [`PieceNotch::on_cut_line`], mm.
    pub start: DVec2,
    /// Unit direction into the piece (towards the sew line).
    pub inward: DVec2,
    /// Distance from `start` to the notch's sew-line point, mm (0 without seam allowance).
    pub to_sew_line: f64,
}

impl NotchMark {
    /// The mark of `notch` on the piece whose cut line is `cut_line`;
    /// `None` when its points are not finite.
    pub fn of(notch: &PieceNotch, cut_line: &[DVec2]) -> Option<Self> {
        if !(notch.at.is_finite() && notch.on_cut_line.is_finite() && notch.outward.is_finite()) {
            return None;
        }
        let start = closest_on_polygon(cut_line, notch.on_cut_line).unwrap_or(notch.on_cut_line);
        let to_sew = notch.at - start;
        let inward = if to_sew.length() > f64::EPSILON {
            to_sew.normalize()
        } else {
            (-notch.outward).try_normalize().unwrap_or(DVec2::NEG_Y)
        };
        Some(Self { start, inward, to_sew_line: to_sew.length() })
    }

    /// End point of a mark `depth` mm long, but not beyond the sew line
    /// when there is a seam allowance.
    pub fn end(&self, depth: f64) -> DVec2 {
        let len = if self.to_sew_line > f64::EPSILON { depth.min(self.to_sew_line) } else { depth };
        self.start + self.inward * len
    }
}

/// The point of the closed polygon's edges closest to `p` (`None` for an
/// empty polygon or non-finite points).
/// Bounds of all of a piece's geometry (cut and sew lines, grain, internal lines).
pub(crate) fn piece_bounds(p: &PatternPiece) -> Option<Bounds> {
    Bounds::of(
        p.cut_line
            .iter()
            .chain(&p.sew_line)
            .chain(&p.grain)
            .chain(p.internal_lines.iter().flat_map(|l| &l.points))
            .copied(),
    )
}

pub(crate) fn closest_on_polygon(poly: &[DVec2], p: DVec2) -> Option<DVec2> {
    let n = poly.len();
    (0..n)
        .filter_map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let ab = b - a;
            let len2 = ab.length_squared();
            let t = if len2 > 0.0 { ((p - a).dot(ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
            let q = a + ab * t;
            q.is_finite().then_some((q.distance_squared(p), q))
        })
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, q)| q)
}

/// Formats `v` with at most `decimals` decimals, without trailing zeros and
/// without a negative zero (`-0.0001` at 3 decimals is `0`).
pub(crate) fn fmt_num(v: f64, decimals: usize) -> String {
    let mut s = format!("{v:.decimals$}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" {
        s = "0".to_string();
    }
    s
}

pub mod samples {
    //! Synthetic pieces for examples and the export tests (here and in the
    //! workspace's `tests/`): a front with a curved side seam, notches,
    //! grain and an internal line; a back with an awkward name; a small
    //! rectangular pocket.

    use glam::DVec2;

    use crate::pattern::piece::{
        GradePoint, GradePointKind, GradeRule, GradeRuleTable, InternalLine, PatternPiece, PieceGradeRules, PieceNotch,
    };

    /// Seam allowance of the test pieces, mm.
    pub const ALLOWANCE: f64 = 10.0;

    /// Offsets a CCW polygon outwards with mitred corners (good enough for
    /// the convex test shapes).
    fn offset(poly: &[DVec2], d: f64) -> Vec<DVec2> {
        let n = poly.len();
        let normal = |i: usize| {
            let e = (poly[(i + 1) % n] - poly[i]).normalize();
            DVec2::new(e.y, -e.x)
        };
        (0..n)
            .map(|k| {
                let (n0, n1) = (normal((k + n - 1) % n), normal(k));
                poly[k] + (n0 + n1) * (d / (1.0 + n0.dot(n1)))
            })
            .collect()
    }

    /// A piece from its sew line; `corners` are indices into it, the notch
    /// sits at sew-line vertex `k`.
    fn piece(name: &str, size: &str, sew: Vec<DVec2>, corners: Vec<usize>, k: usize, quantity: u32) -> PatternPiece {
        let cut = offset(&sew, ALLOWANCE);
        let n = sew.len();
        let normal = {
            let e0 = (sew[k] - sew[(k + n - 1) % n]).normalize();
            let e1 = (sew[(k + 1) % n] - sew[k]).normalize();
            (DVec2::new(e0.y, -e0.x) + DVec2::new(e1.y, -e1.x)).normalize()
        };
        let notch = PieceNotch {
            name: "hip".to_string(),
            at: sew[k],
            outward: normal,
            on_cut_line: sew[k] + normal * ALLOWANCE,
        };
        let mut grade_points: Vec<GradePoint> = corners
            .iter()
            .map(|&c| GradePoint {
                node: c as u32 + 100,
                label: format!("corner_{c}"),
                at: sew[c],
                kind: GradePointKind::Corner,
            })
            .collect();
        grade_points.push(GradePoint { node: 7, label: "hip".to_string(), at: sew[k], kind: GradePointKind::Notch });
        let ys: Vec<f64> = sew.iter().map(|p| p.y).collect();
        let (lo, hi) = ys.iter().fold((f64::MAX, f64::MIN), |(a, b), &y| (a.min(y), b.max(y)));
        PatternPiece {
            name: name.to_string(),
            size: size.to_string(),
            quantity,
            cut_pair: false,
            sew_line: sew,
            corners,
            cut_line: cut,
            seam_allowance_mm: ALLOWANCE,
            notches: vec![notch],
            grain: [DVec2::new(0.0, lo + 0.2 * (hi - lo)), DVec2::new(0.0, lo + 0.8 * (hi - lo))],
            internal_lines: vec![InternalLine {
                name: "hip_line".to_string(),
                points: vec![
                    DVec2::new(-60.0 * 0.5, lo + 0.5 * (hi - lo)),
                    DVec2::new(60.0 * 0.5, lo + 0.5 * (hi - lo)),
                ],
            }],
            grade_points,
            stack_point: DVec2::ZERO,
        }
    }

    /// The front: a rectangle 200 × 400 mm whose right side is a curve
    /// (sampled), grown by `grow` mm per side.
    pub fn front(size: &str, grow: f64) -> PatternPiece {
        let (w, h) = (100.0 + grow, 200.0 + grow);
        let mut sew = vec![DVec2::new(-w, -h), DVec2::new(w, -h)];
        let steps = 8;
        for i in 1..steps {
            let t = i as f64 / steps as f64;
            let y = -h + 2.0 * h * t;
            sew.push(DVec2::new(w + 25.0 * (std::f64::consts::PI * t).sin(), y));
        }
        sew.push(DVec2::new(w, h));
        sew.push(DVec2::new(-w, h));
        let last = sew.len() - 1;
        piece("front & <side>", size, sew, vec![0, 1, last - 1, last], steps / 2 + 1, 1)
    }

    /// The back: a plain trapezoid with a name full of characters that need
    /// escaping or sanitising.
    pub fn back(size: &str, grow: f64) -> PatternPiece {
        let (w, h) = (90.0 + grow, 190.0 + grow);
        let sew = vec![
            DVec2::new(-w, -h),
            DVec2::new(0.0, -h),
            DVec2::new(w, -h),
            DVec2::new(w - 10.0, h),
            DVec2::new(-w + 10.0, h),
        ];
        piece("back \"left\" 'L' > x", size, sew, vec![0, 2, 3, 4], 1, 2)
    }

    /// A pocket: a small rectangle.
    pub fn pocket(size: &str, grow: f64) -> PatternPiece {
        let (w, h) = (60.0 + grow, 70.0 + grow);
        let sew = vec![DVec2::new(-w, -h), DVec2::new(0.0, -h), DVec2::new(w, -h), DVec2::new(w, h), DVec2::new(-w, h)];
        piece("pocket", size, sew, vec![0, 2, 3, 4], 1, 2)
    }

    /// The three pieces of one size.
    pub fn pieces(size: &str, grow: f64) -> Vec<PatternPiece> {
        vec![front(size, grow), back(size, grow), pocket(size, grow)]
    }

    /// Sizes of the test nest, smallest to largest, with their growth (mm).
    pub const SIZES: [(&str, f64); 3] = [("S", -8.0), ("M", 0.0), ("L & XL", 8.0)];

    /// The graded nest of the three pieces over [`SIZES`].
    pub fn nests() -> Vec<(String, Vec<PatternPiece>)> {
        let all: Vec<Vec<PatternPiece>> = SIZES.iter().map(|&(s, g)| pieces(s, g)).collect();
        (0..all[0].len()).map(|i| (all[0][i].name.clone(), all.iter().map(|size| size[i].clone()).collect())).collect()
    }

    /// A 3-size rule table for the nest: every grade point of the base size
    /// `M` moves by its growth away from the centre.
    pub fn rules() -> GradeRuleTable {
        let base = pieces("M", 0.0);
        let mut number = 0;
        let pieces = base
            .iter()
            .map(|p| PieceGradeRules {
                piece: p.name.clone(),
                rules: p
                    .grade_points
                    .iter()
                    .map(|g| {
                        number += 1;
                        GradeRule {
                            number,
                            node: g.node,
                            label: g.label.clone(),
                            deltas: SIZES.iter().map(|&(_, grow)| g.at.signum() * grow).collect(),
                        }
                    })
                    .collect(),
            })
            .collect();
        GradeRuleTable {
            style: "Dress, \"summer\"".to_string(),
            sizes: SIZES.iter().map(|&(s, _)| s.to_string()).collect(),
            base_size: "M".to_string(),
            pieces,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shelf_layout_does_not_overlap_and_wraps() {
        let b =
            |w: f64, h: f64| Some(Bounds { min: DVec2::new(-w / 2.0, -h / 2.0), max: DVec2::new(w / 2.0, h / 2.0) });
        let items = vec![b(100.0, 50.0), b(80.0, 120.0), None, b(150.0, 30.0), b(40.0, 40.0)];
        let layout = ShelfLayout { gap_mm: 10.0, max_row_width_mm: 250.0 };
        let t = layout.place(&items);
        let placed: Vec<Option<Bounds>> = items.iter().zip(&t).map(|(b, t)| b.map(|b| b.translated(*t))).collect();
        for (i, a) in placed.iter().enumerate() {
            for bb in placed.iter().skip(i + 1) {
                if let (Some(a), Some(bb)) = (a, bb) {
                    let apart = a.max.x + 10.0 <= bb.min.x + 1e-9
                        || bb.max.x + 10.0 <= a.min.x + 1e-9
                        || a.max.y + 10.0 <= bb.min.y + 1e-9
                        || bb.max.y + 10.0 <= a.min.y + 1e-9;
                    assert!(apart, "{a:?} and {bb:?} are closer than the gap");
                }
            }
        }
        // first row: 100 + 10 + 80 = 190; the 150 wide one wraps
        let p3 = placed[3].unwrap_or(Bounds { min: DVec2::ZERO, max: DVec2::ZERO });
        assert!((p3.min.x - 0.0).abs() < 1e-9 && (p3.max.y - (-130.0)).abs() < 1e-9, "{p3:?}");
    }

    #[test]
    fn numbers_are_trimmed() {
        assert_eq!(fmt_num(1.5, 3), "1.5");
        assert_eq!(fmt_num(2.0, 3), "2");
        assert_eq!(fmt_num(-0.0001, 3), "0");
        assert_eq!(fmt_num(-12.34567, 3), "-12.346");
        assert_eq!(fmt_num(100.0, 0), "100");
    }
}
