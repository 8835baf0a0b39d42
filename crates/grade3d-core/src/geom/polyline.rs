//! Polylines in 3D: arc length, tangents, sub-arcs, closest points,
//! crossings of two curves, and the tape-measure length of a planar loop.
//!
//! Feature curves on a body are polylines on its surface (seed 000 §3.1:
//! "each semantic feature curve consists of a sorted set of line segments
//! lying on the mesh surface"). Arc length `s` is the parameter throughout;
//! for a closed polyline `s` wraps modulo the length.
//!
//! Tangents are taken as the chord over a window of half-width `h`
//! (`t(s) = (c(s+h) − c(s−h)) / |…|`), which makes them independent of how
//! finely the surface under the curve happens to be meshed.

use glam::{DVec2, DVec3};

use super::plane::Plane;

/// An open or closed polyline. A closed one does not repeat its first point.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Polyline {
    /// The vertices in order.
    pub points: Vec<DVec3>,
    /// Whether the last point connects back to the first.
    pub closed: bool,
}

/// The closest point of a polyline to a query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestOnPolyline {
    /// Arc-length parameter of the closest point.
    pub s: f64,
    /// The closest point.
    pub point: DVec3,
    /// Its distance to the query.
    pub distance: f64,
}

/// Closest approach of two polylines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Arc length on the first polyline.
    pub s_a: f64,
    /// Arc length on the second polyline.
    pub s_b: f64,
    /// Midpoint of the two closest points.
    pub point: DVec3,
    /// Distance between the two closest points (0 where they truly cross).
    pub gap: f64,
}

