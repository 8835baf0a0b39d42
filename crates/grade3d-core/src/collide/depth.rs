//! Depth maps of a body and the image-based inside test (seed 000 §5.4,
//! Eq. (13)).
//!
//! A [`View`] looks at the body orthographically along its depth axis `d`
//! (towards the camera), with `u` to the right and `w` up on the image.
//! Rendering it twice, once keeping the nearest surface (depth test
//! *Less*) and once the farthest (*Greater*, cleared to 0), gives for every
//! pixel `(X, Y)` the interval `[back(X, Y), front(X, Y)]` of the body
//! along `d` — seed 000's front and back depth buffers. A point `p` is
//! inside the body by Eq. (13) when
//!
//! `back(X, Y) ≤ p·d ≤ front(X, Y)` at its pixel,
//!
//! and, with several views, when that holds in **every** view (each view
//! only over-estimates the body: concavities hidden along its axis read as
//! inside; intersecting views removes most of them).
//!
//! This module is pure data: the maps arrive from the renderer
//! (`grade3d-render`'s wgpu renderer, [`super::raster`]) or from tests.
//! Empty pixels hold NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// An orthographic view of the body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Image right, unit.
    pub u: DVec3,
    /// Image up, unit.
    pub w: DVec3,
    /// Depth axis, towards the camera, unit (`u × w`).
    pub d: DVec3,
    /// World range along `u` covered by the image, m.
    pub u_range: [f64; 2],
    /// World range along `w`, m.
    pub w_range: [f64; 2],
    /// World range along `d` mapped to depth [1, 0], m.
    pub d_range: [f64; 2],
}

/// Which views to render.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViewSet {
    /// Front and back (seed 000): one view along +Z.
    FrontBack,
    /// Front/back and left/right: views along +Z and +X.
    FrontBackSides,
}

impl View {
    /// The views of a body with bounding box `[lo, hi]`, padded by `pad`.
    pub fn set(set: ViewSet, lo: DVec3, hi: DVec3, pad: f64) -> Vec<View> {
        let (lo, hi) = (lo - DVec3::splat(pad), hi + DVec3::splat(pad));
        let along_z = View {
            u: DVec3::X,
            w: DVec3::Y,
            d: DVec3::Z,
            u_range: [lo.x, hi.x],
            w_range: [lo.y, hi.y],
            d_range: [lo.z, hi.z],
        };
        let along_x = View {
            u: DVec3::NEG_Z,
            w: DVec3::Y,
            d: DVec3::X,
            u_range: [-hi.z, -lo.z],
            w_range: [lo.y, hi.y],
            d_range: [lo.x, hi.x],
        };
        match set {
            ViewSet::FrontBack => vec![along_z],
            ViewSet::FrontBackSides => vec![along_z, along_x],
        }
    }

    /// Clip-space position of a world point: x, y in [−1, 1], depth in
    /// [0, 1] with 0 nearest the camera (largest `p·d`).
    pub fn clip(&self, p: DVec3) -> [f32; 3] {
        let x = 2.0 * (p.dot(self.u) - self.u_range[0]) / (self.u_range[1] - self.u_range[0]) - 1.0;
        let y = 2.0 * (p.dot(self.w) - self.w_range[0]) / (self.w_range[1] - self.w_range[0]) - 1.0;
        let z = (self.d_range[1] - p.dot(self.d)) / (self.d_range[1] - self.d_range[0]);
        [x as f32, y as f32, z as f32]
    }

    /// World coordinate along `d` of a depth value in [0, 1].
    pub fn depth_to_world(&self, z: f64) -> f64 {
        self.d_range[1] - z * (self.d_range[1] - self.d_range[0])
    }
}

