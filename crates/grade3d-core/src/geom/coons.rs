//! Coons patches spanned by four boundary curves (issue #18 item 2: a
//! panel given as closed 3D boundary curves becomes a surface).
//!
//! # Method
//!
//! Seed 001 §3.1 (Wang et al., progressive Coons-patch modelling from 3D
//! curves), Eq. (1), with the erratum of `seeds-notes.md` §B.2: the printed
//! triple product
//!
//! ```text
//! [−1  f₁(u)  f₂(u)] · [[0, p(u,0), p(u,1)], [p(0,v), p(0,0), p(0,1)], [p(1,v), p(1,0), p(1,1)]] · [−1  f₁(v)  f₂(v)]ᵀ
//! ```
//!
//! equals **−P(u, v)** (checked in this module's tests), so the expanded
//! form is implemented:
//!
//! ```text
//! P(u,v) = f₁(u) p(0,v) + f₂(u) p(1,v) + f₁(v) p(u,0) + f₂(v) p(u,1)
//!        − [f₁(u)f₁(v) p(0,0) + f₁(u)f₂(v) p(0,1) + f₂(u)f₁(v) p(1,0) + f₂(u)f₂(v) p(1,1)]
//! ```
//!
//! with the bicubic (cubic Hermite) blends of seed 001, `f₁(t) = 2t³ − 3t² + 1`,
//! `f₂(t) = 1 − f₁(t) = −2t³ + 3t²` ([`Blend::Hermite`], the default), or
//! the bilinear ones of seed 002 (L30), `f₁(t) = 1 − t`, `f₂(t) = t`
//! ([`Blend::Linear`]).
//!
//! Each boundary curve is a polyline parameterised by its normalised arc
//! length (chord length), `p(t)` the point at fraction `t` of its length.
//! The bottom `p(u,0)` and top `p(u,1)` run in `u` from the left curve to
//! the right one; the left `p(0,v)` and right `p(1,v)` run in `v` from the
//! bottom to the top. A side may be a single point: a three-sided patch
//! (seed 001 Fig. 4, `F(u,1) ≡ F₁`).
//!
//! # What it reproduces (exact answers, tests below)
//!
//! - Both blends interpolate the four boundary curves: `P(u,0) = p(u,0)` and
//!   so on, for every `u`, to rounding (blends with `f₁(0) = 1`, `f₁(1) = 0`).
//! - With linear blends, every bilinear patch
//!   `B(u,v) = (1−u)(1−v)p₀₀ + u(1−v)p₁₀ + (1−u)v p₀₁ + uv p₁₁` whose sides
//!   are sampled at their own parameters.
//! - With the Hermite blends, a bilinear patch only when its twist
//!   `p₀₀ − p₁₀ − p₀₁ + p₁₁` vanishes (a parallelogram): writing
//!   `g(t) = f₁(t) − (1 − t)`, the patch of a bilinear `B`'s sides is
//!   `B(u,v) − g(u) g(v) (p₀₀ − p₁₀ − p₀₁ + p₁₁)`. So the issue's bar
//!   "reproduces a bilinear patch" holds for the Hermite form on twist-free
//!   patches and for the linear form on all; the tests plant that formula.
//! - A translational surface `a(u) + b(v)` (a cylinder quarter, a ruled
//!   sheet swept along a line) with either blend, at the sides' samples.
//!
//! # Failure modes
//!
//! [`CoonsError`]: a side with no point, a non-finite point, sides whose
//! ends do not meet at the four corners within
//! [`CoonsOptions::corner_tolerance_mm`], two opposite sides both
//! collapsed to a point, or a sampling of fewer than one interval.

use glam::DVec3;

use crate::geom::polyline::Polyline;

/// The blending functions `f₁`, `f₂ = 1 − f₁` (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Blend {
    /// Seed 001's cubic Hermite blends, `f₁(t) = 2t³ − 3t² + 1`: zero slope
    /// at the sides, so the cross-boundary derivative depends only on the
    /// transversal sides at the corners.
    #[default]
    Hermite,
    /// Seed 002's bilinear blends, `f₁(t) = 1 − t`.
    Linear,
}

impl Blend {
    /// `f₁(t)`.
    pub fn f1(self, t: f64) -> f64 {
        match self {
            Blend::Hermite => (2.0 * t - 3.0) * t * t + 1.0,
            Blend::Linear => 1.0 - t,
        }
    }