/// Closest points of segments `[p0,p1]` and `[q0,q1]`: parameters in [0,1].
pub fn segment_segment(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (f64, f64) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.dot(d1);
    let e = d2.dot(d2);
    let f = d2.dot(r);
    let eps = 1e-300;
    if a <= eps && e <= eps {
        return (0.0, 0.0);
    }
    if a <= eps {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(r);
    if e <= eps {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > 1e-14 * a * e { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Closest point on segment `[a,b]` to `p`: parameter in [0,1].
pub fn point_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    if l2 <= 0.0 {
        0.0
    } else {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    }
}

impl Polyline {
    /// A polyline from points.
    pub fn new(points: Vec<DVec3>, closed: bool) -> Self {
        Self { points, closed }
    }

    /// Number of segments.
    pub fn segment_count(&self) -> usize {
        match self.points.len() {
            0 | 1 => 0,
            n if self.closed => n,
            n => n - 1,
        }
    }

    /// Endpoints of segment `i`.
    #[inline]
    pub fn segment(&self, i: usize) -> (DVec3, DVec3) {
        let n = self.points.len();
        (self.points[i], self.points[(i + 1) % n])
    }

    /// Cumulative arc length at each vertex (`len = points.len()`, plus the
    /// closing length as a last entry for a closed polyline).
    pub fn cumulative(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.points.len() + 1);
        let mut acc = 0.0;
        out.push(0.0);
        for i in 0..self.segment_count() {
            let (a, b) = self.segment(i);
            acc += a.distance(b);
            out.push(acc);
        }
        out
    }

    /// Total length.
    pub fn length(&self) -> f64 {
        (0..self.segment_count())
            .map(|i| {
                let (a, b) = self.segment(i);
                a.distance(b)
            })
            .sum()
    }

    fn wrap(&self, s: f64, total: f64) -> f64 {
        if self.closed && total > 0.0 {
            s.rem_euclid(total)
        } else {
            s.clamp(0.0, total)
        }
    }

    /// The point at arc length `s` (wrapped for closed, clamped for open).
    pub fn point_at(&self, s: f64) -> DVec3 {
        let cum = self.cumulative();
        self.point_at_with(&cum, s)
    }

    /// [`Polyline::point_at`] with the cumulative lengths given
    /// ([`Polyline::cumulative`]: many points of one curve).
    pub(crate) fn point_at_with(&self, cum: &[f64], s: f64) -> DVec3 {
        let total = *cum.last().unwrap_or(&0.0);
        if self.points.is_empty() {
            return DVec3::ZERO;
        }
        if self.segment_count() == 0 {
            return self.points[0];
        }
        let s = self.wrap(s, total);
        let i = match cum.binary_search_by(|x| x.total_cmp(&s)) {
            Ok(i) => i.min(self.segment_count() - 1),
            Err(i) => (i.max(1) - 1).min(self.segment_count() - 1),
        };
        let (a, b) = self.segment(i);
        let l = cum[i + 1] - cum[i];
        if l <= 0.0 {
            a
        } else {
            a.lerp(b, ((s - cum[i]) / l).clamp(0.0, 1.0))
        }
    }

    /// Unit tangent at `s`: the chord from `s − h` to `s + h` (clamped to
    /// the ends of an open polyline). `None` if that chord has zero length.
    pub fn tangent_at(&self, s: f64, h: f64) -> Option<DVec3> {
        let cum = self.cumulative();
        let total = *cum.last()?;
        let (s0, s1) = if self.closed {
            (s - h, s + h)
        } else {
            let a = (s - h).max(0.0);
            let b = (s + h).min(total);
            (a, b)
        };
        (self.point_at_with(&cum, s1) - self.point_at_with(&cum, s0)).try_normalize()
    }

    /// Closest point to `p`.
    pub fn closest(&self, p: DVec3) -> Option<ClosestOnPolyline> {
        let cum = self.cumulative();
        let mut best: Option<ClosestOnPolyline> = None;
        if self.segment_count() == 0 {
            return self.points.first().map(|&q| ClosestOnPolyline { s: 0.0, point: q, distance: q.distance(p) });
        }
        for i in 0..self.segment_count() {
            let (a, b) = self.segment(i);
            let t = point_segment(p, a, b);
            let q = a.lerp(b, t);
            let d = q.distance(p);
            if best.is_none_or(|c| d < c.distance) {
                best = Some(ClosestOnPolyline { s: cum[i] + t * (cum[i + 1] - cum[i]), point: q, distance: d });
            }
        }
        best
    }

    /// The polyline traversed backwards.
    pub fn reversed(&self) -> Self {
        let mut pts = self.points.clone();
        pts.reverse();
        Self { points: pts, closed: self.closed }
    }

    /// The open sub-arc from `s0` to `s1`, walking forward. On a closed
    /// polyline it wraps past the start when `s1 < s0`; on an open one the
    /// parameters are clamped and swapped if needed (the result then runs
    /// from the smaller to the larger).
    pub fn arc(&self, s0: f64, s1: f64) -> Self {
        let cum = self.cumulative();
        let total = *cum.last().unwrap_or(&0.0);
        let mut pts = Vec::new();
        if self.points.is_empty() {
            return Self::new(pts, false);
        }
        let (a, b) = if self.closed {
            let a = self.wrap(s0, total);
            let mut b = self.wrap(s1, total);
            if b < a {
                b += total;
            }
            (a, b)
        } else {
            let a = s0.clamp(0.0, total);
            let b = s1.clamp(0.0, total);
            (a.min(b), a.max(b))
        };
        pts.push(self.point_at_with(&cum, a));
        let n = self.points.len();
        let laps = if self.closed { 2 } else { 1 };
        for lap in 0..laps {
            for (i, &c) in cum.iter().enumerate().take(n) {
                let s = c + lap as f64 * total;
                if s > a && s < b {
                    pts.push(self.points[i]);
                }
            }
        }
        pts.push(self.point_at_with(&cum, b));
        Self::new(pts, false)
    }

    /// Signed area of the polyline (as a closed loop) about `axis`:
    /// `½ Σ (p_i × p_{i+1}) · axis`. Positive when it turns anticlockwise
    /// seen from the tip of `axis`.
    pub fn signed_area(&self, axis: DVec3) -> f64 {
        let n = self.points.len();
        if n < 3 {
            return 0.0;
        }
        let c = self.points.iter().copied().sum::<DVec3>() / n as f64;
        let mut a = DVec3::ZERO;
        for i in 0..n {
            a += (self.points[i] - c).cross(self.points[(i + 1) % n] - c);
        }
        0.5 * a.dot(axis)
    }

    /// The part of this loop (taken as closed) on the non-negative side of
    /// `plane`, by Sutherland–Hodgman clipping against one plane: points
    /// behind it are dropped, and the loop's crossings of the plane are
    /// joined along it (a tape passed between two thighs pressed together
    /// runs along the plane where they meet). `None` if fewer than three
    /// points are left; the loop itself (closed) where nothing is behind.
    pub fn clipped(&self, plane: &Plane) -> Option<Polyline> {
        let n = self.points.len();
        let mut out = Vec::with_capacity(n + 2);
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            let (da, db) = (plane.signed_distance(a), plane.signed_distance(b));
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                out.push(a + (b - a) * (da / (da - db)));
            }
        }
        (out.len() >= 3).then(|| Polyline::new(out, true))
    }

    /// Centroid of the vertices.
    pub fn centroid(&self) -> DVec3 {
        if self.points.is_empty() {
            return DVec3::ZERO;
        }
        self.points.iter().copied().sum::<DVec3>() / self.points.len() as f64
    }

    /// Centroid of the curve as a wire of uniform density,
    /// `Σ ½(a_i + b_i)·|b_i − a_i| / Σ |b_i − a_i|` over its segments (the
    /// closing one too, where closed): unlike [`Polyline::centroid`] it does
    /// not depend on how densely the curve is sampled, so a plane section
    /// whose crossed mesh edges change from one body to the next keeps a
    /// centroid that moves continuously with the body. The vertex centroid
    /// where the curve has no length.
    pub fn length_centroid(&self) -> DVec3 {
        let (mut sum, mut total) = (DVec3::ZERO, 0.0);
        for i in 0..self.segment_count() {
            let (a, b) = self.segment(i);
            let l = a.distance(b);
            sum += 0.5 * (a + b) * l;
            total += l;
        }
        if total > 0.0 {
            sum / total
        } else {
            self.centroid()
        }
    }

    /// Points projected into the 2D coordinates of `plane`'s basis.
    pub fn to_plane_2d(&self, plane: &Plane) -> Vec<DVec2> {
        let (u, v) = plane.basis();
        self.points.iter().map(|&p| DVec2::new(p.dot(u), p.dot(v))).collect()
    }

    /// Whether `p`, projected onto `plane`, lies inside this loop projected
    /// onto the same plane (even–odd rule).
    pub fn contains_projected(&self, plane: &Plane, p: DVec3) -> bool {
        let (u, v) = plane.basis();
        let q = DVec2::new(p.dot(u), p.dot(v));
        point_in_polygon(&self.to_plane_2d(plane), q)
    }

    /// Closest approach between this polyline and `other`. Among all pairs
    /// of segments whose gap is within `gap_tolerance` of the smallest gap,
    /// picks the pair nearest to `near` (so that, of several true crossings,
    /// the one at a landmark wins).
    pub fn crossing(&self, other: &Polyline, near: DVec3, gap_tolerance: f64) -> Option<Crossing> {
        let ca = self.cumulative();
        let cb = other.cumulative();
        // Segment bounding boxes of `other`, to skip pairs that cannot be
        // within the tolerance of the smallest gap found so far.
        let boxes: Vec<(DVec3, DVec3)> = (0..other.segment_count())
            .map(|j| {
                let (q0, q1) = other.segment(j);
                (q0.min(q1), q0.max(q1))
            })
            .collect();
        // …and of blocks of consecutive segments: a block whose box is out of reach holds no
        // segment in reach (its box holds theirs), so skipping it changes nothing
        let blocks: Vec<(DVec3, DVec3)> = boxes
            .chunks(CROSSING_BLOCK)
            .map(|c| c.iter().fold(c[0], |(lo, hi), (blo, bhi)| (lo.min(*blo), hi.max(*bhi))))
            .collect();
        let sep = |lo: DVec3, hi: DVec3, (blo, bhi): (DVec3, DVec3)| (blo - hi).max(lo - bhi).max(DVec3::ZERO).length();
        let mut min_gap = f64::INFINITY;
        let mut cands: Vec<Crossing> = Vec::new();
        for i in 0..self.segment_count() {
            let (p0, p1) = self.segment(i);
            let (lo, hi) = (p0.min(p1), p0.max(p1));
            for (k, &block) in blocks.iter().enumerate() {
                if sep(lo, hi, block) > min_gap + gap_tolerance {
                    continue;
                }
                for j in k * CROSSING_BLOCK..((k + 1) * CROSSING_BLOCK).min(boxes.len()) {
                    if sep(lo, hi, boxes[j]) > min_gap + gap_tolerance {
                        continue;
                    }
                    let (q0, q1) = other.segment(j);
                    let (s, t) = segment_segment(p0, p1, q0, q1);
                    let a = p0.lerp(p1, s);
                    let b = q0.lerp(q1, t);
                    let gap = a.distance(b);
                    if gap > min_gap + gap_tolerance {
                        continue;
                    }
                    min_gap = min_gap.min(gap);
                    cands.push(Crossing {
                        s_a: ca[i] + s * (ca[i + 1] - ca[i]),
                        s_b: cb[j] + t * (cb[j + 1] - cb[j]),
                        point: 0.5 * (a + b),
                        gap,
                    });
                }
            }
        }
        cands
            .into_iter()
            .filter(|c| c.gap <= min_gap + gap_tolerance)
            .min_by(|x, y| x.point.distance(near).total_cmp(&y.point.distance(near)))
    }
}