/// Front and back depth maps (and normals) of one view.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthMap {
    /// The view.
    pub view: View,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Per image row, its run of stored pixels `[start, x0, x1]`: pixels
    /// `x0..x1` of the row (from its first to its last covered pixel) are
    /// stored from index `start` of the pixel arrays; every other pixel is
    /// empty (issue #15: a body covers 36–42 % of its views' pixels within
    /// such runs, so a body's maps take 13 MB instead of 32).
    rows: Vec<[u32; 3]>,
    /// The stored pixels.
    pixels: Pixels,
}

/// The stored pixels of a [`DepthMap`], in the order of its rows' runs.
#[derive(Debug, Clone, PartialEq)]
enum Pixels {
    /// As a GPU renderer wrote them (RGBA8).
    Encoded {
        /// Nearest surface along `d`: the depth code in RGB (24 bits, R
        /// most significant; [`encode_depth`], [`DepthMap::front_depth`]),
        /// A 255 where the body covers the pixel and 0 where it is empty.
        front: Vec<[u8; 4]>,
        /// Farthest surface along `d`, as `front`.
        back: Vec<[u8; 4]>,
        /// Outward unit normal of the nearest surface: each component
        /// `n·½ + ½` in unorm8 in RGB ([`encode_normal`],
        /// [`decode_normal`]), A unused.
        front_normal: Vec<[u8; 4]>,
        /// Outward unit normal of the farthest surface, as `front_normal`.
        back_normal: Vec<[u8; 4]>,
    },
    /// As the CPU rasteriser left them (issue #15): per pixel the clip
    /// depth and the face of the nearest and the farthest surface, and per
    /// face its interpolated normal as a function of the pixel centre. A
    /// pixel is encoded when it is read, exactly as the GPU path encodes
    /// it ([`encode_depth_code`], [`encode_normal`] of the normalised
    /// normal), so both read the same values; the collision reads a few
    /// thousand of a map's half million stored pixels, and encoding them
    /// all was half of the rasteriser's time.
    Faces {
        /// Clip depth `[nearest, farthest]` per stored pixel.
        z: Vec<[f32; 2]>,
        /// Their faces ([`NO_FACE`] where the pixel is empty).
        face: Vec<[u32; 2]>,
        /// Per face, its vertex normals interpolated,
        /// `n(x, y) = n₀ + n_x x + n_y y` at pixel coordinates (not
        /// normalised).
        normals: Vec<FaceNormal>,
    },
}

/// Face id of an empty pixel in a rasteriser's [`BandRows`].
pub const NO_FACE: u32 = u32::MAX;

/// A face's vertex normals interpolated over a view's pixels:
/// `[n₀, n_x, n_y]`, `n(x, y) = n₀ + n_x x + n_y y` (not normalised) at
/// pixel coordinates (`x` right, `y` down, pixel `(i, j)` centred at
/// `(i + ½, j + ½)`).
pub type FaceNormal = [glam::Vec3; 3];

/// Consecutive rows of a depth map as the CPU rasteriser leaves them
/// ([`DepthMap::from_bands`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BandRows {
    /// Per row its covered run `(x0, x1)`: pixels `x0..x1` from its first
    /// to its last covered pixel; `None` where the row is empty.
    pub runs: Vec<Option<(usize, usize)>>,
    /// The runs' pixels in row order: clip depth of the nearest and the
    /// farthest surface.
    pub z: Vec<[f32; 2]>,
    /// Their faces ([`NO_FACE`] where a pixel inside a run is empty).
    pub face: Vec<[u32; 2]>,
}

/// Largest depth code: depth `z ∈ [0, 1]` is stored as `round(z (2²⁴ − 1))`.
pub const DEPTH_CODES: f64 = 16_777_215.0;

/// A pixel of a [`DepthMap`]'s front or back depth image for the surface at
/// `p·d = world` (m) in `view`: `z = (d_max − world) / (d_max − d_min)`,
/// code `round(z (2²⁴ − 1))`, covered.
pub fn encode_depth(view: &View, world: f64) -> [u8; 4] {
    encode_depth_code((view.d_range[1] - world) / (view.d_range[1] - view.d_range[0]))
}

