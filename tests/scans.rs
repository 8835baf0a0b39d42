//! Issue #17's bar: scans as they come, graded without landmarks.
//!
//! The first [`BODIES`] bodies of issue #7's population (`tests/population.rs`:
//! the planted extremes and draws), each made into what a scanner hands
//! over: re-meshed to an unrelated topology with 1 mm normal noise
//! ([`scan_like`]), holes cut at both armpits, the crotch, both soles and
//! the top of the head, 1 % of the triangle count added as degenerate
//! triangles (a repeated vertex, a coincident copy of a vertex, three
//! collinear points) and duplicates, every second body in millimetres and
//! Z-up (facing −Y, as such tools export) — written as a GLB and graded
//! with every library template through the service's scan flow
//! ([`work::bodies`]) **without landmarks**.
//!
//! Asserted on every body: graded (100 %); the repair counted every
//! planted fault (degenerate and duplicate triangles dropped, the holes
//! closed); the units, up axis and facing found; the registration's
//! residual within its bar; the deepest garment vertex at most 1 mm inside
//! the body and no garment triangle through a body triangle outside a
//! thigh contact (issue #7); no flipped triangle or self-crossing sew or cut
//! line, skirt and trouser pieces |E_s| ≤ 2 % and p95 strain ≤ 4 % (the
//! trouser backs ≤ 8 %, as `tests/population.rs`: issue #14); every
//! declared girth's ease within ±5 mm of the expected
//! (issue #13's bar); per landmark, the found landmark within 5 mm of the
//! hm08 mesh's own at the median and 15 mm at the 95th percentile; the bust,
//! waist, hip and thigh girths measured from
//! the found landmarks within 5 mm of those from the true ones (the hm08
//! mesh's, on the same repaired scan). Printed: per body the residual and
//! the time to read and grade it, over all bodies the distance of each found
//! landmark from the landmark of the same body's hm08 mesh (median, 95th
//! percentile, max), and the girths' differences (median, worst).
//!
//! ```sh
//! cargo test --release --test scans -- --nocapture
//! SCANS_ONLY=13 cargo test --release --test scans twenty -- --nocapture   # one body
//! ```

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::{DMat3, DVec3};
use grade3d::body::derive::Landmarks;
use grade3d::body::frame::FrameHints;
use grade3d::body::measure::{measure, MeasureOptions, MeasurementId};
use grade3d::body::vocab::PointId;
use grade3d::collide::cache::{ObstacleCache, ObstacleCacheOptions};
use grade3d::collide::render::{Renderer, RendererChoice};
use grade3d::geom::mesh::TriMesh;
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::BodyModel;
use grade3d::mannequin::population::{sample_population, scan_like, SplitMix64};
use grade3d::scan::{scan_body, ScanOptions};
use grade3d::service::report::BodiesReport;
use grade3d::service::work::{self, BodyInput, WorkContext, WorkOptions};
use grade3d::template::library::builtin;

/// The population of `tests/population.rs`: its seed and size.
const SEED: u64 = 13;
/// See [`SEED`].
const COUNT: usize = 40;
/// Bodies graded (the issue asks for at least 20).
const BODIES: usize = 20;
/// Faces of the re-meshed copies.
const SCAN_FACES: usize = 60_000;
/// Normal noise, m.
const NOISE_M: f64 = 1e-3;
/// Radius of the holes at the armpits and the crotch, m.
const HOLE_RADIUS_M: f64 = 0.015;
/// Radius of the hole at the top of the head, m.
const HEAD_HOLE_RADIUS_M: f64 = 0.04;
/// Height above the floor below which downward faces are the soles' hole, m.
const SOLE_HEIGHT_M: f64 = 0.012;
/// Issue #17's landmark bars: per landmark over the bodies, the found
/// landmark's distance from the hm08 mesh's own at most this at the median,
/// mm.
const LANDMARK_MEDIAN_MM: f64 = 5.0;
/// ... and at the 95th percentile, mm.
const LANDMARK_P95_MM: f64 = 15.0;
/// Issue #17's girth bar: bust, waist, hip and thigh girths from the found
/// landmarks within this of those from the true ones, mm.
const GIRTH_TOLERANCE_MM: f64 = 5.0;
/// Issue #13's ease bar, mm.
const EASE_TOLERANCE_MM: f64 = 5.0;
/// Issue #14's strain bar for skirt and trouser pieces (p95 edge strain),
/// and the ceiling of the pieces whose bar the garment's shape does not
/// allow (`tests/population.rs`).
const STRAIN_P95: f64 = 0.04;
/// See [`STRAIN_P95`].
const STRAIN_P95_OPEN: f64 = 0.08;
/// See [`STRAIN_P95`].
const STRAIN_OPEN: [&str; 2] = ["trousers left_back", "trousers right_back"];
/// Issue #14's area bar for skirt and trouser pieces (|E_s|).
const AREA_ACCURACY: f64 = 0.02;
/// The deepest garment vertex inside the body, mm (issue #7's bar).
const DEEPEST_MM: f64 = 1.0;
/// The library's A-line skirt's strain ceiling (`tests/common/authored.rs`:
/// pop04-f-heavy-medium's back reaches 5.36 % here).
const A_LINE_STRAIN_CEILING: f64 = 0.055;

