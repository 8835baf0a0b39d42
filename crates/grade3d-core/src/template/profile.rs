//! Edge profiles of a garment feature template: the attached points of an
//! edge, their chord-length parameters, and the cubic spline through them
//! (seed 000: Wang, Wang & Yuen 2002, §4.1, §4.2 and §5.2).
//!
//! # Contract
//!
//! **Method.** A profile is the list of attached points `Q_0 … Q_{n−1}` of a
//! template edge — `Q_0` on the edge's start node, `Q_{n−1}` on its end node —
//! and a parametric curve `c(u)`, `u ∈ [0, 1]`, through all of them with
//! `c(0) = Q_0` and `c(1) = Q_{n−1}` (seed 000, §4.1). Each attached point
//! gets the chord-length parameter of seed 000, Eq. (3):
//!
//! ```text
//! u_0 = 0,   u_i = u_{i−1} + |Q_i − Q_{i−1}| / Σ_{j=1}^{n−1} |Q_j − Q_{j−1}|     (Eq. 3)
//! ```
//!
//! evaluated as `u_i = L_i / L_{n−1}` with `L_i = Σ_{j≤i} |Q_j − Q_{j−1}|`,
//! which equals the recursion up to rounding and gives `u_{n−1} = 1` exactly.
//!
//! **Curve.** `c` is the *not-a-knot* cubic spline through `(u_i, Q_i)`, one
//! spline per coordinate over the same knots, stored in Hermite form (the
//! value `Q_i` and the slope `c'(u_i)` at every knot). On piece
//! `[u_i, u_{i+1}]`, with `h_i = u_{i+1} − u_i` and `t = (u − u_i) / h_i`,
//!
//! ```text
//! c(u) = H00(t) Q_i + H10(t) h_i c'(u_i) + H01(t) Q_{i+1} + H11(t) h_i c'(u_{i+1})
//! H00 = 2t³ − 3t² + 1,  H10 = t³ − 2t² + t,  H01 = −2t³ + 3t²,  H11 = t³ − t²
//! ```
//!
//! so `c(u_i) = Q_i` holds bit for bit and `c` is C1 by construction. The
//! slopes `s_i = c'(u_i)` solve, with `δ_i = (Q_{i+1} − Q_i) / h_i`,
//!
//! ```text
//! h_i s_{i−1} + 2(h_{i−1} + h_i) s_i + h_{i−1} s_{i+1} = 3(h_i δ_{i−1} + h_{i−1} δ_i)     (C2 at u_i, 0 < i < n−1)
//! h_1 s_0 + (h_0 + h_1) s_1 = ((3h_0 + 2h_1) h_1 δ_0 + h_0² δ_1) / (h_0 + h_1)            (c''' continuous at u_1)
//! ```
//!
//! and the mirror of the last row at `u_{n−2}`. Eliminating the two end rows
//! leaves a strictly diagonally dominant tridiagonal system (solved without
//! pivoting). Hence: `n = 2` gives the straight segment, `n = 3` the parabola
//! through the three points, `n ≥ 4` a C2 spline that reproduces any cubic.
//! A straight profile (collinear points, any spacing) is reproduced exactly,
//! since chord-length parameters are then affine in arc length.
//!
//! **Relocation (seed 000, Eq. (5)).** When the edge's nodes move from
//! `v_l = Q_0`, `v_m = Q_{n−1}` to `v_l*`, `v_m*`, every attached point moves by
//!
//! ```text
//! p*(Q_i) = s·{p(Q_i) − p(v_l) − u_i [p(v_m) − p(v_l)]} + p(v_l*) + u_i [p(v_m*) − p(v_l*)],
//! s = |v_l* v_m*| / |v_l v_m|                                                          (Eq. 5)
//! ```
//!
//! with `u_i` from Eq. (3) of the *old* points. The offset of `Q_i` from its
//! chord point keeps its direction and is scaled by `s`; the formula is not
//! rotation-covariant. The new curve is the spline of the moved points
//! ([`Profile::new`]); its end points are set to `v_l*`, `v_m*` exactly (the
//! formula's own values there, without the rounding of `v_l* + 1·(v_m* − v_l*)`).
//!
//! **Split (seed 000, §5.2).** Subdivision inserts the vertex `c(1/2)` on a
//! profiled edge and divides `c` into `c_f(t) = c(t/2)` and
//! `c_b(t) = c(1/2 + t/2)`. [`Profile::split_half`] keeps the spline pieces:
//! knots map by `t = 2u` (front) or `t = 2u − 1` (back), slopes halve, and the
//! piece containing `u = 1/2` is cut there with the value `c(1/2)` and slope
//! `c'(1/2)` as the new knot's data. Scaling by two is exact in binary
//! floating point, so the halves reproduce the parent to rounding (the
//! untouched pieces bit for bit; measured ≤ 1e-14 of the chord length on
//! random wild profiles, ≈1e-16 on smooth ones), also after repeated
//! splitting, and the shared end point is the same `c(1/2)` bit for bit.
//! The halves' parameters are these mapped knots — the curve's parameters of
//! their attached points — and in general differ from Eq. (3) of the halves'
//! own points; [`chord_length_params`] computes Eq. (3) for any point list.
//!
//! **Lengths.** [`Profile::chord_length`] is the polyline length of the
//! attached points (the denominator of Eq. (3)); [`Profile::length`] is the
//! arc length of `c` by adaptive Gauss–Legendre quadrature
//! ([`LENGTH_TOLERANCE`]). [`Profile::closest_point`] and
//! [`Profile::max_deviation_from`] measure distances from `c` (sampling plus
//! golden-section refinement, [`ClosestOptions`]).
//!
//! **Preconditions.** At least two points, all coordinates finite, no two
//! consecutive points coincident (every chord must advance the Eq. (3)
//! parameter). Relocation needs distinct old end nodes and finite new ones.
//! No tolerance is applied: a nearly closed profile (tiny `|v_l v_m|`) yields
//! the large `s` that Eq. (5) prescribes.
//!
//! **Failure modes.** Typed [`ProfileError`]s naming the offending point
//! index; no panics on bad input.
//!
//! **Serde form.** `{"points": [[x,y,z],…], "params": [u_i…], "tangents":
//! [[…],…]}`; serialisation always writes all three, so split halves round
//! trip. On input `params` and `tangents` may both be omitted: the profile is
//! then rebuilt from the points (Eq. (3) and the not-a-knot spline). If given,
//! they are validated: `params` start at 0, end at 1 and strictly increase;
//! everything is finite; all lists have one entry per point.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Initial Gauss–Legendre subintervals per spline piece in [`Profile::length`].
pub const LENGTH_SUBINTERVALS_PER_PIECE: usize = 4;

/// Target error of [`Profile::length`], relative to [`Profile::chord_length`].
///
/// A subinterval is accepted when 5-point Gauss–Legendre on it and on its two
/// halves agree within its share (proportional to its width in `u`) of this
/// budget. The speed `|c'(u)|` is the square root of a quartic and smooth
/// except where `c'` nearly vanishes (a near-cusp), which the bisection isolates.
pub const LENGTH_TOLERANCE: f64 = 1e-12;

/// Bisection depth limit of [`Profile::length`] below each initial subinterval
/// (intervals down to `2⁻⁴⁰` of it); the last estimate is accepted there.
pub const LENGTH_MAX_DEPTH: u32 = 40;

