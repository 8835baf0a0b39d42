//! A CPU depth-map rasteriser (issue #15): the [`DepthRenderer`] for
//! machines whose only wgpu adapter is itself a CPU driver (Mesa's llvmpipe
//! or lavapipe), where drawing through wgpu costs a driver, a shader
//! compiler and a read-back for what a direct rasteriser does in a fraction
//! of the time.
//!
//! # Method
//!
//! The same orthographic views and the same pixels as the wgpu renderer
//! (`grade3d-render`): per view ([`View::set`]), every triangle is scanned
//! over the pixel centres inside its bounding box; a centre `s` is covered
//! when its barycentric coordinates
//!
//! `λ_a = E(b, c, s) / E(a, b, c)`, `λ_b = E(c, a, s) / E(a, b, c)`,
//! `λ_c = 1 − λ_a − λ_b`, with `E(p, q, r) = (q − p) × (r − p)` (2D),
//!
//! are all ≥ 0 (both orientations: no culling, as the wgpu passes), and its
//! depth is `z = λ_a z_a + λ_b z_b + λ_c z_c` (exact for an orthographic
//! view). The barycentric coordinates and `z` are linear in the pixel
//! centre, so each row is stepped along `x` by adding their `x`
//! derivatives. Per pixel the nearest surface (least `z`, the wgpu pass
//! with depth test *Less*) and the farthest (greatest `z`, *Greater*) keep
//! their depth (single precision, as a GPU's depth buffer) and their face;
//! the normal stored is the face's vertex normals interpolated at the pixel
//! centre and normalised (as the wgpu fragment shader does). Depth and
//! normal are encoded as the wgpu renderer stores them
//! ([`encode_depth_code`], [`encode_normal`]).
//!
//! The image is cut into bands of 32 rows (`BAND_ROWS`); each triangle is
//! binned into the bands its rows reach, and the bands are rasterised side
//! by side on rayon's pool (the process's one thread budget), each in a
//! scratch buffer that stays in cache, and copied into the map's runs as
//! depth and face per pixel ([`DepthMap::from_bands`]), with each face's
//! normal as a function of the pixel centre: the map encodes a pixel's
//! depth and normal when it is read, as the GPU path stores them (issue
//! #15: encoding every covered pixel was half the rasteriser's time, and
//! the collision reads a few thousand of them).
//!
//! Differences from a GPU, within the golden test's tolerances
//! (`tests/collide.rs`): pixel centres exactly on an edge are covered by
//! both faces (a GPU's top-left rule gives them to one), which only
//! matters on the silhouette.
//!
//! Cost: one pass over the triangles per view and one over the covered
//! pixels (the female fixture scan, 26,756 faces, two views at 1024²: about
//! 30 ms on two cores, against 55–66 ms for wgpu on llvmpipe or lavapipe,
//! `benches/collide.rs`).
//!
//! # Failure modes
//!
//! A resolution outside `16..=`[`MAX_RESOLUTION`] is refused
//! ([`RasterError::Resolution`]), as the wgpu renderer refuses what its
//! device cannot hold. Degenerate (zero-area) triangles cover nothing.

use glam::DVec3;
use rayon::prelude::*;

use super::depth::{BandRows, DepthMap, FaceNormal, View, NO_FACE};
use super::{DepthRenderer, RenderOptions};
use crate::geom::mesh::TriMesh;

/// Largest resolution [`CpuRasteriser`] renders, pixels a side (a GPU's
/// usual 2D texture limit; at 8192² one view holds 1.6 GB while it runs).
pub const MAX_RESOLUTION: u32 = 8192;

/// Smallest resolution, pixels a side (as the wgpu renderer's).
pub const MIN_RESOLUTION: u32 = 16;

/// Why the CPU rasteriser refused to render.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RasterError {
    /// The resolution is outside what it renders.
    #[error("depth-map resolution {requested} is outside {MIN_RESOLUTION}..={MAX_RESOLUTION}")]
    Resolution {
        /// Requested, pixels a side.
        requested: u32,
    },
}

/// The CPU depth-map renderer (module docs). It holds nothing: every call
/// rasterises its mesh afresh.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CpuRasteriser;

impl DepthRenderer for CpuRasteriser {
    type Error = RasterError;

