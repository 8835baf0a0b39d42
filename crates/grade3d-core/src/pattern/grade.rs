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

use super::assemble::signed_area;
use crate::body::measure::MeasurementId;
use crate::geom::polyline::{distance_to_polygon, point_in_polygon, segments_cross};
use crate::template::format::Template;

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

/// How one step of a graded nest reads (issue #14, item 3): the sew lines
/// of two consecutive sizes of a piece, overlaid as the nest stacks them.
#[derive(Debug, Clone, PartialEq)]
pub struct NestStep {
    /// Piece name.
    pub piece: String,
    /// The smaller size (earlier in size order).
    pub smaller: String,
    /// The next size.
    pub larger: String,
    /// Segment pairs of the two sew lines that properly cross (touching at
    /// a shared point — the stack point, a grain end — is not a crossing).
    pub crossings: usize,
    /// Sew-line points of the smaller size outside the larger one's, farther
    /// than [`NEST_TOUCH_MM`] from it.
    pub outside: usize,
    /// How far the farthest of them lies outside, mm (0 when none does).
    pub outside_mm: f64,
}

/// Two sew lines closer than this touch (a shared stack point or grain
/// end), mm.
pub const NEST_TOUCH_MM: f64 = 0.01;

/// Every consecutive step of every piece of `nest` ([`nests`]) as a
/// [`NestStep`]. Where the chart grows, each size's sew line should lie
/// inside the next one's: 0 crossings, 0 points outside.
pub fn nest_steps(nest: &[(String, Vec<PatternPiece>)]) -> Vec<NestStep> {
    let mut out = Vec::new();
    for (piece, all) in nest {
        for w in all.windows(2) {
            let (a, b) = (&w[0].sew_line, &w[1].sew_line);
            let mut crossings = 0;
            for i in 0..a.len() {
                let (p, q) = (a[i], a[(i + 1) % a.len()]);
                for j in 0..b.len() {
                    if segments_cross(p, q, b[j], b[(j + 1) % b.len()]) {
                        crossings += 1;
                    }
                }
            }
            let beyond: Vec<f64> = a
                .iter()
                .filter(|&&p| !point_in_polygon(b, p))
                .map(|&p| distance_to_polygon(b, p))
                .filter(|&d| d > NEST_TOUCH_MM)
                .collect();
            out.push(NestStep {
                piece: piece.clone(),
                smaller: w[0].size.clone(),
                larger: w[1].size.clone(),
                crossings,
                outside: beyond.len(),
                outside_mm: beyond.iter().copied().fold(0.0, f64::max),
            });
        }
    }
    out
}

/// How regular one grade point's steps are (issue #14, item 4).
#[derive(Debug, Clone, PartialEq)]
pub struct StepRegularity {
    /// Piece name.
    pub piece: String,
    /// Grade point label.
    pub label: String,
    /// The steps between consecutive sizes, mm, each scaled to the mean
    /// chart step (`step_k · mean(w) / w_k` for chart steps `w`).
    pub steps: Vec<DVec2>,
    /// The largest `|step_k − mean step|`, mm.
    pub worst_mm: f64,
    /// What the bar allows: `max(2 mm, 25 % of |mean step|)`, mm.
    pub allowed_mm: f64,
    /// Steps whose x or y as cut (unscaled) runs against the mean step's by
    /// more than [`STEP_SIGN_TOLERANCE_MM`] (a grade point that moves back).
    pub sign_changes: usize,
}

/// A step component smaller than this has no sign, mm (below what a
/// pattern maker's ruler shows).
pub const STEP_SIGN_TOLERANCE_MM: f64 = 0.5;

/// The chart steps that one grade point's steps are read against, per axis
/// of the piece (one per consecutive pair of sizes, any unit): `x` across
/// the grain (a width: the girth the point lies on), `y` along it (a
/// length: the stature, or where the chart grades no length the girth that
/// lengthens the piece). `None` reads that axis unscaled.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AxisSteps {
    /// Chart steps that the step's x (across the grain) is scaled by.
    pub x: Option<Vec<f64>>,
    /// Chart steps that the step's y (along the grain) is scaled by.
    pub y: Option<Vec<f64>>,
}

impl AxisSteps {
    /// The same chart steps for both axes (one governing girth).
    pub fn both(steps: Option<Vec<f64>>) -> Self {
        Self { x: steps.clone(), y: steps }
    }
}