    /// `f₂(t) = 1 − f₁(t)`, evaluated from its own polynomial.
    pub fn f2(self, t: f64) -> f64 {
        match self {
            Blend::Hermite => (3.0 - 2.0 * t) * t * t,
            Blend::Linear => t,
        }
    }
}

/// Knobs of [`CoonsPatch::new`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct CoonsOptions {
    /// The blends. Default [`Blend::Hermite`] (seed 001).
    pub blend: Blend,
    /// How far apart two sides' ends may be at a corner, mm (the patch
    /// takes the bottom or top side's end as the corner). Default 0.01.
    pub corner_tolerance_mm: f64,
}

impl Default for CoonsOptions {
    fn default() -> Self {
        Self { blend: Blend::Hermite, corner_tolerance_mm: 0.01 }
    }
}

/// Which side of a patch (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// `p(u, 0)`.
    Bottom,
    /// `p(u, 1)`.
    Top,
    /// `p(0, v)`.
    Left,
    /// `p(1, v)`.
    Right,
}

/// A corner of a patch, by its `(u, v)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Corner {
    /// 0 or 1.
    pub u: u8,
    /// 0 or 1.
    pub v: u8,
}

/// Why a patch could not be made or sampled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoonsError {
    /// A side has no point.
    #[error("the {side:?} side has no point")]
    EmptySide {
        /// Which.
        side: Side,
    },
    /// A point is not finite.
    #[error("point {index} of the {side:?} side is not finite")]
    NonFinite {
        /// Which side.
        side: Side,
        /// Its index on that side.
        index: usize,
    },
    /// Two sides do not meet at a corner.
    #[error("the sides miss corner (u {}, v {}) by {gap_mm:.3} mm (at most {tolerance_mm} mm)", corner.u, corner.v)]
    OpenCorner {
        /// The corner.
        corner: Corner,
        /// How far apart their ends are, mm.
        gap_mm: f64,
        /// The tolerance, mm.
        tolerance_mm: f64,
    },
    /// Two opposite sides are both a single point: no surface.
    #[error("the {a:?} and {b:?} sides are both a single point")]
    Degenerate {
        /// One side.
        a: Side,
        /// The opposite one.
        b: Side,
    },
    /// A sampling needs at least one interval each way.
    #[error("a patch is sampled at least 1 × 1 intervals, not {nu} × {nv}")]
    Sampling {
        /// Intervals along `u`.
        nu: usize,
        /// Intervals along `v`.
        nv: usize,
    },
}

/// One side: its polyline and cumulative chord lengths
/// ([`Polyline::cumulative`]).
#[derive(Debug, Clone, PartialEq)]
struct Curve {
    line: Polyline,
    cum: Vec<f64>,
}

impl Curve {
    fn new(points: &[DVec3], side: Side) -> Result<Self, CoonsError> {
        if points.is_empty() {
            return Err(CoonsError::EmptySide { side });
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(CoonsError::NonFinite { side, index });
        }
        let line = Polyline::new(points.to_vec(), false);
        let cum = line.cumulative();
        Ok(Self { line, cum })
    }

    /// Its length (0 for a single point, or points all in one place).
    fn length(&self) -> f64 {
        self.cum.last().copied().unwrap_or(0.0)
    }

    /// Whether the side is one point (or points all in one place).
    fn is_point(&self) -> bool {
        self.length() == 0.0
    }

    fn first(&self) -> DVec3 {
        self.line.points[0]
    }

    fn last(&self) -> DVec3 {
        self.line.points[self.line.points.len() - 1]
    }

    /// The point at fraction `t` of its length (clamped to `[0, 1]`,
    /// [`Polyline::point_at`]).
    fn at(&self, t: f64) -> DVec3 {
        if self.is_point() {
            return self.first();
        }
        self.line.point_at_with(&self.cum, t.clamp(0.0, 1.0) * self.length())
    }

    /// The parameter `t` of its sample `k`.
    #[cfg(test)]
    fn param(&self, k: usize) -> f64 {
        self.cum[k] / self.length()
    }
}

