//! Pattern pieces in 2D at true scale (millimetres), what the exports
//! ([`super::export`]) write and the grade rules ([`super::grade`]) compare.
//!
//! Conventions: x to the right, y up (the grain line runs along −y, down the
//! body, so pieces are upright), lengths
//! in mm; polygons are closed implicitly (the last point is not repeated)
//! and counter-clockwise; every piece is placed so that its stack point
//! ([`PatternPiece::stack_point`]) is the origin.

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// A notch: a short cut into the seam allowance marking where two pieces meet.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PieceNotch {
    /// What it marks (`hip`, `knee`, `bust`, …).
    pub name: String,
    /// The notch's point on the sew line, mm.
    pub at: DVec2,
    /// Unit direction from the sew line out across the allowance (outward normal).
    pub outward: DVec2,
    /// Where the notch reaches the cut line, mm (`at + outward × allowance`).
    pub on_cut_line: DVec2,
}

/// A grade point of a piece: a corner (turn point) or a notch, with the
/// template node it comes from, so that every size names the same points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GradePoint {
    /// Template node id.
    pub node: u32,
    /// Label: the node's feature point, e.g. `waist_front`.
    pub label: String,
    /// Position on the sew line, mm.
    pub at: DVec2,
    /// Corner (turn point) or notch.
    pub kind: GradePointKind,
}

/// Kind of a [`GradePoint`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GradePointKind {
    /// A template node on the sew line: a turn point, or a curve point that is
    /// graded (every template node on the outline is one).
    Corner,
    /// A notch (AAMA layer 4).
    Notch,
}

/// An internal line of a piece (AAMA layer 8): a feature curve such as the
/// hip line, or a dart's legs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InternalLine {
    /// What it is (`hip_line`, `dart`, …).
    pub name: String,
    /// Open polyline, mm.
    pub points: Vec<DVec2>,
}

/// One pattern piece of one size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PatternPiece {
    /// Piece name, from the template's panel (`front`, `left_back`, …).
    pub name: String,
    /// Size name (`size-8`, a scan's id, …).
    pub size: String,
    /// Pieces to cut.
    pub quantity: u32,
    /// Whether this piece stands for a mirror pair of panels, cut as a pair
    /// (one right side up, one face down: AAMA's mirrored piece). Its
    /// `quantity` counts both.
    #[serde(default)]
    pub cut_pair: bool,
    /// The sew (stitch) line: closed polygon, counter-clockwise, mm.
    pub sew_line: Vec<DVec2>,
    /// Indices into `sew_line` of its corners (turn points); the rest are curve points.
    pub corners: Vec<usize>,
    /// The cut line: the sew line offset outwards by the seam allowance, with
    /// mitred corners; closed polygon, counter-clockwise, mm.
    pub cut_line: Vec<DVec2>,
    /// Seam allowance, mm.
    pub seam_allowance_mm: f64,
    /// Notches.
    pub notches: Vec<PieceNotch>,
    /// Grain line, start and end (parallel to the y axis, pointing down), mm.
    pub grain: [DVec2; 2],
    /// Internal lines.
    pub internal_lines: Vec<InternalLine>,
    /// Grade points (corners and notches), in a stable order per template.
    pub grade_points: Vec<GradePoint>,
    /// The point all sizes of this piece are stacked at in a graded nest (the origin).
    pub stack_point: DVec2,
}

/// Grade rules of one piece: how each grade point moves from the base size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PieceGradeRules {
    /// Piece name.
    pub piece: String,
    /// One rule per grade point, in the piece's grade-point order.
    pub rules: Vec<GradeRule>,
}

/// The move of one grade point over all sizes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GradeRule {
    /// Rule number, 1-based, unique within the table (AAMA rule id).
    pub number: u32,
    /// Template node.
    pub node: u32,
    /// Label of the grade point.
    pub label: String,
    /// `(dx, dy)` of every size from the base size, in the table's size order, mm.
    pub deltas: Vec<DVec2>,
}

/// Grade rules of a garment: base size, sizes in order, and every piece's rules.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GradeRuleTable {
    /// Garment (template) name.
    pub style: String,
    /// Sizes, smallest to largest.
    pub sizes: Vec<String>,
    /// The base (sample) size, one of `sizes`.
    pub base_size: String,
    /// Per piece.
    pub pieces: Vec<PieceGradeRules>,
}
