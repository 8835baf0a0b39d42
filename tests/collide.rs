//! GPU golden test of the body depth maps, on both of Mesa's CPU drivers
//! (wgpu's GL backend through llvmpipe, Vulkan through lavapipe).
//!
//! Reference: a CPU rasteriser of the same orthographic views (pixel
//! centres, nearest and farthest surface). Metric, per view and map:
//! * coverage: pixels covered in one image but not the other ≤ 0.5 % of the
//!   covered pixels (silhouette pixels may differ by fill rules);
//! * depth: on pixels covered in both whose 8 neighbours are covered in
//!   both and lie within 5 mm of the pixel in the reference (no silhouette
//!   inside the image, e.g. an arm's edge in front of the torso),
//!   max |GPU − CPU| ≤ 0.5 mm.
//!
//! On failure `target/golden/<name>-actual.png` (GPU depth) and
//! `<name>-difference.png` (red: coverage differs, white: depth over the
//! threshold) are written.

use std::collections::HashMap;
use std::time::Instant;

use glam::DVec3;
use grade3d::collide::depth::{encode_depth, encode_normal, inside, DepthMap, View};
use grade3d::collide::raster::CpuRasteriser;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::collide::{DepthRenderer, Obstacle};
use grade3d::geom::mesh::{FaceId, TriMesh};
use grade3d::geom::query;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf;
use grade3d::mannequin::population::SplitMix64;

fn fixtures() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

const COVERAGE_TOLERANCE: f64 = 0.005;
const DEPTH_TOLERANCE_M: f64 = 0.5e-3;
/// Depth steps between neighbouring pixels above this mark a silhouette
/// inside the image (an arm in front of the torso); such pixels are left
/// to the coverage metric.
const SMOOTH_STEP_M: f64 = 5e-3;

/// CPU reference: nearest (`front`) and farthest (`back`) surface along the view's `d` at pixel centres.
fn rasterise(mesh: &TriMesh, view: &View, n: u32) -> (Vec<f64>, Vec<f64>) {
    let r = rasterise_faces(mesh, view, n);
    (r.front, r.back)
}

/// [`rasterise`] with the face each pixel's surface belongs to.
struct Raster {
    front: Vec<f64>,
    back: Vec<f64>,
    front_face: Vec<u32>,
    back_face: Vec<u32>,
}

fn rasterise_faces(mesh: &TriMesh, view: &View, n: u32) -> Raster {
    let px = (n * n) as usize;
    let mut r =
        Raster { front: vec![f64::NAN; px], back: vec![f64::NAN; px], front_face: vec![0; px], back_face: vec![0; px] };
    let to_px = |p: DVec3| {
        let fx = (p.dot(view.u) - view.u_range[0]) / (view.u_range[1] - view.u_range[0]) * f64::from(n);
        let fy = (view.w_range[1] - p.dot(view.w)) / (view.w_range[1] - view.w_range[0]) * f64::from(n);
        (fx, fy, p.dot(view.d))
    };
    for f in 0..mesh.face_count() {
        let [a, b, c] = mesh.corners(FaceId(f as u32)).map(to_px);
        let area = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
        if area.abs() < 1e-12 {
            continue;
        }
        let x0 = a.0.min(b.0).min(c.0).floor().max(0.0) as u32;
        let x1 = (a.0.max(b.0).max(c.0).ceil() as u32).min(n - 1);
        let y0 = a.1.min(b.1).min(c.1).floor().max(0.0) as u32;
        let y1 = (a.1.max(b.1).max(c.1).ceil() as u32).min(n - 1);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (sx, sy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                let w0 = ((b.0 - sx) * (c.1 - sy) - (b.1 - sy) * (c.0 - sx)) / area;
                let w1 = ((c.0 - sx) * (a.1 - sy) - (c.1 - sy) * (a.0 - sx)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * a.2 + w1 * b.2 + w2 * c.2;
                let i = (y * n + x) as usize;
                if r.front[i].is_nan() || z > r.front[i] {
                    r.front[i] = z;
                    r.front_face[i] = f as u32;
                }
                if r.back[i].is_nan() || z < r.back[i] {
                    r.back[i] = z;
                    r.back_face[i] = f as u32;
                }
            }
        }
    }
    r
}

