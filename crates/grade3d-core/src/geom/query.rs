//! Proximity queries on a triangle mesh: closest surface point, and the
//! surface normal averaged over a disc.
//!
//! Closest point on a triangle: Ericson, *Real-Time Collision Detection*
//! §5.1.5 (Voronoi regions of the vertices, edges and face). The plain
//! queries are exhaustive (linear in the face count). [`SphereIndex`] holds
//! every face's bounding sphere and one for each block of [`SPHERE_BLOCK`]
//! consecutive faces, built once per body in linear time: a query skips a
//! block whose sphere lies beyond its reach, and visits the other faces in
//! the same order with the same arithmetic, so its answers are the
//! exhaustive ones bit for bit (a mesh's faces are numbered in spatially
//! coherent runs, so most blocks are skipped: 3–10× fewer faces visited on
//! an hm08 body).
//!
//! [`PointGrid`] answers "is there a point within `r` of `q`" over a point
//! set by a uniform grid of cell `r` (the 27 cells around `q`).
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

/// Faces per block of a [`SphereIndex`].
pub const SPHERE_BLOCK: usize = 32;

/// Bounding spheres of a mesh's faces and of blocks of consecutive faces,
/// for [`SphereIndex::closest_point`] and [`SphereIndex::disc_normal`]
/// (module docs). Built for one mesh; queries with another mesh are
/// answered for the index's own spheres and are meaningless.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereIndex {
    /// Per face: centroid and the distance to its farthest corner.
    faces: Vec<(DVec3, f64)>,
    /// Per block: a centre and a radius that holds every face sphere of it.
    blocks: Vec<(DVec3, f64)>,
}

impl SphereIndex {
    /// The index of `mesh`'s faces.
    pub fn new(mesh: &TriMesh) -> Self {
        let faces: Vec<(DVec3, f64)> = (0..mesh.face_count())
            .map(|f| {
                let [a, b, c] = mesh.corners(FaceId(f as u32));
                let centre = (a + b + c) / 3.0;
                (centre, centre.distance(a).max(centre.distance(b)).max(centre.distance(c)))
            })
            .collect();
        let blocks = faces
            .chunks(SPHERE_BLOCK)
            .map(|chunk| {
                let centre = chunk.iter().map(|s| s.0).sum::<DVec3>() / chunk.len() as f64;
                let radius = chunk.iter().map(|s| s.0.distance(centre) + s.1).fold(0.0, f64::max);
                // a rounding margin: a block is skipped only where each of its faces would be
                (centre, radius * (1.0 + 1e-9) + 1e-12 * centre.length())
            })
            .collect();
        Self { faces, blocks }
    }

    /// Visits, in face order, every face whose bounding sphere comes within
    /// `reach` of `p`; `visit` returns the reach from then on (a closest-point
    /// search narrows it). A block is skipped only where each of its faces
    /// would be.
    fn visit_within(&self, p: DVec3, mut reach: f64, mut visit: impl FnMut(FaceId) -> f64) {
        for (k, &(bc, br)) in self.blocks.iter().enumerate() {
            if bc.distance(p) - br > reach {
                continue;
            }
            let start = k * SPHERE_BLOCK;
            let end = (start + SPHERE_BLOCK).min(self.faces.len());
            for (f, &(centre, rad)) in self.faces[start..end].iter().enumerate() {
                if centre.distance(p) - rad > reach {
                    continue;
                }
                reach = visit(FaceId((start + f) as u32));
            }
        }
    }

    /// [`closest_point`] of `mesh` (the mesh this index was built for) to `p`.
    pub fn closest_point(&self, mesh: &TriMesh, p: DVec3) -> SurfacePoint {
        let mut best = SurfacePoint { face: FaceId(0), point: DVec3::ZERO, distance: f64::INFINITY };
        self.visit_within(p, f64::INFINITY, |face| {
            let [a, b, c] = mesh.corners(face);
            let q = closest_on_triangle(p, a, b, c);
            let d = q.distance(p);
            if d < best.distance {
                best = SurfacePoint { face, point: q, distance: d };
            }
            best.distance
        });
        best
    }

