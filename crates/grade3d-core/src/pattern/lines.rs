//! Clean lines (issue #14, item 5; `DESIGN.md` §9 "Clean lines"): the
//! internal lines of a pattern piece (AAMA layer 8: dart legs, girth lines
//! such as `hip_line`) as a pattern maker checks them.
//!
//! # Contract
//!
//! Input: one [`PatternPiece`] (sew line closed and counter-clockwise, mm).
//! Each internal line must be
//! - **simple**: no two of its segments that do not share an end point
//!   properly cross;
//! - **inside its piece**: none of its points lies outside the sew line by
//!   more than [`LINE_TOUCH_MM`], and none of its segments properly crosses
//!   the sew line;
//! - **ended**: each end lies on the sew line (within [`LINE_TOUCH_MM`]) or
//!   at a dart's apex (the middle point of a dart's legs, which run mouth →
//!   apex → mouth).
//!
//! Every breach is returned as a [`LineProblem`] naming the line; no
//! failure modes (a line of fewer than two points is reported as not ended).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::piece::PatternPiece;
use crate::geom::polyline::{distance_to_polygon, point_in_polygon, segment_crosses_polygon, segments_cross};

/// A point closer than this to the sew line lies on it, mm (a CAD system's
/// snap distance; far below a drawn line's width).
pub const LINE_TOUCH_MM: f64 = 0.01;

/// What is wrong with an internal line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum LineProblem {
    /// Two of its segments cross (segment indices).
    SelfCrossing {
        /// The line's name.
        line: String,
        /// The two segments.
        segments: [usize; 2],
    },
    /// It leaves the piece: a point outside the sew line, or a segment
    /// crossing it.
    OutsidePiece {
        /// The line's name.
        line: String,
        /// The point or segment index.
        at: usize,
        /// How far outside, mm (0 for a crossing segment).
        distance_mm: f64,
    },
    /// An end neither on the sew line nor at a dart apex.
    LooseEnd {
        /// The line's name.
        line: String,
        /// Its distance from the sew line, mm.
        distance_mm: f64,
    },
}

/// Every [`LineProblem`] of `piece`'s internal lines (module docs).
pub fn line_problems(piece: &PatternPiece) -> Vec<LineProblem> {
    let sew = &piece.sew_line;
    let apexes: Vec<DVec2> = piece
        .internal_lines
        .iter()
        .filter(|l| l.name.starts_with("dart") && l.points.len() >= 3)
        .map(|l| l.points[l.points.len() / 2])
        .collect();
    let to_sew = |p: DVec2| distance_to_polygon(sew, p);
    let mut out = Vec::new();
    for line in &piece.internal_lines {
        let pts = &line.points;
        let name = || line.name.clone();
        if pts.len() < 2 {
            out.push(LineProblem::LooseEnd { line: name(), distance_mm: f64::INFINITY });
            continue;
        }
        let segs = pts.len() - 1;
        for i in 0..segs {
            for j in i + 2..segs {
                if segments_cross(pts[i], pts[i + 1], pts[j], pts[j + 1]) {
                    out.push(LineProblem::SelfCrossing { line: name(), segments: [i, j] });
                }
            }
        }
        for (k, &p) in pts.iter().enumerate() {
            let d = to_sew(p);
            if !point_in_polygon(sew, p) && d > LINE_TOUCH_MM {
                out.push(LineProblem::OutsidePiece { line: name(), at: k, distance_mm: d });
            }
        }
        for i in 0..segs {
            if segment_crosses_polygon(pts[i], pts[i + 1], sew) {
                out.push(LineProblem::OutsidePiece { line: name(), at: i, distance_mm: 0.0 });
            }
        }
        for end in [pts[0], pts[pts.len() - 1]] {
            let d = to_sew(end);
            let at_apex = apexes.iter().any(|a| a.distance(end) <= LINE_TOUCH_MM);
            if d > LINE_TOUCH_MM && !at_apex {
                out.push(LineProblem::LooseEnd { line: name(), distance_mm: d });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::piece::InternalLine;

    fn square_with(lines: Vec<InternalLine>) -> PatternPiece {
        let sew = vec![DVec2::ZERO, DVec2::new(100.0, 0.0), DVec2::new(100.0, 100.0), DVec2::new(0.0, 100.0)];
        PatternPiece {
            name: "p".into(),
            size: "s".into(),
            quantity: 1,
            cut_pair: false,
            cut_line: sew.clone(),
            sew_line: sew,
            corners: vec![0, 1, 2, 3],
            seam_allowance_mm: 0.0,
            notches: Vec::new(),
            grain: [DVec2::ZERO, DVec2::new(0.0, -1.0)],
            internal_lines: lines,
            grade_points: Vec::new(),
            stack_point: DVec2::ZERO,
        }
    }

    fn line(name: &str, pts: &[[f64; 2]]) -> InternalLine {
        InternalLine { name: name.into(), points: pts.iter().map(|&p| DVec2::from(p)).collect() }
    }

    #[test]
    fn a_girth_line_across_and_a_dart_are_clean() {
        let p = square_with(vec![
            line("hip_line", &[[0.0, 50.0], [50.0, 52.0], [100.0, 50.0]]),
            line("dart_front", &[[40.0, 100.0], [50.0, 70.0], [60.0, 100.0]]),
        ]);
        assert_eq!(line_problems(&p), Vec::new());
    }

    #[test]
    fn a_crossed_dart_a_line_out_of_the_piece_and_a_loose_end_are_named() {
        let p = square_with(vec![
            // legs crossed into a bow tie
            line("dart_x", &[[40.0, 100.0], [60.0, 60.0], [40.0, 60.0], [60.0, 100.0]]),
        ]);
        assert!(line_problems(&p).iter().any(|e| matches!(e, LineProblem::SelfCrossing { segments: [0, 2], .. })));
        let p = square_with(vec![line("hip_line", &[[0.0, 50.0], [120.0, 50.0]])]);
        let problems = line_problems(&p);
        assert!(problems.iter().any(
            |e| matches!(e, LineProblem::OutsidePiece { at: 1, distance_mm, .. } if (distance_mm - 20.0).abs() < 1e-9)
        ));
        let p = square_with(vec![line("knee_line", &[[0.0, 50.0], [70.0, 50.0]])]);
        assert_eq!(line_problems(&p), vec![LineProblem::LooseEnd { line: "knee_line".into(), distance_mm: 30.0 }]);
    }
}