    fn depth_maps(&self, mesh: &TriMesh, opts: &RenderOptions) -> Result<Vec<DepthMap>, RasterError> {
        let n = opts.resolution;
        if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&n) {
            return Err(RasterError::Resolution { requested: n });
        }
        let bb = mesh.aabb();
        let views = View::set(opts.views, bb.min, bb.max, opts.padding_mm * 1e-3);
        let normals = mesh.vertex_normals();
        Ok(views.par_iter().map(|view| rasterise(mesh, &normals, view, n)).collect())
    }
}

/// A vertex in pixel coordinates: `x` right and `y` down from the image's
/// top-left corner (pixel `(i, j)` has its centre at `(i + ½, j + ½)`),
/// `z` the clip depth in `[0, 1]` (0 nearest the camera).
#[derive(Debug, Clone, Copy)]
struct Pixel {
    x: f64,
    y: f64,
    z: f64,
}

/// The view's pixel coordinates of `p` at `n` pixels a side.
fn to_pixel(view: &View, n: f64, p: DVec3) -> Pixel {
    let span = |r: [f64; 2]| r[1] - r[0];
    Pixel {
        x: (p.dot(view.u) - view.u_range[0]) / span(view.u_range) * n,
        y: (view.w_range[1] - p.dot(view.w)) / span(view.w_range) * n,
        z: (view.d_range[1] - p.dot(view.d)) / span(view.d_range),
    }
}

/// A triangle set up for scanning: its three edge functions and its depth
/// plane, each `f(x, y) = f₀ + f_x x + f_y y` at pixel coordinates, the
/// edge functions scaled by `1 / E(a, b, c)` so that they are the
/// barycentric coordinates `λ_a, λ_b, λ_c` (module docs).
#[derive(Debug, Clone, Copy)]
struct Setup {
    /// `[f₀, f_x, f_y]` of `λ_a` and `λ_b` (`λ_c = 1 − λ_a − λ_b`).
    lambda: [[f64; 3]; 2],
    /// `[f₀, f_x, f_y]` of the depth.
    z: [f64; 3],
}

impl Setup {
    /// `None` for a zero-area (or non-finite) triangle.
    fn new([a, b, c]: [Pixel; 3]) -> Option<Self> {
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area == 0.0 || !area.is_finite() {
            return None;
        }
        let inv = 1.0 / area;
        // E(p, q, s) = (q.x − p.x)(s.y − p.y) − (q.y − p.y)(s.x − p.x), linear in s
        let edge = |p: Pixel, q: Pixel| {
            let (dx, dy) = (q.x - p.x, q.y - p.y);
            [(dy * p.x - dx * p.y) * inv, -dy * inv, dx * inv]
        };
        let (la, lb) = (edge(b, c), edge(c, a));
        let z = std::array::from_fn(|k| la[k] * (a.z - c.z) + lb[k] * (b.z - c.z) + if k == 0 { c.z } else { 0.0 });
        Some(Self { lambda: [la, lb], z })
    }
}

/// Rows of one band: the triangles are binned by the bands their rows
/// reach and each band is rasterised on its own (its buffers stay in cache,
/// and bands run side by side on rayon's pool).
const BAND_ROWS: usize = 32;

/// A triangle ready to scan: its setup and its pixel-centre bounds.
#[derive(Debug, Clone, Copy)]
struct Scan {
    setup: Setup,
    /// First and last pixel column whose centre is within its bounds.
    x: [usize; 2],
    /// First and last pixel row.
    y: [usize; 2],
}