/// The step regularity of every grade point of `table`; `chart_steps`, where
/// given (one per consecutive pair of sizes, any unit), are the chart steps
/// of the governing girth that the grade steps are scaled by (an uneven
/// chart), both axes alike.
pub fn step_regularity(table: &GradeRuleTable, chart_steps: Option<&[f64]>) -> Vec<StepRegularity> {
    step_regularity_by(table, |_| AxisSteps::both(chart_steps.map(<[f64]>::to_vec)))
}

/// [`step_regularity`] with each grade point's own chart steps, per axis:
/// `chart_steps(node)` gives the steps that the x and the y of the grade
/// point at template node `node` are scaled by ([`step_regularity_governed`]
/// picks them). A step `Δ_k` becomes `(Δx_k · w̄x / wx_k, Δy_k · w̄y / wy_k)`,
/// `w_k` the axis' chart step and `w̄` their mean; chart steps of the wrong
/// count or not all positive leave that axis unscaled.
///
/// A step *runs back* (a sign change) where its component as cut — the
/// move a pattern maker's ruler shows, before any scaling — opposes the
/// mean step's by more than [`STEP_SIGN_TOLERANCE_MM`].
pub fn step_regularity_by(table: &GradeRuleTable, chart_steps: impl Fn(u32) -> AxisSteps) -> Vec<StepRegularity> {
    let mut out = Vec::new();
    for piece in &table.pieces {
        for r in &piece.rules {
            let raw: Vec<DVec2> = r.deltas.windows(2).map(|w| w[1] - w[0]).collect();
            if raw.is_empty() {
                continue;
            }
            let chart = chart_steps(r.node);
            // per axis, the factor `w̄ / w_k` of each step (1 where unscaled)
            let factors = |c: Option<Vec<f64>>| -> Vec<f64> {
                match c.filter(|c| c.len() == raw.len() && c.iter().all(|&w| w > 0.0)) {
                    Some(c) => {
                        let mean_w = c.iter().sum::<f64>() / c.len() as f64;
                        c.iter().map(|w| mean_w / w).collect()
                    }
                    None => vec![1.0; raw.len()],
                }
            };
            let (fx, fy) = (factors(chart.x), factors(chart.y));
            let steps: Vec<DVec2> = raw.iter().enumerate().map(|(k, s)| DVec2::new(s.x * fx[k], s.y * fy[k])).collect();
            let mean = steps.iter().copied().sum::<DVec2>() / steps.len() as f64;
            let worst_mm = steps.iter().map(|s| s.distance(mean)).fold(0.0, f64::max);
            let against = |v: f64, m: f64| m.abs() > STEP_SIGN_TOLERANCE_MM && v * m.signum() < -STEP_SIGN_TOLERANCE_MM;
            let sign_changes = raw.iter().filter(|s| against(s.x, mean.x) || against(s.y, mean.y)).count();
            out.push(StepRegularity {
                piece: piece.piece.clone(),
                label: r.label.clone(),
                steps,
                worst_mm,
                allowed_mm: (0.25 * mean.length()).max(2.0),
                sign_changes,
            });
        }
    }
    out
}

/// [`step_regularity_by`] with each grade point read as a grader reads its
/// rule, each axis against the chart steps of the measurement that governs
/// it — the first of these that `chart_steps` gives with every step
/// positive:
/// * **x**, across the grain (a width): the point's own governing girths
///   ([`governing_girths`] of template `t`: a waist point the waist, an
///   armpit point the chest), then the template's [`principal_girths`];
/// * **y**, along the grain (a length): the stature, then the template's
///   [`principal_girths`] — on a chart that grades no length, a bodice
///   lengthens over a fuller bust (its waist points' y follow the bust's
///   steps, their x the waist's) and a skirt or trousers over a fuller hip.
pub fn step_regularity_governed(
    table: &GradeRuleTable,
    t: &Template,
    chart_steps: impl Fn(MeasurementId) -> Option<Vec<f64>>,
) -> Vec<StepRegularity> {
    let principal = principal_girths(t);
    let first = |candidates: Vec<MeasurementId>| {
        candidates.into_iter().find_map(|m| chart_steps(m).filter(|c| !c.is_empty() && c.iter().all(|&w| w > 0.0)))
    };
    let y = first([vec![MeasurementId::Stature], principal.clone()].concat());
    step_regularity_by(table, |node| AxisSteps {
        x: first([governing_girths(t, node), principal.clone()].concat()),
        y: y.clone(),
    })
}