/// The CPU reference as the core's [`DepthRenderer`] (issue #16: the core
/// takes its renderer as a trait): per pixel the nearest and farthest
/// surface's depth code and its face's outward normal, as the wgpu
/// renderer stores them.
struct CpuReference;

impl DepthRenderer for CpuReference {
    type Error = std::convert::Infallible;

    fn depth_maps(&self, mesh: &TriMesh, opts: &RenderOptions) -> Result<Vec<DepthMap>, Self::Error> {
        let bb = mesh.aabb();
        let n = opts.resolution;
        let normal = |f: u32| {
            let [a, b, c] = mesh.corners(FaceId(f));
            (b - a).cross(c - a).normalize_or_zero().as_vec3().to_array()
        };
        let maps = View::set(opts.views, bb.min, bb.max, opts.padding_mm * 1e-3)
            .into_iter()
            .map(|view| {
                let r = rasterise_faces(mesh, &view, n);
                let pixels = |depth: &[f64], face: &[u32], as_normal: bool| -> Vec<[u8; 4]> {
                    depth
                        .iter()
                        .zip(face)
                        .map(|(&z, &f)| match (z.is_nan(), as_normal) {
                            (true, _) => [0; 4],
                            (false, false) => encode_depth(&view, z),
                            (false, true) => encode_normal(normal(f)),
                        })
                        .collect()
                };
                let images = [
                    pixels(&r.front, &r.front_face, false),
                    pixels(&r.back, &r.back_face, false),
                    pixels(&r.front, &r.front_face, true),
                    pixels(&r.back, &r.back_face, true),
                ];
                let w = n as usize;
                DepthMap::from_rows(view, n, n, |y| images.each_ref().map(|im| &im[y * w..(y + 1) * w]))
            })
            .collect();
        Ok(maps)
    }
}

fn write_png(path: &std::path::Path, n: u32, rgb: &[u8]) {
    let file = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), n, n);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header().unwrap().write_image_data(rgb).unwrap();
}

struct Comparison {
    coverage_mismatch: f64,
    max_depth_diff_m: f64,
}

fn compare(name: &str, n: u32, gpu: &[f32], cpu: &[f64], view: &View) -> Comparison {
    let covered = |v: f64| v.is_finite();
    let mut mismatch = 0usize;
    let mut covered_px = 0usize;
    let mut worst = 0.0f64;
    let mut diff_img = vec![0u8; (3 * n * n) as usize];
    let mut bad = false;
    for y in 0..n {
        for x in 0..n {
            let i = (y * n + x) as usize;
            let (g, c) = (f64::from(gpu[i]), cpu[i]);
            if covered(g) || covered(c) {
                covered_px += 1;
            }
            if covered(g) != covered(c) {
                mismatch += 1;
                diff_img[3 * i] = 255;
                continue;
            }
            if !covered(g) {
                continue;
            }
            let interior = (-1i32..=1).all(|dy| {
                (-1i32..=1).all(|dx| {
                    let (xx, yy) = (x as i32 + dx, y as i32 + dy);
                    xx >= 0 && yy >= 0 && xx < n as i32 && yy < n as i32 && {
                        let j = (yy as u32 * n + xx as u32) as usize;
                        covered(f64::from(gpu[j])) && covered(cpu[j]) && (cpu[j] - c).abs() < SMOOTH_STEP_M
                    }
                })
            });
            if interior {
                let d = (g - c).abs();
                worst = worst.max(d);
                if d > DEPTH_TOLERANCE_M {
                    diff_img[3 * i..3 * i + 3].copy_from_slice(&[255, 255, 255]);
                    bad = true;
                }
            }
        }
    }
    let cmp = Comparison { coverage_mismatch: mismatch as f64 / covered_px.max(1) as f64, max_depth_diff_m: worst };
    if bad || cmp.coverage_mismatch > COVERAGE_TOLERANCE {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/golden");
        std::fs::create_dir_all(&dir).unwrap();
        let (lo, hi) = (view.d_range[0], view.d_range[1]);
        let actual: Vec<u8> = gpu
            .iter()
            .flat_map(|&g| {
                let v = if g.is_finite() { (255.0 * (f64::from(g) - lo) / (hi - lo)) as u8 } else { 0 };
                [v, v, v]
            })
            .collect();
        write_png(&dir.join(format!("{name}-actual.png")), n, &actual);
        write_png(&dir.join(format!("{name}-difference.png")), n, &diff_img);
    }
    cmp
}