/// 5-point Gauss–Legendre nodes on `[−1, 1]`: `0`, `±(1/3)√(5 − 2√(10/7))`,
/// `±(1/3)√(5 + 2√(10/7))`.
const GAUSS_NODES: [f64; 5] =
    [-0.906_179_845_938_664, -0.538_469_310_105_683_1, 0.0, 0.538_469_310_105_683_1, 0.906_179_845_938_664];

/// 5-point Gauss–Legendre weights: `(322 − 13√70)/900`, `(322 + 13√70)/900`, `128/225`.
const GAUSS_WEIGHTS: [f64; 5] = [
    0.236_926_885_056_189_08,
    0.478_628_670_499_366_47,
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_47,
    0.236_926_885_056_189_08,
];

/// The parameter at which subdivision splits a profile (seed 000, §5.2: `c(1/2)`).
pub const SPLIT_PARAM: f64 = 0.5;

/// Errors from building, relocating or loading a [`Profile`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProfileError {
    /// Fewer than two attached points.
    #[error("a profile needs at least 2 attached points, got {count}")]
    TooFewPoints {
        /// Number of points given.
        count: usize,
    },
    /// An attached point has a NaN or infinite coordinate.
    #[error("attached point {index} has a non-finite coordinate")]
    NonFinitePoint {
        /// Index of the point.
        index: usize,
    },
    /// Points `index − 1` and `index` coincide, or are so close that the
    /// Eq. (3) parameter does not advance between them.
    #[error("attached points {} and {index} coincide (zero chord; Eq. (3) parameter does not advance)", .index - 1)]
    ZeroChord {
        /// Index of the second point of the pair.
        index: usize,
    },
    /// The chord ending at point `index`, or the sum of the chords up to it,
    /// overflows `f64` (`|Q_i − Q_{i−1}|²` does beyond ≈1.3e154).
    #[error("chord lengths overflow at attached point {index}")]
    ChordOverflow {
        /// Index of the point where the cumulative length becomes infinite.
        index: usize,
    },
    /// Relocation: the old end nodes `Q_0` and `Q_{end_index}` coincide, so
    /// the scale `s` of Eq. (5) is undefined.
    #[error("attached points 0 and {end_index} coincide: the edge's old chord has zero length, Eq. (5) is undefined")]
    ZeroNodeChord {
        /// Index of the last attached point.
        end_index: usize,
    },
    /// Relocation: the new node landing on attached point `index` (0 or the
    /// last) has a non-finite coordinate.
    #[error("the new node for attached point {index} has a non-finite coordinate")]
    NonFiniteNode {
        /// 0 for the start node, the last index for the end node.
        index: usize,
    },
    /// Stored form: a list has the wrong number of entries.
    #[error("stored profile: `{field}` has {found} entries, expected {expected} (one per point)")]
    StoredLength {
        /// `"params"` or `"tangents"`.
        field: &'static str,
        /// Number of points.
        expected: usize,
        /// Number of entries found.
        found: usize,
    },
    /// Stored form: exactly one of `params` and `tangents` was given.
    #[error("stored profile: give both `params` and `tangents`, or neither")]
    StoredIncomplete,
    /// Stored form: parameter `index` is non-finite, out of order, or the
    /// first is not 0 or the last not 1.
    #[error("stored profile: parameter {index} must be finite, 0 first, 1 last, strictly increasing")]
    StoredParam {
        /// Index of the parameter.
        index: usize,
    },
    /// Stored form: tangent `index` has a non-finite coordinate.
    #[error("stored profile: tangent {index} has a non-finite coordinate")]
    NonFiniteTangent {
        /// Index of the tangent.
        index: usize,
    },
}

/// Chord-length parameters of a point list, seed 000 Eq. (3).
///
/// `u_i = L_i / L_{n−1}`, `L_i = Σ_{j=1}^{i} |Q_j − Q_{j−1}|`; `u_0 = 0`,
/// `u_{n−1} = 1` exactly, strictly increasing.
///
/// # Errors
/// [`ProfileError::TooFewPoints`], [`ProfileError::NonFinitePoint`],
/// [`ProfileError::ZeroChord`], [`ProfileError::ChordOverflow`].
pub fn chord_length_params(points: &[DVec3]) -> Result<Vec<f64>, ProfileError> {
    if points.len() < 2 {
        return Err(ProfileError::TooFewPoints { count: points.len() });
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(ProfileError::NonFinitePoint { index });
    }
    let mut cumulative = Vec::with_capacity(points.len());
    let mut acc = 0.0;
    cumulative.push(acc);
    for (i, w) in points.windows(2).enumerate() {
        let chord = w[0].distance(w[1]);
        if chord == 0.0 {
            return Err(ProfileError::ZeroChord { index: i + 1 });
        }
        acc += chord;
        if !acc.is_finite() {
            return Err(ProfileError::ChordOverflow { index: i + 1 });
        }
        cumulative.push(acc);
    }
    let total = acc;
    let params: Vec<f64> = cumulative.iter().map(|l| l / total).collect();
    if let Some(i) = params.windows(2).position(|w| w[1] <= w[0]) {
        return Err(ProfileError::ZeroChord { index: i + 1 });
    }
    Ok(params)
}

/// The closest point of a profile curve to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestOnProfile {
    /// Curve parameter of the closest point.
    pub u: f64,
    /// The closest point `c(u)`.
    pub point: DVec3,
    /// Its distance to the query.
    pub distance: f64,
}

/// Settings of the closest-point search ([`Profile::closest_point_with`]).
///
/// The curve is sampled uniformly in `u` on every piece; around every sample
/// that is a local minimum of the squared distance, golden-section search on
/// `|c(u) − p|²` over the neighbouring samples' bracket refines `u` until the
/// bracket is below `f64::EPSILON` wide or the iteration budget is spent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestOptions {
    /// Samples per spline piece (at least 1 is used). A bracket must hold a
    /// single local minimum of the distance, so a curl within one piece needs
    /// more samples.
    pub samples_per_piece: usize,
    /// Golden-section iterations per bracket. Each shrinks the bracket by
    /// `0.618`; 100 take a bracket of width 1 below `f64::EPSILON`.
    pub max_iterations: usize,
}

impl Default for ClosestOptions {
    fn default() -> Self {
        Self { samples_per_piece: 16, max_iterations: 100 }
    }
}

/// An edge profile: attached points, their curve parameters, and the cubic
/// spline `c(u)` through them (module docs for the formulas).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "StoredProfile", into = "StoredProfile")]
pub struct Profile {
    /// Attached points `Q_i`; the first is on the start node, the last on the end node.
    points: Vec<DVec3>,
    /// Curve parameters `u_i` of the points (the spline knots): Eq. (3) for a
    /// profile built from points, mapped parent knots for a split half.
    params: Vec<f64>,
    /// Slopes `c'(u_i)` at the knots (Hermite form).
    tangents: Vec<DVec3>,
}

/// The serialised form of a [`Profile`] (module docs, "Serde form").
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct StoredProfile {
    points: Vec<DVec3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    params: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tangents: Option<Vec<DVec3>>,
}

impl From<Profile> for StoredProfile {
    fn from(p: Profile) -> Self {
        Self { points: p.points, params: Some(p.params), tangents: Some(p.tangents) }
    }
}