/// Segments of the other curve per block in [`Polyline::crossing`] (count).
const CROSSING_BLOCK: usize = 16;

/// Whether segments `pq` and `rs` cross at a point interior to both (strict
/// orientation signs: touching or collinear overlap is not a crossing).
pub fn segments_cross(p: DVec2, q: DVec2, r: DVec2, s: DVec2) -> bool {
    let o = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    o(r, s, p) * o(r, s, q) < 0.0 && o(p, q, r) * o(p, q, s) < 0.0
}

/// Whether segment `pq` properly crosses an edge of the closed polygon `poly`
/// ([`segments_cross`]).
pub fn segment_crosses_polygon(p: DVec2, q: DVec2, poly: &[DVec2]) -> bool {
    let n = poly.len();
    (0..n).any(|k| segments_cross(p, q, poly[k], poly[(k + 1) % n]))
}

/// Distance from `p` to the outline of the closed polygon `poly` (infinite
/// for an empty one).
pub fn distance_to_polygon(poly: &[DVec2], p: DVec2) -> f64 {
    nearest_edge(poly, p).0
}

/// Distance from `p` to the outline of the closed polygon `poly` and the
/// index `j` of the edge `(j, j + 1)` nearest it (`(∞, 0)` for an empty one).
pub fn nearest_edge(poly: &[DVec2], p: DVec2) -> (f64, usize) {
    (0..poly.len())
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            (p.distance(a.lerp(b, point_segment(p.extend(0.0), a.extend(0.0), b.extend(0.0)))), i)
        })
        .fold((f64::INFINITY, 0), |x, y| if y.0 < x.0 { y } else { x })
}