/// One view's depth map (module docs).
fn rasterise(mesh: &TriMesh, normals: &[DVec3], view: &View, n: u32) -> DepthMap {
    let side = n as usize;
    let nf = f64::from(n);
    let px: Vec<Pixel> = mesh.positions().iter().map(|&p| to_pixel(view, nf, p)).collect();
    // pixel centres i + ½ within [min, max]
    let first = |lo: f64| ((lo - 0.5).ceil().max(0.0)) as usize;
    let last = |hi: f64| (hi - 0.5).floor().min(nf - 1.0);
    let scans: Vec<Option<Scan>> = mesh
        .triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| px[v.idx()]);
            let setup = Setup::new([a, b, c])?;
            let (x_hi, y_hi) = (last(a.x.max(b.x).max(c.x)), last(a.y.max(b.y).max(c.y)));
            let (x0, y0) = (first(a.x.min(b.x).min(c.x)), first(a.y.min(b.y).min(c.y)));
            if x_hi < x0 as f64 || y_hi < y0 as f64 {
                return None;
            }
            Some(Scan { setup, x: [x0, x_hi as usize], y: [y0, y_hi as usize] })
        })
        .collect();
    // Σ λ_k n_k = n_c + λ_a (n_a − n_c) + λ_b (n_b − n_c), each λ linear in (x, y); read by the
    // map when a pixel is (zero for a face that covers nothing)
    let face_normals: Vec<FaceNormal> = mesh
        .triangles()
        .iter()
        .zip(&scans)
        .map(|(t, scan)| {
            let Some(sc) = scan else { return [glam::Vec3::ZERO; 3] };
            let [na, nb, nc] = t.map(|v| normals[v.idx()]);
            let [la, lb] = sc.setup.lambda;
            std::array::from_fn(|k| {
                let base = if k == 0 { nc } else { DVec3::ZERO };
                (base + (na - nc) * la[k] + (nb - nc) * lb[k]).as_vec3()
            })
        })
        .collect();
    // the faces of each band, in face order (counting sort)
    let bands = side.div_ceil(BAND_ROWS);
    let mut start = vec![0usize; bands + 1];
    for sc in scans.iter().flatten() {
        for b in sc.y[0] / BAND_ROWS..=sc.y[1] / BAND_ROWS {
            start[b + 1] += 1;
        }
    }
    for b in 0..bands {
        start[b + 1] += start[b];
    }
    let mut fill = start.clone();
    let mut faces = vec![0u32; start[bands]];
    for (f, sc) in scans.iter().enumerate() {
        let Some(sc) = sc else { continue };
        for b in sc.y[0] / BAND_ROWS..=sc.y[1] / BAND_ROWS {
            faces[fill[b]] = f as u32;
            fill[b] += 1;
        }
    }
    let parts: Vec<BandRows> = (0..bands)
        .into_par_iter()
        .map_init(
            || Scratch::new(BAND_ROWS * side),
            |scratch, b| {
                let rows = (b * BAND_ROWS)..((b + 1) * BAND_ROWS).min(side);
                rasterise_band(&scans, &faces[start[b]..start[b + 1]], rows, side, scratch)
            },
        )
        .collect();
    DepthMap::from_bands(*view, n, n, parts, face_normals)
}

/// Per pixel of a band while it is rasterised: the least and greatest clip
/// depth and their faces.
struct Scratch {
    front_z: Vec<f32>,
    front_face: Vec<u32>,
    back_z: Vec<f32>,
    back_face: Vec<u32>,
}

impl Scratch {
    fn new(pixels: usize) -> Self {
        Self {
            front_z: vec![f32::INFINITY; pixels],
            front_face: vec![NO_FACE; pixels],
            back_z: vec![f32::NEG_INFINITY; pixels],
            back_face: vec![NO_FACE; pixels],
        }
    }

    /// Every pixel empty again (a worker's scratch is reused band after band).
    fn clear(&mut self) {
        self.front_z.fill(f32::INFINITY);
        self.front_face.fill(NO_FACE);
        self.back_z.fill(f32::NEG_INFINITY);
        self.back_face.fill(NO_FACE);
    }
}

