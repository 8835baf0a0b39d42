//! Oriented planes and least-squares plane fitting.
//!
//! A plane is `{x : n·x = d}` with unit normal `n`. [`Plane::fit`] is the
//! total-least-squares fit: the normal is the eigenvector of the smallest
//! eigenvalue of the points' covariance matrix `C = Σ (p−c)(p−c)ᵀ`
//! (Jacobi rotations on the 3×3 symmetric matrix).
//!
//! Failure mode: fewer than three points, or collinear points, give no
//! unique plane; [`Plane::fit`] then returns `None` and callers pick a rule
//! of their own (e.g. a horizontal plane through the mean).

use glam::{DMat3, DVec3};

/// An oriented plane `n·x = d`, `|n| = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Unit normal.
    pub normal: DVec3,
    /// Offset: `normal · x` for every point `x` on the plane.
    pub offset: f64,
}

/// Relative size of the second-smallest covariance eigenvalue below which
/// points count as collinear in [`Plane::fit`].
pub const COLLINEAR_TOLERANCE: f64 = 1e-10;

impl Plane {
    /// The plane through `point` with normal `normal` (normalised here).
    /// Returns `None` for a zero or non-finite normal.
    pub fn from_point_normal(point: DVec3, normal: DVec3) -> Option<Self> {
        let n = normal.try_normalize()?;
        Some(Self { normal: n, offset: n.dot(point) })
    }

    /// Signed distance `n·x − d`.
    #[inline]
    pub fn signed_distance(&self, x: DVec3) -> f64 {
        self.normal.dot(x) - self.offset
    }

    /// Orthogonal projection of `x` onto the plane.
    #[inline]
    pub fn project(&self, x: DVec3) -> DVec3 {
        x - self.signed_distance(x) * self.normal
    }

    /// The same plane with the normal pointing the other way.
    pub fn flipped(&self) -> Self {
        Self { normal: -self.normal, offset: -self.offset }
    }

    /// The same plane oriented so that `normal · towards ≥ 0`.
    pub fn oriented_towards(&self, towards: DVec3) -> Self {
        if self.normal.dot(towards) < 0.0 {
            self.flipped()
        } else {
            *self
        }
    }

    /// An orthonormal basis `(u, v)` of the plane with `u × v = n`.
    pub fn basis(&self) -> (DVec3, DVec3) {
        let n = self.normal;
        let helper = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let u = helper.cross(n).normalize();
        let v = n.cross(u);
        (u, v)
    }

    /// The plane that mirrors each left point `l` of `pairs` `(l, r)` onto
    /// its right point `r`, in the mean: normal
    ///
    /// ```text
    /// n = Σ (l − r) / |Σ (l − r)|,   made perpendicular to `upright` first where given
    /// d = (1/k) Σ n·(l + r)/2
    /// ```
    ///
    /// (a body's or garment's mid-sagittal plane from its left/right
    /// feature points or nodes; `upright` the body's up, for a plane that
    /// stands upright whatever the pairs' heights). Exact for pairs that
    /// mirror across one plane. `None` without pairs, or where the `l − r`
    /// cancel (or lie along `upright`).
    pub fn bisecting(pairs: &[(DVec3, DVec3)], upright: Option<DVec3>) -> Option<Self> {
        let mut across = pairs.iter().map(|(l, r)| *l - *r).sum::<DVec3>();
        if let Some(up) = upright.and_then(DVec3::try_normalize) {
            across -= across.dot(up) * up;
        }
        let n = across.try_normalize()?;
        let d = pairs.iter().map(|(l, r)| n.dot(0.5 * (*l + *r))).sum::<f64>() / pairs.len() as f64;
        Some(Self { normal: n, offset: d })
    }

