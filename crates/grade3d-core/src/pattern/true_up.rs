//! Truing a graded nest at its corners (issue #14, item 3): the pattern
//! maker's check that, where the chart grows, each size's sew line lies
//! inside the next larger one's, and the correction of the grade rules at
//! the corners where it does not.
//!
//! # Why
//!
//! Each size's piece is flattened from that size's 3D garment. Where a
//! girth grows but the lengths beside it do not (a chart without lengths,
//! a waist-to-hip depth the same in every size), the 3D grade moves a corner
//! straight outwards, while the line beside it meets that corner at a slope.
//! The skirt's side waist is the example: its waist line rises towards the
//! side seam at the hip spring's slope `k` (0.3–0.45 on the ASTM
//! mannequins), the side-waist corner moves out `δx` ≈ 6 mm per step and up
//! only 0.5 mm, so the smaller size's corner stands `k δx − δy` ≈ 0.7–4.9 mm
//! above the larger size's waist line: the nest crosses there, as a grade
//! rule table would regenerate it in any CAD system. A grader keeps the
//! waist lines parallel by moving that corner up the seam as well; this
//! module makes that move, and only that one.
//!
//! # Method
//!
//! Sizes are trued outwards from the base size, which is never moved: each
//! size larger than the base against the (trued) size below it, each size
//! smaller against the (trued) size above it. At every convex corner `c` of
//! the larger piece whose turn is at least [`TrueOptions::min_turn_deg`],
//! with edges `a` (into `c`) and `b` (out of `c`), outward unit normals
//! `n_a`, `n_b`, the smaller piece's corner at the same template node `p_s`
//! must satisfy
//!
//! ```text
//! D_a = (p_s − p_l)·n_a ≤ 0,   D_b = (p_s − p_l)·n_b ≤ 0
//! ```
//!
//! A violated `D_a` is corrected by sliding the corner along the other
//! edge's line, `b` — so `D_b` does not change — by
//! `s = (D_a + m) / (u_b · n_a)` (`m`: [`TrueOptions::margin_mm`]), `u_b` the unit direction of `b` extended beyond
//! the corner: the run from `c` to the next grade point along `b` gets
//! longer by `s` (the larger size corrected) or the smaller size's run
//! shorter by `s`. A run shared by two pieces of the garment (a seam: the
//! same two template nodes on both) gets the same slide on both pieces, the
//! largest either needs, so the seam's two sides keep their lengths equal.
//! Sew lines correspond point by point across sizes (every size of a
//! template has the same outline connectivity), so the same test runs at
//! every convex outline point whose turn passes the gate, not only at grade
//! points (a closed dart's far mouth point is one), where the run it lies on
//! is no seam. Then, off the seams, two passes for what is left: a point of
//! the smaller size outside the larger one's line moves the larger line's
//! nearest edge out (growing) or the point in (shrinking), along the normal,
//! by its distance plus `m`; and a point of the larger size's line inside
//! the smaller one's (the lines cross between the smaller size's points)
//! likewise. These are flattening noise along lines every size shares (a hem
//! at one length, a centre front waist), at most tenths of a millimetre.
//! A step repeats up to `ROUNDS` times (a slide can uncover another point).
//!
//! Every move is spread along the outline, linearly in arc length down to
//! zero at the grade points on either side, as a CAD system distributes a
//! grade rule between grade points; where two moves overlap a point takes
//! the larger (their sum would bulge). Grade points other than those moved,
//! notches on them and internal lines ending on them do not move. The cut
//! line is offset again from the trued sew line.
//!
//! # Limits and failure modes
//!
//! No failure: a corner whose slide would exceed [`TrueOptions::max_slide_mm`]
//! or whose edges are nearly parallel (`u_b · n_a` below
//! [`TrueOptions::min_slide_gain`]), and a point off the grade points on a
//! seam, are left and counted in [`TrueReport::left`]. A seam keeps its two
//! sides' lengths to first order: a slide along one run at a corner also
//! moves the other run's end (measured on the even charts: skirt and
//! trousers seam sides change by at most 0.008 mm, the bodice's by up to
//! 0.86 mm). The 3D garment is not changed, nor are the per-piece and
//! per-seam figures of the pattern report (they are those of the pattern
//! as cut); [`TrueReport`] says how far each piece moved from it.