/// A soup as a scanner hands it over (module docs); also what was planted.
struct Planted {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    degenerate: usize,
    duplicates: usize,
    z_up_mm: bool,
}

fn as_scanned(mesh: &TriMesh, truth: &BTreeMap<PointId, DVec3>, z_up_mm: bool, seed: u64) -> Planted {
    let aabb = mesh.aabb();
    let top = mesh.positions().iter().copied().max_by(|a, b| a.y.total_cmp(&b.y)).unwrap();
    let centres = [truth[&PointId::UnderarmLeft], truth[&PointId::UnderarmRight], truth[&PointId::Crotch]];
    let mut positions = mesh.positions().to_vec();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for f in 0..mesh.face_count() {
        let [a, b, c] = mesh.corners(f.into());
        let centroid = (a + b + c) / 3.0;
        let normal = (b - a).cross(c - a).normalize_or_zero();
        let hole = centres.iter().any(|p| p.distance(centroid) < HOLE_RADIUS_M)
            || top.distance(centroid) < HEAD_HOLE_RADIUS_M
            || (centroid.y < aabb.min.y + SOLE_HEIGHT_M && normal.y < -0.5);
        if !hole {
            triangles.push(mesh.triangles()[f].map(|v| v.0));
        }
    }
    // 1 % degenerate and duplicate triangles, in turn
    let mut rng = SplitMix64(seed);
    let read = triangles.len();
    let extra = read / 100;
    let (mut degenerate, mut duplicates) = (0, 0);
    let mut picked = std::collections::BTreeSet::new();
    for k in 0..extra {
        let mut at = (rng.next_u64() % read as u64) as usize;
        while !picked.insert(at) {
            at = (at + 1) % read;
        }
        let t = triangles[at];
        match k % 4 {
            0 => {
                triangles.push([t[0], t[0], t[1]]);
                degenerate += 1;
            }
            1 => {
                positions.push(positions[t[1] as usize]);
                triangles.push([t[0], t[1], (positions.len() - 1) as u32]);
                degenerate += 1;
            }
            2 => {
                positions.push(positions[t[0] as usize].lerp(positions[t[1] as usize], 0.5));
                triangles.push([t[0], t[1], (positions.len() - 1) as u32]);
                degenerate += 1;
            }
            _ => {
                triangles.push([t[1], t[2], t[0]]);
                duplicates += 1;
            }
        }
    }
    if z_up_mm {
        let to_z_up = DMat3::from_rotation_x(std::f64::consts::FRAC_PI_2);
        for p in &mut positions {
            *p = to_z_up * *p * 1000.0;
        }
    }
    Planted { positions, triangles, degenerate, duplicates, z_up_mm }
}

/// A GLB of one mesh with 32-bit float positions and `u32` indices, as
/// written by scanning software (no validation: repeated indices stay).
fn glb(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in positions {
        for (k, v) in p.as_vec3().to_array().into_iter().enumerate() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
            bin.extend(v.to_le_bytes());
        }
    }
    let index_at = bin.len();
    for i in triangles.iter().flatten() {
        bin.extend(i.to_le_bytes());
    }
    let json = serde_json::json!({
        "asset": {"version": "2.0", "generator": "tests/scans.rs"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": index_at},
            {"buffer": 0, "byteOffset": index_at, "byteLength": bin.len() - index_at}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": triangles.len() * 3, "type": "SCALAR"}
        ]
    });
    let mut json = serde_json::to_vec(&json).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