impl TryFrom<StoredProfile> for Profile {
    type Error = ProfileError;

    fn try_from(s: StoredProfile) -> Result<Self, ProfileError> {
        match (s.params, s.tangents) {
            (None, None) => Profile::new(s.points),
            (Some(params), Some(tangents)) => Profile::from_stored(s.points, params, tangents),
            _ => Err(ProfileError::StoredIncomplete),
        }
    }
}

impl Profile {
    /// The profile through `points`: Eq. (3) parameters and the not-a-knot
    /// cubic spline through `(u_i, Q_i)`.
    ///
    /// # Errors
    /// [`ProfileError::TooFewPoints`] (fewer than 2), [`ProfileError::NonFinitePoint`],
    /// [`ProfileError::ZeroChord`] (consecutive points coincide),
    /// [`ProfileError::ChordOverflow`].
    pub fn new(points: Vec<DVec3>) -> Result<Self, ProfileError> {
        let params = chord_length_params(&points)?;
        let tangents = not_a_knot_slopes(&params, &points);
        Ok(Self { points, params, tangents })
    }

    /// Validates a stored Hermite form (module docs, "Serde form").
    fn from_stored(points: Vec<DVec3>, params: Vec<f64>, tangents: Vec<DVec3>) -> Result<Self, ProfileError> {
        let n = points.len();
        if n < 2 {
            return Err(ProfileError::TooFewPoints { count: n });
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(ProfileError::NonFinitePoint { index });
        }
        if params.len() != n {
            return Err(ProfileError::StoredLength { field: "params", expected: n, found: params.len() });
        }
        if tangents.len() != n {
            return Err(ProfileError::StoredLength { field: "tangents", expected: n, found: tangents.len() });
        }
        if params[0] != 0.0 {
            return Err(ProfileError::StoredParam { index: 0 });
        }
        if let Some(i) = params.windows(2).position(|w| !w[1].is_finite() || w[1] <= w[0]) {
            return Err(ProfileError::StoredParam { index: i + 1 });
        }
        if params[n - 1] != 1.0 {
            return Err(ProfileError::StoredParam { index: n - 1 });
        }
        if let Some(index) = tangents.iter().position(|t| !t.is_finite()) {
            return Err(ProfileError::NonFiniteTangent { index });
        }
        Ok(Self { points, params, tangents })
    }

    /// The attached points `Q_0 … Q_{n−1}`.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The curve parameters `u_i` of the attached points, `c(u_i) = Q_i`:
    /// Eq. (3) for a profile from [`Profile::new`], [`Profile::relocated`] or
    /// points-only serde input; the mapped parent parameters for a half from
    /// [`Profile::split_half`].
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// The slopes `c'(u_i)` at the attached points.
    pub fn tangents(&self) -> &[DVec3] {
        &self.tangents
    }

    /// `Q_0`, on the edge's start node.
    pub fn start(&self) -> DVec3 {
        self.points[0]
    }

    /// `Q_{n−1}`, on the edge's end node.
    pub fn end(&self) -> DVec3 {
        self.points[self.points.len() - 1]
    }

    /// Number of cubic pieces (`n − 1`).
    pub fn piece_count(&self) -> usize {
        self.points.len() - 1
    }

    /// The piece holding `u` (clamped to [0, 1]) and the local parameter `t ∈ [0, 1]`.
    fn locate(&self, u: f64) -> (usize, f64) {
        let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
        let last = self.piece_count() - 1;
        let i = self.params.partition_point(|&k| k <= u).saturating_sub(1).min(last);
        let (a, b) = (self.params[i], self.params[i + 1]);
        (i, ((u - a) / (b - a)).clamp(0.0, 1.0))
    }

    /// Hermite data of piece `i`: `(Q_i, h c'(u_i), Q_{i+1}, h c'(u_{i+1}), h)`.
    fn piece(&self, i: usize) -> (DVec3, DVec3, DVec3, DVec3, f64) {
        let h = self.params[i + 1] - self.params[i];
        (self.points[i], h * self.tangents[i], self.points[i + 1], h * self.tangents[i + 1], h)
    }

    /// `c(u)`, with `u` clamped to [0, 1] (NaN reads as 0). Exact at the
    /// knots: `c(u_i) = Q_i`, in particular `c(0) = Q_0`, `c(1) = Q_{n−1}`.
    pub fn eval(&self, u: f64) -> DVec3 {
        let (i, t) = self.locate(u);
        let (p0, m0, p1, m1, _) = self.piece(i);
        let t2 = t * t;
        let t3 = t2 * t;
        p0 * (2.0 * t3 - 3.0 * t2 + 1.0) + m0 * (t3 - 2.0 * t2 + t) + p1 * (-2.0 * t3 + 3.0 * t2) + m1 * (t3 - t2)
    }

    /// `c'(u)`, with `u` clamped to [0, 1] (one-sided at the ends).
    pub fn derivative(&self, u: f64) -> DVec3 {
        let (i, t) = self.locate(u);
        let (p0, m0, p1, m1, h) = self.piece(i);
        let t2 = t * t;
        (p0 * (6.0 * t2 - 6.0 * t)
            + m0 * (3.0 * t2 - 4.0 * t + 1.0)
            + p1 * (6.0 * t - 6.0 * t2)
            + m1 * (3.0 * t2 - 2.0 * t))
            / h
    }

    /// `c''(u)`, with `u` clamped to [0, 1]; at an interior knot the value of
    /// the piece to its right (continuous for a spline from [`Profile::new`]).
    pub fn second_derivative(&self, u: f64) -> DVec3 {
        let (i, t) = self.locate(u);
        let (p0, m0, p1, m1, h) = self.piece(i);
        (p0 * (12.0 * t - 6.0) + m0 * (6.0 * t - 4.0) + p1 * (6.0 - 12.0 * t) + m1 * (6.0 * t - 2.0)) / (h * h)
    }

    /// Length of the polyline of attached points, `Σ |Q_i − Q_{i−1}|` (the
    /// denominator of Eq. (3)).
    pub fn chord_length(&self) -> f64 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    /// Arc length of `c`, `∫₀¹ |c'(u)| du`: adaptive 5-point Gauss–Legendre
    /// starting from [`LENGTH_SUBINTERVALS_PER_PIECE`] equal subintervals of
    /// every piece, to [`LENGTH_TOLERANCE`] relative to the chord length
    /// (depth limit [`LENGTH_MAX_DEPTH`]). At least [`Profile::chord_length`]
    /// up to that error. Deterministic.
    pub fn length(&self) -> f64 {
        let gauss = |a: f64, b: f64| -> f64 {
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            half * GAUSS_NODES
                .iter()
                .zip(GAUSS_WEIGHTS)
                .map(|(&x, w)| w * self.derivative(mid + half * x).length())
                .sum::<f64>()
        };
        let budget = LENGTH_TOLERANCE * self.chord_length();
        let mut total = 0.0;
        let mut stack = Vec::new();
        for i in 0..self.piece_count() {
            let (a, b) = (self.params[i], self.params[i + 1]);
            let w = (b - a) / LENGTH_SUBINTERVALS_PER_PIECE as f64;
            for k in (0..LENGTH_SUBINTERVALS_PER_PIECE).rev() {
                let lo = a + w * k as f64;
                let hi = if k + 1 == LENGTH_SUBINTERVALS_PER_PIECE { b } else { a + w * (k + 1) as f64 };
                stack.push((lo, hi, gauss(lo, hi), 0));
            }
            while let Some((lo, hi, whole, depth)) = stack.pop() {
                let mid = 0.5 * (lo + hi);
                let (left, right) = (gauss(lo, mid), gauss(mid, hi));
                if depth >= LENGTH_MAX_DEPTH || (left + right - whole).abs() <= budget * (hi - lo) {
                    total += left + right;
                } else {
                    stack.push((mid, hi, right, depth + 1));
                    stack.push((lo, mid, left, depth + 1));
                }
            }
        }
        total
    }