use std::collections::BTreeMap;

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::assemble::{offset_polygon, untangle, PieceOptions};
use super::piece::{GradePointKind, PatternPiece};
use crate::geom::polyline::{nearest_edge, point_in_polygon};

/// Knobs of truing a nest.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrueOptions {
    /// Whether to true at all. Default true.
    pub enabled: bool,
    /// How far inside the next larger size's lines a smaller size's corner is
    /// kept, mm. Default 0.05 (a touch, below any pencil line).
    pub margin_mm: f64,
    /// Least turn of a sew-line corner for it to be trued, degrees. Default 20
    /// (at a gentler turn the two edges' lines are nearly one and a slide
    /// along one barely moves the corner off the other).
    pub min_turn_deg: f64,
    /// Least `u_b · n_a` of a slide (how much of it moves the corner off the
    /// violated line). Default 0.25.
    pub min_slide_gain: f64,
    /// Largest slide of one corner in one size step, mm. Default 8 (the ASTM
    /// skirt back needs 4.9).
    pub max_slide_mm: f64,
    /// Most a size's truing may move a sew-line point from the pattern as
    /// cut, mm; where a size would need more, the whole grade is left as cut
    /// (truing part of it would put a jump into its grade rules where trued
    /// and untrued sizes meet) and those sizes are named in
    /// [`TrueReport::as_cut`]. Default 10, the seam
    /// allowance: a trued sew line stays inside the cut line as cut, and a
    /// side waist is not moved further off the body's waist than that (the
    /// ASTM skirt's would rise 23 mm by size 20, the bodice front's armhole
    /// 39 mm at 18).
    pub max_move_mm: f64,
    /// Mitre limit of the re-cut cut line, × allowance. Default that of
    /// [`PieceOptions`].
    pub miter_limit: f64,
}

impl Default for TrueOptions {
    fn default() -> Self {
        Self {
            enabled: true,
            margin_mm: 0.05,
            min_turn_deg: 20.0,
            min_slide_gain: 0.25,
            max_slide_mm: 8.0,
            max_move_mm: 10.0,
            miter_limit: PieceOptions::default().miter_limit,
        }
    }
}

/// How far truing moved one piece of one size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct TrueMove {
    /// Piece name.
    pub piece: String,
    /// Size.
    pub size: String,
    /// Corners moved, count.
    pub corners: usize,
    /// The largest move of a sew-line point from the piece as cut, mm.
    pub moved_mm: f64,
}

/// What truing did.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct TrueReport {
    /// Every piece and size that moved.
    pub moved: Vec<TrueMove>,
    /// Corners that needed a slide beyond the limits and were left, count.
    pub left: usize,
    /// The largest move of any sew-line point, mm.
    pub largest_move_mm: f64,
    /// The sizes whose truing would have moved a point further than
    /// [`TrueOptions::max_move_mm`]; when any, the whole grade was left as
    /// cut (`moved` is empty).
    pub as_cut: Vec<String>,
}

/// Slides of the corners at grade points, shared by a seam's two sides: the
/// corner's template node and the node at the other end of the run it slides
/// along → the slide, mm (positive: that run grows).
type Slides = BTreeMap<(u32, u32), f64>;

/// Slides of the other corners of one piece (a closed dart's far mouth
/// point, on a run no other piece shares): sew-line index → move, mm.
type Moves = BTreeMap<usize, DVec2>;

/// Rounds of truing one size step (a slide can uncover another point):
/// 6 (3 left crossings on the men's chart's skirt).
const ROUNDS: usize = 6;