#[test]
fn twenty_scans_as_they_come_are_graded_without_landmarks() {
    let model = BodyModel::embedded().unwrap();
    let renderer = Renderer::new(RendererChoice::Auto).expect("a depth-map renderer (the one the service picks)");
    let ctx = WorkContext {
        renderer: Some(Arc::new(renderer)),
        obstacles: Arc::new(ObstacleCache::new(ObstacleCacheOptions::default())),
        blocks: Default::default(),
        design_bodies: grade3d::service::work::DesignBodyResolver::core(),
        opts: WorkOptions::default(),
    };
    let templates = builtin().unwrap();
    let mut failures = Vec::new();
    let mut landmark_error: BTreeMap<PointId, Vec<f64>> = BTreeMap::new();
    let mut graded = 0;
    let mut girth_error: BTreeMap<MeasurementId, Vec<(f64, String)>> = BTreeMap::new();
    let only: Option<usize> = std::env::var("SCANS_ONLY").ok().and_then(|v| v.parse().ok());
    for (i, b) in sample_population(COUNT, SEED).into_iter().take(BODIES).enumerate() {
        if only.is_some_and(|o| o != i) {
            continue;
        }
        let mesh = model.build(&b.params).unwrap();
        let truth = hm08_landmarks(model, &mesh, &Default::default()).unwrap().points;
        let scan = scan_like(&mesh, SCAN_FACES, NOISE_M, SEED ^ i as u64).unwrap();
        let planted = as_scanned(&scan, &truth, i % 2 == 1, SEED + i as u64);
        let bytes = glb(&planted.positions, &planted.triangles);
        let input = BodyInput { name: &b.name, glb: &bytes, landmarks: None, hints: Default::default() };
        let started = std::time::Instant::now();
        let outcome = match work::bodies(&ctx, &templates, &[input], None, None, &|_, _, _| {}) {
            Ok(o) => o,
            Err(e) => {
                failures.push(format!("{}: {e}", b.name));
                continue;
            }
        };
        let report: BodiesReport = serde_json::from_value(outcome.report).expect("a bodies report");
        let body = &report.bodies[0];
        let s = &body.scan;
        let reg = s.registration.as_ref().expect("registered: no landmarks were given");
        println!(
            "{:28} {:5.2} s  rms {:.2} mm p95 {:.2} mm (shape alone {:.2})  repair: {} degenerate, {} duplicates, {} holes",
            b.name,
            started.elapsed().as_secs_f64(),
            reg.rms_mm,
            reg.p95_mm,
            reg.shape_rms_mm,
            s.repair.degenerate_dropped,
            s.repair.duplicates_dropped,
            s.repair.holes_filled
        );
        let mut check = |ok: bool, what: String| {
            if !ok {
                failures.push(format!("{}: {what}", b.name));
            }
        };
        check(s.repair.degenerate_dropped >= planted.degenerate, format!("degenerate {:?}", s.repair));
        check(s.repair.duplicates_dropped >= planted.duplicates, format!("duplicates {:?}", s.repair));
        check(s.repair.holes_filled >= 5 && s.repair.holes_left == 0, format!("holes {:?}", s.repair));
        let (units, up, facing) = if planted.z_up_mm { ("mm", "+z", "-y") } else { ("m", "+y", "+z") };
        let found = serde_json::to_value((s.frame.units, s.frame.up, s.frame.facing)).unwrap();
        check(found == serde_json::json!([units, up, facing]), format!("frame {:?}", s.frame));
        check(s.landmarks_found == truth.len(), format!("{} landmarks found", s.landmarks_found));
        for g in &body.garments {
            let deepest = g.fit.penetration.as_ref().map_or(0.0, |p| p.deepest_mm);
            check(deepest <= DEEPEST_MM, format!("{} deepest vertex {deepest} mm inside", g.template));
            for e in &g.fit.girth_ease {
                let err = e.measured_mm - e.expected_mm;
                check(err.abs() <= EASE_TOLERANCE_MM, format!("{} {} ease off by {err:.1} mm", g.template, e.girth));
            }
            if let Some(p) = &g.fit.penetration {
                let through = p.intersecting_triangle_pairs - p.intersecting_triangle_pairs_at_thigh_contact;
                check(through == 0, format!("{} {through} garment triangles through the body", g.template));
            }
            // issue #14's piece bars (as tests/population.rs holds them)
            for r in &g.pieces {
                let d = &r.distortion;
                let at = format!("{} {}", g.template, r.name);
                check(
                    d.flipped == 0 && !r.sew_line_self_intersects && !r.cut_line_self_intersects,
                    format!("{at}: {} flipped, sew line crosses itself {}", d.flipped, r.sew_line_self_intersects),
                );
                if g.template != "fitted-bodice" {
                    let open = STRAIN_OPEN.contains(&at.as_str());
                    // the library's A-line skirt (issue #18) is held to its ceiling on the
                    // population's bodies (`tests/common/authored.rs`)
                    let ceiling = if open {
                        STRAIN_P95_OPEN
                    } else if g.template == "a-line-skirt" {
                        A_LINE_STRAIN_CEILING
                    } else {
                        STRAIN_P95
                    };
                    check(d.area_accuracy.abs() <= AREA_ACCURACY, format!("{at}: E_s {:.4}", d.area_accuracy));
                    check(d.strain_p95 <= ceiling, format!("{at}: p95 strain {:.4} over {ceiling}", d.strain_p95));
                }
            }
        }
        // the found landmarks against the hm08 mesh's own, both in the scan's axes (metres)
        let to_scan =
            if planted.z_up_mm { DMat3::from_rotation_x(std::f64::consts::FRAC_PI_2) } else { DMat3::IDENTITY };
        for (id, p) in &truth {
            let q = DVec3::from_array(s.landmarks[id]);
            landmark_error.entry(*id).or_default().push(q.distance(to_scan * *p) * 1e3);
        }
        // the body's girths from the found landmarks (the graded body's, as the report gives
        // them) against those from the true ones, on the same repaired scan
        let soup: Vec<[u64; 3]> = planted.triangles.iter().map(|t| t.map(u64::from)).collect();
        let given =
            Landmarks { points: truth.iter().map(|(&id, &p)| (id, to_scan * p)).collect(), curves: BTreeMap::new() };
        let (true_body, _) =
            scan_body(&planted.positions, &soup, &FrameHints::default(), Some(&given), &ScanOptions::default())
                .unwrap();
        let m_true = measure(&true_body, &MeasureOptions::default());
        for id in
            [MeasurementId::BustGirth, MeasurementId::WaistGirth, MeasurementId::HipGirth, MeasurementId::ThighGirth]
        {
            let (Some(a), Some(t)) = (body.measurements_m.get(id.as_str()), m_true.get(&id)) else {
                check(false, format!("{} not measured", id.as_str()));
                continue;
            };
            let d = (a - t) * 1e3;
            girth_error.entry(id).or_default().push((d.abs(), b.name.clone()));
            check(d.abs() <= GIRTH_TOLERANCE_MM, format!("{} from found landmarks off by {d:.1} mm", id.as_str()));
        }
        graded += 1;
    }
    for (id, e) in &mut girth_error {
        e.sort_by(|a, b| a.0.total_cmp(&b.0));
        let worst = e.last().unwrap();
        println!(
            "{:12} from found landmarks against true ones: median {:.1} mm, worst {:.1} mm ({})",
            id.as_str(),
            e[e.len() / 2].0,
            worst.0,
            worst.1
        );
    }
    let mut all: Vec<f64> = landmark_error.values().flatten().copied().collect();
    all.sort_by(f64::total_cmp);
    if !all.is_empty() {
        let q = |f: f64| all[((all.len() - 1) as f64 * f).round() as usize];
        println!(
            "found landmarks against the hm08 mesh's: median {:.1} mm, p95 {:.1} mm, max {:.1} mm",
            q(0.5),
            q(0.95),
            q(1.0)
        );
        for (id, e) in &landmark_error {
            let mut e = e.clone();
            e.sort_by(f64::total_cmp);
            let p95 = e[((e.len() - 1) as f64 * 0.95).round() as usize];
            if e[e.len() / 2] > LANDMARK_MEDIAN_MM || p95 > LANDMARK_P95_MM {
                failures.push(format!("{}: median {:.1} mm, p95 {p95:.1} mm", id.as_str(), e[e.len() / 2]));
            }
            println!(
                "  {:16} median {:5.1} mm  p95 {:5.1} mm  max {:5.1} mm",
                id.as_str(),
                e[e.len() / 2],
                p95,
                e[e.len() - 1]
            );
        }
    }
    println!("graded without landmarks: {graded} of {BODIES}");
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
    assert_eq!(graded, BODIES);
}