/// A Coons patch (module docs): four sides and their corners.
#[derive(Debug, Clone, PartialEq)]
pub struct CoonsPatch {
    bottom: Curve,
    top: Curve,
    left: Curve,
    right: Curve,
    /// `p(0,0)`, `p(1,0)`, `p(0,1)`, `p(1,1)`.
    corners: [DVec3; 4],
    blend: Blend,
}

impl CoonsPatch {
    /// The patch of `bottom` `p(u,0)` and `top` `p(u,1)` (each from the left
    /// side to the right one), `left` `p(0,v)` and `right` `p(1,v)` (each
    /// from the bottom to the top), in one length unit (metres for
    /// garments). One side, or two adjacent ones, may be a single point.
    ///
    /// # Errors
    /// [`CoonsError`] (module docs).
    pub fn new(
        bottom: &[DVec3],
        top: &[DVec3],
        left: &[DVec3],
        right: &[DVec3],
        opts: &CoonsOptions,
    ) -> Result<Self, CoonsError> {
        let bottom = Curve::new(bottom, Side::Bottom)?;
        let top = Curve::new(top, Side::Top)?;
        let left = Curve::new(left, Side::Left)?;
        let right = Curve::new(right, Side::Right)?;
        for (a, b, sa, sb) in [(&bottom, &top, Side::Bottom, Side::Top), (&left, &right, Side::Left, Side::Right)] {
            if a.is_point() && b.is_point() {
                return Err(CoonsError::Degenerate { a: sa, b: sb });
            }
        }
        // the unit of the points is metres where the tolerance is in mm
        let tolerance = opts.corner_tolerance_mm * 1e-3;
        let meet = |p: DVec3, q: DVec3, u: u8, v: u8| {
            let gap = p.distance(q);
            if gap <= tolerance {
                Ok(())
            } else {
                Err(CoonsError::OpenCorner {
                    corner: Corner { u, v },
                    gap_mm: gap * 1e3,
                    tolerance_mm: opts.corner_tolerance_mm,
                })
            }
        };
        meet(bottom.first(), left.first(), 0, 0)?;
        meet(bottom.last(), right.first(), 1, 0)?;
        meet(top.first(), left.last(), 0, 1)?;
        meet(top.last(), right.last(), 1, 1)?;
        let corners = [bottom.first(), bottom.last(), top.first(), top.last()];
        Ok(Self { bottom, top, left, right, corners, blend: opts.blend })
    }

    /// `P(u, v)` by the expanded form (module docs); `u`, `v` clamped to `[0, 1]`.
    pub fn at(&self, u: f64, v: f64) -> DVec3 {
        let (u, v) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
        let b = self.blend;
        let (f1u, f2u, f1v, f2v) = (b.f1(u), b.f2(u), b.f1(v), b.f2(v));
        let [p00, p10, p01, p11] = self.corners;
        let ruled = self.left.at(v) * f1u + self.right.at(v) * f2u + self.bottom.at(u) * f1v + self.top.at(u) * f2v;
        let tensor = p00 * (f1u * f1v) + p01 * (f1u * f2v) + p10 * (f2u * f1v) + p11 * (f2u * f2v);
        ruled - tensor
    }

