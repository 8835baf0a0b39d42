//! Graded nests and grade rules: how the 3D grading of every size feeds the
//! 2D grading systems the industry runs (issue #5; AAMA/ASTM D6673 grade
//! rule tables).
//!
//! # Contract
//!
//! Input: the pattern pieces of each size, sizes in order (smallest to
//! largest), every piece already placed by [`super::assemble`] — stack
//! point at the origin, grain line along `−y`.
//!
//! **Nest** — per piece name, the piece of every size in size order,
//! overlaid as they are (same stack point, grain lines parallel).
//!
//! **Grade rules** — per piece, for each grade point `g` (corner or notch,
//! identified by its template node and kind) of the base size `b`, the move
//! `Δ_s(g) = p_s(g) − p_b(g)` (mm, piece axes) in every size `s`. Rules are
//! numbered from 1 over all pieces in order, as a rule table does.
//!
//! **Failure modes** — [`GradeError`]: no sizes, a base size not among
//! them, a piece missing from a size, a grade point of the base size
//! missing in another size.

use glam::DVec2;

use super::piece::{GradePointKind, GradeRule, GradeRuleTable, PatternPiece, PieceGradeRules};

/// Why grading across sizes failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GradeError {
    /// No sizes given.
    #[error("no sizes to grade")]
    NoSizes,
    /// The base size is not one of the sizes.
    #[error("base size '{0}' is not among the graded sizes")]
    UnknownBase(String),
    /// A piece of the base size is missing in another size.
    #[error("size '{size}' has no piece '{piece}'")]
    MissingPiece {
        /// Size.
        size: String,
        /// Piece name.
        piece: String,
    },
    /// A grade point of the base size is missing in another size.
    #[error("size '{size}', piece '{piece}': no grade point at node {node}")]
    MissingGradePoint {
        /// Size.
        size: String,
        /// Piece.
        piece: String,
        /// Template node.
        node: u32,
    },
}

/// All sizes of every piece, overlaid: `(piece name, pieces smallest to largest)`,
/// pieces in the order of the first size.
///
/// # Errors
/// [`GradeError::NoSizes`], [`GradeError::MissingPiece`].
pub fn nests(sizes: &[(String, Vec<PatternPiece>)]) -> Result<Vec<(String, Vec<PatternPiece>)>, GradeError> {
    let (_, first) = sizes.first().ok_or(GradeError::NoSizes)?;
    first
        .iter()
        .map(|p| {
            let all = sizes
                .iter()
                .map(|(size, pieces)| {
                    pieces
                        .iter()
                        .find(|q| q.name == p.name)
                        .cloned()
                        .ok_or_else(|| GradeError::MissingPiece { size: size.clone(), piece: p.name.clone() })
                })
                .collect::<Result<Vec<_>, _>>()?;
            Ok((p.name.clone(), all))
        })
        .collect()
}

/// The grade rule table of `style` from the pieces of every size, relative to `base`
/// (module docs).
///
/// # Errors
/// [`GradeError`].
pub fn grade_rules(
    style: &str,
    sizes: &[(String, Vec<PatternPiece>)],
    base: &str,
) -> Result<GradeRuleTable, GradeError> {
    let nests = nests(sizes)?;
    let base_index = sizes.iter().position(|(s, _)| s == base).ok_or_else(|| GradeError::UnknownBase(base.into()))?;
    let mut number = 0u32;
    let mut pieces = Vec::with_capacity(nests.len());
    for (name, all) in &nests {
        let base_piece = &all[base_index];
        let mut rules = Vec::with_capacity(base_piece.grade_points.len());
        for g in &base_piece.grade_points {
            let deltas = all
                .iter()
                .map(|p| {
                    find_point(p, g.node, g.kind).map(|at| at - g.at).ok_or_else(|| GradeError::MissingGradePoint {
                        size: p.size.clone(),
                        piece: name.clone(),
                        node: g.node,
                    })
                })
                .collect::<Result<Vec<DVec2>, _>>()?;
            number += 1;
            rules.push(GradeRule { number, node: g.node, label: g.label.clone(), deltas });
        }
        pieces.push(PieceGradeRules { piece: name.clone(), rules });
    }
    Ok(GradeRuleTable {
        style: style.to_string(),
        sizes: sizes.iter().map(|(s, _)| s.clone()).collect(),
        base_size: base.to_string(),
        pieces,
    })
}

fn find_point(p: &PatternPiece, node: u32, kind: GradePointKind) -> Option<DVec2> {
    p.grade_points.iter().find(|g| g.node == node && g.kind == kind).map(|g| g.at)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::piece::GradePoint;

    fn square(size: &str, side: f64) -> PatternPiece {
        let sew = vec![DVec2::ZERO, DVec2::new(side, 0.0), DVec2::new(side, -side), DVec2::new(0.0, -side)];
        PatternPiece {
            name: "front".into(),
            size: size.into(),
            quantity: 1,
            sew_line: sew.clone(),
            corners: vec![0, 1, 2, 3],
            cut_line: sew.clone(),
            seam_allowance_mm: 0.0,
            notches: vec![],
            grain: [DVec2::ZERO, DVec2::new(0.0, -side)],
            internal_lines: vec![],
            grade_points: sew
                .iter()
                .enumerate()
                .map(|(i, &at)| GradePoint { node: i as u32, label: format!("c{i}"), at, kind: GradePointKind::Corner })
                .collect(),
            stack_point: DVec2::ZERO,
        }
    }

    #[test]
    fn a_planted_linear_grade_comes_back_as_rules() {
        // squares growing by 20 mm a size: the far corner moves (+20, −20) per size
        let sizes: Vec<(String, Vec<PatternPiece>)> =
            (0..3).map(|k| (format!("s{k}"), vec![square(&format!("s{k}"), 100.0 + 20.0 * k as f64)])).collect();
        let t = grade_rules("test", &sizes, "s1").expect("rules");
        assert_eq!(t.pieces.len(), 1);
        let rules = &t.pieces[0].rules;
        assert_eq!(rules.iter().map(|r| r.number).collect::<Vec<_>>(), [1, 2, 3, 4]);
        assert_eq!(rules[0].deltas, vec![DVec2::ZERO; 3], "the stack point never moves");
        assert_eq!(rules[2].deltas, vec![DVec2::new(-20.0, 20.0), DVec2::ZERO, DVec2::new(20.0, -20.0)]);
        assert_eq!(grade_rules("t", &sizes, "xl").unwrap_err(), GradeError::UnknownBase("xl".into()));
        let mut broken = sizes.clone();
        broken[2].1[0].grade_points.pop();
        assert_eq!(
            grade_rules("t", &broken, "s0").unwrap_err(),
            GradeError::MissingGradePoint { size: "s2".into(), piece: "front".into(), node: 3 }
        );
        broken[2].1.clear();
        assert!(matches!(nests(&broken).unwrap_err(), GradeError::MissingPiece { .. }));
        assert_eq!(nests(&[]).unwrap_err(), GradeError::NoSizes);
    }
}