    /// Total-least-squares plane through the points; `None` if fewer than
    /// three points or they are (numerically) collinear.
    pub fn fit(points: &[DVec3]) -> Option<Self> {
        if points.len() < 3 {
            return None;
        }
        let c = points.iter().copied().sum::<DVec3>() / points.len() as f64;
        let mut m = DMat3::ZERO;
        for p in points {
            let d = *p - c;
            m += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let (vals, vecs) = symmetric_eigen(m);
        // vals sorted ascending
        let scale = vals[2].abs().max(f64::MIN_POSITIVE);
        if vals[1] / scale < COLLINEAR_TOLERANCE {
            return None;
        }
        Self::from_point_normal(c, vecs[0])
    }
}

/// Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations.
/// Returns eigenvalues ascending and the matching unit eigenvectors.
#[expect(clippy::needless_range_loop, reason = "Jacobi rotations index rows and columns as in the textbook formulas")]
pub fn symmetric_eigen(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let mut a = m.to_cols_array_2d(); // a[col][row]; symmetric so fine
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        if off < 1e-30 * (a[0][0].powi(2) + a[1][1].powi(2) + a[2][2].powi(2)).max(f64::MIN_POSITIVE) {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            if a[p][q].abs() < f64::MIN_POSITIVE {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let akp = a[k][p];
                let akq = a[k][q];
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[p][k];
                let aqk = a[q][k];
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let vp = row[p];
                let vq = row[q];
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let vals = idx.map(|i| a[i][i]);
    let vecs = idx.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i]).normalize_or_zero());
    (vals, vecs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bisecting_recovers_a_planted_mirror_plane() {
        let plane = Plane::from_point_normal(DVec3::new(0.02, 1.0, -0.01), DVec3::new(1.0, 0.05, 0.1)).unwrap();
        let mirror = |p: DVec3| p - 2.0 * plane.signed_distance(p) * plane.normal;
        let left: Vec<DVec3> =
            (0..7).map(|i| DVec3::new(0.2 + 0.01 * f64::from(i), 0.3 * f64::from(i), 0.05)).collect();
        let pairs: Vec<(DVec3, DVec3)> = left.iter().map(|&l| (l, mirror(l))).collect();
        let b = Plane::bisecting(&pairs, None).unwrap();
        assert!((b.normal - plane.normal).length() < 1e-12, "{b:?}");
        assert!((b.offset - plane.offset).abs() < 1e-12, "{b:?}");
        // upright: the normal loses its vertical part
        let u = Plane::bisecting(&pairs, Some(DVec3::Y)).unwrap();
        assert!(u.normal.y.abs() < 1e-15 && (u.normal.length() - 1.0).abs() < 1e-12, "{u:?}");
        assert_eq!(Plane::bisecting(&[], None), None);
        let cancel = [(DVec3::X, DVec3::ZERO), (DVec3::ZERO, DVec3::X)];
        assert_eq!(Plane::bisecting(&cancel, None), None);
        assert_eq!(Plane::bisecting(&[(DVec3::Y, DVec3::ZERO)], Some(DVec3::Y)), None);
    }

    #[test]
    fn fit_recovers_planted_plane() {
        let n = DVec3::new(0.2, 1.0, -0.3).normalize();
        let plane = Plane::from_point_normal(DVec3::new(0.1, 1.0, 0.2), n).unwrap();
        let (u, v) = plane.basis();
        let o = plane.project(DVec3::ZERO);
        let pts: Vec<DVec3> = (0..20).map(|i| o + u * (i as f64).sin() + v * (i as f64 * 0.7).cos()).collect();
        let fit = Plane::fit(&pts).unwrap().oriented_towards(n);
        assert!((fit.normal - n).length() < 1e-12);
        assert!((fit.offset - plane.offset).abs() < 1e-12);
    }

    #[test]
    fn collinear_points_have_no_plane() {
        let pts = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0, DVec3::X * 3.5];
        assert!(Plane::fit(&pts).is_none());
        assert!(Plane::fit(&pts[..2]).is_none());
    }

    #[test]
    fn eigen_of_diagonal_and_rotated() {
        let (vals, _) = symmetric_eigen(DMat3::from_diagonal(DVec3::new(3.0, 1.0, 2.0)));
        assert_eq!(vals, [1.0, 2.0, 3.0]);
        let r = DMat3::from_rotation_y(0.3) * DMat3::from_rotation_x(0.4);
        let m = r * DMat3::from_diagonal(DVec3::new(5.0, 0.5, 2.0)) * r.transpose();
        let (vals, vecs) = symmetric_eigen(m);
        assert!((vals[0] - 0.5).abs() < 1e-12 && (vals[2] - 5.0).abs() < 1e-12);
        assert!((m * vecs[0] - vecs[0] * 0.5).length() < 1e-12);
    }
}