/// Trues the nest of `sizes` (smallest to largest, each size's pieces placed
/// at their stack point) outwards from `sizes[base]` (module docs). Pieces
/// are changed in place.
pub fn true_nest(sizes: &mut [(String, Vec<PatternPiece>)], base: usize, opts: &TrueOptions) -> TrueReport {
    let mut report = TrueReport::default();
    if !opts.enabled || base >= sizes.len() {
        return report;
    }
    let original: Vec<Vec<PatternPiece>> = sizes.iter().map(|(_, p)| p.clone()).collect();
    for t in (base + 1..sizes.len()).chain((0..base).rev()) {
        let grows = t > base;
        let r = if grows { t - 1 } else { t + 1 };
        let reference = sizes[r].1.clone();
        let sign = if grows { 1.0 } else { -1.0 };
        let mut step_left = 0;
        for _ in 0..ROUNDS {
            let target = &mut sizes[t].1;
            let seams = shared_runs(target);
            let mut slides = Slides::new();
            let mut moves: Vec<Moves> = vec![Moves::new(); target.len()];
            let mut left = 0;
            for (piece, own) in target.iter().zip(&mut moves) {
                if let Some(other) = reference.iter().find(|q| q.name == piece.name) {
                    let (small, large) = if grows { (other, piece) } else { (piece, other) };
                    needed(small, large, piece, &seams, sign, opts, &mut slides, own, &mut left);
                }
            }
            step_left = left;
            if slides.is_empty() && moves.iter().all(BTreeMap::is_empty) {
                break;
            }
            for (piece, own) in target.iter_mut().zip(&moves) {
                apply(piece, &slides, own, sign, opts.miter_limit);
            }
        }
        report.left += step_left;
        let too_far = sizes[t]
            .1
            .iter()
            .zip(&original[t])
            .any(|(p, q)| p.sew_line.iter().zip(&q.sew_line).any(|(a, b)| a.distance(*b) > opts.max_move_mm));
        if too_far {
            report.as_cut.push(sizes[t].0.clone());
        }
    }
    // a grade is trued as a whole or not at all: truing part of it would put a jump in its
    // grade rules where the trued sizes meet the ones as cut
    if !report.as_cut.is_empty() {
        for ((_, pieces), before) in sizes.iter_mut().zip(&original) {
            pieces.clone_from(before);
        }
        report.left = 0;
        return report;
    }
    for ((_, pieces), before) in sizes.iter().zip(&original) {
        for (p, q) in pieces.iter().zip(before) {
            let moved = p.sew_line.iter().zip(&q.sew_line).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
            if moved > 0.0 {
                let corners = p.grade_points.iter().zip(&q.grade_points).filter(|(a, b)| a.at != b.at).count();
                report.largest_move_mm = report.largest_move_mm.max(moved);
                report.moved.push(TrueMove { piece: p.name.clone(), size: p.size.clone(), corners, moved_mm: moved });
            }
        }
    }
    report
}

/// Sew-line index of every corner grade point of `p`, with its node, in
/// outline order: the ends of the runs a truing move spreads along.
pub fn anchors(p: &PatternPiece) -> Vec<(usize, u32)> {
    let mut out: Vec<(usize, u32)> = p
        .grade_points
        .iter()
        .filter(|g| g.kind == GradePointKind::Corner)
        .filter_map(|g| p.sew_line.iter().position(|q| q.distance(g.at) < 1e-9).map(|i| (i, g.node)))
        .collect();
    out.sort_unstable();
    out.dedup_by_key(|a| a.0);
    out
}

/// The runs (consecutive grade points' nodes, as an unordered pair) that
/// more than one piece of a size has: its seams.
fn shared_runs(pieces: &[PatternPiece]) -> BTreeMap<(u32, u32), usize> {
    let mut count: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for p in pieces {
        let a = anchors(p);
        for k in 0..a.len() {
            let (u, v) = (a[k].1, a[(k + 1) % a.len()].1);
            *count.entry((u.min(v), u.max(v))).or_default() += 1;
        }
    }
    count.retain(|_, n| *n > 1);
    count
}