/// Rasterises `faces` over `rows` of the image (`side` pixels wide) and
/// encodes the band's runs.
fn rasterise_band(
    scans: &[Option<Scan>],
    faces: &[u32],
    rows: std::ops::Range<usize>,
    side: usize,
    s: &mut Scratch,
) -> BandRows {
    s.clear();
    for &f in faces {
        let Some(sc) = scans[f as usize] else { continue };
        let st = sc.setup;
        let [la, lb] = st.lambda;
        let sx0 = sc.x[0] as f64 + 0.5;
        for y in sc.y[0].max(rows.start)..=sc.y[1].min(rows.end - 1) {
            let sy = y as f64 + 0.5;
            let row = (y - rows.start) * side;
            // the barycentric coordinates and depth at the row's first centre, then stepped along x
            let (mut wa, mut wb) = (la[0] + la[1] * sx0 + la[2] * sy, lb[0] + lb[1] * sx0 + lb[2] * sy);
            let mut z = st.z[0] + st.z[1] * sx0 + st.z[2] * sy;
            // the row's pixels as slices, zipped: no bounds check nor reload per pixel
            let span = row + sc.x[0]..row + sc.x[1] + 1;
            let pixels = s.front_z[span.clone()]
                .iter_mut()
                .zip(&mut s.front_face[span.clone()])
                .zip(s.back_z[span.clone()].iter_mut().zip(&mut s.back_face[span]));
            for ((fz, ff), (bz, bf)) in pixels {
                if wa >= 0.0 && wb >= 0.0 && wa + wb <= 1.0 {
                    let zf = z as f32;
                    if zf < *fz {
                        *fz = zf;
                        *ff = f;
                    }
                    if zf > *bz {
                        *bz = zf;
                        *bf = f;
                    }
                }
                wa += la[1];
                wb += lb[1];
                z += st.z[1];
            }
        }
    }
    let runs: Vec<Option<(usize, usize)>> = rows
        .clone()
        .map(|y| {
            let row = (y - rows.start) * side;
            let faces = &s.front_face[row..row + side];
            let x0 = faces.iter().position(|&f| f != NO_FACE)?;
            let x1 = faces.iter().rposition(|&f| f != NO_FACE)?;
            Some((x0, x1 + 1))
        })
        .collect();
    let stored: usize = runs.iter().flatten().map(|(x0, x1)| x1 - x0).sum();
    let (mut z, mut face) = (Vec::with_capacity(stored), Vec::with_capacity(stored));
    for (y, run) in rows.clone().zip(&runs) {
        let row = (y - rows.start) * side;
        let Some((x0, x1)) = *run else { continue };
        for i in row + x0..row + x1 {
            z.push([s.front_z[i], s.back_z[i]]);
            face.push([s.front_face[i], s.back_face[i]]);
        }
    }
    BandRows { runs, z, face }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::depth::{inside, ViewSet};

    fn opts(resolution: u32) -> RenderOptions {
        RenderOptions { resolution, views: ViewSet::FrontBackSides, padding_mm: 20.0 }
    }

    #[test]
    fn a_cube_reads_its_faces_exactly_and_its_inside() {
        // an axis-aligned 0.2 m cube: every covered pixel's front is its +d face and its
        // back its −d face, to the depth code; its middle is inside, a point beside it is not
        let c = [
            [-0.1, -0.1, -0.1],
            [0.1, -0.1, -0.1],
            [0.1, 0.1, -0.1],
            [-0.1, 0.1, -0.1],
            [-0.1, -0.1, 0.1],
            [0.1, -0.1, 0.1],
            [0.1, 0.1, 0.1],
            [-0.1, 0.1, 0.1],
        ]
        .map(DVec3::from_array);
        let faces = [
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [3, 6, 2],
            [3, 7, 6],
            [0, 4, 7],
            [0, 7, 3],
            [1, 2, 6],
            [1, 6, 5],
        ];
        let cube = TriMesh::from_raw(c.to_vec(), &faces).expect("cube");
        let maps = CpuRasteriser.depth_maps(&cube, &opts(64)).expect("maps");
        assert_eq!(maps.len(), 2);
        for m in &maps {
            let step = (m.view.d_range[1] - m.view.d_range[0]) / crate::collide::depth::DEPTH_CODES;
            let mut covered = 0;
            for i in 0..(m.width * m.height) as usize {
                let (Some(f), Some(b)) = (m.front_depth(i), m.back_depth(i)) else { continue };
                covered += 1;
                assert!((f - 0.1).abs() <= 2.0 * step + 1e-6, "front {f}");
                assert!((b + 0.1).abs() <= 2.0 * step + 1e-6, "back {b}");
            }
            // 0.2 m of a 0.24 m wide image at 64 px: 53 or 54 pixels a side
            assert!((53 * 53..=54 * 54).contains(&covered), "{covered} pixels covered");
        }
        assert!(inside(&maps, DVec3::ZERO).is_some());
        let probe = inside(&maps, DVec3::new(0.0, 0.0, 0.095)).expect("inside near the front");
        assert!((probe.escape - 0.005).abs() < 1e-4, "{probe:?}");
        assert!(probe.normal.dot(DVec3::Z) > 0.5, "{probe:?}");
        assert!(inside(&maps, DVec3::new(0.0, 0.0, 0.105)).is_none());
        assert!(inside(&maps, DVec3::new(0.105, 0.0, 0.0)).is_none());
    }

    #[test]
    fn resolutions_outside_the_range_are_refused() {
        let m = TriMesh::icosahedron();
        for n in [0, 15, MAX_RESOLUTION + 1] {
            assert_eq!(CpuRasteriser.depth_maps(&m, &opts(n)).unwrap_err(), RasterError::Resolution { requested: n });
        }
        assert!(CpuRasteriser.depth_maps(&m, &opts(16)).is_ok());
    }
}