    /// The same curve traversed from its end to its start: points reversed,
    /// knots `1 − u_i`, slopes negated — `reversed().eval(u) = eval(1 − u)`
    /// up to the rounding of `1 − u`.
    pub fn reversed(&self) -> Profile {
        Profile {
            points: self.points.iter().rev().copied().collect(),
            params: self.params.iter().rev().map(|u| 1.0 - u).collect(),
            tangents: self.tangents.iter().rev().map(|&t| -t).collect(),
        }
    }

    /// The halves `c_f(t) = c(t/2)` and `c_b(t) = c(1/2 + t/2)` of seed 000
    /// §5.2, as profiles.
    ///
    /// The front half's attached points are the `Q_i` with `u_i < 1/2`, then
    /// `c(1/2)`; the back half's are `c(1/2)`, then the `Q_i` with `u_i > 1/2`
    /// (a `Q_i` at `u_i = 1/2` exactly *is* `c(1/2)`). Parameters map by
    /// `2u` and `2u − 1`, slopes halve, and the piece containing `1/2` is cut
    /// there. The front's last point and the back's first point are the same
    /// `c(1/2)` bit for bit, equal to `self.eval(SPLIT_PARAM)`.
    pub fn split_half(&self) -> (Profile, Profile) {
        let (mid, mid_slope) = match self.params.binary_search_by(|k| k.total_cmp(&SPLIT_PARAM)) {
            Ok(k) => (self.points[k], self.tangents[k]),
            Err(_) => (self.eval(SPLIT_PARAM), self.derivative(SPLIT_PARAM)),
        };
        let mut front = Profile { points: Vec::new(), params: Vec::new(), tangents: Vec::new() };
        let mut back = Profile { points: vec![mid], params: vec![0.0], tangents: vec![0.5 * mid_slope] };
        for ((&q, &u), &s) in self.points.iter().zip(&self.params).zip(&self.tangents) {
            if u < SPLIT_PARAM {
                front.points.push(q);
                front.params.push(2.0 * u);
                front.tangents.push(0.5 * s);
            } else if u > SPLIT_PARAM {
                back.points.push(q);
                back.params.push(2.0 * u - 1.0);
                back.tangents.push(0.5 * s);
            }
        }
        front.points.push(mid);
        front.params.push(1.0);
        front.tangents.push(0.5 * mid_slope);
        (front, back)
    }

    /// The profile after the edge's nodes move to `new_start`, `new_end`:
    /// seed 000 Eq. (5) applied to every attached point, with `v_l = Q_0`,
    /// `v_m = Q_{n−1}`, `u_i` from Eq. (3) of the current points and
    /// `s = |new_end − new_start| / |Q_{n−1} − Q_0|`; then the spline through
    /// the moved points ([`Profile::new`]). The first and last moved points are
    /// `new_start` and `new_end` exactly.
    ///
    /// # Errors
    /// [`ProfileError::NonFiniteNode`] for a non-finite new node;
    /// [`ProfileError::ZeroNodeChord`] if `Q_0 = Q_{n−1}`; errors of
    /// [`Profile::new`] for the moved points, e.g. [`ProfileError::ZeroChord`]
    /// when `new_start = new_end` (then `s = 0` and every point collapses).
    pub fn relocated(&self, new_start: DVec3, new_end: DVec3) -> Result<Profile, ProfileError> {
        let last = self.points.len() - 1;
        if !new_start.is_finite() {
            return Err(ProfileError::NonFiniteNode { index: 0 });
        }
        if !new_end.is_finite() {
            return Err(ProfileError::NonFiniteNode { index: last });
        }
        let (old_start, old_end) = (self.start(), self.end());
        let old_axis = old_end - old_start;
        let old_chord = old_axis.length();
        if old_chord == 0.0 {
            return Err(ProfileError::ZeroNodeChord { end_index: last });
        }
        let u = chord_length_params(&self.points)?;
        let new_axis = new_end - new_start;
        let s = new_axis.length() / old_chord;
        let mut moved: Vec<DVec3> = self
            .points
            .iter()
            .zip(&u)
            .map(|(&q, &ui)| s * (q - old_start - ui * old_axis) + new_start + ui * new_axis)
            .collect();
        moved[0] = new_start;
        moved[last] = new_end;
        Profile::new(moved)
    }

    /// The closest point of `c` to `p` with [`ClosestOptions::default`].
    pub fn closest_point(&self, p: DVec3) -> ClosestOnProfile {
        self.closest_point_with(p, &ClosestOptions::default())
    }

    /// The closest point of `c` to `p`: uniform samples per piece, then
    /// golden-section refinement around every sampled local minimum of
    /// `|c(u) − p|²` (see [`ClosestOptions`]). Deterministic.
    pub fn closest_point_with(&self, p: DVec3, options: &ClosestOptions) -> ClosestOnProfile {
        let per_piece = options.samples_per_piece.max(1);
        let mut us = Vec::with_capacity(self.piece_count() * per_piece + 1);
        for i in 0..self.piece_count() {
            let (a, b) = (self.params[i], self.params[i + 1]);
            us.extend((0..per_piece).map(|k| a + (b - a) * (k as f64 / per_piece as f64)));
        }
        us.push(1.0);
        let d2: Vec<f64> = us.iter().map(|&u| (self.eval(u) - p).length_squared()).collect();
        let dist2 = |u: f64| (self.eval(u) - p).length_squared();
        let mut best = (us[0], d2[0]);
        for k in 0..us.len() {
            let left_ok = k == 0 || d2[k] <= d2[k - 1];
            let right_ok = k + 1 == us.len() || d2[k] <= d2[k + 1];
            if !(left_ok && right_ok) {
                continue;
            }
            if d2[k] < best.1 {
                best = (us[k], d2[k]);
            }
            let (mut a, mut b) = (us[k.saturating_sub(1)], us[(k + 1).min(us.len() - 1)]);
            let ratio = (5.0_f64.sqrt() - 1.0) / 2.0;
            let mut x1 = b - ratio * (b - a);
            let mut x2 = a + ratio * (b - a);
            let (mut f1, mut f2) = (dist2(x1), dist2(x2));
            for _ in 0..options.max_iterations {
                if b - a <= f64::EPSILON {
                    break;
                }
                if f1 <= f2 {
                    b = x2;
                    x2 = x1;
                    f2 = f1;
                    x1 = b - ratio * (b - a);
                    f1 = dist2(x1);
                } else {
                    a = x1;
                    x1 = x2;
                    f1 = f2;
                    x2 = a + ratio * (b - a);
                    f2 = dist2(x2);
                }
            }
            for (x, f) in [(x1, f1), (x2, f2)] {
                if f < best.1 {
                    best = (x, f);
                }
            }
        }
        let point = self.eval(best.0);
        ClosestOnProfile { u: best.0, point, distance: point.distance(p) }
    }