/// The slides `target` (the piece moved: `large` when growing, `small`
/// otherwise; `sign` +1 and −1) needs for `small` to lie inside `large` at
/// `large`'s corners: at grade points into `slides` (a seam's two sides
/// alike), elsewhere into `moves`, where the run is no seam. Sew lines
/// correspond point by point (every size of a template has the same
/// outline connectivity); where they do not, only grade points are trued.
#[expect(clippy::too_many_arguments, reason = "one step's state, split from the loop for reading")]
fn needed(
    small: &PatternPiece,
    large: &PatternPiece,
    target: &PatternPiece,
    seams: &BTreeMap<(u32, u32), usize>,
    sign: f64,
    opts: &TrueOptions,
    slides: &mut Slides,
    moves: &mut Moves,
    left: &mut usize,
) {
    let (la, ta) = (anchors(large), anchors(target));
    if la.len() < 3 || ta.len() != la.len() {
        return;
    }
    let n = large.sew_line.len();
    let by_index = small.sew_line.len() == n && target.sew_line.len() == n;
    let small_at: BTreeMap<u32, DVec2> =
        anchors(small).into_iter().map(|(i, node)| (node, small.sew_line[i])).collect();
    let min_turn = opts.min_turn_deg.to_radians().sin();
    let outward = |d: DVec2| DVec2::new(d.y, -d.x);
    for i in 0..n {
        // the grade point here, if any: its node and the nodes at the ends of its two runs
        let k = la.iter().position(|a| a.0 == i);
        let ps = match k {
            Some(k) => match small_at.get(&la[k].1) {
                Some(&p) => p,
                None => continue,
            },
            None if by_index => small.sew_line[i],
            None => continue,
        };
        let pl = large.sew_line[i];
        let (prev, next) = (large.sew_line[(i + n - 1) % n], large.sew_line[(i + 1) % n]);
        let (da, db) = ((pl - prev).normalize_or_zero(), (next - pl).normalize_or_zero());
        // convex corners of a counter-clockwise outline turn left
        if da.perp_dot(db) < min_turn {
            continue;
        }
        let (na, nb) = (outward(da), outward(db));
        // the target's own point and the directions its two runs leave it by
        let ti = match k {
            Some(k) => match ta.iter().find(|a| a.1 == la[k].1) {
                Some(a) => a.0,
                None => continue,
            },
            None => i,
        };
        let tn = target.sew_line.len();
        let tc = target.sew_line[ti];
        let ub = (tc - target.sew_line[(ti + 1) % tn]).normalize_or_zero();
        let ua = (tc - target.sew_line[(ti + tn - 1) % tn]).normalize_or_zero();
        // the grade points before and after `i` on the large outline: the run `i` lies on
        let after = la.iter().position(|a| a.0 > i).unwrap_or(0);
        let before = (after + la.len() - 1) % la.len();
        // D_a: slide along b (the run forward); D_b: along a (the run backward)
        for (outside, u, n_violated, forward) in [((ps - pl).dot(na), ub, na, true), ((ps - pl).dot(nb), ua, nb, false)]
        {
            // a corner on the line (lines that meet exactly) is left as it is
            if outside <= 0.0 {
                continue;
            }
            let gain = u.dot(n_violated);
            let s = (outside + opts.margin_mm) / gain.max(f64::EPSILON);
            if gain < opts.min_slide_gain || s > opts.max_slide_mm {
                *left += 1;
                continue;
            }
            match k {
                Some(k) => {
                    let end = if forward { la[(k + 1) % la.len()].1 } else { la[(k + la.len() - 1) % la.len()].1 };
                    let e = slides.entry((la[k].1, end)).or_insert(0.0);
                    *e = e.max(s);
                }
                None => {
                    let (u0, v0) = (la[before].1, la[after].1);
                    if seams.contains_key(&(u0.min(v0), u0.max(v0))) {
                        *left += 1;
                        continue;
                    }
                    keep_largest(moves, i, u * (sign * s));
                }
            }
        }
    }
    // the rest of the outline, off the seams: a point of the smaller size outside the larger
    // one's line (a gentle turn, flattening noise along a hem or waist that every size shares)
    // moves the line there out (growing) or the point in (shrinking), along the normal
    let seam = |u: u32, v: u32| seams.contains_key(&(u.min(v), u.max(v)));
    let on_seam = |i: usize| {
        let after = la.iter().position(|a| a.0 >= i).unwrap_or(0);
        let before = (after + la.len() - 1) % la.len();
        if la[after].0 == i {
            // a grade point: on a seam if either run at it is one
            let next = la[(after + 1) % la.len()].1;
            return seam(la[before].1, la[after].1) || seam(la[after].1, next);
        }
        seam(la[before].1, la[after].1)
    };
    let m = small.sew_line.len();
    let edge_normal = |line: &[DVec2], j: usize| outward((line[(j + 1) % line.len()] - line[j]).normalize_or_zero());
    let vertex_normal = |line: &[DVec2], i: usize| {
        let k = line.len();
        outward((line[(i + 1) % k] - line[(i + k - 1) % k]).normalize_or_zero())
    };
    for (i, d, j) in wrong_side(&small.sew_line, &large.sew_line, true) {
        let push = d + opts.margin_mm;
        if sign > 0.0 {
            for k in [j, (j + 1) % n] {
                if !on_seam(k) {
                    keep_largest(moves, k, edge_normal(&large.sew_line, j) * push);
                }
            }
        } else if m == n && !on_seam(i) {
            keep_largest(moves, i, -vertex_normal(&small.sew_line, i) * push);
        }
    }
    // and a point of the larger size's line inside the smaller one's (the lines cross between
    // the smaller size's points): that point out (growing) or the smaller line there in
    for (i, d, j) in wrong_side(&large.sew_line, &small.sew_line, false) {
        let push = d + opts.margin_mm;
        if sign > 0.0 {
            if !on_seam(i) {
                keep_largest(moves, i, vertex_normal(&large.sew_line, i) * push);
            }
        } else if m == n {
            for k in [j, (j + 1) % m] {
                if !on_seam(k) {
                    keep_largest(moves, k, -edge_normal(&small.sew_line, j) * push);
                }
            }
        }
    }
}