/// The pixel of [`encode_depth`] for clip depth `z` (clamped to `[0, 1]`):
/// code `round(z (2²⁴ − 1))`, covered. Rounded as `⌊v + ½⌋` (`v ≥ 0`): a
/// cast, not a call to `round` — the CPU rasteriser encodes every covered
/// pixel with it.
#[inline]
pub fn encode_depth_code(z: f64) -> [u8; 4] {
    let code = (z.clamp(0.0, 1.0) * DEPTH_CODES + 0.5) as u32;
    [(code >> 16) as u8, (code >> 8) as u8, code as u8, 255]
}

/// The world coordinate `p·d` (m) of a depth pixel, `None` where empty:
/// `d_max − (code / (2²⁴ − 1)) (d_max − d_min)`, in single precision (the
/// code's 24 bits fit its mantissa).
pub fn decode_depth(view: &View, px: [u8; 4]) -> Option<f64> {
    if px[3] == 0 {
        return None;
    }
    let code = (u32::from(px[0]) << 16) | (u32::from(px[1]) << 8) | u32::from(px[2]);
    Some(f64::from(view.depth_to_world(f64::from(code) / DEPTH_CODES) as f32))
}

/// What the inside test found for a point in one view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Probe {
    /// Inside the interval of its pixel.
    pub inside: bool,
    /// Distance to move along the nearer face's normal to leave the body, m.
    pub escape: f64,
    /// That normal.
    pub normal: DVec3,
}

impl DepthMap {
    /// A map from its full images, row by row, as rendered: `row(y)` gives
    /// row `y` (`width` pixels) of the front depth, back depth, front
    /// normal and back normal images. Each row keeps the run from its first
    /// to its last pixel covered in either depth image.
    pub fn from_rows<'a>(
        view: View,
        width: u32,
        height: u32,
        mut row: impl FnMut(usize) -> [&'a [[u8; 4]]; 4],
    ) -> Self {
        let mut rows = Vec::with_capacity(height as usize);
        let (mut front, mut back, mut front_normal, mut back_normal) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for y in 0..height as usize {
            let [f, b, fnm, bnm] = row(y);
            let covered = |x: &usize| f[*x][3] != 0 || b[*x][3] != 0;
            let w = (width as usize).min(f.len()).min(b.len()).min(fnm.len()).min(bnm.len());
            let start = front.len() as u32;
            let Some(x0) = (0..w).find(covered) else {
                rows.push([start, 0, 0]);
                continue;
            };
            let x1 = (x0..w).rfind(covered).map_or(x0, |x| x + 1);
            front.extend_from_slice(&f[x0..x1]);
            back.extend_from_slice(&b[x0..x1]);
            front_normal.extend_from_slice(&fnm[x0..x1]);
            back_normal.extend_from_slice(&bnm[x0..x1]);
            rows.push([start, x0 as u32, x1 as u32]);
        }
        DepthMap { view, width, height, rows, pixels: Pixels::Encoded { front, back, front_normal, back_normal } }
    }

    /// A map from the CPU rasteriser's [`BandRows`] of consecutive rows
    /// from the top and its faces' `normals`. Rows beyond `height` are
    /// ignored; missing rows are empty; a run is cut to `width` and to the
    /// pixels given.
    pub fn from_bands(view: View, width: u32, height: u32, bands: Vec<BandRows>, normals: Vec<FaceNormal>) -> Self {
        let stored: usize = bands.iter().map(|band| band.z.len().min(band.face.len())).sum();
        let mut rows = Vec::with_capacity(height as usize);
        let (mut z, mut face) = (Vec::with_capacity(stored), Vec::with_capacity(stored));
        for BandRows { runs, z: bz, face: bf } in bands {
            let given = bz.len().min(bf.len());
            // where the next run's pixels start in the band's arrays
            let mut next = 0usize;
            for run in runs {
                if rows.len() == height as usize {
                    break;
                }
                let start = z.len() as u32;
                let Some((x0, x1)) = run.filter(|(x0, x1)| x0 < x1) else {
                    rows.push([start, 0, 0]);
                    continue;
                };
                let len = x1 - x0;
                let (x0c, x1c) = (x0.min(width as usize), x1.min(width as usize));
                let at = next.min(given);
                let keep = (x1c - x0c).min(given - at);
                z.extend_from_slice(&bz[at..at + keep]);
                face.extend_from_slice(&bf[at..at + keep]);
                rows.push([start, x0c as u32, (x0c + keep) as u32]);
                next += len;
            }
        }
        while rows.len() < height as usize {
            rows.push([z.len() as u32, 0, 0]);
        }
        DepthMap { view, width, height, rows, pixels: Pixels::Faces { z, face, normals } }
    }