    /// The largest distance of `pts` from the curve `c` (0 for no points),
    /// each by [`Profile::closest_point`]. Used to check that vertices
    /// generated on profiled edges lie on the profile curve.
    pub fn max_deviation_from(&self, pts: &[DVec3]) -> f64 {
        pts.iter().map(|&q| self.closest_point(q).distance).fold(0.0, f64::max)
    }
}

/// Slopes `c'(u_i)` of the not-a-knot cubic spline through `(u_i, Q_i)`
/// (module docs). `u` strictly increasing, same length as `q`, at least 2.
fn not_a_knot_slopes(u: &[f64], q: &[DVec3]) -> Vec<DVec3> {
    let n = u.len();
    let h: Vec<f64> = u.windows(2).map(|w| w[1] - w[0]).collect();
    let delta: Vec<DVec3> = (0..n - 1).map(|i| (q[i + 1] - q[i]) / h[i]).collect();
    match n {
        2 => vec![delta[0]; 2],
        3 => {
            // The parabola through the three points: c'(u) = δ_0 + A (2u − u_0 − u_1).
            let a = (delta[1] - delta[0]) / (h[0] + h[1]);
            vec![delta[0] - a * h[0], delta[0] + a * h[0], delta[1] + a * h[1]]
        }
        _ => {
            // Rows 0 and n−1 (not-a-knot) and the C2 rows 1..n−2.
            let r_first = ((3.0 * h[0] + 2.0 * h[1]) * h[1] * delta[0] + h[0] * h[0] * delta[1]) / (h[0] + h[1]);
            let (ho, hi) = (h[n - 2], h[n - 3]);
            let r_last = ((3.0 * ho + 2.0 * hi) * hi * delta[n - 2] + ho * ho * delta[n - 3]) / (ho + hi);
            // Reduced system in s_1 … s_{n−2} (index k = i − 1).
            let m = n - 2;
            let mut sub = vec![0.0; m];
            let mut diag = vec![0.0; m];
            let mut sup = vec![0.0; m];
            let mut rhs = vec![DVec3::ZERO; m];
            for k in 0..m {
                let i = k + 1;
                sub[k] = h[i];
                diag[k] = 2.0 * (h[i - 1] + h[i]);
                sup[k] = h[i - 1];
                rhs[k] = 3.0 * (h[i] * delta[i - 1] + h[i - 1] * delta[i]);
            }
            // Substitute s_0 from row 0 into row 1, s_{n−1} from row n−1 into row n−2.
            diag[0] = h[0] + h[1];
            rhs[0] -= r_first;
            sub[0] = 0.0;
            diag[m - 1] = h[n - 3] + h[n - 2];
            rhs[m - 1] -= r_last;
            sup[m - 1] = 0.0;
            // Thomas algorithm (strictly diagonally dominant: no pivoting needed).
            for k in 1..m {
                let w = sub[k] / diag[k - 1];
                diag[k] -= w * sup[k - 1];
                let prev = rhs[k - 1];
                rhs[k] -= w * prev;
            }
            let mut s = vec![DVec3::ZERO; n];
            s[m] = rhs[m - 1] / diag[m - 1];
            for k in (0..m - 1).rev() {
                s[k + 1] = (rhs[k] - sup[k] * s[k + 2]) / diag[k];
            }
            s[0] = (r_first - (h[0] + h[1]) * s[1]) / h[1];
            s[n - 1] = (r_last - (h[n - 2] + h[n - 3]) * s[n - 2]) / h[n - 3];
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Tolerance of the interpolation checks, relative to the profile's chord length.
    const INTERP_TOL: f64 = 1e-12;
    /// Tolerance of the split and on-curve checks, relative to the profile's chord length.
    const SPLIT_TOL: f64 = 1e-9;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    /// A curved 3D profile with uneven spacing.
    fn wavy() -> Profile {
        Profile::new(vec![
            v(0.0, 0.0, 0.0),
            v(0.3, 0.2, 0.05),
            v(0.9, 0.35, -0.1),
            v(1.4, 0.1, 0.0),
            v(2.2, -0.3, 0.25),
            v(2.5, -0.1, 0.4),
            v(3.1, 0.4, 0.3),
        ])
        .unwrap()
    }

    /// Largest `|c_half(t) − c(a + w t)| / size` over `samples + 1` values of `t`.
    fn half_error(parent: &Profile, half: &Profile, a: f64, w: f64, samples: usize, size: f64) -> f64 {
        (0..=samples)
            .map(|k| {
                let t = k as f64 / samples as f64;
                half.eval(t).distance(parent.eval(a + w * t)) / size
            })
            .fold(0.0, f64::max)
    }

    /// Third derivative of piece `i` (constant on the piece).
    fn third_derivative(p: &Profile, i: usize) -> DVec3 {
        let (p0, m0, p1, m1, h) = p.piece(i);
        (12.0 * p0 + 6.0 * m0 - 12.0 * p1 + 6.0 * m1) / (h * h * h)
    }

    #[test]
    fn eq3_params_of_planted_polyline() {
        // Cumulative lengths 0, 1, 3, 6 along a bent path.
        let pts = vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 2.0, 0.0), v(1.0, 2.0, 3.0)];
        let p = Profile::new(pts.clone()).unwrap();
        let expected = [0.0, 1.0 / 6.0, 0.5, 1.0];
        for (u, e) in p.params().iter().zip(expected) {
            assert!((u - e).abs() <= 1e-15, "{u} vs {e}");
        }
        assert_eq!(p.params()[0], 0.0);
        assert_eq!(p.params()[3], 1.0);
        assert_eq!(chord_length_params(&pts).unwrap(), p.params());
        assert!((p.chord_length() - 6.0).abs() <= 1e-15);
    }

    #[test]
    fn interpolates_attached_points() {
        let p = wavy();
        let size = p.chord_length();
        for (q, &u) in p.points().iter().zip(p.params()) {
            assert!(p.eval(u).distance(*q) <= INTERP_TOL * size);
        }
        assert_eq!(p.eval(0.0), p.points()[0]);
        assert_eq!(p.eval(1.0), *p.points().last().unwrap());
        assert_eq!(p.eval(-3.0), p.start());
        assert_eq!(p.eval(7.0), p.end());
    }

    #[test]
    fn spline_is_c2_and_not_a_knot() {
        let p = wavy();
        for i in 1..p.piece_count() {
            let (p0, m0, p1, m1, h0) = p.piece(i - 1);
            // c'' at the end of piece i−1 (t = 1) vs at the start of piece i.
            let left = (p0 * 6.0 + m0 * 2.0 - p1 * 6.0 + m1 * 4.0) / (h0 * h0);
            let right = p.second_derivative(p.params()[i]);
            assert!((left - right).length() <= 1e-9 * (1.0 + right.length()), "knot {i}: {left} vs {right}");
        }
        let n = p.points().len();
        let a = third_derivative(&p, 0);
        let b = third_derivative(&p, 1);
        assert!((a - b).length() <= 1e-9 * (1.0 + a.length()));
        let a = third_derivative(&p, n - 3);
        let b = third_derivative(&p, n - 2);
        assert!((a - b).length() <= 1e-9 * (1.0 + a.length()));
    }

    #[test]
    fn not_a_knot_reproduces_cubics_and_three_points_give_the_parabola() {
        let knots = [0.0, 0.13, 0.2, 0.55, 0.61, 0.9, 1.0];
        let (a, b, c, d) = (v(1.0, -2.0, 0.5), v(0.3, 4.0, -1.0), v(-2.0, 1.5, 3.0), v(5.0, -0.7, 2.0));
        let f = |u: f64| a + b * u + c * u * u + d * u * u * u;
        let df = |u: f64| b + 2.0 * c * u + 3.0 * d * u * u;
        let values: Vec<DVec3> = knots.iter().map(|&u| f(u)).collect();
        let slopes = not_a_knot_slopes(&knots, &values);
        for (s, &u) in slopes.iter().zip(&knots) {
            assert!(s.distance(df(u)) <= 1e-11 * df(u).length().max(1.0), "u = {u}: {s} vs {}", df(u));
        }
        for n in [4, 5] {
            let values: Vec<DVec3> = knots[..n - 1].iter().chain([&1.0]).map(|&u| f(u)).collect();
            let ks: Vec<f64> = knots[..n - 1].iter().copied().chain([1.0]).collect();
            let slopes = not_a_knot_slopes(&ks, &values);
            for (s, &u) in slopes.iter().zip(&ks) {
                assert!(s.distance(df(u)) <= 1e-11 * df(u).length().max(1.0), "n = {n}, u = {u}");
            }
        }
        // Three points: c is the quadratic (Lagrange) interpolant over (u_i, Q_i).
        let p = Profile::new(vec![v(0.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(3.0, 1.0, 1.0)]).unwrap();
        let (u, q) = (p.params(), p.points());
        for k in 0..=20 {
            let x = k as f64 / 20.0;
            let l0 = (x - u[1]) * (x - u[2]) / ((u[0] - u[1]) * (u[0] - u[2]));
            let l1 = (x - u[0]) * (x - u[2]) / ((u[1] - u[0]) * (u[1] - u[2]));
            let l2 = (x - u[0]) * (x - u[1]) / ((u[2] - u[0]) * (u[2] - u[1]));
            let lagrange = q[0] * l0 + q[1] * l1 + q[2] * l2;
            assert!(p.eval(x).distance(lagrange) <= 1e-13, "x = {x}");
        }
    }

    #[test]
    fn straight_profiles_evaluate_on_the_line() {
        let (a, dir) = (v(1.0, -2.0, 0.5), v(2.0, 1.0, -2.0)); // |dir| = 3
        for stations in
            [vec![0.0, 1.0], vec![0.0, 0.5, 1.0], vec![0.0, 0.25, 0.5, 0.75, 1.0], vec![0.0, 0.05, 0.4, 0.45, 0.9, 1.0]]
        {
            let p = Profile::new(stations.iter().map(|&s| a + s * dir).collect()).unwrap();
            for (u, s) in p.params().iter().zip(&stations) {
                assert!((u - s).abs() <= 1e-15);
            }
            for k in 0..=100 {
                let u = k as f64 / 100.0;
                assert!(p.eval(u).distance(a + u * dir) <= 1e-14, "{stations:?} u = {u}");
                assert!(p.derivative(u).distance(dir) <= 1e-12, "{stations:?} u = {u}");
            }
            assert!((p.length() - 3.0).abs() <= 1e-13);
            assert!((p.chord_length() - 3.0).abs() <= 1e-14);
        }
    }

    #[test]
    fn split_half_reproduces_the_parent() {
        let p = wavy();
        let size = p.chord_length();
        let (f, b) = p.split_half();
        let mid = p.eval(SPLIT_PARAM);
        assert_eq!(f.end(), mid);
        assert_eq!(b.start(), mid);
        assert_eq!(f.end().to_array().map(f64::to_bits), b.start().to_array().map(f64::to_bits));
        assert_eq!(f.eval(1.0), mid);
        assert_eq!(b.eval(0.0), mid);
        assert_eq!(f.start(), p.start());
        assert_eq!(b.end(), p.end());
        // Halves are exact on their attached points.
        for h in [&f, &b] {
            for (q, &u) in h.points().iter().zip(h.params()) {
                assert_eq!(h.eval(u), *q);
            }
        }
        let ef = half_error(&p, &f, 0.0, 0.5, 200, size);
        let eb = half_error(&p, &b, 0.5, 0.5, 200, size);
        eprintln!("split_half: max |c_f(t) − c(t/2)|/L = {ef:.3e}, max |c_b(t) − c(1/2 + t/2)|/L = {eb:.3e}");
        assert!(ef <= SPLIT_TOL && eb <= SPLIT_TOL);
        // Derivatives follow the chain rule c_f'(t) = c'(t/2)/2.
        for k in 0..=50 {
            let t = k as f64 / 50.0;
            assert!(f.derivative(t).distance(0.5 * p.derivative(0.5 * t)) <= 1e-9 * size);
            assert!(b.derivative(t).distance(0.5 * p.derivative(0.5 + 0.5 * t)) <= 1e-9 * size);
        }
        // Arc lengths add up.
        assert!((f.length() + b.length() - p.length()).abs() <= 1e-12 * size);
    }

    #[test]
    fn split_at_an_existing_knot_reuses_it() {
        // Chords 1, 1, 1, 1 → u = 0, 1/4, 1/2, 3/4, 1: Q_2 sits at u = 1/2.
        let p = Profile::new(vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(1.0, 1.0, 1.0),
            v(2.0, 1.0, 1.0),
        ])
        .unwrap();
        let (f, b) = p.split_half();
        assert_eq!(f.end(), p.eval(SPLIT_PARAM));
        assert_eq!(f.points(), &p.points()[..3]);
        assert_eq!(b.points(), &p.points()[2..]);
        assert_eq!(f.params(), &[0.0, 0.5, 1.0]);
        assert_eq!(b.params(), &[0.0, 0.5, 1.0]);
        let size = p.chord_length();
        assert!(half_error(&p, &f, 0.0, 0.5, 200, size) <= SPLIT_TOL);
        assert!(half_error(&p, &b, 0.5, 0.5, 200, size) <= SPLIT_TOL);
        // A two-point profile splits into two straight halves.
        let line = Profile::new(vec![v(0.0, 0.0, 0.0), v(2.0, 4.0, 6.0)]).unwrap();
        let (f, b) = line.split_half();
        assert_eq!(f.end(), v(1.0, 2.0, 3.0));
        assert_eq!(b.points(), &[v(1.0, 2.0, 3.0), v(2.0, 4.0, 6.0)]);
    }

    /// All pieces after `levels` rounds of halving, with their parent interval `[a, a + w]`.
    fn split_levels(p: &Profile, levels: u32) -> Vec<(Profile, f64, f64)> {
        let mut pieces = vec![(p.clone(), 0.0, 1.0)];
        for _ in 0..levels {
            pieces = pieces
                .into_iter()
                .flat_map(|(q, a, w)| {
                    let (f, b) = q.split_half();
                    [(f, a, 0.5 * w), (b, a + 0.5 * w, 0.5 * w)]
                })
                .collect();
        }
        pieces
    }

    #[test]
    fn repeated_splitting_stays_on_the_original_curve() {
        let p = wavy();
        let size = p.chord_length();
        let pieces = split_levels(&p, 3);
        assert_eq!(pieces.len(), 8);
        let mut worst: f64 = 0.0;
        let mut vertices = Vec::new();
        for (k, (q, a, w)) in pieces.iter().enumerate() {
            assert_eq!(*a, k as f64 / 8.0);
            worst = worst.max(half_error(&p, q, *a, *w, 200, size));
            vertices.extend_from_slice(q.points());
        }
        // Consecutive pieces share their end vertex bit for bit.
        for pair in pieces.windows(2) {
            assert_eq!(pair[0].0.end(), pair[1].0.start());
        }
        let on_curve = p.max_deviation_from(&vertices) / size;
        eprintln!("3-level split: max |c_piece(t) − c(a + t/8)|/L = {worst:.3e}; vertices' distance from c /L = {on_curve:.3e}");
        assert!(worst <= SPLIT_TOL);
        assert!(on_curve <= SPLIT_TOL);
    }

    #[test]
    fn closest_point_planted() {
        let line = Profile::new(vec![v(0.0, 0.0, 0.0), v(4.0, 0.0, 0.0)]).unwrap();
        let c = line.closest_point(v(1.0, 2.0, 0.0));
        assert!((c.distance - 2.0).abs() <= 1e-12);
        assert!((c.u - 0.25).abs() <= 1e-9);
        assert!(c.point.distance(v(1.0, 0.0, 0.0)) <= 1e-9);
        // Beyond the end: the end point.
        let c = line.closest_point(v(7.0, 4.0, 0.0));
        assert_eq!(c.u, 1.0);
        assert!((c.distance - 5.0).abs() <= 1e-12);
        assert_eq!(line.max_deviation_from(&[]), 0.0);
        assert!((line.max_deviation_from(&[v(2.0, 0.0, 0.0), v(3.0, 0.0, -3.0)]) - 3.0).abs() <= 1e-12);
        // On a curved profile: off-curve points along the normal at u = 0.3.
        let p = wavy();
        let (c0, t) = (p.eval(0.3), p.derivative(0.3).normalize());
        let n = t.any_orthonormal_vector();
        let c = p.closest_point(c0 + 0.01 * n);
        assert!((c.distance - 0.01).abs() <= 1e-9, "{}", c.distance);
        assert!((c.u - 0.3).abs() <= 1e-6);
        assert!(p.max_deviation_from(&[c0, p.eval(0.77)]) <= 1e-14);
    }

    #[test]
    fn length_of_a_curved_profile() {
        // Points on a quarter circle of radius 2: the spline's length is near π.
        let pts: Vec<DVec3> = (0..=8)
            .map(|k| {
                let a = std::f64::consts::FRAC_PI_2 * k as f64 / 8.0;
                v(2.0 * a.cos(), 2.0 * a.sin(), 0.0)
            })
            .collect();
        let p = Profile::new(pts).unwrap();
        assert!(p.length() >= p.chord_length());
        assert!((p.length() - std::f64::consts::PI).abs() <= 1e-4, "{}", p.length());
        for k in 0..=64 {
            let r = p.eval(k as f64 / 64.0).length();
            assert!((r - 2.0).abs() <= 1e-4, "r = {r}");
        }
    }

    #[test]
    fn eq5_planted_answer() {
        // Chords 3, 4, 3 → u = 0, 0.3, 0.7, 1; old chord Q_0 → Q_3 = (4,0,0), |·| = 4.
        let p = Profile::new(vec![v(0.0, 0.0, 0.0), v(0.0, 3.0, 0.0), v(4.0, 3.0, 0.0), v(4.0, 0.0, 0.0)]).unwrap();
        // New chord (0,0,6): |·| = 6, s = 1.5, turned by 90°. Offsets keep their direction.
        let (ns, ne) = (v(10.0, 0.0, 0.0), v(10.0, 0.0, 6.0));
        let r = p.relocated(ns, ne).unwrap();
        // Q_1: 1.5·((0,3,0) − 0.3·(4,0,0)) + (10,0,0) + 0.3·(0,0,6) = (8.2, 4.5, 1.8)
        // Q_2: 1.5·((4,3,0) − 0.7·(4,0,0)) + (10,0,0) + 0.7·(0,0,6) = (11.8, 4.5, 4.2)
        let expected = [ns, v(8.2, 4.5, 1.8), v(11.8, 4.5, 4.2), ne];
        for (q, e) in r.points().iter().zip(expected) {
            assert!(q.distance(e) <= 1e-14, "{q} vs {e}");
        }
        assert_eq!(r.start(), ns);
        assert_eq!(r.end(), ne);
        assert_eq!(r.eval(0.0), ns);
        assert_eq!(r.eval(1.0), ne);
    }

    #[test]
    fn eq5_endpoints_are_exactly_the_new_nodes() {
        let p = wavy();
        let (ns, ne) = (v(0.1, 0.2, 0.3), v(-1.7, 2.9, 0.123_456_789));
        let r = p.relocated(ns, ne).unwrap();
        assert_eq!(r.points()[0], ns);
        assert_eq!(*r.points().last().unwrap(), ne);
        assert_eq!(r.points().len(), p.points().len());
    }

    #[test]
    fn eq5_translation_translates_every_point() {
        let p = wavy();
        let d = v(0.7, -1.25, 3.5);
        let r = p.relocated(p.start() + d, p.end() + d).unwrap();
        let size = p.chord_length();
        for (q, q0) in r.points().iter().zip(p.points()) {
            assert!(q.distance(*q0 + d) <= 1e-14 * size.max(1.0) * 10.0, "{q} vs {}", *q0 + d);
        }
        for k in 0..=40 {
            let u = k as f64 / 40.0;
            assert!(r.eval(u).distance(p.eval(u) + d) <= 1e-12 * size);
        }
    }

    #[test]
    fn eq5_scaling_the_chord_scales_the_offsets() {
        let p = wavy();
        let u = chord_length_params(p.points()).unwrap();
        let (vl, vm) = (p.start(), p.end());
        let k = 1.75;
        let r = p.relocated(vl, vl + k * (vm - vl)).unwrap();
        let new_axis = k * (vm - vl);
        for ((q, q_new), &ui) in p.points().iter().zip(r.points()).zip(&u) {
            let offset_old = *q - (vl + ui * (vm - vl));
            let offset_new = *q_new - (vl + ui * new_axis);
            assert!(offset_new.distance(k * offset_old) <= 1e-13, "{offset_new} vs {}", k * offset_old);
        }
        // Planted: Q = (0,0,0), (1,1,0), (2,0,0); chord (2,0,0); u = 0, 1/2, 1.
        // Chord doubled and lifted: v_l* = (0,0,1), v_m* = (4,0,1), s = 2:
        // Q_1* = 2·((1,1,0) − ½(2,0,0)) + (0,0,1) + ½(4,0,0) = (2, 2, 1).
        let p = Profile::new(vec![v(0.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(2.0, 0.0, 0.0)]).unwrap();
        let r = p.relocated(v(0.0, 0.0, 1.0), v(4.0, 0.0, 1.0)).unwrap();
        assert_eq!(r.points(), &[v(0.0, 0.0, 1.0), v(2.0, 2.0, 1.0), v(4.0, 0.0, 1.0)]);
    }

    #[test]
    fn eq5_uses_eq3_params_of_the_old_points_for_a_half() {
        let p = wavy();
        let (f, _) = p.split_half();
        let u = chord_length_params(f.points()).unwrap();
        let (ns, ne) = (v(1.0, 1.0, 1.0), v(2.0, 3.0, 4.0));
        let r = f.relocated(ns, ne).unwrap();
        let (vl, vm) = (f.start(), f.end());
        let s = ne.distance(ns) / vm.distance(vl);
        for ((q, q_new), &ui) in f.points().iter().zip(r.points()).zip(&u) {
            let e = s * (*q - vl - ui * (vm - vl)) + ns + ui * (ne - ns);
            assert!(q_new.distance(e) <= 1e-14);
        }
    }

    #[test]
    fn errors_name_the_bad_input() {
        assert_eq!(Profile::new(vec![v(1.0, 2.0, 3.0)]), Err(ProfileError::TooFewPoints { count: 1 }));
        assert_eq!(Profile::new(vec![]), Err(ProfileError::TooFewPoints { count: 0 }));
        assert_eq!(
            Profile::new(vec![v(0.0, 0.0, 0.0), v(1.0, f64::NAN, 0.0), v(2.0, 0.0, 0.0)]),
            Err(ProfileError::NonFinitePoint { index: 1 })
        );
        assert_eq!(
            Profile::new(vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, f64::INFINITY)]),
            Err(ProfileError::NonFinitePoint { index: 2 })
        );
        assert_eq!(
            Profile::new(vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0)]),
            Err(ProfileError::ZeroChord { index: 2 })
        );
        assert_eq!(
            Profile::new(vec![v(0.0, 0.0, 0.0), v(1e155, 0.0, 0.0), v(1e155, 1.0, 0.0)]),
            Err(ProfileError::ChordOverflow { index: 1 })
        );
        // A chord far below the parameter resolution: u does not advance.
        assert_eq!(
            Profile::new(vec![v(0.0, 0.0, 0.0), v(1e20, 0.0, 0.0), v(1e20, 1e-10, 0.0)]),
            Err(ProfileError::ZeroChord { index: 2 })
        );
        let closed =
            Profile::new(vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 0.0, 0.0)]).unwrap();
        assert_eq!(
            closed.relocated(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)),
            Err(ProfileError::ZeroNodeChord { end_index: 3 })
        );
        let p = wavy();
        assert_eq!(p.relocated(v(f64::NAN, 0.0, 0.0), p.end()), Err(ProfileError::NonFiniteNode { index: 0 }));
        assert_eq!(p.relocated(p.start(), v(0.0, f64::INFINITY, 0.0)), Err(ProfileError::NonFiniteNode { index: 6 }));
        // Collapsing the edge (new nodes equal) collapses every point: zero chord.
        assert_eq!(p.relocated(v(1.0, 1.0, 1.0), v(1.0, 1.0, 1.0)), Err(ProfileError::ZeroChord { index: 1 }));
        assert_eq!(
            ProfileError::ZeroChord { index: 2 }.to_string(),
            "attached points 1 and 2 coincide (zero chord; Eq. (3) parameter does not advance)"
        );
    }

    #[test]
    fn serde_round_trip_and_points_only_input() {
        let p = wavy();
        let (f, b) = p.split_half();
        for prof in [&p, &f, &b] {
            let json = serde_json::to_string(prof).unwrap();
            let back: Profile = serde_json::from_str(&json).unwrap();
            assert_eq!(back.points().len(), prof.points().len());
            let size = prof.chord_length();
            for k in 0..=50 {
                let t = k as f64 / 50.0;
                assert!(back.eval(t).distance(prof.eval(t)) <= 1e-14 * size);
            }
        }
        let only: Profile = serde_json::from_str("{\"points\": [[0,0,0],[1,0,0],[1,2,0],[1,2,3]]}").unwrap();
        assert_eq!(
            only,
            Profile::new(vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 2.0, 0.0), v(1.0, 2.0, 3.0)]).unwrap()
        );
        let err = |s: &str| serde_json::from_str::<Profile>(s).unwrap_err().to_string();
        assert!(err("{\"points\": [[0,0,0]]}").contains("at least 2"));
        assert!(err("{\"points\": [[0,0,0],[0,0,0]]}").contains("attached points 0 and 1 coincide"));
        assert!(err("{\"points\": [[0,0,0],[1,0,0]], \"params\": [0,1]}").contains("both"));
        assert!(err("{\"points\": [[0,0,0],[1,0,0]], \"params\": [0,1,2], \"tangents\": [[1,0,0],[1,0,0]]}")
            .contains("`params` has 3 entries"));
        assert!(err(
            "{\"points\": [[0,0,0],[1,0,0],[2,0,0]], \"params\": [0,0.7,0.5], \"tangents\": [[1,0,0],[1,0,0],[1,0,0]]}"
        )
        .contains("parameter 2"));
        assert!(err("{\"points\": [[0,0,0],[1,0,0]], \"params\": [0,0.9], \"tangents\": [[1,0,0],[1,0,0]]}")
            .contains("parameter 1"));
    }

    fn profile_points() -> impl Strategy<Value = Vec<DVec3>> {
        (
            prop::array::uniform3(-10.0..10.0f64),
            prop::collection::vec((prop::array::uniform3(-1.0..1.0f64), 0.05..5.0f64), 2..8),
        )
            .prop_map(|(start, steps)| {
                let mut pts = vec![DVec3::from(start)];
                for (dir, len) in steps {
                    let d = DVec3::from(dir);
                    let d = if d.length() < 1e-3 { DVec3::X } else { d.normalize() };
                    let last = pts[pts.len() - 1];
                    pts.push(last + len * d);
                }
                pts
            })
    }

    proptest! {
        #[test]
        fn random_profiles_interpolate_and_split_exactly(pts in profile_points()) {
            let p = Profile::new(pts.clone()).unwrap();
            let size = p.chord_length();
            prop_assert_eq!(p.eval(0.0), pts[0]);
            prop_assert_eq!(p.eval(1.0), pts[pts.len() - 1]);
            for (q, &u) in pts.iter().zip(p.params()) {
                prop_assert!(p.eval(u).distance(*q) <= INTERP_TOL * size);
            }
            let (f, b) = p.split_half();
            prop_assert_eq!(f.end(), b.start());
            prop_assert!(half_error(&p, &f, 0.0, 0.5, 100, size) <= SPLIT_TOL);
            prop_assert!(half_error(&p, &b, 0.5, 0.5, 100, size) <= SPLIT_TOL);
            for (q, a, w) in split_levels(&p, 3) {
                prop_assert!(half_error(&p, &q, a, w, 20, size) <= SPLIT_TOL);
            }
        }

        #[test]
        fn random_relocations_hit_the_new_nodes(pts in profile_points(), ns in prop::array::uniform3(-5.0..5.0f64),
                                               d in prop::array::uniform3(-5.0..5.0f64)) {
            let p = Profile::new(pts).unwrap();
            let (ns, ne) = (DVec3::from(ns), DVec3::from(ns) + DVec3::from(d));
            prop_assume!(p.start() != p.end() && ns.distance(ne) > 1e-3);
            let r = p.relocated(ns, ne).unwrap();
            prop_assert_eq!(r.start(), ns);
            prop_assert_eq!(r.end(), ne);
            prop_assert_eq!(r.eval(1.0), ne);
        }
    }
}