/// The girths that govern a garment as a whole, nearest first: the bust and
/// the chest for a garment with a node on a bust point (a bodice), else the
/// hip. A grader grades a piece's lengths by them where the chart grades no
/// length, and reads a grade point by them where the chart lacks the
/// point's own girth.
pub fn principal_girths(t: &Template) -> Vec<MeasurementId> {
    if t.nodes.iter().any(|n| MeasurementId::governing(n.point).contains(&MeasurementId::BustGirth)) {
        vec![MeasurementId::BustGirth, MeasurementId::ChestGirth]
    } else {
        vec![MeasurementId::HipGirth]
    }
}

/// The girths that govern how template node `node` grades, nearest first
/// (issue #14, item 4): for a node placed along a body curve
/// ([`crate::template::format::OnCurve`]) the girth along that curve, then
/// those of the feature point it is tied to
/// ([`MeasurementId::governing`]: a waist point the waist girth, an armpit
/// point the chest girth). A reader falls back to the template's
/// [`principal_girths`] where the chart gives none of them.
pub fn governing_girths(t: &Template, node: u32) -> Vec<MeasurementId> {
    let mut out: Vec<MeasurementId> =
        t.on_curve.iter().filter(|c| c.node == node).filter_map(|c| MeasurementId::girth_along(c.curve)).collect();
    if let Some(n) = t.nodes.get(node as usize) {
        for m in MeasurementId::governing(n.point) {
            if !out.contains(&m) {
                out.push(m);
            }
        }
    }
    out
}

/// How far two pieces of a mirror pair are from mirror images (issue #14,
/// item 2): the second mirrored across the grain line through the stack
/// point (`x → −x`: pieces are placed stack point at the origin, grain
/// along −y) and compared with the first.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MirrorDifference {
    /// |A₁ − A₂| / A₁ of the areas inside the sew lines, %.
    pub area_pct: f64,
    /// Relative difference of the widths (x extent), %.
    pub width_pct: f64,
    /// Relative difference of the heights (y extent), %.
    pub height_pct: f64,
    /// Largest distance from a sew-line point of either piece to the other's
    /// sew line (a symmetric Hausdorff distance over the vertices), mm.
    pub sew_line_mm: f64,
}