/// The points of `pts` on the wrong side of the closed polygon `poly`
/// (outside it when `outside`, else inside), off its line: `(index,
/// distance to the line, index of the nearest edge)`.
fn wrong_side<'a>(
    pts: &'a [DVec2],
    poly: &'a [DVec2],
    outside: bool,
) -> impl Iterator<Item = (usize, f64, usize)> + 'a {
    pts.iter().enumerate().filter(move |(_, &q)| point_in_polygon(poly, q) != outside).filter_map(|(i, &q)| {
        let (d, j) = nearest_edge(poly, q);
        (d > 0.0).then_some((i, d, j))
    })
}

/// `moves[i]` becomes `v` where `v` is the longer.
fn keep_largest(moves: &mut Moves, i: usize, v: DVec2) {
    let e = moves.entry(i).or_insert(DVec2::ZERO);
    if v.length() > e.length() {
        *e = v;
    }
}

/// Applies `slides` (mm; `sign` +1 lengthens the runs, −1 shortens them) to
/// every grade-point corner of `p` that has one, and `moves` to its other
/// points, spreading each move along the outline to the grade points on
/// either side (module docs), and re-cuts the piece.
fn apply(p: &mut PatternPiece, slides: &Slides, moves: &Moves, sign: f64, miter_limit: f64) {
    let a = anchors(p);
    let (n, k) = (p.sew_line.len(), a.len());
    if k < 3 {
        return;
    }
    let before = p.sew_line.clone();
    let mut at: Vec<(usize, DVec2)> = moves.iter().map(|(&i, &v)| (i, v)).collect();
    for (j, &(i, node)) in a.iter().enumerate() {
        let (prev_node, next_node) = (a[(j + k - 1) % k].1, a[(j + 1) % k].1);
        let c = before[i];
        let mut v = DVec2::ZERO;
        if let Some(&s) = slides.get(&(node, next_node)) {
            v += (c - before[(i + 1) % n]).normalize_or_zero() * (sign * s);
        }
        if let Some(&s) = slides.get(&(node, prev_node)) {
            v += (c - before[(i + n - 1) % n]).normalize_or_zero() * (sign * s);
        }
        if v != DVec2::ZERO {
            at.push((i, v));
        }
    }
    if at.is_empty() {
        return;
    }
    let is_anchor: Vec<bool> = (0..n).map(|i| a.iter().any(|x| x.0 == i)).collect();
    // each point takes the largest of the moves spread onto it (not their sum: neighbouring
    // points pushed out by the same noise would add up to a bulge)
    let mut delta = vec![DVec2::ZERO; n];
    let mut take = |q: usize, v: DVec2| {
        if v.length() > delta[q].length() {
            delta[q] = v;
        }
    };
    for (i, v) in at {
        take(i, v);
        // weight 1 at `i`, falling linearly in arc length to 0 at the grade point on either side
        for step in [1, n - 1] {
            let mut run = vec![i];
            let mut q = i;
            loop {
                q = (q + step) % n;
                run.push(q);
                if is_anchor[q] || q == i {
                    break;
                }
            }
            let lengths: Vec<f64> = run.windows(2).map(|w| before[w[0]].distance(before[w[1]])).collect();
            let total: f64 = lengths.iter().sum();
            if total <= 0.0 {
                continue;
            }
            let mut along = 0.0;
            for (idx, &q) in run.iter().enumerate().skip(1).take(run.len().saturating_sub(2)) {
                along += lengths[idx - 1];
                take(q, v * (1.0 - along / total));
            }
        }
    }
    let moved = |q: DVec2| before.iter().position(|b| b.distance(q) < 1e-9).map(|i| delta[i]);
    for (q, d) in p.sew_line.iter_mut().zip(&delta) {
        *q += *d;
    }
    for g in &mut p.grade_points {
        if let Some(d) = moved(g.at) {
            g.at += d;
        }
    }
    for notch in &mut p.notches {
        if let Some(d) = moved(notch.at) {
            notch.at += d;
            notch.on_cut_line += d;
        }
    }
    for line in &mut p.internal_lines {
        for q in &mut line.points {
            if let Some(d) = moved(*q) {
                *q += d;
            }
        }
    }
    for g in &mut p.grain {
        if let Some(d) = moved(*g) {
            *g += d;
        }
    }
    p.cut_line = untangle(offset_polygon(&p.sew_line, p.seam_allowance_mm, miter_limit));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::grade::{nest_steps, nests};
    use crate::pattern::piece::GradePoint;

    /// A skirt-front-like quadrilateral: hem corners at `±w_hem`, y = −300;
    /// side-waist corners at `(±w_waist, 180 + rise)`; the waist line a
    /// polyline through `(±w_waist·0.6, 170 + rise/2)`; the centre front at `(0, 168)`.
    fn piece(size: &str, w_hem: f64, w_waist: f64, rise: f64) -> PatternPiece {
        let sew_line = vec![
            DVec2::new(-w_hem, -300.0),
            DVec2::new(0.0, -300.0),
            DVec2::new(w_hem, -300.0),
            DVec2::new(w_waist, 180.0 + rise),
            DVec2::new(0.6 * w_waist, 170.0 + rise / 2.0),
            DVec2::new(0.0, 168.0),
            DVec2::new(-0.6 * w_waist, 170.0 + rise / 2.0),
            DVec2::new(-w_waist, 180.0 + rise),
        ];
        let gp = |node: u32, i: usize| GradePoint {
            node,
            label: format!("n{node}"),
            at: sew_line[i],
            kind: GradePointKind::Corner,
        };
        let grade_points = vec![gp(0, 0), gp(1, 1), gp(2, 2), gp(3, 3), gp(5, 5), gp(7, 7)];
        PatternPiece {
            name: "front".into(),
            size: size.into(),
            quantity: 1,
            cut_pair: false,
            cut_line: offset_polygon(&sew_line, 10.0, 3.0),
            sew_line,
            corners: vec![0, 2, 3, 7],
            seam_allowance_mm: 10.0,
            notches: vec![],
            grain: [DVec2::ZERO, DVec2::new(0.0, -300.0)],
            internal_lines: vec![],
            grade_points,
            stack_point: DVec2::ZERO,
        }
    }

    fn set(rise: f64) -> Vec<(String, Vec<PatternPiece>)> {
        (0..5)
            .map(|k| {
                let s = format!("s{k}");
                let x = f64::from(k) * 6.0;
                (s.clone(), vec![piece(&s, 260.0 + x, 200.0 + x, rise * f64::from(k))])
            })
            .collect()
    }

    #[test]
    fn a_nest_that_nests_is_left_exactly_as_it_is() {
        // corners rising 3 mm per 6 mm out: above the waist line's slope, every size inside the next
        let mut sizes = set(3.0);
        let before = sizes.clone();
        assert!(nest_steps(&nests(&sizes).unwrap()).iter().all(|s| s.crossings == 0 && s.outside == 0));
        let report = true_nest(&mut sizes, 2, &TrueOptions::default());
        assert_eq!(sizes, before);
        assert_eq!(report, TrueReport::default());
    }

    #[test]
    fn side_waist_corners_moving_straight_out_are_slid_up_their_seam_until_the_nest_nests() {
        // the side-waist corner moves 6 mm out, 0 up; the waist line's last part rises 10 mm
        // over 80 mm (slope 0.125) and the side seam leans 20 mm over 480 mm: each smaller
        // corner stands ≈ 0.75 mm above the next size's waist line
        let mut sizes = set(0.0);
        let steps = nest_steps(&nests(&sizes).unwrap());
        assert!(steps.iter().all(|s| s.outside > 0), "{steps:?}");
        let base = sizes[2].1.clone();
        let report = true_nest(&mut sizes, 2, &TrueOptions::default());
        let steps = nest_steps(&nests(&sizes).unwrap());
        assert!(steps.iter().all(|s| s.crossings == 0 && s.outside == 0), "{steps:?}");
        // the base size is untouched; the others moved, symmetric left and right, by a few mm
        assert_eq!(sizes[2].1, base);
        assert_eq!(report.left, 0);
        assert!(report.largest_move_mm > 0.5 && report.largest_move_mm < 3.0, "{report:?}");
        for (_, p) in &sizes {
            let (l, r) = (p[0].sew_line[7], p[0].sew_line[3]);
            assert!((l.x + r.x).abs() < 1e-9 && (l.y - r.y).abs() < 1e-9, "{} {l} {r}", p[0].size);
            // the hem does not move; the centre front waist only by the passes off the corners
            // (the waist's middle point of each smaller size stands 0.06 mm above the next
            // one's line), under 1 mm two steps from the base
            assert_eq!(p[0].sew_line[1], DVec2::new(0.0, -300.0));
            assert!(p[0].sew_line[5].distance(DVec2::new(0.0, 168.0)) < 1.0, "{}", p[0].sew_line[5]);
            assert_eq!(p[0].grade_points[3].at, r);
        }
        // the corners moved along their side seam: up and inwards for larger sizes, down for smaller
        assert!(sizes[4].1[0].sew_line[3].y > 180.5 && sizes[0].1[0].sew_line[3].y < 179.5);
    }

    #[test]
    fn a_grade_that_would_move_further_than_allowed_is_left_as_cut_as_a_whole() {
        // the same set; truing moves its outer sizes ≈ 1.5 mm, its inner ones ≈ 0.8 mm
        let mut sizes = set(0.0);
        let before = sizes.clone();
        let opts = TrueOptions { max_move_mm: 1.0, ..TrueOptions::default() };
        let report = true_nest(&mut sizes, 2, &opts);
        assert_eq!(sizes, before, "no size trued when one cannot be");
        assert!(report.moved.is_empty() && report.largest_move_mm == 0.0, "{report:?}");
        assert_eq!(report.as_cut, vec!["s4".to_string(), "s0".to_string()]);
        // switched off: nothing
        let off = TrueOptions { enabled: false, ..TrueOptions::default() };
        assert_eq!(true_nest(&mut sizes, 2, &off), TrueReport::default());
        assert_eq!(sizes, before);
    }
}