    /// The patch sampled on the grid `u = i / nu`, `v = j / nv` and
    /// triangulated, two triangles per cell, counter-clockwise seen from the
    /// side `∂P/∂u × ∂P/∂v` points to. Vertex `j (nu + 1) + i` is `P(i/nu,
    /// j/nv)`, except on a side that is one point: its row or column is one
    /// vertex, and the triangles that would have no area there are left
    /// out. For a four-sided patch: `(nu + 1)(nv + 1)` vertices and
    /// `2 nu nv` triangles.
    ///
    /// # Errors
    /// [`CoonsError::Sampling`] for `nu` or `nv` zero.
    pub fn sample(&self, nu: usize, nv: usize) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), CoonsError> {
        if nu == 0 || nv == 0 {
            return Err(CoonsError::Sampling { nu, nv });
        }
        let collapsed = [self.bottom.is_point(), self.top.is_point(), self.left.is_point(), self.right.is_point()];
        let [bottom, top, left, right] = collapsed;
        // grid (i, j) → vertex, one vertex for all of a collapsed side
        let mut id = vec![u32::MAX; (nu + 1) * (nv + 1)];
        let mut positions = Vec::with_capacity((nu + 1) * (nv + 1));
        for j in 0..=nv {
            for i in 0..=nu {
                let same = if j == 0 && bottom && i > 0 {
                    Some(id[0])
                } else if j == nv && top && i > 0 {
                    Some(id[nv * (nu + 1)])
                } else if i == 0 && left && j > 0 {
                    Some(id[0])
                } else if i == nu && right && j > 0 {
                    Some(id[nu])
                } else {
                    None
                };
                id[j * (nu + 1) + i] = same.unwrap_or_else(|| {
                    positions.push(self.at(i as f64 / nu as f64, j as f64 / nv as f64));
                    (positions.len() - 1) as u32
                });
            }
        }
        let mut triangles = Vec::with_capacity(2 * nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let [a, b, c, d] = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|(x, y)| id[y * (nu + 1) + x]);
                for t in [[a, b, c], [a, c, d]] {
                    if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                        triangles.push(t);
                    }
                }
            }
        }
        Ok((positions, triangles))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `n + 1` samples of `f` on `[0, 1]`.
    fn side(n: usize, f: impl Fn(f64) -> DVec3) -> Vec<DVec3> {
        (0..=n).map(|k| f(k as f64 / n as f64)).collect()
    }

    fn patch_of(s: impl Fn(f64, f64) -> DVec3, n: usize, blend: Blend) -> CoonsPatch {
        let opts = CoonsOptions { blend, ..CoonsOptions::default() };
        CoonsPatch::new(
            &side(n, |u| s(u, 0.0)),
            &side(n, |u| s(u, 1.0)),
            &side(n, |v| s(0.0, v)),
            &side(n, |v| s(1.0, v)),
            &opts,
        )
        .unwrap()
    }

    #[test]
    fn the_printed_eq_1_is_minus_the_patch_and_the_expanded_form_is_the_patch() {
        // seed 001 Eq. (1) as printed, evaluated literally as a triple product, gives −P
        // (seeds-notes §B.2, §G: (0, −0.3, 0) for p(0, 0.3) = (0, 0.3, 0))
        let s = |u: f64, v: f64| DVec3::new(u, v, 0.2 * (u * v).sin());
        let p = patch_of(s, 8, Blend::Hermite);
        let b = Blend::Hermite;
        let printed = |u: f64, v: f64| {
            let row = [-1.0, b.f1(u), b.f2(u)];
            let col = [-1.0, b.f1(v), b.f2(v)];
            let m = [
                [DVec3::ZERO, p.bottom.at(u), p.top.at(u)],
                [p.left.at(v), p.corners[0], p.corners[2]],
                [p.right.at(v), p.corners[1], p.corners[3]],
            ];
            let mut sum = DVec3::ZERO;
            for (r, line) in row.iter().zip(m) {
                for (c, q) in col.iter().zip(line) {
                    sum += q * (r * c);
                }
            }
            sum
        };
        assert!((printed(0.0, 0.3) + s(0.0, 0.3)).length() < 1e-12, "{}", printed(0.0, 0.3));
        for (u, v) in [(0.0, 0.3), (0.25, 0.5), (0.7, 0.9), (1.0, 0.125)] {
            assert!((printed(u, v) + p.at(u, v)).length() < 1e-12, "({u}, {v})");
        }
    }

    #[test]
    fn both_blends_interpolate_the_four_sides() {
        // wiggly sides from a doubly curved surface, unevenly spaced samples
        let s = |u: f64, v: f64| DVec3::new(u + 0.1 * (3.0 * v).sin(), v * v + 0.3 * u, (2.0 * u).cos() * (1.0 + v));
        let warp = |t: f64| t * t * (3.0 - 2.0 * t);
        for blend in [Blend::Hermite, Blend::Linear] {
            let opts = CoonsOptions { blend, ..CoonsOptions::default() };
            let sides = [
                side(17, |u| s(warp(u), 0.0)),
                side(13, |u| s(warp(u), 1.0)),
                side(11, |v| s(0.0, v)),
                side(19, |v| s(1.0, v)),
            ];
            let p = CoonsPatch::new(&sides[0], &sides[1], &sides[2], &sides[3], &opts).unwrap();
            for (k, q) in sides[0].iter().enumerate() {
                assert!((p.at(p.bottom.param(k), 0.0) - *q).length() < 1e-12);
            }
            for (k, q) in sides[1].iter().enumerate() {
                assert!((p.at(p.top.param(k), 1.0) - *q).length() < 1e-12);
            }
            for (k, q) in sides[2].iter().enumerate() {
                assert!((p.at(0.0, p.left.param(k)) - *q).length() < 1e-12);
            }
            for (k, q) in sides[3].iter().enumerate() {
                assert!((p.at(1.0, p.right.param(k)) - *q).length() < 1e-12);
            }
            // and between samples, the sides' own segments
            let t = 0.5 * (p.bottom.param(3) + p.bottom.param(4));
            assert!((p.at(t, 0.0) - sides[0][3].lerp(sides[0][4], 0.5)).length() < 1e-12);
        }
    }

    #[test]
    fn a_bilinear_patch_linear_always_hermite_when_twist_free_else_off_by_the_twist_term() {
        let [p00, p10, p01, p11] =
            [DVec3::ZERO, DVec3::new(1.0, 0.1, 0.0), DVec3::new(0.2, 1.0, 0.1), DVec3::new(1.1, 1.3, 0.9)];
        let bilinear = |q00: DVec3, q10: DVec3, q01: DVec3, q11: DVec3| {
            move |u: f64, v: f64| {
                q00 * ((1.0 - u) * (1.0 - v)) + q10 * (u * (1.0 - v)) + q01 * ((1.0 - u) * v) + q11 * (u * v)
            }
        };
        let twisted = bilinear(p00, p10, p01, p11);
        let twist = p00 - p10 - p01 + p11;
        assert!(twist.length() > 0.5);
        // a parallelogram: p11 = p10 + p01 − p00
        let flat = bilinear(p00, p10, p01, p10 + p01 - p00);
        let linear = patch_of(twisted, 8, Blend::Linear);
        let hermite = patch_of(twisted, 8, Blend::Hermite);
        let hermite_flat = patch_of(flat, 8, Blend::Hermite);
        let g = |t: f64| Blend::Hermite.f1(t) - (1.0 - t);
        for i in 0..=10 {
            for j in 0..=10 {
                let (u, v) = (i as f64 / 10.0, j as f64 / 10.0);
                assert!((linear.at(u, v) - twisted(u, v)).length() < 1e-12, "linear ({u}, {v})");
                assert!((hermite_flat.at(u, v) - flat(u, v)).length() < 1e-12, "hermite, no twist ({u}, {v})");
                let planted = twisted(u, v) - twist * (g(u) * g(v));
                assert!((hermite.at(u, v) - planted).length() < 1e-12, "hermite, twisted ({u}, {v})");
            }
        }
        // so the Hermite patch of a twisted bilinear one is off inside: by ¼·¼ of the twist at
        // (¼, ¼)-ish, zero on the sides
        assert!((hermite.at(0.25, 0.25) - twisted(0.25, 0.25)).length() > 1e-3);
    }

    #[test]
    fn a_cylinder_quarter_is_reproduced_at_its_samples() {
        // translational: a(u) + b(v); the arc sampled at equal angles is parameterised
        // by chord length exactly at its samples
        let r = 0.15;
        let s = |u: f64, v: f64| {
            let a = std::f64::consts::FRAC_PI_2 * u;
            DVec3::new(r * a.cos(), 0.4 * v, r * a.sin())
        };
        let n = 24;
        for blend in [Blend::Hermite, Blend::Linear] {
            let p = patch_of(s, n, blend);
            for i in 0..=n {
                for j in 0..=n {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    assert!((p.at(u, v) - s(u, v)).length() < 1e-12, "{blend:?} ({u}, {v})");
                }
            }
        }
    }

    #[test]
    fn sampling_counts_and_orientation() {
        let p = patch_of(|u, v| DVec3::new(u, v, 0.0), 4, Blend::Hermite);
        let (pos, tris) = p.sample(5, 3).unwrap();
        assert_eq!(pos.len(), 6 * 4);
        assert_eq!(tris.len(), 2 * 5 * 3);
        // counter-clockwise seen from +z (∂P/∂u × ∂P/∂v = x × y)
        for t in &tris {
            let [a, b, c] = t.map(|k| pos[k as usize]);
            assert!((b - a).cross(c - a).z > 0.0);
        }
        assert_eq!(p.sample(0, 3), Err(CoonsError::Sampling { nu: 0, nv: 3 }));
    }

    #[test]
    fn a_three_sided_patch_collapses_its_point_side() {
        // the top is one point (seed 001 Fig. 4): a triangle-like panel
        let apex = DVec3::new(0.5, 1.0, 0.2);
        let bottom = side(6, |u| DVec3::new(u, 0.0, 0.1 * (std::f64::consts::PI * u).sin()));
        let left = side(6, |v| DVec3::ZERO.lerp(apex, v));
        let right = side(6, |v| DVec3::X.lerp(apex, v));
        let p = CoonsPatch::new(&bottom, &[apex], &left, &right, &CoonsOptions::default()).unwrap();
        for u in [0.0, 0.3, 1.0] {
            assert!((p.at(u, 1.0) - apex).length() < 1e-12);
        }
        let (pos, tris) = p.sample(4, 4).unwrap();
        // 5 × 4 rows below the apex, and the apex
        assert_eq!(pos.len(), 5 * 4 + 1);
        // the top row's cells lose one triangle each
        assert_eq!(tris.len(), 2 * 4 * 4 - 4);
        for t in &tris {
            let [a, b, c] = t.map(|k| pos[k as usize]);
            assert!((b - a).cross(c - a).length() > 1e-9, "no sliver at the apex");
        }
    }

    #[test]
    fn bad_sides_are_refused_by_name() {
        let s = |u: f64, v: f64| DVec3::new(u, v, 0.0);
        let (b, t, l, r) =
            (side(3, |u| s(u, 0.0)), side(3, |u| s(u, 1.0)), side(3, |v| s(0.0, v)), side(3, |v| s(1.0, v)));
        let o = CoonsOptions::default();
        assert_eq!(CoonsPatch::new(&[], &t, &l, &r, &o), Err(CoonsError::EmptySide { side: Side::Bottom }));
        let mut bad = r.clone();
        bad[2].y = f64::NAN;
        assert_eq!(CoonsPatch::new(&b, &t, &l, &bad, &o), Err(CoonsError::NonFinite { side: Side::Right, index: 2 }));
        // the left side 1 mm off its bottom corner
        let moved: Vec<DVec3> = l.iter().map(|p| *p + DVec3::new(0.001, 0.0, 0.0)).collect();
        match CoonsPatch::new(&b, &t, &moved, &r, &o) {
            Err(CoonsError::OpenCorner { corner: Corner { u: 0, v: 0 }, gap_mm, .. }) => {
                assert!((gap_mm - 1.0).abs() < 1e-9);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(
            CoonsPatch::new(&b, &t, &[DVec3::ZERO], &r, &o),
            Err(CoonsError::OpenCorner {
                corner: Corner { u: 0, v: 1 },
                gap_mm: 1e3,
                tolerance_mm: o.corner_tolerance_mm
            })
        );
        let point = [DVec3::ZERO];
        assert_eq!(
            CoonsPatch::new(&point, &point, &point, &point, &o),
            Err(CoonsError::Degenerate { a: Side::Bottom, b: Side::Top })
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// Planted answer: the patch of rigidly moved (and uniformly scaled) sides is the
        /// moved patch — the expanded form is affine in the points, its blends sum to one.
        #[test]
        fn similarity_motions_commute_with_the_patch(
            axis in (-1.0f64..1.0, -1.0f64..1.0, 0.1f64..1.0),
            angle in -3.1f64..3.1,
            shift in (-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0),
            scale in 0.5f64..2.0,
            (u, v) in (0.0f64..=1.0, 0.0f64..=1.0),
            linear in any::<bool>(),
        ) {
            let blend = if linear { Blend::Linear } else { Blend::Hermite };
            let s = |u: f64, v: f64| DVec3::new(0.5 * u + 0.1 * v * v, 0.4 * v - 0.05 * u, 0.1 * (3.0 * u).sin() * v);
            let rot = glam::DQuat::from_axis_angle(DVec3::new(axis.0, axis.1, axis.2).normalize(), angle);
            let t = DVec3::new(shift.0, shift.1, shift.2);
            let motion = |q: DVec3| rot * q * scale + t;
            let p = patch_of(s, 9, blend);
            let moved = patch_of(|u, v| motion(s(u, v)), 9, blend);
            prop_assert!((moved.at(u, v) - motion(p.at(u, v))).length() < 1e-12);
        }
    }
}