/// Both of Mesa's CPU drivers: GL through llvmpipe, Vulkan through lavapipe.
fn backends() -> [(wgpu::Backends, &'static str); 2] {
    [(wgpu::Backends::GL, "gl"), (wgpu::Backends::VULKAN, "vulkan")]
}

#[test]
fn body_depth_maps_match_the_cpu_reference_on_gl_and_vulkan() {
    for (backends, label) in backends() {
        let gpu = match GpuContext::with_backends(backends) {
            Ok(g) => g,
            Err(e) => panic!("no {label} adapter: {e} (.ci/run installs Mesa's llvmpipe and lavapipe)"),
        };
        let info = gpu.adapter();
        check_body_maps(&gpu, &format!("{} ({:?})", info.name, info.backend), &format!("{:?}", info.backend));
    }
}

/// The core's CPU rasteriser (issue #15: the renderer on machines whose
/// adapter is a CPU driver) against the same reference and metric as wgpu.
#[test]
fn the_cpu_rasteriser_matches_the_cpu_reference() {
    check_body_maps(&CpuRasteriser, "CPU rasteriser", "cpu");
}

fn check_body_maps<R: DepthRenderer>(renderer: &R, label: &str, file: &str)
where
    R::Error: std::fmt::Debug,
{
    let mesh = gltf::read_mesh(
        &std::fs::read(fixtures().join("bodies/female-average-caucasian.glb")).unwrap(),
        &Default::default(),
    )
    .unwrap();
    let n = 512; // the golden test pins its own resolution
    let maps: Vec<DepthMap> =
        renderer.depth_maps(&mesh, &RenderOptions { resolution: n, ..Default::default() }).unwrap();
    assert_eq!(maps.len(), 2);
    for (k, m) in maps.iter().enumerate() {
        let (front, back) = rasterise(&mesh, &m.view, n);
        let px = (n * n) as usize;
        let world = |depth: &dyn Fn(usize) -> Option<f64>| -> Vec<f32> {
            (0..px).map(|i| depth(i).map_or(f32::NAN, |w| w as f32)).collect()
        };
        let (gf, gb) = (world(&|i| m.front_depth(i)), world(&|i| m.back_depth(i)));
        for (which, g, c) in [("front", &gf, &front), ("back", &gb, &back)] {
            let name = format!("{file}-view{k}-{which}");
            let cmp = compare(&name, n, g, c, &m.view);
            eprintln!(
                "{label} view {k} {which}: coverage mismatch {:.4} %, max interior depth difference {:.4} mm",
                100.0 * cmp.coverage_mismatch,
                cmp.max_depth_diff_m * 1e3
            );
            assert!(cmp.coverage_mismatch <= COVERAGE_TOLERANCE, "{name}: coverage mismatch {}", cmp.coverage_mismatch);
            assert!(cmp.max_depth_diff_m <= DEPTH_TOLERANCE_M, "{name}: depth difference {} m", cmp.max_depth_diff_m);
        }
    }
}

/// The winding tree on a real scan (a body with holes: armpits, crotch,
/// soles): the fast winding number against the exact one, the branch and
/// bound closest point against the exhaustive search (moved from the
/// core's unit tests with issue #16: it reads a GLB, which the core does not).
#[test]
fn body_fast_and_exact_agree() {
    let bytes = std::fs::read(fixtures().join("bodies/female-average-caucasian.glb")).unwrap();
    let body = gltf::read_mesh(&bytes, &Default::default()).unwrap();
    let bb = body.aabb();
    let mut rng = SplitMix64(2024);
    let pts: Vec<DVec3> =
        (0..2_000).map(|_| bb.min + (bb.max - bb.min) * DVec3::new(rng.unit(), rng.unit(), rng.unit())).collect();
    let us = |d: std::time::Duration| d.as_secs_f64() * 1e6 / pts.len() as f64;

    let tree = WindingTree::new(&body, &WindingOptions::default());
    let t0 = Instant::now();
    let exact: Vec<f64> = pts.iter().map(|&p| tree.winding_number_exact(p)).collect();
    let t_exact = t0.elapsed();
    let t0 = Instant::now();
    let dist: Vec<f64> = pts.iter().map(|&p| tree.closest_point(p).2).collect();
    let t_closest = t0.elapsed();
    let inside = exact.iter().filter(|&&w| w >= 0.5).count();
    let welded = body.welded(1e-7).unwrap();
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    for t in welded.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k].0, t[(k + 1) % 3].0);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let boundary = edges.values().filter(|&&n| n == 1).count();
    // how far from 0 or 1 the exact w gets more than 1 cm from the skin (the holes)
    let frac_far = (0..pts.len())
        .filter(|&i| dist[i] > 1e-2)
        .map(|i| exact[i].abs().min((1.0 - exact[i]).abs()))
        .fold(0.0, f64::max);
    println!(
        "body: {} faces, {} nodes, {boundary} boundary edges; {inside}/{} sample points inside; \
         max |w − round(w)| beyond 1 cm = {frac_far:.1e}",
        tree.face_count(),
        tree.node_count(),
        pts.len()
    );
    println!("body: per query {:.1} µs exact winding number, {:.2} µs closest point", us(t_exact), us(t_closest));
    // branch and bound against the exhaustive search, on a subset
    for (p, d) in pts.iter().zip(&dist).step_by(20) {
        let brute = query::closest_point(&body, *p);
        assert!((brute.distance - d).abs() < 1e-12, "{} vs {d}", brute.distance);
    }
    assert!(inside > 0 && inside < pts.len());

    for beta in [2.0, 3.0] {
        let t0 = Instant::now();
        let tree = WindingTree::new(&body, &WindingOptions { accuracy_beta: beta, ..Default::default() });
        let build = t0.elapsed();
        let t0 = Instant::now();
        let fast: Vec<f64> = pts.iter().map(|&p| tree.winding_number(p)).collect();
        let t_fast = t0.elapsed();
        let t0 = Instant::now();
        let depth: Vec<f64> = pts.iter().map(|&p| tree.signed_depth(p)).collect();
        let t_depth = t0.elapsed();
        let (mut max_diff, mut max_diff_far, mut disagree, mut disagree_far) = (0.0f64, 0.0f64, 0, 0);
        for i in 0..pts.len() {
            let diff = (fast[i] - exact[i]).abs();
            max_diff = max_diff.max(diff);
            if dist[i] > 1e-3 {
                max_diff_far = max_diff_far.max(diff);
            }
            if (fast[i] >= 0.5) != (exact[i] >= 0.5) {
                disagree += 1;
                disagree_far += usize::from(dist[i] > 1e-3);
            }
            assert_eq!(depth[i].abs(), dist[i]);
            assert_eq!(depth[i] > 0.0, fast[i] >= 0.5 && dist[i] > 0.0);
        }
        println!(
            "body β = {beta}: build {:.1} ms; max |w_fast − w_exact| = {max_diff:.2e} ({max_diff_far:.2e} beyond 1 mm); \
             is_inside disagreements {disagree} ({disagree_far} beyond 1 mm)",
            build.as_secs_f64() * 1e3
        );
        println!(
            "body β = {beta}: per query {:.2} µs fast winding number ({:.0}× faster than exact), {:.2} µs signed depth",
            us(t_fast),
            t_exact.as_secs_f64() / t_fast.as_secs_f64(),
            us(t_depth)
        );
        assert_eq!(disagree_far, 0);
        assert!(max_diff < 1e-2, "β = {beta}: {max_diff}");
    }

    // garment-like points: skin vertices moved ±1 mm and ±5 mm along their normals
    let normals = welded.vertex_normals();
    let (mut near, mut agree, mut as_offset, mut max_diff) = (0, 0, 0, 0.0f64);
    for (v, (&x, &n)) in welded.positions().iter().zip(&normals).enumerate().step_by(25) {
        let offset = [-5e-3, -1e-3, 1e-3, 5e-3][v % 4];
        let p = x + offset * n;
        let (fast, exact) = (tree.winding_number(p), tree.winding_number_exact(p));
        near += 1;
        max_diff = max_diff.max((fast - exact).abs());
        agree += usize::from((fast >= 0.5) == (exact >= 0.5));
        as_offset += usize::from(tree.is_inside(p) == (offset < 0.0));
    }
    println!(
        "body, {near} points 1–5 mm off the skin: fast/exact is_inside agree on {agree}, \
         inside ⇔ moved inward on {as_offset}; max |w_fast − w_exact| = {max_diff:.2e}"
    );
    assert_eq!(agree, near);
    // the misses are 5 mm offsets at lips, nose and toes that cross into another part of the skin
    assert!(as_offset * 100 >= near * 98, "{as_offset}/{near}");
}