    /// Where pixel `i` (row-major image index) is stored; `None` where it
    /// is empty or outside the image.
    fn stored(&self, i: usize) -> Option<usize> {
        let w = self.width as usize;
        let [start, x0, x1] = *self.rows.get(i / w)?;
        let x = (i % w) as u32;
        (x >= x0 && x < x1).then(|| (start + x - x0) as usize)
    }

    /// How many pixels are stored (those within the rows' runs).
    pub fn stored_pixels(&self) -> usize {
        match &self.pixels {
            Pixels::Encoded { front, .. } => front.len(),
            Pixels::Faces { z, .. } => z.len(),
        }
    }

    /// Stored pixel `s` of surface `k` (0 nearest, 1 farthest): its depth
    /// pixel as rendered (RGBA8, module docs; A 0 where empty); `None` past
    /// the stored pixels.
    fn depth_pixel(&self, s: usize, k: usize) -> Option<[u8; 4]> {
        match &self.pixels {
            Pixels::Encoded { front, back, .. } => (if k == 0 { front } else { back }).get(s).copied(),
            Pixels::Faces { z, face, normals } => {
                let covered = (face.get(s)?[k] as usize) < normals.len();
                Some(if covered { encode_depth_code(f64::from(z[s][k])) } else { [0; 4] })
            }
        }
    }

    /// Stored pixel `s` (image pixel `i`) of surface `k`: its normal pixel
    /// as rendered (the face's normal at the pixel centre, normalised and
    /// encoded, for a rasterised map); `None` past the stored pixels.
    fn normal_pixel(&self, s: usize, i: usize, k: usize) -> Option<[u8; 4]> {
        match &self.pixels {
            Pixels::Encoded { front_normal, back_normal, .. } => {
                (if k == 0 { front_normal } else { back_normal }).get(s).copied()
            }
            Pixels::Faces { face, normals, .. } => {
                let Some(n) = normals.get(face.get(s)?[k] as usize) else { return Some([0; 4]) };
                let w = self.width as usize;
                let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                Some(encode_normal((n[0] + n[1] * x + n[2] * y).normalize_or_zero().to_array()))
            }
        }
    }

    /// The nearest surface at pixel `i` (world `p·d`, m); `None` where empty
    /// or outside the image.
    pub fn front_depth(&self, i: usize) -> Option<f64> {
        decode_depth(&self.view, self.depth_pixel(self.stored(i)?, 0)?)
    }

    /// The farthest surface at pixel `i`, as [`Self::front_depth`].
    pub fn back_depth(&self, i: usize) -> Option<f64> {
        decode_depth(&self.view, self.depth_pixel(self.stored(i)?, 1)?)
    }

    /// The pixel of a point, row 0 at the top of the image; `None` outside the image.
    pub fn pixel(&self, p: DVec3) -> Option<usize> {
        let v = &self.view;
        let fx = (p.dot(v.u) - v.u_range[0]) / (v.u_range[1] - v.u_range[0]);
        let fy = (v.w_range[1] - p.dot(v.w)) / (v.w_range[1] - v.w_range[0]);
        if !(0.0..1.0).contains(&fx) || !(0.0..1.0).contains(&fy) {
            return None;
        }
        let x = (fx * f64::from(self.width)) as usize;
        let y = (fy * f64::from(self.height)) as usize;
        Some(y * self.width as usize + x)
    }