/// Even–odd point-in-polygon test in 2D.
pub fn point_in_polygon(poly: &[DVec2], q: DVec2) -> bool {
    let n = poly.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > q.y) != (b.y > q.y) {
            let x = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if q.x < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Convex hull of 2D points (Andrew's monotone chain), anticlockwise.
pub fn convex_hull_2d(points: &[DVec2]) -> Vec<DVec2> {
    let mut pts: Vec<DVec2> = points.iter().copied().filter(|p| p.is_finite()).collect();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut lower: Vec<DVec2> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<DVec2> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Perimeter of a closed 2D polygon.
pub fn perimeter_2d(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    if n < 2 {
        return 0.0;
    }
    (0..n).map(|i| poly[i].distance(poly[(i + 1) % n])).sum()
}

/// Tape-measure length of loops lying in `plane`: the perimeter of the
/// convex hull of their projections. This is how a tape laid around the
/// body at that level measures a girth (it bridges concavities such as the
/// hollow between the breasts), ISO 8559-1 §5.3 practice.
pub fn tape_length(loops: &[&Polyline], plane: &Plane) -> f64 {
    let pts: Vec<DVec2> = loops.iter().flat_map(|l| l.to_plane_2d(plane)).collect();
    perimeter_2d(&convex_hull_2d(&pts))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn circle(r: f64, n: usize) -> Polyline {
        Polyline::new(
            (0..n).map(|i| 2.0 * PI * i as f64 / n as f64).map(|t| DVec3::new(r * t.cos(), 0.0, r * t.sin())).collect(),
            true,
        )
    }

    #[test]
    fn clipping_a_square_at_its_middle_keeps_half_and_closes_it_on_the_plane() {
        let sq = Polyline::new(
            vec![
                DVec3::new(-1.0, 0.0, -1.0),
                DVec3::new(1.0, 0.0, -1.0),
                DVec3::new(1.0, 0.0, 1.0),
                DVec3::new(-1.0, 0.0, 1.0),
            ],
            true,
        );
        let right = Plane::from_point_normal(DVec3::ZERO, DVec3::X).unwrap();
        let half = sq.clipped(&right).unwrap();
        assert!(half.points.iter().all(|p| p.x >= 0.0));
        // 2 + 2 + 2 (the square's right half) + 2 along the plane
        assert!((half.length() - 8.0 / 2.0 - 2.0).abs() < 1e-12, "{}", half.length());
        // nothing behind: unchanged; everything behind: nothing
        assert_eq!(
            sq.clipped(&Plane::from_point_normal(DVec3::X * -2.0, DVec3::X).unwrap()).unwrap().points,
            sq.points
        );
        assert!(sq.clipped(&Plane::from_point_normal(DVec3::X * 2.0, DVec3::X).unwrap()).is_none());
    }

    #[test]
    fn circle_length_and_tape() {
        let c = circle(1.0, 1000);
        let exact = 2.0 * 1000.0 * (PI / 1000.0).sin();
        assert!((c.length() - exact).abs() < 1e-12);
        let plane = Plane::from_point_normal(DVec3::ZERO, DVec3::Y).unwrap();
        assert!((tape_length(&[&c], &plane) - exact).abs() < 1e-9);
    }

    #[test]
    fn crossing_by_blocks_matches_every_pair() {
        // two wiggly closed curves around the same axis (a girth and a path that cross it)
        let ring = Polyline::new(
            (0..300)
                .map(|i| {
                    let a = i as f64 / 300.0 * 2.0 * PI;
                    DVec3::new(a.cos(), 0.05 * (7.0 * a).sin(), a.sin())
                })
                .collect(),
            true,
        );
        let path = Polyline::new(
            (0..=250)
                .map(|i| {
                    let t = i as f64 / 250.0 * 2.0 - 1.0;
                    DVec3::new(0.3 * (3.0 * t).sin(), t, 1.0 + 0.02 * (11.0 * t).cos())
                })
                .collect(),
            false,
        );
        for near in [DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.5, -1.0, 0.5), DVec3::new(-2.0, 3.0, 0.0)] {
            for tol in [0.0, 1e-3, 0.05] {
                let fast = ring.crossing(&path, near, tol).expect("crossing");
                // every pair of segments, the pairs within tol of the least gap, the one nearest `near`
                let (ca, cb) = (ring.cumulative(), path.cumulative());
                let mut all = Vec::new();
                for i in 0..ring.segment_count() {
                    for j in 0..path.segment_count() {
                        let ((p0, p1), (q0, q1)) = (ring.segment(i), path.segment(j));
                        let (s, t) = segment_segment(p0, p1, q0, q1);
                        let (a, b) = (p0.lerp(p1, s), q0.lerp(q1, t));
                        all.push(Crossing {
                            s_a: ca[i] + s * (ca[i + 1] - ca[i]),
                            s_b: cb[j] + t * (cb[j + 1] - cb[j]),
                            point: 0.5 * (a + b),
                            gap: a.distance(b),
                        });
                    }
                }
                let min = all.iter().map(|c| c.gap).fold(f64::INFINITY, f64::min);
                let brute = all
                    .into_iter()
                    .filter(|c| c.gap <= min + tol)
                    .min_by(|x, y| x.point.distance(near).total_cmp(&y.point.distance(near)))
                    .expect("pairs");
                assert_eq!(fast, brute, "near {near}, tolerance {tol}");
            }
        }
    }

    #[test]
    fn length_centroid_does_not_follow_the_sampling() {
        // a 2 × 2 square about the origin, its front side (y = 1) sampled by 40 points
        let mut pts = vec![DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, -1.0, 0.0)];
        pts.extend((0..=40).map(|i| DVec3::new(1.0 - 2.0 * i as f64 / 40.0, 1.0, 0.0)));
        let square = Polyline::new(pts, true);
        assert!(square.centroid().y > 0.8, "the vertex centroid follows the dense side");
        assert!(square.length_centroid().length() < 1e-12, "{}", square.length_centroid());
        // an open L: legs of length 2 and 1 from the corner
        let l = Polyline::new(vec![DVec3::new(2.0, 0.0, 0.0), DVec3::ZERO, DVec3::new(0.0, 1.0, 0.0)], false);
        assert!(l.length_centroid().distance(DVec3::new(2.0 / 3.0, 1.0 / 6.0, 0.0)) < 1e-12);
        // no length: the vertex centroid
        let dot = Polyline::new(vec![DVec3::ONE, DVec3::ONE], false);
        assert_eq!(dot.length_centroid(), DVec3::ONE);
    }

    #[test]
    fn tape_bridges_concavity() {
        // a square with a notch: the tape is the square's perimeter
        let pts = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 2.0], [0.0, 4.0]];
        let l = Polyline::new(pts.iter().map(|p| DVec3::new(p[0], 0.0, p[1])).collect(), true);
        let plane = Plane::from_point_normal(DVec3::ZERO, DVec3::Y).unwrap();
        assert!((tape_length(&[&l], &plane) - 16.0).abs() < 1e-12);
    }

    #[test]
    fn arcs_wrap_on_closed_and_clamp_on_open() {
        let sq = Polyline::new(vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y], true);
        assert_eq!(sq.length(), 4.0);
        let a = sq.arc(3.5, 0.5);
        assert!((a.length() - 1.0).abs() < 1e-12);
        assert_eq!(a.points.first().copied(), Some(DVec3::new(0.0, 0.5, 0.0)));
        let open = Polyline::new(vec![DVec3::ZERO, DVec3::X * 2.0], false);
        assert!((open.arc(1.5, 0.5).length() - 1.0).abs() < 1e-12);
        assert_eq!(open.point_at(9.0), DVec3::X * 2.0);
    }

    #[test]
    fn tangent_and_closest() {
        let c = circle(2.0, 4000);
        let t = c.tangent_at(0.0, 0.01).unwrap();
        assert!((t - DVec3::Z).length() < 1e-6);
        let q = c.closest(DVec3::new(5.0, 1.0, 0.0)).unwrap();
        assert!((q.point - DVec3::new(2.0, 0.0, 0.0)).length() < 1e-9);
        assert!((q.distance - 10f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn crossing_of_two_lines_picks_nearest() {
        let a = Polyline::new(vec![DVec3::new(-1.0, 0.0, 0.0), DVec3::new(3.0, 0.0, 0.0)], false);
        let b = Polyline::new(
            vec![
                DVec3::new(0.0, -1.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(2.0, 1.0, 0.0),
                DVec3::new(2.0, -1.0, 0.0),
            ],
            false,
        );
        let c = a.crossing(&b, DVec3::new(2.1, 0.0, 0.0), 1e-12).unwrap();
        assert!((c.point - DVec3::new(2.0, 0.0, 0.0)).length() < 1e-12);
        assert!(c.gap < 1e-12);
        assert!((c.s_a - 3.0).abs() < 1e-12 && (c.s_b - 5.0).abs() < 1e-12);
    }

    #[test]
    fn signed_area_orientation() {
        let c = circle(1.0, 64); // x = cos, z = sin: seen from +Y this is clockwise
        assert!(c.signed_area(DVec3::Y) < 0.0);
        assert!(c.reversed().signed_area(DVec3::Y) > 0.0);
    }
}