/// The core builds its obstacle from any [`DepthRenderer`] (issue #16):
/// from the CPU reference and from wgpu, the inside test of Eq. (13)
/// agrees between the two and with the exact winding number on a scan.
#[test]
fn the_core_builds_one_obstacle_from_any_renderer() {
    let bytes = std::fs::read(fixtures().join("bodies/female-average-caucasian.glb")).unwrap();
    let mesh = gltf::read_mesh(&bytes, &Default::default()).unwrap();
    let opts = RenderOptions { resolution: 512, ..Default::default() };
    let winding = WindingOptions::default();
    let cpu = Obstacle::build(&mesh, &CpuReference, &opts, &winding).unwrap();
    let gpu = GpuContext::new().expect("wgpu adapter (see .ci/run)");
    let wgpu = Obstacle::build(&mesh, &gpu, &opts, &winding).unwrap();
    let raster = Obstacle::build(&mesh, &CpuRasteriser, &opts, &winding).unwrap();
    let bb = mesh.aabb();
    let mut rng = SplitMix64(16);
    let pts: Vec<DVec3> =
        (0..20_000).map(|_| bb.min + (bb.max - bb.min) * DVec3::new(rng.unit(), rng.unit(), rng.unit())).collect();
    let (mut same, mut cpu_exact, mut gpu_exact, mut inside_count) = (0, 0, 0, 0);
    let (mut raster_same, mut raster_gpu) = (0, 0);
    for &p in &pts {
        let (c, g) = (inside(&cpu.maps, p).is_some(), inside(&wgpu.maps, p).is_some());
        let r = inside(&raster.maps, p).is_some();
        let exact = cpu.tree.winding_number(p) >= 0.5;
        same += usize::from(c == g);
        raster_same += usize::from(r == c);
        raster_gpu += usize::from(r == g);
        cpu_exact += usize::from(c == exact);
        gpu_exact += usize::from(g == exact);
        inside_count += usize::from(exact);
    }
    let share = |k: usize| k as f64 / pts.len() as f64;
    eprintln!(
        "{} of {} points inside; CPU vs wgpu {:.4}, CPU vs exact {:.4}, wgpu vs exact {:.4}",
        inside_count,
        pts.len(),
        share(same),
        share(cpu_exact),
        share(gpu_exact)
    );
    eprintln!("CPU rasteriser vs reference {:.4}, vs wgpu {:.4}", share(raster_same), share(raster_gpu));
    assert!(inside_count > 1_000, "the sample reaches into the body");
    assert!(share(raster_same) >= 0.999 && share(raster_gpu) >= 0.998, "{raster_same} {raster_gpu}");
    assert!(share(same) >= 0.998, "CPU and wgpu obstacles agree on {:.4}", share(same));
    assert!(share(cpu_exact) >= 0.995 && share(gpu_exact) >= 0.995, "{:.4} {:.4}", share(cpu_exact), share(gpu_exact));
}
