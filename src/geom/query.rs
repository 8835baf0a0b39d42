//! Proximity queries on a triangle mesh: closest surface point, and the
//! surface normal averaged over a disc.
//!
//! Closest point on a triangle: Ericson, *Real-Time Collision Detection*
//! §5.1.5 (Voronoi regions of the vertices, edges and face). The queries
//! are exhaustive (linear in the face count): they run a few dozen times
//! per body, where building an acceleration structure would cost more.
//!
//! The disc-averaged normal `n(q) = normalize(Σ_f A_f n_f)` over the faces
//! whose closest point lies within radius `r` of `q` does not depend on how
//! finely the surface is meshed, which keeps the local frames of seed 000
//! Eq. (1) stable between a body and a re-meshed copy of it.

use glam::DVec3;

use super::mesh::{FaceId, TriMesh};

/// The closest point of a mesh to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The triangle it lies on.
    pub face: FaceId,
    /// The point.
    pub point: DVec3,
    /// Its distance to the query.
    pub distance: f64,
}

/// Closest point to `p` on triangle `(a, b, c)`.
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + v * ab;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + w * ac;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + w * (c - b);
    }
    let denom = va + vb + vc;
    if denom.abs() <= f64::MIN_POSITIVE {
        return a;
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

/// The closest point of `mesh` to `p`.
pub fn closest_point(mesh: &TriMesh, p: DVec3) -> SurfacePoint {
    let mut best = SurfacePoint { face: FaceId(0), point: DVec3::ZERO, distance: f64::INFINITY };
    for f in 0..mesh.face_count() {
        let face = FaceId(f as u32);
        let [a, b, c] = mesh.corners(face);
        // cheap reject by bounding sphere of the triangle
        let centre = (a + b + c) / 3.0;
        let rad = centre.distance(a).max(centre.distance(b)).max(centre.distance(c));
        if centre.distance(p) - rad > best.distance {
            continue;
        }
        let q = closest_on_triangle(p, a, b, c);
        let d = q.distance(p);
        if d < best.distance {
            best = SurfacePoint { face, point: q, distance: d };
        }
    }
    best
}

/// Mean unit normal of the faces within `radius` of `p`, each weighted by
/// its area and by the Epanechnikov kernel `1 − (d/r)²` of the distance `d`
/// from `p` to its closest point: a face's weight falls to zero as it
/// leaves the disc, so the normal moves continuously with `p` and with the
/// body (a face counted whole or not at all made Eq. 1 frames, and the
/// template nodes placed by them, jump between consecutive sizes of a
/// grade). Falls back to the normal of the closest face when no face lies
/// within the radius or the sum vanishes. `None` only if every face is
/// degenerate there.
pub fn disc_normal(mesh: &TriMesh, p: DVec3, radius: f64) -> Option<DVec3> {
    let mut sum = DVec3::ZERO;
    for f in 0..mesh.face_count() {
        let face = FaceId(f as u32);
        let [a, b, c] = mesh.corners(face);
        let centre = (a + b + c) / 3.0;
        let rad = centre.distance(a).max(centre.distance(b)).max(centre.distance(c));
        if centre.distance(p) - rad > radius {
            continue;
        }
        let d = closest_on_triangle(p, a, b, c).distance(p);
        if d <= radius {
            sum += mesh.face_area_vector(face) * (1.0 - (d / radius).powi(2));
        }
    }
    sum.try_normalize().or_else(|| mesh.face_area_vector(closest_point(mesh, p).face).try_normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_on_triangle_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(closest_on_triangle(DVec3::new(-1.0, -1.0, 3.0), a, b, c), a);
        assert_eq!(closest_on_triangle(DVec3::new(0.25, 0.25, 3.0), a, b, c), DVec3::new(0.25, 0.25, 0.0));
        assert_eq!(closest_on_triangle(DVec3::new(0.5, -2.0, 0.0), a, b, c), DVec3::new(0.5, 0.0, 0.0));
        let q = closest_on_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((q - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
    }
}