    /// [`disc_normal`] of `mesh` (the mesh this index was built for) at `p`.
    pub fn disc_normal(&self, mesh: &TriMesh, p: DVec3, radius: f64) -> Option<DVec3> {
        let mut sum = DVec3::ZERO;
        self.visit_within(p, radius, |face| {
            let [a, b, c] = mesh.corners(face);
            let d = closest_on_triangle(p, a, b, c).distance(p);
            if d <= radius {
                sum += mesh.face_area_vector(face) * (1.0 - (d / radius).powi(2));
            }
            radius
        });
        sum.try_normalize().or_else(|| mesh.face_area_vector(self.closest_point(mesh, p).face).try_normalize())
    }
}

/// Points hashed into a uniform grid of cell `r` (module docs): the
/// points within `r` of a query are in the 27 cells around it.
#[derive(Debug, Clone)]
pub struct PointGrid {
    cell: f64,
    cells: std::collections::HashMap<[i64; 3], Vec<usize>>,
    points: Vec<DVec3>,
}

impl PointGrid {
    /// The grid of `points` with cells of side `r` (> 0, m).
    pub fn new(points: &[DVec3], r: f64) -> Self {
        let mut cells: std::collections::HashMap<[i64; 3], Vec<usize>> = std::collections::HashMap::new();
        for (i, &p) in points.iter().enumerate() {
            cells.entry(Self::key(p, r)).or_default().push(i);
        }
        Self { cell: r, cells, points: points.to_vec() }
    }

    fn key(p: DVec3, r: f64) -> [i64; 3] {
        (p / r).floor().as_i64vec3().to_array()
    }