    /// Eq. (13) for one view.
    pub fn probe(&self, p: DVec3) -> Probe {
        self.probe_with_margin(p, 0.0)
    }

    /// Eq. (13) for the body thickened by `margin` (m) along the view axis:
    /// `back − margin ≤ p·d ≤ front + margin`.
    pub fn probe_with_margin(&self, p: DVec3, margin: f64) -> Probe {
        let outside = Probe { inside: false, escape: 0.0, normal: DVec3::ZERO };
        let Some((i, s)) = self.pixel(p).and_then(|i| Some((i, self.stored(i)?))) else { return outside };
        let depth = |k: usize| self.depth_pixel(s, k).and_then(|px| decode_depth(&self.view, px));
        let (Some(f), Some(b)) = (depth(0), depth(1)) else { return outside };
        let z = p.dot(self.view.d);
        if z < b - margin || z > f + margin {
            return outside;
        }
        let to_front = f + margin - z;
        let to_back = z - (b - margin);
        // the normal of the nearer surface, read only for a point inside
        let n = self.normal_pixel(s, i, usize::from(to_front > to_back)).unwrap_or_default();
        Probe { inside: true, escape: to_front.min(to_back), normal: decode_normal(n).normalize_or_zero() }
    }
}

/// A normal as the renderer stores it: each component `n·½ + ½` in unorm8,
/// `round(255 (n·½ + ½))`, in RGB (rounded as `⌊v + ½⌋`, as
/// [`encode_depth_code`]).
#[inline]
pub fn encode_normal(n: [f32; 3]) -> [u8; 4] {
    let c = n.map(|c| (c.clamp(-1.0, 1.0) * 127.5 + 128.0) as u8);
    [c[0], c[1], c[2], 255]
}

/// The normal of [`encode_normal`]'s bytes, `b / 255 · 2 − 1` per
/// component (not normalised).
pub fn decode_normal(b: [u8; 4]) -> DVec3 {
    let c = |b: u8| f64::from(f32::from(b) / 255.0 * 2.0 - 1.0);
    DVec3::new(c(b[0]), c(b[1]), c(b[2]))
}

/// Eq. (13) over several views: inside iff inside in every view. Returns
/// the probe with the smallest escape (the way out).
pub fn inside(maps: &[DepthMap], p: DVec3) -> Option<Probe> {
    inside_with_margin(maps, p, 0.0)
}