/// Issue #17, item 1: holes are tolerated — the inside tests the grading
/// relies on (the exact winding number, and the depth maps' inside test)
/// answer on the repaired scan as on the closed body it was cut from: away
/// from the holes exactly so, and at the holes but for the thin lens
/// between the flat fill and the skin it stands for.
#[test]
fn holes_leave_the_inside_tests_right() {
    use grade3d::collide::depth::inside;
    use grade3d::collide::DepthRenderer;
    use grade3d::geom::winding::{WindingOptions, WindingTree};
    let model = BodyModel::embedded().unwrap();
    let b = &sample_population(COUNT, SEED)[0];
    let mesh = model.build(&b.params).unwrap();
    let truth = hm08_landmarks(model, &mesh, &Default::default()).unwrap().points;
    let closed = scan_like(&mesh, SCAN_FACES, NOISE_M, SEED).unwrap();
    let planted = as_scanned(&closed, &truth, false, SEED);
    let soup: Vec<[u64; 3]> = planted.triangles.iter().map(|t| t.map(u64::from)).collect();
    let (body, report) =
        grade3d::scan::scan_body(&planted.positions, &soup, &Default::default(), None, &Default::default()).unwrap();
    assert!(report.repair.holes_filled >= 5 && report.repair.holes_left == 0, "{:?}", report.repair);
    let repaired = &body.mesh;
    let renderer = Renderer::new(RendererChoice::Auto).unwrap();
    let tests = |m: &TriMesh| {
        (WindingTree::new(m, &WindingOptions::default()), renderer.depth_maps(m, &Default::default()).unwrap())
    };
    let (reference, reference_maps) = tests(&closed);
    let (tree, maps) = tests(repaired);
    // points within 15 mm of the skin, and within 30 mm of each hole
    let mut rng = SplitMix64(7);
    let mut u = || 2.0 * rng.unit() - 1.0;
    let normals = closed.vertex_normals();
    let skin: Vec<DVec3> = (0..20_000)
        .map(|_| {
            let v = (u().abs() * closed.vertex_count() as f64) as usize % closed.vertex_count();
            closed.positions()[v] + normals[v] * 0.015 * u()
        })
        .collect();
    let top = closed.positions().iter().copied().max_by(|a, b| a.y.total_cmp(&b.y)).unwrap();
    let aabb = closed.aabb();
    let mut holes: Vec<DVec3> = Vec::new();
    for c in [truth[&PointId::UnderarmLeft], truth[&PointId::UnderarmRight], truth[&PointId::Crotch], top] {
        holes.extend((0..2_000).map(|_| c + DVec3::new(u(), u(), u()) * 0.03));
    }
    let span = aabb.max - aabb.min;
    holes.extend((0..2_000).map(|_| {
        let (x, z) = (0.5 * (1.0 + u()), 0.5 * (1.0 + u()));
        DVec3::new(aabb.min.x + span.x * x, aabb.min.y + 0.02 * u().abs(), aabb.min.z + span.z * z)
    }));
    let near_hole = |p: DVec3| {
        [truth[&PointId::UnderarmLeft], truth[&PointId::UnderarmRight], truth[&PointId::Crotch], top]
            .iter()
            .any(|c| c.distance(p) < 0.05)
            || p.y < aabb.min.y + 0.03
    };
    let away: Vec<DVec3> = skin.into_iter().filter(|&p| !near_hole(p)).collect();
    // each against the closed body's exact test; the depth maps' own error (2 mm pixels, points
    // within 15 mm of the skin, and between two limbs in every view) is what the closed body's
    // maps show, and the repaired scan's may differ from it only as much as a shift of the pixel
    // grid does (the maps frame the mesh's bounding box, which the sole's fill moves)
    let agree = |points: &[DVec3]| {
        let share = |n: usize| n as f64 / points.len() as f64;
        let exact = points.iter().filter(|&&p| tree.is_inside(p) == reference.is_inside(p)).count();
        let by_maps = points.iter().filter(|&&p| inside(&maps, p).is_some() == reference.is_inside(p)).count();
        let closed_maps =
            points.iter().filter(|&&p| inside(&reference_maps, p).is_some() == reference.is_inside(p)).count();
        (share(exact), share(by_maps), share(closed_maps))
    };
    let (away_exact, away_maps, away_closed) = agree(&away);
    let (hole_exact, hole_maps, hole_closed) = agree(&holes);
    println!(
        "inside tests against the closed body's exact test: {} points near the skin away from the holes: exact \
         {away_exact:.5}, depth maps {away_maps:.5} (the closed body's maps {away_closed:.5}); {} points within 3 cm \
         of the holes: exact {hole_exact:.4}, depth maps {hole_maps:.4} (closed {hole_closed:.4})",
        away.len(),
        holes.len()
    );
    assert!(away_exact >= 0.9995 && away_maps >= away_closed - 0.005, "{away_exact} {away_maps} {away_closed}");
    assert!(hole_exact >= 0.95 && hole_maps >= hole_closed - 0.05, "{hole_exact} {hole_maps} {hole_closed}");
}