/// [`MirrorDifference`] of `a` and `b`.
pub fn mirror_difference(a: &PatternPiece, b: &PatternPiece) -> MirrorDifference {
    let mirrored: Vec<DVec2> = b.sew_line.iter().map(|p| DVec2::new(-p.x, p.y)).collect();
    let area = |poly: &[DVec2]| signed_area(poly).abs();
    let extent = |poly: &[DVec2], f: fn(&DVec2) -> f64| {
        let v = poly.iter().map(f);
        v.clone().fold(f64::MIN, f64::max) - v.fold(f64::MAX, f64::min)
    };
    let pct = |x: f64, y: f64| if x.abs() > 0.0 { 100.0 * (x - y).abs() / x.abs() } else { 0.0 };
    let far = |from: &[DVec2], to: &[DVec2]| from.iter().map(|&p| distance_to_polygon(to, p)).fold(0.0, f64::max);
    MirrorDifference {
        area_pct: pct(area(&a.sew_line), area(&mirrored)),
        width_pct: pct(extent(&a.sew_line, |p| p.x), extent(&mirrored, |p| p.x)),
        height_pct: pct(extent(&a.sew_line, |p| p.y), extent(&mirrored, |p| p.y)),
        sew_line_mm: far(&a.sew_line, &mirrored).max(far(&mirrored, &a.sew_line)),
    }
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
            cut_pair: false,
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
        // the planted grade is a nest that nests and steps evenly
        let nest = nests(&sizes).expect("nest");
        for step in nest_steps(&nest) {
            assert_eq!((step.crossings, step.outside), (0, 0), "{step:?}");
        }
        for r in step_regularity(&t, None) {
            assert!(r.worst_mm < 1e-9 && r.sign_changes == 0, "{r:?}");
        }
    }

    #[test]
    fn crossing_outlines_and_uneven_steps_are_counted() {
        // a square, then a rectangle wider but shorter: the outlines cross twice and two
        // corners of the first lie outside the second
        let mut wide = square("s1", 120.0);
        wide.sew_line = vec![DVec2::ZERO, DVec2::new(120.0, 0.0), DVec2::new(120.0, -80.0), DVec2::new(0.0, -80.0)];
        wide.grade_points[2].at = DVec2::new(120.0, -80.0);
        wide.grade_points[3].at = DVec2::new(0.0, -80.0);
        let sizes = vec![("s0".to_string(), vec![square("s0", 100.0)]), ("s1".to_string(), vec![wide])];
        let steps = nest_steps(&nests(&sizes).expect("nest"));
        assert_eq!(steps.len(), 1);
        // the sides x = 100 (down to −100) and y = −80 cross once; the bottom corners are outside
        assert_eq!((steps[0].crossings, steps[0].outside), (1, 2), "{:?}", steps[0]);
        // …by the square's 20 mm below the rectangle
        assert!((steps[0].outside_mm - 20.0).abs() < 1e-9, "{:?}", steps[0]);
        // steps +20, +20, −5 of one point: the last runs back; scaled by a chart whose last
        // step is a quarter of the others it is +20 again
        let mut t = grade_rules("t", &sizes, "s0").expect("rules");
        t.pieces[0].rules[1].deltas =
            vec![DVec2::ZERO, DVec2::new(20.0, 0.0), DVec2::new(40.0, 0.0), DVec2::new(35.0, 0.0)];
        let r = &step_regularity(&t, None)[1];
        assert_eq!(r.sign_changes, 1, "{r:?}");
        assert!(r.worst_mm > r.allowed_mm, "{r:?}");
        let scaled = &step_regularity(&t, Some(&[4.0, 4.0, -1.0]))[1];
        assert_eq!(scaled.steps.len(), 3, "a chart step that is not positive leaves the steps unscaled");
        // per grade point: steps +20, +40, +20 of a point whose own girth steps 1, 2, 1 are
        // even; the other points, read against an even girth, are left as they are
        t.pieces[0].rules[1].deltas =
            vec![DVec2::ZERO, DVec2::new(20.0, 0.0), DVec2::new(60.0, 0.0), DVec2::new(80.0, 0.0)];
        let node = t.pieces[0].rules[1].node;
        let own = step_regularity_by(&t, |n| {
            AxisSteps::both(Some(if n == node { vec![1.0, 2.0, 1.0] } else { vec![1.0; 3] }))
        });
        assert!(own[1].worst_mm < 1e-9 && own[1].sign_changes == 0, "{:?}", own[1]);
        assert_eq!(own[0].steps, step_regularity(&t, None)[0].steps);
        let one = &step_regularity(&t, Some(&[1.0, 1.0, 1.0]))[1];
        assert!(one.worst_mm > one.allowed_mm, "read against one even girth the point jumps: {one:?}");
    }

    /// One rule of one piece, steps `steps` from a base at the first size.
    fn one_rule(node: u32, steps: &[DVec2]) -> GradeRuleTable {
        let mut deltas = vec![DVec2::ZERO];
        for s in steps {
            deltas.push(*deltas.last().unwrap() + *s);
        }
        let sizes: Vec<String> = (0..deltas.len()).map(|k| format!("s{k}")).collect();
        GradeRuleTable {
            style: "t".into(),
            base_size: sizes[0].clone(),
            sizes,
            pieces: vec![PieceGradeRules {
                piece: "front".into(),
                rules: vec![GradeRule { number: 1, node, label: "p".into(), deltas }],
            }],
        }
    }

    #[test]
    fn each_axis_is_read_against_its_own_chart_steps() {
        // x follows a girth stepping 1, 2, 1 (8 mm a unit), y one stepping 2, 1, 1 (−3 mm a unit)
        let table = one_rule(0, &[DVec2::new(8.0, -6.0), DVec2::new(16.0, -3.0), DVec2::new(8.0, -3.0)]);
        let (gx, gy) = (vec![1.0, 2.0, 1.0], vec![2.0, 1.0, 1.0]);
        let per_axis = &step_regularity_by(&table, |_| AxisSteps { x: Some(gx.clone()), y: Some(gy.clone()) })[0];
        assert!(per_axis.worst_mm < 1e-9 && per_axis.sign_changes == 0, "{per_axis:?}");
        for one in [&gx, &gy] {
            let r = &step_regularity(&table, Some(one))[0];
            assert!(r.worst_mm > 2.0, "one girth for both axes leaves a jump: {r:?}");
        }
    }

    #[test]
    fn a_step_runs_back_by_what_the_ruler_shows_not_by_its_scaled_size() {
        // x steps −2, −2, +0.4 mm as cut, the last over a chart step 0.4 of the others: scaled
        // it is +0.8 mm against a mean of −0.8, but it moves 0.4 mm, under the ruler's 0.5
        let chart = [1.0, 1.0, 0.4];
        let small = one_rule(0, &[DVec2::new(-2.0, 0.0), DVec2::new(-2.0, 0.0), DVec2::new(0.4, 0.0)]);
        let r = &step_regularity(&small, Some(&chart))[0];
        assert!((r.steps[2].x - 0.8).abs() < 1e-9 && r.sign_changes == 0, "{r:?}");
        let back = one_rule(0, &[DVec2::new(-2.0, 0.0), DVec2::new(-2.0, 0.0), DVec2::new(0.6, 0.0)]);
        assert_eq!(step_regularity(&back, Some(&chart))[0].sign_changes, 1);
    }

    #[test]
    fn a_bodice_waist_point_is_read_across_by_the_waist_and_along_by_the_bust() {
        use crate::body::vocab::PointId;
        let library = crate::template::library::builtin().expect("built-in templates");
        let bodice = library.iter().find(|t| t.name == "fitted-bodice").expect("bodice");
        let skirt = library.iter().find(|t| t.name == "straight-skirt").expect("skirt");
        assert_eq!(principal_girths(bodice), [MeasurementId::BustGirth, MeasurementId::ChestGirth]);
        assert_eq!(principal_girths(skirt), [MeasurementId::HipGirth]);
        let node = bodice.nodes.iter().position(|n| n.point == PointId::WaistLeft).expect("waist node") as u32;
        // x 10 mm per waist unit (steps 1, 2, 1), y −3 mm per bust unit (steps 2, 1, 1);
        // the chart's stature does not grade (steps 0), so lengths go with the bust
        let table = one_rule(node, &[DVec2::new(10.0, -6.0), DVec2::new(20.0, -3.0), DVec2::new(10.0, -3.0)]);
        let chart = |m: MeasurementId| match m {
            MeasurementId::WaistGirth => Some(vec![1.0, 2.0, 1.0]),
            MeasurementId::BustGirth => Some(vec![2.0, 1.0, 1.0]),
            MeasurementId::Stature => Some(vec![0.0; 3]),
            _ => None,
        };
        let r = &step_regularity_governed(&table, bodice, chart)[0];
        assert!(r.worst_mm < 1e-9 && r.sign_changes == 0, "{r:?}");
        // a chart that grades the stature evenly reads the lengths by it: the y steps jump
        let graded = |m: MeasurementId| if m == MeasurementId::Stature { Some(vec![1.0; 3]) } else { chart(m) };
        let r = &step_regularity_governed(&table, bodice, graded)[0];
        assert!((r.worst_mm - 2.0).abs() < 1e-9, "{r:?}");
    }

    #[test]
    fn a_mirrored_piece_differs_by_nothing_and_a_wider_one_by_its_width() {
        // an L-shaped piece and its mirror image across x = 0
        let mut a = square("s", 100.0);
        a.sew_line = vec![
            DVec2::ZERO,
            DVec2::new(100.0, 0.0),
            DVec2::new(100.0, -40.0),
            DVec2::new(40.0, -40.0),
            DVec2::new(40.0, -100.0),
            DVec2::new(0.0, -100.0),
        ];
        let mut b = a.clone();
        b.sew_line = a.sew_line.iter().rev().map(|p| DVec2::new(-p.x, p.y)).collect();
        let d = mirror_difference(&a, &b);
        assert!(d.area_pct < 1e-12 && d.width_pct < 1e-12 && d.height_pct < 1e-12 && d.sew_line_mm < 1e-12, "{d:?}");
        // the second 2 mm wider on its outer side: 2 % wider, 2 mm off
        b.sew_line[3].x -= 2.0;
        b.sew_line[4].x -= 2.0;
        let d = mirror_difference(&a, &b);
        assert!((d.width_pct - 2.0).abs() < 1e-9 && (d.sew_line_mm - 2.0).abs() < 1e-9, "{d:?}");
    }
}