/// [`inside`] for the body thickened by `margin` (m) along every view axis.
pub fn inside_with_margin(maps: &[DepthMap], p: DVec3, margin: f64) -> Option<Probe> {
    let mut best: Option<Probe> = None;
    for m in maps {
        let pr = m.probe_with_margin(p, margin);
        if !pr.inside {
            return None;
        }
        if best.is_none_or(|b| pr.escape < b.escape) {
            best = Some(pr);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Analytic depth maps of a sphere.
    fn sphere_map(r: f64, n: u32, view: View) -> DepthMap {
        let px = (n * n) as usize;
        let (mut front, mut back, mut front_normal, mut back_normal) =
            (vec![[0; 4]; px], vec![[0; 4]; px], vec![[0; 4]; px], vec![[0; 4]; px]);
        for y in 0..n {
            for x in 0..n {
                let a = view.u_range[0] + (f64::from(x) + 0.5) / f64::from(n) * (view.u_range[1] - view.u_range[0]);
                let b = view.w_range[1] - (f64::from(y) + 0.5) / f64::from(n) * (view.w_range[1] - view.w_range[0]);
                let h2 = r * r - a * a - b * b;
                if h2 >= 0.0 {
                    let i = (y * n + x) as usize;
                    let h = h2.sqrt();
                    front[i] = encode_depth(&view, h);
                    back[i] = encode_depth(&view, -h);
                    let pf = view.u * a + view.w * b + view.d * h;
                    let pb = view.u * a + view.w * b - view.d * h;
                    front_normal[i] = encode_normal((pf / r).as_vec3().to_array());
                    back_normal[i] = encode_normal((pb / r).as_vec3().to_array());
                }
            }
        }
        let w = n as usize;
        let row = |y: usize| [&front, &back, &front_normal, &back_normal].map(|img| &img[y * w..(y + 1) * w]);
        DepthMap::from_rows(view, n, n, row)
    }

    #[test]
    fn stored_runs_keep_every_covered_pixel() {
        let n = 64;
        let views = View::set(ViewSet::FrontBackSides, DVec3::splat(-1.0), DVec3::splat(1.0), 0.1);
        let m = sphere_map(1.0, n, views[0]);
        // a disc of radius 1 in a square of side 2.2: π/4.84 of the pixels covered, more stored
        let covered = (0..(n * n) as usize).filter(|&i| m.front_depth(i).is_some()).count();
        let share = covered as f64 / f64::from(n * n);
        assert!((share - std::f64::consts::PI / 4.84).abs() < 0.02, "{share}");
        assert!(m.stored_pixels() >= covered && m.stored_pixels() < (n * n) as usize);
        // front and back agree on coverage; outside the image and in empty rows: nothing
        assert!((0..(n * n) as usize).all(|i| m.front_depth(i).is_some() == m.back_depth(i).is_some()));
        assert_eq!(m.front_depth(0), None);
        assert_eq!(m.front_depth((n * n) as usize), None);
    }

    #[test]
    fn depth_and_normal_pixels_round_trip() {
        let view = View::set(ViewSet::FrontBack, DVec3::splat(-1.0), DVec3::splat(1.0), 0.0)[0];
        let step = (view.d_range[1] - view.d_range[0]) / DEPTH_CODES;
        for world in [-1.0, -0.3141, 0.0, 0.5, 1.0] {
            let back = decode_depth(&view, encode_depth(&view, world)).unwrap();
            assert!((back - world).abs() <= step, "{world} -> {back}");
        }
        // the ends of the range are codes 0 and 2^24 - 1
        assert_eq!(encode_depth(&view, 1.0), [0, 0, 0, 255]);
        assert_eq!(encode_depth(&view, -1.0), [255, 255, 255, 255]);
        // an empty pixel has no depth, whatever its code
        assert_eq!(decode_depth(&view, [12, 34, 56, 0]), None);
        let n = decode_normal(encode_normal([0.0, -1.0, 1.0]));
        // half a unorm8 step of n·½ + ½, in n
        assert!((n - DVec3::new(0.0, -1.0, 1.0)).abs().max_element() <= 1.0 / 255.0 + 1e-6, "{n}");
    }

    #[test]
    fn sphere_inside_test_and_escape() {
        let views = View::set(ViewSet::FrontBackSides, DVec3::splat(-1.0), DVec3::splat(1.0), 0.1);
        let maps: Vec<DepthMap> = views.iter().map(|v| sphere_map(1.0, 512, *v)).collect();
        let p = DVec3::new(0.1, 0.2, 0.85);
        let pr = inside(&maps, p).unwrap();
        assert!(pr.escape > 0.0 && pr.escape < 0.2);
        assert!(pr.normal.dot(p.normalize()) > 0.9);
        assert!(inside(&maps, DVec3::new(0.0, 0.0, 1.05)).is_none());
        assert!(inside(&maps, DVec3::new(0.9, 0.9, 0.0)).is_none());
        // clip space: nearest point has depth 0
        let v = views[0];
        assert!((v.clip(DVec3::new(0.0, 0.0, 1.1))[2]).abs() < 1e-6);
        assert!((v.depth_to_world(0.5) - 0.0).abs() < 1e-12);
    }
}