    /// The index of the point nearest to `q` among those within `r` of it
    /// (`r` at most the cell size; ties to the lower index), if any.
    pub fn nearest_within(&self, q: DVec3, r: f64) -> Option<usize> {
        let c = Self::key(q, self.cell);
        let mut best: Option<(f64, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else { continue };
                    for &i in list {
                        let d = self.points[i].distance(q);
                        if d <= r && best.is_none_or(|(bd, bi)| d < bd || (d == bd && i < bi)) {
                            best = Some((d, i));
                        }
                    }
                }
            }
        }
        best.map(|(_, i)| i)
    }

    /// Every point within `r` of `q` (`r` at most the cell size), with its
    /// distance, in no particular order.
    pub fn within(&self, q: DVec3, r: f64) -> Vec<(usize, f64)> {
        let c = Self::key(q, self.cell);
        let mut out = Vec::new();
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else { continue };
                    out.extend(list.iter().map(|&i| (i, self.points[i].distance(q))).filter(|&(_, d)| d <= r));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `PointGrid::within` against a brute-force search: a 10 × 10 × 10
    /// lattice 1 mm apart, queries off the lattice, radius up to the cell.
    #[test]
    fn point_grid_within_finds_what_brute_force_finds() {
        let points = lattice();
        let grid = PointGrid::new(&points, 2e-3);
        for (q, r) in [(DVec3::splat(4.3e-3), 2e-3), (DVec3::new(0.2e-3, 9.1e-3, 5.5e-3), 1.5e-3), (DVec3::ZERO, 1e-3)]
        {
            let mut got: Vec<usize> = grid.within(q, r).into_iter().map(|(i, _)| i).collect();
            got.sort_unstable();
            let want: Vec<usize> = (0..points.len()).filter(|&i| points[i].distance(q) <= r).collect();
            assert_eq!(got, want, "{q} {r}");
        }
        // the lattice point and its six neighbours 1 mm away
        assert_eq!(grid.within(DVec3::splat(5e-3), 1e-3 + 1e-12).len(), 7);
    }

    /// `PointGrid::nearest_within` against a brute-force search (the
    /// symmetrisation's partner search, `refine::symmetry`): on the same
    /// lattice, the nearest point where it lies within `r` (ties to the lower
    /// index: a query midway between two lattice points), else none.
    #[test]
    fn nearest_within_is_the_brute_force_nearest_within_reach() {
        let points = lattice();
        let grid = PointGrid::new(&points, 2e-3);
        let brute = |q: DVec3, r: f64| {
            (0..points.len())
                .map(|i| (i, points[i].distance(q)))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .filter(|&(_, d)| d <= r)
                .map(|(i, _)| i)
        };
        for k in 0..200 {
            let t = f64::from(k);
            let q = DVec3::new(
                (t * 0.37).rem_euclid(11.0) - 0.5,
                (t * 0.61).rem_euclid(11.0) - 0.5,
                (t * 0.23).rem_euclid(11.0) - 0.5,
            ) * 1e-3;
            for r in [0.3e-3, 1e-3, 2e-3] {
                assert_eq!(grid.nearest_within(q, r), brute(q, r), "{q} {r}");
            }
        }
        // midway between lattice points 0 and 1: the lower index
        assert_eq!(grid.nearest_within(DVec3::new(0.5e-3, 0.0, 0.0), 1e-3), Some(0));
        // beyond reach of every point
        assert_eq!(grid.nearest_within(DVec3::splat(-5e-3), 2e-3), None);
    }

    /// A 10 × 10 × 10 lattice of points 1 mm apart, metres.
    fn lattice() -> Vec<DVec3> {
        (0..1000).map(|i| DVec3::new(f64::from(i % 10), f64::from(i / 10 % 10), f64::from(i / 100)) * 1e-3).collect()
    }

    #[test]
    fn closest_on_triangle_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(closest_on_triangle(DVec3::new(-1.0, -1.0, 3.0), a, b, c), a);
        assert_eq!(closest_on_triangle(DVec3::new(0.25, 0.25, 3.0), a, b, c), DVec3::new(0.25, 0.25, 0.0));
        assert_eq!(closest_on_triangle(DVec3::new(0.5, -2.0, 0.0), a, b, c), DVec3::new(0.5, 0.0, 0.0));
        let q = closest_on_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((q - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
    }

    /// A lumpy UV sphere of radius about 0.3 (metres), `n` × `2n` quads.
    fn lumpy_sphere(n: u32) -> TriMesh {
        use super::super::mesh::VertexId;
        let mut pos = Vec::new();
        for i in 0..=n {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..2 * n {
                let ph = std::f64::consts::PI * j as f64 / n as f64;
                let r = 0.3 * (1.0 + 0.1 * (3.0 * th).sin() * (5.0 * ph).cos());
                pos.push(DVec3::new(r * th.sin() * ph.cos(), r * th.cos(), r * th.sin() * ph.sin()));
            }
        }
        let at = |i: u32, j: u32| VertexId(i * 2 * n + j % (2 * n));
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..2 * n {
                tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        TriMesh::new(pos, tris).expect("sphere")
    }

    #[test]
    fn the_sphere_index_answers_as_the_exhaustive_queries_bit_for_bit() {
        let mesh = lumpy_sphere(40);
        let index = SphereIndex::new(&mesh);
        // query points inside, on and outside the surface (a fixed linear congruential walk)
        let mut x: u64 = 12345;
        let mut next = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..300 {
            let p = DVec3::new(next(), next(), next()) * 0.45;
            assert_eq!(index.closest_point(&mesh, p), closest_point(&mesh, p), "{p}");
            for r in [0.005, 0.02, 0.1] {
                assert_eq!(index.disc_normal(&mesh, p, r), disc_normal(&mesh, p, r), "{p} {r}");
            }
        }
        // on the surface: the vertices themselves
        for v in (0..mesh.vertex_count()).step_by(37) {
            let p = mesh.positions()[v];
            assert_eq!(index.closest_point(&mesh, p), closest_point(&mesh, p));
            assert_eq!(index.disc_normal(&mesh, p, 0.02), disc_normal(&mesh, p, 0.02));
        }
    }

    #[test]
    fn point_grid_finds_the_nearest_within_reach() {
        let pts = [DVec3::ZERO, DVec3::new(0.1, 0.0, 0.0), DVec3::new(0.1, 0.05, 0.0), DVec3::new(-0.35, 0.0, 0.0)];
        let g = PointGrid::new(&pts, 0.1);
        assert_eq!(g.nearest_within(DVec3::new(0.09, 0.01, 0.0), 0.1), Some(1));
        assert_eq!(g.nearest_within(DVec3::new(-0.3, 0.0, 0.0), 0.1), Some(3));
        // beyond reach, and exactly at it
        assert_eq!(g.nearest_within(DVec3::new(-0.2, 0.0, 0.0), 0.1), None);
        assert_eq!(g.nearest_within(DVec3::new(0.0, 0.0, 0.1), 0.1), Some(0));
    }
}
